//! Loading and validating scene files. Being written.

use super::{Scene, SceneError, SceneErrorKind};
use std::path::{Path, PathBuf};

/// Where to look for meshes besides the scene file's directory.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Directories searched, in order, for mesh files not found next to the scene file.
    pub mesh_dirs: Vec<PathBuf>,
}

/// The scenes embedded in the repository: (name, TOML text).
pub const BUILTIN_SCENES: &[(&str, &str)] = &[];

/// Loads a scene file.
pub fn load(path: &Path, _opts: &LoadOptions) -> Result<Scene, SceneError> {
    Err(SceneError {
        file: path.display().to_string(),
        line: None,
        key: None,
        message: "scene loading is not written yet".into(),
        kind: SceneErrorKind::Invalid,
    })
}

/// Loads a scene from TOML text; `file` names it in errors, `base_dir` resolves relative mesh
/// paths.
pub fn load_str(
    _text: &str,
    file: &str,
    _base_dir: Option<&Path>,
    _opts: &LoadOptions,
) -> Result<Scene, SceneError> {
    Err(SceneError {
        file: file.into(),
        line: None,
        key: None,
        message: "scene loading is not written yet".into(),
        kind: SceneErrorKind::Invalid,
    })
}

/// A built-in scene by name.
pub fn builtin(name: &str, opts: &LoadOptions) -> Result<Scene, SceneError> {
    load_str("", name, None, opts)
}
