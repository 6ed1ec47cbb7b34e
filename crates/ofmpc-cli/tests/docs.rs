//! The user guide cannot drift from the code or break its links:
//! - every relative link and `#anchor` in README.md and docs/**/*.md resolves;
//! - every scenario key the code accepts is documented in docs/guide/reference/scenario.md, and
//!   every key documented there is accepted. The keys are traced from the scenario file's types:
//!   every section denies unknown keys, so serde's message for a probe key ("unknown field
//!   `__probe__`, expected one of `a`, `b`") lists a section's fields; a probe table as a key's
//!   value (through `--set`'s machinery, `ofmpc_scenario::Override`) tells a section or an
//!   array of tables from a value;
//! - every option of every command is in docs/guide/reference/commands.md, under the command's
//!   heading (`## ofmpc run`).

use clap::CommandFactory;
use ofmpc_scenario::{Override, ScenarioError, ScenarioFile};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

// ---------------------------------------------------------------- scenario keys

/// The message of the override `key=value` applied to the default scenario, if it fails.
fn probe(key: &str, value: &str) -> Option<String> {
    let o: Override = format!("{key}={value}").parse().expect("probe syntax");
    match ScenarioFile::default().with_overrides(&[o]) {
        Ok(_) => None,
        Err(ScenarioError::Override { message, .. }) => Some(message),
        Err(e) => Some(e.to_string()),
    }
}

/// The field names in serde's "unknown field `__probe__`, expected one of `a`, `b`" message.
fn fields(message: &str) -> Option<Vec<String>> {
    if !message.contains("unknown field `__probe__`") {
        return None;
    }
    if message.contains("there are no fields") {
        return Some(Vec::new());
    }
    let (_, list) = message.split_once("expected")?;
    Some(
        list.split('`')
            .skip(1)
            .step_by(2)
            .map(String::from)
            .collect(),
    )
}

/// Adds the keys below the section `key` (whose fields are `names`) to `out`, recursively.
fn trace(key: &str, names: Vec<String>, out: &mut BTreeSet<String>) {
    for name in names {
        let full = if key.is_empty() {
            name
        } else {
            format!("{key}.{name}")
        };
        out.insert(full.clone());
        if let Some(sub) = probe(&full, "{__probe__ = 0}").as_deref().and_then(fields) {
            trace(&full, sub, out);
        } else if let Some(sub) = probe(&full, "[{__probe__ = 0}]")
            .as_deref()
            .and_then(fields)
        {
            for f in sub {
                out.insert(format!("{full}[].{f}"));
            }
        }
    }
}

/// Every key of the scenario file, traced from its types: sections (`mpc`) and their keys
/// (`mpc.horizon`); fields of an array of tables as `key[].field`.
fn scenario_keys() -> BTreeSet<String> {
    let top = probe("__probe__", "0").expect("an unknown top-level key is refused");
    let names = fields(&top).unwrap_or_else(|| panic!("no key list in: {top}"));
    let mut keys = BTreeSet::new();
    trace("", names, &mut keys);
    keys
}

/// The backquoted words of `text` outside code blocks.
fn quoted(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut fence = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fence = !fence;
            continue;
        }
        if !fence {
            out.extend(line.split('`').skip(1).step_by(2).map(String::from));
        }
    }
    out
}

#[test]
fn every_scenario_key_is_documented_and_every_documented_key_exists() {
    let keys = scenario_keys();
    assert!(
        keys.contains("mpc.horizon") && keys.contains("robot.model"),
        "{keys:?}"
    );
    let page_path = root().join("docs/guide/reference/scenario.md");
    let documented = quoted(&read(&page_path));
    let missing: Vec<&String> = keys.iter().filter(|k| !documented.contains(*k)).collect();
    assert!(
        missing.is_empty(),
        "{} does not document these scenario keys (write each as `key` in backquotes): {missing:?}",
        page_path.display()
    );
    // A documented dotted key below a known section must exist (array fields, `key[].f`,
    // may name variants the tracer cannot see).
    let sections: BTreeSet<&str> = keys
        .iter()
        .filter(|k| !k.contains('.'))
        .map(String::as_str)
        .collect();
    let stale: Vec<&String> = documented
        .iter()
        .filter(|d| {
            let first = d.split('.').next().unwrap_or("");
            d.contains('.')
                && !d.contains("[]")
                && !d.contains(' ')
                && !d.contains('=')
                && sections.contains(first)
                && !keys.contains(*d)
        })
        .collect();
    assert!(
        stale.is_empty(),
        "{} documents keys the scenario file does not accept: {stale:?}",
        page_path.display()
    );
}

// ---------------------------------------------------------------- commands

/// `(command path, long options)` of every leaf command, e.g. `("ofmpc run", ["payload", ...])`.
fn commands(cmd: &clap::Command, path: &str, out: &mut Vec<(String, Vec<String>)>) {
    let path = format!("{path} {}", cmd.get_name()).trim().to_string();
    if cmd.has_subcommands() {
        for sub in cmd.get_subcommands().filter(|s| s.get_name() != "help") {
            commands(sub, &path, out);
        }
    } else {
        let longs = cmd
            .get_arguments()
            .filter_map(|a| a.get_long())
            .filter(|l| *l != "help" && *l != "version")
            .map(String::from)
            .collect();
        out.push((path, longs));
    }
}

#[test]
fn every_command_and_option_is_in_the_reference() {
    let page_path = root().join("docs/guide/reference/commands.md");
    let page = read(&page_path);
    let mut all = Vec::new();
    commands(&ofmpc_cli::cli::Cli::command(), "", &mut all);
    let mut missing = Vec::new();
    for (cmd, longs) in all {
        let heading = format!("\n## {cmd}\n");
        let Some(start) = page.find(&heading) else {
            missing.push(format!("section `## {cmd}`"));
            continue;
        };
        let rest = &page[start + heading.len()..];
        let section = &rest[..rest.find("\n## ").unwrap_or(rest.len())];
        for l in longs {
            if !section.contains(&format!("`--{l}")) && !section.contains(&format!("--{l} ")) {
                missing.push(format!("{cmd} --{l}"));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "{} lacks: {missing:?}",
        page_path.display()
    );
}

// ---------------------------------------------------------------- links

/// Every Markdown file of the guide and the README, with the folder its links are relative to.
fn markdown_files() -> Vec<(PathBuf, PathBuf)> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "md") {
                out.push(p);
            }
        }
    }
    let root = root();
    let mut files = vec![root.join("README.md")];
    walk(&root.join("docs"), &mut files);
    files
        .into_iter()
        .map(|f| {
            let base = f.parent().unwrap().to_path_buf();
            (f, base)
        })
        .collect()
}

/// Lines outside fenced code blocks, inline code removed.
fn prose(text: &str) -> Vec<String> {
    let mut fence = false;
    let mut out = Vec::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fence = !fence;
            continue;
        }
        if !fence {
            let kept: String = line.split('`').step_by(2).collect::<Vec<_>>().join("");
            out.push(kept);
        }
    }
    out
}

/// The link targets of a Markdown text: `[text](target)` and `![alt](target)`.
fn links(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for line in prose(text) {
        let mut rest = line.as_str();
        while let Some(i) = rest.find("](") {
            let after = &rest[i + 2..];
            let end = after.find(')').unwrap_or(after.len());
            out.push(after[..end].trim().to_string());
            rest = &after[end..];
        }
    }
    out
}

/// GitHub's anchors of a Markdown text's headings: lower case, letters, digits, `-` and `_`
/// kept, spaces to `-`, the rest dropped; a repeated anchor gets `-1`, `-2`, ….
fn anchors(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut fence = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fence = !fence;
            continue;
        }
        let Some(h) = line.strip_prefix('#') else {
            continue;
        };
        if fence {
            continue;
        }
        let title = h.trim_start_matches('#').trim();
        let a: String = title
            .to_lowercase()
            .chars()
            .filter_map(|c| match c {
                ' ' => Some('-'),
                c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
                _ => None,
            })
            .collect();
        let mut anchor = a.clone();
        let mut n = 0;
        while out.contains(&anchor) {
            n += 1;
            anchor = format!("{a}-{n}");
        }
        out.insert(anchor);
    }
    out
}

#[test]
fn every_relative_link_and_anchor_resolves() {
    let mut broken = Vec::new();
    let mut checked = 0;
    for (file, base) in markdown_files() {
        let text = read(&file);
        for target in links(&text) {
            if target.contains("://") || target.starts_with("mailto:") || target.is_empty() {
                continue;
            }
            checked += 1;
            let (path, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let dest = if path.is_empty() {
                file.clone()
            } else {
                base.join(path)
            };
            if !dest.exists() {
                broken.push(format!(
                    "{}: {target} (no {})",
                    file.display(),
                    dest.display()
                ));
                continue;
            }
            if let Some(a) = anchor {
                let dest_text = read(&dest);
                if !anchors(&dest_text).contains(a) {
                    broken.push(format!("{}: {target} (no heading #{a})", file.display()));
                }
            }
        }
    }
    assert!(
        checked > 20,
        "only {checked} links found: the scanner is broken"
    );
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn the_anchor_rule_is_githubs() {
    let a = anchors("# Getting started\n## What the results mean\n## A, b: c (d)\n```\n# not\n```\n## A, b: c (d)\n## Über\n");
    for want in [
        "getting-started",
        "what-the-results-mean",
        "a-b-c-d",
        "a-b-c-d-1",
        "über",
    ] {
        assert!(a.contains(want), "{want} in {a:?}");
    }
    assert!(!a.contains("not"));
    assert_eq!(
        links("see [x](a.md#b) and `[no](c.md)` ![i](d.png)"),
        ["a.md#b", "d.png"]
    );
}

/// The key tracer's output is what the documentation check above relies on: TOML key spellings
/// only, and every dotted key below a section it also found (`a.b` below `a`, `a[].b` below `a`).
#[test]
fn traced_scenario_keys_are_well_formed_and_nested() {
    let keys = scenario_keys();
    assert!(keys.len() > 20, "{keys:?}");
    for k in &keys {
        assert!(
            k.chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || "_.[]-".contains(c)),
            "{k:?} is not a TOML key path"
        );
        if let Some((parent, _)) = k.rsplit_once('.') {
            let parent = parent.strip_suffix("[]").unwrap_or(parent);
            assert!(
                keys.contains(parent),
                "{k:?} without its section {parent:?}"
            );
        }
    }
}

// ---------------------------------------------------------------- templates

/// `ofmpc init robot`'s files and the templates the guide points to load as what they claim:
/// the drives skeleton applies to its robot (a table per moving joint, nothing left unset),
/// the scenarios read as scenarios.
#[test]
fn the_robot_templates_load() {
    let root = root();
    let urdf = root.join("crates/ofmpc/tests/data/arm6.urdf");
    let mut robot = ofmpc::robot::Robot::from_urdf_file(&urdf).unwrap();
    let text = ofmpc_cli::commands::init::drives_skeleton(&robot, &urdf);
    let drives =
        ofmpc::robot::Drives::from_toml_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    let unset = robot.apply_drives(&drives).unwrap();
    assert!(unset.is_empty(), "joints without a table: {unset:?}");

    let dir = tempfile::tempdir().unwrap();
    let scenario = dir.path().join("scenario.toml");
    std::fs::write(
        &scenario,
        ofmpc_cli::commands::init::scenario_skeleton("arm6.urdf"),
    )
    .unwrap();
    let f = ScenarioFile::from_file(&scenario).unwrap();
    assert!(f.robot.model.ends_with("arm6.urdf") && f.robot.drives.is_some());

    ScenarioFile::from_file(&root.join("examples/templates/scenario.toml")).unwrap();
    ofmpc::robot::Drives::from_toml_str(&read(&root.join("examples/templates/drives.toml")))
        .unwrap();
}
