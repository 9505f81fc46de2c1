//! The physics every integrator shares, written once: what a translucent material needs at
//! shading time ([`TranslucentShading`]), the split between radial models and the full S of
//! the directional dipole ([`ShadingModel`]), the Fresnel-transmitted, textured irradiance
//! entering the surface ([`transmitted_irradiance`]) and the exit weight F_t(η, cos θ_o)/(cπ)
//! ([`TranslucentShading::exit_weight`]).
//!
//! Every integrator computes (pbrt 3rd ed. Eq. 11.6–11.7, with c = 1 − 2C₁(η) the
//! normalisation of pbrt's S_ω):
//!
//! L(x_o, ω_o) = F_t(η, cos θ_o)/(cπ) Σ_i R_d(‖x_i − x_o‖) E_i A_i  for radial models, and
//! Σ_i A_i Σ_k S(x_i, ω_k; x_o, ω_o) E_k for the directional dipole,
//!
//! or the integral these sums approximate, with E_i = Σ_k F_t(η, cos θ_k) E_k · texture(x_i).

use crate::lights::Incident;
use glam::DVec3;
use sss_bssrdf::fresnel::ft_dielectric;
use sss_bssrdf::{Bssrdf, ModelKind, Rgb, fresnel_normalization, make_model};
use sss_scene::{Scene, Texture, Translucent};
use std::f64::consts::PI;

/// A material's model, split by what integrators may do with it.
pub enum ShadingModel {
    /// A radial model: S = F_t(η, cos θ_i) R_d(r) F_t(η, cos θ_o)/(cπ), so contributions can be
    /// summed as R_d · E · A (and clustered: trees, many-light methods, separable kernels).
    Radial(Box<dyn Bssrdf>),
    /// The directional dipole (Frisvad et al. 2014): S depends on the incident direction, so
    /// each irradiance sample keeps its incident light packets and S is evaluated per packet.
    Directional(Box<dyn Bssrdf>),
}

impl ShadingModel {
    /// The model, whatever its kind.
    pub fn bssrdf(&self) -> &dyn Bssrdf {
        match self {
            ShadingModel::Radial(m) | ShadingModel::Directional(m) => m.as_ref(),
        }
    }

    /// The model if it is radial.
    pub fn radial(&self) -> Option<&dyn Bssrdf> {
        match self {
            ShadingModel::Radial(m) => Some(m.as_ref()),
            ShadingModel::Directional(_) => None,
        }
    }
}

/// What an integrator needs of one translucent material, in scene units.
pub struct TranslucentShading {
    /// The material's name (for messages).
    pub name: String,
    /// The model kind it was built from.
    pub kind: ModelKind,
    /// The model (built once per material).
    pub model: ShadingModel,
    /// Scene units per millimetre.
    pub units_per_mm: f64,
    /// Relative index of refraction.
    pub eta: f64,
    /// 1/(cπ), the radial models' directional normalisation.
    pub norm: f64,
    /// The pre-scatter texture.
    pub texture: Option<Texture>,
}

impl TranslucentShading {
    /// Builds the model of a translucent material named `name`.
    pub fn new(name: &str, t: &Translucent) -> Self {
        let bssrdf = make_model(t.model, &t.medium);
        let eta = t.medium.eta();
        let model = if t.model == ModelKind::DirectionalDipole {
            ShadingModel::Directional(bssrdf)
        } else {
            ShadingModel::Radial(bssrdf)
        };
        TranslucentShading {
            name: name.to_string(),
            kind: t.model,
            model,
            units_per_mm: t.units_per_mm,
            eta,
            norm: 1.0 / (fresnel_normalization(eta) * PI),
            texture: t.texture.clone(),
        }
    }

    /// The model, whatever its kind.
    #[inline]
    pub fn bssrdf(&self) -> &dyn Bssrdf {
        self.model.bssrdf()
    }

    /// True for the directional dipole (S needs incident directions).
    #[inline]
    pub fn directional(&self) -> bool {
        matches!(self.model, ShadingModel::Directional(_))
    }

    /// The radial model, or an error naming the material and its model for methods that sum
    /// R_d · E · A (trees, many-light, separable kernels), which the directional dipole is not.
    pub fn radial(&self, method: &str) -> Result<&dyn Bssrdf, crate::Error> {
        self.model.radial().ok_or_else(|| {
            crate::Error::Unsupported(format!(
                "material `{}`: method {method} needs a radial model, but `{}` is the directional \
                 dipole, whose S depends on the incident direction (use exact or pathtrace, or \
                 another model)",
                self.name,
                self.kind.name()
            ))
        })
    }

    /// R_d at scene-unit distance `r`, per scene unit² (R_d(r/u)/u², u = units per mm).
    #[inline]
    pub fn rd_scene(&self, r: f64) -> Rgb {
        let u = self.units_per_mm;
        let rd = self.bssrdf().rd_rgb(r / u);
        let s = 1.0 / (u * u);
        [rd[0] * s, rd[1] * s, rd[2] * s]
    }

    /// The R_d an irradiance sample of area `area` (scene units²) contributes per unit area at
    /// scene-unit distance `r` from the shading point: the sample stands for a patch of the
    /// surface, so near the shading point (where R_d is peaked) this is meant to be R_d
    /// averaged over the sample's disk rather than the point value. Every point-sum method
    /// (`exact`, the tree leaves) calls this, so they approximate the same sum.
    ///
    /// Today: the point value [`rd_scene`](Self::rd_scene) (`area` unused).
    #[inline]
    pub fn rd_sample_scene(&self, r: f64, area: f64) -> Rgb {
        let _ = area;
        self.rd_scene(r)
    }

    /// The exit weight F_t(η, n·ω_o)/(cπ) of a radial model at a point with shading normal `n`
    /// seen from direction `wo`.
    #[inline]
    pub fn exit_weight(&self, n: DVec3, wo: DVec3) -> f64 {
        ft_dielectric(n.dot(wo), self.eta) * self.norm
    }

    /// The pre-scatter texture at `p` (1 without a texture).
    #[inline]
    pub fn texture_at(&self, p: DVec3) -> Rgb {
        self.texture.as_ref().map_or([1.0; 3], |t| t.eval(p))
    }
}

/// The irradiance transmitted into the medium at a point with shading normal `n`:
/// Σ_k F_t(η, n·ω_k) E_k · `tex`. The texture is multiplied into each packet in place (the
/// directional dipole keeps the textured packets), then the Fresnel factor is applied.
pub fn transmitted_irradiance(packets: &mut [Incident], n: DVec3, eta: f64, tex: Rgb) -> Rgb {
    let mut e = [0.0; 3];
    for packet in packets {
        let ft = ft_dielectric(n.dot(packet.dir), eta);
        for c in 0..3 {
            packet.e_cos[c] *= tex[c];
            e[c] += ft * packet.e_cos[c];
        }
    }
    e
}

/// The shading data of every material that some translucent object in `objects` uses (None
/// for the others): models and tables are built only for what the image shows.
pub fn shading_for(scene: &Scene, objects: &[u32]) -> Vec<Option<TranslucentShading>> {
    let mut out: Vec<Option<TranslucentShading>> =
        (0..scene.materials.len()).map(|_| None).collect();
    for &o in objects {
        let m = scene.objects[o as usize].material;
        if out[m].is_none()
            && let Some(t) = scene.translucent(o as usize)
        {
            out[m] = Some(TranslucentShading::new(&scene.materials[m].name, t));
        }
    }
    out
}
