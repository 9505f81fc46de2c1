//! Triangle BVH: obvhs traversal in `f32`, exact triangle tests in `f64`.
//!
//! # How the two precisions are combined
//!
//! obvhs traverses in `f32`. Its node tests are not exact, and the compressed wide BVH
//! (CwBvh) node test ignores `ray.tmin` and clamps the entry distance to `1e-4`. This module
//! makes the `f32` part *conservative*, so that it can never cull a triangle that the `f64`
//! test would hit:
//!
//! 1. **Normalised frame.** All `f32` data lives in a frame where the scene's bounding box is
//!    centred at the origin with half-extent 1 (`x_n = (x - centre) / scale`). So the `f32`
//!    precision is relative to the scene size, whatever the absolute coordinates are (a mesh
//!    at 10⁶ m from the origin, or one 10⁻⁶ m across, is traversed equally well).
//! 2. **Padded primitive boxes.** Each triangle's box is grown by [`PAD`] (about 6·10⁻⁵ of
//!    the scene half-extent, i.e. ~500 `f32` ulps). That absorbs the rounding of the vertices,
//!    of the ray origin and direction, and of the slab tests.
//! 3. **Clipped, backed-off ray.** The `f64` ray is clipped to the padded scene box in `f64`,
//!    and the `f32` ray starts [`BACKOFF`] before the clipped entry point. So the `f32` ray
//!    origin is always close to the scene (small rounding), and every box the ray can enter
//!    is at least `BACKOFF - PAD` ahead of it. That puts it past CwBvh's built-in `1e-4`
//!    entry clamp, and also past Bvh2's `t >= 0` test.
//! 4. **`f64` decisions.** The closure that obvhs calls for each candidate runs a two-sided
//!    Möller–Trumbore test in `f64` against the original vertices and the original ray. It
//!    keeps the best `f64` hit itself. obvhs only gets an *upper bound* (`f32` distance +
//!    [`PAD`]) to shorten the ray with, so a closer `f64` hit can never be culled, and
//!    `f32` ties cannot drop a hit. Exact `f64` ties (a ray through a shared edge) go to the
//!    lowest original triangle index, so the result does not depend on the traversal order.
//!
//! Triangles with a non-finite vertex, or whose `f64` normal `e1 × e2` is zero or not
//! finite, are left out of the BVH, so they are never hit.
//!
//! The tree is built like obvhs' `build_cwbvh` with the medium preset: PLOC, then
//! reinsertion, then conversion to CwBvh. The difference is that the binary tree's depth is
//! checked first. obvhs' conversion is recursive, and CwBvh traversal uses a fixed
//! 32-entry stack. So a pathologically deep tree (e.g. triangles whose sizes form a long
//! geometric progression) stays a binary `Bvh2`, which obvhs traverses with a heap stack
//! when needed. Ordinary meshes always get the wide BVH.

use glam::{DVec3, Vec3A};
use obvhs::{
    BvhBuildParams,
    aabb::Aabb,
    bvh2::{Bvh2, reinsertion::ReinsertionOptimizer},
    cwbvh::{CwBvh, bvh2_to_cwbvh::bvh2_to_cwbvh},
    ploc::PlocBuilder,
    ray::{Ray, RayHit},
};

/// Padding of the `f32` primitive boxes, in normalised units (scene half-extent = 1).
/// About 500 `f32` ulps at 1.0; the rounding it covers is a few tens of ulps.
const PAD: f32 = 1.0 / 16384.0;
/// How far before the clipped entry point the `f32` ray starts (normalised units). Must be
/// larger than `PAD` plus CwBvh's entry clamp (`1e-4`).
const BACKOFF: f64 = 1.0 / 512.0;
/// Meshes with at most this many hittable triangles are not traversed: a loop over their
/// triangles costs less than setting up the `f32` ray and walking even a one-node tree (a
/// ground quad is two triangles). The answers are the same, since the traversal's equal brute
/// force; the one exception is absurd input: a direction so long that its length over the
/// mesh's half-extent overflows `f64` makes the traversal report a miss, the loop the hit.
const SMALL_MESH: usize = 4;
/// CwBvh traversal uses a fixed stack of 32 entries that silently saturates, and the
/// conversion from the binary tree is recursive; deeper binary trees (pathological
/// geometry only) stay binary.
const MAX_WIDE_DEPTH: usize = 30;

/// The obvhs hierarchy: the 8-wide compressed BVH normally, the binary one as a fallback
/// for very deep trees.
#[derive(Clone)]
enum Accel {
    Wide(CwBvh),
    Binary(Bvh2),
}

impl Accel {
    fn build(aabbs: &[Aabb]) -> Accel {
        // Same steps as obvhs' `build_cwbvh` (medium preset), minus its debug-only
        // validation, with a depth check before the (recursive) conversion.
        let params = BvhBuildParams::medium_build();
        let mut bvh2 = PlocBuilder::with_capacity(aabbs.len()).build(
            params.ploc_search_distance,
            aabbs,
            (0..aabbs.len() as u32).collect(),
            params.sort_precision,
            params.search_depth_threshold,
        );
        ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
        let depth = bvh2_depth(&bvh2);
        if depth <= MAX_WIDE_DEPTH {
            Accel::Wide(bvh2_to_cwbvh(
                &bvh2,
                params.max_prims_per_leaf.clamp(1, 3),
                true,
                false,
            ))
        } else {
            // Traversal stack size (obvhs switches to a heap stack when needed).
            bvh2.max_depth = bvh2.max_depth.max(depth + 1);
            Accel::Binary(bvh2)
        }
    }

    fn primitive_indices(&self) -> &[u32] {
        match self {
            Accel::Wide(b) => &b.primitive_indices,
            Accel::Binary(b) => &b.primitive_indices,
        }
    }

    fn node_count(&self) -> usize {
        match self {
            Accel::Wide(b) => b.nodes.len(),
            Accel::Binary(b) => b.nodes.len(),
        }
    }

    #[inline]
    fn closest<F: FnMut(&Ray, usize) -> f32>(&self, ray: Ray, f: F) {
        let mut hit = RayHit::none();
        match self {
            Accel::Wide(b) => b.ray_traverse(ray, &mut hit, f),
            Accel::Binary(b) => b.ray_traverse(ray, &mut hit, f),
        };
    }

    #[inline]
    fn miss<F: FnMut(&Ray, usize) -> f32>(&self, ray: Ray, f: F) -> bool {
        match self {
            Accel::Wide(b) => b.ray_traverse_miss(ray, f),
            Accel::Binary(b) => b.ray_traverse_miss(ray, f),
        }
    }
}

/// Depth of a binary BVH (number of nodes on the longest root-leaf path), iteratively.
fn bvh2_depth(b: &Bvh2) -> usize {
    if b.nodes.is_empty() {
        return 0;
    }
    let mut max = 0;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((i, d)) = stack.pop() {
        let n = &b.nodes[i];
        if n.is_leaf() {
            max = max.max(d);
        } else {
            stack.push((n.first_index as usize, d + 1));
            stack.push((n.first_index as usize + 1, d + 1));
        }
    }
    max
}

/// Ray–triangle hit.
///
/// `t` is the distance along the (not necessarily unit) ray direction, so the hit point is
/// `origin + t * dir`. The barycentrics are such that the hit point is
/// `(1 - u - v) * v0 + u * v1 + v * v2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Index of the hit triangle in the slice given to [`TriangleBvh::new`].
    pub triangle: u32,
    /// Ray parameter of the hit (`origin + t * dir`), computed in `f64`.
    pub t: f64,
    /// Barycentric weight of `v1`.
    pub u: f64,
    /// Barycentric weight of `v2`.
    pub v: f64,
}

/// Two-sided Möller–Trumbore ray–triangle test in `f64`.
///
/// Returns `(t, u, v)` with the hit point `origin + t * dir = (1-u-v)*v0 + u*v1 + v*v2` if
/// the line `origin + t * dir` crosses the triangle (edges included, any `t`, either side),
/// and `None` otherwise, also for degenerate (zero-area) or non-finite triangles. This is
/// exactly the test [`TriangleBvh`] runs, so a brute-force loop over this function gives
/// bit-identical answers.
///
/// Möller & Trumbore, "Fast, minimum storage ray-triangle intersection", JGT 2(1), 1997.
#[inline]
pub fn intersect_triangle(origin: DVec3, dir: DVec3, tri: &[DVec3; 3]) -> Option<(f64, f64, f64)> {
    intersect_pre(origin, dir, tri[0], tri[1] - tri[0], tri[2] - tri[0])
}

#[inline(always)]
fn intersect_pre(
    origin: DVec3,
    dir: DVec3,
    v0: DVec3,
    e1: DVec3,
    e2: DVec3,
) -> Option<(f64, f64, f64)> {
    let pvec = dir.cross(e2);
    let det = e1.dot(pvec);
    // Also rejects NaN.
    if !(det != 0.0 && det.is_finite()) {
        return None;
    }
    let inv_det = 1.0 / det;
    let tvec = origin - v0;
    let u = tvec.dot(pvec) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qvec = tvec.cross(e1);
    let v = dir.dot(qvec) * inv_det;
    if !(v >= 0.0 && u + v <= 1.0) {
        return None;
    }
    let t = e2.dot(qvec) * inv_det;
    Some((t, u, v))
}

/// A triangle prepared for the `f64` test, stored in BVH order.
#[derive(Clone, Copy, Debug)]
struct PreparedTriangle {
    v0: DVec3,
    e1: DVec3,
    e2: DVec3,
}

/// A BVH over triangles with `f64` closest-hit and occlusion queries.
///
/// Built once with [`TriangleBvh::new`]. It is immutable afterwards and `Send + Sync`, so
/// all rayon threads can share one BVH. Traversal uses obvhs' compressed 8-wide BVH (CwBvh,
/// Ylitie et al. 2017, built with PLOC, Meister & Bittner 2018) in `f32`. Pathologically
/// deep trees fall back to obvhs' binary BVH, and meshes of at most four hittable triangles
/// (a ground quad) are not traversed at all: a loop over them is cheaper. The triangle tests
/// are done in `f64`, and the results are identical to a brute-force loop over
/// [`intersect_triangle`]. The notes at the top of `src/bvh.rs` explain why no `f64` hit is
/// ever lost to `f32` rounding.
///
/// Degenerate (zero-area) triangles and triangles with non-finite vertices are accepted and
/// never hit. At most `u32::MAX` triangles are supported.
#[derive(Clone)]
pub struct TriangleBvh {
    /// The triangles as given (original order).
    original: Vec<[DVec3; 3]>,
    /// The hittable triangles in BVH order (`prepared[i]` is BVH primitive slot `i`).
    prepared: Vec<PreparedTriangle>,
    /// Original index of each BVH slot.
    ids: Vec<u32>,
    /// `None` if no triangle is hittable.
    bvh: Option<Accel>,
    /// Bounding box of all triangles with finite vertices.
    bounds: Option<(DVec3, DVec3)>,
    /// Centre of the normalised frame.
    centre: DVec3,
    /// `1 / scale` of the normalised frame.
    inv_scale: f64,
    /// Normalised, padded bounds of the hittable triangles (the box rays are clipped to).
    clip_min: DVec3,
    clip_max: DVec3,
}

impl std::fmt::Debug for TriangleBvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TriangleBvh")
            .field("len", &self.len())
            .field("hittable_len", &self.hittable_len())
            .field("bounds", &self.bounds)
            .field("nodes", &self.bvh.as_ref().map_or(0, Accel::node_count))
            .field("wide", &matches!(self.bvh, Some(Accel::Wide(_))))
            .finish()
    }
}

impl TriangleBvh {
    /// Builds the BVH. Any input is accepted: an empty slice gives a BVH that never hits,
    /// and degenerate or non-finite triangles are kept (for [`Self::triangle`] and
    /// [`Self::len`]) but never hit.
    ///
    /// # Panics
    /// If there are more than `u32::MAX` triangles.
    pub fn new(triangles: &[[DVec3; 3]]) -> Self {
        assert!(
            u32::try_from(triangles.len()).is_ok(),
            "TriangleBvh supports at most u32::MAX triangles"
        );
        let original = triangles.to_vec();

        let finite = |t: &[DVec3; 3]| t.iter().all(|p| p.is_finite());
        let mut bounds: Option<(DVec3, DVec3)> = None;
        for t in triangles.iter().filter(|t| finite(t)) {
            for &p in t {
                bounds = Some(match bounds {
                    None => (p, p),
                    Some((lo, hi)) => (lo.min(p), hi.max(p)),
                });
            }
        }

        let hittable: Vec<u32> = (0..triangles.len() as u32)
            .filter(|&i| {
                let t = &triangles[i as usize];
                let n = (t[1] - t[0]).cross(t[2] - t[0]);
                finite(t) && n.is_finite() && n != DVec3::ZERO
            })
            .collect();

        let mut out = TriangleBvh {
            original,
            prepared: Vec::new(),
            ids: Vec::new(),
            bvh: None,
            bounds,
            centre: DVec3::ZERO,
            inv_scale: 1.0,
            clip_min: DVec3::ZERO,
            clip_max: DVec3::ZERO,
        };
        if hittable.is_empty() {
            return out;
        }

        // Normalised frame from the hittable triangles' bounds.
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &i in &hittable {
            for &p in &triangles[i as usize] {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        // Halve before subtracting so that huge coordinates cannot overflow.
        let centre = lo * 0.5 + hi * 0.5;
        let half = (hi * 0.5 - lo * 0.5).max_element();
        // A hittable triangle has a non-zero normal, so the box is not a point: half > 0.
        let inv_scale = if half > 0.0 && half.is_finite() {
            1.0 / half
        } else {
            1.0
        };
        out.centre = centre;
        out.inv_scale = inv_scale;
        let pad = f64::from(PAD);
        out.clip_min = (lo - centre) * inv_scale - DVec3::splat(pad);
        out.clip_max = (hi - centre) * inv_scale + DVec3::splat(pad);

        let aabbs: Vec<Aabb> = hittable
            .iter()
            .map(|&i| {
                let t = &triangles[i as usize];
                let a = (t[0] - centre) * inv_scale;
                let b = (t[1] - centre) * inv_scale;
                let c = (t[2] - centre) * inv_scale;
                let mn = a.min(b).min(c).as_vec3();
                let mx = a.max(b).max(c).as_vec3();
                Aabb::new(
                    Vec3A::from(mn) - Vec3A::splat(PAD),
                    Vec3A::from(mx) + Vec3A::splat(PAD),
                )
            })
            .collect();

        let bvh = Accel::build(&aabbs);

        out.ids = bvh
            .primitive_indices()
            .iter()
            .map(|&k| hittable[k as usize])
            .collect();
        out.prepared = out
            .ids
            .iter()
            .map(|&i| {
                let t = &triangles[i as usize];
                PreparedTriangle {
                    v0: t[0],
                    e1: t[1] - t[0],
                    e2: t[2] - t[0],
                }
            })
            .collect();
        out.bvh = Some(bvh);
        out
    }

    /// Number of triangles given to [`Self::new`] (including the never-hit degenerate ones).
    pub fn len(&self) -> usize {
        self.original.len()
    }

    /// `true` if the BVH was built from no triangles.
    pub fn is_empty(&self) -> bool {
        self.original.is_empty()
    }

    /// Number of triangles that can be hit (finite with non-zero area).
    pub fn hittable_len(&self) -> usize {
        self.ids.len()
    }

    /// Axis-aligned bounds `(min, max)` of all triangles whose vertices are finite
    /// (degenerate ones included); `None` if there are none, in particular if empty.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        self.bounds
    }

    /// Triangle `i` as given to [`Self::new`].
    ///
    /// # Panics
    /// If `i >= self.len()`.
    pub fn triangle(&self, i: u32) -> [DVec3; 3] {
        self.original[i as usize]
    }

    /// Sets up the `f32` ray. Returns the ray, `tau_start` (the normalised ray parameter of
    /// the `f32` origin) and `k` (world `t` to normalised `tau`: `tau = t * k`), or `None`
    /// if the ray cannot hit anything.
    #[inline]
    fn setup_ray(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_min: f64,
        t_max: f64,
    ) -> Option<(&Accel, Ray, f64, f64)> {
        let bvh = self.bvh.as_ref()?;
        if !(origin.is_finite() && dir.is_finite()) || t_min.is_nan() || t_max.is_nan() {
            return None;
        }
        // Neither is NaN here.
        if t_max <= t_min {
            return None;
        }
        // Length without overflow/underflow for huge or tiny directions.
        let m = dir.abs().max_element();
        // `dir` is finite, so `m` is not NaN.
        if m == 0.0 {
            return None;
        }
        let scaled = dir / m;
        let sl = scaled.length();
        // `+ 0.0` turns a −0.0 component into +0.0: obvhs's traversal branches on the sign
        // bit of each direction component, and a −0.0 there made rays miss boxes they cross.
        let dn = scaled / sl + DVec3::ZERO;
        let len = m * sl;
        let k = len * self.inv_scale;
        if !(k > 0.0 && k.is_finite()) {
            return None;
        }
        let o_n = (origin - self.centre) * self.inv_scale;

        // f64 slab test against the padded, normalised scene box (parameter tau along dn).
        let mut lo = t_min * k;
        let mut hi = t_max * k;
        for a in 0..3 {
            let (o, d) = (o_n[a], dn[a]);
            let (bmin, bmax) = (self.clip_min[a], self.clip_max[a]);
            if d == 0.0 {
                if o < bmin || o > bmax {
                    return None;
                }
            } else {
                let inv = 1.0 / d;
                let (mut ta, mut tb) = ((bmin - o) * inv, (bmax - o) * inv);
                if ta > tb {
                    std::mem::swap(&mut ta, &mut tb);
                }
                lo = lo.max(ta);
                hi = hi.min(tb);
            }
        }
        // No NaN can arise above (k is finite and positive).
        if lo > hi {
            return None;
        }
        // lo and hi are finite now: dn has a non-zero component, so one slab bounded them.
        let tau_start = lo - BACKOFF;
        let o32 = (o_n + tau_start * dn).as_vec3();
        let tmax32 = ((hi - tau_start) as f32) + PAD;
        let ray = Ray::new(Vec3A::from(o32), Vec3A::from(dn.as_vec3()), 0.0, tmax32);
        Some((bvh, ray, tau_start, k))
    }

    /// Whether a ray can hit anything at all: finite origin and non-zero finite direction, and
    /// a non-empty, NaN-free range (the checks [`Self::setup_ray`] starts with).
    #[inline]
    fn valid_ray(origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> bool {
        origin.is_finite() && dir.is_finite() && dir != DVec3::ZERO && t_min < t_max
    }

    /// The closest hit of a small mesh by a loop over its triangles (same test, same tie rule
    /// as the traversal).
    fn closest_hit_small(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<Hit> {
        if !Self::valid_ray(origin, dir, t_min, t_max) {
            return None;
        }
        let mut best: Option<Hit> = None;
        for (p, &id) in self.prepared.iter().zip(&self.ids) {
            let Some((t, u, v)) = intersect_pre(origin, dir, p.v0, p.e1, p.e2) else {
                continue;
            };
            if t > t_min
                && t < t_max
                && best.is_none_or(|b| t < b.t || (t == b.t && id < b.triangle))
            {
                best = Some(Hit {
                    triangle: id,
                    t,
                    u,
                    v,
                });
            }
        }
        best
    }

    /// Closest hit with `t_min < t < t_max` along `origin + t * dir`.
    ///
    /// `dir` need not be normalised; `t` is in units of `dir`. Triangles are two-sided.
    /// Returns `None` for non-finite or zero `dir`, non-finite `origin`, or an empty range.
    /// Exact ties go to the lowest triangle index. To continue a ray from a hit, start at
    /// the hit point with a small positive `t_min` (relative to the scene size).
    pub fn closest_hit(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<Hit> {
        if self.ids.len() <= SMALL_MESH {
            return self.closest_hit_small(origin, dir, t_min, t_max);
        }
        let (bvh, ray, tau_start, k) = self.setup_ray(origin, dir, t_min, t_max)?;
        let prepared = &self.prepared;
        let ids = &self.ids;
        let mut best: Option<Hit> = None;
        bvh.closest(ray, |_, slot| {
            let p = &prepared[slot];
            let Some((t, u, v)) = intersect_pre(origin, dir, p.v0, p.e1, p.e2) else {
                return f32::INFINITY;
            };
            if !(t > t_min && t < t_max) {
                return f32::INFINITY;
            }
            let id = ids[slot];
            let better = match best {
                None => true,
                Some(b) => t < b.t || (t == b.t && id < b.triangle),
            };
            if !better {
                return f32::INFINITY;
            }
            best = Some(Hit {
                triangle: id,
                t,
                u,
                v,
            });
            // Conservative upper bound for obvhs' culling.
            ((t * k - tau_start) as f32) + PAD
        });
        best
    }

    /// `true` if any triangle is hit with `t_min < t < t_max` along `origin + t * dir`
    /// (shadow / visibility rays). Same conventions as [`Self::closest_hit`]; stops at the
    /// first hit found.
    pub fn occluded(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> bool {
        if self.ids.len() <= SMALL_MESH {
            return Self::valid_ray(origin, dir, t_min, t_max)
                && self.prepared.iter().any(|p| {
                    matches!(intersect_pre(origin, dir, p.v0, p.e1, p.e2),
                        Some((t, _, _)) if t > t_min && t < t_max)
                });
        }
        let Some((bvh, ray, _, _)) = self.setup_ray(origin, dir, t_min, t_max) else {
            return false;
        };
        let prepared = &self.prepared;
        !bvh.miss(ray, |_, slot| {
            let p = &prepared[slot];
            match intersect_pre(origin, dir, p.v0, p.e1, p.e2) {
                Some((t, _, _)) if t > t_min && t < t_max => f32::NEG_INFINITY,
                _ => f32::INFINITY,
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn single_triangle_hit_and_barycentrics() {
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let bvh = TriangleBvh::new(&[tri]);
        assert_eq!(bvh.len(), 1);
        let h = bvh
            .closest_hit(
                DVec3::new(0.25, 0.5, 2.0),
                DVec3::new(0.0, 0.0, -2.0),
                0.0,
                10.0,
            )
            .expect("hit");
        assert_eq!(h.triangle, 0);
        assert!((h.t - 1.0).abs() < 1e-15);
        assert!((h.u - 0.25).abs() < 1e-15 && (h.v - 0.5).abs() < 1e-15);
        // Range excludes the hit.
        assert!(
            bvh.closest_hit(DVec3::new(0.25, 0.5, 2.0), DVec3::NEG_Z, 0.0, 1.5)
                .is_none()
        );
        assert!(bvh.occluded(DVec3::new(0.25, 0.5, 2.0), DVec3::NEG_Z, 0.0, 2.5));
        assert!(!bvh.occluded(DVec3::new(0.25, 0.5, 2.0), DVec3::NEG_Z, 0.0, 1.5));
        // Backface (two-sided).
        assert!(
            bvh.closest_hit(DVec3::new(0.25, 0.5, -2.0), DVec3::Z, 0.0, 10.0)
                .is_some()
        );
    }

    #[test]
    fn origin_on_surface_and_tiny_t_min() {
        // Two parallel triangles 1e-3 apart; a ray starting on the first one must find the
        // second one even though it is within CwBvh's 1e-4 clamp in absolute units when
        // the scene is small.
        let s = 1e-3;
        let a = [DVec3::ZERO, DVec3::X * s, DVec3::Y * s];
        let b = [
            DVec3::Z * 1e-7,
            DVec3::new(s, 0.0, 1e-7),
            DVec3::new(0.0, s, 1e-7),
        ];
        let bvh = TriangleBvh::new(&[a, b]);
        let o = DVec3::new(0.2 * s, 0.2 * s, 0.0);
        let h = bvh.closest_hit(o, DVec3::Z, 1e-12, f64::INFINITY).unwrap();
        assert_eq!(h.triangle, 1);
        assert!((h.t - 1e-7).abs() < 1e-15);
    }

    /// Geometric size progressions give very deep trees (PLOC chains them); CwBvh's fixed
    /// 32-entry traversal stack would silently drop nodes, so such trees stay binary and
    /// must still agree with brute force. Ordinary meshes use the wide BVH.
    #[test]
    fn deep_trees_fall_back_to_the_binary_bvh() {
        use rand::{RngExt, SeedableRng};
        let mut tris = Vec::new();
        for i in 0..300 {
            let x = 1.15f64.powi(i);
            let s = x * 0.3;
            tris.push([
                DVec3::new(x, 0.0, 0.0),
                DVec3::new(x + s, 0.0, s * 0.1),
                DVec3::new(x, s, -s * 0.1),
            ]);
        }
        let bvh = TriangleBvh::new(&tris);
        let Some(Accel::Binary(b)) = &bvh.bvh else {
            panic!("expected the binary fallback: {bvh:?}");
        };
        assert!(bvh2_depth(b) > MAX_WIDE_DEPTH);
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
        let mut hits = 0;
        for _ in 0..3000 {
            let t = tris[rng.random_range(0..tris.len())];
            let (a, b): (f64, f64) = (rng.random_range(0.0..0.5), rng.random_range(0.0..0.5));
            let target = t[0] + a * (t[1] - t[0]) + b * (t[2] - t[0]);
            let o = target + DVec3::new(0.3, -0.2, 1.0) * (target.x * rng.random_range(0.1..2.0));
            let d = target - o;
            let got = bvh.closest_hit(o, d, 0.0, f64::INFINITY);
            let mut want: Option<Hit> = None;
            for (i, tri) in tris.iter().enumerate() {
                if let Some((t, u, v)) = intersect_triangle(o, d, tri)
                    && t > 0.0
                    && want.is_none_or(|w| t < w.t)
                {
                    want = Some(Hit {
                        triangle: i as u32,
                        t,
                        u,
                        v,
                    });
                }
            }
            assert_eq!(got, want);
            assert_eq!(bvh.occluded(o, d, 0.0, f64::INFINITY), want.is_some());
            hits += usize::from(got.is_some());
        }
        assert!(hits > 2500);

        // An ordinary mesh (a 32x32 grid) is shallow and uses the wide BVH.
        let mut grid = Vec::new();
        for j in 0..32 {
            for i in 0..32 {
                let p = |a: i32, b: i32| DVec3::new(f64::from(a), f64::from(b), 0.0);
                grid.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                grid.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
        assert!(matches!(TriangleBvh::new(&grid).bvh, Some(Accel::Wide(_))));
    }
}
