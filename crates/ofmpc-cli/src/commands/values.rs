//! Option values the commands share that name no robot: controller lists (`--controllers`)
//! and tool tables (`--tool-table`). A leaf of `commands/`.

/// Parses a comma-separated list of controller names for option `name`.
pub(crate) fn parse_controllers(
    name: &str,
    text: &str,
) -> anyhow::Result<Vec<ofmpc::control::ControllerKind>> {
    let mut v = Vec::new();
    for (i, part) in text.split(',').enumerate() {
        if let Some(kinds) = ofmpc_scenario::expand_shorthand(part) {
            for k in kinds {
                if !v.contains(k) {
                    v.push(*k);
                }
            }
            continue;
        }
        let k: ofmpc::control::ControllerKind = part
            .trim()
            .parse()
            .map_err(|e| anyhow::anyhow!("{name}: value {} '{}': {e}", i + 1, part.trim()))?;
        if !v.contains(&k) {
            v.push(k);
        }
    }
    Ok(v)
}

/// The tool table of `--tool-table FILE`, if given.
pub(crate) fn read_tool_table(
    path: Option<&std::path::Path>,
) -> anyhow::Result<Option<ofmpc::gcode::ToolTable>> {
    Ok(path
        .map(|p| ofmpc_scenario::read_tool_table(p, "--tool-table"))
        .transpose()?)
}
