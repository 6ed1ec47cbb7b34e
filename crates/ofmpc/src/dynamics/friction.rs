//! The joint friction model, one home for the plant and the controllers.
//!
//! Per joint: viscous friction `F_v q̇` plus Coulomb friction smoothed over a
//! velocity scale `v_s`,
//!
//! `F(q̇) = F_v q̇ + F_c tanh(q̇ / v_s)`,
//!
//! the torque that opposes the motion. The plant integrates it
//! (`sim::Plant`); the controllers' friction compensation uses it as the
//! linear-like damping [`damping`] (`F(q̇) = d(q̇) q̇`). The state observer's
//! discrete-time, stick-aware Coulomb term is the same friction resolved
//! within one sample (`control::StateObserver::set_friction`).

/// Default velocity scale `v_s` of the smoothed Coulomb friction (rad/s):
/// the plant's and the controllers' default.
pub const DEFAULT_COULOMB_VELOCITY: f64 = 1e-3;

/// Friction torque `F(v) = F_v v + F_c tanh(v / v_s)` of a joint moving at
/// `v` (`viscous` = `F_v`, `coulomb` = `F_c`, `v_s` > 0).
#[inline]
pub fn torque(viscous: f64, coulomb: f64, v_s: f64, v: f64) -> f64 {
    viscous * v + coulomb * (v / v_s).tanh()
}

/// The linear-like damping `d(v) = F_v + F_c tanh(v/v_s)/v`, so that
/// `d(v)·v` is the friction torque [`torque`] (up to rounding); at rest
/// (`|v/v_s| < 10⁻⁶`) its limit `F_v + F_c/v_s`.
#[inline]
pub fn damping(viscous: f64, coulomb: f64, v_s: f64, v: f64) -> f64 {
    let x = v / v_s;
    let c = if x.abs() < 1e-6 {
        coulomb / v_s
    } else {
        coulomb * x.tanh() / v
    };
    viscous + c
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `d(v)·v = F(v)`, and the damping is continuous at rest.
    #[test]
    fn damping_times_velocity_is_the_torque() {
        let (fv, fc, vs) = (0.7, 2.5, DEFAULT_COULOMB_VELOCITY);
        for v in [-3.0, -1e-2, -2e-9, 1e-12, 5e-4, 1e-3, 0.2, 4.0] {
            let f = torque(fv, fc, vs, v);
            let d = damping(fv, fc, vs, v) * v;
            assert!(
                (f - d).abs() <= 1e-12 * f.abs().max(1e-300),
                "v = {v}: {f} vs {d}"
            );
        }
        let at_rest = damping(fv, fc, vs, 0.0);
        let near = damping(fv, fc, vs, 1e-7 * vs);
        assert!((at_rest - near).abs() <= 1e-9 * at_rest);
    }
}
