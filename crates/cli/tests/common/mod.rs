//! Helpers shared by the `sss` binary's test files: run it and read its output.

// Each test file uses some of these.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
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

/// A scene file in `dir`: a skin1 sphere under a point light at `width` × `height` pixels.
pub fn sphere_scene(dir: &Path, name: &str, width: u32, height: u32) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(
        &path,
        format!(
            r#"
[camera]
position = [0.0, 0.0, 4.0]
target = [0.0, 0.0, 0.0]
fov = 35.0
resolution = [{width}, {height}]

[[lights]]
type = "point"
position = [2.0, 2.0, 3.0]
intensity = 10.0

[materials.skin]
type = "translucent"
model = "better-dipole"
preset = "skin1"
units_per_mm = 0.1

[[objects]]
shape = "sphere"
radius = 1.0
subdivisions = 3
material = "skin"
"#
        ),
    )
    .unwrap();
    path
}
