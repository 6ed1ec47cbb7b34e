//! Exact zero-order-hold discretization of the linear-like model (Eq. (9)–(13)).
//!
//! With `A = [[0, I], [0, f0]]`, `B = [[0], [I]]` and `M = f0·Ts`:
//!
//! ```text
//! Ad = e^{A Ts} = [[I, Φ1], [0, e^M]],   Bd = ∫₀^Ts e^{A s} B ds = [[Φ2], [Φ1]],
//! Φ1 = ∫₀^Ts e^{f0 s} ds = Ts·Σ M^k/(k+1)!,
//! Φ2 = ∫₀^Ts ∫₀^s e^{f0 r} dr ds = Ts²·Σ M^k/(k+2)!.
//! ```
//!
//! The three series are summed for `X = M/2^s` with `‖X‖₁ ≤ 1/4` (13 terms,
//! truncation below 1e-17), then scaled back by `s` doublings of the interval
//! `t → 2t`:
//!
//! ```text
//! Φ2(2t) = Φ2 + E Φ2 + t Φ1,   Φ1(2t) = Φ1 + E Φ1,   E(2t) = E E.
//! ```
//!
//! This is the exact exponential of the augmented matrix `[[A, B], [0, 0]]·Ts`
//! (shown equal to 1e-12 in the tests) at the cost of a few n×n products, in
//! buffers sized once.

use nalgebra::DMatrix;

use crate::control::model_errors::ZohError;
use crate::control::solvers::dense::{gemm, norm1};

/// Largest 1-norm of the scaled `X = M/2^s` summed by the Taylor series.
const THETA: f64 = 0.25;
/// Highest power of the Taylor series: `θ^13/13! < 3e-18`.
const TERMS: usize = 12;
/// Largest accepted number of doublings (‖M‖₁ up to 2^60·θ).
const MAX_SQUARINGS: u32 = 60;

/// ZOH discretization of `q̈ = f0 q̇ + u` for `n` joints, with preallocated
/// n×n buffers. Allocation-free after [`Zoh::new`].
#[derive(Debug, Clone)]
pub struct Zoh {
    n: usize,
    e: DMatrix<f64>,
    phi1: DMatrix<f64>,
    phi2: DMatrix<f64>,
    x: DMatrix<f64>,
    p: DMatrix<f64>,
    tmp: DMatrix<f64>,
    squarings: u32,
}

impl Zoh {
    /// Buffers for `n` joints.
    pub fn new(n: usize) -> Self {
        let z = || DMatrix::zeros(n, n);
        Self {
            n,
            e: z(),
            phi1: z(),
            phi2: z(),
            x: z(),
            p: z(),
            tmp: z(),
            squarings: 0,
        }
    }

    /// Number of joints `n`.
    pub fn dof(&self) -> usize {
        self.n
    }

    /// Discretizes with sampling period `ts` (Eq. (13)). `f0` is n×n.
    pub fn discretize(&mut self, f0: &DMatrix<f64>, ts: f64) -> Result<(), ZohError> {
        let n = self.n;
        if f0.shape() != (n, n) {
            return Err(ZohError::WrongShape { n, got: f0.shape() });
        }
        let (s, tau) = self.scaled_exponent(f0, ts)?;
        self.taylor_sums(tau);
        // Doublings t → 2t.
        let mut t = tau;
        for _ in 0..s {
            self.double(t);
            t *= 2.0;
        }
        let finite = |m: &DMatrix<f64>| m.as_slice().iter().all(|v| v.is_finite());
        if !(finite(&self.e) && finite(&self.phi1) && finite(&self.phi2)) {
            return Err(ZohError::Overflow);
        }
        Ok(())
    }

    /// Sets `X = f0·Ts / 2^s` with the fewest doublings `s` that bring `‖X‖₁` within
    /// [`THETA`] (at most [`MAX_SQUARINGS`]); returns `s` and the scaled period
    /// `τ = Ts / 2^s`.
    fn scaled_exponent(&mut self, f0: &DMatrix<f64>, ts: f64) -> Result<(u32, f64), ZohError> {
        // X = f0·Ts / 2^s
        for (x, f) in self.x.as_mut_slice().iter_mut().zip(f0.as_slice()) {
            *x = f * ts;
        }
        let norm = norm1(self.n, self.x.as_slice());
        if !norm.is_finite() || !ts.is_finite() {
            return Err(ZohError::BadNorm { norm });
        }
        let mut s = 0u32;
        let mut scaled = norm;
        while scaled > THETA {
            scaled *= 0.5;
            s += 1;
            if s > MAX_SQUARINGS {
                return Err(ZohError::BadNorm { norm });
            }
        }
        self.squarings = s;
        let scale = 0.5f64.powi(s as i32);
        let tau = ts * scale;
        self.x.as_mut_slice().iter_mut().for_each(|v| *v *= scale);
        Ok((s, tau))
    }

    /// The truncated Taylor series at the scaled interval `τ`: `E = Σ X^k/k!`,
    /// `Φ1 = τ·Σ X^k/(k+1)!`, `Φ2 = τ²·Σ X^k/(k+2)!` (k ≤ [`TERMS`]).
    fn taylor_sums(&mut self, tau: f64) {
        let n = self.n;
        // Taylor sums: E = Σ X^k/k!, S1 = Σ X^k/(k+1)!, S2 = Σ X^k/(k+2)!.
        // P_k = X^k/k!; S1 gets P_k/(k+1), S2 gets P_k/((k+1)(k+2)).
        self.e.fill(0.0);
        self.phi1.fill(0.0);
        self.phi2.fill(0.0);
        self.p.fill(0.0);
        for i in 0..n {
            self.p[(i, i)] = 1.0;
        }
        for k in 0..=TERMS {
            if k > 0 {
                gemm(
                    n,
                    n,
                    n,
                    1.0 / k as f64,
                    self.p.as_slice(),
                    self.x.as_slice(),
                    0.0,
                    self.tmp.as_mut_slice(),
                );
                std::mem::swap(&mut self.p, &mut self.tmp);
            }
            let c1 = 1.0 / (k + 1) as f64;
            let c2 = c1 / (k + 2) as f64;
            for (((e, a), b), p) in self
                .e
                .as_mut_slice()
                .iter_mut()
                .zip(self.phi1.as_mut_slice())
                .zip(self.phi2.as_mut_slice())
                .zip(self.p.as_slice())
            {
                *e += p;
                *a += c1 * p;
                *b += c2 * p;
            }
        }
        // Φ1 = τ·S1, Φ2 = τ²·S2.
        self.phi1.as_mut_slice().iter_mut().for_each(|v| *v *= tau);
        self.phi2
            .as_mut_slice()
            .iter_mut()
            .for_each(|v| *v *= tau * tau);
    }

    /// One doubling of the interval `t → 2t`: `Φ2 ← Φ2 + E Φ2 + t Φ1`, `Φ1 ← Φ1 + E Φ1`,
    /// `E ← E E`.
    fn double(&mut self, t: f64) {
        let n = self.n;
        // Φ2 ← Φ2 + E Φ2 + t Φ1
        self.tmp.copy_from(&self.phi2);
        gemm(
            n,
            n,
            n,
            1.0,
            self.e.as_slice(),
            self.phi2.as_slice(),
            1.0,
            self.tmp.as_mut_slice(),
        );
        for (d, p1) in self.tmp.as_mut_slice().iter_mut().zip(self.phi1.as_slice()) {
            *d += t * p1;
        }
        std::mem::swap(&mut self.phi2, &mut self.tmp);
        // Φ1 ← Φ1 + E Φ1
        self.tmp.copy_from(&self.phi1);
        gemm(
            n,
            n,
            n,
            1.0,
            self.e.as_slice(),
            self.phi1.as_slice(),
            1.0,
            self.tmp.as_mut_slice(),
        );
        std::mem::swap(&mut self.phi1, &mut self.tmp);
        // E ← E E
        gemm(
            n,
            n,
            n,
            1.0,
            self.e.as_slice(),
            self.e.as_slice(),
            0.0,
            self.tmp.as_mut_slice(),
        );
        std::mem::swap(&mut self.e, &mut self.tmp);
    }

    /// `e^{f0 Ts}`, the lower-right block of `Ad`.
    pub fn e(&self) -> &DMatrix<f64> {
        &self.e
    }

    /// `Φ1 = ∫₀^Ts e^{f0 s} ds`: upper-right block of `Ad`, lower block of `Bd`.
    pub fn phi1(&self) -> &DMatrix<f64> {
        &self.phi1
    }

    /// `Φ2 = ∫₀^Ts ∫₀^s e^{f0 r} dr ds`: upper block of `Bd`.
    pub fn phi2(&self) -> &DMatrix<f64> {
        &self.phi2
    }

    /// Number of doublings used by the last [`Zoh::discretize`].
    pub fn squarings(&self) -> u32 {
        self.squarings
    }

    /// Writes the full `Ad` (2n×2n) and `Bd` (2n×n) of Eq. (13).
    pub fn fill_discrete(
        &self,
        ad: &mut DMatrix<f64>,
        bd: &mut DMatrix<f64>,
    ) -> Result<(), ZohError> {
        let n = self.n;
        for (shape, want) in [(ad.shape(), (2 * n, 2 * n)), (bd.shape(), (2 * n, n))] {
            if shape != want {
                return Err(ZohError::WrongShape { n, got: shape });
            }
        }
        ad.fill(0.0);
        for i in 0..n {
            ad[(i, i)] = 1.0;
        }
        ad.view_mut((0, n), (n, n)).copy_from(&self.phi1);
        ad.view_mut((n, n), (n, n)).copy_from(&self.e);
        bd.view_mut((0, 0), (n, n)).copy_from(&self.phi2);
        bd.view_mut((n, 0), (n, n)).copy_from(&self.phi1);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact ZOH by the exponential of the augmented (3n)×(3n) matrix.
    fn reference(f0: &DMatrix<f64>, ts: f64) -> (DMatrix<f64>, DMatrix<f64>) {
        let n = f0.nrows();
        let mut aug = DMatrix::<f64>::zeros(3 * n, 3 * n);
        for i in 0..n {
            aug[(i, n + i)] = 1.0; // A12 = I
            aug[(n + i, 2 * n + i)] = 1.0; // B2 = I
        }
        aug.view_mut((n, n), (n, n)).copy_from(f0);
        let ex = (aug * ts).exp();
        (
            ex.view((0, 0), (2 * n, 2 * n)).into_owned(),
            ex.view((0, 2 * n), (2 * n, n)).into_owned(),
        )
    }

    fn random(n: usize, seed: &mut u64) -> DMatrix<f64> {
        DMatrix::from_fn(n, n, |_, _| crate::linalg::random::symmetric(seed))
    }

    fn rel(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
        (a - b).norm() / b.norm()
    }

    #[test]
    fn equals_exponential_of_augmented_matrix() {
        let mut seed = 7;
        let ts = 0.01;
        for n in [1, 2, 3, 6] {
            // ‖f0·Ts‖ from 1e-6 to ~40: no doubling up to many doublings.
            for target in [1e-4, 1e-1, 1.0, 10.0, 1e2, 1e3, 4e3] {
                for sign in [1.0, -1.0] {
                    let r = random(n, &mut seed);
                    let f0 = &r * (sign * target / r.norm());
                    let mut z = Zoh::new(n);
                    z.discretize(&f0, ts).unwrap();
                    let mut ad = DMatrix::zeros(2 * n, 2 * n);
                    let mut bd = DMatrix::zeros(2 * n, n);
                    z.fill_discrete(&mut ad, &mut bd).unwrap();
                    let (ad_ref, bd_ref) = reference(&f0, ts);
                    let (ea, eb) = (rel(&ad, &ad_ref), rel(&bd, &bd_ref));
                    assert!(
                        ea <= 1e-12 && eb <= 1e-12,
                        "n={n} |f0|={target} sign={sign}: rel err Ad {ea:e}, Bd {eb:e}"
                    );
                    // Blocks separately, too (Φ2 is much smaller than Ad).
                    let n2 = 2 * n;
                    let e_ref = ad_ref.view((n, n), (n, n)).into_owned();
                    let p1_ref = bd_ref.view((n, 0), (n, n)).into_owned();
                    let p2_ref = bd_ref.view((0, 0), (n, n)).into_owned();
                    assert!(rel(z.e(), &e_ref) <= 1e-12, "E, n={n} {target}");
                    assert!(rel(z.phi1(), &p1_ref) <= 1e-12, "Φ1, n={n} {target}");
                    assert!(rel(z.phi2(), &p2_ref) <= 1e-12, "Φ2, n={n} {target}");
                    assert_eq!(ad.shape(), (n2, n2));
                }
            }
        }
    }

    #[test]
    fn zero_f0_gives_double_integrator() {
        let n = 3;
        let ts = 0.02;
        let mut z = Zoh::new(n);
        z.discretize(&DMatrix::zeros(n, n), ts).unwrap();
        let i = DMatrix::<f64>::identity(n, n);
        assert!((z.e() - &i).norm() == 0.0);
        assert!((z.phi1() - &i * ts).norm() < 1e-16);
        assert!((z.phi2() - &i * (ts * ts / 2.0)).norm() < 1e-18);
        assert_eq!(z.squarings(), 0);
    }

    #[test]
    fn rejects_non_finite_f0() {
        let mut z = Zoh::new(2);
        let mut f0 = DMatrix::zeros(2, 2);
        f0[(0, 1)] = f64::NAN;
        assert!(matches!(
            z.discretize(&f0, 0.01),
            Err(ZohError::BadNorm { .. })
        ));
    }
}
