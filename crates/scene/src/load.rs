//! Loading and validating scene files (TOML, documented key by key in `scenes/README.md`).
//!
//! [`load`] reads a file, [`load_str`] a string, [`builtin`] one of [`BUILTIN_SCENES`]. Every
//! problem comes back as a [`SceneError`] naming the file, the line and key where known, and
//! what is wrong; nothing panics on bad input. Non-fatal findings (degenerate triangles
//! dropped, unused materials, a mesh whose winding was reversed) go to [`Scene::warnings`].
//!
//! The loader is split by concern: `builtin_scenes` holds the embedded scenes, `context` the
//! loading state and how errors find their line and key, `checks` the value checks every
//! table shares; `assemble` puts a scene together from `camera`, `lights`, `materials` (with
//! their `textures`) and `objects`, whose mesh files `mesh_search` finds and `obj` reads.

mod assemble;
mod builtin_scenes;
mod camera;
mod checks;
mod context;
mod lights;
mod materials;
mod mesh_search;
mod obj;
mod objects;
mod textures;

pub use builtin_scenes::{BUILTIN_SCENES, builtin};

use crate::format::{SceneFile, SpanIndex};
use crate::{Scene, SceneError, SceneErrorKind};
use context::Ctx;
use std::path::{Path, PathBuf};

/// Where to look for meshes besides the scene file's directory.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Directories searched, in order, for mesh files not found next to the scene file.
    pub mesh_dirs: Vec<PathBuf>,
}

impl LoadOptions {
    /// Mesh directories from the environment variable `SSS_MESH_DIR`, split like `PATH`
    /// (`:` on Unix, `;` on Windows); none when it is unset or empty.
    pub fn from_env() -> Self {
        let mesh_dirs = std::env::var_os("SSS_MESH_DIR")
            .map(|v| {
                std::env::split_paths(&v)
                    .filter(|p| !p.as_os_str().is_empty())
                    .collect()
            })
            .unwrap_or_default();
        LoadOptions { mesh_dirs }
    }
}

/// Loads a scene file. Relative mesh paths are resolved against the file's directory first,
/// then `opts.mesh_dirs`. The scene's name is the file stem.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Scene, SceneError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| SceneError {
        file: file.clone(),
        line: None,
        key: None,
        message: format!("cannot read the scene file: {e}"),
        kind: SceneErrorKind::Io,
    })?;
    let text = String::from_utf8(bytes).map_err(|e| SceneError {
        file: file.clone(),
        line: None,
        key: None,
        message: format!("the scene file is not UTF-8 text: {e}"),
        kind: SceneErrorKind::Invalid,
    })?;
    let base = path.parent().unwrap_or(Path::new(""));
    let mut scene = load_str(&text, &file, Some(base), opts)?;
    scene.path = Some(path.to_path_buf());
    Ok(scene)
}

/// Loads a scene from TOML text; `file` names it in errors (its stem becomes the scene's
/// name), `base_dir` resolves relative mesh paths (before `opts.mesh_dirs`).
pub fn load_str(
    text: &str,
    file: &str,
    base_dir: Option<&Path>,
    opts: &LoadOptions,
) -> Result<Scene, SceneError> {
    let mut ctx = Ctx {
        file,
        spans: SpanIndex::empty(text),
        base_dir,
        opts,
        warnings: Vec::new(),
    };
    let doc = toml::de::DeTable::parse(text).map_err(|e| ctx.toml_error(&e))?;
    ctx.spans = SpanIndex::new(text, doc.get_ref());
    let def: SceneFile = toml::from_str(text).map_err(|e| ctx.toml_error(&e))?;
    let name = Path::new(file)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| file.to_string());
    ctx.scene(def, name)
}
