//! The screen-space sampling rate s_p of the multiply-scattered light at each G-buffer sample
//! (Milaenen et al. 2019, §3, Eq. 4–5): how many samples per pixel the subsurface signal needs
//! there, from the material's Fourier bandwidths (`sss-bandwidth`), the surface's curvature,
//! the distance and the view angle. Shared by the methods that decide from it how finely to
//! shade the image: the dual trees (a pixel cluster's extent ρ/s_p, Eq. 6) and the many-light
//! method that estimates a sparse set of pixels and reconstructs the rest.

use crate::Error;
use crate::frame::Frame;
use crate::gbuffer::GSample;
use crate::shading::TranslucentShading;
use glam::DVec3;
use rayon::prelude::*;
use sss_bandwidth::{MaterialBandwidth, PixelFootprint, ShadeGeometry, vertex_max_abs_curvature};

/// The image's angular footprint (Eq. 5's f_x, f_y, W, H).
pub fn pixel_footprint(frame: &Frame<'_>) -> PixelFootprint {
    let cam = &frame.scene.camera;
    let fov_y = cam.vfov_deg.to_radians();
    let aspect = f64::from(cam.width) / f64::from(cam.height.max(1));
    let fov_x = 2.0 * ((0.5 * fov_y).tan() * aspect).atan();
    PixelFootprint {
        fov_x_rad: fov_x,
        fov_y_rad: fov_y,
        width_px: cam.width,
        height_px: cam.height,
    }
}

/// Barycentric interpolation of per-vertex `values` at `p` on triangle `tri` (clamped to the
/// triangle; the vertex mean on a degenerate one).
fn interpolate(positions: &[DVec3], tri: [u32; 3], values: &[f64], p: DVec3) -> f64 {
    let [a, b, c] = tri.map(|i| positions[i as usize]);
    let [va, vb, vc] = tri.map(|i| values[i as usize]);
    let (e0, e1, e2) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (e0.dot(e0), e0.dot(e1), e1.dot(e1));
    let (d20, d21) = (e2.dot(e0), e2.dot(e1));
    let den = d00 * d11 - d01 * d01;
    if !(den > 1e-300 * (d00 * d11).max(f64::MIN_POSITIVE)) || !den.is_finite() {
        return (va + vb + vc) / 3.0;
    }
    let v = ((d11 * d20 - d01 * d21) / den).clamp(0.0, 1.0);
    let w = ((d00 * d21 - d01 * d20) / den).clamp(0.0, 1.0);
    let s = v + w;
    let (v, w) = if s > 1.0 { (v / s, w / s) } else { (v, w) };
    (1.0 - v - w) * va + v * vb + w * vc
}

/// s_p at one shading point (samples per pixel, Eq. 4–5), from the material's bandwidths, the
/// curvature k (1/scene unit) and the hit.
fn rate_at(
    g: &GSample,
    k_scene: f64,
    sh: &TranslucentShading,
    bw: &MaterialBandwidth,
    footprint: &PixelFootprint,
) -> Result<f64, Error> {
    let u = sh.units_per_mm;
    let geometry = ShadeGeometry {
        curvature_per_mm: k_scene * u,
        distance_mm: g.distance / u,
        cos_theta_o: g.n.dot(g.wo),
    };
    bw.sampling_rate_per_pixel(&geometry, footprint)
        .map_err(|e| Error::Input(format!("material `{}`: s_p: {e}", sh.name)))
}

/// The G-buffer samples on object `o` (indices, ascending) and the curvature k = max(|κ₁|,
/// |κ₂|) at each (1/scene unit): in closed form for a procedural shape under a uniform scale
/// ([`sss_scene::Curvature`]: sphere, plane, box, torus), otherwise per mesh vertex by
/// Rusinkiewicz 2004 ([`vertex_max_abs_curvature`]), interpolated with the hit's barycentric
/// coordinates.
pub fn curvature_at_hits(frame: &Frame<'_>, o: u32) -> Result<(Vec<u32>, Vec<f64>), Error> {
    let object = &frame.scene.objects[o as usize];
    let index: Vec<u32> = (0..frame.gbuffer.samples.len() as u32)
        .filter(|&i| frame.gbuffer.samples[i as usize].object == o)
        .collect();
    if let Some(c) = object.curvature {
        let curvature = index
            .iter()
            .map(|&i| c.max_abs_at(frame.gbuffer.samples[i as usize].p))
            .collect();
        return Ok((index, curvature));
    }
    let mesh = &object.mesh;
    let coords: Vec<[f64; 3]> = mesh.positions.iter().map(|p| p.to_array()).collect();
    let k = vertex_max_abs_curvature(&coords, &mesh.triangles)
        .map_err(|e| Error::Input(format!("object `{}`: curvature: {e}", object.name)))?;
    let curvature = index
        .par_iter()
        .map(|&i| {
            let g = &frame.gbuffer.samples[i as usize];
            interpolate(
                &mesh.positions,
                mesh.triangles[g.triangle as usize],
                &k,
                g.p,
            )
        })
        .collect();
    Ok((index, curvature))
}

/// The sampling rates of one object: its G-buffer samples' indices (ascending) and s_p at each
/// (samples per pixel).
pub type ObjectRates = (Vec<u32>, Vec<f64>);

/// s_p at every G-buffer sample of every visible translucent object, per object (`None` for
/// the others): B_s and the B_θ table once per visible material, the curvature per sample
/// ([`curvature_at_hits`]), Eq. 4–5 per sample.
pub fn object_rates(frame: &Frame<'_>) -> Result<Vec<Option<ObjectRates>>, Error> {
    let scene = frame.scene;
    let bandwidths: Vec<Option<MaterialBandwidth>> = frame
        .shading
        .par_iter()
        .map(|sh| {
            sh.as_ref()
                .map(|sh| {
                    MaterialBandwidth::new(sh.bssrdf())
                        .map_err(|e| Error::Input(format!("material `{}`: {e}", sh.name)))
                })
                .transpose()
        })
        .collect::<Result<_, _>>()?;
    let footprint = pixel_footprint(frame);
    footprint
        .radians_per_pixel()
        .map_err(|e| Error::Input(format!("camera: {e}")))?;
    let mut out: Vec<Option<ObjectRates>> = (0..scene.objects.len()).map(|_| None).collect();
    for &o in &frame.visible {
        let (Some(sh), Some(bw)) = (
            frame.shading_of(o),
            bandwidths[scene.objects[o as usize].material].as_ref(),
        ) else {
            continue;
        };
        let (index, curvature) = curvature_at_hits(frame, o)?;
        let rates: Vec<f64> = index
            .par_iter()
            .zip(&curvature)
            .map(|(&i, &k_scene)| {
                rate_at(
                    &frame.gbuffer.samples[i as usize],
                    k_scene,
                    sh,
                    bw,
                    &footprint,
                )
            })
            .collect::<Result<_, Error>>()?;
        out[o as usize] = Some((index, rates));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_reproduces_linear_functions_and_survives_degenerate_triangles() {
        let pos = [
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 3.0, 0.0),
            DVec3::new(4.0, 0.0, 0.0),
        ];
        // f = 1 + x + 2y at the vertices.
        let f = [1.0, 3.0, 7.0, 5.0];
        let p = DVec3::new(0.5, 1.0, 0.0);
        assert!((interpolate(&pos, [0, 1, 2], &f, p) - 3.5).abs() < 1e-12);
        // Outside the triangle: clamped to it.
        let v = interpolate(&pos, [0, 1, 2], &f, DVec3::new(5.0, 5.0, 0.0));
        assert!((1.0..=7.0).contains(&v));
        // Collinear vertices: the mean.
        assert_eq!(interpolate(&pos, [0, 1, 3], &f, p), 3.0);
    }
}
