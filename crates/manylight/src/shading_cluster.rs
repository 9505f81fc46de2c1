//! Shading clusters (SCs): a binary tree over one pixel's shading points (the camera samples
//! that hit the translucent object), as the gather tree of Multidimensional Lightcuts (Walter
//! et al. 2006), with the weights w(x_o) of Nabata & Iwasaki Eq. 2.

use glam::DVec3;

use crate::Error;
use crate::aabb::Aabb;
use crate::binary_tree::{descend, median_split};

/// A shading point x_o with its weight w(x_o) = W(x_o) F_t(x_o) / (π p(x_o) |S|) (Eq. 2): the
/// caller folds the pixel filter, the exit Fresnel factor and the sample count into `weight`,
/// so the pixel value is Σ_{x_o} w(x_o) ∫ R_d E dA (Eq. 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingPoint {
    /// Position.
    pub position: DVec3,
    /// Unit shading normal (kept for callers and future cone bounds; the estimator's bounds do
    /// not need it because F_t(x_o) is in the weight).
    pub normal: DVec3,
    /// Weight w(x_o) ≥ 0.
    pub weight: f64,
}

/// A node of the [`ShadingTree`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingNode {
    /// Box of the points below.
    pub bbox: Aabb,
    /// Sum of their weights (W_j of Eq. 5).
    pub weight: f64,
    /// Children, or `None` for a leaf of one point.
    pub children: Option<[u32; 2]>,
    /// The point of a leaf.
    pub point: u32,
}

/// A binary tree over a pixel's shading points, built top-down by median split along the
/// longest axis (one point per leaf).
#[derive(Clone, Debug)]
pub struct ShadingTree {
    points: Vec<ShadingPoint>,
    nodes: Vec<ShadingNode>,
}

impl ShadingTree {
    /// Builds the tree. Errors: no points, more than 2²⁰, a non-finite position, or a negative
    /// or non-finite weight.
    pub fn new(points: Vec<ShadingPoint>) -> Result<ShadingTree, Error> {
        if points.is_empty() {
            return Err(Error::InvalidInput("no shading points".into()));
        }
        if points.len() > (1 << 20) {
            return Err(Error::InvalidInput(format!(
                "{} shading points in one pixel (at most 2^20)",
                points.len()
            )));
        }
        for (k, p) in points.iter().enumerate() {
            if !(p.position.is_finite() && p.weight.is_finite() && p.weight >= 0.0) {
                return Err(Error::InvalidInput(format!(
                    "shading point {k}: position {:?}, weight {} (need finite, weight ≥ 0)",
                    p.position, p.weight
                )));
            }
        }
        let positions: Vec<DVec3> = points.iter().map(|p| p.position).collect();
        let nodes = median_split(
            &positions,
            |k| ShadingNode {
                bbox: Aabb::point(points[k as usize].position),
                weight: points[k as usize].weight,
                children: None,
                point: k,
            },
            |a, b, children| ShadingNode {
                bbox: a.bbox.union(b.bbox),
                weight: a.weight + b.weight,
                children: Some(children),
                point: a.point,
            },
        );
        Ok(ShadingTree { points, nodes })
    }

    /// The points (input order).
    pub fn points(&self) -> &[ShadingPoint] {
        &self.points
    }

    /// All nodes; the root is node 0.
    pub fn nodes(&self) -> &[ShadingNode] {
        &self.nodes
    }

    /// One node.
    #[inline]
    pub fn node(&self, id: u32) -> &ShadingNode {
        &self.nodes[id as usize]
    }

    /// Samples a point below `id` with probability `weight / node.weight` (p_S of Eq. 5) from
    /// one uniform in [0, 1). Returns the point index.
    pub fn sample(&self, id: u32, u: f64) -> u32 {
        let nodes = &self.nodes;
        let (leaf, _) = descend(
            id,
            u,
            |n| nodes[n as usize].children,
            |n| nodes[n as usize].weight,
        );
        nodes[leaf as usize].point
    }
}
