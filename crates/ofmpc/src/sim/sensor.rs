//! The sensor stage: what happens between the true and the measured state.
//!
//! [`Sensor::read`] takes the true state as a plain [`JointState`] (from
//! [`super::Plant::state`] in a simulation, from the drives on real hardware:
//! it never touches a plant) and gives the reading the controller's side
//! receives: encoder quantization, noise, a backward-difference encoder
//! velocity, the encoder faults of a scenario's `[plant] faults` (glitch,
//! dropout), the delay line (all set by the sensing part of
//! [`PlantSettings`]), then the loss of whole samples ([`LossSchedule`]: NaN
//! readings and dropouts). Standing in for a lost or invalid reading is the
//! supervised controller's measurement repair ([`super::SupervisedController`]),
//! not the sensor's.
//!
//! The noise keeps its own generator (xorshift + Box–Muller, seeded by
//! `[plant] seed`): `linalg::random` is a linear congruential generator, whose
//! sequence differs, and the noisy runs must stay reproducible bit for bit.

use super::faults::{Fault, FaultSchedule, LossSchedule};
use super::plant::{PlantError, PlantSettings, PlantSettingsError};
use super::state::JointState;

/// A small deterministic Gaussian generator (xorshift + Box–Muller), so that
/// noisy runs are reproducible from their seed.
#[derive(Debug, Clone)]
struct Gauss {
    s: u64,
    spare: Option<f64>,
}

impl Gauss {
    fn uniform(&mut self) -> f64 {
        self.s ^= self.s << 13;
        self.s ^= self.s >> 7;
        self.s ^= self.s << 17;
        ((self.s >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn next(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        let (u1, u2) = (self.uniform(), self.uniform());
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (2.0 * std::f64::consts::PI * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }
}

/// Measures the true state and loses the scheduled samples. Sized at
/// construction; [`Sensor::read`] and [`Sensor::measure`] allocate nothing.
#[derive(Debug, Clone)]
pub struct Sensor {
    n: usize,
    /// The control period (s).
    ts: f64,
    /// The sensing settings (and the faults) of the plant's settings.
    settings: PlantSettings,
    /// The encoders' resolution (rad; 0: not quantized).
    resolution: f64,
    rng: Gauss,
    /// Delay line of measurements, `(D + 1) × 2n`, and its next slot.
    ring: Vec<f64>,
    ring_next: usize,
    /// Measured positions of the previous sample (encoder velocity).
    prev_qm: Vec<f64>,
    measured_once: bool,
    /// The encoder faults' path samples ([`FaultSchedule::for_plant`]).
    schedule: FaultSchedule,
    /// Per fault: an encoder glitch already happened.
    fired: Vec<bool>,
    /// The last measurement before the delay line (for frozen encoders).
    last_meas: Vec<f64>,
    lost: LossSchedule,
}

impl Sensor {
    /// A sensor for `n` joints read once per control period `ts` (s), with
    /// the sensing effects and encoder faults of `settings` (checked here),
    /// losing the samples of `lost` (scheduled at `ts`).
    pub fn new(
        settings: &PlantSettings,
        n: usize,
        ts: f64,
        lost: LossSchedule,
    ) -> Result<Self, PlantSettingsError> {
        settings.validate(n)?;
        Ok(Self::checked(settings, n, ts, lost))
    }

    /// An ideal sensor (the true state, no delay) for `n` joints at the
    /// period `ts`, losing the samples of `lost`.
    pub fn ideal(n: usize, ts: f64, lost: LossSchedule) -> Self {
        Self::checked(&PlantSettings::default(), n, ts, lost)
    }

    /// [`Self::new`] with settings already checked (by the plant's
    /// construction).
    pub(crate) fn checked(settings: &PlantSettings, n: usize, ts: f64, lost: LossSchedule) -> Self {
        let delay = settings.delay_samples;
        let resolution = if settings.encoder_counts > 0 {
            2.0 * std::f64::consts::PI / settings.encoder_counts as f64
        } else {
            0.0
        };
        Self {
            n,
            ts,
            settings: settings.clone(),
            resolution,
            rng: Gauss {
                s: settings.seed.max(1).wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1,
                spare: None,
            },
            ring: vec![0.0; (delay + 1) * 2 * n],
            ring_next: 0,
            prev_qm: vec![0.0; n],
            measured_once: false,
            schedule: FaultSchedule::for_plant(&settings.faults, ts),
            fired: vec![false; settings.faults.len()],
            last_meas: vec![0.0; 2 * n],
            lost,
        }
    }

    /// Whether samples can be lost (the readings then differ from the
    /// plant's state and are worth recording).
    pub fn loses_samples(&self) -> bool {
        !self.lost.is_empty()
    }

    /// The reading of path sample `k` into `x` (2n): the measurement of
    /// `state` ([`Self::measure`]), or NaN when the sample is lost. `fresh`:
    /// measure (`false` reuses what `x` holds, e.g. the reading the run
    /// started from).
    pub fn read(
        &mut self,
        state: &JointState,
        k: usize,
        fresh: bool,
        x: &mut [f64],
    ) -> Result<(), PlantError> {
        if fresh {
            self.measure(state, x)?;
        }
        if self.lost.lost(k) {
            x.fill(f64::NAN);
        }
        Ok(())
    }

    /// The measurement of the true `state`: `x = [q, q̇]` (noise and encoder
    /// quantization applied; the velocity a backward difference of the
    /// measured positions with `velocity_from_encoder`; the encoder faults of
    /// its path sample; `delay_samples` periods old) written into `x` (2n).
    /// Call it once per control period: each call is one sample of the
    /// encoders. Allocation-free; `x` of another length is an error.
    pub fn measure(&mut self, state: &JointState, x: &mut [f64]) -> Result<(), PlantError> {
        let n = self.n;
        if state.q.len() != n || state.qd.len() != n {
            return Err(PlantError::MeasurementLength {
                expected: 2 * n,
                got: state.q.len() + state.qd.len(),
            });
        }
        if x.len() != 2 * n {
            return Err(PlantError::MeasurementLength {
                expected: 2 * n,
                got: x.len(),
            });
        }
        self.encode(state, x);
        if let Some(k) = state.path_sample {
            self.encoder_faults(k, x);
        }
        self.last_meas.copy_from_slice(&x[..2 * n]);
        self.prev_qm.copy_from_slice(&x[..n]);
        self.delay(x);
        self.measured_once = true;
        Ok(())
    }

    /// The encoders' reading of `state` into `x` (2n): noise, quantization
    /// to the resolution, and the velocity (a backward difference of the
    /// measured positions with `velocity_from_encoder`, else the true one
    /// with its noise).
    fn encode(&mut self, state: &JointState, x: &mut [f64]) {
        let (n, res) = (self.n, self.resolution);
        for i in 0..n {
            let mut q = state.q[i];
            if self.settings.position_noise > 0.0 {
                q += self.settings.position_noise * self.rng.next();
            }
            if res > 0.0 {
                q = (q / res).round() * res;
            }
            x[i] = q;
            let mut v = state.qd[i];
            if self.settings.velocity_from_encoder {
                // At the first sample the robot is at rest (it starts so).
                v = if self.measured_once && state.sample > 0 {
                    (q - self.prev_qm[i]) / self.ts
                } else {
                    0.0
                };
            } else if self.settings.velocity_noise > 0.0 {
                v += self.settings.velocity_noise * self.rng.next();
            }
            x[n + i] = v;
        }
    }

    /// The encoder faults covering path sample `k`, on the reading `x`: a
    /// glitch's offset once, a dropout's frozen last reading.
    fn encoder_faults(&mut self, k: usize, x: &mut [f64]) {
        let n = self.n;
        let faults = self.settings.faults.iter().zip(self.fired.iter_mut());
        for (index, (f, fired)) in faults.enumerate() {
            let (from, to) = self.schedule.range(index).unwrap_or((usize::MAX, 0));
            match *f {
                // Once, at the first measurement of its sample or after.
                Fault::EncoderGlitch {
                    joint, offset_rad, ..
                } if !*fired && k >= from => {
                    *fired = true;
                    x[joint - 1] += offset_rad;
                }
                Fault::EncoderDropout { joint, .. }
                    if self.measured_once && k >= from && k < to =>
                {
                    let i = joint - 1;
                    x[i] = self.last_meas[i];
                    x[n + i] = self.last_meas[n + i];
                }
                _ => {}
            }
        }
    }

    /// The delay line: `x` (2n) in, the reading `delay_samples` periods old
    /// out (the first reading fills the line: the robot starts at rest).
    fn delay(&mut self, x: &mut [f64]) {
        let d = self.settings.delay_samples;
        if d == 0 {
            return;
        }
        let w = 2 * self.n;
        if !self.measured_once {
            for slot in self.ring.chunks_exact_mut(w) {
                slot.copy_from_slice(&x[..w]);
            }
        }
        let at = self.ring_next;
        self.ring[at * w..(at + 1) * w].copy_from_slice(&x[..w]);
        self.ring_next = (at + 1) % (d + 1);
        // The oldest slot is the one written next.
        let old = self.ring_next;
        x[..w].copy_from_slice(&self.ring[old * w..(old + 1) * w]);
    }
}

#[cfg(test)]
mod tests {
    use super::super::plant::MAX_DELAY_SAMPLES;
    use super::*;
    use crate::robot::Robot;
    use crate::sim::Plant;

    /// Quantized positions, from a plain state (no plant): each position a
    /// whole number of encoder counts, and a reading of another length an
    /// error, not a panic.
    #[test]
    fn quantized_measurement_of_a_plain_state() {
        let s = PlantSettings {
            encoder_counts: 1000,
            position_noise: 1e-3,
            ..Default::default()
        };
        let mut sensor = Sensor::new(&s, 6, 0.01, LossSchedule::default()).unwrap();
        let (q, qd) = ([0.1, -0.2, 0.3, 0.0, 0.5, 1.0], [0.0; 6]);
        let state = JointState {
            q: &q,
            qd: &qd,
            sample: 0,
            path_sample: Some(0),
        };
        let mut x = [0.0; 12];
        sensor.measure(&state, &mut x).unwrap();
        let res = 2.0 * std::f64::consts::PI / 1000.0;
        for (v, t) in x[..6].iter().zip(&q) {
            assert!(((v / res).round() * res - v).abs() < 1e-12, "quantized");
            assert!((v - t).abs() < 0.01 + res, "near the truth");
        }
        let mut short = [0.0; 11];
        assert!(matches!(
            sensor.measure(&state, &mut short),
            Err(PlantError::MeasurementLength {
                expected: 12,
                got: 11
            })
        ));
        assert!(Sensor::new(
            &PlantSettings {
                encoder_counts: 1000,
                delay_samples: MAX_DELAY_SAMPLES + 1,
                ..Default::default()
            },
            6,
            0.01,
            LossSchedule::default()
        )
        .is_err());
    }

    #[test]
    fn delayed_measurement_and_encoder_velocity() {
        let q0 = [0.0, 0.3, 0.2, 0.0, 0.4, 0.0];
        let s = PlantSettings {
            delay_samples: 2,
            velocity_from_encoder: true,
            ..Default::default()
        };
        let mut p = Plant::with_period(Robot::irb140(), s.clone(), &q0, 0.01).unwrap();
        let mut sensor = Sensor::new(&s, 6, 0.01, LossSchedule::default()).unwrap();
        let mut truth: Vec<Vec<f64>> = Vec::new();
        let mut x = [0.0; 12];
        for k in 0..6usize {
            truth.push(p.q().to_vec());
            sensor.measure(&p.state(), &mut x).unwrap();
            // The position seen is that of max(k − 2, 0).
            let want = &truth[k.saturating_sub(2)];
            assert_eq!(&x[..6], &want[..], "k = {k}");
            // The velocity is the backward difference of those positions.
            let prev = &truth[k.saturating_sub(3)];
            for i in 0..6 {
                let v = if k >= 3 {
                    (want[i] - prev[i]) / 0.01
                } else {
                    0.0
                };
                assert!((x[6 + i] - v).abs() < 1e-12, "k = {k}, joint {i}");
            }
            p.advance(&[0.0; 6]).unwrap();
        }
        assert!(PlantSettings {
            delay_samples: MAX_DELAY_SAMPLES + 1,
            ..Default::default()
        }
        .validate(6)
        .is_err());
    }
}
