//! Drive data of each joint: reflected rotor inertia ("armature"), torque and
//! speed limits, from a TOML file such as the IRB 140's `drives.toml`:
//!
//! ```toml
//! [joints.joint_1]
//! armature_kgm2 = 1.0      # added to H[0][0]
//! max_torque_nm = 290.0    # symmetric peak torque
//! max_speed_rad_s = 3.49   # symmetric speed limit
//! coulomb_nm = 1.0         # Coulomb friction estimate (friction compensation)
//! viscous_nms = 0.5        # viscous friction estimate (friction compensation)
//! max_accel_rad_s2 = 12.0  # symmetric acceleration limit (motion planning)
//! ```
//!
//! Keys ending in `_source` and a `[meta]` table are documentation and ignored.

use super::error::{DrivesError, ModelError};
use serde::Deserialize;
use std::collections::BTreeMap;

const JOINT_KEYS: &str =
    "armature_kgm2, max_torque_nm, max_speed_rad_s, max_accel_rad_s2, coulomb_nm, viscous_nms (or a *_source note)";

/// The drive data of one joint; absent values leave the URDF's in place.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
pub struct DriveData {
    /// Reflected rotor inertia J_motor·G² on the joint side (kg·m²).
    pub armature_kgm2: Option<f64>,
    /// Peak joint torque, symmetric (N·m).
    pub max_torque_nm: Option<f64>,
    /// Maximum joint speed, symmetric (rad/s).
    pub max_speed_rad_s: Option<f64>,
    /// Coulomb friction estimate (N·m), used by friction compensation.
    pub coulomb_nm: Option<f64>,
    /// Viscous friction estimate (N·m·s/rad), used by friction compensation.
    pub viscous_nms: Option<f64>,
    /// Maximum joint acceleration, symmetric (rad/s²), for the motion planner.
    pub max_accel_rad_s2: Option<f64>,
    #[serde(flatten)]
    other: BTreeMap<String, toml::Value>,
}

/// A drives file: joint name → drive data.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Drives {
    /// Drive data by joint name.
    pub joints: BTreeMap<String, DriveData>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    joints: BTreeMap<String, DriveData>,
    #[serde(default)]
    #[allow(dead_code)]
    meta: Option<toml::Value>,
}

impl Drives {
    /// Parses a drives file; errors name the line and column (TOML syntax), or
    /// the joint and key (values).
    pub fn from_toml_str(text: &str) -> Result<Self, ModelError> {
        // Unknown top-level tables and keys first, by name (serde's message
        // would list them less clearly).
        let value: toml::Table =
            toml::from_str(text).map_err(|e| DrivesError::Syntax(e.to_string()))?;
        if let Some(key) = value.keys().find(|k| *k != "joints" && *k != "meta") {
            return Err(DrivesError::UnknownKey {
                what: if value[key].is_table() {
                    "table"
                } else {
                    "key"
                },
                key: key.clone(),
                joint: None,
                expected: "[joints.<joint name>] tables and an optional [meta] table",
            }
            .into());
        }
        let f: File = toml::from_str(text).map_err(|e| DrivesError::Syntax(e.to_string()))?;
        if f.joints.is_empty() {
            return Err(DrivesError::Empty.into());
        }
        for (name, d) in &f.joints {
            if let Some(key) = d.other.keys().find(|k| !k.ends_with("_source")) {
                return Err(DrivesError::UnknownKey {
                    what: "key",
                    key: key.clone(),
                    joint: Some(name.clone()),
                    expected: JOINT_KEYS,
                }
                .into());
            }
            for (key, v) in [
                ("armature_kgm2", d.armature_kgm2),
                ("max_torque_nm", d.max_torque_nm),
                ("max_speed_rad_s", d.max_speed_rad_s),
                ("coulomb_nm", d.coulomb_nm),
                ("viscous_nms", d.viscous_nms),
                ("max_accel_rad_s2", d.max_accel_rad_s2),
            ] {
                let nonneg = matches!(key, "armature_kgm2" | "coulomb_nm" | "viscous_nms");
                if let Some(v) = v {
                    let ok = v.is_finite() && if nonneg { v >= 0.0 } else { v > 0.0 };
                    if !ok {
                        return Err(DrivesError::Value {
                            joint: name.clone(),
                            key,
                            value: v,
                            requirement: if nonneg { "≥ 0" } else { "> 0" },
                        }
                        .into());
                    }
                }
            }
        }
        Ok(Self { joints: f.joints })
    }

    /// Reads a drives file.
    pub fn from_file(path: &std::path::Path) -> Result<Self, ModelError> {
        let text =
            super::read::read_text_limited(path, super::read::MAX_DRIVES_BYTES, "a drives file")?;
        Self::from_toml_str(&text).map_err(|e| match e {
            ModelError::Drives { error, .. } => ModelError::Drives {
                file: format!("{}: ", path.display()),
                error,
            },
            e => e,
        })
    }
}
