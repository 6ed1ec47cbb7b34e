//! No import cycle between the files of any folder of any crate, and no arrow back up
//! between the stages of a folder that holds several (issue 34).
//!
//! See [`ofmpc_policy::imports`] for what counts as a reference. A failure names the folder,
//! the files in the cycle and every reference that ties them (file, line, text).

use ofmpc_policy::imports::{strongly_connected, use_paths, without_test_items, Graph, UsePath};
use ofmpc_policy::{workspace, CRATES};

/// Folders cut into stages, upstream first: a stage may reference the stages before it only.
/// The motion folder: path (blending, corners) → timing (time laws, TOPP) → joint reference.
const STAGES: &[(&str, &str, &[&str])] = &[(
    "ofmpc",
    "crates/ofmpc/src/motion",
    &["path/", "timing/", "reference/"],
)];

fn graphs() -> Vec<Graph> {
    CRATES
        .iter()
        .map(|c| Graph::of_crate(&workspace().join("crates").join(c), c))
        .collect()
}

/// The import cycles that remain, as `folder: {entries}`: a ratchet, empty since issue 34
/// cut the last ones. A cycle not listed fails the test; a listed one that is gone fails it
/// too, so that the list only shrinks.
const KNOWN_CYCLES: &[&str] = &[];

#[test]
fn no_folder_has_an_import_cycle() {
    let mut found = Vec::new();
    let mut heads = Vec::new();
    for g in graphs() {
        assert!(g.references.len() > 5, "{}: too few references", g.name);
        for c in g.cycles() {
            let text = c.to_string();
            let head = text.lines().next().unwrap_or("").trim().to_string();
            if !KNOWN_CYCLES.contains(&head.as_str()) {
                found.push(text);
            }
            heads.push(head);
        }
    }
    assert!(
        found.is_empty(),
        "import cycles between the files of a folder (import siblings directly, put what two \
         files share in a leaf file):\n{}",
        found.join("")
    );
    let gone: Vec<_> = KNOWN_CYCLES
        .iter()
        .filter(|k| !heads.iter().any(|h| h == *k))
        .collect();
    assert!(
        gone.is_empty(),
        "these known cycles are gone: remove them from KNOWN_CYCLES: {gone:?}"
    );
}

#[test]
fn no_stage_references_a_downstream_one() {
    let graphs = graphs();
    let mut bad = Vec::new();
    for (krate, folder, order) in STAGES {
        let g = graphs.iter().find(|g| g.name == *krate).unwrap();
        for stage in *order {
            assert!(
                g.has_file(&format!("{folder}/{stage}")),
                "{folder}/{stage} does not exist: update STAGES"
            );
        }
        bad.extend(g.back_arrows(folder, order).iter().map(|r| r.to_string()));
    }
    assert!(
        bad.is_empty(),
        "a stage references a downstream one (stages, upstream first: {STAGES:?}):\n  {}",
        bad.join("\n  ")
    );
}

fn leaf(segments: &[&str], binding: &str) -> UsePath {
    UsePath {
        segments: segments.iter().map(|s| s.to_string()).collect(),
        binding: binding.to_string(),
    }
}

/// The finder itself: use trees (groups, `self`, `as`, globs), test items cut, the entries an
/// edge joins, and the components.
#[test]
fn the_finder_reads_use_trees_cuts_tests_and_finds_components() {
    assert_eq!(
        use_paths("super::{a::B, c::{self, D as E}, *}"),
        vec![
            leaf(&["super", "a", "B"], "B"),
            leaf(&["super", "c"], "c"),
            leaf(&["super", "c", "D"], "E"),
            leaf(&["super"], "*"),
        ]
    );
    assert_eq!(
        use_paths("crate::x::y"),
        vec![leaf(&["crate", "x", "y"], "y")]
    );
    let (code, files) = without_test_items(
        "use super::a::X;\n#[cfg(test)]\nmod tests {\n    use super::b::Y;\n}\n\
         #[cfg(test)]\nmod more;\nfn f() {}\n",
    );
    assert!(code.contains("super::a::X") && !code.contains("super::b") && code.contains("fn f"));
    assert_eq!(code.lines().count(), 8);
    assert_eq!(files.into_iter().collect::<Vec<_>>(), ["more"]);
    assert_eq!(
        Graph::entries("c/src/m/t/topp.rs", "c/src/m/reference.rs"),
        (
            "c/src/m".to_string(),
            "t/".to_string(),
            "reference.rs".to_string()
        )
    );
    assert_eq!(
        Graph::entries("c/src/m/mod.rs", "c/src/m/a.rs"),
        (
            "c/src/m".to_string(),
            "mod.rs".to_string(),
            "a.rs".to_string()
        )
    );
    let e = |a: &str, b: &str| (a.to_string(), b.to_string());
    let sccs = strongly_connected(&[
        e("a", "b"),
        e("b", "c"),
        e("c", "a"),
        e("c", "d"),
        e("d", "e"),
    ]);
    assert_eq!(sccs.len(), 1);
    assert_eq!(sccs[0].iter().collect::<Vec<_>>(), ["a", "b", "c"]);
}

/// On a small crate written to a temporary folder: a re-export in `mod.rs` is followed to the
/// sibling that defines the item, so `x.rs → y.rs` and `y.rs → x.rs` close a cycle; test
/// modules do not count.
#[test]
fn the_finder_follows_re_exports_to_the_defining_sibling() {
    let dir = std::env::temp_dir().join(format!("ofmpc-policy-{}", std::process::id()));
    let src = dir.join("src/m");
    std::fs::create_dir_all(&src).unwrap();
    let write = |p: &str, t: &str| std::fs::write(dir.join(p), t).unwrap();
    write("src/lib.rs", "pub mod m;\npub mod z;\n");
    write(
        "src/z.rs",
        "pub fn zz() {}\n#[cfg(test)]\nmod tests { use crate::m::Y; }\n",
    );
    write(
        "src/m/mod.rs",
        "mod x;\nmod y;\npub use x::X;\npub use y::*;\n",
    );
    write(
        "src/m/x.rs",
        "pub struct X;\nfn f() -> super::Y { crate::z::zz(); loop {} }\n",
    );
    write("src/m/y.rs", "use super::X;\npub struct Y(X);\n");
    let g = Graph::of_crate(&dir, "t");
    let _ = std::fs::remove_dir_all(&dir);
    let edges: Vec<String> = g.references.iter().map(|r| r.to_string()).collect();
    assert_eq!(edges.len(), 3, "{edges:#?}");
    let cycles = g.cycles();
    assert_eq!(cycles.len(), 1, "{edges:#?}");
    assert_eq!(cycles[0].entries, ["x.rs", "y.rs"]);
    assert!(cycles[0].to_string().contains("src/m/y.rs:1: references"));
}
