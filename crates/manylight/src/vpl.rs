//! Virtual point lights and the binary light tree of Multidimensional Lightcuts (Walter et al.
//! 2006, §4: a binary tree whose nodes carry a bounding box, the total intensity, a
//! representative and, for oriented lights, a normal cone).

use glam::DVec3;

use crate::Error;
use crate::aabb::Aabb;
use crate::binary_tree::{descend, median_split};
pub use crate::cone::NormalCone;
use crate::profile::luminance;

/// What kind of emitter a VPL is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VplKind {
    /// An isotropic point light: radiant intensity `I` (W/sr) in every direction.
    Point,
    /// A cosine (Lambertian) emitter with a normal: intensity `I cos θ_y` towards a direction at
    /// angle θ_y from the normal, 0 behind it. A sample of an area light with power Φ spread over
    /// N samples has `I = Φ/(N π)` (Keller 1997, instant radiosity).
    Oriented,
}

/// One virtual point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vpl {
    /// Position.
    pub position: DVec3,
    /// Unit normal for [`VplKind::Oriented`], `None` for a point light.
    pub normal: Option<DVec3>,
    /// RGB intensity (W/sr; along the normal for an oriented VPL), each ≥ 0.
    pub intensity: [f64; 3],
}

impl Vpl {
    /// An isotropic point light.
    pub fn point(position: DVec3, intensity: [f64; 3]) -> Vpl {
        Vpl {
            position,
            normal: None,
            intensity,
        }
    }

    /// A cosine emitter; `normal` is normalised here.
    pub fn oriented(position: DVec3, normal: DVec3, intensity: [f64; 3]) -> Vpl {
        Vpl {
            position,
            normal: Some(normal.normalize_or_zero()),
            intensity,
        }
    }

    /// Its kind.
    pub fn kind(&self) -> VplKind {
        if self.normal.is_some() {
            VplKind::Oriented
        } else {
            VplKind::Point
        }
    }

    /// The scalar intensity `LUMINANCE · intensity` by which VPLs are sampled (p_L of Eq. 5).
    pub fn scalar_intensity(&self) -> f64 {
        luminance(self.intensity)
    }

    /// The emission factor towards the unit direction `dir` (from the VPL to the receiver):
    /// 1 for a point light, max(0, n · dir) for an oriented one.
    #[inline]
    pub fn emission_cos(&self, dir: DVec3) -> f64 {
        match self.normal {
            None => 1.0,
            Some(n) => n.dot(dir).max(0.0),
        }
    }

    fn validate(&self, k: usize) -> Result<(), Error> {
        let ok_pos = self.position.is_finite();
        let ok_int = self.intensity.iter().all(|v| v.is_finite() && *v >= 0.0);
        let ok_n = self
            .normal
            .is_none_or(|n| n.is_finite() && (n.length() - 1.0).abs() < 1e-6);
        if ok_pos && ok_int && ok_n {
            Ok(())
        } else {
            Err(Error::InvalidInput(format!(
                "VPL {k}: position {:?}, normal {:?}, intensity {:?} (need finite position, \
                 unit normal or none, finite intensity ≥ 0)",
                self.position, self.normal, self.intensity
            )))
        }
    }
}

/// A node of the [`LightTree`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightNode {
    /// Box of the VPL positions below.
    pub bbox: Aabb,
    /// Sum of the scalar intensities below (I_j of Eq. 5).
    pub intensity: f64,
    /// Representative VPL (index into [`LightTree::vpls`]): the brighter child's
    /// representative (MDLC picks it at random in proportion to intensity; a deterministic
    /// choice keeps the tree reproducible). The estimator does not use it; MDLC does.
    pub representative: u32,
    /// Normal cone when every VPL below is oriented, `None` otherwise (a point light emits
    /// everywhere).
    pub cone: Option<NormalCone>,
    /// Children, or `None` for a leaf holding exactly one VPL.
    pub children: Option<[u32; 2]>,
    /// The VPL of a leaf (equal to `representative`).
    pub vpl: u32,
}

/// A binary tree over VPLs, built top-down by median split of the positions along the longest
/// axis of their box (one VPL per leaf). Shared by all pixels (`Send + Sync`).
#[derive(Clone, Debug)]
pub struct LightTree {
    vpls: Vec<Vpl>,
    nodes: Vec<LightNode>,
}

impl LightTree {
    /// Builds the tree. Errors: no VPLs, more than 2³¹, or a VPL with a non-finite position, a
    /// non-unit normal or a negative or non-finite intensity.
    pub fn new(vpls: Vec<Vpl>) -> Result<LightTree, Error> {
        if vpls.is_empty() {
            return Err(Error::InvalidInput("no VPLs".into()));
        }
        if vpls.len() > (1 << 31) {
            return Err(Error::InvalidInput(format!(
                "{} VPLs (at most 2^31)",
                vpls.len()
            )));
        }
        for (k, v) in vpls.iter().enumerate() {
            v.validate(k)?;
        }
        let positions: Vec<DVec3> = vpls.iter().map(|v| v.position).collect();
        let leaf = |k: u32| {
            let v = &vpls[k as usize];
            LightNode {
                bbox: Aabb::point(v.position),
                intensity: v.scalar_intensity(),
                representative: k,
                cone: v.normal.map(|axis| NormalCone {
                    axis,
                    half_angle: 0.0,
                }),
                children: None,
                vpl: k,
            }
        };
        let inner = |a: &LightNode, b: &LightNode, children: [u32; 2]| {
            let representative = if b.intensity > a.intensity {
                b.representative
            } else {
                a.representative
            };
            LightNode {
                bbox: a.bbox.union(b.bbox),
                intensity: a.intensity + b.intensity,
                representative,
                cone: match (a.cone, b.cone) {
                    (Some(x), Some(y)) => Some(x.union(y)),
                    _ => None,
                },
                children: Some(children),
                vpl: representative,
            }
        };
        let nodes = median_split(&positions, leaf, inner);
        Ok(LightTree { vpls, nodes })
    }

    /// The VPLs (in input order).
    pub fn vpls(&self) -> &[Vpl] {
        &self.vpls
    }

    /// All nodes; the root is node 0.
    pub fn nodes(&self) -> &[LightNode] {
        &self.nodes
    }

    /// One node.
    #[inline]
    pub fn node(&self, id: u32) -> &LightNode {
        &self.nodes[id as usize]
    }

    /// The root id (0).
    pub fn root(&self) -> u32 {
        0
    }

    /// Samples a VPL below `id` with probability `scalar_intensity / node.intensity`
    /// (p_L of Eq. 5) by descending in proportion to the children's intensities, from one
    /// uniform `u` in [0, 1). Returns the VPL index and its probability. A node of zero
    /// intensity returns its leftmost VPL with probability 0.
    pub fn sample(&self, id: u32, u: f64) -> (u32, f64) {
        let nodes = &self.nodes;
        let (leaf, p) = descend(
            id,
            u,
            |n| nodes[n as usize].children,
            |n| nodes[n as usize].intensity,
        );
        let n = &nodes[leaf as usize];
        (n.vpl, if n.intensity > 0.0 { p } else { 0.0 })
    }
}
