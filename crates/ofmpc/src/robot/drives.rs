//! Drive data of each joint: reflected rotor inertia ("armature"), torque and
//! speed limits, from a TOML file such as the IRB 140's `drives.toml`:
//!
//! ```toml
//! [joints.joint_1]
//! armature_kgm2 = 1.0      # added to H[0][0]
//! max_torque_nm = 290.0    # symmetric peak torque
//! max_speed_rad_s = 3.49   # symmetric speed limit
//! max_accel_rad_s2 = 12.0  # symmetric acceleration limit (motion planning)
//! ```
//!
//! Keys ending in `_source` and a `[meta]` table are documentation and ignored.

use super::ModelError;
use serde::Deserialize;
use std::collections::BTreeMap;

/// The drive data of one joint; absent values leave the URDF's in place.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
pub struct DriveData {
    /// Reflected rotor inertia J_motor·G² on the joint side (kg·m²).
    pub armature_kgm2: Option<f64>,
    /// Peak joint torque, symmetric (N·m).
    pub max_torque_nm: Option<f64>,
    /// Maximum joint speed, symmetric (rad/s).
    pub max_speed_rad_s: Option<f64>,
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
        let f: File = toml::from_str(text).map_err(|e| ModelError::Drives(e.to_string()))?;
        for (name, d) in &f.joints {
            for key in d.other.keys() {
                if !key.ends_with("_source") {
                    return Err(ModelError::Drives(format!(
                        "[joints.{name}]: unknown key '{key}': expected armature_kgm2, max_torque_nm, max_speed_rad_s, max_accel_rad_s2 (or a *_source note)"
                    )));
                }
            }
            for (key, v) in [
                ("armature_kgm2", d.armature_kgm2),
                ("max_torque_nm", d.max_torque_nm),
                ("max_speed_rad_s", d.max_speed_rad_s),
                ("max_accel_rad_s2", d.max_accel_rad_s2),
            ] {
                if let Some(v) = v {
                    let ok = v.is_finite()
                        && if key == "armature_kgm2" {
                            v >= 0.0
                        } else {
                            v > 0.0
                        };
                    if !ok {
                        return Err(ModelError::Drives(format!(
                            "[joints.{name}] {key} = {v}: must be a finite number {}",
                            if key == "armature_kgm2" {
                                "≥ 0"
                            } else {
                                "> 0"
                            }
                        )));
                    }
                }
            }
        }
        Ok(Self { joints: f.joints })
    }

    /// Reads a drives file.
    pub fn from_file(path: &std::path::Path) -> Result<Self, ModelError> {
        let text = std::fs::read_to_string(path).map_err(|e| ModelError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        Self::from_toml_str(&text).map_err(|e| match e {
            ModelError::Drives(m) => ModelError::Drives(format!("{}: {m}", path.display())),
            e => e,
        })
    }
}
