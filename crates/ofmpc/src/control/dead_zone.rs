//! The hold dead zone of the integrating actions (Ioannou & Sun, *Robust
//! Adaptive Control*, §8.5.3: a dead zone on the adaptation/integration
//! driven by an error below the noise level), issue 35.
//!
//! On a real arm the integrating action of an offset-free controller (the
//! incremental input `u_k = u_{k−1} + Δu_k` of the first and second
//! algorithms, the integral of the PID/CTC baselines, the disturbance
//! estimate of `dob-mpc`) is driven at rest by an error the encoder cannot
//! resolve (quantization, noise) through a friction that the model does not
//! carry (a stiff damper `F_c/v_s` near rest, a relay beyond): it integrates
//! until the joint breaks away, overshoots and integrates back — it hunts
//! instead of settling. Within the sensor's resolution there is nothing left
//! to remove, so there the integration stops: on a joint whose reference
//! rests over the whole horizon and whose error is within
//! [`MpcSettings::encoder_counts`](crate::control::MpcSettings::encoder_counts)'s
//! [`DEAD_ZONE_COUNTS`] counts, the integrating state is held. Outside the
//! band, or while the reference moves, nothing changes (the controller stays
//! offset-free to the band). Off (`encoder_counts = 0`) by default.

use crate::control::drive_model::DriveModel;

/// Half-width of the dead zone in encoder counts.
pub const DEAD_ZONE_COUNTS: f64 = 1.0;

/// Half-width of the dead zone (rad) for `counts` encoder counts per
/// revolution (0: no dead zone).
pub fn band_rad(counts: f64) -> f64 {
    if counts > 0.0 && counts.is_finite() {
        DEAD_ZONE_COUNTS * std::f64::consts::TAU / counts
    } else {
        0.0
    }
}

/// Half-widths of the dead zone (rad) per joint for `counts` encoder counts
/// per revolution and `widths` counts each
/// ([`MpcSettings::dead_zone_counts`](crate::control::MpcSettings::dead_zone_counts),
/// one value for every joint or one per joint, [`DEAD_ZONE_COUNTS`] where
/// missing); all 0 without encoders. A width of [`DEAD_ZONE_COUNTS`] gives
/// [`band_rad`] exactly. Allocates (construction only).
pub fn bands_rad(counts: f64, widths: &crate::control::Weight, n: usize) -> Vec<f64> {
    let one = band_rad(counts);
    (0..n)
        .map(|i| match widths.get(i) {
            Some(w) if w != DEAD_ZONE_COUNTS && one > 0.0 => w * std::f64::consts::TAU / counts,
            _ => one,
        })
        .collect()
}

/// [`in_dead_zone`] with a half-width per joint (`bands`, n values, from
/// [`bands_rad`]). Allocates nothing.
pub fn in_dead_zone_bands(
    bands: &[f64],
    w_k: &[f64],
    y: &[f64],
    preview: &[f64],
    hold: &mut [bool],
) {
    let n = hold.len();
    for (i, (h, band)) in hold.iter_mut().zip(bands).enumerate() {
        *h = *band > 0.0
            && (w_k[i] - y[i]).abs() <= *band
            && preview.chunks_exact(n).all(|p| p[i] == w_k[i]);
    }
}

/// Marks in `hold[i]` the joints whose integrating action is held: the
/// reference rests over the horizon (`w_{k+j} = w_k`, `j = 1..N`, exactly;
/// `preview` is N·n values) and `|w_k − y| ≤ band`. All `false` when
/// `band ≤ 0`. Allocates nothing.
pub fn in_dead_zone(band: f64, w_k: &[f64], y: &[f64], preview: &[f64], hold: &mut [bool]) {
    let n = hold.len();
    for (i, h) in hold.iter_mut().enumerate() {
        *h = band > 0.0
            && (w_k[i] - y[i]).abs() <= band
            && preview.chunks_exact(n).all(|p| p[i] == w_k[i]);
    }
}

/// A joint creeps while `|q̇| < CREEP_FACTOR·v_s` ([`creeps_at_rest`]): the
/// friction's slope there is still a fifth of its slope at rest or more
/// (`F_c tanh(3)/(3 v_s)`), and one encoder count per sample (6e-4 rad/s at
/// 20 bits and 10 ms) does not leave it.
pub const CREEP_FACTOR: f64 = 3.0;

/// Whether joint `i` holds on the friction's stiff damper: a drive model
/// with a Coulomb estimate (`drives`, given only with friction
/// compensation; `None`: never), a reference that rests over the horizon
/// (`preview`, N·n values, equal to `w_k` exactly) and a creeping joint
/// (`|q̇_i| < CREEP_FACTOR · v_s`). Near rest the smoothed Coulomb friction
/// `F_c tanh(v/v_s)` is a damper `b = F_c/v_s` far stiffer than a light
/// joint's gains are tuned for; the stiffer holds of the incremental
/// algorithms (`hold_q_du_scale`) and of the baselines (`hold_gain_scale`)
/// apply there and only there: beyond it — a joint broken away — the
/// stiffer gain on the bare inertia would cycle through the delay. One
/// home for the condition. Allocates nothing.
pub fn creeps_at_rest(
    drives: Option<&DriveModel>,
    i: usize,
    qd: f64,
    w_k: &[f64],
    preview: &[f64],
) -> bool {
    let n = w_k.len();
    drives.is_some_and(|d| {
        d.coulomb_nm[i] > 0.0
            && qd.abs() < CREEP_FACTOR * d.coulomb_velocity_rad_s
            && preview.chunks_exact(n).all(|p| p[i] == w_k[i])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_resting_joints_within_the_band_are_held() {
        let band = band_rad(1_048_576.0);
        assert!((band - 5.99e-6).abs() < 1e-8);
        let w = [1.0, 2.0, 3.0];
        let y = [1.0 + 0.5 * band, 2.0 + 2.0 * band, 3.0];
        let preview = [1.0, 2.0, 3.0, 1.0, 2.0, 3.1];
        let mut hold = [false; 3];
        in_dead_zone(band, &w, &y, &preview, &mut hold);
        assert_eq!(hold, [true, false, false]);
        in_dead_zone(0.0, &w, &w, &[1.0, 2.0, 3.0], &mut hold);
        assert_eq!(hold, [false; 3]);
    }

    #[test]
    fn per_joint_bands_widen_only_their_joints() {
        use crate::control::Weight;
        let counts = 1_048_576.0;
        let one = band_rad(counts);
        // One count: the scalar band exactly; two on the last joint.
        let bands = bands_rad(counts, &Weight::Diagonal(vec![1.0, 1.0, 2.0]), 3);
        assert_eq!(bands[..2], [one, one]);
        assert!((bands[2] - 2.0 * one).abs() < 1e-18);
        assert_eq!(bands_rad(counts, &Weight::Scalar(1.0), 2), vec![one; 2]);
        assert_eq!(bands_rad(0.0, &Weight::Scalar(2.0), 2), vec![0.0; 2]);
        let w = [1.0, 2.0, 3.0];
        let y = [1.0 + 1.5 * one, 2.0 + 1.5 * one, 3.0 + 1.5 * one];
        let preview = [1.0, 2.0, 3.0];
        let mut hold = [false; 3];
        in_dead_zone_bands(&bands, &w, &y, &preview, &mut hold);
        assert_eq!(hold, [false, false, true]);
        // The same as the scalar rule with equal bands.
        let mut scalar = [false; 3];
        in_dead_zone_bands(&[one; 3], &w, &y, &preview, &mut hold);
        in_dead_zone(one, &w, &y, &preview, &mut scalar);
        assert_eq!(hold, scalar);
    }

    #[test]
    fn only_creeping_joints_at_a_resting_reference_hold_on_the_damper() {
        let mut d = DriveModel::from_robot(&crate::robot::Robot::irb140());
        d.coulomb_nm = vec![1.0, 0.0];
        d.coulomb_velocity_rad_s = 1e-3;
        let w = [1.0, 2.0];
        let rest = [1.0, 2.0, 1.0, 2.0];
        // Creeping (below 3 v_s) at a resting reference: holds.
        assert!(creeps_at_rest(Some(&d), 0, 2.9e-3, &w, &rest));
        assert!(creeps_at_rest(Some(&d), 0, -2.9e-3, &w, &rest));
        // Broken away, no Coulomb estimate, no drives (no compensation).
        assert!(!creeps_at_rest(Some(&d), 0, 3.1e-3, &w, &rest));
        assert!(!creeps_at_rest(Some(&d), 1, 0.0, &w, &rest));
        assert!(!creeps_at_rest(None, 0, 0.0, &w, &rest));
        // The reference moves anywhere over the horizon.
        assert!(!creeps_at_rest(
            Some(&d),
            0,
            0.0,
            &w,
            &[1.0, 2.0, 1.0 + 1e-12, 2.0]
        ));
    }
}
