//! The code reads top-down: no function of the workspace (sources, examples,
//! benches; tests are exempt) is longer than [`MAX_LINES`] lines, signature to closing brace,
//! outside the SIMD kernels (hand-scheduled register blocks, listed in
//! [`KERNELS`]).
//!
//! A second budget: at most [`MAX_LONG_FUNCTIONS`] functions over [`LONG_LINES`] lines in
//! the whole workspace (non-test code: `#[cfg(test)]` items cut; SIMD kernels exempt).
//!
//! The scanner is a small brace counter (strings, character literals and
//! line comments stripped): exact for rustfmt-formatted code, which CI
//! enforces.

use ofmpc_policy::imports::without_test_items;
use ofmpc_policy::source::code_only;
use std::fs;
use std::path::{Path, PathBuf};

/// Longest function allowed (lines).
const MAX_LINES: usize = 120;

/// Functions longer than this (lines) count against [`MAX_LONG_FUNCTIONS`].
const LONG_LINES: usize = 60;

/// How many functions of the workspace may be longer than [`LONG_LINES`] (issue 34).
const MAX_LONG_FUNCTIONS: usize = 40;

/// Files whose functions are SIMD kernels (exempt).
const KERNELS: &[&str] = &["crates/ofmpc/src/control/solvers/lsq/avx2.rs"];

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The line without string and character literals and without a trailing
/// `//` comment.
fn code_of(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' => {
                while let Some(d) = chars.next() {
                    match d {
                        '\\' => {
                            chars.next();
                        }
                        '"' => break,
                        _ => {}
                    }
                }
            }
            '\'' => {
                // A character literal ('x', '\n', '{') or a lifetime ('a).
                let rest: String = chars.clone().take(3).collect();
                let lit = rest.starts_with('\\') || rest.chars().nth(1) == Some('\'');
                if lit {
                    while let Some(d) = chars.next() {
                        match d {
                            '\\' => {
                                chars.next();
                            }
                            '\'' => break,
                            _ => {}
                        }
                    }
                }
            }
            '/' if chars.peek() == Some(&'/') => break,
            _ => out.push(c),
        }
    }
    out
}

/// The name of the function a line declares, if it does.
fn declared_fn(code: &str) -> Option<&str> {
    let mut words = code.split_whitespace().peekable();
    while let Some(w) = words.next() {
        match w {
            "pub" | "const" | "async" | "unsafe" | "extern" | "\"C\"" => continue,
            w if w.starts_with("pub(") => continue,
            "fn" => {
                let name = words.next()?;
                let end = name.find(['(', '<']).unwrap_or(name.len());
                return Some(&name[..end]);
            }
            _ => return None,
        }
    }
    None
}

/// `(name, first line, length)` of every function with a body in `text`.
fn functions(text: &str) -> Vec<(String, usize, usize)> {
    let lines: Vec<String> = text.lines().map(code_of).collect();
    let mut found = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let Some(name) = declared_fn(line) else {
            continue;
        };
        let mut depth = 0i64;
        // Brackets of the signature (`[f64; 3]` holds a `;`).
        let mut brackets = 0i64;
        let mut opened = false;
        'scan: for (j, l) in lines.iter().enumerate().skip(i) {
            for c in l.chars() {
                match c {
                    '{' => {
                        depth += 1;
                        opened = true;
                    }
                    '}' => depth -= 1,
                    '(' | '[' if !opened => brackets += 1,
                    ')' | ']' if !opened => brackets -= 1,
                    // A declaration without a body.
                    ';' if !opened && brackets == 0 => break 'scan,
                    _ => {}
                }
                if opened && depth == 0 {
                    found.push((name.to_string(), i + 1, j - i + 1));
                    break 'scan;
                }
            }
        }
    }
    found
}

#[test]
fn the_scanner_measures_what_rustfmt_writes() {
    let text = "fn a() {\n    let s = \"}}\";\n    let c = '{';\n}\n\
                pub(crate) fn b<T>(x: T) -> usize\nwhere\n    T: Copy,\n{\n    // }\n    1\n}\n\
                fn decl();\nfn c(a: [f64; 3]) -> [u8; 2] {\n    [0; 2]\n}\n";
    let f = functions(text);
    assert_eq!(
        f,
        vec![
            ("a".to_string(), 1, 4),
            ("b".to_string(), 5, 7),
            ("c".to_string(), 13, 3)
        ],
        "{f:?}"
    );
}

#[test]
fn no_function_is_longer_than_the_limit() {
    let root = workspace();
    let mut files = Vec::new();
    for krate in ["ofmpc", "ofmpc-cli", "ofmpc-py", "ofmpc-scenario"] {
        for dir in ["src", "examples", "benches"] {
            rust_files(&root.join("crates").join(krate).join(dir), &mut files);
        }
    }
    assert!(files.len() > 50, "found only {} files", files.len());
    let mut long = Vec::new();
    for file in &files {
        let rel = file.strip_prefix(&root).unwrap_or(file);
        let rel_s = rel.to_string_lossy().replace('\\', "/");
        if KERNELS.iter().any(|k| rel_s.ends_with(k)) {
            continue;
        }
        let text = fs::read_to_string(file).unwrap();
        for (name, line, len) in functions(&text) {
            if len > MAX_LINES {
                long.push(format!("{rel_s}:{line}: fn {name} has {len} lines"));
            }
        }
    }
    assert!(
        long.is_empty(),
        "functions over {MAX_LINES} lines (split them along their structure):\n{}",
        long.join("\n")
    );
}

/// The files the budgets cover: sources, examples and benches of every crate.
fn covered_files() -> Vec<PathBuf> {
    let root = workspace();
    let mut files = Vec::new();
    for krate in ofmpc_policy::CRATES {
        for dir in ["src", "examples", "benches"] {
            rust_files(&root.join("crates").join(krate).join(dir), &mut files);
        }
    }
    files
}

/// `(file:line: fn name, length)` of every non-test function over `lines` lines outside the
/// kernels.
fn longer_than(lines: usize) -> Vec<(String, usize)> {
    let root = workspace();
    let mut long = Vec::new();
    for file in covered_files() {
        let rel = file.strip_prefix(&root).unwrap_or(&file);
        let rel_s = rel.to_string_lossy().replace('\\', "/");
        if KERNELS.iter().any(|k| rel_s.ends_with(k)) {
            continue;
        }
        let text = fs::read_to_string(&file).unwrap();
        let (code, _) = without_test_items(&code_only(&text));
        for (name, line, len) in functions(&code) {
            if len > lines {
                long.push((format!("{rel_s}:{line}: fn {name}"), len));
            }
        }
    }
    long.sort_by_key(|f| std::cmp::Reverse(f.1));
    long
}

#[test]
fn the_test_items_are_cut_before_counting() {
    let body = "    x();\n".repeat(LONG_LINES + 1);
    let text = format!(
        "fn a() {{\n{body}}}\n#[cfg(test)]\nmod tests {{\n    fn b() {{\n{body}    }}\n}}\n"
    );
    let (code, _) = without_test_items(&code_only(&text));
    let f: Vec<String> = functions(&code).into_iter().map(|f| f.0).collect();
    assert_eq!(f, ["a"]);
}

#[test]
fn few_functions_are_longer_than_sixty_lines() {
    let long = longer_than(LONG_LINES);
    assert!(
        long.len() <= MAX_LONG_FUNCTIONS,
        "{} functions over {LONG_LINES} lines, at most {MAX_LONG_FUNCTIONS} allowed (split where a named step reads clearer):\n{}",
        long.len(),
        long.iter()
            .map(|(f, n)| format!("{f} has {n} lines"))
            .collect::<Vec<_>>()
            .join("\n")
    );
}
