//! The point sums: methods that sum R_d over an object's irradiance samples at each shading
//! point (Jensen & Buhler 2002), exactly (`exact`) or through trees over the samples
//! (`single_tree`, Jensen & Buhler §4) and over the shading points too (`dual_tree`, Milaenen et
//! al. 2019 Algorithm 2; `dual_tree_fmm`, local expansions). This module holds what they share:
//! the illumination tree over irradiance samples and its traversal primitives, the work
//! counters, the ε sweep, and the dual trees' shading points with their s_p (Milaenen et al.
//! Eq. 4-5), their pixel trees, the loop over the objects they shade and the parallel task
//! split. Every method here is radial-only except `exact`.

pub mod dual_tree;
pub mod dual_tree_fmm;
pub mod exact;
pub mod single_tree;

use super::Stat;
use crate::Error;
use crate::frame::Frame;
use crate::gbuffer::GSample;
use crate::irradiance::ObjectSamples;
use crate::shading::TranslucentShading;
use glam::DVec3;
use rayon::prelude::*;
use sss_bandwidth::{MaterialBandwidth, PixelFootprint, ShadeGeometry, vertex_max_abs_curvature};
use sss_bssrdf::Rgb;
use sss_hierarchy::{IrradiancePoint, IrradianceTree, KdNode, PixelPoint, PixelTree};
use std::sync::atomic::{AtomicU64, Ordering};

/// Irradiance samples per leaf of the illumination tree. Small, because a leaf that is not
/// accepted is summed sample by sample; the solid-angle test on leaves keeps distant leaves
/// at one evaluation.
pub const ILLUMINATION_LEAF: usize = 4;

/// The ε values `cargo xtask compare` sweeps, cheapest first (Milaenen et al. Fig. 6 spans
/// [0.01, 0.2]; three points of it keep the default run near 20 minutes, and
/// `cargo xtask compare --trees` sweeps it finely at paper scale).
pub fn eps_sweep(quick: bool) -> Vec<f64> {
    if quick {
        vec![0.2, 0.05]
    } else {
        vec![0.2, 0.05, 0.01]
    }
}

/// Work counters shared by the tree traversals (summed over threads; integer sums, so the
/// totals do not depend on the thread count).
#[derive(Default)]
pub(crate) struct Counts {
    /// Nodes (or node pairs) visited.
    pub visits: AtomicU64,
    /// Evaluations of R_d for a whole node.
    pub cluster_evals: AtomicU64,
    /// Evaluations of R_d for one irradiance sample.
    pub sample_evals: AtomicU64,
}

impl Counts {
    pub(crate) fn add(&self, visits: u64, clusters: u64, samples: u64) {
        self.visits.fetch_add(visits, Ordering::Relaxed);
        self.cluster_evals.fetch_add(clusters, Ordering::Relaxed);
        self.sample_evals.fetch_add(samples, Ordering::Relaxed);
    }

    pub(crate) fn stats(&self, visit_name: &'static str) -> Vec<Stat> {
        vec![
            Stat {
                name: visit_name,
                value: self.visits.load(Ordering::Relaxed) as f64,
            },
            Stat {
                name: "cluster_evaluations",
                value: self.cluster_evals.load(Ordering::Relaxed) as f64,
            },
            Stat {
                name: "sample_evaluations",
                value: self.sample_evals.load(Ordering::Relaxed) as f64,
            },
        ]
    }
}

/// One illumination tree per visible translucent object, indexed by object.
pub(crate) fn illumination_trees(
    frame: &Frame<'_>,
    samples: &[ObjectSamples],
) -> Vec<Option<IrradianceTree>> {
    let by_object = frame.samples_by_object(samples);
    by_object
        .par_iter()
        .map(|s| {
            s.map(|s| {
                let points: Vec<IrradiancePoint> = s
                    .samples
                    .iter()
                    .map(|p| IrradiancePoint {
                        position: p.position,
                        area: p.area,
                        irradiance: p.irradiance,
                    })
                    .collect();
                IrradianceTree::build(&points, ILLUMINATION_LEAF)
            })
        })
        .collect()
}

/// Bytes of the illumination trees for the per-object sample estimates of
/// [`crate::budget::irradiance_estimate`].
pub(crate) fn illumination_tree_bytes(samples: &[(usize, u64, u64)]) -> u64 {
    samples.iter().fold(0u64, |a, e| {
        a.saturating_add(IrradianceTree::bytes_for(
            usize::try_from(e.1).unwrap_or(usize::MAX / 2),
            ILLUMINATION_LEAF,
        ))
    })
}

/// Δω = A / d² < ε (written without a division, so d = 0 never accepts).
#[inline]
pub(crate) fn accepts(area: f64, d2: f64, eps: f64) -> bool {
    area < eps * d2
}

/// True if `x` is inside the node's (closed) bounding box.
#[inline]
pub(crate) fn inside(node: &KdNode<3>, x: DVec3) -> bool {
    (0..3).all(|k| node.lo[k] <= x[k] && x[k] <= node.hi[k])
}

/// Adds the point sum of `points` at `x` to `acc`
/// ([`TranslucentShading::add_point_sum`], as `exact` sums).
#[inline]
pub(crate) fn add_samples(
    acc: &mut Rgb,
    points: &[IrradiancePoint],
    x: DVec3,
    sh: &TranslucentShading,
) {
    sh.add_point_sum(
        acc,
        x,
        points.iter().map(|p| (p.position, p.area, p.irradiance)),
    );
}

/// rd ⊙ flux.
#[inline]
pub(crate) fn rd_times(rd: Rgb, flux: [f64; 3]) -> Rgb {
    [rd[0] * flux[0], rd[1] * flux[1], rd[2] * flux[2]]
}

/// Shading points per leaf of the pixel tree (a leaf whose extent exceeds P is shaded point by
/// point, so this bounds memory, not accuracy: ~200 bytes per node).
pub const PIXEL_LEAF: usize = 8;

/// Largest pixel-tree subtree handled as one parallel task.
pub const TASK_ITEMS: usize = 2048;

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

/// The shading point of G-buffer sample `g` in a frame `width` pixels wide (at its pixel's
/// centre on screen), with sampling rate `rate`.
pub(crate) fn pixel_point(g: &GSample, width: u32, rate: f64) -> PixelPoint {
    PixelPoint {
        screen: [
            f64::from(g.pixel % width) + 0.5,
            f64::from(g.pixel / width) + 0.5,
        ],
        position: g.p,
        normal: g.n,
        view: g.wo,
        rate,
    }
}

/// The shading points of every visible translucent object with their s_p, and the G-buffer
/// index of each, per object.
pub(crate) type ObjectPoints = Vec<Option<(Vec<PixelPoint>, Vec<u32>)>>;

pub(crate) fn shading_points(frame: &Frame<'_>) -> Result<ObjectPoints, Error> {
    let scene = frame.scene;
    // B_s and the B_θ table once per visible material.
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
    let width = frame.gbuffer.width.max(1);
    let mut out: ObjectPoints = (0..scene.objects.len()).map(|_| None).collect();
    for &o in &frame.visible {
        let (Some(sh), Some(bw)) = (
            frame.shading_of(o),
            bandwidths[scene.objects[o as usize].material].as_ref(),
        ) else {
            continue;
        };
        let (index, curvature) = curvature_at_hits(frame, o)?;
        let points: Vec<PixelPoint> = index
            .par_iter()
            .zip(&curvature)
            .map(|(&i, &k_scene)| {
                let g = &frame.gbuffer.samples[i as usize];
                let rate = rate_at(g, k_scene, sh, bw, &footprint)?;
                Ok(pixel_point(g, width, rate))
            })
            .collect::<Result<_, Error>>()?;
        out[o as usize] = Some((points, index));
    }
    Ok(out)
}

/// One pixel tree over each object's shading points, timed as the `shading_tree` stage.
pub(crate) fn pixel_trees(frame: &Frame<'_>, points: &ObjectPoints) -> Vec<Option<PixelTree>> {
    frame.timed("shading_tree", || {
        points
            .iter()
            .map(|p| p.as_ref().map(|(pts, _)| PixelTree::build(pts, PIXEL_LEAF)))
            .collect()
    })
}

/// One visible translucent object as the dual trees shade it: its shading, its two trees, and
/// its shading points in pixel-tree order.
pub(crate) struct DualObject<'a> {
    /// The object's material shading.
    pub(crate) sh: &'a TranslucentShading,
    /// The illumination tree over its irradiance samples.
    pub(crate) irr: &'a IrradianceTree,
    /// The pixel tree over its shading points.
    pub(crate) px: &'a PixelTree,
    /// The shading points in pixel-tree order.
    pub(crate) ordered: Vec<PixelPoint>,
    /// The G-buffer sample of each shading point, in the points' order before the tree.
    index: &'a [u32],
}

impl DualObject<'_> {
    /// The G-buffer sample of the `k`-th shading point in tree order.
    pub(crate) fn sample(&self, k: usize) -> usize {
        self.index[self.px.tree.order[k] as usize] as usize
    }
}

/// Calls `shade` for every visible translucent object that has its trees and shading points,
/// in `frame.visible`'s order, and returns how many shading points they hold (the G-buffer
/// samples the dual trees shade, for progress).
pub(crate) fn for_each_dual_object(
    frame: &Frame<'_>,
    trees: &[Option<IrradianceTree>],
    pixel_trees: &[Option<PixelTree>],
    points: &ObjectPoints,
    mut shade: impl FnMut(DualObject<'_>),
) -> u64 {
    let mut shaded = 0u64;
    for &o in &frame.visible {
        let (Some(sh), Some(irr), Some(px), Some((pts, index))) = (
            frame.shading_of(o),
            trees[o as usize].as_ref(),
            pixel_trees[o as usize].as_ref(),
            points[o as usize].as_ref(),
        ) else {
            continue;
        };
        let ordered: Vec<PixelPoint> = px.tree.order.iter().map(|&k| pts[k as usize]).collect();
        shaded += ordered.len() as u64;
        shade(DualObject {
            sh,
            irr,
            px,
            ordered,
            index,
        });
    }
    shaded
}

/// `acc` (one value per shading point, in pixel-tree order) cut into the disjoint slices of
/// the task roots ([`tasks`]), each with its root, so the tasks can run in parallel.
pub(crate) fn task_slices<'a>(px: &PixelTree, acc: &'a mut [Rgb]) -> Vec<(u32, &'a mut [Rgb])> {
    let roots = tasks(px);
    let mut slices = Vec::with_capacity(roots.len());
    let mut rest = acc;
    for &s in &roots {
        let (a, b) = rest.split_at_mut(px.tree.nodes[s as usize].len());
        slices.push((s, a));
        rest = b;
    }
    slices
}

/// The task roots: pixel-tree nodes with at most [`TASK_ITEMS`] points whose parent has more
/// (or the root), in tree order.
pub(crate) fn tasks(px: &PixelTree) -> Vec<u32> {
    let mut out = Vec::new();
    if px.tree.nodes.is_empty() {
        return out;
    }
    let mut stack = vec![0u32];
    while let Some(s) = stack.pop() {
        let n = &px.tree.nodes[s as usize];
        if n.len() <= TASK_ITEMS || n.is_leaf() {
            out.push(s);
        } else {
            stack.push(n.right);
            stack.push(n.left);
        }
    }
    out
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
