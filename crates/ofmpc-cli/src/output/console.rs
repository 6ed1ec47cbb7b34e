//! The terminal side of the output layer: every line for stdout goes through [`print()`], which
//! returns the I/O error instead of panicking like `println!` does when stdout is closed
//! (`ofmpc inspect robot | head -1`). `main` turns an error of kind
//! [`io::ErrorKind::BrokenPipe`] into a quiet exit with status 0, as ripgrep and coreutils'
//! consumers of `head` expect. Messages for stderr ([`warn`], [`note`]) ignore write errors: a
//! closed stderr must not turn a finished run into a failure.

use std::io::{self, Write};

/// Writes `text` to stdout and flushes it. A closed pipe gives an error of kind
/// [`io::ErrorKind::BrokenPipe`] (Rust ignores SIGPIPE, so the write fails instead of killing
/// the process).
pub fn print(text: &str) -> io::Result<()> {
    let mut out = io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.flush()
}

/// Like [`print()`] with a newline appended.
pub fn println(text: &str) -> io::Result<()> {
    let mut out = io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.write_all(b"\n")?;
    out.flush()
}

/// Prints `warning: <text>` on stderr (errors writing it are ignored).
pub fn warn(text: &str) {
    let _ = writeln!(io::stderr().lock(), "warning: {text}");
}

/// Prints `note: <text>` on stderr (errors writing it are ignored).
pub fn note(text: &str) {
    let _ = writeln!(io::stderr().lock(), "note: {text}");
}

/// Whether `e` (or any error in its chain) is a closed-pipe error on an output stream.
pub fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<io::Error>()
            .is_some_and(|io| io.kind() == io::ErrorKind::BrokenPipe)
    })
}
