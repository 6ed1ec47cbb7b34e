//! Workspace-wide policy checks on the source text (issue 34), kept out of the library crate so
//! that `cargo test -p ofmpc` does not fail on a change to the CLI or the bindings.
//!
//! [`source`] blanks comments and literals; [`imports`] builds the file-level import graph of a
//! crate and finds its cycles folder by folder. The tests in `tests/` apply them to every crate
//! of the workspace.

pub mod imports;
pub mod source;

use std::path::{Path, PathBuf};

/// The workspace root (two levels above this crate).
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The crates whose sources the policies cover.
pub const CRATES: &[&str] = &["ofmpc", "ofmpc-scenario", "ofmpc-cli", "ofmpc-py"];
