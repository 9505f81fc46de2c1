//! Virtual point lights and the binary light tree of Multidimensional Lightcuts (Walter et al.
//! 2006, §4: a binary tree whose nodes carry a bounding box, the total intensity, a
//! representative and, for oriented lights, a normal cone).

use glam::DVec3;

use crate::Error;
use crate::aabb::Aabb;
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

/// A cone of directions: every normal in the cluster is within `half_angle` of `axis`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalCone {
    /// Unit axis.
    pub axis: DVec3,
    /// Half-angle in radians, in [0, π] (π: any direction).
    pub half_angle: f64,
}

impl NormalCone {
    /// The smallest cone around both (the standard merge of two bounding cones: the merged
    /// half-angle is (φ + θ₁ + θ₂)/2 with φ the angle between the axes, the axis rotated from
    /// `self.axis` towards `o.axis`; Walter et al. 2006 keep such cones per node).
    pub fn union(self, o: NormalCone) -> NormalCone {
        let phi = angle_between(self.axis, o.axis);
        if phi + o.half_angle <= self.half_angle {
            return self;
        }
        if phi + self.half_angle <= o.half_angle {
            return o;
        }
        let theta = 0.5 * (phi + self.half_angle + o.half_angle);
        let perp = o.axis - self.axis * self.axis.dot(o.axis);
        if theta >= std::f64::consts::PI || perp.length_squared() < 1e-24 {
            return NormalCone {
                axis: self.axis,
                half_angle: std::f64::consts::PI,
            };
        }
        let rot = theta - self.half_angle;
        let axis = (self.axis * rot.cos() + perp.normalize() * rot.sin()).normalize();
        NormalCone {
            axis,
            half_angle: theta,
        }
    }

    /// True if unit direction `d` lies in the cone (with a 1e-9 rad tolerance).
    pub fn contains(&self, d: DVec3) -> bool {
        angle_between(self.axis, d) <= self.half_angle + 1e-9
    }
}

/// The angle between two unit vectors as atan2(‖a × b‖, a · b), accurate near 0 and π (unlike
/// acos of the dot product, which loses half the digits there).
fn angle_between(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
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
        let mut order: Vec<u32> = (0..vpls.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * vpls.len() - 1);
        build(&vpls, &mut order, &mut nodes);
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
    pub fn sample(&self, mut id: u32, mut u: f64) -> (u32, f64) {
        let mut p = 1.0;
        loop {
            let n = &self.nodes[id as usize];
            let Some([a, b]) = n.children else {
                return (n.vpl, if n.intensity > 0.0 { p } else { 0.0 });
            };
            let (wa, wb) = (
                self.nodes[a as usize].intensity,
                self.nodes[b as usize].intensity,
            );
            let w = wa + wb;
            if w <= 0.0 {
                id = a;
                p = 0.0;
                continue;
            }
            let pa = wa / w;
            if u < pa || wb <= 0.0 {
                p *= pa;
                u = if pa > 0.0 {
                    (u / pa).min(1.0 - f64::EPSILON)
                } else {
                    0.0
                };
                id = a;
            } else {
                let pb = wb / w;
                p *= pb;
                u = ((u - pa) / pb).clamp(0.0, 1.0 - f64::EPSILON);
                id = b;
            }
        }
    }
}

/// Builds the subtree over `idx` and returns its node id. Iterative over an explicit stack to
/// keep deep trees off the call stack: nodes are allocated first and filled bottom-up.
fn build(vpls: &[Vpl], idx: &mut [u32], nodes: &mut Vec<LightNode>) {
    // (node id, range start, range end)
    struct Job {
        node: u32,
        lo: usize,
        hi: usize,
    }
    let blank = LightNode {
        bbox: Aabb::EMPTY,
        intensity: 0.0,
        representative: 0,
        cone: None,
        children: None,
        vpl: 0,
    };
    nodes.push(blank);
    let mut stack = vec![Job {
        node: 0,
        lo: 0,
        hi: idx.len(),
    }];
    let mut post = Vec::new();
    while let Some(j) = stack.pop() {
        let range = &mut idx[j.lo..j.hi];
        if range.len() == 1 {
            let v = &vpls[range[0] as usize];
            nodes[j.node as usize] = LightNode {
                bbox: Aabb::point(v.position),
                intensity: v.scalar_intensity(),
                representative: range[0],
                cone: v.normal.map(|axis| NormalCone {
                    axis,
                    half_angle: 0.0,
                }),
                children: None,
                vpl: range[0],
            };
            continue;
        }
        let b = range
            .iter()
            .fold(Aabb::EMPTY, |b, &k| b.grow(vpls[k as usize].position));
        let e = b.extent();
        let axis = if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        };
        // Sort by the axis coordinate, ties by index, so the tree is a function of the input.
        range.sort_unstable_by(|&p, &q| {
            let (a, c) = (
                vpls[p as usize].position[axis],
                vpls[q as usize].position[axis],
            );
            a.total_cmp(&c).then(p.cmp(&q))
        });
        let mid = j.lo + range.len() / 2;
        let (l, r) = (nodes.len() as u32, nodes.len() as u32 + 1);
        nodes.push(blank);
        nodes.push(blank);
        nodes[j.node as usize].children = Some([l, r]);
        post.push(j.node);
        stack.push(Job {
            node: l,
            lo: j.lo,
            hi: mid,
        });
        stack.push(Job {
            node: r,
            lo: mid,
            hi: j.hi,
        });
    }
    // Children always have larger ids than their parent: fill parents in reverse order.
    for &id in post.iter().rev() {
        let [l, r] = nodes[id as usize].children.expect("inner node");
        let (a, b) = (nodes[l as usize], nodes[r as usize]);
        let cone = match (a.cone, b.cone) {
            (Some(x), Some(y)) => Some(x.union(y)),
            _ => None,
        };
        let representative = if b.intensity > a.intensity {
            b.representative
        } else {
            a.representative
        };
        nodes[id as usize] = LightNode {
            bbox: a.bbox.union(b.bbox),
            intensity: a.intensity + b.intensity,
            representative,
            cone,
            children: Some([l, r]),
            vpl: representative,
        };
    }
}
