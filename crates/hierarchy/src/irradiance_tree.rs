//! The illumination tree of Jensen & Buhler 2002 (§4, "A rapid hierarchical rendering
//! technique for translucent materials") and Milaenen et al. 2019 (§4.1): a kd-tree over one
//! object's irradiance samples whose nodes aggregate their samples, so a distant cluster can
//! stand for all of them in one BSSRDF evaluation.
//!
//! Node aggregates (bottom-up, each equal to the sum over the node's range):
//! * total area A = Σ A_i;
//! * area-weighted irradiance, kept as the flux ΣE_i A_i (the mean irradiance is ΣE A / A);
//! * the representative position p = Σ w_i x_i / Σ w_i with w_i = lum(E_i) A_i (irradiance
//!   weighted, as the papers say; Mitsuba's `irrtree` uses the same luminance × area weights),
//!   falling back to area weights where the node receives no light, so p is always inside the
//!   node's bounding box;
//! * the bounding box of the sample positions.

use crate::kdtree::{KdNode, KdTree};
use glam::DVec3;
use sss_util::LUMINANCE;

/// One irradiance sample, as the tree needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrradiancePoint {
    /// Position on the surface.
    pub position: DVec3,
    /// Area it stands for (≥ 0).
    pub area: f64,
    /// Irradiance (RGB, ≥ 0).
    pub irradiance: [f64; 3],
}

/// A node's aggregates (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrradianceCluster {
    /// Σ A_i.
    pub area: f64,
    /// Σ E_i A_i, per channel.
    pub flux: [f64; 3],
    /// Irradiance-weighted mean position (area-weighted if the node is dark).
    pub position: DVec3,
}

/// A kd-tree over irradiance samples with per-node [`IrradianceCluster`]s.
#[derive(Clone, Debug)]
pub struct IrradianceTree {
    /// The kd-tree (its `order` indexes the input samples).
    pub tree: KdTree<3>,
    /// Aggregates, indexed like `tree.nodes`.
    pub clusters: Vec<IrradianceCluster>,
    /// The samples in leaf order (`points[k]` is input sample `tree.order[k]`), so a leaf's
    /// samples are the contiguous `points[start..end]`.
    pub points: Vec<IrradiancePoint>,
}

/// Per-node sums used to build the aggregates.
#[derive(Clone, Copy, Default)]
struct Sums {
    area: f64,
    flux: [f64; 3],
    weight: f64,
    weighted: DVec3,
    area_weighted: DVec3,
}

impl Sums {
    fn add(&mut self, o: &Sums) {
        self.area += o.area;
        for c in 0..3 {
            self.flux[c] += o.flux[c];
        }
        self.weight += o.weight;
        self.weighted += o.weighted;
        self.area_weighted += o.area_weighted;
    }

    fn of(p: &IrradiancePoint) -> Sums {
        let a = p.area;
        let flux = [
            p.irradiance[0] * a,
            p.irradiance[1] * a,
            p.irradiance[2] * a,
        ];
        let w = (0..3).map(|c| LUMINANCE[c] * flux[c]).sum::<f64>();
        Sums {
            area: a,
            flux,
            weight: w,
            weighted: p.position * w,
            area_weighted: p.position * a,
        }
    }

    fn cluster(&self, node: &KdNode<3>, first: DVec3) -> IrradianceCluster {
        let position = if self.weight > 0.0 {
            self.weighted / self.weight
        } else if self.area > 0.0 {
            self.area_weighted / self.area
        } else {
            first
        };
        // Rounding can put the weighted mean a hair outside the box.
        let lo = DVec3::from_array(node.lo);
        let hi = DVec3::from_array(node.hi);
        IrradianceCluster {
            area: self.area,
            flux: self.flux,
            position: position.clamp(lo, hi),
        }
    }
}

impl IrradianceTree {
    /// Builds the tree over `samples` with at most `leaf_size` samples per leaf. Samples with a
    /// non-finite position are the caller's bug; negative or non-finite areas and irradiances
    /// count as 0.
    pub fn build(samples: &[IrradiancePoint], leaf_size: usize) -> Self {
        let coords: Vec<[f64; 3]> = samples.iter().map(|s| s.position.to_array()).collect();
        let tree = KdTree::build(&coords, leaf_size);
        let clean = |x: f64| if x.is_finite() && x > 0.0 { x } else { 0.0 };
        let points: Vec<IrradiancePoint> = tree
            .order
            .iter()
            .map(|&i| {
                let s = samples[i as usize];
                IrradiancePoint {
                    position: s.position,
                    area: clean(s.area),
                    irradiance: s.irradiance.map(clean),
                }
            })
            .collect();
        let sums = tree.bottom_up(
            Sums::default(),
            |node| {
                let mut s = Sums::default();
                for p in &points[node.start as usize..node.end as usize] {
                    s.add(&Sums::of(p));
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
            .map(|(n, s)| s.cluster(n, points[n.start as usize].position))
            .collect();
        IrradianceTree {
            tree,
            clusters,
            points,
        }
    }

    /// The samples of node `n`, contiguous.
    #[inline]
    pub fn points_of(&self, n: &KdNode<3>) -> &[IrradiancePoint] {
        &self.points[n.start as usize..n.end as usize]
    }

    /// Bytes this tree will take for `n` samples at `leaf_size` (an upper bound: at most
    /// 2⌈n/⌊leaf/2⌋⌉ nodes), for memory budgets before the build.
    pub fn bytes_for(n: usize, leaf_size: usize) -> u64 {
        let leaves = n.div_ceil((leaf_size / 2).max(1)) as u64;
        let nodes = 2 * leaves;
        nodes * (std::mem::size_of::<KdNode<3>>() + std::mem::size_of::<IrradianceCluster>()) as u64
            + n as u64 * (4 + 2 * std::mem::size_of::<IrradiancePoint>() as u64)
    }
}
