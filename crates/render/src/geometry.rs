//! Ray casting against a scene: one triangle BVH per object (from `sss-hierarchy`), so probe
//! rays of the BSSRDF sampler can be limited to their own object and the scene is only a short
//! list of per-object BVHs with bounding boxes.

use glam::DVec3;
use sss_hierarchy::TriangleBvh;
use sss_scene::{Mesh, Scene};

/// Where a ray met a surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// Object index in [`Scene::objects`].
    pub object: u32,
    /// Triangle index in that object's mesh.
    pub triangle: u32,
    /// Distance along the ray direction (in units of its length).
    pub t: f64,
    /// Hit position.
    pub p: DVec3,
    /// Unit geometric normal (from the winding, pointing out of the object).
    pub ng: DVec3,
    /// Unit shading normal (interpolated vertex normals, pointing out of the object).
    pub n: DVec3,
}

/// Per-object BVHs and the data to turn a BVH hit into a [`SurfaceHit`].
pub struct SceneGeometry {
    objects: Vec<ObjectGeometry>,
    /// A length below which offsets are negligible: 1e-6 of the scene's extent.
    epsilon: f64,
    extent: f64,
}

struct ObjectGeometry {
    bvh: TriangleBvh,
    lo: DVec3,
    hi: DVec3,
    mesh: Mesh,
}

/// Slab test of a ray against an axis-aligned box: does the segment (t_min, t_max) overlap it?
fn ray_box(lo: DVec3, hi: DVec3, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> bool {
    ray_box_entry(lo, hi, origin, dir, t_min, t_max).is_some()
}

/// Slab test of a ray against an axis-aligned box (Kay & Kajiya, "Ray tracing complex scenes",
/// SIGGRAPH 1986): where the segment (t_min, t_max) enters the box, `None` if it misses it.
/// The entry is at least `t_min`; no point of the box on the segment has a smaller `t` (up to
/// the rounding of the slab distances, which the callers' padded boxes absorb).
fn ray_box_entry(
    lo: DVec3,
    hi: DVec3,
    origin: DVec3,
    dir: DVec3,
    t_min: f64,
    t_max: f64,
) -> Option<f64> {
    let mut t0 = t_min;
    let mut t1 = t_max;
    for a in 0..3 {
        let inv = 1.0 / dir[a];
        let (mut near, mut far) = ((lo[a] - origin[a]) * inv, (hi[a] - origin[a]) * inv);
        if near > far {
            std::mem::swap(&mut near, &mut far);
        }
        // NaN (0 · inf, origin on the slab with a zero direction) keeps the bounds unchanged.
        if near > t0 {
            t0 = near;
        }
        if far < t1 {
            t1 = far;
        }
        if t0 > t1 {
            return None;
        }
    }
    Some(t0)
}

/// Scenes with up to this many objects are traversed nearest box first (the order is kept in
/// a fixed array on the stack); larger ones in index order.
const MAX_SORTED_OBJECTS: usize = 16;

impl SceneGeometry {
    /// Builds one BVH per object of `scene`.
    pub fn new(scene: &Scene) -> Self {
        let objects: Vec<ObjectGeometry> = scene
            .objects
            .iter()
            .map(|o| {
                let tris = triangles_of(&o.mesh);
                let bvh = TriangleBvh::new(&tris);
                let (lo, hi) = bvh.bounds().unwrap_or((DVec3::ZERO, DVec3::ZERO));
                // Pad the box so rays grazing a flat object are not culled by rounding.
                let pad = (hi - lo).max_element() * 1e-9 + 1e-12;
                ObjectGeometry {
                    bvh,
                    lo: lo - DVec3::splat(pad),
                    hi: hi + DVec3::splat(pad),
                    mesh: o.mesh.clone(),
                }
            })
            .collect();
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for o in &objects {
            lo = lo.min(o.lo);
            hi = hi.max(o.hi);
        }
        let extent = if lo.is_finite() && hi.is_finite() {
            (hi - lo).max_element().max(1e-30)
        } else {
            1.0
        };
        SceneGeometry {
            objects,
            epsilon: extent * 1e-6,
            extent,
        }
    }

    /// Offsets below this length are negligible at the scene's scale.
    pub fn epsilon(&self) -> f64 {
        self.epsilon
    }

    /// The largest side of the scene's bounding box.
    pub fn extent(&self) -> f64 {
        self.extent
    }

    /// The exact bounding box of object `object`'s usable triangles (None if it has none).
    pub fn bounds(&self, object: u32) -> Option<(DVec3, DVec3)> {
        self.objects[object as usize].bvh.bounds()
    }

    /// The mesh of object `i`.
    pub fn mesh(&self, object: u32) -> &Mesh {
        &self.objects[object as usize].mesh
    }

    fn surface_hit(
        &self,
        object: u32,
        hit: sss_hierarchy::Hit,
        origin: DVec3,
        dir: DVec3,
    ) -> SurfaceHit {
        let mesh = &self.objects[object as usize].mesh;
        let [a, b, c] = mesh.triangles[hit.triangle as usize];
        let (pa, pb, pc) = (
            mesh.positions[a as usize],
            mesh.positions[b as usize],
            mesh.positions[c as usize],
        );
        let w = 1.0 - hit.u - hit.v;
        let p_bary = pa * w + pb * hit.u + pc * hit.v;
        let p = if p_bary.is_finite() {
            p_bary
        } else {
            origin + dir * hit.t
        };
        let ng = (pb - pa).cross(pc - pa).normalize_or_zero();
        let ns = (mesh.normals[a as usize] * w
            + mesh.normals[b as usize] * hit.u
            + mesh.normals[c as usize] * hit.v)
            .normalize_or_zero();
        let n = if ns == DVec3::ZERO { ng } else { ns };
        SurfaceHit {
            object,
            triangle: hit.triangle,
            t: hit.t,
            p,
            ng,
            n,
        }
    }

    /// The closest surface along the ray with t in (t_min, t_max), over all objects. Exact
    /// ties go to the lowest object index, then (within the object) to the lowest triangle
    /// index.
    ///
    /// The objects whose bounding boxes the ray enters are visited nearest entry first, and
    /// the walk stops at the first box that starts beyond the closest hit so far: a ray that
    /// hits an object in front of the ground never traverses the ground's BVH. The order
    /// only saves work; the hit is the same as visiting every object in index order.
    pub fn closest_hit(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_min: f64,
        t_max: f64,
    ) -> Option<SurfaceHit> {
        let best = if self.objects.len() <= MAX_SORTED_OBJECTS {
            self.closest_sorted(origin, dir, t_min, t_max)
        } else {
            self.closest_in_order(origin, dir, t_min, t_max)
        };
        best.map(|(i, h)| self.surface_hit(i, h, origin, dir))
    }

    /// [`Self::closest_hit`] for at most [`MAX_SORTED_OBJECTS`] objects: the BVH hit and its
    /// object, nearest box first.
    fn closest_sorted(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_min: f64,
        t_max: f64,
    ) -> Option<(u32, sss_hierarchy::Hit)> {
        // (box entry, object), sorted by entry (insertion sort: a handful of objects).
        let mut order = [(0.0f64, 0u32); MAX_SORTED_OBJECTS];
        let mut n = 0;
        for (i, o) in self.objects.iter().enumerate() {
            let Some(entry) = ray_box_entry(o.lo, o.hi, origin, dir, t_min, t_max) else {
                continue;
            };
            let mut j = n;
            while j > 0 && order[j - 1].0 > entry {
                order[j] = order[j - 1];
                j -= 1;
            }
            order[j] = (entry, i as u32);
            n += 1;
        }
        let mut best: Option<(u32, sss_hierarchy::Hit)> = None;
        let mut t_best = t_max;
        for &(entry, i) in &order[..n] {
            // Every later box starts at least as far: none can hold a hit closer than t_best
            // (nor one at t_best, which a box starting beyond it cannot contain).
            if entry > t_best {
                break;
            }
            // A hit exactly at t_best wins if its object comes first in index order; `next_up`
            // admits t == t_best (t_best is finite once there is a hit).
            let limit = match best {
                Some((b, _)) if i < b => t_best.next_up(),
                _ => t_best,
            };
            if let Some(h) = self.objects[i as usize]
                .bvh
                .closest_hit(origin, dir, t_min, limit)
            {
                t_best = h.t;
                best = Some((i, h));
            }
        }
        best
    }

    /// [`Self::closest_hit`] for any number of objects, in index order.
    fn closest_in_order(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_min: f64,
        t_max: f64,
    ) -> Option<(u32, sss_hierarchy::Hit)> {
        let mut best: Option<(u32, sss_hierarchy::Hit)> = None;
        let mut t_best = t_max;
        for (i, o) in self.objects.iter().enumerate() {
            if !ray_box(o.lo, o.hi, origin, dir, t_min, t_best) {
                continue;
            }
            if let Some(h) = o.bvh.closest_hit(origin, dir, t_min, t_best) {
                t_best = h.t;
                best = Some((i as u32, h));
            }
        }
        best
    }

    /// The closest surface of object `object` along the ray, ignoring every other object.
    pub fn closest_hit_on(
        &self,
        object: u32,
        origin: DVec3,
        dir: DVec3,
        t_min: f64,
        t_max: f64,
    ) -> Option<SurfaceHit> {
        let o = &self.objects[object as usize];
        if !ray_box(o.lo, o.hi, origin, dir, t_min, t_max) {
            return None;
        }
        o.bvh
            .closest_hit(origin, dir, t_min, t_max)
            .map(|h| self.surface_hit(object, h, origin, dir))
    }

    /// Whether anything blocks the segment (t_min, t_max) of the ray.
    pub fn occluded(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> bool {
        self.objects.iter().any(|o| {
            ray_box(o.lo, o.hi, origin, dir, t_min, t_max)
                && o.bvh.occluded(origin, dir, t_min, t_max)
        })
    }

    /// A point just off the surface at `p` on the side of `ng` that `towards` lies on, for
    /// spawning rays without re-hitting the surface.
    pub fn offset(&self, p: DVec3, ng: DVec3, towards: DVec3) -> DVec3 {
        let side = if ng.dot(towards) >= 0.0 { 1.0 } else { -1.0 };
        p + ng * (side * self.epsilon * 4.0)
    }
}

/// The triangles of a mesh as position triples.
pub fn triangles_of(mesh: &Mesh) -> Vec<[DVec3; 3]> {
    mesh.triangles
        .iter()
        .map(|t| {
            [
                mesh.positions[t[0] as usize],
                mesh.positions[t[1] as usize],
                mesh.positions[t[2] as usize],
            ]
        })
        .collect()
}
