//! Integrators: ways to compute the subsurface term at the G-buffer's points. Each computes
//! the same quantity (see `ARCHITECTURE.md`):
//!
//! L(x_o, ω_o) = F_t(η, cos θ_o)/(cπ) Σ_i R_d(‖x_i − x_o‖) E_i A_i for separable models
//! (pbrt 3rd ed. Eq. 11.6-11.7 with c = 1 − 2C₁(η)), and Σ_i A_i Σ_k S(x_i, ω_k; x_o, ω_o) E_k
//! for the directional dipole, or the integral these sums approximate.

pub mod exact;
pub mod pathtrace;
pub mod separable;

use sss_scene::{Scene, Texture, Translucent};
use sss_bssrdf::{Bssrdf, ModelKind, Rgb, fresnel_normalization, make_model};
use std::f64::consts::PI;

/// What an integrator needs of one translucent material, in scene units.
pub struct TranslucentShading {
    /// The model (built once per material).
    pub model: Box<dyn Bssrdf>,
    /// Scene units per millimetre.
    pub units_per_mm: f64,
    /// Relative index of refraction.
    pub eta: f64,
    /// 1/(cπ), the separable directional normalisation.
    pub norm: f64,
    /// True when the model needs incident directions (the directional dipole).
    pub directional: bool,
    /// The pre-scatter texture.
    pub texture: Option<Texture>,
}

impl TranslucentShading {
    /// Builds the model of a translucent material.
    pub fn new(t: &Translucent) -> Self {
        let model = make_model(t.model, &t.medium);
        let eta = t.medium.eta();
        TranslucentShading {
            model,
            units_per_mm: t.units_per_mm,
            eta,
            norm: 1.0 / (fresnel_normalization(eta) * PI),
            directional: t.model == ModelKind::DirectionalDipole,
            texture: t.texture.clone(),
        }
    }

    /// R_d at scene-unit distance `r`, per scene unit² (R_d(r/u)/u², u = units per mm).
    #[inline]
    pub fn rd_scene(&self, r: f64) -> Rgb {
        let u = self.units_per_mm;
        let rd = self.model.rd_rgb(r / u);
        let s = 1.0 / (u * u);
        [rd[0] * s, rd[1] * s, rd[2] * s]
    }
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
            out[m] = Some(TranslucentShading::new(t));
        }
    }
    out
}

/// Adds `s·v` to `acc`.
#[inline]
pub(crate) fn add_scaled(acc: &mut Rgb, v: Rgb, s: f64) {
    for c in 0..3 {
        acc[c] += v[c] * s;
    }
}
