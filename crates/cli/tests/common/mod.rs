//! Helpers shared by the `sss` binary's test files: run it and read its output.

// Each test file uses some of these.
#![allow(dead_code)]

use std::process::{Command, Output};

/// Runs the `sss` binary with `args`.
pub fn sss(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sss"))
        .args(args)
        .output()
        .expect("run sss")
}

/// Its stdout as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8(o.stdout.clone()).expect("utf-8 stdout")
}

/// Its stderr as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8(o.stderr.clone()).expect("utf-8 stderr")
}
