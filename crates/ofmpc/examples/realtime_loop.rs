//! One controller in a fixed-rate loop, the way to embed it in one's own system:
//! absolute deadlines, every buffer allocated before the loop, nothing allocated in
//! it (counted on this thread by the allocator below), against the library's plant
//! at 1 kHz. Prints the step-time percentiles and the deadline misses.
//!
//! The loop is built from the library's stages as `ofmpc::sim::ClosedLoop` composes
//! them: a [`Sensor`] (reading, repair of invalid values), a [`Supervisor`]
//! (plausibility check, safe stop when the controller fails), the controller, an
//! [`Actuator`] (the drives' loading) and the plant.
//!
//! ```sh
//! cargo run --release -p ofmpc --example realtime_loop               # second algorithm, 4 s
//! cargo run --release -p ofmpc --example realtime_loop -- first 14   # the whole path + hold
//! ```
//!
//! The operating system decides whether the deadlines are met: on a loaded desktop
//! some are missed; on a real-time kernel (PREEMPT_RT) with the thread under
//! `SCHED_FIFO`, pinned to an isolated core and its memory locked (`mlockall`),
//! none should be. Those settings need privileges and are left out here; the loop
//! itself is what matters: it cannot allocate, lock or print.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::time::{Duration, Instant};

use ofmpc::control::{new_controller, Algorithm, ControllerKind, MpcSettings};
use ofmpc::dynamics::RobotDynamics;
use ofmpc::gcode::PAPER_TABLE1;
use ofmpc::motion::{plan, JointReference, PlanOptions};
use ofmpc::robot::{Payload, Robot};
use ofmpc::sim::{
    quantile, Actuator, LoopSettings, LossSchedule, Plant, PlantSettings, Sensor, StopReason,
    Supervisor,
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
    let (reference, mut controller, mut model, mut plant) = set_up(kind)?;
    let n = reference.dof();
    let total = (seconds / TS).round() as usize;
    let horizon = controller.horizon();
    let mut x = vec![0.0; 2 * n];
    let mut tau = vec![0.0; n];
    let mut preview = vec![0.0; horizon * n];
    let mut step_us = vec![0.0; total];
    let mut lateness_us = vec![0.0; total];
    let mut misses = 0usize;
    let mut failure: Option<(usize, ofmpc::control::StepFailure)> = None;
    let mut worst_error = 0.0f64;
    // The stages around the controller, sized here.
    let loop_settings = LoopSettings {
        plausibility_check: true,
        safe_stop: true,
        ..LoopSettings::default()
    };
    let mut sensor = Sensor::new(
        n,
        plant.settings().delay_samples,
        LossSchedule::default(),
        TS,
    );
    let mut supervisor = Supervisor::with_period(
        plant.robot(),
        loop_settings.supervisor(&Default::default()),
        TS,
    );
    let actuator = Actuator::for_robot(plant.robot());
    let mut max_torque_ratio = 0.0f64;
    plant.measure(&mut x)?;
    controller.reset(&x)?;
    sensor.reset(&x);
    supervisor.reset(&x);
    let period = Duration::from_secs_f64(TS);

    // ---- The loop: measure, control, actuate, wait for the next absolute deadline.
    let before = allocations();
    let start = Instant::now();
    let mut release = start; // release time of sample k: start + k·Ts (no drift)
    for k in 0..total {
        let woke = Instant::now();
        lateness_us[k] = woke.saturating_duration_since(release).as_secs_f64() * 1e6;
        let t = k as f64 * TS;
        sensor.read(&mut plant, k, true, &mut x)?; // in a real system: read the encoders
        sensor.repair(&mut model, &mut x); // an invalid value: the model's prediction
        let w = reference.q(k);
        let inspection = supervisor.inspect(&mut x, w);
        if let Some(reason) = inspection.trigger {
            supervisor.begin_stop(t, reason, &x, &mut model);
        }
        reference.preview(k, horizon, &mut preview);
        let t0 = Instant::now();
        let status = if supervisor.stopping().is_some() {
            supervisor.stop_torque(&mut model, &x, &x, &mut tau)
        } else {
            controller
                .step(
                    &mut model,
                    &ofmpc::control::StepInput {
                        x: &x,
                        w_k: w,
                        preview: &preview,
                    },
                    &mut tau,
                )
                .map(|_| ())
        };
        step_us[k] = t0.elapsed().as_secs_f64() * 1e6;
        if let Err(e) = status {
            // Brake and hold; the torque of this sample is the last one.
            failure = failure.or(Some((k, e)));
            supervisor.begin_stop(t, StopReason::ControllerFailed(e), &x, &mut model);
        }
        max_torque_ratio = max_torque_ratio.max(actuator.account(&tau).max_ratio);
        sensor.record_torque(&tau);
        supervisor.record_torque(&tau);
        // In a real system: write τ to the drives. Here the plant integrates it over Ts.
        if plant.advance(&tau).is_err() {
            break;
        }
        for i in 0..n {
            worst_error = worst_error.max((w[i] - x[i]).abs());
        }
        let deadline = release + period;
        let now = Instant::now();
        if now > deadline {
            misses += 1; // this sample's work ran past the next release
        } else {
            std::thread::sleep(deadline - now);
        }
        release = deadline;
    }
    let elapsed = start.elapsed().as_secs_f64();
    let in_loop = allocations() - before;

    // ---- Report (allocates: after the loop).
    report(&Stats {
        kind,
        seconds,
        total,
        elapsed,
        step_us,
        lateness_us,
        misses,
        worst_error,
        max_torque_ratio,
        in_loop,
    });
    if let Some((k, e)) = failure {
        return Err(format!("the controller failed at sample {k} (safe stop): {e}").into());
    }
    if in_loop != 0 {
        return Err(format!("{in_loop} allocations inside the real-time loop").into());
    }
    Ok(())
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
    in_loop: u64,
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
         largest torque / rated {max_torque_ratio:.2}; allocations in the loop: {in_loop}",
        100.0 * misses as f64 / total.max(1) as f64
    );
}

/// The paper's path at 1 kHz, the controller `kind` with its model (no
/// payload), and the plant carrying a 0.25 kg payload the controller does
/// not know.
#[allow(clippy::type_complexity)]
fn set_up(
    kind: ControllerKind,
) -> Result<
    (
        JointReference,
        Box<dyn Algorithm + Send>,
        RobotDynamics,
        Plant,
    ),
    Box<dyn std::error::Error>,
> {
    let robot = Robot::irb140();
    // The library's one planning entry point (parse, time, IK).
    let ts = TS;
    let reference = plan(
        PAPER_TABLE1,
        &robot,
        &PlanOptions {
            ts,
            ..PlanOptions::default()
        },
    )?
    .reference;
    let settings = MpcSettings {
        ts: TS,
        ..MpcSettings::default() // horizon 10 (10 ms ahead), the paper's weights
    };
    let n = robot.dof();
    let controller = new_controller(kind, n, &settings)?;
    let model = RobotDynamics::new(robot.clone()); // the controller's model: no payload
    let mut plant_robot = robot;
    plant_robot.set_payload(Some(Payload::point_mass(0.25)))?; // unknown to the controller
    let plant_settings = PlantSettings {
        substep: TS, // one RK4 step per period
        ..PlantSettings::default()
    };
    let plant = Plant::with_period(plant_robot, plant_settings, reference.q(0), TS)?;
    Ok((reference, controller, model, plant))
}
