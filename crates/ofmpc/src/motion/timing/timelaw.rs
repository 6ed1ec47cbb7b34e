//! Rest-to-rest time laws: how the arc length advances along one path segment.
//!
//! A profile is a normalized polynomial `σ(τ)`, `τ = t/T ∈ [0, 1]`, with `σ(0) = 0`,
//! `σ(1) = 1` and zero velocity and acceleration at both ends. The arc length along a segment
//! of length `L` and duration `T` is `s(t) = L σ(t/T)`, so `ṡ = (L/T) σ'`, `s̈ = (L/T²) σ''`,
//! `s⃛ = (L/T³) σ'''`.
//!
//! The paper (section IV) time-parameterizes its path "with a 5th order polynomial of
//! acceleration": the acceleration is a quintic in time, i.e. the position is the septic
//! [`Profile::Septic`], which also has zero jerk at both ends. [`Profile::Quintic`] is the
//! common alternative (zero velocity and acceleration at the ends, but not zero jerk).
//!
//! # Peak factors (derivation)
//!
//! Septic: `σ' = 140 τ³ (1−τ)³`, maximal at `τ = 1/2`: `35/16`.
//! `σ'' = 420 τ² (1−τ)² (1−2τ)`; with `x = τ − 1/2`, `σ'' = −840 x (1/4 − x²)²`, extremal where
//! `x² = 1/20`: `|σ''|max = 840 · (1/(2√5)) · (1/5)² = 84√5/25`.
//! `σ''' = 420 (1/4 − x²)(10x² − 1/2)`, extremal at `x = 0`: `|σ'''|max = 105/2`.
//!
//! Quintic: `σ' = 30 τ² (1−τ)²`, max `15/8`; `σ'' = 60 τ (1−τ)(1−2τ)`, extremal at
//! `x² = 1/12`: `10/√3`; `σ''' = 60 (1 − 6τ + 6τ²)`, extremal at the ends: `60`.

/// A normalized rest-to-rest position profile `σ(τ)`, `τ ∈ [0, 1]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Profile {
    /// `σ = 35τ⁴ − 84τ⁵ + 70τ⁶ − 20τ⁷`: the acceleration is a 5th-order polynomial of time
    /// (the paper's time law, section IV); zero velocity, acceleration and jerk at both ends.
    #[default]
    Septic,
    /// `σ = 10τ³ − 15τ⁴ + 6τ⁵`: zero velocity and acceleration at both ends.
    Quintic,
}

/// Value and derivatives of a normalized profile at one `τ` (derivatives with respect to `τ`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileValue {
    /// `σ(τ)`.
    pub s: f64,
    /// `σ'(τ)`.
    pub ds: f64,
    /// `σ''(τ)`.
    pub dds: f64,
    /// `σ'''(τ)` (jerk).
    pub ddds: f64,
}

impl Profile {
    /// `σ` and its first three derivatives at `τ`.
    ///
    /// On `[0, 1]` (ends included) these are the polynomial's values, so the quintic's jerk is
    /// 60 at `τ = 0` and `τ = 1`. Strictly outside, the profile rests: `σ = 0` before (and for
    /// NaN), `σ = 1` after, all derivatives zero.
    pub fn eval(self, tau: f64) -> ProfileValue {
        if tau.is_nan() || tau <= 0.0 {
            return ProfileValue {
                s: 0.0,
                ds: 0.0,
                dds: 0.0,
                ddds: if tau == 0.0 {
                    self.eval_inside(0.0).ddds
                } else {
                    0.0
                },
            };
        }
        if tau >= 1.0 {
            return ProfileValue {
                s: 1.0,
                ds: 0.0,
                dds: 0.0,
                ddds: if tau == 1.0 {
                    self.eval_inside(1.0).ddds
                } else {
                    0.0
                },
            };
        }
        self.eval_inside(tau)
    }

    fn eval_inside(self, t: f64) -> ProfileValue {
        let u = 1.0 - t;
        match self {
            Profile::Septic => {
                // σ = τ⁴ (35 − 84τ + 70τ² − 20τ³), in Horner form.
                let t2 = t * t;
                let t3 = t2 * t;
                ProfileValue {
                    s: t2 * t2 * (35.0 + t * (-84.0 + t * (70.0 - 20.0 * t))),
                    ds: 140.0 * t3 * u * u * u,
                    dds: 420.0 * t2 * u * u * (1.0 - 2.0 * t),
                    // d/dτ [τ²(1−τ)²(1−2τ)] = 2τ(1−τ)(1−2τ)² − 2τ²(1−τ)²
                    ddds: 840.0 * t * u * ((1.0 - 2.0 * t).powi(2) - t * u),
                }
            }
            Profile::Quintic => ProfileValue {
                s: t * t * t * (10.0 + t * (-15.0 + 6.0 * t)),
                ds: 30.0 * t * t * u * u,
                dds: 60.0 * t * u * (1.0 - 2.0 * t),
                ddds: 60.0 * (1.0 - 6.0 * t * u),
            },
        }
    }

    /// `max σ'` (peak velocity is `factor · L/T`): 35/16 (septic), 15/8 (quintic).
    pub fn peak_velocity_factor(self) -> f64 {
        match self {
            Profile::Septic => 35.0 / 16.0,
            Profile::Quintic => 15.0 / 8.0,
        }
    }

    /// `max |σ''|` (peak acceleration is `factor · L/T²`): 84√5/25 (septic), 10/√3 (quintic).
    pub fn peak_acceleration_factor(self) -> f64 {
        match self {
            Profile::Septic => 84.0 * 5f64.sqrt() / 25.0,
            Profile::Quintic => 10.0 / 3f64.sqrt(),
        }
    }

    /// `max |σ'''|` (peak jerk is `factor · L/T³`): 105/2 (septic), 60 (quintic).
    pub fn peak_jerk_factor(self) -> f64 {
        match self {
            Profile::Septic => 105.0 / 2.0,
            Profile::Quintic => 60.0,
        }
    }

    /// The shortest duration `T` (s) of a segment of length `length` (m) whose peak path speed
    /// stays within `max_speed` (m/s) and whose peak path acceleration stays within `max_accel`
    /// (m/s²): `T = max(f_v L / v_max, √(f_a L / a_max))`.
    ///
    /// "Path acceleration" is `s̈`, the tangential acceleration; on an arc the Cartesian
    /// acceleration also has the centripetal part `ṡ²/r`. Returns 0 for `length ≤ 0`.
    /// The limits must be positive and finite (checked by the callers' option validation).
    pub fn min_duration(self, length: f64, max_speed: f64, max_accel: f64) -> f64 {
        if length.is_nan() || length <= 0.0 {
            return 0.0;
        }
        let t_speed = self.peak_velocity_factor() * length / max_speed;
        let t_accel = (self.peak_acceleration_factor() * length / max_accel).sqrt();
        t_speed.max(t_accel)
    }
}

/// Arc length, path speed, path acceleration and jerk at one instant of a [`TimeLaw`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathState {
    /// Arc length `s` (m).
    pub s: f64,
    /// Path speed `ṡ` (m/s).
    pub speed: f64,
    /// Path acceleration `s̈` (m/s²).
    pub accel: f64,
    /// Path jerk `s⃛` (m/s³).
    pub jerk: f64,
}

/// A profile scaled to one segment: length `L` travelled in duration `T`, rest to rest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeLaw {
    /// The normalized profile.
    pub profile: Profile,
    /// Path length `L` (m).
    pub length: f64,
    /// Duration `T` (s).
    pub duration: f64,
}

impl TimeLaw {
    /// The fastest law over `length` that respects `max_speed` and `max_accel`
    /// (see [`Profile::min_duration`]).
    pub fn fastest(profile: Profile, length: f64, max_speed: f64, max_accel: f64) -> Self {
        TimeLaw {
            profile,
            length,
            duration: profile.min_duration(length, max_speed, max_accel),
        }
    }

    /// State at time `t` since the segment's start; before 0 it rests at `s = 0`, after `T`
    /// at `s = L`.
    pub fn eval(&self, t: f64) -> PathState {
        let big_t = self.duration;
        if big_t <= 0.0 {
            return PathState {
                s: if t > 0.0 { self.length } else { 0.0 },
                speed: 0.0,
                accel: 0.0,
                jerk: 0.0,
            };
        }
        let p = self.profile.eval(t / big_t);
        let l = self.length;
        PathState {
            s: l * p.s,
            speed: l / big_t * p.ds,
            accel: l / (big_t * big_t) * p.dds,
            jerk: l / (big_t * big_t * big_t) * p.ddds,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PROFILES: [Profile; 2] = [Profile::Septic, Profile::Quintic];

    #[test]
    fn boundary_conditions() {
        for p in PROFILES {
            let a = p.eval(0.0);
            let b = p.eval(1.0);
            assert_eq!((a.s, a.ds, a.dds), (0.0, 0.0, 0.0), "{p:?} at 0");
            assert!((b.s - 1.0).abs() < 1e-15, "{p:?} σ(1) = {}", b.s);
            assert!(
                b.ds.abs() < 1e-13 && b.dds.abs() < 1e-12,
                "{p:?} at 1: {b:?}"
            );
            // Just inside the interval the polynomial itself gives the same values.
            let e = 1e-7;
            let a_in = p.eval(e);
            let b_in = p.eval(1.0 - e);
            assert!(a_in.s < 1e-13 && a_in.ds < 1e-12 && a_in.dds.abs() < 1e-5);
            assert!((1.0 - b_in.s) < 1e-13 && b_in.ds < 1e-12 && b_in.dds.abs() < 1e-5);
            match p {
                Profile::Septic => {
                    assert_eq!(a.ddds, 0.0);
                    assert!(b.ddds.abs() < 1e-12);
                }
                Profile::Quintic => {
                    assert_eq!(a.ddds, 60.0);
                    assert!((b.ddds - 60.0).abs() < 1e-12);
                }
            }
            // Symmetry: σ(1−τ) = 1 − σ(τ).
            for i in 0..=100 {
                let t = i as f64 / 100.0;
                assert!((p.eval(1.0 - t).s - (1.0 - p.eval(t).s)).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        for p in PROFILES {
            let h = 1e-5;
            for i in 1..200 {
                let t = i as f64 / 200.0;
                let (m, c, q) = (p.eval(t - h), p.eval(t), p.eval(t + h));
                assert!(((q.s - m.s) / (2.0 * h) - c.ds).abs() < 1e-8);
                assert!(((q.ds - m.ds) / (2.0 * h) - c.dds).abs() < 1e-7);
                assert!(((q.dds - m.dds) / (2.0 * h) - c.ddds).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn peak_factors_match_dense_scan() {
        for p in PROFILES {
            let n = 200_000;
            let (mut v, mut a, mut j) = (0.0f64, 0.0f64, 0.0f64);
            for i in 0..=n {
                let e = p.eval(i as f64 / n as f64);
                v = v.max(e.ds.abs());
                a = a.max(e.dds.abs());
                j = j.max(e.ddds.abs());
            }
            // The scan never exceeds the analytic peak and comes within O(h²) of it.
            for (scan, exact) in [
                (v, p.peak_velocity_factor()),
                (a, p.peak_acceleration_factor()),
                (j, p.peak_jerk_factor()),
            ] {
                assert!(scan <= exact * (1.0 + 1e-14), "{p:?}: {scan} > {exact}");
                assert!(exact - scan < 1e-8 * exact, "{p:?}: {scan} vs {exact}");
            }
        }
        assert!((Profile::Septic.peak_acceleration_factor() - 7.513_188_404_399_292).abs() < 1e-12);
    }

    #[test]
    fn durations_respect_both_limits() {
        for p in PROFILES {
            for &(len, vmax, amax) in &[
                (0.4, 0.5, 2.5),
                (0.001, 0.5, 2.5),
                (2.0, 0.1, 10.0),
                (1.2566, 1.0, 0.3),
            ] {
                let law = TimeLaw::fastest(p, len, vmax, amax);
                let n = 20_000;
                let (mut v, mut a) = (0.0f64, 0.0f64);
                for i in 0..=n {
                    let st = law.eval(law.duration * i as f64 / n as f64);
                    v = v.max(st.speed.abs());
                    a = a.max(st.accel.abs());
                }
                assert!(v <= vmax * (1.0 + 1e-9) && a <= amax * (1.0 + 1e-9));
                // Minimal: one of the two limits is reached (within the scan resolution).
                assert!(v > vmax * (1.0 - 1e-6) || a > amax * (1.0 - 1e-6));
                assert!((law.eval(law.duration).s - len).abs() < 1e-15);
                assert_eq!(law.eval(-1.0).s, 0.0);
                assert_eq!(law.eval(law.duration + 1.0).s, len);
            }
        }
    }

    #[test]
    fn degenerate_inputs() {
        assert_eq!(Profile::Septic.min_duration(0.0, 1.0, 1.0), 0.0);
        assert_eq!(Profile::Septic.min_duration(f64::NAN, 1.0, 1.0), 0.0);
        let law = TimeLaw::fastest(Profile::Septic, 0.0, 1.0, 1.0);
        assert_eq!(law.eval(1.0).speed, 0.0);
        assert_eq!(Profile::Septic.eval(f64::NAN).s, 0.0);
    }
}
