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
pub mod interreflection;
pub mod single_tree;

use super::{Layer, Stat, add_scaled};
use crate::Error;
use crate::frame::Frame;
use crate::gbuffer::GSample;
use crate::irradiance::{IrradianceSettings, ObjectSamples};
use crate::local_radius::{FrameBalls, LocalBalls, frame_balls};
use crate::sampling_rate::object_rates;
pub use crate::sampling_rate::{curvature_at_hits, pixel_footprint};
use crate::shading::TranslucentShading;
use glam::DVec3;
use rayon::prelude::*;
use sss_bssrdf::{BallFamily, Rgb};
use sss_hierarchy::{IrradiancePoint, IrradianceTree, KdNode, KdTree, PixelPoint, PixelTree};
use std::sync::Arc;
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

/// The irradiance samples a point sum reads, their balls and the stats of their light
/// ([`lit_samples`]).
pub(crate) struct LitSamples {
    /// Per visible translucent object, its samples.
    pub(crate) samples: Arc<Vec<ObjectSamples>>,
    /// The samples' and the G-buffer's balls (none without `sphere_radius = "local"`).
    pub(crate) balls: FrameBalls,
    /// The gather's stats (none without bounces).
    pub(crate) stats: Vec<Stat>,
}

/// The irradiance samples a point sum reads for `settings`: the frame's samples lit by the
/// lights ([`Frame::irradiance_samples`]), and with `settings.bounces` > 0 lit also by that
/// many bounces of the light the surfaces trade ([`interreflection`]; built once per frame
/// and settings, timed as stage `bounces`).
pub(crate) fn lit_samples(
    frame: &Frame<'_>,
    settings: &IrradianceSettings,
) -> Result<LitSamples, Error> {
    let direct = frame.irradiance_samples(&IrradianceSettings {
        bounces: 0,
        ..*settings
    });
    let balls = frame_balls(frame, &frame.samples_by_object(&direct))?;
    if settings.bounces == 0 {
        return Ok(LitSamples {
            samples: direct,
            balls,
            stats: Vec::new(),
        });
    }
    let (samples, figures) = frame.bounced_samples(settings, || {
        frame.timed("bounces", || {
            interreflection::bounced(frame, &direct, &balls, settings.bounces)
        })
    })?;
    let stats = figures
        .into_iter()
        .map(|(name, value)| Stat { name, value })
        .collect();
    Ok(LitSamples {
        samples,
        balls,
        stats,
    })
}

/// The sum at `x` over the tree, by Algorithm 1 (before the exit weight). With `balls` (the
/// tree's [`TreeBalls`] and x's radius in mm), each pair takes its own ball: a node is accepted
/// only where one radius stands for its samples, and a leaf sums each pair with its own.
pub(crate) fn single(
    tree: &IrradianceTree,
    x: DVec3,
    eps: f64,
    sh: &TranslucentShading,
    counts: &Counts,
    balls: Option<(&TreeBalls<'_>, f64)>,
) -> Rgb {
    let mut acc = [0.0; 3];
    if tree.tree.nodes.is_empty() {
        return acc;
    }
    let (mut visits, mut clusters, mut singles) = (0u64, 0u64, 0u64);
    let mut stack: Vec<u32> = Vec::with_capacity(64);
    stack.push(0);
    while let Some(k) = stack.pop() {
        visits += 1;
        let node = &tree.tree.nodes[k as usize];
        let cl = &tree.clusters[k as usize];
        let d2 = (cl.position - x).length_squared();
        // The node's one ball, if its samples share one (always, with one profile).
        let ball = match balls {
            Some((b, rx)) => b.nodes[k as usize].map(|r| Some(pair_ball(r, rx))),
            None => Some(None),
        };
        if let Some(ball) = ball
            && accepts(cl.area, d2, eps)
            && !inside(node, x)
        {
            let rd = match (ball, balls) {
                (Some(pair), Some((b, _))) => {
                    sh.rd_cluster_ball(d2.sqrt(), cl.area, b.family, pair)
                }
                _ => sh.rd_sample_scene(d2.sqrt(), cl.area),
            };
            add_scaled(&mut acc, rd_times(rd, cl.flux), 1.0);
            clusters += 1;
        } else if node.is_leaf() {
            match balls {
                Some((b, rx)) => b.add_samples(&mut acc, tree, node, x, rx, sh),
                None => add_samples(&mut acc, tree.points_of(node), x, sh),
            }
            singles += node.len() as u64;
        } else {
            // Right first, so the left subtree is summed first.
            stack.push(node.right);
            stack.push(node.left);
        }
    }
    counts.add(visits, clusters, singles);
    acc
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

/// The widest spread of ball radii, ln(R_max / R_min), over which one radius (their geometric
/// mean) stands for a tree node's points when each point has its own ball
/// (`sphere_radius = "local"`): radii within a factor 2, so a pair's radius √(R_i R_o) errs by
/// at most a factor √2 from a node's side, the ball family's node spacing. Measured against
/// `exact` on the truth experiment's bunny, dragon and head (`docs/compare.md`): a spread of
/// 0.2 costs 1.5–3 times the shading time for no error that shows (under 0.6 % relative RMSE
/// either way), and no limit at all adds little.
pub const BALL_SPREAD: f64 = std::f64::consts::LN_2;

/// Per node of `tree`, the ball radius (mm) that stands for its points when each point has
/// its own ball: their geometric mean where their radii `radii` (mm, in the tree's leaf
/// order; NaN: none) spread by at most [`BALL_SPREAD`] in ln R, NaN where none of them has a
/// radius (the half-space's profile), `None` where the node must be split (a wider spread, or
/// points with and without a radius).
pub(crate) fn node_balls<const D: usize>(tree: &KdTree<D>, radii: &[f64]) -> Vec<Option<f64>> {
    #[derive(Clone, Copy)]
    struct Span {
        n: u32,
        none: u32,
        lo: f64,
        hi: f64,
        sum_ln: f64,
    }
    let empty = Span {
        n: 0,
        none: 0,
        lo: f64::INFINITY,
        hi: f64::NEG_INFINITY,
        sum_ln: 0.0,
    };
    let spans = tree.bottom_up(
        empty,
        |node| {
            let mut s = empty;
            for &r in radii
                .get(node.start as usize..node.end as usize)
                .unwrap_or(&[])
            {
                s.n += 1;
                if r.is_finite() && r > 0.0 {
                    let l = r.ln();
                    s.lo = s.lo.min(l);
                    s.hi = s.hi.max(l);
                    s.sum_ln += l;
                } else {
                    s.none += 1;
                }
            }
            s
        },
        |a, b| Span {
            n: a.n + b.n,
            none: a.none + b.none,
            lo: a.lo.min(b.lo),
            hi: a.hi.max(b.hi),
            sum_ln: a.sum_ln + b.sum_ln,
        },
    );
    spans
        .iter()
        .map(|s| {
            if s.none == s.n {
                Some(f64::NAN)
            } else if s.none > 0 || !(s.hi - s.lo <= BALL_SPREAD) {
                None
            } else {
                // Every point has a radius here (s.none == 0).
                Some((s.sum_ln / f64::from(s.n)).exp())
            }
        })
        .collect()
}

/// The ball radius (mm) of a pair whose sides have radii `a` and `b`: √(a b), NaN when either
/// has none (the half-space's profile; [`crate::local_radius`]).
#[inline]
pub(crate) fn pair_ball(a: f64, b: f64) -> f64 {
    (a * b).sqrt()
}

/// One object's balls as the trees over its irradiance samples read them.
pub(crate) struct TreeBalls<'a> {
    /// The object's family of ball profiles.
    pub(crate) family: &'a BallFamily,
    /// Per irradiance sample in the illumination tree's leaf order, its radius (mm; NaN: none).
    pub(crate) samples: Vec<f64>,
    /// Per illumination-tree node, the radius that stands for its samples ([`node_balls`]).
    pub(crate) nodes: Vec<Option<f64>>,
}

impl<'a> TreeBalls<'a> {
    /// The balls of `tree`'s samples, from their object's `balls`.
    pub(crate) fn new(tree: &IrradianceTree, balls: &'a LocalBalls) -> Self {
        let samples: Vec<f64> = tree
            .tree
            .order
            .iter()
            .map(|&i| balls.samples.get(i as usize).copied().unwrap_or(f64::NAN))
            .collect();
        let nodes = node_balls(&tree.tree, &samples);
        TreeBalls {
            family: &balls.family,
            samples,
            nodes,
        }
    }

    /// Adds the point sum at `x` (radius `rx` mm) of the samples of `node`, each pair with its
    /// own ball ([`TranslucentShading::add_point_sum_local`], as `exact` sums them).
    pub(crate) fn add_samples(
        &self,
        acc: &mut Rgb,
        tree: &IrradianceTree,
        node: &KdNode<3>,
        x: DVec3,
        rx: f64,
        sh: &TranslucentShading,
    ) {
        let range = node.start as usize..node.end as usize;
        sh.add_point_sum_local(
            acc,
            x,
            self.family,
            tree.points[range.clone()]
                .iter()
                .zip(&self.samples[range])
                .map(|(p, &r)| (p.position, p.area, p.irradiance, pair_ball(rx, r))),
        );
    }
}

/// Per object (indexed by object), the [`TreeBalls`] of its illumination tree where its
/// material gives each point its own ball.
pub(crate) fn tree_balls<'a>(
    balls: &'a FrameBalls,
    trees: &[Option<IrradianceTree>],
) -> Vec<Option<TreeBalls<'a>>> {
    trees
        .iter()
        .enumerate()
        .map(|(o, t)| {
            let own = balls.objects.get(o)?.as_ref()?;
            Some(TreeBalls::new(t.as_ref()?, own))
        })
        .collect()
}

/// The stat `ball_radii` and the layer `local_radius` of a frame whose materials give each
/// point its own ball (nothing otherwise): `exact`'s and the trees' record of the balls.
pub(crate) fn ball_outputs(
    frame: &Frame<'_>,
    balls: &FrameBalls,
    stats: &mut Vec<Stat>,
    layers: &mut Vec<Layer>,
) {
    if balls.any() {
        stats.push(Stat {
            name: "ball_radii",
            value: balls.nodes() as f64,
        });
        layers.push(Layer {
            name: "local_radius",
            pixels: balls.pixel_radii(frame),
        });
    }
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
    /// The object's index in the scene.
    pub(crate) object: u32,
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
            object: o,
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

    /// A kd-tree over points on a line, leaves of `leaf` points, in the input's order (the
    /// points are sorted, so the leaf order is the input's).
    fn line(n: usize, leaf: usize) -> KdTree<1> {
        let points: Vec<[f64; 1]> = (0..n).map(|i| [i as f64]).collect();
        let tree = KdTree::build(&points, leaf);
        assert!(tree.order.iter().enumerate().all(|(k, &i)| k == i as usize));
        tree
    }

    /// A node's ball is the geometric mean of its points' radii while they spread by at most
    /// BALL_SPREAD in ln R; wider, or with points with and without a radius, it has none; with
    /// none having one, NaN (the half-space's profile).
    #[test]
    fn a_node_takes_one_ball_only_where_its_points_share_one() {
        let tree = line(8, 2);
        let root = 0;
        let leaves: Vec<usize> = (0..tree.nodes.len())
            .filter(|&k| tree.nodes[k].is_leaf())
            .collect();
        // Radii spreading by e^0.15 over the whole line: every node takes their mean.
        let radii: Vec<f64> = (0..8)
            .map(|i| 2.0 * (0.15 * i as f64 / 7.0).exp())
            .collect();
        let balls = node_balls(&tree, &radii);
        let mean = 2.0 * (0.15f64 * 0.5).exp();
        let b = balls[root].unwrap();
        assert!((b / mean - 1.0).abs() < 1e-12, "{b} vs {mean}");
        // Spread beyond BALL_SPREAD over the line (but not within a leaf of two): the root is
        // split, each leaf has its own ball, between its two radii.
        let radii: Vec<f64> = (0..8).map(|i| 2.0 * (0.2 * i as f64).exp()).collect();
        let balls = node_balls(&tree, &radii);
        assert_eq!(balls[root], None);
        for &k in &leaves {
            let n = &tree.nodes[k];
            let (a, z) = (radii[n.start as usize], radii[n.end as usize - 1]);
            let b = balls[k].unwrap();
            assert!(a <= b && b <= z, "leaf {k}: {b} not in [{a}, {z}]");
            assert!((b - (a * z).sqrt()).abs() < 1e-12 * b);
        }
        // One point without a radius: its leaf and every node above it are split; none with
        // one: NaN.
        let mut radii = vec![3.0; 8];
        radii[5] = f64::NAN;
        let balls = node_balls(&tree, &radii);
        assert_eq!(balls[root], None);
        let holder = leaves
            .iter()
            .find(|&&k| (tree.nodes[k].start..tree.nodes[k].end).contains(&5))
            .unwrap();
        assert_eq!(balls[*holder], None);
        assert!(
            leaves
                .iter()
                .filter(|&&k| k != *holder)
                .all(|&k| balls[k].is_some_and(|b| (b - 3.0).abs() < 1e-12))
        );
        // No radius (NaN), and radii that are none (0, negative, infinite): every node takes
        // the half-space's profile.
        for none in [f64::NAN, 0.0, -1.0, f64::INFINITY] {
            let balls = node_balls(&tree, &[none; 8]);
            assert!(balls.iter().all(|b| b.is_some_and(f64::is_nan)), "{none}");
        }
        // Radii a factor 2 apart still stand as one, a hair more do not.
        let radii: Vec<f64> = (0..8).map(|i| if i < 4 { 1.0 } else { 2.0 }).collect();
        assert!(node_balls(&tree, &radii)[root].is_some());
        let radii: Vec<f64> = (0..8).map(|i| if i < 4 { 1.0 } else { 2.01 }).collect();
        assert_eq!(node_balls(&tree, &radii)[root], None);
    }

    #[test]
    fn a_pairs_ball_is_the_geometric_mean_and_nan_without_one() {
        assert!((pair_ball(2.0, 8.0) - 4.0).abs() < 1e-15);
        assert!(pair_ball(f64::NAN, 8.0).is_nan());
        assert!(pair_ball(3.0, f64::NAN).is_nan());
    }
}
