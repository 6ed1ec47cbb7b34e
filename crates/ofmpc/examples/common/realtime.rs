//! The thread's real-time settings, asked for before a loop (Linux: libc),
//! shared by the examples that time a control loop (`realtime_loop`,
//! `step_budget`): `#[path = "common/realtime.rs"] mod realtime;`.

#[cfg(target_os = "linux")]
pub use linux::request;

#[cfg(target_os = "linux")]
mod linux {
    use std::io::Error;
    use std::mem::{size_of, zeroed};

    /// `SCHED_FIFO` priority asked for (1–99; 80: above the usual interrupt
    /// threads' 50 of a PREEMPT_RT kernel, below the watchdogs').
    const PRIORITY: i32 = 80;

    /// Pins the calling thread to one CPU, locks the process's memory and
    /// asks for `SCHED_FIFO`; one line per request saying what it got.
    pub fn request() -> Vec<String> {
        if std::env::var("OFMPC_RT").as_deref() == Ok("0") {
            return vec!["not requested (OFMPC_RT=0)".into()];
        }
        vec![pin(), lock_memory(), fifo()]
    }

    fn pin() -> String {
        // SAFETY: cpu_set_t is plain data; the calls get valid pointers and sizes.
        unsafe {
            let mut allowed: libc::cpu_set_t = zeroed();
            if libc::sched_getaffinity(0, size_of::<libc::cpu_set_t>(), &mut allowed) != 0 {
                return format!("not pinned (sched_getaffinity: {})", Error::last_os_error());
            }
            let last = (0..libc::CPU_SETSIZE as usize)
                .rev()
                .find(|&c| libc::CPU_ISSET(c, &allowed));
            let cpu = match std::env::var("OFMPC_RT_CPU")
                .ok()
                .map(|v| v.parse::<usize>())
            {
                Some(Ok(c)) => Some(c),
                Some(Err(_)) => return "not pinned: OFMPC_RT_CPU is not a CPU number".into(),
                None => last,
            };
            let Some(cpu) = cpu.filter(|&c| c < libc::CPU_SETSIZE as usize) else {
                return "not pinned: no CPU to pin to".into();
            };
            let mut set: libc::cpu_set_t = zeroed();
            libc::CPU_SET(cpu, &mut set);
            if libc::sched_setaffinity(0, size_of::<libc::cpu_set_t>(), &set) == 0 {
                format!("pinned to CPU {cpu}")
            } else {
                format!("not pinned to CPU {cpu} ({})", Error::last_os_error())
            }
        }
    }

    /// Locks the process's memory (`mlockall`, current and future pages: no
    /// page is faulted in on its first touch inside a step); says what it got.
    fn lock_memory() -> String {
        // SAFETY: no pointers; affects this process only.
        if unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) } == 0 {
            "memory locked (mlockall: no page faults in the loop)".into()
        } else {
            format!(
                "memory not locked ({}; needs CAP_IPC_LOCK or RLIMIT_MEMLOCK)",
                Error::last_os_error()
            )
        }
    }

    fn fifo() -> String {
        let param = libc::sched_param {
            sched_priority: PRIORITY,
        };
        // SAFETY: a valid sched_param; affects the calling thread only.
        let rc =
            unsafe { libc::pthread_setschedparam(libc::pthread_self(), libc::SCHED_FIFO, &param) };
        if rc == 0 {
            format!("SCHED_FIFO, priority {PRIORITY}")
        } else {
            // pthread calls return the error number.
            format!(
                "SCHED_OTHER (SCHED_FIFO refused: {}; needs CAP_SYS_NICE or RLIMIT_RTPRIO)",
                Error::from_raw_os_error(rc)
            )
        }
    }
}

/// Elsewhere: nothing asked for.
#[cfg(not(target_os = "linux"))]
pub fn request() -> Vec<String> {
    vec!["pinning, memory locking and SCHED_FIFO are requested on Linux only".into()]
}
