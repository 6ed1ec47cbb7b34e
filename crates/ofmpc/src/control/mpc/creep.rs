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

/// The end velocities `x` of a sample of joints with inertia matrix `h`
/// (positive definite) that would reach `s` without friction, under the
/// friction law of each joint (`law = (F_v, F_c, v_s)`, per joint `F_v`,
/// `F_c`) taken at the end of the sample, all joints together:
/// `h (x − s)/Ts + F(x) = 0`. It is the minimum of the strictly convex
/// `Φ(x) = (x − s)ᵀh(x − s)/(2Ts) + Σ (F_v x²/2 + F_c v_s ln cosh(x/v_s))`:
/// Newton steps on `h/Ts + diag F'(x)` (a Cholesky factorization in `work`,
/// `n² + 2n` values), halved until `Φ` decreases, from the joint-by-joint
/// solution ([`implicit_velocity`] through `h_ii`), at most 30, until no
/// joint moves by more than `1e-12 max(|x|, v_s)`. With a diagonal `h` the
/// start is the answer. No allocation; a matrix that is not positive
/// definite leaves the joint-by-joint solution.
pub(crate) fn implicit_velocities(
    h: &nalgebra::DMatrix<f64>,
    ts: f64,
    s: &[f64],
    law: (&[f64], &[f64], f64),
    x: &mut [f64],
    work: &mut [f64],
) {
    let (viscous, coulomb, v_s) = law;
    let n = s.len();
    for i in 0..n {
        x[i] = implicit_velocity(h[(i, i)], ts, s[i], viscous[i], coulomb[i], v_s);
    }
    let (a, rest) = work.split_at_mut(n * n);
    let (d, trial) = rest.split_at_mut(n);
    let phi = |x: &[f64]| -> f64 {
        let mut p = 0.0;
        for i in 0..n {
            let hx: f64 = (0..n).map(|j| h[(i, j)] * (x[j] - s[j])).sum();
            let z = (x[i] / v_s).abs();
            let lncosh = z + (-2.0 * z).exp().ln_1p() - std::f64::consts::LN_2;
            p += 0.5 * (x[i] - s[i]) * hx / ts
                + 0.5 * viscous[i] * x[i] * x[i]
                + coulomb[i] * v_s * lncosh;
        }
        p
    };
    for _ in 0..30 {
        // Residual r (in d) and the Jacobian (in a, row-major).
        for i in 0..n {
            let mut r = viscous[i] * x[i] + coulomb[i] * (x[i] / v_s).tanh();
            for j in 0..n {
                r += h[(i, j)] * (x[j] - s[j]) / ts;
                a[i * n + j] = h[(i, j)] / ts;
            }
            a[i * n + i] += slope(viscous[i], coulomb[i], v_s, x[i]);
            d[i] = r;
        }
        if !cholesky_solve(a, d, n) {
            return;
        }
        let (p0, mut step) = (phi(x), 1.0);
        loop {
            for i in 0..n {
                trial[i] = x[i] - step * d[i];
            }
            if phi(trial) <= p0 || step < 1e-6 {
                break;
            }
            step *= 0.5;
        }
        let scale = x.iter().fold(v_s, |m, v| m.max(v.abs()));
        let moved = (0..n).fold(0.0_f64, |m, i| m.max((trial[i] - x[i]).abs()));
        x.copy_from_slice(trial);
        if moved <= 1e-12 * scale {
            break;
        }
    }
}

/// Solves `a y = b` in place (`b ← y`) for a symmetric positive definite
/// row-major `n × n` matrix `a` (overwritten by its Cholesky factor).
/// Returns false when `a` is not positive definite (or not finite).
fn cholesky_solve(a: &mut [f64], b: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let mut djj = a[j * n + j];
        for k in 0..j {
            djj -= a[j * n + k] * a[j * n + k];
        }
        if !(djj > 0.0 && djj.is_finite()) {
            return false;
        }
        let ljj = djj.sqrt();
        a[j * n + j] = ljj;
        for i in j + 1..n {
            let mut v = a[i * n + j];
            for k in 0..j {
                v -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = v / ljj;
        }
    }
    for i in 0..n {
        for k in 0..i {
            b[i] -= a[i * n + k] * b[k];
        }
        b[i] /= a[i * n + i];
    }
    for i in (0..n).rev() {
        for k in i + 1..n {
            b[i] -= a[k * n + i] * b[k];
        }
        b[i] /= a[i * n + i];
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The coupled step solves `h (x − s)/Ts + F(x) = 0` (the residual of
    /// every joint, brute force), for a strongly coupled inertia (two
    /// parallel axes under a payload) at rest, creeping and sliding; with a
    /// diagonal inertia it is the joint-by-joint step.
    #[test]
    fn the_coupled_step_solves_the_coupled_implicit_friction() {
        let h = nalgebra::DMatrix::from_row_slice(
            3,
            3,
            &[0.9, 0.7, 0.1, 0.7, 0.8, 0.05, 0.1, 0.05, 0.3],
        );
        let (ts, vs) = (0.01, 1e-3);
        let (fv, fc) = ([4.0, 0.5, 0.25], [3.0, 0.8, 0.4]);
        let (mut x, mut work) = ([0.0; 3], [0.0; 15]);
        for s in [
            [0.0, 0.0, 0.0],
            [2e-3, -1e-3, 5e-4],
            [0.5, -0.3, 0.2],
            [-1.0, 1.0, 0.0],
        ] {
            implicit_velocities(&h, ts, &s, (&fv, &fc, vs), &mut x, &mut work);
            for i in 0..3 {
                let r: f64 = (0..3).map(|j| h[(i, j)] * (x[j] - s[j]) / ts).sum::<f64>()
                    + fv[i] * x[i]
                    + fc[i] * (x[i] / vs).tanh();
                assert!(r.abs() < 1e-6, "s = {s:?}: residual {r} on joint {i}");
            }
        }
        let d = nalgebra::DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![0.9, 0.8, 0.3]));
        let s = [0.02, -1e-3, 3e-4];
        implicit_velocities(&d, ts, &s, (&fv, &fc, vs), &mut x, &mut work);
        for i in 0..3 {
            let one = implicit_velocity(d[(i, i)], ts, s[i], fv[i], fc[i], vs);
            assert!((x[i] - one).abs() <= 1e-12 * one.abs().max(vs), "joint {i}");
        }
    }

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
