//! The robot handle: the built-in model or a URDF with a drives file.

use crate::ffi::*;
use crate::settings::chain;
use ofmpc::robot::Drives;
use ofmpc::Robot;
use std::ffi::c_char;
use std::path::Path;

/// A robot model (kinematics, dynamics, drives). Opaque.
pub struct ofmpc_robot(pub(crate) Robot);

fn model_failure(what: &str, e: &(dyn std::error::Error + 'static)) -> Failure {
    Failure::new(ofmpc_status::OFMPC_PARSE, format!("{what}: {}", chain(e)))
}

/// The built-in robot `name` ("irb140") into `*out`.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_robot_new_builtin(
    name: *const c_char,
    out: *mut *mut ofmpc_robot,
) -> ofmpc_status {
    boundary(|| {
        let name = unsafe { text(name, "name") }?;
        if out.is_null() {
            return Err(null("out"));
        }
        let robot = Robot::builtin(name).map_err(|e| {
            Failure::new(
                ofmpc_status::OFMPC_INVALID_ARG,
                format!("robot {name:?}: {}", chain(&e)),
            )
        })?;
        unsafe { give(out, ofmpc_robot(robot)) };
        Ok(())
    })
}

/// A robot from URDF text and, optionally, a drives file's TOML text
/// (armature, torque and speed limits, friction; NULL: the URDF's limits).
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_robot_new_urdf(
    urdf: *const c_char,
    drives_toml: *const c_char,
    out: *mut *mut ofmpc_robot,
) -> ofmpc_status {
    boundary(|| {
        let urdf = unsafe { text(urdf, "urdf") }?;
        let drives = unsafe { opt_text(drives_toml, "drives_toml") }?;
        if out.is_null() {
            return Err(null("out"));
        }
        let mut robot = Robot::from_urdf_str(urdf).map_err(|e| model_failure("URDF", &e))?;
        robot
            .require_inertials()
            .map_err(|e| Failure::new(ofmpc_status::OFMPC_BUILD, chain(&e)))?;
        if let Some(d) = drives {
            let d = Drives::from_toml_str(d).map_err(|e| model_failure("drives TOML", &e))?;
            robot
                .apply_drives(&d)
                .map_err(|e| model_failure("drives TOML", &e))?;
        }
        unsafe { give(out, ofmpc_robot(robot)) };
        Ok(())
    })
}

/// A robot from a URDF file and, optionally, a drives file (NULL: none);
/// paths are UTF-8, relative to the working directory.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn ofmpc_robot_new_urdf_file(
    urdf_path: *const c_char,
    drives_path: *const c_char,
    out: *mut *mut ofmpc_robot,
) -> ofmpc_status {
    boundary(|| {
        let urdf = unsafe { text(urdf_path, "urdf_path") }?;
        let drives = unsafe { opt_text(drives_path, "drives_path") }?;
        if out.is_null() {
            return Err(null("out"));
        }
        let mut robot =
            Robot::from_urdf_file(Path::new(urdf)).map_err(|e| model_failure(urdf, &e))?;
        robot.require_inertials().map_err(|e| {
            Failure::new(ofmpc_status::OFMPC_BUILD, format!("{urdf}: {}", chain(&e)))
        })?;
        if let Some(d) = drives {
            let drives = Drives::from_file(Path::new(d)).map_err(|e| model_failure(d, &e))?;
            robot
                .apply_drives(&drives)
                .map_err(|e| model_failure(d, &e))?;
        }
        unsafe { give(out, ofmpc_robot(robot)) };
        Ok(())
    })
}

/// Number of joints (0 for NULL).
#[no_mangle]
pub unsafe extern "C" fn ofmpc_robot_dof(robot: *const ofmpc_robot) -> usize {
    query(0, || unsafe { robot.as_ref() }.map(|r| r.0.dof()))
}

/// Frees a robot (NULL: nothing). Objects built from it do not borrow it.
#[no_mangle]
pub unsafe extern "C" fn ofmpc_robot_free(robot: *mut ofmpc_robot) {
    let _ = boundary(|| {
        unsafe { take(robot) };
        Ok(())
    });
}
