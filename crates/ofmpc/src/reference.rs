//! The joint reference the controllers follow: `w_k = q_ref(k Ts)`, sampled
//! once before the run, with its preview `w_{k+1..k+N}` (the last value held
//! past the end of the path), its velocity and acceleration, and the flange
//! position it corresponds to.
//!
//! [`build_reference`] maps a timed Cartesian path to joint space by inverse
//! kinematics: analytic (OPW) where the robot's kinematics are ortho-parallel
//! with a spherical wrist and match the built-in parameters (the IRB 140),
//! else numeric (damped least squares seeded by the previous sample).

use crate::dynamics::RobotDynamics;
use crate::ik::{
    ForwardKinematics, IkError, IkSolver, NumericIk, NumericIkSettings, OpwParameters,
};
use crate::robot::Robot;
use crate::trajectory::CartesianTrajectory;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// Why a path cannot be followed in joint space.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "program line {line} (t = {time:.3} s), flange at ({:.1}, {:.1}, {:.1}) mm: {message}; {hint}",
    position[0] * 1e3, position[1] * 1e3, position[2] * 1e3
)]
pub struct ReferenceError {
    /// Program line of the failing sample.
    pub line: usize,
    /// Time of the failing sample (s).
    pub time: f64,
    /// Requested flange position (m, base frame).
    pub position: [f64; 3],
    /// What failed (unreachable pose, joint limit, joint speed).
    pub message: String,
    /// What to do.
    pub hint: String,
}

/// How the flange orientation along the path is chosen: constant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Orientation {
    /// The flange orientation of the robot at q = 0 (the IRB 140: tool axis
    /// along base +x, as in the paper).
    AtZero,
    /// A fixed rotation of the flange in the base frame.
    Fixed(UnitQuaternion<f64>),
}

enum Ik {
    Analytic(Box<IkSolver>),
    Numeric(Box<NumericIk>),
}

/// True when the built-in OPW parameters reproduce the robot's forward
/// kinematics (checked at 50 pseudo-random configurations to 1e-9).
fn opw_matches(d: &mut RobotDynamics, opw: &OpwParameters) -> bool {
    if d.robot().dof() != 6 {
        return false;
    }
    let mut s = 12345u64;
    (0..50).all(|_| {
        let q: [f64; 6] = std::array::from_fn(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 6.0 - 3.0
        });
        let a = d.flange_pose(&q);
        let b = opw.forward(&q);
        (a.translation.vector - b.translation.vector).norm() < 1e-9
            && a.rotation.angle_to(&b.rotation) < 1e-9
    })
}

/// When the analytic solution jumps to another configuration, whether the
/// continuous branch (the solution nearest to `prev` with the limits lifted)
/// leaves a joint's range: the real reason for the jump.
fn branch_limit(ik: &Ik, pose: &Isometry3<f64>, prev: &[f64], robot: &Robot) -> Option<String> {
    let Ik::Analytic(s) = ik else { return None };
    let wide = IkSolver::new(*s.parameters(), [-100.0; 6], [100.0; 6]).ok()?;
    let hint: [f64; 6] = std::array::from_fn(|i| prev[i]);
    let q = wide.solve_near(pose, &hint).ok()?;
    robot.joints().iter().enumerate().find_map(|(i, j)| {
        (q[i] < j.limits.lower || q[i] > j.limits.upper).then(|| {
            format!(
                "joint {} ({}) would have to reach {:.1}°, outside its range [{:.1}°, {:.1}°], to follow the path \
                 (the only solutions within the limits are another arm configuration, a jump)",
                i + 1,
                j.name,
                q[i].to_degrees(),
                j.limits.lower.to_degrees(),
                j.limits.upper.to_degrees()
            )
        })
    })
}

/// Maps the timed path to joint space, sampled every `ts` seconds from t = 0
/// to the end of the path, with constant flange `orientation`.
///
/// Checks every sample: reachable, within the joint limits, and each joint's
/// step within its speed limit times `ts`. The first sample takes the
/// solution closest to q = 0 (within limits); each later one the solution
/// closest to the previous sample.
pub fn build_reference(
    robot: &Robot,
    trajectory: &CartesianTrajectory,
    orientation: Orientation,
    ts: f64,
) -> Result<JointReference, ReferenceError> {
    let n = robot.dof();
    // One model for every kinematic query below: q = 0 pose, OPW check,
    // numeric IK, Jacobians.
    let mut fk = RobotDynamics::new(robot.clone());
    let rotation = match orientation {
        Orientation::AtZero => fk.flange_pose(&vec![0.0; n]).rotation,
        Orientation::Fixed(r) => r,
    };
    let fail =
        |line: usize, time: f64, p: Vector3<f64>, message: String, hint: &str| ReferenceError {
            line,
            time,
            position: [p.x, p.y, p.z],
            message,
            hint: hint.to_string(),
        };
    let offset_hint = "move the part into the workspace with a work offset (a G10 L2 P1 X.. Y.. Z.. line, or --origin X,Y,Z in mm), or change the orientation";
    if !(ts.is_finite() && ts > 0.0) {
        return Err(fail(
            trajectory.sample(0.0).line,
            0.0,
            trajectory.start(),
            format!("sample period {ts} s"),
            "give a positive Ts",
        ));
    }
    let lower = robot.lower_limits();
    let upper = robot.upper_limits();
    let opw = OpwParameters::irb140();
    let mut ik = if opw_matches(&mut fk, &opw) {
        let lo: [f64; 6] = std::array::from_fn(|i| lower[i].max(-1e6));
        let up: [f64; 6] = std::array::from_fn(|i| upper[i].min(1e6));
        Ik::Analytic(Box::new(IkSolver::new(opw, lo, up).map_err(|e| {
            fail(
                0,
                0.0,
                trajectory.start(),
                e.to_string(),
                "check the joint limits",
            )
        })?))
    } else {
        let lo: Vec<f64> = lower.iter().map(|v| v.max(-1e6)).collect();
        let up: Vec<f64> = upper.iter().map(|v| v.min(1e6)).collect();
        let numeric = NumericIk::new(n, &lo, &up, NumericIkSettings::default()).map_err(|e| {
            fail(
                0,
                0.0,
                trajectory.start(),
                e.to_string(),
                "check the joint limits",
            )
        })?;
        Ik::Numeric(Box::new(numeric))
    };
    let steps = (trajectory.duration() / ts - 1e-9).ceil().max(0.0) as usize + 1;
    let mut q = Vec::with_capacity(steps * n);
    let mut position = Vec::with_capacity(steps);
    let mut lines = Vec::with_capacity(steps);
    let mut prev = vec![0.0; n];
    let mut jac = nalgebra::DMatrix::zeros(6, n);
    let mut exact_qd = Vec::with_capacity(if n == 6 { steps * n } else { 0 });
    let mut exact_ok = true;
    for k in 0..steps {
        let t = (k as f64 * ts).min(trajectory.duration());
        let sample = trajectory.sample(t);
        let p = sample.position;
        let pose = Isometry3::from_parts(Translation3::from(p), rotation);
        let sol: Result<Vec<f64>, IkError> = match &mut ik {
            Ik::Analytic(s) => {
                let hint: [f64; 6] = std::array::from_fn(|i| prev[i]);
                s.solve_near(&pose, &hint).map(|a| a.to_vec())
            }
            Ik::Numeric(num) => {
                let mut x = prev.clone();
                num.solve(&mut fk, &pose, &mut x).map(|_| x)
            }
        };
        let sol = sol.map_err(|e| fail(sample.line, t, p, e.to_string(), offset_hint))?;
        if k > 0 {
            for (i, j) in robot.joints().iter().enumerate() {
                let speed = (sol[i] - prev[i]).abs() / ts;
                if speed > j.limits.velocity {
                    if let Some(msg) = branch_limit(&ik, &pose, &prev, robot) {
                        return Err(fail(sample.line, t, p, msg, offset_hint));
                    }
                    return Err(fail(
                        sample.line,
                        t,
                        p,
                        format!(
                            "joint {} ({}) would move at {:.3} rad/s, above its speed limit {:.3} rad/s",
                            i + 1,
                            j.name,
                            speed,
                            j.limits.velocity
                        ),
                        "lower the path speed (--speed) or acceleration (--accel), or move the part away from the wrist singularity with a work offset",
                    ));
                }
            }
        }
        // Exact joint velocity where the Jacobian is square and regular:
        // J(q) q̇ = [ṗ; ω] with ω = 0 (constant orientation).
        if n == 6 {
            fk.flange_jacobian(&sol, &mut jac);
            let rhs = nalgebra::DVector::from_column_slice(&[
                sample.velocity.x,
                sample.velocity.y,
                sample.velocity.z,
                0.0,
                0.0,
                0.0,
            ]);
            match jac.clone().lu().solve(&rhs) {
                Some(v) if v.iter().all(|x| x.is_finite()) => exact_qd.extend(v.iter()),
                _ => exact_ok = false,
            }
        }
        q.extend_from_slice(&sol);
        position.push([p.x, p.y, p.z]);
        lines.push(sample.line);
        prev.copy_from_slice(&sol);
    }
    let mut r = JointReference::from_samples(n, ts, q, position, lines).ok_or_else(|| {
        fail(
            0,
            0.0,
            trajectory.start(),
            "empty reference".into(),
            "check the program",
        )
    })?;
    if n == 6 && exact_ok && exact_qd.len() == r.qd.len() {
        r.qd = exact_qd;
    }
    Ok(r)
}
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
    /// accelerations are central differences of `q` (zero at the ends, where
    /// the path is at rest). [`build_reference`] replaces the velocities by
    /// the exact `J(q)⁻¹ ṗ` for six-joint robots.
    ///
    /// Returns `None` when the sizes disagree, `K = 0` or `ts ≤ 0`.
    pub fn from_samples(
        n: usize,
        ts: f64,
        q: Vec<f64>,
        position: Vec<[f64; 3]>,
        line: Vec<usize>,
    ) -> Option<Self> {
        let k = position.len();
        if n == 0 || k == 0 || q.len() != k * n || line.len() != k || !(ts > 0.0 && ts.is_finite())
        {
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
        Some(Self {
            n,
            ts,
            q,
            qd,
            qdd,
            position,
            line,
        })
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
    /// Reference velocity at sample `k` (n values); past the end, the last
    /// sample's (the path ends at rest: zero).
    pub fn qd(&self, k: usize) -> &[f64] {
        let k = self.clamp(k);
        &self.qd[k * self.n..(k + 1) * self.n]
    }
    /// Reference acceleration at sample `k` (n values); past the end, the
    /// last sample's (zero).
    pub fn qdd(&self, k: usize) -> &[f64] {
        let k = self.clamp(k);
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
        let q: Vec<f64> = (0..k)
            .flat_map(|s| {
                let t = s as f64 * ts;
                [t * t, -t]
            })
            .collect();
        let r = JointReference::from_samples(2, ts, q, vec![[0.0; 3]; k], vec![1; k]).unwrap();
        assert!(
            (r.qd(5)[0] - 1.0).abs() < 1e-12
                && (r.qdd(5)[0] - 2.0).abs() < 1e-9
                && (r.qd(5)[1] + 1.0).abs() < 1e-12
        );
        let mut p = vec![0.0; 6];
        r.preview(9, 3, &mut p);
        assert_eq!(&p[0..2], r.q(10));
        assert_eq!(&p[2..4], r.q(10));
        assert_eq!(&p[4..6], r.q(10));
        assert!((r.duration() - 1.0).abs() < 1e-12);
        assert!(
            JointReference::from_samples(2, ts, vec![0.0; 3], vec![[0.0; 3]; 2], vec![1; 2])
                .is_none()
        );
    }
}
