//! The scenes embedded in the crate (`scenes/*.toml`, through the `builtin` symlink) and
//! [`builtin`], which loads one by name.

use super::{LoadOptions, load_str};
use crate::{Scene, SceneError, SceneErrorKind};

/// The scenes embedded in the repository: (name, TOML text of `scenes/NAME.toml`). See
/// `scenes/README.md` for what each one tests.
pub const BUILTIN_SCENES: &[(&str, &str)] = &[
    ("sphere", include_str!("../../builtin/sphere.toml")),
    ("toad", include_str!("../../builtin/toad.toml")),
    ("picnic", include_str!("../../builtin/picnic.toml")),
    ("backlit", include_str!("../../builtin/backlit.toml")),
    ("slab", include_str!("../../builtin/slab.toml")),
    ("bunny", include_str!("../../builtin/bunny.toml")),
];

/// A built-in scene by name (one of [`BUILTIN_SCENES`]). Its mesh files, if any, are searched
/// in `opts.mesh_dirs`; when one is absent the error's kind is
/// [`SceneErrorKind::MeshNotFound`], so callers can skip the scene.
pub fn builtin(name: &str, opts: &LoadOptions) -> Result<Scene, SceneError> {
    let Some((_, text)) = BUILTIN_SCENES.iter().find(|(n, _)| *n == name) else {
        let names: Vec<&str> = BUILTIN_SCENES.iter().map(|(n, _)| *n).collect();
        return Err(SceneError {
            file: name.to_string(),
            line: None,
            key: None,
            message: format!(
                "unknown built-in scene `{name}`; the built-in scenes are {}",
                names.join(", ")
            ),
            kind: SceneErrorKind::Invalid,
        });
    };
    let mut scene = load_str(text, &format!("scenes/{name}.toml"), None, opts)?;
    scene.name = name.to_string();
    Ok(scene)
}
