//! The `exact` reference: at each shading point, the sum over every irradiance sample of its
//! object of the model's contribution, with no hierarchy and no culling. Ground truth for the
//! hierarchical methods (single tree, dual tree, many-light) on the same points.

use super::{TranslucentShading, add_scaled};
use crate::gbuffer::GSample;
use crate::irradiance::ObjectSamples;
use sss_bssrdf::fresnel::ft_dielectric;
use sss_bssrdf::{Rgb, SurfacePoint};

/// The subsurface radiance leaving `g` towards the camera.
pub fn shade(g: &GSample, shading: &TranslucentShading, samples: &ObjectSamples) -> Rgb {
    let mut sum = [0.0; 3];
    if shading.directional {
        // Full S of the directional dipole, positions in mm.
        let u = shading.units_per_mm;
        let xo = SurfacePoint { p: g.p / u, n: g.n };
        for (i, s) in samples.samples.iter().enumerate() {
            let xi = SurfacePoint {
                p: s.position / u,
                n: s.normal,
            };
            let a = s.area / (u * u);
            for packet in samples.incident_of(i) {
                let sv = shading.model.s(&xi, packet.dir, &xo, g.wo);
                for c in 0..3 {
                    sum[c] += sv[c] * packet.e_cos[c] * a;
                }
            }
        }
        return sum;
    }
    for s in &samples.samples {
        let rd = shading.rd_scene((s.position - g.p).length());
        for c in 0..3 {
            sum[c] += rd[c] * s.irradiance[c] * s.area;
        }
    }
    let mut out = [0.0; 3];
    add_scaled(
        &mut out,
        sum,
        ft_dielectric(g.n.dot(g.wo), shading.eta) * shading.norm,
    );
    out
}
