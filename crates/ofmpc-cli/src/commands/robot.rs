//! Robot selection shared by the commands: `--robot`, `--drives`, `--payload`.

use crate::args::{ChainArgs, RobotArgs};
use anyhow::bail;
use ofmpc::robot::{Payload, Robot};
use ofmpc_scenario::RobotSection;

/// Loads the robot named by `--robot` (built-in name or URDF path), applies
/// `--drives`, `--tip`, `--tcp`, `--tcp-rpy`, `--start-q` and a point-mass payload at the
/// flange.
pub fn load_robot(args: &RobotArgs, payload_kg: f64) -> anyhow::Result<Robot> {
    let mut robot = load_model_with(&args.robot, args.drives.as_deref(), &args.chain)?;
    if !payload_kg.is_finite() || payload_kg < 0.0 {
        bail!("--payload {payload_kg}: the payload must be a finite mass ≥ 0 kg");
    }
    if payload_kg > 0.0 {
        robot.set_payload(Some(Payload::point_mass(payload_kg)))?;
    }
    Ok(robot)
}

impl ChainArgs {
    /// Writes `--tip`, `--tcp`, `--tcp-rpy` and `--start-q` into a `[robot]` section.
    pub fn apply(&self, section: &mut RobotSection) -> anyhow::Result<()> {
        let three = |name: &str, text: &str, what: &str| -> anyhow::Result<[f64; 3]> {
            let v = parse_fixed(name, text, 3, what, "0,0,120")?;
            Ok([v[0], v[1], v[2]])
        };
        if let Some(t) = &self.tip {
            section.tip = Some(t.clone());
        }
        if let Some(t) = &self.tcp {
            section.tcp_mm = Some(three("--tcp", t, "x,y,z of the tool centre point in mm")?);
        }
        if let Some(t) = &self.tcp_rpy {
            section.tcp_rpy_deg = Some(three(
                "--tcp-rpy",
                t,
                "roll,pitch,yaw of the tool in degrees",
            )?);
        }
        if let Some(t) = &self.start_q {
            section.start_q = Some(parse_vector("--start-q", t, None)?);
        }
        Ok(())
    }
}

/// Loads a robot by name or URDF path with an optional drives file and the chain options,
/// printing its warnings. A `--start-q` that does not fit is named as such.
pub fn load_model_with(
    model: &str,
    drives: Option<&std::path::Path>,
    chain: &ChainArgs,
) -> anyhow::Result<Robot> {
    let mut section = RobotSection {
        model: model.to_string(),
        drives: drives.map(|d| d.to_path_buf()),
        ..RobotSection::default()
    };
    chain.apply(&mut section)?;
    let start_q = section.start_q.take();
    let (mut robot, warnings) = ofmpc_scenario::load_robot_section(&section)?;
    for w in &warnings {
        crate::output::console::warn(w);
    }
    if let Some(q) = start_q {
        robot
            .set_start_q(&q)
            .map_err(|e| anyhow::anyhow!("--start-q: {e}"))?;
    }
    Ok(robot)
}

/// Parses a comma-separated vector of numbers for option `name`, checking its
/// length against `n` when given.
pub fn parse_vector(name: &str, text: &str, n: Option<usize>) -> anyhow::Result<Vec<f64>> {
    let mut v = Vec::new();
    for (i, part) in text.split(',').enumerate() {
        let p = part.trim();
        let x: f64 = p.parse().map_err(|_| {
            anyhow::anyhow!(
                "{name}: value {} '{p}' is not a number (expected e.g. {name} 0.1,-0.2,0.3)",
                i + 1
            )
        })?;
        if !x.is_finite() {
            bail!("{name}: value {} is {x}: every value must be finite", i + 1);
        }
        v.push(x);
    }
    if let Some(n) = n {
        if v.len() != n {
            bail!("{name} has {} values but the robot has {n} joints: give one value per joint, comma-separated", v.len());
        }
    }
    Ok(v)
}

/// Parses a comma-separated vector of exactly `n` numbers for option `name` whose values are
/// `what` (e.g. "x,y,z of the work offset in mm"); `example` is a valid value for the message.
pub fn parse_fixed(
    name: &str,
    text: &str,
    n: usize,
    what: &str,
    example: &str,
) -> anyhow::Result<Vec<f64>> {
    let v = parse_vector(name, text, None)?;
    if v.len() != n {
        bail!(
            "{name} has {} value{} but needs {n}: {what}, comma-separated (e.g. {name} {example})",
            v.len(),
            if v.len() == 1 { "" } else { "s" }
        );
    }
    Ok(v)
}
