//! The OBJ reader of `sss_scene` on the input as a mesh file: a scene TOML naming `mesh.obj`
//! (written once per process) is loaded after the input is written to `mesh.obj` beside it.
//! A scene that loads must pass `sss_render::check_scene`.
#![no_main]

mod common;

use libfuzzer_sys::fuzz_target;
use sss_render::scene::{LoadOptions, load};
use std::sync::OnceLock;

/// A small scene whose one object is the mesh `mesh.obj`, translated and scaled so that the
/// transform's code runs too.
const SCENE: &str = r#"[camera]
position = [0.0, 0.5, 4.0]
target = [0.0, 0.0, 0.0]
fov = 35.0
resolution = [16, 12]

[[lights]]
type = "point"
position = [2.0, 3.0, 3.0]
intensity = 50.0

[materials.m]
type = "translucent"
model = "better-dipole"
preset = "skin1"
units_per_mm = 0.05

[[objects]]
name = "mesh"
material = "m"
shape = "mesh"
file = "mesh.obj"
transform = { translate = [0.0, -0.2, 0.0], scale = 1.5 }
"#;

fuzz_target!(|data: &[u8]| {
    let dir = common::work_dir("obj");
    static SCENE_FILE: OnceLock<std::path::PathBuf> = OnceLock::new();
    let scene = SCENE_FILE.get_or_init(|| {
        let p = dir.join("scene.toml");
        common::write(&p, SCENE.as_bytes());
        p
    });
    common::write(&dir.join("mesh.obj"), data);
    if let Ok(scene) = load(scene, &LoadOptions::default()) {
        if let Err(e) = sss_render::check_scene(&scene) {
            panic!("a loaded scene fails check_scene: {e}");
        }
    }
});
