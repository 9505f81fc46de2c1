//! Loading and validating scene files (TOML, documented key by key in `scenes/README.md`).
//!
//! [`load`] reads a file, [`load_str`] a string, [`builtin`] one of [`BUILTIN_SCENES`]. Every
//! problem comes back as a [`SceneError`] naming the file, the line and key where known, and
//! what is wrong; nothing panics on bad input. Non-fatal findings (degenerate triangles
//! dropped, unused materials, a mesh whose winding was reversed) go to [`Scene::warnings`].

mod obj;

use super::format::{
    CameraDef, Keys, LightDef, MaterialDef, ObjectDef, SceneFile, SpanIndex, TextureDef,
    TransformDef, Triple,
};
use super::shapes::{self, RawMesh, Transform};
use super::{
    Camera, Light, Material, MaterialKind, Object, Scene, SceneError, SceneErrorKind, Texture,
    Translucent,
};
use glam::DVec3;
use sss_bssrdf::presets::{PRESET_ETA, PRESETS};
use sss_bssrdf::{Medium, ModelKind, Rgb};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::str::FromStr;

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

/// The scenes embedded in the repository: (name, TOML text of `scenes/NAME.toml`). See
/// `scenes/README.md` for what each one tests.
pub const BUILTIN_SCENES: &[(&str, &str)] = &[
    ("sphere", include_str!("../builtin/sphere.toml")),
    ("toad", include_str!("../builtin/toad.toml")),
    ("picnic", include_str!("../builtin/picnic.toml")),
    ("backlit", include_str!("../builtin/backlit.toml")),
    ("slab", include_str!("../builtin/slab.toml")),
    ("bunny", include_str!("../builtin/bunny.toml")),
];

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

/// Limits that keep a typo from asking for billions of triangles.
const MAX_SPHERE_SUBDIVISIONS: u32 = 8;
const MAX_PLANE_SUBDIVISIONS: u32 = 1024;
const MAX_TORUS_SEGMENTS: i64 = 4096;

/// Loading state: the file, its span index, where meshes are searched, warnings so far.
struct Ctx<'a> {
    file: &'a str,
    spans: SpanIndex,
    base_dir: Option<&'a Path>,
    opts: &'a LoadOptions,
    warnings: Vec<String>,
}

/// A number as written in messages (`0.5`, `NaN`, `inf`).
fn fmt_num(v: f64) -> String {
    format!("{v}")
}

fn list(items: &[&str]) -> String {
    items
        .iter()
        .map(|s| format!("`{s}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

impl Ctx<'_> {
    /// An `Invalid` error at key path `key` (its line looked up in the document).
    fn err(&self, key: &str, message: impl Into<String>) -> SceneError {
        SceneError {
            file: self.file.to_string(),
            line: self.spans.line(key),
            key: Some(key.to_string()),
            message: message.into(),
            kind: SceneErrorKind::Invalid,
        }
    }

    /// An error of the scene as a whole (no key).
    fn err_scene(&self, message: impl Into<String>) -> SceneError {
        SceneError {
            file: self.file.to_string(),
            line: None,
            key: None,
            message: message.into(),
            kind: SceneErrorKind::Invalid,
        }
    }

    /// A toml syntax or structure error: its message, the line of its span, and the key it
    /// points at (for `unknown field` and `missing field`, the key named in the message).
    fn toml_error(&self, e: &toml::de::Error) -> SceneError {
        let message = e.message().trim().to_string();
        let (mut line, mut key) = (None, None);
        if let Some(span) = e.span() {
            line = Some(self.spans.line_of_offset(span.start));
            key = self.spans.path_at(&span).map(str::to_string);
        }
        if let Some(missing) = backticked(&message, "missing field `") {
            let path = match &key {
                Some(k) => format!("{k}.{missing}"),
                None => missing.to_string(),
            };
            key = Some(path);
        } else if let Some(unknown) = backticked(&message, "unknown field `") {
            // The span is the key itself; make sure the path names it.
            if key.as_deref().is_none_or(|k| !k.ends_with(unknown)) {
                key = Some(unknown.to_string());
            }
        }
        SceneError {
            file: self.file.to_string(),
            line,
            key,
            message,
            kind: SceneErrorKind::Invalid,
        }
    }

    /// Rejects keys that are present but do not belong to this `type`/`shape`.
    fn check_keys(
        &self,
        path: &str,
        present: &[&'static str],
        allowed: &[&str],
        what: &str,
    ) -> Result<(), SceneError> {
        if let Some(k) = present.iter().find(|k| !allowed.contains(k)) {
            return Err(self.err(
                &format!("{path}.{k}"),
                format!(
                    "`{k}` does not apply to {what} (its keys: {})",
                    list(allowed)
                ),
            ));
        }
        Ok(())
    }

    fn required<T: Copy>(
        &self,
        v: Option<T>,
        path: &str,
        key: &str,
        what: &str,
    ) -> Result<T, SceneError> {
        v.ok_or_else(|| self.err(&format!("{path}.{key}"), format!("{what} needs `{key}`")))
    }

    fn finite_vec(&self, v: [f64; 3], key: &str) -> Result<DVec3, SceneError> {
        if let Some(bad) = v.iter().find(|x| !x.is_finite()) {
            return Err(self.err(key, format!("must be finite, got {}", fmt_num(*bad))));
        }
        Ok(DVec3::from_array(v))
    }

    fn nonzero_vec(&self, v: [f64; 3], key: &str) -> Result<DVec3, SceneError> {
        let d = self.finite_vec(v, key)?;
        if d.length_squared() == 0.0 || !d.length_squared().is_finite() {
            return Err(self.err(key, "must be a non-zero vector"));
        }
        Ok(d)
    }

    /// A radiometric colour: finite and ≥ 0 per channel.
    fn emission(&self, c: Triple, key: &str) -> Result<Rgb, SceneError> {
        for (ch, v) in c.0.iter().enumerate() {
            if !v.is_finite() || *v < 0.0 {
                return Err(self.err(
                    key,
                    format!(
                        "must be finite and non-negative, got {} in channel {ch}",
                        fmt_num(*v)
                    ),
                ));
            }
        }
        Ok(c.0)
    }

    /// A reflectance-like colour in [0, 1] per channel.
    fn unit_colour(&self, c: Triple, key: &str) -> Result<Rgb, SceneError> {
        for (ch, v) in c.0.iter().enumerate() {
            if !(0.0..=1.0).contains(v) {
                return Err(self.err(
                    key,
                    format!("must be in [0, 1], got {} in channel {ch}", fmt_num(*v)),
                ));
            }
        }
        Ok(c.0)
    }

    fn positive(&self, v: f64, key: &str) -> Result<f64, SceneError> {
        if !(v.is_finite() && v > 0.0) {
            return Err(self.err(
                key,
                format!("must be a finite number > 0, got {}", fmt_num(v)),
            ));
        }
        Ok(v)
    }

    // -----------------------------------------------------------------------------------------

    fn scene(mut self, def: SceneFile, name: String) -> Result<Scene, SceneError> {
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
            let mesh = self.object_mesh(o, &path, &obj_name)?;
            objects.push(Object {
                name: obj_name,
                material: index,
                mesh,
            });
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

    fn camera(&self, c: &CameraDef) -> Result<Camera, SceneError> {
        let position = self.finite_vec(c.position, "camera.position")?;
        let target = self.finite_vec(c.target, "camera.target")?;
        let up = self.nonzero_vec(c.up.unwrap_or([0.0, 1.0, 0.0]), "camera.up")?;
        if !(c.fov.is_finite() && c.fov > 0.0 && c.fov < 180.0) {
            return Err(self.err(
                "camera.fov",
                format!(
                    "the vertical field of view must be in (0, 180) degrees, got {}",
                    fmt_num(c.fov)
                ),
            ));
        }
        if c.resolution.contains(&0) {
            return Err(self.err(
                "camera.resolution",
                format!(
                    "width and height must be at least 1, got [{}, {}]",
                    c.resolution[0], c.resolution[1]
                ),
            ));
        }
        let pixel_samples = c.pixel_samples.unwrap_or(1);
        if pixel_samples == 0 {
            return Err(self.err("camera.pixel_samples", "must be at least 1"));
        }
        let view = target - position;
        if view.length_squared() == 0.0 {
            return Err(self.err(
                "camera.target",
                "equals camera.position, so the view direction is undefined",
            ));
        }
        if view.normalize().cross(up.normalize()).length() < 1e-6 {
            return Err(self.err(
                "camera.up",
                "is parallel to the view direction (target - position)",
            ));
        }
        Ok(Camera {
            position,
            target,
            up,
            vfov_deg: c.fov,
            width: c.resolution[0],
            height: c.resolution[1],
            pixel_samples,
        })
    }

    fn light(&self, l: &LightDef, path: &str) -> Result<Light, SceneError> {
        let types = ["point", "directional", "quad", "environment"];
        let present = l.present();
        let what = format!("a {} light", l.kind);
        let key = |k: &str| format!("{path}.{k}");
        match l.kind.as_str() {
            "point" => {
                self.check_keys(path, &present, &["position", "intensity"], &what)?;
                let p = self.required(l.position, path, "position", &what)?;
                let i = self.required(l.intensity, path, "intensity", &what)?;
                Ok(Light::Point {
                    position: self.finite_vec(p, &key("position"))?,
                    intensity: self.emission(i, &key("intensity"))?,
                })
            }
            "directional" => {
                self.check_keys(path, &present, &["direction", "irradiance"], &what)?;
                let d = self.required(l.direction, path, "direction", &what)?;
                let e = self.required(l.irradiance, path, "irradiance", &what)?;
                Ok(Light::Directional {
                    direction: self.nonzero_vec(d, &key("direction"))?.normalize(),
                    irradiance: self.emission(e, &key("irradiance"))?,
                })
            }
            "quad" => {
                self.check_keys(
                    path,
                    &present,
                    &["corner", "edge_u", "edge_v", "radiance"],
                    &what,
                )?;
                let c = self.required(l.corner, path, "corner", &what)?;
                let u = self.required(l.edge_u, path, "edge_u", &what)?;
                let v = self.required(l.edge_v, path, "edge_v", &what)?;
                let r = self.required(l.radiance, path, "radiance", &what)?;
                let corner = self.finite_vec(c, &key("corner"))?;
                let edge_u = self.nonzero_vec(u, &key("edge_u"))?;
                let edge_v = self.nonzero_vec(v, &key("edge_v"))?;
                if edge_u.cross(edge_v).length() <= 1e-12 * edge_u.length() * edge_v.length() {
                    return Err(self.err(
                        &key("edge_v"),
                        "is parallel to edge_u, so the quad has no area",
                    ));
                }
                Ok(Light::Quad {
                    corner,
                    edge_u,
                    edge_v,
                    radiance: self.emission(r, &key("radiance"))?,
                })
            }
            "environment" => {
                self.check_keys(path, &present, &["radiance"], &what)?;
                let r = self.required(l.radiance, path, "radiance", &what)?;
                Ok(Light::Environment {
                    radiance: self.emission(r, &key("radiance"))?,
                })
            }
            other => Err(self.err(
                &key("type"),
                format!(
                    "unknown light type `{other}`; expected one of {}",
                    list(&types)
                ),
            )),
        }
    }

    fn material(&self, m: &MaterialDef, path: &str) -> Result<MaterialKind, SceneError> {
        let present = m.present();
        let key = |k: &str| format!("{path}.{k}");
        match m.kind.as_str() {
            "translucent" => {
                let what = "a translucent material";
                self.check_keys(
                    path,
                    &present,
                    &[
                        "model",
                        "preset",
                        "sigma_a",
                        "sigma_s",
                        "g",
                        "eta",
                        "units_per_mm",
                        "texture",
                    ],
                    what,
                )?;
                let model = match &m.model {
                    None => ModelKind::BetterDipole,
                    Some(name) => ModelKind::from_str(name).map_err(|_| {
                        let names: Vec<&str> = ModelKind::ALL.iter().map(|k| k.name()).collect();
                        self.err(
                            &key("model"),
                            format!("unknown model `{name}`; expected one of {}", list(&names)),
                        )
                    })?,
                };
                let g = m.g.unwrap_or(0.0);
                if !(g.is_finite() && g.abs() < 1.0) {
                    return Err(self.err(
                        &key("g"),
                        format!("the anisotropy must be in (-1, 1), got {}", fmt_num(g)),
                    ));
                }
                let eta = m.eta.unwrap_or(PRESET_ETA);
                if !(eta.is_finite() && eta > 0.0) {
                    return Err(self.err(
                        &key("eta"),
                        format!(
                            "the relative index of refraction must be finite and > 0, got {}",
                            fmt_num(eta)
                        ),
                    ));
                }
                let (sigma_a, sigma_s) = match (&m.preset, m.sigma_a, m.sigma_s) {
                    (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
                        let k = if m.sigma_a.is_some() {
                            "sigma_a"
                        } else {
                            "sigma_s"
                        };
                        return Err(self.err(
                            &key(k),
                            "give either `preset` or `sigma_a` and `sigma_s`, not both",
                        ));
                    }
                    (Some(name), None, None) => {
                        let p = sss_bssrdf::presets::find(name).map_err(|_| {
                            let names: Vec<&str> = PRESETS.iter().map(|p| p.name).collect();
                            self.err(
                                &key("preset"),
                                format!(
                                    "unknown preset `{name}`; expected one of {}",
                                    list(&names)
                                ),
                            )
                        })?;
                        // The table gives reduced scattering; keep it under the chosen g.
                        (p.sigma_a, p.sigma_s_reduced.map(|s| s / (1.0 - g)))
                    }
                    (None, a, s) => {
                        let a = a.ok_or_else(|| {
                            self.err(
                                &key("sigma_a"),
                                "a translucent material needs `preset` or `sigma_a` and `sigma_s`",
                            )
                        })?;
                        let s = s.ok_or_else(|| {
                            self.err(
                                &key("sigma_s"),
                                "a translucent material needs `preset` or `sigma_a` and `sigma_s`",
                            )
                        })?;
                        (
                            self.coefficient(a, &key("sigma_a"))?,
                            self.coefficient(s, &key("sigma_s"))?,
                        )
                    }
                };
                let medium = Medium::new(sigma_a, sigma_s, g, eta)
                    .map_err(|e| self.err(path, format!("invalid medium: {e}")))?;
                let upm = self.required(m.units_per_mm, path, "units_per_mm", what)?;
                if !(upm.is_finite() && upm > 0.0) {
                    return Err(self.err(
                        &key("units_per_mm"),
                        format!(
                            "scene units per millimetre must be finite and > 0, got {}",
                            fmt_num(upm)
                        ),
                    ));
                }
                let texture = match &m.texture {
                    Some(t) => Some(self.texture(t, &key("texture"))?),
                    None => None,
                };
                Ok(MaterialKind::Translucent(Translucent {
                    model,
                    medium,
                    units_per_mm: upm,
                    texture,
                }))
            }
            "diffuse" => {
                let what = "a diffuse material";
                self.check_keys(path, &present, &["albedo", "texture"], what)?;
                let albedo = self.required(m.albedo, path, "albedo", what)?;
                let albedo = self.unit_colour(albedo, &key("albedo"))?;
                let texture = match &m.texture {
                    Some(t) => Some(self.texture(t, &key("texture"))?),
                    None => None,
                };
                Ok(MaterialKind::Diffuse { albedo, texture })
            }
            other => Err(self.err(
                &key("type"),
                format!("unknown material type `{other}`; expected `translucent` or `diffuse`"),
            )),
        }
    }

    /// A coefficient in 1/mm: finite and ≥ 0 per channel.
    fn coefficient(&self, c: Triple, key: &str) -> Result<Rgb, SceneError> {
        for (ch, v) in c.0.iter().enumerate() {
            if !v.is_finite() || *v < 0.0 {
                return Err(self.err(
                    key,
                    format!(
                        "coefficients must be finite and non-negative (1/mm), got {} in channel {ch}",
                        fmt_num(*v)
                    ),
                ));
            }
        }
        Ok(c.0)
    }

    fn texture(&self, t: &TextureDef, path: &str) -> Result<Texture, SceneError> {
        let present = t.present();
        let key = |k: &str| format!("{path}.{k}");
        let what = format!("a {} texture", t.kind);
        let colours = |s: &Self| -> Result<(Rgb, Rgb), SceneError> {
            let a = s.required(t.a, path, "a", &what)?;
            let b = s.required(t.b, path, "b", &what)?;
            Ok((s.unit_colour(a, &key("a"))?, s.unit_colour(b, &key("b"))?))
        };
        match t.kind.as_str() {
            "checker" => {
                self.check_keys(path, &present, &["scale", "a", "b"], &what)?;
                let scale = self.required(t.scale, path, "scale", &what)?;
                let scale = self.positive(scale, &key("scale"))?;
                let (a, b) = colours(self)?;
                Ok(Texture::Checker { scale, a, b })
            }
            "stripes" => {
                self.check_keys(path, &present, &["axis", "period", "a", "b"], &what)?;
                let axis = self.required(t.axis, path, "axis", &what)?;
                let axis = self.nonzero_vec(axis, &key("axis"))?.normalize();
                let period = self.required(t.period, path, "period", &what)?;
                let period = self.positive(period, &key("period"))?;
                let (a, b) = colours(self)?;
                Ok(Texture::Stripes { axis, period, a, b })
            }
            "noise" => {
                self.check_keys(path, &present, &["scale", "seed", "a", "b"], &what)?;
                let scale = self.required(t.scale, path, "scale", &what)?;
                let scale = self.positive(scale, &key("scale"))?;
                let (a, b) = colours(self)?;
                Ok(Texture::Noise {
                    scale,
                    seed: t.seed.unwrap_or(0),
                    a,
                    b,
                })
            }
            other => Err(self.err(
                &key("type"),
                format!(
                    "unknown texture type `{other}`; expected one of {}",
                    list(&["checker", "stripes", "noise"])
                ),
            )),
        }
    }

    fn transform(&self, t: &TransformDef, path: &str) -> Result<Transform, SceneError> {
        let key = |k: &str| format!("{path}.{k}");
        let scale = match t.scale {
            Some(s) => {
                let v = self.finite_vec(s.0, &key("scale"))?;
                if v.x == 0.0 || v.y == 0.0 || v.z == 0.0 {
                    return Err(self.err(&key("scale"), "scale factors must be non-zero"));
                }
                v
            }
            None => DVec3::ONE,
        };
        let rotate = self.finite_vec(t.rotate.unwrap_or([0.0; 3]), &key("rotate"))?;
        let translate = self.finite_vec(t.translate.unwrap_or([0.0; 3]), &key("translate"))?;
        Ok(Transform::new(scale, rotate, translate))
    }

    /// Builds, transforms and cleans an object's mesh.
    fn object_mesh(
        &mut self,
        o: &ObjectDef,
        path: &str,
        name: &str,
    ) -> Result<super::Mesh, SceneError> {
        let present = o.present();
        let key = |k: &str| format!("{path}.{k}");
        let what = format!("shape `{}`", o.shape);
        let shapes_list = ["mesh", "sphere", "plane", "box", "torus", "bumpy-sphere"];
        // The object-space mesh, and the mesh file it came from (named in later messages).
        let (raw, source): (RawMesh, Option<String>) = match o.shape.as_str() {
            "mesh" => {
                self.check_keys(path, &present, &["file"], &what)?;
                let Some(file) = o.file.as_deref() else {
                    return Err(self.err(&key("file"), "shape `mesh` needs `file`"));
                };
                let found = self.find_mesh(file, &key("file"))?;
                let shown = found.display().to_string();
                let bytes = std::fs::read(&found).map_err(|e| SceneError {
                    file: shown.clone(),
                    line: None,
                    key: None,
                    message: format!("cannot read the mesh file (object `{name}`): {e}"),
                    kind: SceneErrorKind::Io,
                })?;
                let m = obj::parse(&shown, &bytes).map_err(|mut e| {
                    e.message += &format!(" (mesh of object `{name}`, {path} in {})", self.file);
                    e
                })?;
                if m.flipped {
                    self.warnings.push(format!(
                        "{shown}: the closed mesh enclosed a negative volume, so its triangles \
                         were reversed to face outwards"
                    ));
                }
                (m.raw, Some(shown))
            }
            "sphere" => {
                self.check_keys(path, &present, &["radius", "subdivisions"], &what)?;
                let r = self.required(o.radius, path, "radius", &what)?;
                let r = self.positive(r, &key("radius"))?;
                let n = self.subdivisions(
                    o.subdivisions,
                    4,
                    MAX_SPHERE_SUBDIVISIONS,
                    &key("subdivisions"),
                )?;
                (shapes::sphere(r, n), None)
            }
            "bumpy-sphere" => {
                self.check_keys(
                    path,
                    &present,
                    &["radius", "amplitude", "frequency", "seed", "subdivisions"],
                    &what,
                )?;
                let r = self.required(o.radius, path, "radius", &what)?;
                let r = self.positive(r, &key("radius"))?;
                let a = self.required(o.amplitude, path, "amplitude", &what)?;
                if !(a.is_finite() && a >= 0.0 && a < r) {
                    return Err(self.err(
                        &key("amplitude"),
                        format!(
                            "must be finite, >= 0 and smaller than the radius {}, got {}",
                            fmt_num(r),
                            fmt_num(a)
                        ),
                    ));
                }
                let f = self.required(o.frequency, path, "frequency", &what)?;
                let f = self.positive(f, &key("frequency"))?;
                let n = self.subdivisions(
                    o.subdivisions,
                    5,
                    MAX_SPHERE_SUBDIVISIONS,
                    &key("subdivisions"),
                )?;
                (shapes::bumpy_sphere(r, a, f, o.seed.unwrap_or(0), n), None)
            }
            "plane" => {
                self.check_keys(path, &present, &["size", "subdivisions"], &what)?;
                let size = self.sizes(o.size.as_deref(), 2, path, &what)?;
                let n = self.subdivisions(
                    o.subdivisions,
                    1,
                    MAX_PLANE_SUBDIVISIONS,
                    &key("subdivisions"),
                )?;
                if n == 0 {
                    return Err(self.err(&key("subdivisions"), "must be at least 1"));
                }
                (shapes::plane(size[0], size[1], n), None)
            }
            "box" => {
                self.check_keys(path, &present, &["size"], &what)?;
                let size = self.sizes(o.size.as_deref(), 3, path, &what)?;
                (shapes::cuboid(DVec3::new(size[0], size[1], size[2])), None)
            }
            "torus" => {
                self.check_keys(path, &present, &["major", "minor", "segments"], &what)?;
                let major = self.required(o.major, path, "major", &what)?;
                let major = self.positive(major, &key("major"))?;
                let minor = self.required(o.minor, path, "minor", &what)?;
                let minor = self.positive(minor, &key("minor"))?;
                if minor >= major {
                    return Err(self.err(
                        &key("minor"),
                        format!(
                            "the tube radius must be smaller than the major radius {} (got {})",
                            fmt_num(major),
                            fmt_num(minor)
                        ),
                    ));
                }
                let [nu, nv] = o.segments.map(|s| s.0).unwrap_or([64, 32]);
                for v in [nu, nv] {
                    if !(3..=MAX_TORUS_SEGMENTS).contains(&v) {
                        return Err(self.err(
                            &key("segments"),
                            format!("segments must be in [3, {MAX_TORUS_SEGMENTS}], got {v}"),
                        ));
                    }
                }
                (shapes::torus(major, minor, nu as u32, nv as u32), None)
            }
            other => {
                return Err(self.err(
                    &key("shape"),
                    format!(
                        "unknown shape `{other}`; expected one of {}",
                        list(&shapes_list)
                    ),
                ));
            }
        };
        let transform = match &o.transform {
            Some(t) => self.transform(t, &key("transform"))?,
            None => Transform::new(DVec3::ONE, DVec3::ZERO, DVec3::ZERO),
        };
        let raw = transform.apply(raw);
        let total = raw.triangles.len();
        let (mesh, dropped) = shapes::finish(raw);
        let label = match &source {
            Some(f) => f.clone(),
            None => format!("{}: object `{name}` ({path})", self.file),
        };
        if mesh.triangles.is_empty() {
            let message = if total == 0 {
                format!("the mesh of object `{name}` has no triangles")
            } else {
                format!(
                    "the mesh of object `{name}` has no triangles left after dropping {dropped} \
                     degenerate one{}",
                    if dropped == 1 { "" } else { "s" }
                )
            };
            return Err(match source {
                Some(f) => SceneError {
                    file: f,
                    line: None,
                    key: None,
                    message,
                    kind: SceneErrorKind::Invalid,
                },
                None => self.err(path, message),
            });
        }
        if dropped > 0 {
            self.warnings.push(format!(
                "{label}: dropped {dropped} degenerate triangle{} (repeated vertex or area below \
                 {:e} of the squared bounding-box diagonal), kept {}",
                if dropped == 1 { "" } else { "s" },
                shapes::DEGENERATE_AREA,
                mesh.triangles.len()
            ));
        }
        Ok(mesh)
    }

    fn subdivisions(
        &self,
        v: Option<u32>,
        default: u32,
        max: u32,
        key: &str,
    ) -> Result<u32, SceneError> {
        let n = v.unwrap_or(default);
        if n > max {
            return Err(self.err(key, format!("must be at most {max}, got {n}")));
        }
        Ok(n)
    }

    /// `size` with `n` positive finite components.
    fn sizes(
        &self,
        v: Option<&[f64]>,
        n: usize,
        path: &str,
        what: &str,
    ) -> Result<Vec<f64>, SceneError> {
        let key = format!("{path}.size");
        let Some(v) = v else {
            return Err(self.err(&key, format!("{what} needs `size`")));
        };
        if v.len() != n {
            return Err(self.err(
                &key,
                format!("{what} needs `size` with {n} numbers, got {}", v.len()),
            ));
        }
        for x in v {
            if !(x.is_finite() && *x > 0.0) {
                return Err(self.err(
                    &key,
                    format!("sizes must be finite and > 0, got {}", fmt_num(*x)),
                ));
            }
        }
        Ok(v.to_vec())
    }

    /// Resolves a mesh file name: as given if absolute; else next to the scene file, then in
    /// each of `opts.mesh_dirs`.
    fn find_mesh(&self, file: &str, key: &str) -> Result<PathBuf, SceneError> {
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
            "no directories to search (set SSS_MESH_DIR or LoadOptions::mesh_dirs)".to_string()
        } else {
            let shown: Vec<String> = dirs
                .iter()
                .map(|d| {
                    if d.as_os_str().is_empty() {
                        ".".to_string()
                    } else {
                        d.display().to_string()
                    }
                })
                .collect();
            format!("searched: {}", shown.join(", "))
        };
        Err(SceneError {
            kind: SceneErrorKind::MeshNotFound,
            ..self.err(key, format!("mesh file `{file}` not found; {searched}"))
        })
    }
}

/// The text between `prefix` and the next backtick in `message`, if `message` contains
/// `prefix`.
fn backticked<'m>(message: &'m str, prefix: &str) -> Option<&'m str> {
    let start = message.find(prefix)? + prefix.len();
    let len = message[start..].find('`')?;
    Some(&message[start..start + len])
}
