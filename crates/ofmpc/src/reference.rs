//! The joint reference the controllers follow: `w_k = q_ref(k Ts)`, sampled
//! once before the run, with its preview `w_{k+1..k+N}` (the last value held
//! past the end of the path), its velocity and acceleration, and the flange
//! position it corresponds to.

/// A joint reference sampled at `ts`. Vectors are stored row-major (`k·n + i`).
#[derive(Debug, Clone, PartialEq)]
pub struct JointReference {
    n: usize,
    ts: f64,
    q: Vec<f64>,
    qd: Vec<f64>,
    qdd: Vec<f64>,
    position: Vec<[f64; 3]>,
    line: Vec<usize>,
}

impl JointReference {
    /// A reference from its samples: `q` (K·n values), the flange positions
    /// (K) and the program line of each sample (K). Velocities and
    /// accelerations are central differences of `q` (one-sided at the ends,
    /// where the path is at rest).
    ///
    /// Returns `None` when the sizes disagree, `K = 0` or `ts ≤ 0`.
    pub fn from_samples(n: usize, ts: f64, q: Vec<f64>, position: Vec<[f64; 3]>, line: Vec<usize>) -> Option<Self> {
        let k = position.len();
        if n == 0 || k == 0 || q.len() != k * n || line.len() != k || !(ts > 0.0 && ts.is_finite()) {
            return None;
        }
        let mut qd = vec![0.0; k * n];
        let mut qdd = vec![0.0; k * n];
        for s in 1..k.saturating_sub(1) {
            for i in 0..n {
                let (a, b, c) = (q[(s - 1) * n + i], q[s * n + i], q[(s + 1) * n + i]);
                qd[s * n + i] = (c - a) / (2.0 * ts);
                qdd[s * n + i] = (c - 2.0 * b + a) / (ts * ts);
            }
        }
        Some(Self { n, ts, q, qd, qdd, position, line })
    }
    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.n
    }
    /// Sample period (s).
    pub fn ts(&self) -> f64 {
        self.ts
    }
    /// Number of samples K (the path; the hold is not included).
    pub fn len(&self) -> usize {
        self.position.len()
    }
    /// Always false: a reference has at least one sample.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }
    /// Duration of the path (s): `(K − 1) Ts`.
    pub fn duration(&self) -> f64 {
        (self.len() - 1) as f64 * self.ts
    }
    fn clamp(&self, k: usize) -> usize {
        k.min(self.len() - 1)
    }
    /// `w_k` (n values); past the end, the last sample.
    pub fn q(&self, k: usize) -> &[f64] {
        let k = self.clamp(k);
        &self.q[k * self.n..(k + 1) * self.n]
    }
    /// Reference velocity at sample `k` (zero past the end).
    pub fn qd(&self, k: usize) -> &[f64] {
        if k >= self.len() {
            return &self.qd[..0];
        }
        &self.qd[k * self.n..(k + 1) * self.n]
    }
    /// Reference acceleration at sample `k` (empty past the end).
    pub fn qdd(&self, k: usize) -> &[f64] {
        if k >= self.len() {
            return &self.qdd[..0];
        }
        &self.qdd[k * self.n..(k + 1) * self.n]
    }
    /// Flange position of the reference at sample `k` (m, base frame).
    pub fn position(&self, k: usize) -> [f64; 3] {
        self.position[self.clamp(k)]
    }
    /// Program line of sample `k`.
    pub fn line(&self, k: usize) -> usize {
        self.line[self.clamp(k)]
    }
    /// Writes the preview `w_{k+1}, …, w_{k+N}` into `out` (N·n values, `N =
    /// out.len() / n`), holding the last value past the end. Allocation-free.
    pub fn preview(&self, k: usize, horizon: usize, out: &mut [f64]) {
        let n = self.n;
        for j in 0..horizon.min(out.len() / n) {
            out[j * n..(j + 1) * n].copy_from_slice(self.q(k + 1 + j));
        }
    }
    /// All samples of `q`, row-major.
    pub fn q_all(&self) -> &[f64] {
        &self.q
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn preview_holds_the_last_value_and_differences_are_exact_for_parabolas() {
        let ts = 0.1;
        let k = 11;
        let q: Vec<f64> = (0..k).flat_map(|s| {
            let t = s as f64 * ts;
            [t * t, -t]
        }).collect();
        let r = JointReference::from_samples(2, ts, q, vec![[0.0; 3]; k], vec![1; k]).unwrap();
        assert!((r.qd(5)[0] - 1.0).abs() < 1e-12 && (r.qdd(5)[0] - 2.0).abs() < 1e-9 && (r.qd(5)[1] + 1.0).abs() < 1e-12);
        let mut p = vec![0.0; 6];
        r.preview(9, 3, &mut p);
        assert_eq!(&p[0..2], r.q(10));
        assert_eq!(&p[2..4], r.q(10));
        assert_eq!(&p[4..6], r.q(10));
        assert!((r.duration() - 1.0).abs() < 1e-12);
        assert!(JointReference::from_samples(2, ts, vec![0.0; 3], vec![[0.0; 3]; 2], vec![1; 2]).is_none());
    }
}
