//! The library's public surface, checked against a snapshot so that it cannot grow unnoticed.
//!
//! The list holds what rustdoc's "all items" page of `ofmpc` lists: every type, function,
//! constant, static, trait and type alias a user can name, at the path where it is public
//! (methods and fields are not items of that page). It is read from the source: from
//! `src/lib.rs` down through `pub mod` declarations, every `pub` item a public module
//! defines at its top level and every name a `pub use` makes public there. Items marked
//! `#[doc(hidden)]`, or in a `#[doc(hidden)]` module, are listed with the tag `hidden`
//! (rustdoc does not show them; they are
//! kept in the snapshot so that they cannot grow unnoticed either).
//!
//! Checked: (a) the list equals `public-api.txt` beside this crate's `Cargo.toml`
//! (regenerate it with `OFMPC_BLESS=1 cargo test -p ofmpc-policy --test public_api` and
//! review the diff); (b) at most [`MAX_ITEMS`] items rustdoc shows; (c) no glob re-export
//! (`pub use x::*`: its items could not be listed); (d) one path per item: no name is public
//! at two paths, except names of distinct items listed in [`DISTINCT_SAME_NAME`].

use ofmpc_policy::imports::{use_paths, without_test_items};
use ofmpc_policy::source::code_only;
use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

/// Most items rustdoc's "all items" page may list: a ratchet at today's count (312 before
/// issue 34's curation brought it to 148; issue 37's command modes added 9:
/// `control::OutputMode` and the servo stage's `sim::{Servo, ServoSettings, ServoProfile,
/// OnLate, LateSteps, ServoReport, ServoStatus, ServoSettingsError}`; the step telemetry 2:
/// `FallbackLevel` and `StepTelemetry`).
const MAX_ITEMS: usize = 160;

/// Names that two distinct items carry at two public paths (reviewed: not one item twice).
const DISTINCT_SAME_NAME: &[&str] = &[];

/// One public item: its path, its kind and whether rustdoc hides it.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Item {
    path: String,
    kind: String,
    hidden: bool,
}

impl Item {
    fn line(&self) -> String {
        let tag = if self.hidden { " hidden" } else { "" };
        format!("{} {}{}", self.kind, self.path, tag)
    }
}

fn library_src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../ofmpc/src")
}

/// The file of module `name` declared in `file` (`name.rs` or `name/mod.rs`).
fn module_file(file: &Path, name: &str) -> Option<PathBuf> {
    let stem = file.file_stem()?.to_str()?;
    let dir = if stem == "lib" || stem == "mod" {
        file.parent()?.to_path_buf()
    } else {
        file.with_extension("")
    };
    [
        dir.join(format!("{name}.rs")),
        dir.join(name).join("mod.rs"),
    ]
    .into_iter()
    .find(|p| p.exists())
}

/// `code` with everything inside braces blanked: what remains are the file's top-level
/// declarations (`{` and `}` of a top-level item are kept, so `pub mod x {` stays visible).
fn top_level(code: &str) -> String {
    let mut depth = 0usize;
    code.chars()
        .map(|c| match c {
            '{' => {
                depth += 1;
                if depth == 1 {
                    '{'
                } else {
                    ' '
                }
            }
            '}' => {
                depth = depth.saturating_sub(1);
                if depth == 0 {
                    '}'
                } else {
                    ' '
                }
            }
            '\n' => '\n',
            c if depth == 0 => c,
            _ => ' ',
        })
        .collect()
}

/// Whether the attributes just before byte `at` of `code` include `#[doc(hidden)]`.
fn hidden_before(code: &str, at: usize) -> bool {
    let before = code[..at].trim_end();
    let mut rest = before;
    // Walk back over attributes (`#[…]`) that directly precede the item.
    while rest.ends_with(']') {
        let Some(open) = rest.rfind("#[") else { break };
        if rest[open..].replace(' ', "").starts_with("#[doc(hidden)]") {
            return true;
        }
        rest = rest[..open].trim_end();
    }
    false
}

const KINDS: &[&str] = &[
    "struct", "enum", "fn", "trait", "const", "static", "type", "union", "mod", "use", "macro",
];

/// Scans `file`, the source of `module`; `hidden_module`: the module is `#[doc(hidden)]`, so
/// rustdoc hides every item in it too.
fn scan(
    file: &Path,
    module: &str,
    hidden_module: bool,
    out: &mut Vec<Item>,
    errors: &mut Vec<String>,
) {
    let src = fs::read_to_string(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    let (code, _) = without_test_items(&code_only(&src));
    let top = top_level(&code);
    let mut from = 0;
    while let Some(i) = top[from..].find("pub ") {
        let at = from + i;
        from = at + 4;
        let prev = top[..at].chars().last();
        if prev.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let mut words = top[at + 4..].split_whitespace();
        let mut kind = words.next().unwrap_or("");
        while matches!(kind, "unsafe" | "async" | "extern" | "\"C\"")
            || (kind == "const"
                && top[at + 4..].trim_start()[5..]
                    .trim_start()
                    .starts_with("fn"))
        {
            kind = words.next().unwrap_or("");
        }
        if !KINDS.contains(&kind) {
            continue;
        }
        let hidden = hidden_module || hidden_before(&code, at);
        if kind == "use" {
            let body_start = at + top[at..].find("use").unwrap() + 3;
            let end = code[body_start..].find(';').map(|e| body_start + e);
            let Some(end) = end else { continue };
            for leaf in use_paths(&code[body_start..end]) {
                match leaf.binding.as_str() {
                    "*" => errors.push(format!(
                        "{}: glob re-export `pub use {}::*` (list its items)",
                        file.display(),
                        leaf.segments.join("::")
                    )),
                    "self" | "_" => {}
                    name => out.push(Item {
                        path: format!("{module}::{name}"),
                        kind: "use".into(),
                        hidden,
                    }),
                }
            }
            continue;
        }
        let name: String = words
            .next()
            .unwrap_or("")
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        if name.is_empty() {
            continue;
        }
        if kind == "mod" {
            let decl = top[at..].split(['\n']).next().unwrap_or("");
            if decl.contains('{') {
                errors.push(format!(
                    "{}: inline `pub mod {name} {{ … }}` (give it a file)",
                    file.display()
                ));
            } else if let Some(child) = module_file(file, &name) {
                scan(&child, &format!("{module}::{name}"), hidden, out, errors);
            }
            continue;
        }
        out.push(Item {
            path: format!("{module}::{name}"),
            kind: kind.into(),
            hidden,
        });
    }
}

fn public_items() -> (Vec<Item>, Vec<String>) {
    let mut items = Vec::new();
    let mut errors = Vec::new();
    scan(
        &library_src().join("lib.rs"),
        "ofmpc",
        false,
        &mut items,
        &mut errors,
    );
    items.sort();
    items.dedup();
    (items, errors)
}

fn snapshot_file() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("public-api.txt")
}

#[test]
fn the_public_api_equals_its_snapshot() {
    let (items, errors) = public_items();
    assert!(errors.is_empty(), "{}", errors.join("\n"));
    let text: String = items.iter().map(|i| i.line() + "\n").collect();
    if std::env::var_os("OFMPC_BLESS").is_some() {
        fs::write(snapshot_file(), &text).unwrap();
    }
    let stored = fs::read_to_string(snapshot_file()).unwrap_or_default();
    if stored != text {
        let old: Vec<&str> = stored.lines().collect();
        let new: Vec<&str> = text.lines().collect();
        let added: Vec<&&str> = new.iter().filter(|l| !old.contains(l)).collect();
        let removed: Vec<&&str> = old.iter().filter(|l| !new.contains(l)).collect();
        panic!(
            "the public API changed: added {added:?}, removed {removed:?}; if intended, \
             regenerate {} with OFMPC_BLESS=1 cargo test -p ofmpc-policy --test public_api",
            snapshot_file().display()
        );
    }
}

#[test]
fn the_public_api_is_small_and_each_item_has_one_path() {
    let (items, _) = public_items();
    // A root re-export (`ofmpc::Robot`) of a façade module's item is the same item: count it once.
    let mut names: Vec<&str> = items
        .iter()
        .filter(|i| !i.hidden)
        .map(|i| i.path.rsplit("::").next().unwrap())
        .collect();
    names.sort();
    names.dedup();
    let shown = names.len();
    assert!(
        shown <= MAX_ITEMS,
        "{shown} public items (at most {MAX_ITEMS}): make internals pub(crate)"
    );
    let mut paths: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for i in &items {
        let name = i.path.rsplit("::").next().unwrap();
        paths.entry(name).or_default().push(&i.path);
    }
    let twice: Vec<_> = paths
        .iter()
        .filter(|(n, p)| {
            // The root re-exports what a user needs most: `ofmpc::X` beside `ofmpc::m::X`.
            let root = format!("ofmpc::{n}");
            let others = p.iter().filter(|q| **q != root).count();
            others > 1 && !DISTINCT_SAME_NAME.contains(n)
        })
        .collect();
    assert!(twice.is_empty(), "items public at two paths: {twice:?}");
}

#[test]
fn the_scanner_reads_items_re_exports_and_hidden_ones() {
    let dir = std::env::temp_dir().join(format!("ofmpc-public-api-{}", std::process::id()));
    fs::create_dir_all(dir.join("a")).unwrap();
    fs::write(
        dir.join("lib.rs"),
        "pub mod a;\n#[doc(hidden)]\npub mod z;\nmod b;\npub use b::{B, C as D};\n#[doc(hidden)]\npub fn h() {}\n\
         pub(crate) fn no() {}\nimpl X { pub fn method() {} }\npub const fn k() -> u8 { 1 }\n",
    )
    .unwrap();
    fs::write(
        dir.join("a/mod.rs"),
        "pub struct S { pub f: u8 }\n#[cfg(test)]\nmod tests { pub fn t() {} }\n",
    )
    .unwrap();
    fs::write(dir.join("z.rs"), "pub struct Z;\n").unwrap();
    let (mut items, mut errors) = (Vec::new(), Vec::new());
    scan(&dir.join("lib.rs"), "c", false, &mut items, &mut errors);
    items.sort();
    let mut got: Vec<String> = items.iter().map(Item::line).collect();
    got.sort();
    let mut expected = [
        "struct c::a::S",
        "struct c::z::Z hidden",
        "use c::B",
        "use c::D",
        "fn c::h hidden",
        "fn c::k",
    ];
    expected.sort();
    assert_eq!(got, expected);
    assert!(errors.is_empty());
    fs::remove_dir_all(&dir).ok();
}
