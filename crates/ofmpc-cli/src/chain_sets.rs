//! The robot options `--tip`, `--tcp`, `--tcp-rpy`, `--start-q` and `--tool-table` of `run`
//! and `reproduce`, as the scenario keys they stand for (`robot.tip`, `robot.tcp_mm`,
//! `robot.tcp_rpy_deg`, `robot.start_q`, `program.tool_table`): overrides applied before any
//! `--set`, so that every check of the scenario file applies to them.

use ofmpc_scenario::Override;

/// The options as given (each `None` when absent).
#[derive(Debug, Default, Clone, Copy)]
pub struct ChainFlags<'a> {
    /// `--tip LINK`.
    pub tip: Option<&'a str>,
    /// `--tcp X,Y,Z` (mm).
    pub tcp: Option<&'a str>,
    /// `--tcp-rpy R,P,Y` (degrees).
    pub tcp_rpy: Option<&'a str>,
    /// `--start-q Q1,…,Qn`.
    pub start_q: Option<&'a str>,
    /// `--tool-table FILE`.
    pub tool_table: Option<&'a std::path::Path>,
}

/// Comma-separated numbers of option `flag`; `len` values when given.
fn numbers(flag: &str, text: &str, len: Option<usize>) -> anyhow::Result<Vec<toml::Value>> {
    let mut v = Vec::new();
    for (i, part) in text.split(',').enumerate() {
        let x: f64 = part.trim().parse().map_err(|_| {
            anyhow::anyhow!(
                "{flag}: value {} {:?} is not a number (give comma-separated numbers, e.g. {flag} 0,-1.2,1.5)",
                i + 1,
                part.trim()
            )
        })?;
        if !x.is_finite() {
            anyhow::bail!("{flag}: value {} is not finite", i + 1);
        }
        v.push(toml::Value::Float(x));
    }
    if let Some(n) = len.filter(|n| *n != v.len()) {
        anyhow::bail!("{flag}: {} values given, {n} expected", v.len());
    }
    Ok(v)
}

/// The overrides the options stand for, in the order of [`ChainFlags`]'s fields.
pub fn chain_overrides(f: &ChainFlags) -> anyhow::Result<Vec<Override>> {
    let set = |key: &str, raw: &str, value: toml::Value| Override {
        key: key.into(),
        raw: raw.into(),
        value,
    };
    let mut v = Vec::new();
    if let Some(t) = f.tip {
        v.push(set("robot.tip", t, toml::Value::String(t.into())));
    }
    if let Some(t) = f.tcp {
        let xyz = numbers("--tcp", t, Some(3))?;
        v.push(set("robot.tcp_mm", t, toml::Value::Array(xyz)));
    }
    if let Some(t) = f.tcp_rpy {
        let rpy = numbers("--tcp-rpy", t, Some(3))?;
        v.push(set("robot.tcp_rpy_deg", t, toml::Value::Array(rpy)));
    }
    if let Some(q) = f.start_q {
        let q = numbers("--start-q", q, None)?;
        v.push(set(
            "robot.start_q",
            &format!("{q:?}"),
            toml::Value::Array(q),
        ));
    }
    if let Some(p) = f.tool_table {
        let abs = ofmpc_scenario::absolute(p).display().to_string();
        v.push(set(
            "program.tool_table",
            &abs,
            toml::Value::String(abs.clone()),
        ));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_flag_sets_its_key_and_bad_numbers_name_the_flag() {
        let f = ChainFlags {
            tip: Some("panda_hand"),
            tcp: Some("0,0,100"),
            start_q: Some("0.1,-0.2"),
            ..ChainFlags::default()
        };
        let keys: Vec<String> = chain_overrides(&f)
            .unwrap()
            .into_iter()
            .map(|o| format!("{}={}", o.key, o.value))
            .collect();
        assert_eq!(
            keys,
            [
                "robot.tip=\"panda_hand\"",
                "robot.tcp_mm=[0.0, 0.0, 100.0]",
                "robot.start_q=[0.1, -0.2]"
            ]
        );
        let bad = ChainFlags {
            tcp: Some("0,x,1"),
            ..ChainFlags::default()
        };
        let e = chain_overrides(&bad).unwrap_err().to_string();
        assert!(e.starts_with("--tcp: value 2 \"x\""), "{e}");
        let short = ChainFlags {
            tcp: Some("0,1"),
            ..ChainFlags::default()
        };
        assert!(chain_overrides(&short)
            .unwrap_err()
            .to_string()
            .contains("3 expected"));
    }
}
