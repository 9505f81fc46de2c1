//! The `[materials.NAME]` tables: translucent materials (a model, and a preset or explicit
//! coefficients) and diffuse ones.

use super::context::{Ctx, fmt_num, list};
use crate::format::{Keys, MaterialDef, RadiusDef, Triple};
use crate::{Angular, MaterialKind, SceneError, Translucent};
use sss_bssrdf::presets::{PRESET_ETA, PRESETS};
use sss_bssrdf::{Medium, ModelKind, Rgb};
use std::str::FromStr;

impl Ctx<'_> {
    pub(super) fn material(&self, m: &MaterialDef, path: &str) -> Result<MaterialKind, SceneError> {
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
                        "angular",
                        "sphere_radius",
                        "drift",
                        "unscattered",
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
                if model == ModelKind::McTable && !sss_bssrdf::mc_table::eta_in_range(eta) {
                    let etas = sss_bssrdf::mc_table::ETAS;
                    return Err(self.err(
                        &key("eta"),
                        format!(
                            "model `mc-table` is tabulated for a relative index of refraction \
                             from {} to {}, got {}; choose another model for this material",
                            fmt_num(etas[0]),
                            fmt_num(etas[etas.len() - 1]),
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
                let angular = match m.angular.as_deref() {
                    None | Some("fresnel") => Angular::Fresnel,
                    Some("albedo") => Angular::Albedo,
                    Some(other) => {
                        return Err(self.err(
                            &key("angular"),
                            format!(
                                "unknown angular factors `{other}`; expected one of fresnel, albedo"
                            ),
                        ));
                    }
                };
                if angular == Angular::Albedo && model == ModelKind::DirectionalDipole {
                    return Err(self.err(
                        &key("angular"),
                        "angular = \"albedo\" reshapes a radial model's entry and exit; the \
                         directional dipole has its own S (choose a radial model or leave \
                         `angular` out)",
                    ));
                }
                let sphere_radius = match &m.sphere_radius {
                    None => None,
                    Some(_) if model == ModelKind::DirectionalDipole => {
                        return Err(self.err(
                            &key("sphere_radius"),
                            "sphere_radius reshapes a radial profile; the directional dipole's \
                             S is not radial (choose a radial model or leave `sphere_radius` out)",
                        ));
                    }
                    // Resolved from the material's objects once they are loaded (`assemble`).
                    // `local` leaves the radius to each point (`local_radius`).
                    Some(RadiusDef::Keyword(k)) if k == "auto" || k == "local" => None,
                    Some(RadiusDef::Keyword(k)) => {
                        return Err(self.err(
                            &key("sphere_radius"),
                            format!(
                                "unknown sphere radius `{k}`; expected a length in scene units, \
                                 \"auto\" or \"local\""
                            ),
                        ));
                    }
                    Some(RadiusDef::Value(r)) => {
                        if !(r.is_finite() && *r > 0.0) {
                            return Err(self.err(
                                &key("sphere_radius"),
                                format!(
                                    "the sphere's radius must be finite and > 0 scene units, got {}",
                                    fmt_num(*r)
                                ),
                            ));
                        }
                        Some(*r)
                    }
                };
                let drift = m.drift.unwrap_or(false);
                if drift && model == ModelKind::DirectionalDipole {
                    return Err(self.err(
                        &key("drift"),
                        "drift moves a radial model's light along the entry direction; the \
                         directional dipole's S has its own (choose a radial model or leave \
                         `drift` out)",
                    ));
                }
                let local_radius = matches!(
                    &m.sphere_radius,
                    Some(RadiusDef::Keyword(k)) if k == "local"
                );
                Ok(MaterialKind::Translucent(Translucent {
                    model,
                    medium,
                    units_per_mm: upm,
                    texture,
                    angular,
                    sphere_radius,
                    local_radius,
                    drift,
                    unscattered: m.unscattered.unwrap_or(false),
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
    pub(super) fn coefficient(&self, c: Triple, key: &str) -> Result<Rgb, SceneError> {
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
}
