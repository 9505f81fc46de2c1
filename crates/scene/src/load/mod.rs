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

    /// The mesh directories `dirs` (searched first), then those of `SSS_MESH_DIR`.
    pub fn with_dirs(dirs: &[PathBuf]) -> Self {
        let mut opts = LoadOptions::from_env();
        let mut all = dirs.to_vec();
        all.append(&mut opts.mesh_dirs);
        opts.mesh_dirs = all;
        opts
    }
}

/// Loads a scene file, or a built-in scene when `name` is not a file but names one, with the
/// mesh directories `mesh_dirs` (then `SSS_MESH_DIR`). `mesh_dir_hint` says how the caller's
/// user adds a mesh directory (`--mesh-dir DIR` in the CLI, `mesh_dirs=[...]` in Python): a
/// missing mesh's error names it ([`SceneError::with_mesh_hint`]), and a name that is neither a
/// file nor a built-in scene lists the built-in scenes.
pub fn load_named(
    name: &str,
    mesh_dirs: &[PathBuf],
    mesh_dir_hint: &str,
) -> Result<Scene, SceneError> {
    let opts = LoadOptions::with_dirs(mesh_dirs);
    let path = Path::new(name);
    let is_builtin = BUILTIN_SCENES.iter().any(|(n, _)| *n == name);
    let loaded = if !path.exists() && is_builtin {
        builtin(name, &opts)
    } else {
        load(path, &opts)
    };
    loaded.map_err(|mut e| {
        if e.kind == SceneErrorKind::Io && !path.exists() && !is_builtin {
            let names: Vec<&str> = BUILTIN_SCENES.iter().map(|(n, _)| *n).collect();
            e.message = format!(
                "{}; nor is it a built-in scene ({})",
                e.message,
                names.join(", ")
            );
        }
        e.with_mesh_hint(mesh_dir_hint)
    })
}

impl SceneError {
    /// The error with, when a mesh file was not found, how to add a directory: `hint` (the
    /// caller's own way, `--mesh-dir DIR` say) or the `SSS_MESH_DIR` environment variable.
    pub fn with_mesh_hint(mut self, hint: &str) -> SceneError {
        if self.kind == SceneErrorKind::MeshNotFound {
            self.message = format!(
                "{}; add a mesh directory with {hint} or the SSS_MESH_DIR environment variable",
                self.message
            );
        }
        self
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
