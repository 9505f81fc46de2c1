//! Shading clusters (SCs): a binary tree over one pixel's shading points (the camera samples
//! that hit the translucent object), as the gather tree of Multidimensional Lightcuts (Walter
//! et al. 2006), with the weights w(x_o) of Nabata & Iwasaki Eq. 2.

use glam::DVec3;

use crate::Error;
use crate::aabb::Aabb;

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
        let blank = ShadingNode {
            bbox: Aabb::EMPTY,
            weight: 0.0,
            children: None,
            point: 0,
        };
        let mut order: Vec<u32> = (0..points.len() as u32).collect();
        let mut nodes = vec![blank];
        let mut stack = vec![(0u32, 0usize, points.len())];
        let mut post = Vec::new();
        while let Some((node, lo, hi)) = stack.pop() {
            let range = &mut order[lo..hi];
            if range.len() == 1 {
                let p = &points[range[0] as usize];
                nodes[node as usize] = ShadingNode {
                    bbox: Aabb::point(p.position),
                    weight: p.weight,
                    children: None,
                    point: range[0],
                };
                continue;
            }
            let e = range
                .iter()
                .fold(Aabb::EMPTY, |b, &k| b.grow(points[k as usize].position))
                .extent();
            let axis = if e.x >= e.y && e.x >= e.z {
                0
            } else if e.y >= e.z {
                1
            } else {
                2
            };
            range.sort_unstable_by(|&p, &q| {
                points[p as usize].position[axis]
                    .total_cmp(&points[q as usize].position[axis])
                    .then(p.cmp(&q))
            });
            let mid = lo + range.len() / 2;
            let (l, r) = (nodes.len() as u32, nodes.len() as u32 + 1);
            nodes.push(blank);
            nodes.push(blank);
            nodes[node as usize].children = Some([l, r]);
            post.push(node);
            stack.push((l, lo, mid));
            stack.push((r, mid, hi));
        }
        for &id in post.iter().rev() {
            let [l, r] = nodes[id as usize].children.expect("inner node");
            let (a, b) = (nodes[l as usize], nodes[r as usize]);
            nodes[id as usize] = ShadingNode {
                bbox: a.bbox.union(b.bbox),
                weight: a.weight + b.weight,
                children: Some([l, r]),
                point: a.point,
            };
        }
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
    pub fn sample(&self, mut id: u32, mut u: f64) -> u32 {
        loop {
            let n = &self.nodes[id as usize];
            let Some([a, b]) = n.children else {
                return n.point;
            };
            let (wa, wb) = (self.nodes[a as usize].weight, self.nodes[b as usize].weight);
            let pa = if wa + wb > 0.0 { wa / (wa + wb) } else { 1.0 };
            if u < pa || wb <= 0.0 {
                u = if pa > 0.0 {
                    (u / pa).min(1.0 - f64::EPSILON)
                } else {
                    0.0
                };
                id = a;
            } else {
                u = ((u - pa) / (1.0 - pa)).clamp(0.0, 1.0 - f64::EPSILON);
                id = b;
            }
        }
    }
}
