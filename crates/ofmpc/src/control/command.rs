//! Command modes: what the controller hands to the robot's interface.
//!
//! Most arms do not take joint torque from outside. A torque interface
//! (Franka's, KUKA's FRI torque overlay) takes [`OutputMode::Torque`]: the
//! controller's `τ_k`. Interfaces that close their own joint loop (UR's
//! `servoj`, ABB's EGM, KUKA's RSI) take a joint position and velocity
//! ([`OutputMode::PositionVelocity`]) or a velocity
//! ([`OutputMode::Velocity`]), and act on it some time later (their lag). For
//! them the controller outputs the state **its own model predicted** one
//! lead time `L` ahead (`[mpc] output_lead_s`, by default the interface's
//! lag and smoothing): the interface's drive then reaches at `t_k + L` the
//! point the controller planned for `t_k + L`, which compensates the lag
//! from the prediction the step already made (`ŷ(k+i|k)`, `i = 1..N`, of
//! [`Algorithm::predicted_outputs`](crate::control::Algorithm::predicted_outputs)):
//! no second model, no allocation.
//!
//! The lead point is read off the predicted positions `ŷ_0 = q_k` (the
//! state the step acted on), `ŷ_1, …, ŷ_N` by the quadratic through the
//! three samples nearest `s = L/Ts` (`j = clamp(round(s), 1, N − 1)`,
//! `u = s − j`):
//!
//! ```text
//! q_cmd   = ŷ_j + u (ŷ_{j+1} − ŷ_{j−1})/2 + u²/2 (ŷ_{j+1} − 2ŷ_j + ŷ_{j−1})
//! q̇_cmd   = [(ŷ_{j+1} − ŷ_{j−1})/2 + u (ŷ_{j+1} − 2ŷ_j + ŷ_{j−1})] / Ts
//! q̈_cmd   = (ŷ_{j+1} − 2ŷ_j + ŷ_{j−1}) / Ts²
//! ```
//!
//! so `L` may be any time from 0 to `(N − 1)·Ts` (refused beyond:
//! [`BuildError::OutputLead`](crate::control::BuildError::OutputLead)). The
//! acceleration is the feed-forward a drive's own loop adds; the torque
//! `τ_k` stays in the output for interfaces that take it as feed-forward.
//!
//! An interface that smooths its setpoint by a first-order filter of time
//! constant `T` (UR's `lookahead_time`: `ṡ = (c − s)/T`) delays a ramp by
//! `T` but also rounds every change of speed: a lead of `lag + T` leaves
//! the arm following a filtered copy of the plan (measured on ur-servoj:
//! 0.097 mm RMS where the torque interface gives 0.0047). With
//! `[mpc] output_smoothing_s = T` the command is the filter's inverse
//! applied to the plan, `c = y + T ẏ` on each channel,
//!
//! ```text
//! q_cmd + T q̇_cmd,   q̇_cmd + T q̈_cmd,   q̈_cmd + T q⃛_cmd,
//! q⃛_cmd = (ŷ_{j+2} − 3ŷ_{j+1} + 3ŷ_j − ŷ_{j−1}) / Ts³   (0 when j + 2 > N),
//! ```
//!
//! whose filtered value is the plan itself (exact for a cubic plan), and
//! the lead covers the lag alone (0.012 mm on the same run).
//!
//! ## The stream model (`[mpc] output_cycle_s`)
//!
//! `q + T q̇` is the continuous filter's inverse on a smooth plan, but the
//! interface runs its filter in discrete steps `h` on a setpoint it
//! extrapolates from the command over its cycles, and the plan is re-made
//! every period: on ur-servoj (gain 2000, payload known to the controller
//! and the drive) that left 0.0099 mm where the same loop without the
//! smoothing gives 0.0023. Measured one cause at a time on that run:
//! the velocity channel's `T q̈` read at `ŷ_j` (10 ms) instead of the lead
//! (4.5 ms; 0.0062 with a cubic at the lead), the continuous inverse of a
//! discrete filter (`q + T q̇` misses its `−T h/2 q̈`: 0.0047 with the exact
//! discrete inverse), the interface's quadratic extrapolation over the
//! period (the acceleration it extrapolates with is best the plan's at
//! the period's middle: 0.0037) and the re-plans, which the filtered
//! acceleration follows only as `e^{−t/T}` (0.0025 with the copy below).
//! With the interface's cycle `P` and filter step `h` ([`Stream`]) the
//! command is:
//!
//! 1. the **plan** as the cubic `y(t)` through the four predicted samples
//!    around the lead `L` (`ŷ_0 = q_k`, `ŷ_1, …`);
//! 2. its **exact discrete inverse**: the filter `f_{i+1} = f_i + β (s_i −
//!    f_i)` follows `y` step for step if its input is `g(t) = (y(t) − (1 −
//!    β) y(t − h))/β`, on each channel: `q_cmd = g(L)`, `q̇_cmd = ġ(L)`,
//!    `q̈_cmd = g̈(L + Ts/2)`, with `β = h/(T + h)` (`T` the smoothing's
//!    delay, `output_smoothing_s`; `h` = `output_smoothing_step_s`);
//! 3. plus, on the acceleration, `γ (ÿ − f̂)`: `f̂` is the controller's copy
//!    of the interface's filtered acceleration, run on every command it
//!    sent as the interface smooths it, `ÿ` the plan's at the step before
//!    this command's first setpoint reaches the filter (`L − (P + h)/2`);
//!    `γ = d/(1 − d)`, `d = (1 − β)^{Ts/h}` the filter's decay over a
//!    period: the offset that closes the gap by the period's end.
//!
//! The same copy on position and velocity (0.0027 mm) pulls the setpoint
//! towards the plan's start — the measured state — and so slows the hold's
//! convergence to the reference (its slowest mode from 0.35 s to 2 s); on
//! the acceleration alone it is 0.9 s (0.5 s without the copy, 0.35 s
//! before any of this). The copy knows only what was sent: a command the
//! interface missed (a late step) leaves it off by a gap that decays as
//! the filter does.

use crate::dynamics::{rnea, Workspace};
use crate::robot::{ModelError, Robot};
use serde::{Deserialize, Serialize};
use std::fmt;

/// What the controller's output drives (`[mpc] output`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum OutputMode {
    /// Joint torque `τ_k` (the paper's, the default).
    #[default]
    Torque,
    /// Joint position and velocity, one lead time ahead, with the
    /// acceleration and the torque as feed-forward.
    PositionVelocity,
    /// Joint velocity one lead time ahead, with the acceleration and the
    /// torque as feed-forward.
    Velocity,
}

impl OutputMode {
    /// Every mode, in the order of the documentation.
    pub const ALL: [OutputMode; 3] = [
        OutputMode::Torque,
        OutputMode::PositionVelocity,
        OutputMode::Velocity,
    ];

    /// `"torque"`, `"position_velocity"` or `"velocity"` (as in a scenario).
    pub fn name(self) -> &'static str {
        match self {
            OutputMode::Torque => "torque",
            OutputMode::PositionVelocity => "position_velocity",
            OutputMode::Velocity => "velocity",
        }
    }

    /// True for [`OutputMode::Torque`].
    pub fn is_torque(self) -> bool {
        self == OutputMode::Torque
    }

    /// Whether `self` is the default (for `skip_serializing_if`).
    pub(crate) fn is_default(&self) -> bool {
        self.is_torque()
    }
}

impl fmt::Display for OutputMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The largest lead time for a horizon of `horizon` samples of `ts` (s):
/// `(N − 1)·Ts` (the quadratic needs the sample after the lead point).
pub(crate) fn max_output_lead(horizon: usize, ts: f64) -> f64 {
    horizon.saturating_sub(1) as f64 * ts
}

/// Sample `k` of joint `joint`'s predicted positions: `ŷ_0 = now`, `ŷ_k`
/// (`k ≥ 1`) from `predicted` (N·n), past its end the current position.
fn sample(now: &[f64], predicted: &[f64], k: usize, joint: usize) -> f64 {
    match k.checked_sub(1) {
        None => now[joint],
        Some(i) => predicted
            .get(i * now.len() + joint)
            .copied()
            .unwrap_or(now[joint]),
    }
}

/// The command one lead time ahead from the predicted positions: fills
/// `q`, `qd`, `qdd` (n each) from `now` (`ŷ_0`, n values) and `predicted`
/// (`ŷ_1..ŷ_N`, N·n values), `lead_s` ahead at the period `ts`,
/// pre-compensated for a first-order smoothing of time constant
/// `smoothing_s` (0: none; module docs). Allocation free; `N ≥ 2` (the
/// builder checks it through the lead's bound).
pub(crate) fn lead_point(
    now: &[f64],
    predicted: &[f64],
    lead_s: f64,
    smoothing_s: f64,
    ts: f64,
    cmd: [&mut [f64]; 3],
) {
    let n = now.len();
    let horizon = predicted.len() / n.max(1);
    let s = lead_s / ts;
    let j = (s.round() as usize).clamp(1, horizon.saturating_sub(1).max(1));
    let u = s - j as f64;
    let y = |i: usize, joint: usize| sample(now, predicted, i, joint);
    let [q, qd, qdd] = cmd;
    for i in 0..n {
        let (ym, y0, yp) = (y(j - 1, i), y(j, i), y(j + 1, i));
        let slope = 0.5 * (yp - ym);
        let curve = yp - 2.0 * y0 + ym;
        q[i] = y0 + u * slope + 0.5 * u * u * curve;
        qd[i] = (slope + u * curve) / ts;
        qdd[i] = curve / (ts * ts);
        if smoothing_s > 0.0 {
            let jerk = if j + 2 <= horizon {
                (y(j + 2, i) - 3.0 * yp + 3.0 * y0 - ym) / (ts * ts * ts)
            } else {
                0.0
            };
            q[i] += smoothing_s * qd[i];
            qd[i] += smoothing_s * qdd[i];
            qdd[i] += smoothing_s * jerk;
        }
    }
}

/// The payload, carried to a drive that closes its own joint loop on the
/// controller's nominal model (the payload the user declared), as a torque
/// feed-forward.
///
/// The drive computes `τ = ID_v(q, q̇, a) + τ_ff` (its inverse dynamics on
/// the vendor's model, `a` = the commanded acceleration plus its loop's
/// correction, and the feed-forward an interface that takes one adds). When
/// the controller's model carries an identified payload (an adaptive kind
/// through an interface that reports its applied torque) the arm needs
/// `τ* = ID_m(q, q̇, q̈)` along the plan, so the command's feed-forward is
///
/// ```text
/// τ_ff = ID_m(q, q̇, q̈) − ID_v(q, q̇, q̈)
/// ```
///
/// at the physical lead point (the plan's `q, q̇, q̈` one lead ahead, before
/// any smoothing pre-compensation): with it the drive's loop has no load
/// left to carry with its following error. Zero when the two models are
/// equal. (Carried in the commanded acceleration instead, `M_v⁻¹ τ_ff`, it
/// would also move the positions an interface extrapolates along the
/// command, `½ q̈ dt²`: a steady offset of 5e-5 rad on the IRB 140 at 2 kg
/// through the simulated ABB EGM.) Sized at construction; allocation-free.
#[derive(Debug, Clone)]
pub(crate) struct PayloadFeedForward {
    vendor: Robot,
    ws_vendor: Workspace,
    ws_model: Workspace,
    point: [Vec<f64>; 3],
}

impl PayloadFeedForward {
    /// For a drive whose model is `vendor` (the controller's nominal one).
    /// Allocates.
    pub(crate) fn new(vendor: &Robot) -> Self {
        let n = vendor.dof();
        Self {
            ws_vendor: Workspace::new(vendor),
            ws_model: Workspace::new(vendor),
            vendor: vendor.clone(),
            point: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
        }
    }

    /// The feed-forward for the controller's current `model` into `tau_ff`
    /// (n), at the lead point of `now`/`predicted` (as [`lead_point`] reads
    /// it, without smoothing).
    pub(crate) fn torque(
        &mut self,
        model: &Robot,
        now: &[f64],
        predicted: &[f64],
        lead_s: f64,
        ts: f64,
        tau_ff: &mut [f64],
    ) -> Result<(), ModelError> {
        let [q, qd, qdd] = &mut self.point;
        lead_point(now, predicted, lead_s, 0.0, ts, [q, qd, qdd]);
        let needed = rnea(model, &mut self.ws_model, q, qd, qdd)?;
        let vendor = rnea(&self.vendor, &mut self.ws_vendor, q, qd, qdd)?;
        for ((f, m), v) in tau_ff.iter_mut().zip(needed.iter()).zip(vendor.iter()) {
            *f = m - v;
        }
        Ok(())
    }
}

/// The controller's model of an interface's stream and smoothing (module
/// docs, "The stream model"): sized at construction, allocation-free.
#[derive(Debug, Clone)]
pub(crate) struct Stream {
    /// The cycle and the filter's step (s).
    cycle_s: f64,
    step_s: f64,
    /// `1 − β`: the filter's decay per step.
    decay: f64,
    /// `d`: its decay over a control period.
    period_decay: f64,
    /// The copy of the filtered acceleration (n).
    filtered: Vec<f64>,
    /// No command sent since the last reset: the copy starts on the plan.
    fresh: bool,
}

/// Why a stream model cannot be built (the builder's
/// [`BuildError::OutputStream`](crate::control::BuildError::OutputStream)).
pub(crate) fn check_stream(
    ts: f64,
    cycle_s: f64,
    step_s: f64,
    smoothing_s: Option<f64>,
    horizon: usize,
) -> Result<(), &'static str> {
    let whole = |a: f64, b: f64| {
        let r = a / b;
        r.round() >= 1.0 && (r - r.round()).abs() < 1e-6
    };
    if !(cycle_s.is_finite() && cycle_s > 0.0 && whole(ts, cycle_s)) {
        return Err("the interface's cycle must be a whole divisor of the control period");
    }
    if !(step_s.is_finite() && step_s > 0.0 && whole(cycle_s, step_s)) {
        return Err("the smoothing's step must be a whole divisor of the interface's cycle");
    }
    if !smoothing_s.is_some_and(|t| t > 0.0) {
        return Err(
            "it inverts a smoothing: give a position or velocity output an output_smoothing_s > 0",
        );
    }
    if horizon < 4 {
        return Err(
            "it reads a cubic through four predicted samples: give a horizon of at least 4",
        );
    }
    Ok(())
}

impl Stream {
    /// The model of `n` joints streamed every `cycle_s` under a control
    /// period `ts`, smoothed every `step_s` by a filter of delay
    /// `smoothing_s` (checked by [`check_stream`]). Allocates.
    pub(crate) fn new(n: usize, ts: f64, cycle_s: f64, step_s: f64, smoothing_s: f64) -> Self {
        let decay = smoothing_s / (smoothing_s + step_s);
        Self {
            cycle_s,
            step_s,
            decay,
            period_decay: decay.powi((ts / step_s).round() as i32),
            filtered: vec![0.0; n],
            fresh: true,
        }
    }

    /// Forgets the copy: the next command starts it on the plan.
    pub(crate) fn reset(&mut self) {
        self.fresh = true;
    }

    /// The command from the predicted positions (as [`lead_point`]'s
    /// `now`, `predicted`, `lead_s`, `ts`), then the copy advanced over the
    /// period. Allocation-free.
    pub(crate) fn command(
        &mut self,
        now: &[f64],
        predicted: &[f64],
        lead_s: f64,
        ts: f64,
        cmd: [&mut [f64]; 3],
    ) {
        let n = now.len();
        let horizon = predicted.len() / n.max(1);
        let s = lead_s / ts;
        let j0 = (s.round() as usize)
            .saturating_sub(1)
            .min(horizon.saturating_sub(3));
        let (h, decay) = (self.step_s / ts, self.decay);
        let inverse = |y: f64, before: f64| (y - decay * before) / (1.0 - decay);
        let gap_at = s - 0.5 * (self.cycle_s + self.step_s) / ts;
        let d = self.period_decay;
        let [q, qd, qdd] = cmd;
        for i in 0..n {
            let cubic = Cubic::through(j0, |k| sample(now, predicted, k, i));
            let (y, before) = (cubic.at(s), cubic.at(s - h));
            let (mid, mid_before) = (cubic.at(s + 0.5), cubic.at(s + 0.5 - h));
            q[i] = inverse(y[0], before[0]);
            qd[i] = inverse(y[1], before[1]) / ts;
            qdd[i] = inverse(mid[2], mid_before[2]) / (ts * ts);
            let plan = cubic.at(gap_at)[2] / (ts * ts);
            let f = &mut self.filtered[i];
            if self.fresh {
                *f = plan;
            }
            qdd[i] += d / (1.0 - d) * (plan - *f);
            // The period's filter steps on the held acceleration.
            *f = qdd[i] + d * (*f - qdd[i]);
        }
        self.fresh = false;
    }
}

/// A cubic through the samples `j0..=j0 + 3` (unit spacing), in Newton's
/// form.
struct Cubic {
    j0: f64,
    a: [f64; 4],
}

impl Cubic {
    fn through(j0: usize, sample: impl Fn(usize) -> f64) -> Self {
        let mut a = [sample(j0), sample(j0 + 1), sample(j0 + 2), sample(j0 + 3)];
        for level in 1..4 {
            for k in (level..4).rev() {
                a[k] = (a[k] - a[k - 1]) / level as f64;
            }
        }
        Self { j0: j0 as f64, a }
    }

    /// Its value and first three derivatives at `x` (sample units).
    fn at(&self, x: f64) -> [f64; 4] {
        let (mut p, mut d1, mut d2, mut d3) = (self.a[3], 0.0, 0.0, 0.0);
        for k in (0..3).rev() {
            let dx = x - (self.j0 + k as f64);
            d3 = d3 * dx + 3.0 * d2;
            d2 = d2 * dx + 2.0 * d1;
            d1 = d1 * dx + p;
            p = p * dx + self.a[k];
        }
        [p, d1, d2, d3]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a predicted parabola `y(t) = a + b t + c t²` the lead point is
    /// exact at any lead (on the grid and between), for position, velocity
    /// and acceleration.
    #[test]
    fn lead_point_is_exact_on_a_parabola() {
        let (ts, horizon) = (0.01, 10);
        let f = |t: f64| 0.3 + 1.5 * t - 4.0 * t * t;
        let now = [f(0.0)];
        let predicted: Vec<f64> = (1..=horizon).map(|i| f(i as f64 * ts)).collect();
        for lead in [0.0, 0.002, 0.0137, 0.04, 0.065, 0.09] {
            let (mut q, mut qd, mut qdd) = ([0.0], [0.0], [0.0]);
            lead_point(&now, &predicted, lead, 0.0, ts, [&mut q, &mut qd, &mut qdd]);
            assert!(
                (q[0] - f(lead)).abs() < 1e-12,
                "lead {lead}: {} vs {}",
                q[0],
                f(lead)
            );
            assert!((qd[0] - (1.5 - 8.0 * lead)).abs() < 1e-9, "lead {lead}");
            assert!((qdd[0] + 8.0).abs() < 1e-6, "lead {lead}");
        }
        assert!((max_output_lead(horizon, ts) - 0.09).abs() < 1e-15);
    }

    /// With a smoothing `T` the command is `c = y + T ẏ` on each channel of
    /// a cubic plan (exact); and a first-order filter of time constant `T`
    /// run on that command along the plan gives back the plan: the
    /// pre-compensation is the filter's inverse.
    #[test]
    fn the_smoothing_pre_compensation_is_the_filters_inverse() {
        let (ts, horizon, t_s) = (0.01, 10, 0.03);
        let f = |t: f64| 0.3 + 1.5 * t - 4.0 * t * t + 20.0 * t * t * t;
        let (df, ddf, dddf) = (
            |t: f64| 1.5 - 8.0 * t + 60.0 * t * t,
            |t: f64| -8.0 + 120.0 * t,
            |_: f64| 120.0,
        );
        let now = [f(0.0)];
        let predicted: Vec<f64> = (1..=horizon).map(|i| f(i as f64 * ts)).collect();
        for lead in [0.0, 0.0045, 0.01, 0.034, 0.06, 0.085] {
            let (mut q0, mut qd0, mut qdd0) = ([0.0], [0.0], [0.0]);
            lead_point(
                &now,
                &predicted,
                lead,
                0.0,
                ts,
                [&mut q0, &mut qd0, &mut qdd0],
            );
            let (mut q, mut qd, mut qdd) = ([0.0], [0.0], [0.0]);
            lead_point(&now, &predicted, lead, t_s, ts, [&mut q, &mut qd, &mut qdd]);
            // The third difference of a cubic's samples is its third
            // derivative, where the sample after next exists (j + 2 ≤ N).
            let j = ((lead / ts).round() as usize).clamp(1, horizon - 1);
            let jerk = if j + 2 <= horizon { dddf(lead) } else { 0.0 };
            assert!((q[0] - (q0[0] + t_s * qd0[0])).abs() < 1e-14, "lead {lead}");
            assert!(
                (qd[0] - (qd0[0] + t_s * qdd0[0])).abs() < 1e-12,
                "lead {lead}"
            );
            assert!(
                (qdd[0] - (qdd0[0] + t_s * jerk)).abs() < 1e-6,
                "lead {lead}: {}",
                qdd[0]
            );
            // Without the smoothing the channels are the plan's (the quadratic
            // through three samples of the cubic; exact at the middle one).
            if (lead / ts - j as f64).abs() < 1e-12 {
                assert!((q0[0] - f(lead)).abs() < 1e-12);
                assert!((qd0[0] - df(lead)).abs() < 120.0 * ts * ts / 6.0 + 1e-9);
                assert!((qdd0[0] - ddf(lead)).abs() < 1e-6);
            }
        }
        // The filter ṡ = (c − s)/T on c = y + T ẏ, from s(0) = y(0): s = y.
        let (h, mut s, mut worst) = (1e-5, f(0.0), 0.0f64);
        for k in 0..20_000 {
            let t = k as f64 * h;
            let c = |t: f64| f(t) + t_s * df(t);
            // RK4 of the filter.
            let k1 = (c(t) - s) / t_s;
            let k2 = (c(t + h / 2.0) - (s + h / 2.0 * k1)) / t_s;
            let k3 = (c(t + h / 2.0) - (s + h / 2.0 * k2)) / t_s;
            let k4 = (c(t + h) - (s + h * k3)) / t_s;
            s += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            worst = worst.max((s - f(t + h)).abs());
        }
        assert!(worst < 1e-12, "filtered command vs plan: {worst}");
    }

    /// The interface of `servo.rs`, brute force, on one joint: the command
    /// of each period (`command(now, predicted)`, at `t_k = k Ts`) streamed
    /// at each cycle `τ` as `c + ċ τ + ½ c̈ τ²` (and its derivatives),
    /// delayed `lag` whole cycles, smoothed by `f += β (s − f)` at every
    /// step `h` of the cycle, `β = 1 − e^{−h/T₀}`. Returns the largest
    /// error of the smoothed q, q̇, q̈ against the plan `y` (value and two
    /// derivatives) over the last half of `periods`.
    fn smoothed_error(
        y: impl Fn(f64) -> [f64; 3],
        mut command: impl FnMut(&[f64], &[f64]) -> [f64; 3],
        (ts, cycle, h, lag, t0): (f64, f64, f64, f64, f64),
        horizon: usize,
        periods: usize,
    ) -> [f64; 3] {
        let (cycles, steps) = ((ts / cycle).round() as usize, (cycle / h).round() as usize);
        let lag_cycles = (lag / cycle).round() as usize;
        let beta = 1.0 - (-h / t0).exp();
        let mut line: std::collections::VecDeque<[f64; 3]> =
            std::iter::repeat_n(y(0.0), lag_cycles).collect();
        let (mut f, mut worst) = (y(0.0), [0.0f64; 3]);
        for k in 0..periods {
            let tk = k as f64 * ts;
            let predicted: Vec<f64> = (1..=horizon).map(|i| y(tk + i as f64 * ts)[0]).collect();
            let c = command(&[y(tk)[0]], &predicted);
            for m in 0..cycles {
                let tau = m as f64 * cycle;
                line.push_back([
                    c[0] + c[1] * tau + 0.5 * c[2] * tau * tau,
                    c[1] + c[2] * tau,
                    c[2],
                ]);
                let s = line.pop_front().unwrap();
                for i in 0..steps {
                    let t = tk + tau + i as f64 * h;
                    for ch in 0..3 {
                        f[ch] += beta * (s[ch] - f[ch]);
                        if k >= periods / 2 {
                            worst[ch] = worst[ch].max((f[ch] - y(t)[ch]).abs());
                        }
                    }
                }
            }
        }
        worst
    }

    /// The stream model's command is the smoothing's exact inverse as the
    /// interface runs it: on a quadratic plan, streamed every step (the
    /// cycle = the filter's step: no hold), the smoothed setpoint is the
    /// plan on every channel to rounding; at ur-servoj's timing (2 ms
    /// cycle, 1 ms step, 4 ms lag, 30 ms) on a cubic plan it is closer to
    /// the plan than `q + T q̇` on every channel (largest errors measured:
    /// 6.6e-6 against 3.7e-5 rad, most of both the ripple of the setpoint
    /// held over two steps; 4.0e-5 against 7.0e-4 rad/s; 2.2e-3 against
    /// 5.9e-3 rad/s²).
    /// One joint's command from `command`, as `[q, q̇, q̈]`.
    fn one_joint(command: impl FnOnce([&mut [f64]; 3])) -> [f64; 3] {
        let (mut q, mut qd, mut qdd) = ([0.0], [0.0], [0.0]);
        command([&mut q, &mut qd, &mut qdd]);
        [q[0], qd[0], qdd[0]]
    }

    #[test]
    fn the_stream_model_inverts_the_interfaces_smoothing() {
        let (ts, horizon, t0, lag) = (0.01, 10, 0.03, 0.004);
        let delay = |h: f64| h * (-h / t0).exp() / (1.0 - (-h / t0).exp());
        let quadratic = |t: f64| [0.3 + 1.5 * t - 4.0 * t * t, 1.5 - 8.0 * t, -8.0];
        let h = 1e-3;
        let mut stream = Stream::new(1, ts, h, h, delay(h));
        let worst = smoothed_error(
            quadratic,
            |now, predicted| one_joint(|cmd| stream.command(now, predicted, lag, ts, cmd)),
            (ts, h, h, lag, t0),
            horizon,
            200,
        );
        assert!(worst.iter().all(|e| *e < 1e-9), "{worst:?}");
        // ur-servoj's timing: the lead covers the lag and the hold.
        let cubic = |t: f64| {
            let t = t - 1.0;
            [
                0.3 + 0.5 * t - 0.8 * t * t + 0.6 * t.powi(3),
                0.5 - 1.6 * t + 1.8 * t * t,
                -1.6 + 3.6 * t,
            ]
        };
        let (cycle, lead) = (0.002, lag + 0.5 * (0.002 - h));
        let mut stream = Stream::new(1, ts, cycle, h, delay(h));
        let timing = (ts, cycle, h, lag, t0);
        let new = smoothed_error(
            cubic,
            |now, predicted| one_joint(|cmd| stream.command(now, predicted, lead, ts, cmd)),
            timing,
            horizon,
            200,
        );
        let old = smoothed_error(
            cubic,
            |now, predicted| {
                let (mut q, mut qd, mut qdd) = ([0.0], [0.0], [0.0]);
                lead_point(
                    now,
                    predicted,
                    lead,
                    delay(h),
                    ts,
                    [&mut q, &mut qd, &mut qdd],
                );
                [q[0], qd[0], qdd[0]]
            },
            timing,
            horizon,
            200,
        );
        assert!(
            new[0] * 4.0 < old[0] && new[1] * 10.0 < old[1],
            "{new:?} vs {old:?}"
        );
        assert!(new[2] * 2.0 < old[2], "{new:?} vs {old:?}");
    }

    #[test]
    fn names_round_trip() {
        for m in OutputMode::ALL {
            let toml = format!("\"{}\"", m.name());
            let back: OutputMode = serde_json::from_str(&toml).unwrap();
            assert_eq!(back, m);
        }
        assert_eq!(OutputMode::default(), OutputMode::Torque);
    }
}
