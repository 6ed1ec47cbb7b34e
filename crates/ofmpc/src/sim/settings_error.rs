//! Why the loop's settings or a run's conditions cannot be used: a leaf
//! the settings types of the loop, its conditions and its faults share.

/// Why the hold, divergence threshold or steady window cannot be used.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LoopSettingsError {
    /// The hold after the path is negative or not finite.
    #[error("the hold after the path is {0} s: it must be a finite time ≥ 0 s")]
    HoldTime(f64),
    /// The divergence threshold is not a positive number.
    #[error("the divergence threshold is {0} rad: it must be a finite angle > 0")]
    DivergenceThreshold(f64),
    /// The steady window is not positive or longer than the hold.
    #[error(
        "the steady window is {value} s: it must be > 0 and not longer than the hold ({hold_s} s)"
    )]
    SteadyWindow {
        /// The window (s).
        value: f64,
        /// The hold (s).
        hold_s: f64,
    },
    /// The identification phase is negative, not finite or too long.
    #[error("the identification phase is {value} s: it must be a time from 0 to {max} s")]
    IdentificationTime {
        /// The phase (s).
        value: f64,
        /// The longest allowed (s).
        max: f64,
    },
    /// The settling at rest is negative, not finite or too long.
    #[error("the settling at rest is {value} s: it must be a time from 0 to {max} s")]
    SettleTime {
        /// The settling (s).
        value: f64,
        /// The longest allowed (s).
        max: f64,
    },
    /// The pick-up time is negative or not finite.
    #[error("the payload pick-up time is {0} s: it must be a finite time ≥ 0 s")]
    PickUpTime(f64),
    /// A time of an invalid (NaN) measurement is negative or not finite.
    #[error("invalid-measurement time {index} is {value} s: it must be a finite time ≥ 0 s")]
    FaultTime {
        /// 0-based position in the list.
        index: usize,
        /// The time (s).
        value: f64,
    },
    /// A measurement dropout interval is not `0 ≤ from < to`, finite.
    #[error(
        "dropout interval {index} is [{from}, {to}] s: it must be finite with 0 ≤ start < end"
    )]
    DropoutInterval {
        /// 0-based position in the list.
        index: usize,
        /// Start (s).
        from: f64,
        /// End (s).
        to: f64,
    },
    /// The safety limit on the joint error is not a positive angle.
    #[error("the joint error limit of the safe stop is {0} rad: it must be a finite angle > 0")]
    MaxJointError(f64),
}
