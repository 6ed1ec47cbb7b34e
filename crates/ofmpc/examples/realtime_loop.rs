//! One controller in a fixed-rate loop, the way to embed it in one's own system:
//! absolute deadlines, every buffer allocated before the loop, nothing allocated in
//! it (counted on this thread by the allocator below), against the library's plant
//! at 1 kHz. Prints the step-time percentiles and the deadline misses.
//!
//! The loop is built from the library's stages: a [`Sensor`] (the encoders: here of
//! the simulated plant, on a robot the drives' readings), the
//! [`SupervisedController`] (the built controller behind its guard: repair of
//! invalid values, plausibility check, safe stop when the controller fails), an
//! actuator (the drives: saturation, loading) and the plant.
//!
//! ```sh
//! cargo run --release -p ofmpc --example realtime_loop               # second algorithm, 4 s
//! cargo run --release -p ofmpc --example realtime_loop -- first 14   # the whole path + hold
//! ```
//!
//! The operating system decides whether the deadlines are met: on a loaded desktop
//! some are missed; on a real-time kernel (PREEMPT_RT) with the thread under
//! `SCHED_FIFO`, pinned to an isolated core and its memory locked (`mlockall`),
//! none should be. On Linux the example asks for all three before the loop
//! (`OFMPC_RT_CPU=<n>` picks the core, default the last one it may run on;
//! `OFMPC_RT=0` asks for none) and prints what it got: pinning needs nothing,
//! locking memory `CAP_IPC_LOCK` or a large enough `RLIMIT_MEMLOCK`, `SCHED_FIFO`
//! `CAP_SYS_NICE` or an `RLIMIT_RTPRIO` (e.g. `@realtime - rtprio 98` in
//! `/etc/security/limits.conf`); without the rights it runs as it is. The loop
//! itself cannot allocate, lock or print.

#[path = "common/realtime.rs"]
mod realtime;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::time::{Duration, Instant};

use ofmpc::control::{ControllerBuilder, ControllerKind, MpcSettings};
use ofmpc::gcode::PAPER_TABLE1;
use ofmpc::motion::{plan, JointReference, PlanOptions};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{
    quantile, LoopSettings, LossSchedule, Plant, PlantSettings, Sensor, SupervisedController,
    SupervisedInput, SupervisedStatus,
};

/// Counts the allocations of the calling thread (a thread-local counter: other
/// threads' allocations do not count).
struct CountingAllocator;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

fn allocations() -> u64 {
    ALLOCATIONS.with(|c| c.get())
}

/// Control period: 1 kHz.
const TS: f64 = 1e-3;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let kind: ControllerKind = args.next().as_deref().unwrap_or("second").parse()?;
    let seconds: f64 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(4.0);

    // ---- Set-up: everything that allocates happens here, once.
    let (reference, mut guarded, mut plant) = set_up(kind)?;
    for line in realtime::request() {
        println!("realtime: {line}");
    }
    let (n, horizon) = (reference.dof(), guarded.controller().horizon());
    let mut sensor = Sensor::new(plant.settings(), n, TS, LossSchedule::default())?;
    let mut actuator = plant.settings().actuator(plant.robot(), TS);
    let mut stats = Stats::new(kind, seconds, (seconds / TS).round() as usize);
    let (mut x, mut preview) = (vec![0.0; 2 * n], vec![0.0; horizon * n]);
    sensor.measure(&plant.state(), &mut x)?;
    guarded.reset(&x)?;

    // ---- The loop: measure, control, actuate, wait for the next absolute deadline.
    let before = allocations();
    let start = Instant::now();
    let mut release = start; // release time of sample k: start + k·Ts (no drift)
    for k in 0..stats.total {
        stats.lateness_us[k] = release.elapsed().as_secs_f64() * 1e6;
        sensor.read(&plant.state(), k, true, &mut x)?; // in a real system: read the encoders
        let w = reference.q(k);
        reference.preview(k, horizon, &mut preview);
        let t0 = Instant::now();
        let input = SupervisedInput {
            t: k as f64 * TS,
            x: &x,
            w_k: w,
            preview: &preview,
            truth: None,
        };
        let out = guarded.step(&input)?; // a failed step brakes and holds (safe stop)
        stats.step_us[k] = t0.elapsed().as_secs_f64() * 1e6;
        stats.observe(w, &x, out.status, actuator.account(&out.tau).max_ratio);
        // In a real system: write τ to the drives. Here the plant integrates it over Ts.
        let applied = actuator.apply(&out.tau, plant.state().path_sample);
        if applied
            .map_err(Into::into)
            .and_then(|a| plant.advance(a))
            .is_err()
        {
            break;
        }
        release = wait_until(release + Duration::from_secs_f64(TS), &mut stats.misses);
    }
    stats.elapsed = start.elapsed().as_secs_f64();
    stats.in_loop = allocations() - before;

    // ---- Report (allocates: after the loop).
    report(&stats);
    if let Some(reason) = guarded.stop_reason() {
        return Err(format!("safe stop: {reason}").into());
    }
    if stats.in_loop != 0 {
        return Err(format!("{} allocations inside the real-time loop", stats.in_loop).into());
    }
    Ok(())
}

/// Sleeps until `deadline` (counting a miss when the work ran past it);
/// the next release time.
fn wait_until(deadline: Instant, misses: &mut usize) -> Instant {
    let now = Instant::now();
    if now > deadline {
        *misses += 1; // this sample's work ran past the next release
    } else {
        std::thread::sleep(deadline - now);
    }
    deadline
}

/// What one run of the loop measured.
struct Stats {
    kind: ControllerKind,
    seconds: f64,
    total: usize,
    elapsed: f64,
    step_us: Vec<f64>,
    lateness_us: Vec<f64>,
    misses: usize,
    worst_error: f64,
    max_torque_ratio: f64,
    /// Samples whose reading was repaired.
    repaired: usize,
    in_loop: u64,
}

impl Stats {
    /// Room for `total` samples (allocates: before the loop).
    fn new(kind: ControllerKind, seconds: f64, total: usize) -> Self {
        Self {
            kind,
            seconds,
            total,
            elapsed: 0.0,
            step_us: vec![0.0; total],
            lateness_us: vec![0.0; total],
            misses: 0,
            worst_error: 0.0,
            max_torque_ratio: 0.0,
            repaired: 0,
            in_loop: 0,
        }
    }

    /// One sample: the joint error of the reading `x` against `w`, what the
    /// guard did, and the drives' loading.
    fn observe(&mut self, w: &[f64], x: &[f64], status: SupervisedStatus, loading: f64) {
        for (wi, qi) in w.iter().zip(x) {
            self.worst_error = self.worst_error.max((wi - qi).abs());
        }
        self.repaired += usize::from(status == SupervisedStatus::RepairedMeasurement);
        self.max_torque_ratio = self.max_torque_ratio.max(loading);
    }
}

/// Prints the step-time and lateness percentiles and the deadline misses.
fn report(stats: &Stats) {
    let Stats {
        kind,
        seconds,
        total,
        elapsed,
        ref step_us,
        ref lateness_us,
        misses,
        worst_error,
        max_torque_ratio,
        repaired,
        in_loop,
    } = *stats;
    let pct = |v: &[f64], p: f64| quantile(v, p);
    println!(
        "{kind} at {:.0} Hz for {seconds} s ({total} samples, wall {elapsed:.3} s), \
         IRB 140 with an unknown 0.25 kg payload",
        1.0 / TS
    );
    println!(
        "controller step (µs): median {:.1}  p90 {:.1}  p99 {:.1}  p99.9 {:.1}  max {:.1}",
        pct(step_us, 0.5),
        pct(step_us, 0.9),
        pct(step_us, 0.99),
        pct(step_us, 0.999),
        pct(step_us, 1.0)
    );
    println!(
        "wake-up lateness (µs): median {:.1}  p99 {:.1}  max {:.1}",
        pct(lateness_us, 0.5),
        pct(lateness_us, 0.99),
        pct(lateness_us, 1.0)
    );
    println!(
        "deadline misses: {misses} of {total} ({:.2} %); largest joint error {worst_error:.2e} rad; \
         largest torque / rated {max_torque_ratio:.2}; repaired readings: {repaired}; \
         allocations in the loop: {in_loop}",
        100.0 * misses as f64 / total.max(1) as f64
    );
}

/// The paper's path at 1 kHz, the controller `kind` (its model without the
/// payload) behind its guard, and the plant carrying a 0.25 kg payload the
/// controller does not know.
fn set_up(
    kind: ControllerKind,
) -> Result<(JointReference, SupervisedController, Plant), Box<dyn std::error::Error>> {
    let robot = Robot::irb140();
    // The library's one planning entry point (parse, time, IK).
    let options = PlanOptions {
        ts: TS,
        ..PlanOptions::default()
    };
    let reference = plan(PAPER_TABLE1, &robot, &options)?.reference;
    let settings = MpcSettings {
        ts: TS,
        ..MpcSettings::default() // horizon 10 (10 ms ahead), the paper's weights
    };
    let mpc = ControllerBuilder::new(kind, &robot)
        .settings(settings)
        .build()?;
    let guard = LoopSettings {
        plausibility_check: true,
        safe_stop: true,
        ..LoopSettings::default()
    }
    .supervisor(&Default::default());
    let guarded = SupervisedController::new(mpc, &robot, guard, 0, true)?;
    let mut plant_robot = robot;
    plant_robot.set_payload(Some(Payload::point_mass(0.25)))?; // unknown to the controller
    let plant_settings = PlantSettings {
        substep: TS, // one RK4 step per period
        ..PlantSettings::default()
    };
    let plant = Plant::with_period(plant_robot, plant_settings, reference.q(0), TS)?;
    Ok((reference, guarded, plant))
}
