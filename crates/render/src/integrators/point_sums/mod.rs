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
use crate::sampling_rate::object_rates;
pub use crate::sampling_rate::{curvature_at_hits, pixel_footprint};
use crate::shading::TranslucentShading;
use glam::DVec3;
use rayon::prelude::*;
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
    let width = frame.gbuffer.width.max(1);
    Ok(object_rates(frame)?
        .into_iter()
        .map(|r| {
            r.map(|(index, rates)| {
                let points = index
                    .iter()
                    .zip(&rates)
                    .map(|(&i, &rate)| pixel_point(&frame.gbuffer.samples[i as usize], width, rate))
                    .collect();
                (points, index)
            })
        })
        .collect())
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
