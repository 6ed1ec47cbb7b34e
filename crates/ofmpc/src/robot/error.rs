//! Errors of the robot description.

use super::drives::DrivesError;
use thiserror::Error;

/// What can be wrong with a robot description or with the vectors given to it.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ModelError {
    /// A file could not be read.
    #[error("cannot read {path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// The operating system's message.
        message: String,
    },
    /// The URDF is not well-formed XML or lacks required elements.
    #[error("{file}invalid URDF: {message}")]
    Urdf {
        /// `"path: "` when known.
        file: String,
        /// The parser's message.
        message: String,
    },
    /// The URDF describes a structure this crate does not model.
    #[error("{file}{message}")]
    Structure {
        /// `"path: "` when known.
        file: String,
        /// What is wrong and what to do.
        message: String,
    },
    /// The drives file is malformed or does not fit the robot.
    #[error("{file}drives file: {error}")]
    Drives {
        /// `"path: "` when known.
        file: String,
        /// What is wrong.
        error: DrivesError,
    },
    /// The payload is not a physical rigid body.
    #[error("invalid payload: {0}")]
    InvalidPayload(String),
    /// No built-in robot of that name.
    #[error("unknown robot '{0}': use 'irb140' or the path of a .urdf file")]
    UnknownRobot(String),
    /// A vector has the wrong length.
    #[error("{what} has {got} values, the robot has {expected} joints: give one value per joint")]
    Dimension {
        /// Which vector.
        what: String,
        /// Number of joints.
        expected: usize,
        /// Number given.
        got: usize,
    },
    /// A vector holds NaN or infinity.
    #[error("{what}[{index}] (joint {}) is {value}: every value must be a finite number", index + 1)]
    NonFinite {
        /// Which vector.
        what: String,
        /// 0-based index.
        index: usize,
        /// The value.
        value: f64,
    },
}

impl ModelError {
    /// Names the file in URDF errors.
    pub(crate) fn in_file(self, path: &std::path::Path) -> Self {
        let file = format!("{}: ", path.display());
        match self {
            ModelError::Urdf { message, .. } => ModelError::Urdf { file, message },
            ModelError::Structure { message, .. } => ModelError::Structure { file, message },
            e => e,
        }
    }
    pub(crate) fn structure(message: impl Into<String>) -> Self {
        ModelError::Structure {
            file: String::new(),
            message: message.into(),
        }
    }
}

impl From<DrivesError> for ModelError {
    fn from(error: DrivesError) -> Self {
        ModelError::Drives {
            file: String::new(),
            error,
        }
    }
}
