//! Atomic file output: a run that fails leaves no half-written file behind.
//!
//! Two tools:
//!
//! * [`write_atomic`] / [`write_atomic_with`] replace one file. The bytes go to a temporary file
//!   in the target's directory (same file system, so the final `rename` is atomic), which is
//!   fsynced and then renamed over the target; the directory is fsynced afterwards. On any error
//!   (or a panic in the producer) the temporary file is removed and the target is untouched:
//!   a reader sees either the complete old file or the complete new one, never a mixture.
//!
//! * [`StagedDir`] collects a whole run's outputs in a hidden staging folder
//!   `.ofmpc-stage-<pid>-<n>` inside the output folder and moves them into place only on
//!   [`StagedDir::commit`]. Guarantees: the output folder is locked ([`DirLock`], a second run
//!   fails at once and names the process holding it); if the run fails before `commit` (error,
//!   panic, early return, SIGINT/SIGTERM), the output folder is exactly as it was (folders that
//!   did not exist before and are still empty are removed again); `commit` first checks every
//!   destination ([`check_destinations`]: no device, FIFO, socket, folder or symbolic link and
//!   no input of the run is ever replaced) so that on a conflict nothing moves, and undoes the
//!   moves already done if a later one fails. Only a crash in the middle of `commit` can leave
//!   some files new and some old, never a truncated file; write the file that marks a run as
//!   complete (e.g. `report.html`) last. Files in the output folder that the run does not write
//!   are left alone, so pointing `--out` at a folder holding other data is safe. Stages of dead
//!   processes are removed by the next run ([`remove_stale`]).

use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Counter that makes temporary names unique within this process (the pid makes them unique
/// across processes).
static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Prefix of every temporary file or staging directory this module creates.
pub const TMP_PREFIX: &str = ".ofmpc-tmp-";

/// Adds the path to an I/O error so the message says which file failed.
fn with_path(e: io::Error, what: &str, path: &Path) -> io::Error {
    io::Error::new(e.kind(), format!("{what} {}: {e}", path.display()))
}

/// A fresh name `<dir>/.ofmpc-tmp-<pid>-<n>-<stem>` next to `path`.
fn tmp_sibling(dir: &Path, stem: &str) -> PathBuf {
    let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    dir.join(format!("{TMP_PREFIX}{}-{n}-{stem}", std::process::id()))
}

/// The directory holding `path` (`.` for a bare file name).
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Makes a completed rename durable by fsyncing the directory. Best effort: some file systems
/// do not support fsync on directories, and the rename itself has already happened.
fn sync_dir(dir: &Path) {
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
}

/// Removes a temporary file when dropped unless [`TmpGuard::disarm`] was called; this covers
/// errors and panics alike.
struct TmpGuard {
    path: PathBuf,
    armed: bool,
}

impl TmpGuard {
    fn disarm(&mut self) {
        self.armed = false;
    }
}

impl Drop for TmpGuard {
    fn drop(&mut self) {
        if self.armed {
            let _ = fs::remove_file(&self.path);
        }
    }
}

/// Writes `bytes` to `path` atomically: temporary file in the same directory, fsync, rename over
/// the target. On failure the target is untouched and no temporary file remains.
///
/// The parent directory must exist. The new file gets default permissions (those of a newly
/// created file), not those of the file it replaces.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Like [`write_atomic`], but the content is produced by `fill`, which writes into the
/// temporary file. If `fill` returns an error (or panics), the temporary file is removed, the
/// target is untouched and the error is returned.
pub fn write_atomic_with<F>(path: &Path, fill: F) -> io::Result<()>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{} is not a file path (no file name)", path.display()),
        )
    })?;
    let dir = parent_dir(path);
    // A rename would replace a device, FIFO, socket, folder or symbolic link at `path` by a
    // regular file (as root, `/dev/null` included): refuse anything but a regular file.
    if let Ok(m) = fs::symlink_metadata(path) {
        if !m.file_type().is_file() {
            return Err(io::Error::new(
                io::ErrorKind::AlreadyExists,
                format!(
                    "{} is {}, not a regular file: it is never replaced",
                    path.display(),
                    describe(m.file_type())
                ),
            ));
        }
    }
    let stem = name.to_string_lossy();
    // create_new never reuses an existing file; on the (unlikely) collision take the next number.
    let (file, tmp) = loop {
        let tmp = tmp_sibling(dir, &stem);
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => break (f, tmp),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(with_path(e, "cannot create temporary file", &tmp)),
        }
    };
    let mut guard = TmpGuard {
        path: tmp,
        armed: true,
    };
    let mut w = io::BufWriter::new(file);
    fill(&mut w).map_err(|e| with_path(e, "cannot write", path))?;
    let file = w
        .into_inner()
        .map_err(|e| with_path(e.into_error(), "cannot write", path))?;
    file.sync_all()
        .map_err(|e| with_path(e, "cannot flush to disk", path))?;
    drop(file);
    fs::rename(&guard.path, path).map_err(|e| with_path(e, "cannot replace", path))?;
    guard.disarm();
    sync_dir(dir);
    Ok(())
}

/// Checks that `rel` is a plain relative path (no root, no `..`, not empty) so staged files
/// cannot escape the output directory.
fn check_relative(rel: &Path) -> io::Result<()> {
    let ok =
        rel.components().count() > 0 && rel.components().all(|c| matches!(c, Component::Normal(_)));
    if ok {
        Ok(())
    } else {
        Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "output file name {:?} must be a relative path inside the output directory \
                 (no leading '/', no '..')",
                rel
            ),
        ))
    }
}

/// Prefix of a staging folder: `.ofmpc-stage-<pid>-<n>` (the pid lets the next run tell a stage
/// of a dead process from one of a live run).
pub const STAGE_PREFIX: &str = ".ofmpc-stage-";

/// Name of the lock file in an output folder; it holds the pid of the run writing there.
pub const LOCK_NAME: &str = ".ofmpc-lock";

/// Whether process `pid` is alive: `Some` on Linux (from `/proc`), `None` where this cannot be
/// told (no `/proc`): then nothing is treated as stale.
pub fn pid_alive(pid: u32) -> Option<bool> {
    if cfg!(target_os = "linux") && Path::new("/proc/self").exists() {
        Some(Path::new(&format!("/proc/{pid}")).exists())
    } else {
        None
    }
}

/// Whether this process's user owns the file of `meta` (Unix; elsewhere always true). With
/// `/proc` mounted `hidepid`, other users' processes are invisible: their stages and locks must
/// not be taken for stale, so only our own user's are.
fn owned_by_me(meta: &fs::Metadata) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match fs::metadata("/proc/self") {
            Ok(me) => me.uid() == meta.uid(),
            Err(_) => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        true
    }
}

/// The pid in a name `<prefix><pid>-...`.
fn pid_of(name: &str) -> Option<u32> {
    let rest = name
        .strip_prefix(STAGE_PREFIX)
        .or_else(|| name.strip_prefix(TMP_PREFIX))?;
    rest.split('-').next()?.parse().ok()
}

/// Removes staging folders and temporary files in `dir` left by processes that no longer run
/// (killed with SIGKILL, power loss); returns what was removed.
pub fn remove_stale(dir: &Path) -> Vec<PathBuf> {
    let mut removed = Vec::new();
    let Ok(entries) = fs::read_dir(dir) else {
        return removed;
    };
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(pid) = pid_of(&name.to_string_lossy()) else {
            continue;
        };
        if pid == std::process::id() || pid_alive(pid) != Some(false) {
            continue;
        }
        if !e.metadata().is_ok_and(|m| owned_by_me(&m)) {
            continue;
        }
        let path = e.path();
        let gone = match e.file_type() {
            Ok(t) if t.is_dir() => fs::remove_dir_all(&path),
            _ => fs::remove_file(&path),
        };
        if gone.is_ok() {
            removed.push(path);
        }
    }
    removed
}

/// Exclusive use of an output folder by one process: the file [`LOCK_NAME`] in it, held open
/// with an exclusive `flock` (on Unix; `LockFileEx` elsewhere) for as long as the run writes,
/// and removed on drop. The kernel releases the lock when the process ends in any way (even
/// `kill -9`), and it holds across PID namespaces and containers sharing the folder: whether the
/// lock is held never depends on seeing the holder's pid. The pid written in the file is only
/// information (named in the message), and a file nobody holds is stale and taken over, unless
/// it names a live process of this namespace (a run of an ofmpc that did not lock the file) or
/// no pid at all (then it is respected, with a hint).
#[derive(Debug)]
pub struct DirLock {
    path: PathBuf,
    /// The open, locked file (the lock lives as long as it stays open).
    _file: File,
}

impl DirLock {
    /// Takes the lock of `dir` (which must exist). Fails at once if another process holds
    /// it, naming that process.
    pub fn acquire(dir: &Path) -> io::Result<Self> {
        let path = dir.join(LOCK_NAME);
        let me = std::process::id();
        for _ in 0..8 {
            // A complete file with our pid, locked before it appears under its name.
            match create_locked(&path, format!("{me}\n").as_bytes()) {
                Ok(Some(file)) => return Ok(Self { path, _file: file }),
                Ok(None) => {}
                Err(e) => return Err(with_path(e, "cannot create lock file", &path)),
            }
            let mut file = match OpenOptions::new().read(true).write(true).open(&path) {
                Ok(f) => f,
                Err(e) if e.kind() == io::ErrorKind::NotFound => continue, // removed meanwhile
                Err(e) => return Err(with_path(e, "cannot open lock file", &path)),
            };
            // The pid only, as information: at most 64 bytes of a regular file (a FIFO or a
            // huge file put there is never read whole, never waited on).
            let held = read_pid_text(&path);
            let pid = held.as_deref().and_then(|t| t.trim().parse::<u32>().ok());
            match file.try_lock() {
                Ok(()) => {}
                Err(fs::TryLockError::WouldBlock) => return Err(in_use(dir, &path, pid)),
                Err(fs::TryLockError::Error(e)) => return Err(with_path(e, "cannot lock", &path)),
            }
            // Locked: but is it still the file under the name (its holder may have removed it
            // between our open and our lock)?
            if !same_file(&file, &path) {
                continue;
            }
            let mine = fs::symlink_metadata(&path).is_ok_and(|m| owned_by_me(&m));
            match pid.map(|p| (p, pid_alive(p))) {
                // Nobody holds it and its process is gone: stale, ours now.
                Some((p, Some(false))) if mine && p != me => {
                    file.set_len(0)?;
                    file.write_all(format!("{me}\n").as_bytes())?;
                    return Ok(Self { path, _file: file });
                }
                Some((p, _)) => return Err(in_use(dir, &path, Some(p))),
                None => return Err(in_use(dir, &path, None)),
            }
        }
        Err(in_use(dir, &path, None))
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for DirLock {
    fn drop(&mut self) {
        // Removed while still locked; a process that opened it meanwhile sees, once it gets the
        // lock, that the name no longer leads to its file and starts again.
        let _ = fs::remove_file(&self.path);
    }
}

/// The first 64 bytes of a lock file as text, if it is a regular file (never a FIFO, which a
/// read would wait on, nor more than a pid's worth of a huge file).
fn read_pid_text(path: &Path) -> Option<String> {
    use std::io::Read;
    if !fs::symlink_metadata(path).ok()?.is_file() {
        return None;
    }
    let mut text = String::new();
    fs::File::open(path)
        .ok()?
        .take(64)
        .read_to_string(&mut text)
        .ok()?;
    Some(text)
}

/// Whether `path` names the open `file` (same device and inode on Unix).
fn same_file(file: &File, path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (file.metadata(), fs::metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = file;
        path.exists()
    }
}

/// Creates `path` holding `bytes`, locked: a temporary file is written and locked, then
/// hard-linked to `path`, so the name appears complete and already held. `None` if something
/// is at `path` already. Falls back to `create_new` + lock + write on file systems without hard
/// links.
fn create_locked(path: &Path, bytes: &[u8]) -> io::Result<Option<File>> {
    let dir = parent_dir(path);
    let tmp = tmp_sibling(dir, "lock");
    let mut f = OpenOptions::new()
        .read(true)
        .write(true)
        .create_new(true)
        .open(&tmp)?;
    let _guard = TmpGuard {
        path: tmp.clone(),
        armed: true,
    };
    f.write_all(bytes)?;
    f.try_lock().map_err(io::Error::from)?;
    match fs::hard_link(&tmp, path) {
        Ok(()) => Ok(Some(f)),
        Err(e) if e.kind() == io::ErrorKind::AlreadyExists => Ok(None),
        Err(_) => {
            let mut f = match OpenOptions::new()
                .read(true)
                .write(true)
                .create_new(true)
                .open(path)
            {
                Ok(f) => f,
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => return Ok(None),
                Err(e) => return Err(e),
            };
            f.try_lock().map_err(io::Error::from)?;
            f.write_all(bytes)?;
            Ok(Some(f))
        }
    }
}

/// The error of a folder locked by another process.
fn in_use(dir: &Path, lock: &Path, pid: Option<u32>) -> io::Error {
    let who = match pid {
        Some(p) => format!("process {p} (another ofmpc run)"),
        None => "another process".to_string(),
    };
    io::Error::new(
        io::ErrorKind::WouldBlock,
        format!(
            "the output folder {} is in use by {who}: wait for it to finish or choose another \
             --out (if no such process runs, delete {})",
            dir.display(),
            lock.display()
        ),
    )
}

/// What a file-system entry is, in words.
fn describe(t: fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_fifo() {
            return "a named pipe (FIFO)";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_symlink() {
        "a symbolic link"
    } else if t.is_dir() {
        "a folder"
    } else if t.is_file() {
        "a file"
    } else {
        "not a regular file"
    }
}

/// Identity of a file (device and inode on Unix; the canonical path elsewhere).
#[derive(Debug, Clone, PartialEq, Eq)]
struct FileId(#[cfg(unix)] (u64, u64), #[cfg(not(unix))] PathBuf);

impl FileId {
    fn of(path: &Path) -> Option<Self> {
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            let m = fs::metadata(path).ok()?;
            Some(Self((m.dev(), m.ino())))
        }
        #[cfg(not(unix))]
        {
            Some(Self(fs::canonicalize(path).ok()?))
        }
    }
}

/// An input of a run that its outputs must never replace (scenario, program, robot, drives).
#[derive(Debug, Clone)]
pub struct Input {
    /// How the user named it (for the message).
    pub path: PathBuf,
    /// What it is, e.g. "the scenario file".
    pub role: String,
    id: Option<FileId>,
}

impl Input {
    /// An input file; one that does not exist (a built-in program) protects nothing.
    pub fn new(path: impl Into<PathBuf>, role: impl Into<String>) -> Self {
        let path = path.into();
        let id = FileId::of(&path);
        Self {
            path,
            role: role.into(),
            id,
        }
    }
}

/// Checks, before anything is written, that the files `rels` (relative paths) can be put into
/// `target`: every existing destination is a regular file (not a folder, device, FIFO, socket
/// or symbolic link) and none is one of `inputs`; every folder on the way is a real folder.
/// All conflicts are listed in one error (kind `AlreadyExists`), so that the user can fix them
/// at once. A missing `target` is fine (it will be created).
pub fn check_destinations(target: &Path, rels: &[PathBuf], inputs: &[Input]) -> io::Result<()> {
    let mut conflicts: Vec<String> = Vec::new();
    let mut push = |c: String| {
        if !conflicts.contains(&c) {
            conflicts.push(c);
        }
    };
    match fs::metadata(target) {
        Ok(m) if !m.is_dir() => push(format!(
            "{} is {}, not a folder",
            target.display(),
            describe(m.file_type())
        )),
        _ => {}
    }
    for rel in rels {
        check_relative(rel)?;
        destination_conflicts(target, rel, inputs, &mut push);
    }
    if conflicts.is_empty() {
        return Ok(());
    }
    Err(io::Error::new(
        io::ErrorKind::AlreadyExists,
        format!(
            "nothing was written to {}: {}. Move {} away or choose another output path",
            target.display(),
            conflicts.join("; "),
            if conflicts.len() == 1 { "it" } else { "them" }
        ),
    ))
}

/// The conflicts of writing `rel` into `target` (see [`check_destinations`]), each given to
/// `push`: a component on the way that is not a folder, a destination that is not a regular
/// file, or one that is an input of this run.
fn destination_conflicts(
    target: &Path,
    rel: &Path,
    inputs: &[Input],
    push: &mut dyn FnMut(String),
) {
    let comps: Vec<Component> = rel.components().collect();
    let mut cur = target.to_path_buf();
    for (i, c) in comps.iter().enumerate() {
        cur.push(c);
        let last = i + 1 == comps.len();
        let meta = match fs::symlink_metadata(&cur) {
            Ok(m) => m,
            Err(e) if e.kind() == io::ErrorKind::NotFound => break,
            Err(e) => {
                push(format!("{}: {e}", cur.display()));
                break;
            }
        };
        let t = meta.file_type();
        if !last {
            if !t.is_dir() {
                push(format!(
                    "{} is {}, where this run writes a folder",
                    cur.display(),
                    describe(t)
                ));
                break;
            }
            continue;
        }
        if !t.is_file() {
            let what = match fs::read_link(&cur) {
                Ok(to) => format!("a symbolic link to {}", to.display()),
                Err(_) => describe(t).to_string(),
            };
            push(format!(
                "{} is {what}, where this run writes a file (it is never replaced or \
                 written through)",
                cur.display()
            ));
        } else if let Some(input) = inputs
            .iter()
            .find(|i| i.id.is_some() && i.id == FileId::of(&cur))
        {
            push(format!(
                "{} is {} of this run ({}); it is never overwritten",
                cur.display(),
                input.role,
                input.path.display()
            ));
        }
    }
}

/// An output folder whose files appear only when the whole run succeeded.
///
/// [`StagedDir::new`] takes the folder's lock ([`DirLock`]: a second run into the same folder
/// fails at once and names the process), removes staging folders of dead runs, and creates a
/// hidden staging folder `<target>/.ofmpc-stage-<pid>-<n>` (same file system as the target,
/// so moving files is a rename). Files are written there and moved into `target` by
/// [`StagedDir::commit`], which first checks every destination ([`check_destinations`]): on a
/// conflict nothing moves. Dropping a `StagedDir` without committing, or SIGINT/SIGTERM (see
/// [`super::cleanup`]), removes the staging folder, the lock, and `target` too if this value
/// created it and it is still empty.
#[derive(Debug)]
pub struct StagedDir {
    target: PathBuf,
    staging: PathBuf,
    /// Folders this value created (the target and missing parents), outermost first.
    created_dirs: Vec<PathBuf>,
    /// Relative paths in the order they were written (commit order); no duplicates.
    files: Vec<PathBuf>,
    /// Files the run reads: never overwritten.
    inputs: Vec<Input>,
    lock: Option<DirLock>,
    /// Registration ids in [`super::cleanup`].
    cleanup_ids: Vec<u64>,
    /// Stale staging folders of dead runs removed by [`StagedDir::new`].
    removed_stale: Vec<PathBuf>,
    done: bool,
}

/// An error when `target` exists and is not a folder (a file, a device, a link to one).
fn refuse_non_folder(target: &Path) -> io::Result<()> {
    match fs::metadata(target) {
        Ok(m) if !m.is_dir() => Err(io::Error::new(
            io::ErrorKind::AlreadyExists,
            format!(
                "the output folder {} is {}, not a folder: choose another output path",
                target.display(),
                describe(m.file_type())
            ),
        )),
        _ => Ok(()),
    }
}

impl StagedDir {
    /// Prepares `target` (created with its parents if missing), takes its lock, removes stale
    /// stages of dead runs and creates an empty staging folder. `target` must be a folder (a
    /// symbolic link to one is followed: the caller says so).
    pub fn new(target: &Path) -> io::Result<Self> {
        refuse_non_folder(target)?;
        let mut reg = super::cleanup::lock();
        let mut cleanup_ids = Vec::new();
        // Every folder this creates, outermost first; registered so that they go on a signal.
        let mut created_dirs: Vec<PathBuf> = target
            .ancestors()
            .take_while(|a| !a.as_os_str().is_empty() && !a.exists())
            .map(Path::to_path_buf)
            .collect();
        created_dirs.reverse();
        for d in &created_dirs {
            cleanup_ids.push(super::cleanup::register_empty_dir(&mut reg, d.clone()));
        }
        let fail = |reg: &mut Vec<_>, ids: &[u64], e: io::Error| {
            super::cleanup::unregister(reg, ids);
            for d in created_dirs.iter().rev() {
                let _ = fs::remove_dir(d);
            }
            e
        };
        if let Err(e) = fs::create_dir_all(target) {
            let e = with_path(e, "cannot create output directory", target);
            return Err(fail(&mut reg, &cleanup_ids, e));
        }
        let lock = match DirLock::acquire(target) {
            Ok(l) => l,
            Err(e) => return Err(fail(&mut reg, &cleanup_ids, e)),
        };
        cleanup_ids.push(super::cleanup::register_file(
            &mut reg,
            lock.path().to_path_buf(),
        ));
        let removed_stale = remove_stale(target);
        let staging = loop {
            let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
            let s = target.join(format!("{STAGE_PREFIX}{}-{n}", std::process::id()));
            match fs::create_dir(&s) {
                Ok(()) => break s,
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
                Err(e) => {
                    drop(lock);
                    let e = with_path(e, "cannot create staging directory", &s);
                    return Err(fail(&mut reg, &cleanup_ids, e));
                }
            }
        };
        cleanup_ids.push(super::cleanup::register_tree(&mut reg, staging.clone()));
        Ok(Self {
            target: target.to_path_buf(),
            staging,
            created_dirs: created_dirs.clone(),
            files: Vec::new(),
            inputs: Vec::new(),
            lock: Some(lock),
            cleanup_ids,
            removed_stale,
            done: false,
        })
    }

    /// The final output directory.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Where the staged (not yet committed) files live.
    pub fn staging(&self) -> &Path {
        &self.staging
    }

    /// Relative paths written so far, in commit order.
    pub fn files(&self) -> &[PathBuf] {
        &self.files
    }

    /// Staging folders of dead runs that [`StagedDir::new`] removed.
    pub fn removed_stale(&self) -> &[PathBuf] {
        &self.removed_stale
    }

    /// Declares the files this run reads: [`StagedDir::commit`] refuses to replace any of them.
    pub fn protect(&mut self, inputs: impl IntoIterator<Item = Input>) {
        self.inputs.extend(inputs);
    }

    /// Checks planned destinations now (before a long computation), like `commit` will.
    pub fn check(&self, rels: &[PathBuf]) -> io::Result<()> {
        check_destinations(&self.target, rels, &self.inputs)
    }

    /// Stages `bytes` as `rel` (a relative path, subdirectories allowed). Writing the same `rel`
    /// twice replaces the staged content; it keeps its first position in the commit order.
    pub fn write(&mut self, rel: impl AsRef<Path>, bytes: &[u8]) -> io::Result<()> {
        self.write_with(rel, |w| w.write_all(bytes))
    }

    /// Stages a file whose content `fill` writes. On error the file is not staged (a previous
    /// version staged under the same name stays).
    pub fn write_with<F>(&mut self, rel: impl AsRef<Path>, fill: F) -> io::Result<()>
    where
        F: FnOnce(&mut dyn Write) -> io::Result<()>,
    {
        let rel = rel.as_ref();
        check_relative(rel)?;
        let dest = self.staging.join(rel);
        let dir = parent_dir(&dest);
        // Held while writing: a signal handler waits, so it cannot remove the staging folder
        // under this write and have it recreated by `create_dir_all`.
        let _reg = super::cleanup::lock();
        fs::create_dir_all(dir).map_err(|e| with_path(e, "cannot create directory", dir))?;
        write_atomic_with(&dest, fill)?;
        if !self.files.iter().any(|f| f == rel) {
            self.files.push(rel.to_path_buf());
        }
        Ok(())
    }

    /// Checks every destination ([`check_destinations`]; on a conflict nothing moves and the
    /// error lists them all), then moves every staged file into the target directory (one
    /// atomic rename per file, in write order), fsyncs the directories, removes the staging
    /// directory and releases the lock. A signal arriving meanwhile waits for the end.
    ///
    /// If a move fails anyway (an I/O error, a folder created meanwhile by another program),
    /// the moves already done are undone: each replaced file was first hard-linked (or copied)
    /// into the staging folder and is put back, new files and folders are removed, so the target
    /// is as before. Only a crash in the middle can leave a mixture (never a truncated file).
    pub fn commit(mut self) -> io::Result<()> {
        let mut reg = super::cleanup::lock();
        check_destinations(&self.target, &self.files, &self.inputs)?;
        let backups = self.staging.join(".ofmpc-replaced");
        let mut undo = Undo::default();
        let mut dirs_to_sync: Vec<PathBuf> = vec![self.target.clone()];
        for (i, rel) in self.files.iter().enumerate() {
            let from = self.staging.join(rel);
            let to = self.target.join(rel);
            let dir = parent_dir(&to).to_path_buf();
            let step = (|| {
                for d in missing_dirs(&dir) {
                    fs::create_dir(&d).map_err(|e| with_path(e, "cannot create directory", &d))?;
                    undo.dirs.push(d);
                }
                let backup = if to.exists() {
                    let b = backups.join(rel);
                    fs::create_dir_all(parent_dir(&b))?;
                    fs::hard_link(&to, &b)
                        .or_else(|_| fs::copy(&to, &b).map(|_| ()))
                        .map_err(|e| with_path(e, "cannot keep a copy of", &to))?;
                    Some(b)
                } else {
                    None
                };
                fault_injection(i)?;
                fs::rename(&from, &to).map_err(|e| with_path(e, "cannot move into place", &to))?;
                undo.moved.push((to.clone(), backup));
                Ok::<(), io::Error>(())
            })();
            if let Err(e) = step {
                undo.run();
                return Err(io::Error::new(
                    e.kind(),
                    format!("{e}; the files moved before were put back, nothing changed"),
                ));
            }
            if !dirs_to_sync.contains(&dir) {
                dirs_to_sync.push(dir);
            }
        }
        for d in &dirs_to_sync {
            sync_dir(d);
        }
        self.done = true;
        super::cleanup::unregister(&mut reg, &self.cleanup_ids);
        let removed = fs::remove_dir_all(&self.staging)
            .map_err(|e| with_path(e, "cannot remove staging directory", &self.staging));
        self.lock = None;
        drop(reg);
        removed
    }
}

/// Folders on the way to `dir` that do not exist yet, outermost first.
fn missing_dirs(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = dir
        .ancestors()
        .take_while(|a| !a.as_os_str().is_empty() && !a.exists())
        .map(Path::to_path_buf)
        .collect();
    v.reverse();
    v
}

/// What [`StagedDir::commit`] did so far, to undo it on a failure.
#[derive(Default)]
struct Undo {
    /// Destination and the kept copy of the file it replaced (None: it was new).
    moved: Vec<(PathBuf, Option<PathBuf>)>,
    /// Folders created, outermost first.
    dirs: Vec<PathBuf>,
}

impl Undo {
    fn run(&mut self) {
        for (to, backup) in self.moved.drain(..).rev() {
            let _ = match backup {
                Some(b) => fs::rename(&b, &to),
                None => fs::remove_file(&to),
            };
        }
        for d in self.dirs.drain(..).rev() {
            let _ = fs::remove_dir(&d);
        }
    }
}

#[cfg(test)]
thread_local! {
    /// Test hook: the commit step (index) that fails, on this thread only.
    static FAIL_AT: std::cell::Cell<Option<usize>> = const { std::cell::Cell::new(None) };
}

/// Test hook: fails step `i` of a commit when a test asked for it (no-op in the binary).
fn fault_injection(i: usize) -> io::Result<()> {
    #[cfg(test)]
    if FAIL_AT.with(|f| f.get()) == Some(i) {
        return Err(io::Error::other("injected failure"));
    }
    let _ = i;
    Ok(())
}

impl Drop for StagedDir {
    fn drop(&mut self) {
        let mut reg = super::cleanup::lock();
        super::cleanup::unregister(&mut reg, &self.cleanup_ids);
        if !self.done {
            let _ = fs::remove_dir_all(&self.staging);
            self.lock = None;
            // Each succeeds only if nothing else was put there meanwhile.
            for d in self.created_dirs.iter().rev() {
                let _ = fs::remove_dir(d);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Names in `dir` (not recursive), sorted.
    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn write_atomic_creates_and_replaces() {
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("a.txt");
        write_atomic(&p, b"first").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"first");
        write_atomic(&p, b"second, longer content").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"second, longer content");
        write_atomic(&p, b"").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"");
        assert_eq!(names(tmp.path()), vec!["a.txt"]);
    }

    #[test]
    fn failing_writer_leaves_old_file_and_no_temp() {
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("data.csv");
        write_atomic(&p, b"old complete content\n").unwrap();
        // Writes more than the BufWriter capacity so partial bytes really reach the temp file.
        let err = write_atomic_with(&p, |w| {
            w.write_all(&vec![b'x'; 100_000])?;
            Err(io::Error::other("simulated failure mid-way"))
        })
        .unwrap_err();
        assert!(
            err.to_string().contains("simulated failure mid-way"),
            "{err}"
        );
        assert!(err.to_string().contains("data.csv"), "{err}");
        assert_eq!(fs::read(&p).unwrap(), b"old complete content\n");
        assert_eq!(names(tmp.path()), vec!["data.csv"]);
    }

    #[test]
    fn panicking_writer_leaves_no_temp() {
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("x.bin");
        let r = std::panic::catch_unwind(|| {
            let _ = write_atomic_with(&p, |w| {
                w.write_all(b"partial")?;
                panic!("producer bug");
            });
        });
        assert!(r.is_err());
        assert!(names(tmp.path()).is_empty());
    }

    #[test]
    fn failure_without_target_creates_nothing() {
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("new.txt");
        let _ = write_atomic_with(&p, |_| Err(io::Error::other("no"))).unwrap_err();
        assert!(names(tmp.path()).is_empty());
    }

    #[test]
    fn missing_directory_is_a_clear_error() {
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("no/such/dir/f.txt");
        let e = write_atomic(&p, b"x").unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::NotFound);
        assert!(e.to_string().contains("no/such/dir"), "{e}");
    }

    #[test]
    fn rename_failure_keeps_target_and_removes_temp() {
        // The target is a non-empty directory: rename(file, dir) fails after the temp file was
        // fully written, exercising the late failure path.
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("out");
        fs::create_dir(&p).unwrap();
        fs::write(p.join("keep"), b"k").unwrap();
        assert!(write_atomic(&p, b"data").is_err());
        assert_eq!(names(tmp.path()), vec!["out"]);
        assert_eq!(fs::read(p.join("keep")).unwrap(), b"k");
    }

    #[test]
    fn staged_dir_commits_all_files() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("run");
        fs::create_dir(&out).unwrap();
        fs::write(out.join("unrelated.txt"), b"user data").unwrap();
        fs::write(out.join("a.csv"), b"old a").unwrap();
        let mut s = StagedDir::new(&out).unwrap();
        s.write("a.csv", b"new a").unwrap();
        s.write("fig/q.svg", b"<svg/>").unwrap();
        s.write("report.html", b"<html>").unwrap();
        // Nothing visible before commit.
        assert_eq!(fs::read(out.join("a.csv")).unwrap(), b"old a");
        assert!(!out.join("report.html").exists());
        assert_eq!(
            s.files(),
            &[
                PathBuf::from("a.csv"),
                PathBuf::from("fig/q.svg"),
                PathBuf::from("report.html")
            ]
        );
        s.commit().unwrap();
        assert_eq!(fs::read(out.join("a.csv")).unwrap(), b"new a");
        assert_eq!(fs::read(out.join("fig/q.svg")).unwrap(), b"<svg/>");
        assert_eq!(fs::read(out.join("report.html")).unwrap(), b"<html>");
        assert_eq!(fs::read(out.join("unrelated.txt")).unwrap(), b"user data");
        assert_eq!(
            names(&out),
            vec!["a.csv", "fig", "report.html", "unrelated.txt"]
        );
    }

    #[test]
    fn staged_dir_dropped_without_commit_changes_nothing() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("run");
        fs::create_dir(&out).unwrap();
        fs::write(out.join("a.csv"), b"old a").unwrap();
        {
            let mut s = StagedDir::new(&out).unwrap();
            s.write("a.csv", b"new a").unwrap();
            s.write("b.csv", b"new b").unwrap();
            let e = s
                .write_with("c.csv", |w| {
                    w.write_all(b"half")?;
                    Err(io::Error::other("simulation diverged"))
                })
                .unwrap_err();
            assert!(e.to_string().contains("simulation diverged"));
            // The run gives up here: s is dropped without commit.
        }
        assert_eq!(names(&out), vec!["a.csv"]);
        assert_eq!(fs::read(out.join("a.csv")).unwrap(), b"old a");
    }

    #[test]
    fn staged_dir_removes_a_target_it_created() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("fresh/run");
        {
            let mut s = StagedDir::new(&out).unwrap();
            s.write("a.csv", b"a").unwrap();
        }
        assert!(!out.exists());
    }

    #[test]
    fn staged_dir_rejects_escaping_paths() {
        // The output folder inside a folder of the test's own, so that "../x" is a path
        // nobody else creates (the system's temporary folder may hold an `x`).
        let outer = tempfile::tempdir().unwrap();
        let out = outer.path().join("out");
        fs::create_dir(&out).unwrap();
        let mut s = StagedDir::new(&out).unwrap();
        for bad in ["../x", "/etc/x", "", "a/../../b"] {
            let e = s.write(bad, b"x").unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput, "{bad}");
        }
        drop(s);
        assert!(names(&out).is_empty());
        assert!(!outer.path().join("x").exists());
        assert!(!outer.path().join("b").exists());
    }

    #[test]
    fn staged_dir_rewrite_keeps_first_position() {
        let tmp = tempfile::tempdir().unwrap();
        let mut s = StagedDir::new(tmp.path()).unwrap();
        s.write("a", b"1").unwrap();
        s.write("b", b"2").unwrap();
        s.write("a", b"3").unwrap();
        assert_eq!(s.files(), &[PathBuf::from("a"), PathBuf::from("b")]);
        s.commit().unwrap();
        assert_eq!(fs::read(tmp.path().join("a")).unwrap(), b"3");
        assert_eq!(names(tmp.path()), vec!["a", "b"]);
    }

    /// A pid that is not running: a child that has exited (and been reaped).
    fn dead_pid() -> u32 {
        let mut c = std::process::Command::new("true").spawn().unwrap();
        let pid = c.id();
        c.wait().unwrap();
        pid
    }

    #[test]
    fn commit_checks_every_destination_before_the_first_move() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path();
        let mut s = StagedDir::new(out).unwrap();
        s.write("a.csv", b"a").unwrap();
        s.write("run/b.csv", b"b").unwrap();
        s.write("c.csv", b"c").unwrap();
        // Conflicts appear while the run computes: a file where the run folder goes, a folder
        // where the last file goes.
        fs::write(out.join("run"), b"not a folder").unwrap();
        fs::create_dir(out.join("c.csv")).unwrap();
        let e = s.commit().unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("run is a file, where this run writes a folder"),
            "{msg}"
        );
        assert!(
            msg.contains("c.csv is a folder, where this run writes a file"),
            "{msg}"
        );
        // Nothing moved (a.csv, first in order, has no conflict and still did not appear), and
        // the stage and lock are gone.
        assert_eq!(names(out), vec!["c.csv", "run"]);
        assert_eq!(fs::read(out.join("run")).unwrap(), b"not a folder");
    }

    #[test]
    fn inputs_are_protected_at_commit() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path();
        fs::write(out.join("scenario.toml"), b"# mine").unwrap();
        let mut s = StagedDir::new(out).unwrap();
        s.protect([Input::new(out.join("scenario.toml"), "the scenario file")]);
        s.write("x", b"x").unwrap();
        s.write("scenario.toml", b"generated").unwrap();
        let e = s.commit().unwrap_err().to_string();
        assert!(e.contains("is the scenario file of this run"), "{e}");
        assert_eq!(fs::read(out.join("scenario.toml")).unwrap(), b"# mine");
        assert_eq!(names(out), vec!["scenario.toml"]);
    }

    #[test]
    fn the_lock_is_exclusive_names_its_holder_and_stale_locks_are_taken_over() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path();
        let first = StagedDir::new(out).unwrap();
        let e = StagedDir::new(out).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::WouldBlock);
        assert!(
            e.to_string()
                .contains(&format!("in use by process {}", std::process::id())),
            "{e}"
        );
        drop(first);
        assert!(names(out).is_empty());
        // A lock of a dead process is stale.
        if pid_alive(1) == Some(true) {
            fs::write(out.join(LOCK_NAME), format!("{}\n", dead_pid())).unwrap();
            let s = StagedDir::new(out).unwrap();
            assert_eq!(
                fs::read_to_string(out.join(LOCK_NAME)).unwrap().trim(),
                std::process::id().to_string()
            );
            drop(s);
            assert!(names(out).is_empty());
        }
        // An unreadable lock (no pid) is respected, with a hint.
        fs::write(out.join(LOCK_NAME), b"").unwrap();
        let e = StagedDir::new(out).unwrap_err().to_string();
        assert!(
            e.contains("another process") && e.contains(LOCK_NAME),
            "{e}"
        );
    }

    #[test]
    fn stale_stages_of_dead_processes_are_removed() {
        if pid_alive(1) != Some(true) {
            return; // no /proc: nothing is ever treated as stale
        }
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path();
        let dead = dead_pid();
        let me = std::process::id();
        fs::create_dir_all(out.join(format!("{STAGE_PREFIX}{dead}-7/run"))).unwrap();
        fs::write(out.join(format!("{TMP_PREFIX}{dead}-1-a.csv")), b"x").unwrap();
        fs::create_dir(out.join(format!("{STAGE_PREFIX}{me}-99"))).unwrap();
        fs::write(out.join(".ofmpc-stage-notapid"), b"user file").unwrap();
        let s = StagedDir::new(out).unwrap();
        assert_eq!(s.removed_stale().len(), 2);
        drop(s);
        assert_eq!(
            names(out),
            vec![
                format!("{STAGE_PREFIX}{me}-99"),
                ".ofmpc-stage-notapid".into()
            ]
        );
    }

    #[cfg(unix)]
    #[test]
    fn write_atomic_never_replaces_a_link_or_special_file() {
        let tmp = tempfile::tempdir().unwrap();
        let real = tmp.path().join("real.csv");
        fs::write(&real, b"precious").unwrap();
        let link = tmp.path().join("link.csv");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        let e = write_atomic(&link, b"new").unwrap_err().to_string();
        assert!(e.contains("is a symbolic link, not a regular file"), "{e}");
        assert!(fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(fs::read(&real).unwrap(), b"precious");
        let sock = tmp.path().join("s.sock");
        let _l = std::os::unix::net::UnixListener::bind(&sock).unwrap();
        let e = write_atomic(&sock, b"new").unwrap_err().to_string();
        assert!(e.contains("is a socket"), "{e}");
        assert_eq!(names(tmp.path()), vec!["link.csv", "real.csv", "s.sock"]);
    }

    #[test]
    fn a_failing_move_is_undone() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path();
        fs::write(out.join("a.csv"), b"old a").unwrap();
        fs::write(out.join("mine.txt"), b"user").unwrap();
        let mut s = StagedDir::new(out).unwrap();
        s.write("a.csv", b"new a").unwrap();
        s.write("run/b.csv", b"new b").unwrap();
        s.write("c.csv", b"new c").unwrap();
        FAIL_AT.with(|f| f.set(Some(2)));
        let e = s.commit().unwrap_err().to_string();
        FAIL_AT.with(|f| f.set(None));
        assert!(
            e.contains("injected failure") && e.contains("put back"),
            "{e}"
        );
        // a.csv replaced and b.csv (in a new folder) moved in before the failure: both undone.
        assert_eq!(names(out), vec!["a.csv", "mine.txt"]);
        assert_eq!(fs::read(out.join("a.csv")).unwrap(), b"old a");
    }
}
