//! Helpers shared by the end-to-end tests of the built `lash` binary.
#![allow(dead_code)] // each test file uses its own subset

use std::path::Path;
use std::process::{Command, Output};

use serde_json::Value;

/// Runs the built `lash` binary with `args` in `cwd`.
pub fn lash(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lash"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("run lash")
}

/// Runs `lash`, asserts exit code 0 and returns its standard output.
pub fn ok(args: &[&str], cwd: &Path) -> String {
    let o = lash(args, cwd);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Reads a JSON file.
pub fn json(p: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}
