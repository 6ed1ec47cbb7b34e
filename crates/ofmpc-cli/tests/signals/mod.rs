//! Children of the signal tests start with SIGINT, SIGTERM and SIGHUP at their default
//! dispositions, whatever the test runner inherited: a CI job started in the background by a
//! shell without job control ignores SIGINT, and the CLI keeps a signal it inherits as ignored
//! (`nohup`), so without this the tests would depend on how they were started.

use std::process::Command;

/// `cmd` with SIGINT, SIGTERM and SIGHUP reset to `SIG_DFL` in the child before `exec`.
pub fn with_default_signals(cmd: &mut Command) -> &mut Command {
    use std::os::unix::process::CommandExt;
    // SAFETY: between fork and exec the closure only calls signal(2), which is
    // async-signal-safe, and allocates nothing.
    unsafe {
        cmd.pre_exec(|| {
            for s in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
                libc::signal(s, libc::SIG_DFL);
            }
            Ok(())
        })
    }
}
