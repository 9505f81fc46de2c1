//! A whole scene from its parsed file: the camera, the lights, every material, then the
//! objects, each resolving its material by name; materials no object uses are dropped with a
//! warning.

use super::context::{Ctx, list};
use crate::format::{RadiusDef, SceneFile};
use crate::{Material, MaterialKind, Object, Scene, SceneError};
use std::collections::HashMap;

impl Ctx<'_> {
    pub(super) fn scene(mut self, def: SceneFile, name: String) -> Result<Scene, SceneError> {
        let camera = self.camera(&def.camera)?;
        if def.lights.is_empty() {
            return Err(
                self.err_scene("the scene has no lights; add at least one [[lights]] table")
            );
        }
        let lights = def
            .lights
            .iter()
            .enumerate()
            .map(|(i, l)| self.light(l, &format!("lights[{i}]")))
            .collect::<Result<Vec<_>, _>>()?;
        let mut all_materials: Vec<(String, MaterialKind)> = Vec::new();
        for (mname, m) in &def.materials {
            all_materials.push((
                mname.clone(),
                self.material(m, &format!("materials.{mname}"))?,
            ));
        }
        if def.objects.is_empty() {
            return Err(
                self.err_scene("the scene has no objects; add at least one [[objects]] table")
            );
        }
        let mut materials: Vec<Material> = Vec::new();
        let mut used: HashMap<&str, usize> = HashMap::new();
        let mut objects = Vec::with_capacity(def.objects.len());
        for (i, o) in def.objects.iter().enumerate() {
            let path = format!("objects[{i}]");
            let Some(pos) = all_materials.iter().position(|(n, _)| *n == o.material) else {
                let names: Vec<&str> = all_materials.iter().map(|(n, _)| n.as_str()).collect();
                let defined = if names.is_empty() {
                    "no materials are defined".to_string()
                } else {
                    format!("the materials are {}", list(&names))
                };
                return Err(self.err(
                    &format!("{path}.material"),
                    format!("unknown material `{}`; {defined}", o.material),
                ));
            };
            let index = *used
                .entry(all_materials[pos].0.as_str())
                .or_insert_with(|| {
                    materials.push(Material {
                        name: all_materials[pos].0.clone(),
                        kind: all_materials[pos].1.clone(),
                    });
                    materials.len() - 1
                });
            let obj_name = o.name.clone().unwrap_or_else(|| format!("object{i}"));
            let (mesh, curvature) = self.object_mesh(o, &path, &obj_name)?;
            objects.push(Object {
                name: obj_name,
                material: index,
                mesh,
                curvature,
            });
        }
        // `sphere_radius = "auto"` needs the objects: resolved here, from the parsed table.
        for (index, material) in materials.iter_mut().enumerate() {
            let auto = def.materials.get(&material.name).is_some_and(
                |m| matches!(&m.sphere_radius, Some(RadiusDef::Keyword(k)) if k == "auto"),
            );
            if let MaterialKind::Translucent(t) = &mut material.kind
                && auto
            {
                t.sphere_radius = Some(self.auto_sphere_radius(&objects, index, &material.name)?);
            }
        }
        for (mname, _) in &all_materials {
            if !used.contains_key(mname.as_str()) {
                self.warnings.push(format!(
                    "{}: material `{mname}` is not used by any object (dropped)",
                    self.file
                ));
            }
        }
        Ok(Scene {
            name,
            path: None,
            camera,
            lights,
            materials,
            objects,
            warnings: self.warnings,
        })
    }

    /// `sphere_radius = "auto"`: [`crate::Scene::volume_radius`] of material `index`, or an
    /// error when its objects enclose no volume.
    fn auto_sphere_radius(
        &self,
        objects: &[Object],
        index: usize,
        name: &str,
    ) -> Result<f64, SceneError> {
        crate::volume_radius(objects, index).ok_or_else(|| {
            self.err(
                &format!("materials.{name}.sphere_radius"),
                "\"auto\" takes 3 × volume / area of the material's objects, and they enclose \
                 no volume (open or inside-out meshes): give a length instead",
            )
        })
    }
}
