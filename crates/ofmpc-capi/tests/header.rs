//! The committed header is what cbindgen makes of the code (a stale header
//! fails), with the pinned cbindgen; its version macros are the crate's.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The cbindgen version the header is generated with (cbindgen.toml, .ci/run).
const CBINDGEN_VERSION: &str = "0.29.4";

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// cbindgen: `$CBINDGEN`, else `~/.cargo/bin/cbindgen`, else on PATH.
fn cbindgen() -> PathBuf {
    if let Some(p) = std::env::var_os("CBINDGEN") {
        return p.into();
    }
    let home = std::env::var_os("HOME")
        .map(PathBuf::from)
        .unwrap_or_default();
    let local = home.join(".cargo/bin/cbindgen");
    if local.is_file() {
        local
    } else {
        "cbindgen".into()
    }
}

#[test]
fn the_committed_header_is_what_the_pinned_cbindgen_generates() {
    let bin = cbindgen();
    let version = Command::new(&bin)
        .arg("--version")
        .output()
        .unwrap_or_else(|e| {
            panic!(
                "cbindgen not runnable ({}): {e}; install it with \
             `cargo install cbindgen --version {CBINDGEN_VERSION} --locked`",
                bin.display()
            )
        });
    let version = String::from_utf8_lossy(&version.stdout);
    assert_eq!(
        version.trim(),
        format!("cbindgen {CBINDGEN_VERSION}"),
        "the header is generated with cbindgen {CBINDGEN_VERSION}"
    );
    let dir = crate_dir();
    let fresh = std::env::temp_dir().join(format!("ofmpc-header-{}.h", std::process::id()));
    let status = Command::new(&bin)
        .args(["-q", "--config"])
        .arg(dir.join("cbindgen.toml"))
        .args(["--crate", "ofmpc-capi", "--output"])
        .arg(&fresh)
        .arg(&dir)
        .status()
        .expect("cbindgen runs");
    assert!(status.success(), "cbindgen failed");
    let fresh_text = std::fs::read_to_string(&fresh).expect("generated header");
    let _ = std::fs::remove_file(&fresh);
    let committed = std::fs::read_to_string(dir.join("include/ofmpc.h")).expect("include/ofmpc.h");
    assert!(
        fresh_text == committed,
        "include/ofmpc.h is stale: regenerate it (the command is in crates/ofmpc-capi/cbindgen.toml)"
    );
}

/// `#define NAME value` in `header`.
fn define<'a>(header: &'a str, name: &str) -> &'a str {
    let prefix = format!("#define {name} ");
    header
        .lines()
        .find_map(|l| l.strip_prefix(prefix.as_str()))
        .unwrap_or_else(|| panic!("{name} is not defined in the header"))
        .trim()
}

#[test]
fn the_version_macros_and_ofmpc_version_are_the_crates() {
    let header = std::fs::read_to_string(crate_dir().join("include/ofmpc.h")).unwrap();
    assert_eq!(
        define(&header, "OFMPC_VERSION_MAJOR"),
        env!("CARGO_PKG_VERSION_MAJOR")
    );
    assert_eq!(
        define(&header, "OFMPC_VERSION_MINOR"),
        env!("CARGO_PKG_VERSION_MINOR")
    );
    assert_eq!(
        define(&header, "OFMPC_VERSION_PATCH"),
        env!("CARGO_PKG_VERSION_PATCH")
    );
    assert_eq!(
        define(&header, "OFMPC_VERSION"),
        format!("\"{}\"", env!("CARGO_PKG_VERSION"))
    );
    let v = unsafe { std::ffi::CStr::from_ptr(ofmpc_capi::ofmpc_version()) };
    assert_eq!(v.to_str().unwrap(), env!("CARGO_PKG_VERSION"));
}

#[test]
fn the_cpp_wrapper_and_the_examples_name_the_header() {
    let hpp = std::fs::read_to_string(crate_dir().join("include/ofmpc.hpp")).unwrap();
    assert!(hpp.contains("#include \"ofmpc.h\""));
    assert!(Path::new(&crate_dir().join("examples")).is_dir());
}
