//! Loading the scenes of a run (built-in names or scene-file paths), halved in resolution with
//! `--quick`; scenes whose mesh is missing are skipped with a message.

use super::super::{Context, Error};
use sss_render::scene::{self, LoadOptions, Scene, SceneErrorKind};
use std::path::{Path, PathBuf};

/// The scenes of a run: names of built-in scenes or paths to scene files. Scenes whose mesh is
/// missing are skipped with a message.
/// Loaded scenes with their TOML text (the reference cache key), and skip messages.
pub(in super::super) type LoadedScenes = (Vec<(Scene, String)>, Vec<String>);

pub(in super::super) fn load_scenes(
    ctx: &Context<'_>,
    names: &[String],
) -> Result<LoadedScenes, Error> {
    let cfg = ctx.config;
    let opts = LoadOptions {
        mesh_dirs: cfg.mesh_dirs.clone(),
    };
    let mut out = Vec::new();
    let mut skipped = Vec::new();
    for name in names {
        let path = Path::new(name);
        let (loaded, text) =
            if !path.exists() && scene::BUILTIN_SCENES.iter().any(|(n, _)| n == name) {
                let text = scene::BUILTIN_SCENES
                    .iter()
                    .find(|(n, _)| n == name)
                    .map(|(_, t)| t.to_string())
                    .unwrap_or_default();
                (scene::builtin(name, &opts), text)
            } else {
                let text = std::fs::read_to_string(path).unwrap_or_default();
                (scene::load(path, &opts), text)
            };
        match loaded {
            Ok(mut s) => {
                if cfg.quick {
                    // Half resolution: a quarter of the pixels.
                    s.camera.width = (s.camera.width / 2).max(1);
                    s.camera.height = (s.camera.height / 2).max(1);
                }
                out.push((s, text));
            }
            Err(e) if e.kind == SceneErrorKind::MeshNotFound => {
                (ctx.log)(&format!("scene {name}: skipped ({e})"));
                skipped.push(format!("`{name}`: {e}"));
            }
            Err(e) => return Err(Error(format!("scene {name}: {e}"))),
        }
    }
    Ok((out, skipped))
}

/// Default mesh directories: `SSS_MESH_DIR` and the shared meshes next to the workspace.
pub fn default_mesh_dirs(workspace: &Path) -> Vec<PathBuf> {
    let mut dirs = LoadOptions::from_env().mesh_dirs;
    if let Some(parent) = workspace.parent() {
        dirs.push(parent.join("shared").join("meshes"));
    }
    dirs
}
