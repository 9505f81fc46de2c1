//! The shading (pixel) tree of Milaenen et al. 2019 (§4.2): a kd-tree over one object's
//! shading points, built over their **screen** coordinates so that a node's extent is in
//! pixels (the quantity Eq. 6 compares with ρ / max s_p), with world-space aggregates for the
//! solid-angle and overlap tests of Algorithm 2.
//!
//! Building over screen coordinates is `../shared/docs/wave2.md` F1.0 item 3: the paper's
//! limitation paragraph (pixels grouped across staggered depth discontinuities) only happens
//! with a screen-space build.
//!
//! Node aggregates (each equal to the same quantity computed over the node's range):
//! * the screen-space bounding box (from the kd-tree) and its largest side, the node's
//!   LENGTH in pixels;
//! * the world-space bounding box of the points;
//! * the mean world position, mean normal and mean view direction (plain means of the
//!   points' vectors; a mean normal is not renormalised, its length says how much the
//!   normals agree);
//! * the largest sampling rate s_p of its points.

use crate::kdtree::{KdNode, KdTree};
use glam::DVec3;

/// One shading point, as the tree needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelPoint {
    /// Screen position in pixels (x right, y down; a pixel's centre is at +0.5).
    pub screen: [f64; 2],
    /// World position.
    pub position: DVec3,
    /// Unit shading normal.
    pub normal: DVec3,
    /// Unit direction towards the camera.
    pub view: DVec3,
    /// The sampling rate s_p at this point (samples per pixel, Eq. 5); ≥ 0.
    pub rate: f64,
}

/// A node's world-space aggregates (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelCluster {
    /// Lower corner of the world-space bounding box.
    pub world_lo: DVec3,
    /// Upper corner of the world-space bounding box.
    pub world_hi: DVec3,
    /// Mean world position.
    pub position: DVec3,
    /// Mean normal (not renormalised).
    pub normal: DVec3,
    /// Mean view direction (not renormalised).
    pub view: DVec3,
    /// max s_p over the node's points.
    pub max_rate: f64,
}

/// A kd-tree over shading points with per-node [`PixelCluster`]s.
#[derive(Clone, Debug)]
pub struct PixelTree {
    /// The kd-tree over screen positions (its `order` indexes the input points).
    pub tree: KdTree<2>,
    /// Aggregates, indexed like `tree.nodes`.
    pub clusters: Vec<PixelCluster>,
}

#[derive(Clone, Copy)]
struct Sums {
    lo: DVec3,
    hi: DVec3,
    position: DVec3,
    normal: DVec3,
    view: DVec3,
    max_rate: f64,
}

impl Sums {
    const EMPTY: Sums = Sums {
        lo: DVec3::INFINITY,
        hi: DVec3::NEG_INFINITY,
        position: DVec3::ZERO,
        normal: DVec3::ZERO,
        view: DVec3::ZERO,
        max_rate: 0.0,
    };

    fn add(&mut self, o: &Sums) {
        self.lo = self.lo.min(o.lo);
        self.hi = self.hi.max(o.hi);
        self.position += o.position;
        self.normal += o.normal;
        self.view += o.view;
        self.max_rate = self.max_rate.max(o.max_rate);
    }

    fn of(p: &PixelPoint) -> Sums {
        let rate = if p.rate > 0.0 {
            p.rate.min(f64::MAX)
        } else {
            0.0
        };
        Sums {
            lo: p.position,
            hi: p.position,
            position: p.position,
            normal: p.normal,
            view: p.view,
            max_rate: rate,
        }
    }
}

impl PixelTree {
    /// Builds the tree over `points` with at most `leaf_size` points per leaf. Positions must
    /// be finite; a NaN or negative rate counts as 0, an infinite one as `f64::MAX`.
    pub fn build(points: &[PixelPoint], leaf_size: usize) -> Self {
        let coords: Vec<[f64; 2]> = points.iter().map(|p| p.screen).collect();
        let tree = KdTree::build(&coords, leaf_size);
        let sums = tree.bottom_up(
            Sums::EMPTY,
            |node| {
                let mut s = Sums::EMPTY;
                for &i in tree.items(node) {
                    s.add(&Sums::of(&points[i as usize]));
                }
                s
            },
            |l, r| {
                let mut s = *l;
                s.add(r);
                s
            },
        );
        let clusters = tree
            .nodes
            .iter()
            .zip(&sums)
            .map(|(n, s)| {
                let inv = 1.0 / n.len().max(1) as f64;
                PixelCluster {
                    world_lo: s.lo,
                    world_hi: s.hi,
                    position: (s.position * inv).clamp(s.lo, s.hi),
                    normal: s.normal * inv,
                    view: s.view * inv,
                    max_rate: s.max_rate,
                }
            })
            .collect();
        PixelTree { tree, clusters }
    }

    /// The node's LENGTH: the largest side of its screen-space bounding box, in pixels (0 for
    /// points that share one screen position).
    #[inline]
    pub fn length_px(&self, n: &KdNode<2>) -> f64 {
        n.extent()
    }

    /// Bytes this tree will take for `n` points at `leaf_size` (an upper bound), for memory
    /// budgets before the build.
    pub fn bytes_for(n: usize, leaf_size: usize) -> u64 {
        let leaves = n.div_ceil((leaf_size / 2).max(1)) as u64;
        let nodes = 2 * leaves;
        nodes * (std::mem::size_of::<KdNode<2>>() + std::mem::size_of::<PixelCluster>()) as u64
            + n as u64 * (4 + 16)
    }
}
