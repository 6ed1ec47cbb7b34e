//! Recursive least squares with forgetting for the payload's parameters,
//! kept physically consistent after every update.
//!
//! Measurement model, one row per joint (see [`super::regressor`]):
//! `τ_i − τ_i^0(q, q̇, q̈) = Y_{q,i}(q, q̇, q̈) π`, with `τ^0` the robot's inverse
//! dynamics without payload. The update runs joint row by joint row (a scalar
//! RLS step each), then forgets once per sample:
//!
//! `k = P φ / (r + φᵀ P φ)`, `π ← π + k (y − φᵀ π)`, `P ← P − k φᵀ P`; then
//! `P ← P / λ`, its trace bounded by that of the prior `P₀` (no wind-up while
//! the motion does not excite every parameter, e.g. at rest).
//!
//! Bounds: after each sample the estimate is projected onto the physically
//! consistent set, `0 ≤ m ≤ m_max` and the pseudo-inertia `J(π) ⪰ 0` (the
//! negative eigenvalues of `J` scaled to a 0.1 m length, `T J T` with
//! `T = diag(10, 10, 10, 1)`, clipped), which implies a positive
//! semi-definite inertia that obeys the triangle inequalities
//! ([`super::pseudo_inertia`]). The projected estimate is what the model
//! receives ([`PayloadRls::estimate`]); the recursion itself keeps the
//! unconstrained least-squares solution ([`PayloadRls::raw_estimate`]):
//! projecting the recursion's state in a metric other than `P⁻¹` biases it
//! (early, weakly excited inertia entries would drag the mass), and the
//! exact `P⁻¹`-metric projection is a semi-definite program, too heavy for
//! a real-time step.
//!
//! Everything is fixed-size (10×10, 4×4): an update allocates nothing.

use super::regressor::{params_of_pseudo_inertia, pseudo_inertia, PayloadParams, NUM_PARAMS};
use nalgebra::{Matrix4, SMatrix, SymmetricEigen};

/// Covariance of the parameters.
type Cov = SMatrix<f64, NUM_PARAMS, NUM_PARAMS>;

/// Tuning of the estimator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RlsSettings {
    /// Forgetting factor `λ` per sample (0 < λ ≤ 1); `1/(1 − λ)` samples is
    /// the memory.
    pub forgetting: f64,
    /// Prior standard deviation of the mass (kg).
    pub sigma_mass: f64,
    /// Prior standard deviation of each first moment (kg·m).
    pub sigma_moment: f64,
    /// Prior standard deviation of each inertia entry (kg·m²).
    pub sigma_inertia: f64,
    /// Torque noise standard deviation assumed per joint (N·m).
    pub sigma_torque: f64,
    /// Upper bound of the mass (kg).
    pub max_mass: f64,
    /// A joint's a-priori prediction error (N·m) beyond which the payload is
    /// taken to have changed (picked up, dropped): the covariance restarts
    /// from the prior, so that the estimate moves at once instead of at the
    /// pace of the forgetting factor.
    pub change_threshold_nm: f64,
    /// The model receives the identified rotational inertia (about the
    /// centre of mass) only once the standard deviation of every inertia
    /// entry is below this (kg·m²); until then a point mass at the identified
    /// centre of mass ([`PayloadRls::model_estimate`]). At rest the inertia is
    /// not excited, and an early, poorly determined inertia on a light wrist
    /// would make the model many times heavier than the plant: the
    /// incremental algorithms tolerate only a few per cent of that
    /// (`analyze stability`).
    pub inertia_confidence_kgm2: f64,
}

impl Default for RlsSettings {
    fn default() -> Self {
        Self {
            forgetting: 0.998,
            sigma_mass: 10.0,
            sigma_moment: 1.0,
            sigma_inertia: 0.2,
            sigma_torque: 0.1,
            max_mass: 1e3,
            change_threshold_nm: 2.0,
            inertia_confidence_kgm2: 1e-3,
        }
    }
}

/// Why estimator settings cannot be used.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RlsSettingsError {
    /// The forgetting factor is not in (0, 1].
    #[error("the forgetting factor is {0}: it must be in (0, 1]")]
    Forgetting(f64),
    /// A standard deviation or the mass bound is not finite and > 0.
    #[error("the estimator's {what} is {value}: it must be finite and > 0")]
    NotPositive {
        /// Which value.
        what: &'static str,
        /// The value.
        value: f64,
    },
}

impl RlsSettings {
    /// Checks the values.
    pub fn validate(&self) -> Result<(), RlsSettingsError> {
        if !(self.forgetting > 0.0 && self.forgetting <= 1.0) {
            return Err(RlsSettingsError::Forgetting(self.forgetting));
        }
        for (what, value) in [
            ("prior mass deviation", self.sigma_mass),
            ("prior first-moment deviation", self.sigma_moment),
            ("prior inertia deviation", self.sigma_inertia),
            ("torque noise deviation", self.sigma_torque),
            ("mass bound", self.max_mass),
            ("change threshold", self.change_threshold_nm),
            ("inertia confidence", self.inertia_confidence_kgm2),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(RlsSettingsError::NotPositive { what, value });
            }
        }
        Ok(())
    }

    fn prior_covariance(&self) -> Cov {
        let mut p = Cov::zeros();
        for k in 0..NUM_PARAMS {
            let s = match k {
                0 => self.sigma_mass,
                1..=3 => self.sigma_moment,
                _ => self.sigma_inertia,
            };
            p[(k, k)] = s * s;
        }
        p
    }
}

/// The recursive estimator of `π`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PayloadRls {
    settings: RlsSettings,
    prior: PayloadParams,
    theta: PayloadParams,
    physical: PayloadParams,
    p: Cov,
    p_trace_max: f64,
    updates: u64,
    restarts: u64,
}

impl PayloadRls {
    /// Starts from the prior `π₀` (e.g. no payload, or the payload the model
    /// assumes) with the settings' prior covariance.
    pub fn new(settings: RlsSettings, prior: PayloadParams) -> Result<Self, RlsSettingsError> {
        settings.validate()?;
        let p = settings.prior_covariance();
        let mut s = Self {
            settings,
            prior,
            theta: prior,
            physical: prior,
            p_trace_max: p.trace(),
            p,
            updates: 0,
            restarts: 0,
        };
        s.project();
        Ok(s)
    }

    /// Back to the prior.
    pub fn reset(&mut self) {
        self.theta = self.prior;
        self.p = self.settings.prior_covariance();
        self.updates = 0;
        self.restarts = 0;
        self.project();
    }

    /// The current estimate `π̂`, physically consistent (projected).
    pub fn estimate(&self) -> &PayloadParams {
        &self.physical
    }

    /// Whether the rotational inertia is determined well enough to be used
    /// (see [`RlsSettings::inertia_confidence_kgm2`]).
    pub fn inertia_identified(&self) -> bool {
        let limit = self.settings.inertia_confidence_kgm2;
        (4..NUM_PARAMS).all(|k| self.p[(k, k)].max(0.0).sqrt() < limit)
    }

    /// What the controller's model receives: [`Self::estimate`], or while
    /// the rotational inertia is not identified, the same mass and first
    /// moments as a point mass (inertia about the centre of mass zero; the
    /// projection keeps that consistent: a point mass is on the boundary of
    /// the physical set).
    pub fn model_estimate(&self) -> PayloadParams {
        if self.inertia_identified() {
            return self.physical;
        }
        self.point_mass_estimate()
    }

    /// The estimate's mass and first moments as a point mass (inertia about
    /// the centre of mass zero): [`Self::model_estimate`] before the
    /// rotational inertia is identified.
    pub fn point_mass_estimate(&self) -> PayloadParams {
        let m = self.physical[0];
        let mut out = PayloadParams::zeros();
        out[0] = m;
        if m > 0.0 {
            let h = nalgebra::Vector3::new(self.physical[1], self.physical[2], self.physical[3]);
            let c = h / m;
            // I_o of a point mass at c: m (|c|² 1 − c cᵀ).
            let i_o = (nalgebra::Matrix3::identity() * c.norm_squared() - c * c.transpose()) * m;
            out[1] = h.x;
            out[2] = h.y;
            out[3] = h.z;
            out[4] = i_o[(0, 0)];
            out[5] = i_o[(0, 1)];
            out[6] = i_o[(0, 2)];
            out[7] = i_o[(1, 1)];
            out[8] = i_o[(1, 2)];
            out[9] = i_o[(2, 2)];
        }
        out
    }

    /// The recursion's unconstrained least-squares estimate.
    pub fn raw_estimate(&self) -> &PayloadParams {
        &self.theta
    }

    /// The estimated mass (kg), of [`Self::estimate`].
    pub fn mass(&self) -> f64 {
        self.physical[0]
    }

    /// The parameter covariance `P`.
    pub fn covariance(&self) -> &SMatrix<f64, NUM_PARAMS, NUM_PARAMS> {
        &self.p
    }

    /// Covariance restarts on a detected payload change since the start.
    pub fn restarts(&self) -> u64 {
        self.restarts
    }

    /// Samples processed since the start.
    pub fn updates(&self) -> u64 {
        self.updates
    }

    /// One sample: `rows[i]` is `Y_{q,i}` and `y[i]` the measured payload
    /// torque `τ_i − τ_i^0` of joint `i`. Rows or values that are not finite
    /// make the whole sample skipped (returns `false`).
    pub fn update(&mut self, rows: &[[f64; NUM_PARAMS]], y: &[f64]) -> bool {
        if rows.len() != y.len()
            || !y.iter().all(|v| v.is_finite())
            || !rows.iter().flatten().all(|v| v.is_finite())
        {
            return false;
        }
        let r = self.settings.sigma_torque * self.settings.sigma_torque;
        let jump = rows.iter().zip(y).any(|(row, &yi)| {
            let phi = PayloadParams::from_column_slice(row);
            (yi - phi.dot(&self.theta)).abs() > self.settings.change_threshold_nm
        });
        if jump && self.updates > 0 {
            self.p = self.settings.prior_covariance();
            self.restarts += 1;
        }
        for (row, &yi) in rows.iter().zip(y) {
            let phi = PayloadParams::from_column_slice(row);
            let pphi = self.p * phi;
            let s = r + phi.dot(&pphi);
            if !(s.is_finite() && s > 0.0) {
                continue;
            }
            let k = pphi / s;
            let e = yi - phi.dot(&self.theta);
            self.theta += k * e;
            self.p -= k * pphi.transpose();
        }
        // Forget, keep P symmetric and bounded.
        self.p = (self.p + self.p.transpose()) * (0.5 / self.settings.forgetting);
        let tr = self.p.trace();
        if tr > self.p_trace_max {
            self.p *= self.p_trace_max / tr;
        }
        self.project();
        self.updates += 1;
        true
    }

    /// Projects the recursion's estimate onto the physically consistent set
    /// into `self.physical`; a non-finite estimate restarts from the prior.
    fn project(&mut self) {
        if !self.theta.iter().all(|v| v.is_finite()) {
            self.theta = self.prior;
            self.p = self.settings.prior_covariance();
        }
        self.physical = project_physical(&self.theta, self.settings.max_mass);
    }
}

/// Length scale of the projection (m): balances the pseudo-inertia's entries
/// (kg·m², kg·m, kg) for a tool-sized body.
const PROJECTION_LENGTH: f64 = 0.1;

/// The physically consistent parameters nearest to `pi` in the scaled
/// pseudo-inertia's Frobenius norm: `J ⪰ 0` and `0 ≤ m ≤ max_mass`.
pub fn project_physical(pi: &PayloadParams, max_mass: f64) -> PayloadParams {
    let t = Matrix4::from_diagonal(&nalgebra::Vector4::new(
        1.0 / PROJECTION_LENGTH,
        1.0 / PROJECTION_LENGTH,
        1.0 / PROJECTION_LENGTH,
        1.0,
    ));
    let t_inv = Matrix4::from_diagonal(&nalgebra::Vector4::new(
        PROJECTION_LENGTH,
        PROJECTION_LENGTH,
        PROJECTION_LENGTH,
        1.0,
    ));
    let js = t * pseudo_inertia(pi) * t;
    let eig = SymmetricEigen::new(js);
    let mut out = *pi;
    if eig.eigenvalues.iter().any(|&l| l < 0.0) {
        let clipped = eig.eigenvalues.map(|l| l.max(0.0));
        let js = eig.eigenvectors * Matrix4::from_diagonal(&clipped) * eig.eigenvectors.transpose();
        out = params_of_pseudo_inertia(&(t_inv * js * t_inv));
    }
    if out[0] > max_mass {
        // Scaling the whole body keeps J ⪰ 0.
        out *= max_mass / out[0];
    }
    if out[0].is_nan() || out[0] < 0.0 {
        out = PayloadParams::zeros();
    }
    out
}
