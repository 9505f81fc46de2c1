//! The `[[objects]]` tables: each object's mesh (an OBJ file or a procedural shape), its
//! transform, and the cleaning that drops degenerate triangles.

use super::context::{Ctx, fmt_num, list};
use super::obj;
use crate::format::{Keys, ObjectDef, TransformDef};
use crate::shapes::{self, RawMesh, Transform};
use crate::{SceneError, SceneErrorKind};
use glam::DVec3;

/// Limits that keep a typo from asking for billions of triangles.
const MAX_SPHERE_SUBDIVISIONS: u32 = 8;
const MAX_PLANE_SUBDIVISIONS: u32 = 1024;
const MAX_TORUS_SEGMENTS: i64 = 4096;

impl Ctx<'_> {
    pub(super) fn transform(&self, t: &TransformDef, path: &str) -> Result<Transform, SceneError> {
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
    pub(super) fn object_mesh(
        &mut self,
        o: &ObjectDef,
        path: &str,
        name: &str,
    ) -> Result<(crate::Mesh, Option<crate::Curvature>), SceneError> {
        let present = o.present();
        let key = |k: &str| format!("{path}.{k}");
        let what = format!("shape `{}`", o.shape);
        let shapes_list = ["mesh", "sphere", "plane", "box", "torus", "bumpy-sphere"];
        // The object-space mesh, and the mesh file it came from (named in later messages).
        // The shape's curvature in object space, for the closed forms of `Curvature`.
        let mut local_curvature: Option<crate::Curvature> = None;
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
                local_curvature = Some(crate::Curvature::Uniform(1.0 / r));
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
                local_curvature = Some(crate::Curvature::Uniform(0.0));
                (shapes::plane(size[0], size[1], n), None)
            }
            "box" => {
                self.check_keys(path, &present, &["size"], &what)?;
                let size = self.sizes(o.size.as_deref(), 3, path, &what)?;
                local_curvature = Some(crate::Curvature::Uniform(0.0));
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
                local_curvature = Some(crate::Curvature::Torus {
                    center: DVec3::ZERO,
                    axis: DVec3::Y,
                    major,
                    minor,
                });
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
        let curvature = local_curvature.and_then(|c| transform.curvature(c));
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
        Ok((mesh, curvature))
    }

    pub(super) fn subdivisions(
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
    pub(super) fn sizes(
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
}
