//! The first-stage gains ([`MpcSettings::gains`], issue 37 item 5): on the
//! IRB 140, for a small perturbation `δx` of the measured state, the law
//! `τ ≈ tau_ff + K δx` reproduces the controller's own next torque. `K` is
//! the derivative with the step's ZOH model held (`src/control/mpc/gains.rs`),
//! so the error has a second-order part and a small first-order part from
//! the ZOH's dependence on the state: measured at three perturbation sizes,
//! printed, bounded.
//! The configurations where the gain cannot work refuse to build.

use ofmpc::control::{
    BuildError, Controller, ControllerBuilder, ControllerKind, MpcSettings, Solver, StepInput,
};
use ofmpc::robot::Robot;

const N: usize = 6;

fn settings() -> MpcSettings {
    MpcSettings {
        gains: true,
        horizon: 20,
        ..MpcSettings::default()
    }
}

fn build(kind: ControllerKind, s: &MpcSettings) -> Result<Controller, BuildError> {
    ControllerBuilder::new(kind, &Robot::irb140())
        .settings(s.clone())
        .build()
}

/// A controller driven `steps` samples along a moving reference from `q0`
/// (so that `Δx`, `u_{k−1}` and `ē` are not zero), and the state, target and
/// preview of the next sample.
fn prepared(kind: ControllerKind, steps: usize) -> (Controller, Vec<f64>, Vec<f64>, Vec<f64>) {
    let s = settings();
    let mut c = build(kind, &s).unwrap();
    let q0 = [0.3, 0.4, -0.2, 0.5, 0.8, -0.3];
    let mut x: Vec<f64> = q0.iter().copied().chain([0.0; N]).collect();
    c.reset(&x).unwrap();
    let w = |k: usize| -> Vec<f64> {
        (0..N)
            .map(|i| q0[i] + 0.002 * k as f64 * (1.0 + 0.3 * i as f64))
            .collect()
    };
    let preview = |k: usize| -> Vec<f64> { (1..=s.horizon).flat_map(|j| w(k + j)).collect() };
    for k in 0..steps {
        c.step(&StepInput {
            x: &x,
            w_k: &w(k),
            preview: &preview(k),
        })
        .unwrap();
        // A state that moves along the reference, off it by a little.
        for i in 0..N {
            x[i] = w(k + 1)[i] - 1e-3 * (i as f64 - 2.0);
            x[N + i] = 0.2 * (1.0 + 0.3 * i as f64) + 0.01 * i as f64;
        }
    }
    (c, x, w(steps), preview(steps))
}

fn torque(c: &mut Controller, x: &[f64], w: &[f64], p: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let out = c
        .step(&StepInput {
            x,
            w_k: w,
            preview: p,
        })
        .unwrap();
    assert!(out.status.failure().is_none());
    (out.tau.to_vec(), out.gain.to_vec(), out.x_lin.to_vec())
}

/// `|τ(x + δx) − (tau_ff + K δx)|` for `δx = h·d`.
fn law_error(kind: ControllerKind, d: &[f64], h: f64) -> (f64, f64) {
    let (mut c0, x, w, p) = prepared(kind, 30);
    let (tau0, k, x_lin) = torque(&mut c0, &x, &w, &p);
    assert_eq!(x_lin, x);
    let (mut c1, ..) = prepared(kind, 30);
    let xp: Vec<f64> = x.iter().zip(d).map(|(a, b)| a + h * b).collect();
    let (tau1, ..) = torque(&mut c1, &xp, &w, &p);
    let mut err = 0.0f64;
    let mut lin = 0.0f64;
    for i in 0..N {
        let kd: f64 = (0..2 * N).map(|j| k[i * 2 * N + j] * h * d[j]).sum();
        err = err.max((tau1[i] - tau0[i] - kd).abs());
        lin = lin.max(kd.abs());
    }
    (err, lin)
}

#[test]
fn the_gain_reproduces_the_next_torque_to_first_order() {
    let d: Vec<f64> = (0..2 * N)
        .map(|j| if j % 3 == 0 { 1.0 } else { -0.5 } * (1.0 + 0.1 * j as f64))
        .collect();
    for kind in [
        ControllerKind::Usual,
        ControllerKind::First,
        ControllerKind::Second,
    ] {
        let h = 1e-4;
        let (e1, l1) = law_error(kind, &d, h);
        let (e2, l2) = law_error(kind, &d, h / 2.0);
        let (e3, l3) = law_error(kind, &d, h / 4.0);
        println!(
            "{kind}: |K δx| {l1:.3e} {l2:.3e} {l3:.3e}; error {e1:.3e} {e2:.3e} {e3:.3e}; \
             relative {:.2e} {:.2e} {:.2e}; ratios {:.2} {:.2}",
            e1 / l1,
            e2 / l2,
            e3 / l3,
            e1 / e2,
            e2 / e3
        );
        // The law carries the response: measured 7e-5 (usual), 4e-5
        // (first), 6e-5 (second) of |K δx| left at |δx| ≈ 2e-4 (without
        // the torque map's derivative in K: 1.5e-3, 1.1e-2, 9.5e-2, first
        // order). What is left shrinks faster than |δx|: second order, plus
        // the first-order part of the ZOH model's own dependence on the
        // state (K holds f0 = −H⁻¹C), which the first algorithm barely has
        // (error ratio 4.1 when δx halves) and the usual and second do
        // (2.6–2.9, 2.2–2.3).
        assert!(l1 > 1.0, "{kind}: |K δx| = {l1:e}");
        assert!(e1 <= 2e-4 * l1, "{kind}: error {e1:e} of {l1:e}");
        assert!(
            e2 / l2 <= 0.95 * e1 / l1 && e3 / l3 <= 0.95 * e2 / l2,
            "{kind}: not o(|δx|)"
        );
        if kind == ControllerKind::First {
            assert!(e1 / e2 > 3.5 && e2 / e3 > 3.5, "{kind}: not O(|δx|²)");
        }
    }
}

#[test]
fn gains_refuse_to_build_where_they_cannot_work() {
    let refused = |kind: ControllerKind, s: MpcSettings| {
        matches!(build(kind, &s), Err(BuildError::GainsUnavailable { .. }))
    };
    let s = settings();
    assert!(refused(
        ControllerKind::Second,
        MpcSettings {
            solver: Solver::DenseQr,
            ..s.clone()
        }
    ));
    assert!(refused(
        ControllerKind::Second,
        MpcSettings {
            torque_limits: true,
            ..s.clone()
        }
    ));
    assert!(refused(
        ControllerKind::Second,
        MpcSettings {
            state_observer: true,
            ..s.clone()
        }
    ));
    assert!(refused(ControllerKind::Pid, s.clone()));
    assert!(refused(ControllerKind::DobMpc, s.clone()));
    // Off: empty fields, nothing computed.
    let off = MpcSettings {
        gains: false,
        ..s.clone()
    };
    let c = build(ControllerKind::Second, &off).unwrap();
    assert!(c.output().gain.is_empty() && c.output().tau_ff.is_empty());
    // Auto picks the structured solver.
    for kind in [ControllerKind::First, ControllerKind::SecondAdaptive] {
        let c = build(kind, &s).unwrap();
        assert_eq!(c.output().gain.len(), 2 * N * N);
    }
}
