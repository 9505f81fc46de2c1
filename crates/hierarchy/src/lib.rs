//! # sss-hierarchy
//!
//! Spatial structures for the subsurface-scattering renderer:
//!
//! * [`TriangleBvh`]: a bounding volume hierarchy over one object's triangles, with
//!   [`closest_hit`](TriangleBvh::closest_hit) and [`occluded`](TriangleBvh::occluded)
//!   queries that return `f64` distances and barycentrics. Use one per object for camera
//!   rays, shadow rays, and rays that continue from a surface point. It is `Send + Sync`, so
//!   rayon threads can share it.
//! * [`blue_noise_on_mesh`]: a Poisson-disk (blue-noise) point set on a mesh surface. Each
//!   point carries the surface area it represents. This is what the irradiance-sample
//!   stage of a hierarchical BSSRDF integrator needs (Jensen & Buhler 2002): the outgoing
//!   radiance is estimated as `Σ R_d(|x - x_i|) · E_i · A_i` over the samples. Evenly
//!   spread points with accurate, low-variance areas `A_i` keep that sum's error small.
//! * [`IrradianceTree`] and [`PixelTree`]: kd-trees ([`KdTree`], flat arrays, a contiguous
//!   range per node) over irradiance samples and over shading points in screen space, with
//!   the node aggregates of Jensen & Buhler 2002 (area, flux, irradiance-weighted position)
//!   and Milaenen et al. 2019 §4.2 (world bounds, mean position/normal/view, max s_p). Use
//!   them for hierarchical point sums: the single-tree (Jensen & Buhler) and dual-tree
//!   (Milaenen) traversals of `sss-render` walk them.
//!
//! ## Example
//!
//! ```
//! use glam::DVec3;
//! use sss_hierarchy::{TriangleBvh, blue_noise_on_mesh};
//!
//! // A unit square in the z = 0 plane, as two triangles.
//! let (a, b, c, d) = (DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y);
//! let tris = vec![[a, b, c], [a, c, d]];
//!
//! // Ray casting.
//! let bvh = TriangleBvh::new(&tris);
//! let hit = bvh
//!     .closest_hit(DVec3::new(0.7, 0.2, 1.0), DVec3::NEG_Z, 0.0, f64::INFINITY)
//!     .expect("the ray hits the square");
//! assert_eq!(hit.triangle, 0);
//! assert!((hit.t - 1.0).abs() < 1e-12);
//! let p = (1.0 - hit.u - hit.v) * tris[0][0] + hit.u * tris[0][1] + hit.v * tris[0][2];
//! assert!(p.distance(DVec3::new(0.7, 0.2, 0.0)) < 1e-12);
//! assert!(!bvh.occluded(DVec3::new(2.0, 2.0, 1.0), DVec3::NEG_Z, 0.0, f64::INFINITY));
//!
//! // Blue-noise samples at least 0.05 apart, with their areas.
//! let (samples, stats) = blue_noise_on_mesh(&tris, 0.05, 10_000, 7);
//! assert!(samples.len() > 200 && samples.len() <= 10_000);
//! let total: f64 = samples.iter().map(|s| s.area).sum();
//! assert!((total - 1.0).abs() < 1e-9);
//! assert_eq!(stats.radius, 0.05);
//! ```
//!
//! ## Algorithms and references
//!
//! * **BVH.** The [obvhs](https://crates.io/crates/obvhs) compressed 8-wide BVH (CwBvh,
//!   Ylitie, Karras & Laine, "Efficient Incoherent Ray Traversal on GPUs Through
//!   Compressed Wide BVHs", HPG 2017), built with PLOC (Meister & Bittner, "Parallel
//!   Locally-Ordered Clustering for Bounding Volume Hierarchy Construction", TVCG 2018) and
//!   traversed in `f32`. Triangle tests are the two-sided Möller–Trumbore test (JGT 1997)
//!   in `f64`. The `f32` traversal is made conservative (a normalised frame, padded boxes,
//!   clipped rays), and the `f64` test keeps its own best hit, so `f32` rounding never
//!   loses a hit. The results are identical to a brute-force `f64` loop over all triangles
//!   with [`intersect_triangle`]. CwBvh was chosen over obvhs' binary BVH (`Bvh2`) because
//!   it traced 1.3–2× faster on the 60k-triangle Stanford bunny, for closest-hit and
//!   occlusion rays, from outside and from the surface (`examples/bvh_speed.rs`). `Bvh2`
//!   built faster (~30 vs ~50 ms). `Bvh2` remains the fallback for pathologically deep
//!   trees.
//! * **Blue noise.** Dart throwing (Cook, "Stochastic sampling in computer graphics", TOG
//!   1986) over the area-weighted triangle distribution, with a hash grid. Then void
//!   filling with one stratified candidate per small surface cell, in random order, which
//!   makes the set maximal. That follows the ideas of Bridson ("Fast Poisson disk sampling in
//!   arbitrary dimensions", SIGGRAPH sketches 2007), Ebeida et al. ("Efficient maximal
//!   Poisson-disk sampling", SIGGRAPH 2011) and Yuksel ("Sample elimination for generating
//!   Poisson disk sample sets", EG 2015). Each sample's area is its restricted Voronoi
//!   cell, approximated on surface cells of size ≈ radius/5. The relation between the
//!   radius and the point count comes from the random-sequential-adsorption jamming
//!   density of disks (≈ 0.547, Feder 1980). See [`blue_noise`] for details.

#![forbid(unsafe_code)]

pub mod blue_noise;
mod bvh;
pub mod irradiance_tree;
pub mod kdtree;
pub mod pixel_tree;

pub use blue_noise::{BlueNoiseStats, SurfaceSample, blue_noise_on_mesh};
pub use bvh::{Hit, TriangleBvh, intersect_triangle};
pub use irradiance_tree::{IrradianceCluster, IrradiancePoint, IrradianceTree};
pub use kdtree::{KdNode, KdTree};
pub use pixel_tree::{PixelCluster, PixelPoint, PixelTree};

#[cfg(test)]
mod send_sync {
    fn assert_send_sync<T: Send + Sync>() {}

    #[test]
    fn bvh_is_send_sync() {
        assert_send_sync::<super::TriangleBvh>();
        assert_send_sync::<super::Hit>();
        assert_send_sync::<super::SurfaceSample>();
    }
}
