//! What a run must remove if it is interrupted: its staging folder, its lock file and an output
//! folder it created. [`StagedDir`](super::atomic::StagedDir) registers them here; on SIGINT,
//! SIGTERM or SIGHUP the handler installed by [`install_signal_handler`] removes them and exits
//! with 128 + the signal number (130 for SIGINT, 143 for SIGTERM), as a shell reports a process
//! killed by that signal.
//!
//! The registry's mutex doubles as the file-system lock of the output layer: staged writes and
//! the final commit hold it, so the handler waits for a write in progress to end (milliseconds),
//! removes everything and exits while still holding it — nothing can recreate the staging folder
//! after it was removed, and a commit is never cut in the middle.

use std::fs;
use std::io;
use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};

/// One thing to remove, in registration order reversed.
#[derive(Debug, Clone)]
pub(crate) enum Item {
    /// A folder and everything in it (the staging folder).
    Tree(PathBuf),
    /// One file (the lock file).
    File(PathBuf),
    /// A folder, only if it is empty (an output folder this run created).
    EmptyDir(PathBuf),
}

/// Registered items with their ids.
static REGISTRY: Mutex<Vec<(u64, Item)>> = Mutex::new(Vec::new());

/// Next registration id.
static NEXT_ID: Mutex<u64> = Mutex::new(0);

/// The registry, even if a panicking thread poisoned it (the data stays valid: every update is
/// one push or one retain).
pub(crate) fn lock() -> MutexGuard<'static, Vec<(u64, Item)>> {
    REGISTRY.lock().unwrap_or_else(|e| e.into_inner())
}

fn next_id() -> u64 {
    let mut n = NEXT_ID.lock().unwrap_or_else(|e| e.into_inner());
    *n += 1;
    *n
}

/// Registers a staging folder to remove on a signal; returns its id.
pub(crate) fn register_tree(reg: &mut Vec<(u64, Item)>, path: PathBuf) -> u64 {
    let id = next_id();
    reg.push((id, Item::Tree(path)));
    id
}

/// Registers a file to remove on a signal; returns its id.
pub(crate) fn register_file(reg: &mut Vec<(u64, Item)>, path: PathBuf) -> u64 {
    let id = next_id();
    reg.push((id, Item::File(path)));
    id
}

/// Registers a folder to remove on a signal if it is empty; returns its id.
pub(crate) fn register_empty_dir(reg: &mut Vec<(u64, Item)>, path: PathBuf) -> u64 {
    let id = next_id();
    reg.push((id, Item::EmptyDir(path)));
    id
}

/// Forgets the items with these ids (they were committed or removed by their owner).
pub(crate) fn unregister(reg: &mut Vec<(u64, Item)>, ids: &[u64]) {
    reg.retain(|(id, _)| !ids.contains(id));
}

/// Removes every registered item, newest first (staging folder, then lock, then the output
/// folder if this run created it and it is empty). Errors are ignored: this is the last thing
/// the process does.
fn remove_all(reg: &mut Vec<(u64, Item)>) {
    while let Some((_, item)) = reg.pop() {
        let _ = match item {
            Item::Tree(p) => fs::remove_dir_all(p),
            Item::File(p) => fs::remove_file(p),
            Item::EmptyDir(p) => fs::remove_dir(p),
        };
    }
}

/// Whether `sig` was ignored (`SIG_IGN`) when this process started: `nohup` ignores SIGHUP, a
/// non-interactive shell ignores SIGINT in `cmd &`, and such a signal must keep doing nothing
/// (the GNU coding standards' rule: never catch a signal inherited as ignored).
#[cfg(unix)]
fn inherited_as_ignored(sig: i32) -> bool {
    // SAFETY: sigaction with a null new action only reads the current disposition into `old`,
    // a zeroed plain C struct owned by this frame.
    unsafe {
        let mut old: libc::sigaction = std::mem::zeroed();
        libc::sigaction(sig, std::ptr::null(), &mut old) == 0 && old.sa_sigaction == libc::SIG_IGN
    }
}

/// Installs the handler for SIGINT, SIGTERM and SIGHUP (Unix; elsewhere nothing happens), except
/// for those inherited as ignored (`nohup ofmpc run … &` keeps running when the terminal
/// closes). A thread waits for the signal (signal-hook's self-pipe, so nothing runs in signal
/// context), removes the registered items and exits with 128 + the signal number.
pub fn install_signal_handler() -> io::Result<()> {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        let watched: Vec<i32> = [SIGINT, SIGTERM, SIGHUP]
            .into_iter()
            .filter(|&s| !inherited_as_ignored(s))
            .collect();
        if watched.is_empty() {
            return Ok(());
        }
        let mut signals = signal_hook::iterator::Signals::new(&watched)?;
        std::thread::Builder::new()
            .name("ofmpc-signals".into())
            .spawn(move || {
                if let Some(sig) = signals.forever().next() {
                    let mut reg = lock();
                    remove_all(&mut reg);
                    // Exit while holding the registry: no staged write can start again.
                    std::process::exit(128 + sig);
                }
            })?;
    }
    Ok(())
}
