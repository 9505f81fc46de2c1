//! Where a mesh file named in a scene is looked for: as given if absolute, else next to the
//! scene file, then in each mesh directory.

use super::context::Ctx;
use crate::{SceneError, SceneErrorKind};
use std::path::{Path, PathBuf};

impl Ctx<'_> {
    /// Resolves a mesh file name: as given if absolute; else next to the scene file, then in
    /// each of `opts.mesh_dirs`.
    pub(super) fn find_mesh(&self, file: &str, key: &str) -> Result<PathBuf, SceneError> {
        if file.trim().is_empty() {
            return Err(self.err(key, "the mesh file name is empty"));
        }
        let p = Path::new(file);
        let mut dirs: Vec<&Path> = Vec::new();
        if !p.is_absolute() {
            if let Some(b) = self.base_dir {
                dirs.push(b);
            }
            dirs.extend(self.opts.mesh_dirs.iter().map(PathBuf::as_path));
        }
        let candidates: Vec<PathBuf> = if p.is_absolute() {
            vec![p.to_path_buf()]
        } else {
            dirs.iter().map(|d| d.join(p)).collect()
        };
        if let Some(found) = candidates.iter().find(|c| c.exists()) {
            return Ok(found.clone());
        }
        let searched = if p.is_absolute() {
            "it does not exist".to_string()
        } else if dirs.is_empty() {
            "no mesh directory to search".to_string()
        } else {
            // Each directory once, in the order searched (the scene's own directory and a
            // mesh directory are often the same).
            let mut shown: Vec<String> = Vec::new();
            for d in &dirs {
                let d = if d.as_os_str().is_empty() {
                    ".".to_string()
                } else {
                    d.display().to_string()
                };
                if !shown.contains(&d) {
                    shown.push(d);
                }
            }
            format!("searched: {}", shown.join(", "))
        };
        Err(SceneError {
            kind: SceneErrorKind::MeshNotFound,
            ..self.err(key, format!("mesh file `{file}` not found; {searched}"))
        })
    }
}
