//! `sss_scene::load_str` (through `sss_render::scene`) on the input as UTF-8 scene TOML, with
//! an empty base directory and no mesh directories (a mesh the scene names is not found: the
//! `obj` target feeds the OBJ reader). A scene that loads must pass
//! `sss_render::check_scene`, which checks what the loader promises (finite geometry and
//! lights, valid indices, unit normals).
#![no_main]

mod common;

use libfuzzer_sys::fuzz_target;
use sss_render::scene::{LoadOptions, load_str};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let dir = common::work_dir("scene_toml");
    if let Ok(scene) = load_str(text, "fuzz.toml", Some(dir), &LoadOptions::default()) {
        if let Err(e) = sss_render::check_scene(&scene) {
            panic!("a loaded scene fails check_scene: {e}");
        }
    }
});
