//! Normal cones and the cosine bound between a cone-bounded cluster and a box (Walter et al.
//! 2006, Multidimensional Lightcuts §4.1: the bound on cos θ over a pair of clusters).
//!
//! # The cosine bound
//!
//! Every direction from a point `x` of box `from` to a point `y` of box `to` is a vector of the
//! Minkowski difference `D = to ⊖ from = [to.min − from.max, to.max − from.min]`. In a frame
//! whose z axis is the cone's axis, the eight corners of `D` span a box `B ⊇ D`; for a vector
//! (x, y, z) of `B`, z/‖v‖ grows with z and (for z > 0) falls with x² + y², so
//!
//! `cos θ_min = z_max / √(m_x² + m_y² + z_max²)` when `z_max > 0`,
//!
//! with `m_x²`, `m_y²` the smallest squares over `B`'s x and y ranges (0 when a range spans 0),
//! bounds the cosine between the axis and any direction of `D`; when `z_max < 0` the same
//! argument with the *largest* x² + y² gives the smallest angle, beyond π/2, and `z_max = 0`
//! gives π/2. A normal within the cone's half-angle θ_c of the axis then has
//! `cos θ ≤ cos(max(0, θ_min − θ_c))`, 0 when θ_min − θ_c ≥ π/2. (The public MDLC code does the
//! same with a rotated Minkowski box, wave2 F2.1.)

use glam::DVec3;

use crate::aabb::Aabb;

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

/// Slack added to the cone's half-angle (radians) for the rounding of [`NormalCone::union`]
/// and of the samples' own cosines: the bound stays an upper bound of every computed cosine.
pub const ANGLE_SLACK: f64 = 1e-10;

/// An upper bound, in [0, 1], of `n · (y − x)/‖y − x‖` over every unit normal `n` in `cone`,
/// every `x` in `from` and every `y` in `to` (see the module doc). Empty or non-finite boxes
/// give the trivial bound 1.
pub fn cos_upper(cone: &NormalCone, from: &Aabb, to: &Aabb) -> f64 {
    if from.is_empty() || to.is_empty() || cone.half_angle >= std::f64::consts::PI {
        return 1.0;
    }
    let lo = to.min - from.max;
    let hi = to.max - from.min;
    if !(lo.is_finite() && hi.is_finite() && cone.axis.is_finite()) {
        return 1.0;
    }
    let w = cone.axis.normalize_or_zero();
    if w == DVec3::ZERO {
        return 1.0;
    }
    let (u, v) = w.any_orthonormal_pair();
    let (mut x0, mut x1) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut z1 = f64::NEG_INFINITY;
    for k in 0..8 {
        let c = DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        let (x, y, z) = (u.dot(c), v.dot(c), w.dot(c));
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
        z1 = z1.max(z);
    }
    let min_sq = |a: f64, b: f64| {
        if a <= 0.0 && b >= 0.0 {
            0.0
        } else {
            (a * a).min(b * b)
        }
    };
    let max_sq = |a: f64, b: f64| (a * a).max(b * b);
    // atan2 keeps the angle accurate near 0, π/2 and π.
    let theta_min = if z1 > 0.0 {
        (min_sq(x0, x1) + min_sq(y0, y1)).sqrt().atan2(z1)
    } else if z1 < 0.0 {
        // Every direction is behind the axis: z/‖v‖ < 0 grows with z and with x² + y².
        (max_sq(x0, x1) + max_sq(y0, y1)).sqrt().atan2(z1)
    } else {
        std::f64::consts::FRAC_PI_2
    };
    let gap = theta_min - cone.half_angle - ANGLE_SLACK;
    if gap <= 0.0 {
        1.0
    } else if gap >= std::f64::consts::FRAC_PI_2 {
        0.0
    } else {
        gap.cos()
    }
}
