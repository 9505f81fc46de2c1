//! The `[[lights]]` tables: point, directional, sun, quad and environment lights.

use super::context::{Ctx, list};
use crate::format::{Keys, LightDef};
use crate::{Light, SceneError};

impl Ctx<'_> {
    pub(super) fn light(&self, l: &LightDef, path: &str) -> Result<Light, SceneError> {
        let types = ["point", "directional", "sun", "quad", "environment"];
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
            "sun" => {
                self.check_keys(
                    path,
                    &present,
                    &["direction", "irradiance", "angular_diameter"],
                    &what,
                )?;
                let d = self.required(l.direction, path, "direction", &what)?;
                let e = self.required(l.irradiance, path, "irradiance", &what)?;
                // The sun's angular diameter seen from the earth, in degrees.
                let deg = l.angular_diameter.unwrap_or(0.53);
                if !(deg.is_finite() && deg > 0.0 && deg < 180.0) {
                    return Err(self.err(
                        &key("angular_diameter"),
                        format!(
                            "is {deg}; it must be an angle in degrees above 0 and below 180 \
                             (the sun's is 0.53; a point-like source is a `directional` light)"
                        ),
                    ));
                }
                Ok(Light::Sun {
                    direction: self.nonzero_vec(d, &key("direction"))?.normalize(),
                    irradiance: self.emission(e, &key("irradiance"))?,
                    half_angle: (0.5 * deg).to_radians(),
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
}
