//! One step of the classical fourth-order Runge–Kutta method for a second-order system
//! `q̈ = a(q, q̇)` written as the first-order system `x = (q, v)`, `ẋ = (v, a(q, v))`.
//!
//! With step `h`:
//!
//! - `k₁ = a(q, v)`,
//! - `v₂ = v + ½h k₁`, `k₂ = a(q + ½h v, v₂)`,
//! - `v₃ = v + ½h k₂`, `k₃ = a(q + ½h v₂, v₃)`,
//! - `v₄ = v + h k₃`,  `k₄ = a(q + h v₃, v₄)`,
//! - `q ← q + h/6 (v + 2v₂ + 2v₃ + v₄)`, `v ← v + h/6 (k₁ + 2k₂ + 2k₃ + k₄)`.
//!
//! Operation order (fixed: the plant's trajectories are reproducible bit for bit): a stage
//! point is `x + (c·h)·y` with `c·h` rounded first (`0.5 * h * y`, `h * y`); the update is
//! `x + (h/6)·(((y₁ + 2y₂) + 2y₃) + y₄)`, entry by entry, `q_i` before `v_i`.

/// Scratch entries [`rk4_second_order_step`] needs per degree of freedom (`k₁…k₄`, `v₂…v₄`
/// and the stage position).
pub(crate) const RK4_WORK_PER_DOF: usize = 8;

/// Advances `(q, v)` (`n` entries each) by one RK4 step of length `h` (see the module's
/// equations). `accel(q, v, a)` writes the acceleration `a(q, v)` into `a` (`n` entries); its
/// first error aborts the step and is returned, leaving `q` and `v` unchanged. `work` holds at
/// least [`RK4_WORK_PER_DOF`]` · n` entries of scratch; nothing is allocated.
pub(crate) fn rk4_second_order_step<E>(
    q: &mut [f64],
    v: &mut [f64],
    h: f64,
    work: &mut [f64],
    mut accel: impl FnMut(&[f64], &[f64], &mut [f64]) -> Result<(), E>,
) -> Result<(), E> {
    let n = q.len();
    debug_assert!(v.len() == n && work.len() >= RK4_WORK_PER_DOF * n);
    let (k1, rest) = work.split_at_mut(n);
    let (k2, rest) = rest.split_at_mut(n);
    let (k3, rest) = rest.split_at_mut(n);
    let (k4, rest) = rest.split_at_mut(n);
    let (v2, rest) = rest.split_at_mut(n);
    let (v3, rest) = rest.split_at_mut(n);
    let (v4, rest) = rest.split_at_mut(n);
    let qs = &mut rest[..n];
    accel(q, v, k1)?;
    for i in 0..n {
        qs[i] = q[i] + 0.5 * h * v[i];
        v2[i] = v[i] + 0.5 * h * k1[i];
    }
    accel(qs, v2, k2)?;
    for i in 0..n {
        qs[i] = q[i] + 0.5 * h * v2[i];
        v3[i] = v[i] + 0.5 * h * k2[i];
    }
    accel(qs, v3, k3)?;
    for i in 0..n {
        qs[i] = q[i] + h * v3[i];
        v4[i] = v[i] + h * k3[i];
    }
    accel(qs, v4, k4)?;
    for i in 0..n {
        q[i] += h / 6.0 * (v[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]);
        v[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The harmonic oscillator `q̈ = −ω² q` over a quarter period: the global (phase) error is
    /// `O(h⁴)`, it shrinks 16-fold when `h` halves.
    #[test]
    fn fourth_order_on_the_harmonic_oscillator() {
        let w = std::f64::consts::FRAC_PI_2;
        let err = |steps: usize| {
            let h = 1.0 / steps as f64;
            let (mut q, mut v) = ([1.0], [0.0]);
            let mut work = [0.0; RK4_WORK_PER_DOF];
            for _ in 0..steps {
                rk4_second_order_step(&mut q, &mut v, h, &mut work, |q, _, a| {
                    a[0] = -w * w * q[0];
                    Ok::<(), ()>(())
                })
                .unwrap();
            }
            (q[0] - w.cos()).abs()
        };
        let (e1, e2) = (err(50), err(100));
        assert!(e1 < 1e-5, "{e1}");
        let ratio = e1 / e2;
        assert!((ratio - 16.0).abs() < 1.0, "{ratio}");
    }

    #[test]
    fn an_error_leaves_the_state_unchanged() {
        let (mut q, mut v) = ([1.0, 2.0], [3.0, 4.0]);
        let mut work = [0.0; 2 * RK4_WORK_PER_DOF];
        let mut calls = 0;
        let r = rk4_second_order_step(&mut q, &mut v, 0.1, &mut work, |_, _, a| {
            calls += 1;
            a.fill(1.0);
            if calls == 3 {
                Err("stage 3")
            } else {
                Ok(())
            }
        });
        assert_eq!(r, Err("stage 3"));
        assert_eq!((q, v), ([1.0, 2.0], [3.0, 4.0]));
    }
}
