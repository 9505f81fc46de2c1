//! What the random walk needs of one translucent material: its homogeneous medium in scene
//! units, the Henyey–Greenstein phase function, the boundary's relative index of refraction and
//! the pre-scatter texture.

use crate::Error;
use glam::DVec3;
use sss_bssrdf::Rgb;
use sss_scene::{Scene, Texture, Translucent};
use std::f64::consts::PI;

/// The interior of a translucent material, as the walk uses it (scene units).
#[derive(Clone, Debug, PartialEq)]
pub struct Interior {
    /// Scattering coefficient σ_s per channel, per scene unit.
    pub sigma_s: Rgb,
    /// Extinction coefficient σ_t = σ_a + σ_s per channel, per scene unit (> 0).
    pub sigma_t: Rgb,
    /// Henyey–Greenstein anisotropy in (−1, 1).
    pub g: f64,
    /// Relative index of refraction of the boundary (inside over outside).
    pub eta: f64,
    /// The pre-scatter texture: multiplies the light where it enters the medium.
    pub texture: Option<Texture>,
}

impl Interior {
    /// The interior of material `name`. With `g = None` the medium's own σ_s and g are used;
    /// with `Some(g)` the medium's reduced scattering σ_s' = σ_s(1 − g_medium) is kept and the
    /// walk scatters with σ_s = σ_s'/(1 − g) and Henyey–Greenstein g (the similarity relation;
    /// presets give reduced coefficients, so their medium has g = 0 and σ_s = σ_s').
    pub fn new(name: &str, t: &Translucent, g: Option<f64>) -> Result<Interior, Error> {
        let m = &t.medium;
        let u = t.units_per_mm;
        let g = g.unwrap_or(m.g());
        let sigma_a = m.sigma_a();
        let mut sigma_s = [0.0; 3];
        let mut sigma_t = [0.0; 3];
        for c in 0..3 {
            // Per mm, then per scene unit (a length of ℓ scene units is ℓ/u mm).
            let s_mm = m.sigma_s_reduced(c) / (1.0 - g);
            sigma_s[c] = s_mm / u;
            sigma_t[c] = (sigma_a[c] + s_mm) / u;
            if !(sigma_t[c].is_finite() && sigma_t[c] > 0.0 && sigma_s[c].is_finite()) {
                return Err(Error::Input(format!(
                    "material `{name}`: channel {c} has extinction {} per scene unit (σ_a {} and \
                     σ_s {} per mm at {u} units per mm), which the random walk cannot sample",
                    sigma_t[c], sigma_a[c], s_mm
                )));
            }
        }
        Ok(Interior {
            sigma_s,
            sigma_t,
            g,
            eta: m.eta(),
            texture: t.texture.clone(),
        })
    }

    /// The texture's value at `p` (1 without a texture).
    pub fn texture_at(&self, p: DVec3) -> Rgb {
        self.texture.as_ref().map_or([1.0; 3], |t| t.eval(p))
    }

    /// A new direction scattered from propagation direction `d` (unit) by the
    /// Henyey–Greenstein phase function with this interior's g, from two uniform numbers in
    /// [0, 1). The phase function is sampled exactly, so the path weight does not change.
    pub fn scatter(&self, d: DVec3, u1: f64, u2: f64) -> DVec3 {
        let cos = hg_cos(self.g, u1);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = 2.0 * PI * u2;
        let (t1, t2) = crate::lights::tangent_frame(d);
        (d * cos + t1 * (sin * phi.cos()) + t2 * (sin * phi.sin())).normalize_or(d)
    }
}

/// The cosine between the old and the new propagation direction, drawn from the
/// Henyey–Greenstein phase function p(cos) = (1 − g²)/(4π (1 + g² − 2g cos)^{3/2}) by inverting
/// its distribution (pbrt 3rd ed. §15.2.3, written here in the propagation-direction
/// convention: g > 0 scatters forward). Uniform in [−1, 1] for |g| < 10⁻³, where the inversion
/// loses precision.
pub fn hg_cos(g: f64, u: f64) -> f64 {
    let cos = if g.abs() < 1e-3 {
        1.0 - 2.0 * u
    } else {
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
        (1.0 + g * g - s * s) / (2.0 * g)
    };
    cos.clamp(-1.0, 1.0)
}

/// The interior of every material of `scene` (indexed like `scene.materials`; `None` for
/// the opaque ones), with `g` as in [`Interior::new`].
pub fn interiors(scene: &Scene, g: Option<f64>) -> Result<Vec<Option<Interior>>, Error> {
    scene
        .materials
        .iter()
        .map(|m| match &m.kind {
            sss_scene::MaterialKind::Translucent(t) => Interior::new(&m.name, t, g).map(Some),
            sss_scene::MaterialKind::Diffuse { .. } => Ok(None),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sampled cosines have the Henyey–Greenstein mean ⟨cos⟩ = g and its second moment
    /// ⟨cos²⟩ = (1 + 2g²)/3 (closed forms of the distribution), for isotropic, forward and
    /// backward scattering.
    #[test]
    fn hg_cosines_have_the_closed_form_moments() {
        let n = 200_000;
        for g in [0.0, 0.5, 0.9, -0.7] {
            let (mut m1, mut m2) = (0.0, 0.0);
            for i in 0..n {
                let c = hg_cos(g, (i as f64 + 0.5) / n as f64);
                m1 += c;
                m2 += c * c;
            }
            m1 /= n as f64;
            m2 /= n as f64;
            assert!((m1 - g).abs() < 2e-3, "g {g}: mean cos {m1}");
            let want = (1.0 + 2.0 * g * g) / 3.0;
            assert!(
                (m2 - want).abs() < 2e-3,
                "g {g}: mean cos² {m2}, want {want}"
            );
        }
    }

    #[test]
    fn scattered_directions_are_unit_and_follow_g() {
        let it = Interior {
            sigma_s: [1.0; 3],
            sigma_t: [1.0; 3],
            g: 0.8,
            eta: 1.3,
            texture: None,
        };
        let d = DVec3::new(0.3, -0.4, 0.5).normalize();
        let n = 20_000;
        let mut mean = 0.0;
        for i in 0..n {
            let u1 = (i as f64 + 0.5) / n as f64;
            let u2 = ((i * 7919) % n) as f64 / n as f64;
            let w = it.scatter(d, u1, u2);
            assert!((w.length() - 1.0).abs() < 1e-12);
            mean += w.dot(d);
        }
        assert!((mean / n as f64 - 0.8).abs() < 5e-3);
    }
}
