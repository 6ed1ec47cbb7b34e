//! The library's module layering (issue #23), checked on the source text.
//!
//! Every `.rs` file under `src/` belongs to one top-level module (`src/<m>.rs` or
//! `src/<m>/…`). A reference from module `a` to module `b ≠ a` is a path `crate::b…`, a name
//! `b` inside a `use crate::{…}` group, or a `super::` chain that climbs out of `a` to the
//! crate root and down into `b`. Comments (so doc links) and string literals do not count.
//!
//! Checked: (a) the references between top-level modules have no cycle; (b) every module
//! sits on a layer of [`LAYERS`] (bottom first) and references only modules on lower layers
//! (modules on one layer are independent of each other). A failure names the file, the line
//! and the reference.
//!
//! Also checked here: what the crate embeds with `include_str!` / `include_bytes!` lies inside
//! the crate (so that `cargo package` works), and the embedded copy of the paper's program is
//! byte-identical to the one in `examples/` that users and the README use.

use ofmpc_policy::source::{code_only, group_names, ident_at, rust_files};
use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// The layers, bottom first: a module may reference only modules on lower layers.
///
/// - `linalg`: dense kernels (Cholesky, RK4, dot), the pseudo-random generator; `input`:
///   opening input files without blocking, bounded XML nesting, short quotes;
/// - `spatial` (6-D vectors, transforms), `geometry` (path segments, planes, arcs),
///   `ik` (inverse kinematics against a `ForwardKinematics` trait);
/// - `robot` (model, URDF, drives), `gcode` (program text → moves of geometry);
/// - `dynamics` (RNEA, CRBA, forward dynamics of a robot);
/// - `ident` (payload identification), `motion` (blending, timing, joint reference);
/// - `control` (the MPC controllers);
/// - `sim` (plant, closed loop, metrics), `analysis` (closed-loop stability).
const LAYERS: &[&[&str]] = &[
    &["linalg", "input"],
    &["spatial", "geometry", "ik"],
    &["robot", "gcode"],
    &["dynamics"],
    &["ident", "motion"],
    &["control"],
    &["sim", "analysis"],
];

fn src_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The top-level modules `lib.rs` declares.
fn top_level_modules() -> BTreeSet<String> {
    let lib = code_only(&fs::read_to_string(src_dir().join("lib.rs")).unwrap());
    lib.lines()
        .filter_map(|l| {
            let l = l.trim();
            let l = l
                .strip_prefix("pub(crate) ")
                .or_else(|| l.strip_prefix("pub "))
                .unwrap_or(l);
            let name = l.strip_prefix("mod ")?.strip_suffix(';')?;
            Some(name.trim().to_string())
        })
        .collect()
}

/// A reference from one top-level module to another.
#[derive(Debug, Clone)]
struct Reference {
    from: String,
    to: String,
    file: String,
    line: usize,
    text: String,
}

/// Every reference from the module of `file` to another top-level module.
fn references(file: &Path, modules: &BTreeSet<String>) -> Vec<Reference> {
    let rel = file.strip_prefix(src_dir()).unwrap();
    let parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    if parts == ["lib.rs"] {
        return Vec::new();
    }
    let from = parts[0].trim_end_matches(".rs").to_string();
    // Depth of the file's module below the crate root (src/m.rs, src/m/mod.rs: 1).
    let depth = if parts.last().unwrap() == "mod.rs" {
        parts.len() - 1
    } else {
        parts.len()
    };
    let original = fs::read_to_string(file).unwrap();
    let code = code_only(&original);
    let text = |at: usize| {
        let line = code[..at].matches('\n').count();
        (
            line + 1,
            original.lines().nth(line).unwrap_or("").trim().to_string(),
        )
    };
    let mut out = Vec::new();
    let mut add = |to: &str, at: usize| {
        if to != from && modules.contains(to) {
            let (line, text) = text(at);
            out.push(Reference {
                from: from.clone(),
                to: to.to_string(),
                file: format!("src/{}", rel.display()),
                line,
                text,
            });
        }
    };
    let word_start = |at: usize| {
        at == 0 || {
            let p = code.as_bytes()[at - 1];
            !(p.is_ascii_alphanumeric() || p == b'_' || p == b'$')
        }
    };
    for (at, _) in code.match_indices("crate::") {
        if !word_start(at) {
            continue;
        }
        let rest = &code[at + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            for name in group_names(group) {
                add(&name, at);
            }
        } else {
            add(ident_at(rest), at);
        }
    }
    // super:: chains that climb to the crate root (inline modules ignored: they only make
    // a chain stay lower).
    for (at, _) in code.match_indices("super::") {
        if !word_start(at) {
            continue;
        }
        let mut rest = &code[at..];
        let mut ups = 0;
        while let Some(r) = rest.strip_prefix("super::") {
            ups += 1;
            rest = r.trim_start();
        }
        if ups >= depth {
            if let Some(group) = rest.strip_prefix('{') {
                for name in group_names(group) {
                    add(&name, at);
                }
            } else {
                add(ident_at(rest), at);
            }
        }
    }
    // Skip the tail of a chain already counted (super::super:: found twice).
    out.sort_by(|a, b| (a.line, &a.to).cmp(&(b.line, &b.to)));
    out.dedup_by(|a, b| a.line == b.line && a.to == b.to);
    out
}

fn all_references() -> (BTreeSet<String>, Vec<Reference>) {
    let modules = top_level_modules();
    let refs = rust_files(&src_dir())
        .iter()
        .flat_map(|f| references(f, &modules))
        .collect();
    (modules, refs)
}

fn describe(r: &Reference) -> String {
    format!(
        "{}:{}: `{}` references `{}`: {}",
        r.file, r.line, r.from, r.to, r.text
    )
}

#[test]
fn top_level_modules_have_no_cycle() {
    let (modules, refs) = all_references();
    let mut edges: BTreeMap<&str, BTreeMap<&str, &Reference>> = BTreeMap::new();
    for r in &refs {
        edges
            .entry(r.from.as_str())
            .or_default()
            .entry(r.to.as_str())
            .or_insert(r);
    }
    // Depth-first search; a back edge closes a cycle.
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        New,
        Open,
        Done,
    }
    let mut mark: BTreeMap<&str, Mark> = modules.iter().map(|m| (m.as_str(), Mark::New)).collect();
    let mut cycles = Vec::new();
    fn visit<'a>(
        m: &'a str,
        edges: &BTreeMap<&'a str, BTreeMap<&'a str, &'a Reference>>,
        mark: &mut BTreeMap<&'a str, Mark>,
        path: &mut Vec<&'a Reference>,
        cycles: &mut Vec<String>,
    ) {
        mark.insert(m, Mark::Open);
        for (&to, &r) in edges.get(m).into_iter().flatten() {
            path.push(r);
            match mark.get(to).copied().unwrap_or(Mark::Done) {
                Mark::New => visit(to, edges, mark, path, cycles),
                Mark::Open => {
                    let start = path.iter().position(|r| r.from == to).unwrap();
                    let chain: Vec<String> = path[start..].iter().map(|r| describe(r)).collect();
                    cycles.push(chain.join("\n    then "));
                }
                Mark::Done => {}
            }
            path.pop();
        }
        mark.insert(m, Mark::Done);
    }
    for m in &modules {
        if mark[m.as_str()] == Mark::New {
            visit(m, &edges, &mut mark, &mut Vec::new(), &mut cycles);
        }
    }
    assert!(
        cycles.is_empty(),
        "import cycles among the top-level modules:\n  {}",
        cycles.join("\n  ")
    );
}

#[test]
fn modules_reference_only_lower_layers() {
    let (modules, refs) = all_references();
    let layer: BTreeMap<&str, usize> = LAYERS
        .iter()
        .enumerate()
        .flat_map(|(i, l)| l.iter().map(move |m| (*m, i)))
        .collect();
    let declared: BTreeSet<String> = layer.keys().map(|m| m.to_string()).collect();
    assert_eq!(
        modules, declared,
        "lib.rs declares other top-level modules than the layer list: put each on its layer"
    );
    let bad: Vec<String> = refs
        .iter()
        .filter(|r| layer[r.to.as_str()] >= layer[r.from.as_str()])
        .map(|r| {
            format!(
                "{} (layer {} → layer {})",
                describe(r),
                layer[r.from.as_str()],
                layer[r.to.as_str()]
            )
        })
        .collect();
    assert!(
        bad.is_empty(),
        "modules reference a module on their own or a higher layer (layers, bottom first: {LAYERS:?}):\n  {}",
        bad.join("\n  ")
    );
}

/// The checker itself: references in code count, in comments and strings they do not;
/// `use crate::{…}` groups and `super::` chains out of the module are seen.
#[test]
fn the_reference_finder_reads_groups_chains_and_skips_comments() {
    let code = code_only(
        "// crate::a\n/* crate::b /* nested */ crate::c */ let s = \"crate::d\"; let c = '\"';\n\
         use crate::{e, f::{g, h}, i as j};\nlet r = r#\"crate::k\"#; crate::l::m();\n\
         fn f<'a>(x: &'a u8) -> char { 'μ' } crate::n::p();",
    );
    assert!(!code.contains("crate::a") && !code.contains("crate::b") && !code.contains("crate::c"));
    assert!(!code.contains("crate::d") && !code.contains("crate::k"));
    assert!(code.contains("crate::l::m") && code.contains("crate::n::p"));
    assert_eq!(code.lines().count(), 5);
    let at = code.find("crate::{").unwrap();
    assert_eq!(group_names(&code[at + 8..]), ["e", "f", "i"]);
}

/// `include_str!` / `include_bytes!` in the library reach only files inside the crate.
#[test]
fn embedded_files_lie_inside_the_crate() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .canonicalize()
        .unwrap();
    let mut outside = Vec::new();
    for file in rust_files(&src_dir()) {
        let text = fs::read_to_string(&file).unwrap();
        for (n, line) in text.lines().enumerate() {
            for mac in ["include_str!(\"", "include_bytes!(\""] {
                let Some(at) = line.find(mac) else { continue };
                let arg = &line[at + mac.len()..];
                let arg = &arg[..arg.find('"').unwrap()];
                let target = file.parent().unwrap().join(arg).canonicalize().unwrap();
                if !target.starts_with(&root) {
                    outside.push(format!("{}:{}: {}", file.display(), n + 1, line.trim()));
                }
            }
        }
    }
    assert!(
        outside.is_empty(),
        "files embedded from outside the crate (cargo package leaves them out):\n  {}",
        outside.join("\n  ")
    );
}

/// The crate's copy of the paper's Table I program is the one users run from `examples/`.
#[test]
fn embedded_paper_program_equals_the_examples_copy() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let embedded = fs::read(crate_dir.join("data/paper-table1.gcode")).unwrap();
    let examples = fs::read(crate_dir.join("../../examples/paper-table1.gcode")).unwrap();
    assert!(
        embedded == examples,
        "crates/ofmpc/data/paper-table1.gcode and examples/paper-table1.gcode differ: copy one onto the other"
    );
    assert_eq!(ofmpc::gcode::PAPER_TABLE1.as_bytes(), &embedded[..]);
}

/// The files of `control/` that the file `file` (module path `module`
/// inside `control`, e.g. `mpc::core`) references: paths after `super::`
/// (resolved from the file's folder, `super::super::` one folder up) and
/// after `crate::control::`, groups `{x, …}` included, each resolved to the
/// longest module path of `modules`; without its unit tests.
fn control_references(file: &Path, module: &str, modules: &BTreeSet<String>) -> BTreeSet<String> {
    let src = code_only(&fs::read_to_string(file).unwrap());
    let src = match src.find("#[cfg(test)]\nmod tests") {
        Some(i) => &src[..i],
        None => &src[..],
    };
    let segments: Vec<&str> = module.split("::").collect();
    let mut found = BTreeSet::new();
    for prefix in ["super::", "crate::control::"] {
        let mut rest = src;
        while let Some(i) = rest.find(prefix) {
            let before = &rest[..i];
            let mut after = &rest[i + prefix.len()..];
            rest = after;
            if prefix == "super::" && before.ends_with("::") {
                continue; // inside a chain read already
            }
            let mut base: Vec<String> = Vec::new();
            if prefix == "super::" {
                let mut up = 1;
                while let Some(more) = after.strip_prefix("super::") {
                    up += 1;
                    after = more;
                }
                let keep = segments.len().saturating_sub(up);
                base.extend(segments[..keep].iter().map(|s| s.to_string()));
            }
            let mut paths = Vec::new();
            loop {
                if let Some(group) = after.strip_prefix('{') {
                    for name in group_names(group) {
                        paths.push([base.clone(), vec![name]].concat());
                    }
                    break;
                }
                let id = ident_at(after);
                if id.is_empty() {
                    break;
                }
                base.push(id.to_string());
                paths.push(base.clone());
                match after[id.len()..].strip_prefix("::") {
                    Some(more) => after = more,
                    None => break,
                }
            }
            let modules_named = paths
                .iter()
                .map(|p| p.join("::"))
                .filter(|p| modules.contains(p) && p != module);
            found.extend(modules_named);
        }
    }
    found
}

/// Every `.rs` file under `dir` but the `mod.rs` files, with its module path
/// below `control` (`mpc::core`, `solvers::lsq::avx2`).
fn control_files(dir: &Path, prefix: &str, out: &mut Vec<(String, PathBuf)>) {
    for entry in fs::read_dir(dir).unwrap().flatten() {
        let p = entry.path();
        let stem = p.file_stem().unwrap().to_string_lossy().to_string();
        let module = if prefix.is_empty() {
            stem.clone()
        } else {
            format!("{prefix}::{stem}")
        };
        if p.is_dir() {
            control_files(&p, &module, out);
        } else if p.extension().is_some_and(|x| x == "rs") && stem != "mod" {
            out.push((module, p));
        }
    }
}

/// Inside `control` and its folders, no two files import each other, directly
/// or through a cycle (the `mod.rs` files declare their children and are left
/// out): the settings, the drive model, the solvers and the controllers form
/// a partial order.
#[test]
fn control_files_do_not_import_each_other() {
    let mut files = Vec::new();
    control_files(&src_dir().join("control"), "", &mut files);
    let modules: BTreeSet<String> = files.iter().map(|(m, _)| m.clone()).collect();
    assert!(modules.contains("settings") && modules.contains("mpc::core"));
    let edges: BTreeMap<String, BTreeSet<String>> = files
        .iter()
        .map(|(m, p)| (m.clone(), control_references(p, m, &modules)))
        .collect();
    // Depth-first search; a back edge closes a cycle.
    fn visit(
        at: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, bool>,
        path: &mut Vec<String>,
        cycles: &mut Vec<String>,
    ) {
        state.insert(at.to_string(), false);
        path.push(at.to_string());
        for to in &edges[at] {
            match state.get(to) {
                None => visit(to, edges, state, path, cycles),
                Some(false) => {
                    let from = path.iter().position(|m| m == to).unwrap();
                    cycles.push(format!("{} -> {to}", path[from..].join(" -> ")));
                }
                Some(true) => {}
            }
        }
        path.pop();
        state.insert(at.to_string(), true);
    }
    let mut state = BTreeMap::new();
    let mut cycles = Vec::new();
    for m in edges.keys() {
        if !state.contains_key(m) {
            visit(m, &edges, &mut state, &mut Vec::new(), &mut cycles);
        }
    }
    assert!(
        cycles.is_empty(),
        "import cycles inside control: {cycles:?}"
    );
}

#[test]
fn the_control_reference_finder_reads_paths_groups_and_skips_tests() {
    let path = std::env::temp_dir().join(format!("ofmpc-arch-{}.rs", std::process::id()));
    fs::write(
        &path,
        "use super::core::dense_entries;\nuse super::{settings::Solver, zoh};\n\
         // super::lsq in a comment\nfn f() { crate::control::model::g(); let s = \"super::dense\"; }\n\
         #[cfg(test)]\nmod tests {\n    use super::tracking::T;\n}\n",
    )
    .unwrap();
    let siblings: BTreeSet<String> = [
        "core", "settings", "zoh", "lsq", "model", "dense", "tracking",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let found = control_references(&path, "first", &siblings);
    let _ = fs::remove_file(&path);
    let want: BTreeSet<String> = ["core", "settings", "zoh", "model"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    assert_eq!(found, want);
}
