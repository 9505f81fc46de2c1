//! Axis-aligned bounding boxes and bounding spheres in `f64`, the cluster volumes of every tree.

use glam::DVec3;

/// An axis-aligned box `[min, max]`. The empty box has `min > max` on every axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: DVec3,
    /// Upper corner.
    pub max: DVec3,
}

impl Aabb {
    /// The empty box (the identity of [`Aabb::union`]).
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    /// The box of one point.
    pub fn point(p: DVec3) -> Aabb {
        Aabb { min: p, max: p }
    }

    /// The box of a set of points (empty for none).
    pub fn of_points(points: &[DVec3]) -> Aabb {
        points.iter().fold(Aabb::EMPTY, |b, &p| b.grow(p))
    }

    /// This box grown to contain `p`.
    pub fn grow(self, p: DVec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// The smallest box containing both.
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// True for the empty box.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// The extent `max − min` (zero for the empty box).
    pub fn extent(&self) -> DVec3 {
        if self.is_empty() {
            DVec3::ZERO
        } else {
            self.max - self.min
        }
    }

    /// Length of the diagonal (the "extent" of Max-Extent selection).
    pub fn diagonal(&self) -> f64 {
        self.extent().length()
    }

    /// The centre (the origin for the empty box).
    pub fn center(&self) -> DVec3 {
        if self.is_empty() {
            DVec3::ZERO
        } else {
            0.5 * (self.min + self.max)
        }
    }

    /// True if `p` lies in the box (closed).
    pub fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Squared minimum distance between any point of `self` and any point of `o`: per axis the
    /// gap `max(0, o.min − self.max, self.min − o.max)` (0 when the boxes overlap).
    pub fn min_distance_sq(&self, o: &Aabb) -> f64 {
        let gap = (o.min - self.max).max(self.min - o.max).max(DVec3::ZERO);
        gap.length_squared()
    }

    /// Squared maximum distance between a point of `self` and a point of `o`: per axis the
    /// larger of the two corner-to-corner spans.
    pub fn max_distance_sq(&self, o: &Aabb) -> f64 {
        let span = (o.max - self.min).abs().max((self.max - o.min).abs());
        span.length_squared()
    }

    /// The bounding sphere used by Eq. 11–13 of Nabata & Iwasaki: the box centre and half the
    /// diagonal.
    pub fn sphere(&self) -> Sphere {
        Sphere {
            center: self.center(),
            radius: 0.5 * self.diagonal(),
        }
    }
}

/// A bounding sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: DVec3,
    /// Radius (≥ 0).
    pub radius: f64,
}
