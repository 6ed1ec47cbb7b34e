//! A fixed number of controller steps for instruction counts under
//! callgrind (`valgrind --tool=callgrind`): the second algorithm on the IRB 140,
//! N = 10, from rest toward a target, 220 steps (`limits`: with torque limits and a far
//! target, the QP binding; `structured`: the structured solver; `gains`: the structured
//! solver with the first-stage gains). Compare `Controller::step`'s inclusive count between two
//! builds (issue 37: the telemetry's cost):
//!
//! ```sh
//! cargo build --release -p ofmpc --example step_callgrind
//! valgrind --tool=callgrind --callgrind-out-file=cg.out target/release/examples/step_callgrind
//! callgrind_annotate --inclusive=yes cg.out | grep 'Controller::step '
//! ```
use ofmpc::control::{ControllerBuilder, ControllerKind, MpcSettings, StepInput};
use ofmpc::robot::Robot;

fn main() {
    let mode = std::env::args().nth(1);
    let limits = mode.as_deref() == Some("limits");
    let robot = Robot::irb140();
    // `structured`: the structured solver; `gains`: with the first-stage gains (issue 37).
    let gains = mode.as_deref() == Some("gains");
    let solver = if gains || mode.as_deref() == Some("structured") {
        ofmpc::control::Solver::Structured
    } else {
        ofmpc::control::Solver::Auto
    };
    let settings = MpcSettings {
        torque_limits: limits,
        gains,
        solver,
        ..MpcSettings::default()
    };
    let mut mpc = ControllerBuilder::new(ControllerKind::Second, &robot)
        .settings(settings)
        .build()
        .unwrap();
    let n = mpc.dof();
    let x = vec![0.0; 2 * n];
    mpc.reset(&x).unwrap();
    let target = if limits { 1.5 } else { 0.1 };
    let (w, p) = (vec![target; n], vec![target; n * mpc.horizon()]);
    let input = StepInput {
        x: &x,
        w_k: &w,
        preview: &p,
    };
    let mut sum = 0.0;
    for _ in 0..220 {
        sum += mpc.step(&input).unwrap().tau[0];
    }
    println!("{sum}");
}
