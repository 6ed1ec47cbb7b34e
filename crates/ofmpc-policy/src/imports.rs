//! The file-level import graph of a crate, and its cycles folder by folder.
//!
//! Every `.rs` file under `src/` is a module (`lib.rs` the root, `a/mod.rs` and `a.rs` the
//! module `a`, `a/b.rs` the module `a::b`); `#[cfg(test)]` items (unit tests) are cut, and a
//! file declared `#[cfg(test)] mod x;` is left out. A file references another when one of its
//! paths resolves there:
//!
//! - a `use` statement (`use super::x::Y`, `use crate::a::{b, c::D}`, `use self::x::*`,
//!   `use child::Y` for a declared child module); `pub use` / `pub(crate) use` statements are
//!   re-exports, not imports: they make no edge of their own;
//! - a path expression outside `use` statements (`crate::a::f()`, `super::x::Y`, `child::f()`).
//!
//! A path resolves module by module; at the first segment that is not a module, the item is
//! the module's own when the module's file defines it, else it follows the module's `use`
//! statements (named, then globs): so `super::Item` in `a/x.rs`, where `a/mod.rs` says
//! `pub use y::Item`, is an edge to `a/y.rs`, not to `a/mod.rs`.
//!
//! Folders: an edge from file `f` to file `g` belongs to the deepest folder holding both; in
//! that folder it joins the entries (a file, `mod.rs`, or a sub-folder taken whole) that hold
//! `f` and `g`. [`Graph::cycles`] lists, for every folder, the strongly connected components of
//! more than one entry, with the references that tie them.

use crate::source::{code_only, ident_at, rust_files};
use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::Path;

/// A module path from the crate root (`[]` is the root).
type ModPath = Vec<String>;

/// One module: its file and what it declares, defines and imports.
#[derive(Debug, Default)]
struct Module {
    /// Path of the file relative to the crate (`src/motion/topp.rs`).
    file: String,
    /// Whether the file is `mod.rs` / `lib.rs` (its children live in its folder).
    is_dir: bool,
    /// The code: comments, literals and test items blanked.
    code: String,
    /// The original lines (for messages).
    lines: Vec<String>,
    /// Names of the items the file defines.
    defs: BTreeSet<String>,
    /// Names of the modules the file declares (`mod x;`, tests left out).
    children: BTreeSet<String>,
    /// Every `use` statement: (byte offset, whether it is a re-export, its paths).
    uses: Vec<(usize, bool, Vec<UsePath>)>,
}

/// One leaf of a `use` tree: the path and the name it binds (`*` for a glob).
#[derive(Debug, Clone, PartialEq)]
pub struct UsePath {
    pub segments: Vec<String>,
    pub binding: String,
}

/// A reference from one file to another.
#[derive(Debug, Clone)]
pub struct Reference {
    pub from: String,
    pub to: String,
    pub line: usize,
    pub text: String,
}

impl std::fmt::Display for Reference {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}:{}: references {}: {}",
            self.from, self.line, self.to, self.text
        )
    }
}

/// The import graph of one crate.
#[derive(Debug)]
pub struct Graph {
    /// The crate's name (for messages).
    pub name: String,
    modules: BTreeMap<ModPath, Module>,
    /// Every reference between two files, in file and line order.
    pub references: Vec<Reference>,
}

/// An import cycle inside one folder.
#[derive(Debug)]
pub struct Cycle {
    /// The folder (`crates/ofmpc/src/motion`).
    pub folder: String,
    /// The entries in the cycle (`topp.rs`, `reference.rs`, `timing/`).
    pub entries: Vec<String>,
    /// The references between those entries.
    pub references: Vec<Reference>,
}

impl std::fmt::Display for Cycle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "{}: {{{}}}", self.folder, self.entries.join(", "))?;
        for r in &self.references {
            writeln!(f, "    {r}")?;
        }
        Ok(())
    }
}

/// `code` with every `#[cfg(test)]` item blanked (up to its `;` or its closing brace);
/// newlines kept. Also returns the names of the modules declared `#[cfg(test)] mod x;`.
pub fn without_test_items(code: &str) -> (String, BTreeSet<String>) {
    let mut out = code.as_bytes().to_vec();
    let mut test_files = BTreeSet::new();
    let mut from = 0;
    while let Some(i) = code[from..].find("#[cfg(test)]") {
        let start = from + i;
        let b = code.as_bytes();
        let mut j = start;
        let mut depth = 0i32;
        let mut opened = false;
        while j < b.len() {
            match b[j] {
                b'{' => {
                    depth += 1;
                    opened = true;
                }
                b'}' => depth -= 1,
                b';' if !opened => break,
                _ => {}
            }
            j += 1;
            if opened && depth == 0 {
                break;
            }
        }
        let item = &code[start..j.min(b.len())];
        if !opened {
            if let Some(m) = item.split_whitespace().skip_while(|w| *w != "mod").nth(1) {
                test_files.insert(m.trim_end_matches(';').to_string());
            }
        }
        for c in &mut out[start..j.min(b.len())] {
            if *c != b'\n' {
                *c = b' ';
            }
        }
        from = j.max(start + 1);
    }
    (String::from_utf8(out).unwrap(), test_files)
}

/// The leaves of the `use` tree in `text` (what follows `use`, without the `;`).
pub fn use_paths(text: &str) -> Vec<UsePath> {
    let mut tokens = Vec::new();
    let mut rest = text.trim();
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix("::") {
            tokens.push("::".to_string());
            rest = r;
        } else if rest.starts_with(['{', '}', ',', '*']) {
            tokens.push(rest[..1].to_string());
            rest = &rest[1..];
        } else {
            let id = ident_at(rest);
            if id.is_empty() {
                rest = &rest[rest.chars().next().unwrap().len_utf8()..];
            } else {
                tokens.push(id.to_string());
                rest = &rest[id.len()..];
            }
        }
        rest = rest.trim_start();
    }
    let mut out = Vec::new();
    let mut at = 0;
    if tokens.first().map(String::as_str) == Some("::") {
        at = 1;
    }
    tree(&tokens, &mut at, &[], &mut out);
    out
}

/// Parses one use tree at `tokens[*at]` under `prefix`.
fn tree(tokens: &[String], at: &mut usize, prefix: &[String], out: &mut Vec<UsePath>) {
    let mut path = prefix.to_vec();
    loop {
        match tokens.get(*at).map(String::as_str) {
            Some("{") => {
                *at += 1;
                while !matches!(tokens.get(*at).map(String::as_str), Some("}") | None) {
                    tree(tokens, at, &path, out);
                    if tokens.get(*at).map(String::as_str) == Some(",") {
                        *at += 1;
                    }
                }
                *at += 1;
                return;
            }
            Some("*") => {
                *at += 1;
                out.push(UsePath {
                    segments: path,
                    binding: "*".into(),
                });
                return;
            }
            Some("self") if path.len() == prefix.len() && !prefix.is_empty() => {
                *at += 1;
                let binding = alias(tokens, at).unwrap_or_else(|| path.last().unwrap().clone());
                out.push(UsePath {
                    segments: path,
                    binding,
                });
                return;
            }
            Some(id) if id != "," && id != "}" && id != "::" => {
                path.push(id.to_string());
                *at += 1;
                if tokens.get(*at).map(String::as_str) == Some("::") {
                    *at += 1;
                    continue;
                }
                let binding = alias(tokens, at).unwrap_or_else(|| path.last().unwrap().clone());
                out.push(UsePath {
                    segments: path,
                    binding,
                });
                return;
            }
            _ => return,
        }
    }
}

/// `as name` at `tokens[*at]`, consumed.
fn alias(tokens: &[String], at: &mut usize) -> Option<String> {
    if tokens.get(*at).map(String::as_str) == Some("as") {
        let name = tokens.get(*at + 1).cloned();
        *at += 2;
        return name.or(Some("_".into()));
    }
    None
}

/// The names of the items `code` defines (functions, types, traits, constants, macros).
fn definitions(code: &str) -> BTreeSet<String> {
    let mut defs = BTreeSet::new();
    let words: Vec<&str> = code
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '!'))
        .filter(|w| !w.is_empty())
        .collect();
    for w in words.windows(2) {
        if matches!(
            w[0],
            "fn" | "struct"
                | "enum"
                | "trait"
                | "type"
                | "const"
                | "static"
                | "union"
                | "macro_rules!"
        ) {
            defs.insert(w[1].to_string());
        }
    }
    defs
}

/// Whether the byte before `at` ends an identifier or a path (`x::`, `$`).
fn inside_path(code: &str, at: usize) -> bool {
    let b = code.as_bytes();
    at > 0 && {
        let p = b[at - 1];
        p.is_ascii_alphanumeric() || p == b'_' || p == b'$' || (p == b':' && at >= 2)
    }
}

impl Module {
    fn read(file: &Path, rel: String, is_dir: bool) -> (Module, BTreeSet<String>) {
        let original = fs::read_to_string(file).unwrap();
        let (code, test_files) = without_test_items(&code_only(&original));
        let mut children = BTreeSet::new();
        let mut uses = Vec::new();
        let mut from = 0;
        while let Some(i) = code[from..].find("use ") {
            let at = from + i;
            from = at + 4;
            if inside_path(&code, at) {
                continue;
            }
            let end = at + code[at..].find(';').unwrap_or(code.len() - at);
            let before = code[..at].trim_end();
            let reexport = before.ends_with("pub")
                || before.ends_with(')') && {
                    let open = before.rfind('(').unwrap_or(0);
                    before[..open].trim_end().ends_with("pub")
                };
            uses.push((at, reexport, use_paths(&code[at + 4..end])));
            from = end;
        }
        for line in code.lines() {
            let l = line.trim();
            let l = l.strip_prefix("pub ").unwrap_or(l);
            let l = match l.strip_prefix("pub(") {
                Some(r) => r.split_once(") ").map(|x| x.1).unwrap_or(r),
                None => l,
            };
            if let Some(name) = l.strip_prefix("mod ").and_then(|r| r.strip_suffix(';')) {
                children.insert(name.trim().to_string());
            }
        }
        let module = Module {
            file: rel,
            is_dir,
            defs: definitions(&code),
            lines: original.lines().map(|l| l.trim().to_string()).collect(),
            code,
            children,
            uses,
        };
        (module, test_files)
    }

    fn line_of(&self, at: usize) -> (usize, String) {
        let line = self.code[..at].matches('\n').count();
        (line + 1, self.lines.get(line).cloned().unwrap_or_default())
    }
}

impl Graph {
    /// Reads every file of the crate at `dir` (holding `src/`), `name` for messages.
    pub fn of_crate(dir: &Path, name: &str) -> Graph {
        let src = dir.join("src");
        let mut modules = BTreeMap::new();
        let mut test_only: BTreeSet<ModPath> = BTreeSet::new();
        for file in rust_files(&src) {
            let rel = file.strip_prefix(&src).unwrap();
            let mut parts: Vec<String> = rel
                .iter()
                .map(|p| p.to_string_lossy().into_owned())
                .collect();
            let last = parts.pop().unwrap();
            let is_dir = last == "mod.rs" || (parts.is_empty() && last == "lib.rs");
            if parts.is_empty() && last == "main.rs" && src.join("lib.rs").exists() {
                continue;
            }
            let crate_root = parts.is_empty() && last == "main.rs";
            if !is_dir && !crate_root {
                parts.push(last.trim_end_matches(".rs").to_string());
            }
            let rel_s = format!("crates/{name}/src/{}", rel.to_string_lossy());
            let (module, tests) = Module::read(&file, rel_s, is_dir);
            for t in tests {
                let mut p = parts.clone();
                p.push(t);
                test_only.insert(p);
            }
            modules.insert(parts, module);
        }
        modules.retain(|p, _| !test_only.iter().any(|t| p.starts_with(t)));
        let mut graph = Graph {
            name: name.to_string(),
            modules,
            references: Vec::new(),
        };
        graph.references = graph.find_references();
        graph
    }

    /// `segments` as written in module `m`, made absolute; `None` for another crate.
    fn absolute(&self, m: &ModPath, segments: &[String]) -> Option<ModPath> {
        let first = segments.first()?;
        let mut base = match first.as_str() {
            "crate" => return Some(segments[1..].to_vec()),
            "self" => return Some([m.clone(), segments[1..].to_vec()].concat()),
            "super" => m.clone(),
            _ => {
                let module = self.modules.get(m)?;
                let child: ModPath = [m.clone(), vec![first.clone()]].concat();
                if module.children.contains(first) || self.modules.contains_key(&child) {
                    return Some([m.clone(), segments.to_vec()].concat());
                }
                return None;
            }
        };
        let mut rest = segments;
        while rest.first().map(String::as_str) == Some("super") {
            base.pop();
            rest = &rest[1..];
        }
        Some([base, rest.to_vec()].concat())
    }

    /// Whether module `m` provides the name `s` (defines it or imports it).
    fn provides(&self, m: &ModPath, s: &str, depth: usize) -> bool {
        let Some(module) = self.modules.get(m) else {
            return false;
        };
        if depth > 8 {
            return false;
        }
        module.defs.contains(s)
            || module
                .uses
                .iter()
                .flat_map(|u| &u.2)
                .any(|p| p.binding == s)
            || module
                .uses
                .iter()
                .flat_map(|u| &u.2)
                .filter(|p| p.binding == "*")
                .filter_map(|p| self.absolute(m, &p.segments))
                .any(|g| self.modules.contains_key(&g) && self.provides(&g, s, depth + 1))
    }

    /// The module whose file holds what the absolute path `segments` names.
    fn resolve(&self, segments: &[String], depth: usize) -> ModPath {
        let mut m: ModPath = Vec::new();
        for (i, s) in segments.iter().enumerate() {
            let next: ModPath = [m.clone(), vec![s.clone()]].concat();
            if self.modules.contains_key(&next) {
                m = next;
                continue;
            }
            let module = &self.modules[&m];
            if module.defs.contains(s) || depth > 8 {
                return m;
            }
            let rest = &segments[i + 1..];
            let leaves = module.uses.iter().flat_map(|u| &u.2);
            for p in leaves.clone().filter(|p| &p.binding == s) {
                if let Some(abs) = self.absolute(&m, &p.segments) {
                    return self.resolve(&[abs, rest.to_vec()].concat(), depth + 1);
                }
            }
            for p in leaves.filter(|p| p.binding == "*") {
                if let Some(g) = self.absolute(&m, &p.segments) {
                    if self.modules.contains_key(&g) && self.provides(&g, s, 0) {
                        let path = [g, vec![s.clone()], rest.to_vec()].concat();
                        return self.resolve(&path, depth + 1);
                    }
                }
            }
            return m;
        }
        m
    }

    fn find_references(&self) -> Vec<Reference> {
        let mut out = Vec::new();
        for (m, module) in &self.modules {
            let mut add = |segments: &[String], at: usize| {
                let Some(abs) = self.absolute(m, segments) else {
                    return;
                };
                let target = self.resolve(&abs, 0);
                let to = &self.modules[&target].file;
                if *to != module.file {
                    let (line, text) = module.line_of(at);
                    out.push(Reference {
                        from: module.file.clone(),
                        to: to.clone(),
                        line,
                        text,
                    });
                }
            };
            let mut in_use = Vec::new();
            for (at, reexport, paths) in &module.uses {
                let end = at + module.code[*at..].find(';').unwrap_or(0);
                in_use.push(*at..end);
                if !reexport {
                    for p in paths {
                        add(&p.segments, *at);
                    }
                }
            }
            // Path expressions: `crate::…`, `super::…`, `self::…`, `child::…`.
            let code = &module.code;
            let mut starts: Vec<String> = vec!["crate".into(), "super".into(), "self".into()];
            starts.extend(module.children.iter().cloned());
            for start in &starts {
                let pat = format!("{start}::");
                for (at, _) in code.match_indices(&pat) {
                    if inside_path(code, at) || in_use.iter().any(|r| r.contains(&at)) {
                        continue;
                    }
                    let mut segments = Vec::new();
                    let mut rest = &code[at..];
                    loop {
                        let id = ident_at(rest);
                        if id.is_empty() {
                            break;
                        }
                        segments.push(id.to_string());
                        rest = &rest[id.len()..];
                        match rest.strip_prefix("::") {
                            Some(r) => rest = r.trim_start(),
                            None => break,
                        }
                    }
                    add(&segments, at);
                }
            }
        }
        out.sort_by(|a, b| (&a.from, a.line, &a.to).cmp(&(&b.from, b.line, &b.to)));
        out.dedup_by(|a, b| a.from == b.from && a.line == b.line && a.to == b.to);
        out
    }

    /// The folder and the two entries an edge joins: the deepest folder holding both files.
    pub fn entries(from: &str, to: &str) -> (String, String, String) {
        let a: Vec<&str> = from.split('/').collect();
        let b: Vec<&str> = to.split('/').collect();
        let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
        let entry = |p: &[&str]| {
            if p.len() > common + 1 {
                format!("{}/", p[common])
            } else {
                p[common].to_string()
            }
        };
        (a[..common].join("/"), entry(&a), entry(&b))
    }

    /// Every folder's import cycles (strongly connected components of more than one entry).
    pub fn cycles(&self) -> Vec<Cycle> {
        let mut folders: BTreeMap<String, Vec<(String, String, &Reference)>> = BTreeMap::new();
        for r in &self.references {
            let (folder, a, b) = Self::entries(&r.from, &r.to);
            folders.entry(folder).or_default().push((a, b, r));
        }
        let mut out = Vec::new();
        for (folder, edges) in folders {
            let pairs: Vec<(String, String)> = edges
                .iter()
                .map(|(a, b, _)| (a.clone(), b.clone()))
                .collect();
            for scc in strongly_connected(&pairs) {
                let references = edges
                    .iter()
                    .filter(|(a, b, _)| scc.contains(a) && scc.contains(b))
                    .map(|e| e.2.clone())
                    .collect();
                out.push(Cycle {
                    folder: folder.clone(),
                    entries: scc.into_iter().collect(),
                    references,
                });
            }
        }
        out
    }

    /// The references inside `folder` from an entry to one that `order` lists after it
    /// (`order`: the folder's stages, upstream first, as entries: `path/`, `timing/`).
    pub fn back_arrows(&self, folder: &str, order: &[&str]) -> Vec<Reference> {
        let rank = |e: &str| order.iter().position(|o| *o == e);
        self.references
            .iter()
            .filter(|r| {
                let (f, a, b) = Self::entries(&r.from, &r.to);
                f == folder && matches!((rank(&a), rank(&b)), (Some(i), Some(j)) if i < j)
            })
            .cloned()
            .collect()
    }

    /// Whether the crate has a folder entry at `path` (for checks that name folders).
    pub fn has_file(&self, file: &str) -> bool {
        self.modules
            .values()
            .any(|m| m.file == file || m.is_dir && m.file.starts_with(file))
    }
}

/// The strongly connected components of more than one node (Tarjan), each sorted.
pub fn strongly_connected(edges: &[(String, String)]) -> Vec<BTreeSet<String>> {
    let nodes: BTreeSet<&str> = edges
        .iter()
        .flat_map(|(a, b)| [a.as_str(), b.as_str()])
        .collect();
    let mut adj: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for (a, b) in edges {
        adj.entry(a.as_str()).or_default().push(b.as_str());
    }
    struct State<'a> {
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on: BTreeSet<&'a str>,
        out: Vec<BTreeSet<String>>,
    }
    fn visit<'a>(n: &'a str, adj: &BTreeMap<&'a str, Vec<&'a str>>, s: &mut State<'a>) {
        let i = s.index.len();
        s.index.insert(n, i);
        s.low.insert(n, i);
        s.stack.push(n);
        s.on.insert(n);
        for &m in adj.get(n).into_iter().flatten() {
            if !s.index.contains_key(m) {
                visit(m, adj, s);
                let l = s.low[m].min(s.low[n]);
                s.low.insert(n, l);
            } else if s.on.contains(m) {
                let l = s.index[m].min(s.low[n]);
                s.low.insert(n, l);
            }
        }
        if s.low[n] == s.index[n] {
            let mut scc = BTreeSet::new();
            while let Some(m) = s.stack.pop() {
                s.on.remove(m);
                scc.insert(m.to_string());
                if m == n {
                    break;
                }
            }
            if scc.len() > 1 {
                s.out.push(scc);
            }
        }
    }
    let mut s = State {
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for n in nodes {
        if !s.index.contains_key(n) {
            visit(n, &adj, &mut s);
        }
    }
    s.out
}
