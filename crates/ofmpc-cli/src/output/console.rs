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

/// Progress on stderr when it is not a terminal (a pipe, a CI log): a line every
/// [`PlainProgress::EVERY`] at most, from any thread ([`PlainProgress::inc`] is lock-free).
pub struct PlainProgress {
    total: u64,
    done: std::sync::atomic::AtomicU64,
    start: std::time::Instant,
    /// Milliseconds after `start` of the last line.
    last_ms: std::sync::atomic::AtomicU64,
}

impl PlainProgress {
    /// Seconds between two lines.
    pub const EVERY: std::time::Duration = std::time::Duration::from_secs(5);

    /// Progress over `total` samples.
    pub fn new(total: u64) -> Self {
        Self {
            total,
            done: 0.into(),
            start: std::time::Instant::now(),
            last_ms: 0.into(),
        }
    }

    /// `samples` more are done; prints a line when [`Self::EVERY`] has passed since the last.
    pub fn inc(&self, samples: u64) {
        use std::sync::atomic::Ordering::Relaxed;
        let done = self.done.fetch_add(samples, Relaxed) + samples;
        let now = self.start.elapsed();
        let now_ms = now.as_millis() as u64;
        let last = self.last_ms.load(Relaxed);
        if now_ms < last + Self::EVERY.as_millis() as u64 {
            return;
        }
        if self
            .last_ms
            .compare_exchange(last, now_ms, Relaxed, Relaxed)
            .is_ok()
        {
            let _ = writeln!(
                io::stderr().lock(),
                "{}",
                self.line(done, now.as_secs_f64())
            );
        }
    }

    /// The line for `done` samples after `elapsed_s` seconds.
    pub fn line(&self, done: u64, elapsed_s: f64) -> String {
        let fraction = if self.total == 0 {
            1.0
        } else {
            (done as f64 / self.total as f64).min(1.0)
        };
        let left = if fraction > 0.0 {
            format!(
                ", about {:.0} s left",
                elapsed_s * (1.0 - fraction) / fraction
            )
        } else {
            String::new()
        };
        format!(
            "progress: {:.0} % ({done} of {} samples) after {elapsed_s:.0} s{left}",
            fraction * 100.0,
            self.total
        )
    }
}

#[cfg(test)]
mod tests {
    use super::PlainProgress;

    #[test]
    fn a_progress_line_says_the_fraction_and_the_time_left() {
        let p = PlainProgress::new(1000);
        assert_eq!(
            p.line(250, 10.0),
            "progress: 25 % (250 of 1000 samples) after 10 s, about 30 s left"
        );
        assert_eq!(
            p.line(0, 0.0),
            "progress: 0 % (0 of 1000 samples) after 0 s"
        );
    }
}
