//! Gather points and the gather tree of the two baselines, Multidimensional Lightcuts
//! ([`crate::mdlc`]) and the error estimation for Lightcuts ([`crate::eelc`]), which work on a
//! FIXED set of irradiance points per shading point instead of the triangle clusters of
//! [`crate::irradiance_cluster`].
//!
//! # Gather points
//!
//! For each shading point x_o (weight w(x_o), Nabata & Iwasaki Eq. 2) the caller draws N
//! irradiance points x_k with density p(x_k | x_o) per unit area, either by BSSRDF importance
//! sampling (King et al. 2013; the renderer's probe rays) or uniformly by area over the mesh
//! ([`uniform_points`], p = 1/A). Each carries the area weight A_k = 1/(N p(x_k | x_o))
//! ([`IrradiancePoint::area`]), so that
//!
//! ```text
//! Σ_{x_o} w(x_o) Σ_k A_k R_d(‖x_k − x_o‖) Σ_y I(y) H(y, x_k)
//! ```
//!
//! is an unbiased estimate of the pixel value of Eq. 1 (E_p[f/(N p)] summed over N draws is ∫ f
//! dA wherever p > 0). A **gather point** is one pair (x_o, x_k) folded into one point at x_k
//! with strength S = w(x_o) A_k R_d(‖x_k − x_o‖) per RGB channel ([`gather_points`]): the
//! weight of the eye subpath camera → x_o → x_k, as the gather points of Bidirectional Lightcuts
//! (Walter, Khungurn & Bala 2012, ref. \[16\] of the paper, which brings BSSRDF importance
//! sampling into Lightcuts). R_d is thus known exactly per gather point, and what is left to
//! cluster is the light transport from the VPLs, I(y) H(y, x_k) with H = G V F_t (Eq. 3 of the
//! paper), so the pair bounds need no R_d bound (tighter than R_d(r_min) over cluster boxes).
//!
//! # The gather tree
//!
//! A pixel's gather points (all its shading points' irradiance points on one object) in a
//! binary tree built like the other trees of this crate (median split along the longest axis,
//! one point per leaf, `binary_tree.rs`); each node holds the box, the normal cone (for the
//! cosine bound of MDLC, [`crate::cone`]), the summed RGB strength and its luminance, the
//! largest chroma factor below (see [`GatherNode::chroma`]) and a representative point chosen
//! at random in proportion to strength from its children (as MDLC picks them: that choice
//! makes the representative's estimate of a cluster unbiased over the choice), seeded so that
//! the tree is a function of its input and seed.

use glam::DVec3;

use crate::Error;
use crate::aabb::Aabb;
use crate::binary_tree::{descend, median_split};
use crate::cone::NormalCone;
use crate::irradiance_cluster::TriangleClusterTree;
use crate::profile::{RadialProfile, luminance};
use crate::shading_cluster::ShadingPoint;

/// An irradiance point x_k drawn for one shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrradiancePoint {
    /// Position on the surface.
    pub position: DVec3,
    /// Unit shading normal there (outward; the mesh's interpolated normal): cos θ_i is taken
    /// against it, as `manylight`, `exact` and `pathtrace` take it.
    pub normal: DVec3,
    /// Unit geometric normal of the triangle there (outward): a light below its plane cannot
    /// reach the point, whatever the shading normal (zero: no such test).
    pub geometric: DVec3,
    /// Area weight A_k = 1/(N p(x_k | x_o)) (length²): the point's share of the surface in
    /// an N-point estimate.
    pub area: f64,
}

/// A gather point: an irradiance point x_k with the strength S = w(x_o) A_k R_d(‖x_k − x_o‖)
/// of the shading point x_o it was drawn for (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GatherPoint {
    /// Position x_k.
    pub position: DVec3,
    /// Unit shading normal at x_k (see [`IrradiancePoint::normal`]).
    pub normal: DVec3,
    /// Unit geometric normal at x_k (see [`IrradiancePoint::geometric`]).
    pub geometric: DVec3,
    /// RGB strength, each ≥ 0 (the units of w · R_d · A).
    pub strength: [f64; 3],
}

impl GatherPoint {
    /// The scalar strength `LUMINANCE · strength` by which gather points are sampled.
    pub fn scalar(&self) -> f64 {
        luminance(self.strength)
    }
}

/// Appends the gather points of one shading point `x_o` and its irradiance points: strength
/// w(x_o) A_k R_d(‖x_k − x_o‖) per channel. Points of zero strength (R_d underflowed, A_k = 0,
/// w = 0) contribute exactly 0 and are left out; non-finite strengths are left out too (they
/// cannot arise from finite inputs and a checked profile).
pub fn gather_points(
    x_o: &ShadingPoint,
    points: &[IrradiancePoint],
    profile: &RadialProfile,
    out: &mut Vec<GatherPoint>,
) {
    for p in points {
        let s = x_o.weight * p.area;
        if !(s > 0.0 && s.is_finite()) {
            continue;
        }
        let rd = profile.eval(p.position.distance(x_o.position));
        let strength = rd.map(|v| s * v);
        if strength.iter().all(|v| v.is_finite() && *v >= 0.0) && luminance(strength) > 0.0 {
            out.push(GatherPoint {
                position: p.position,
                normal: p.normal,
                geometric: p.geometric,
                strength,
            });
        }
    }
}

/// Appends `n` points drawn uniformly by area over the mesh of `surface` (a triangle in
/// proportion to its area, then a uniform point on it: density 1/A, Nabata & Iwasaki Eq. 7 over
/// the whole mesh), each with area weight A/n; `next` gives uniforms in [0, 1) (three per point).
pub fn uniform_points(
    surface: &TriangleClusterTree,
    n: usize,
    next: &mut impl FnMut() -> f64,
    out: &mut Vec<IrradiancePoint>,
) {
    if n == 0 {
        return;
    }
    let area = surface.area() / n as f64;
    for _ in 0..n {
        let u = [next(), next(), next()];
        let at = surface.sample_uniform(u);
        out.push(IrradiancePoint {
            position: at.position,
            normal: at.normal,
            geometric: at.geometric,
            area,
        });
    }
}

/// A node of the [`GatherTree`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GatherNode {
    /// Box of the points below.
    pub bbox: Aabb,
    /// A cone holding the normals below (`None` when a point has a zero normal).
    pub cone: Option<NormalCone>,
    /// Summed RGB strength of the points below (MDLC's cluster strength).
    pub rgb: [f64; 3],
    /// Summed scalar strength (luminance) of the points below.
    pub strength: f64,
    /// The largest chroma factor max_c S_c / (LUMINANCE · S) of a point below (≥ 1 for any
    /// non-zero strength, since the luminance weights sum to 1): a sample drawn in proportion to
    /// scalar strength and reweighted by its colour has luminance at most this times its
    /// scalar weight (the EELC bound, [`crate::eelc`]).
    pub chroma: f64,
    /// Representative point (index into [`GatherTree::points`]).
    pub representative: u32,
    /// Children, or `None` for a leaf holding one point.
    pub children: Option<[u32; 2]>,
}

/// A binary tree over one pixel's gather points on one object (see the module doc).
#[derive(Clone, Debug)]
pub struct GatherTree {
    points: Vec<GatherPoint>,
    nodes: Vec<GatherNode>,
}

/// Most gather points in one tree (the node indices are `u32`).
pub const MAX_GATHER_POINTS: usize = 1 << 30;

impl GatherTree {
    /// Builds the tree; `seed` picks the representatives. Errors: no points, more than
    /// [`MAX_GATHER_POINTS`], a non-finite position, a normal that is neither unit nor zero,
    /// or a strength that is negative, not finite, or of zero luminance.
    pub fn new(points: Vec<GatherPoint>, seed: u64) -> Result<GatherTree, Error> {
        if points.is_empty() {
            return Err(Error::InvalidInput("no gather points".into()));
        }
        if points.len() > MAX_GATHER_POINTS {
            return Err(Error::InvalidInput(format!(
                "{} gather points in one pixel (at most 2^30)",
                points.len()
            )));
        }
        for (k, p) in points.iter().enumerate() {
            let unit_or_zero =
                |n: DVec3| n == DVec3::ZERO || (n.is_finite() && (n.length() - 1.0).abs() < 1e-6);
            let ok_n = unit_or_zero(p.normal) && unit_or_zero(p.geometric);
            let ok_s = p.strength.iter().all(|v| v.is_finite() && *v >= 0.0) && p.scalar() > 0.0;
            if !(p.position.is_finite() && ok_n && ok_s) {
                return Err(Error::InvalidInput(format!(
                    "gather point {k}: position {:?}, normals {:?} and {:?}, strength {:?} (need \
                     finite position, unit or zero normals, finite strength ≥ 0 with luminance > \
                     0)",
                    p.position, p.normal, p.geometric, p.strength
                )));
            }
        }
        let positions: Vec<DVec3> = points.iter().map(|p| p.position).collect();
        let leaf = |k: u32| {
            let p = &points[k as usize];
            let s = p.scalar();
            GatherNode {
                bbox: Aabb::point(p.position),
                cone: (p.normal != DVec3::ZERO).then_some(NormalCone {
                    axis: p.normal,
                    half_angle: 0.0,
                }),
                rgb: p.strength,
                strength: s,
                chroma: p.strength[0].max(p.strength[1]).max(p.strength[2]) / s,
                representative: k,
                children: None,
            }
        };
        let inner = |a: &GatherNode, b: &GatherNode, children: [u32; 2]| {
            let strength = a.strength + b.strength;
            // Representative: a's with probability S_a / (S_a + S_b), from a uniform hashed
            // from the seed and the node (its first child's id is unique to it).
            let u = unit(sss_util::splitmix64(
                seed ^ sss_util::splitmix64(u64::from(children[0])),
            ));
            let representative = if u * strength < a.strength {
                a.representative
            } else {
                b.representative
            };
            GatherNode {
                bbox: a.bbox.union(b.bbox),
                cone: match (a.cone, b.cone) {
                    (Some(x), Some(y)) => Some(x.union(y)),
                    _ => None,
                },
                rgb: [0, 1, 2].map(|c| a.rgb[c] + b.rgb[c]),
                strength,
                chroma: a.chroma.max(b.chroma),
                representative,
                children: Some(children),
            }
        };
        let nodes = median_split(&positions, leaf, inner);
        Ok(GatherTree { points, nodes })
    }

    /// The points (input order).
    pub fn points(&self) -> &[GatherPoint] {
        &self.points
    }

    /// All nodes; the root is node 0, children have larger ids than their parent.
    pub fn nodes(&self) -> &[GatherNode] {
        &self.nodes
    }

    /// One node.
    #[inline]
    pub fn node(&self, id: u32) -> &GatherNode {
        &self.nodes[id as usize]
    }

    /// The root id (0).
    pub fn root(&self) -> u32 {
        0
    }

    /// The point of a leaf (its representative), or `None` for an inner node.
    pub fn leaf_point(&self, id: u32) -> Option<u32> {
        let n = &self.nodes[id as usize];
        n.children.is_none().then_some(n.representative)
    }

    /// Samples a point below `id` with probability `scalar / node.strength` from one uniform in
    /// [0, 1), by descending in proportion to the children's scalar strengths. Returns the point.
    pub fn sample(&self, id: u32, u: f64) -> u32 {
        let nodes = &self.nodes;
        let (leaf, _) = descend(
            id,
            u,
            |n| nodes[n as usize].children,
            |n| nodes[n as usize].strength,
        );
        nodes[leaf as usize].representative
    }

    /// The most bytes building and holding a tree of `n` points takes: the points, the nodes
    /// (2n − 1), and the builder's temporaries (positions, order, shape and the nodes once more
    /// while they are filled in).
    pub fn peak_bytes(n: usize) -> u64 {
        let n = n as u64;
        let node = size_of::<GatherNode>() as u64;
        let per_point = size_of::<GatherPoint>() as u64 + size_of::<DVec3>() as u64 + 4;
        n * per_point + 2 * n * (3 * node + 16)
    }
}

/// A uniform in [0, 1) from the top 53 bits of a 64-bit hash.
#[inline]
pub(crate) fn unit(x: u64) -> f64 {
    (x >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}
