//! The drives' friction law near rest as it is: a smoothed Coulomb friction
//! `F(v) = F_v v + F_c tanh(v/v_s)` does not stick, it creeps — below the
//! breakaway torque the joint moves at `v ≈ v_s·atanh(τ/F_c)`, a stiff damper
//! of slope `F'(0) = F_v + F_c/v_s` (issue 35,
//! [`MpcSettings::friction_creep`](crate::control::MpcSettings::friction_creep)).
//!
//! The state observer's model of the friction decides what it predicts over
//! the measurement delay. The stick-aware clamp predicts that a joint held
//! below the breakaway torque stays where it is; the plant creeps, the
//! measurement shows it a sample later, and the controller, acting on a
//! prediction that lags the creep, winds its integrating action through it:
//! a slow cycle of ±10–20 encoder counts at a hold (0.4–0.6 s on the IRB 140's
//! wrist, ±60–130 counts at 30 ms on the second algorithm's joints 2 and 3).
//! Integrated implicitly over a sample ([`implicit_velocity`]: an explicit
//! step of a damper this stiff, `Ts·F'(0)/H_ii` in the hundreds, would
//! diverge) the law predicts the creep itself.
//!
//! (Giving the predictive controllers' own model the slope at a hold was
//! tried and is not done: with one sample of delay the controller then
//! acts as a deadbeat on a damper whose slope changes by orders of magnitude
//! within a few encoder counts per sample, and cycles at the torque limits.)

/// Slope `F'(v) = F_v + F_c (1 − tanh²(v/v_s))/v_s` of the friction law at
/// `v` (N·m·s/rad); `F_v` alone when `v_s ≤ 0`.
pub(crate) fn slope(viscous: f64, coulomb: f64, v_s: f64, v: f64) -> f64 {
    if v_s > 0.0 {
        let t = (v / v_s).tanh();
        viscous + coulomb * (1.0 - t * t) / v_s
    } else {
        viscous
    }
}

/// The velocity `x` at the end of a sample of a joint of inertia `h` that
/// starts at `v` and would reach `s` without friction, under the friction law
/// taken at the end of the sample (implicit Euler):
/// `h (x − s)/Ts + F_v x + F_c tanh(x/v_s) = 0`. The left side increases
/// with `x`, so the root is unique and lies where `tanh = ±1` bound it; a
/// safeguarded Newton iteration (at most 60 steps, no allocation). Returns
/// `s` unchanged for `h ≤ 0` or a non-finite input.
pub(crate) fn implicit_velocity(
    h: f64,
    ts: f64,
    s: f64,
    viscous: f64,
    coulomb: f64,
    v_s: f64,
) -> f64 {
    let k = h / ts;
    if !(k > 0.0 && k.is_finite() && s.is_finite() && v_s > 0.0) {
        return s;
    }
    let f = |x: f64| k * (x - s) + viscous * x + coulomb * (x / v_s).tanh();
    let denom = k + viscous;
    let (mut lo, mut hi) = ((k * s - coulomb) / denom, (k * s + coulomb) / denom);
    if lo > hi {
        std::mem::swap(&mut lo, &mut hi);
    }
    let mut x = (k * s / (k + viscous + coulomb / v_s)).clamp(lo, hi);
    for _ in 0..60 {
        let fx = f(x);
        if fx == 0.0 {
            break;
        }
        if fx > 0.0 {
            hi = x;
        } else {
            lo = x;
        }
        let step = fx / (k + slope(viscous, coulomb, v_s, x));
        let mut next = x - step;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - x).abs() <= 1e-14 * x.abs().max(v_s) {
            x = next;
            break;
        }
        x = next;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_is_the_derivative_of_the_law() {
        let (fv, fc, vs) = (0.8, 4.0, 1e-3);
        for v in [-0.3, -2e-3, 0.0, 4e-4, 1e-3, 0.05] {
            let h = 1e-7;
            let law = |v: f64| crate::dynamics::friction::torque(fv, fc, vs, v);
            let fd = (law(v + h) - law(v - h)) / (2.0 * h);
            assert!((slope(fv, fc, vs, v) - fd).abs() <= 1e-5 * fd.abs(), "{v}");
        }
        assert_eq!(slope(0.5, 3.0, 0.0, 0.0), 0.5);
    }

    #[test]
    fn implicit_velocity_solves_the_implicit_step() {
        let (ts, fv, fc, vs) = (0.01, 1.0, 1.0, 1e-3);
        for h in [0.002, 0.05, 3.0] {
            for s in [-1.0, -0.05, -1e-3, -1e-5, 0.0, 2e-6, 4e-4, 0.02, 0.7] {
                let x = implicit_velocity(h, ts, s, fv, fc, vs);
                let r = h * (x - s) / ts + fv * x + fc * (x / vs).tanh();
                assert!(
                    r.abs() <= 1e-9 * (h / ts) * s.abs().max(vs),
                    "h {h} s {s}: {r}"
                );
                // Friction only slows the joint: same sign, smaller speed.
                assert!(x * s >= 0.0 && x.abs() <= s.abs(), "h {h} s {s}: {x}");
            }
        }
        // Below the breakaway torque it creeps: F_c/2 of torque for one
        // sample on a light joint settles at v_s·atanh(1/2) (quasi-static).
        let h = 1e-4;
        let s = 0.5 * fc * ts / h; // the friction-free velocity of τ = F_c/2
        let x = implicit_velocity(h, ts, s, 0.0, fc, vs);
        let creep = vs * 0.5f64.atanh();
        assert!((x - creep).abs() < 0.01 * creep, "{x} vs {creep}");
        assert_eq!(implicit_velocity(0.0, ts, 0.3, fv, fc, vs), 0.3);
    }
}
