//! Procedural shapes, transforms, mesh clean-up, vertex normals and solid textures.
//!
//! Shapes are built in object space as a [`RawMesh`], moved to world space by a
//! [`Transform`] and turned into a [`Mesh`] by [`finish`], which drops degenerate triangles,
//! removes unused vertices and sets unit per-vertex normals.
//!
//! Sources:
//! - icosphere: the regular icosahedron, each triangle split in four with midpoints pushed to
//!   the sphere (Loop-style 1-to-4 subdivision), the standard geodesic-sphere construction;
//! - smooth vertex normals: the area-weighted mean of the adjacent face normals (sum of the
//!   unnormalised cross products), Gouraud 1971 as weighted by Max, *Weights for computing
//!   vertex normals from facet normals*, JGT 4(2), 1999;
//! - normals under an affine map: the inverse transpose of its linear part (e.g. pbrt,
//!   Pharr, Jakob and Humphreys, 3rd ed., §2.8.3);
//! - value noise: random values on the integer lattice, interpolated trilinearly with
//!   Perlin's quintic fade 6t⁵ − 15t⁴ + 10t³ (Perlin, *Improving Noise*, SIGGRAPH 2002), the
//!   lattice values hashed with the SplitMix64 finaliser (Steele, Lea and Flood, *Fast
//!   splittable pseudorandom number generators*, OOPSLA 2014).

use super::{Mesh, Texture};
use glam::{DMat3, DVec3};
use sss_bssrdf::Rgb;
use std::collections::HashMap;

/// A triangle mesh before transform and clean-up.
#[derive(Clone, Debug, Default)]
pub(super) struct RawMesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Optional per-vertex normals (any length; normalised by [`finish`]). `None` means
    /// "compute smooth normals from the geometry".
    pub normals: Option<Vec<DVec3>>,
    /// Triangles, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

// ---------------------------------------------------------------------------------------------
// Textures and noise

/// Evaluates a solid texture at world-space point `p` (see [`Texture`] for each kind).
pub(crate) fn eval_texture(t: &Texture, p: DVec3) -> Rgb {
    match t {
        Texture::Checker { scale, a, b } => {
            let c = (p / *scale).floor();
            let parity = (c.x as i64)
                .wrapping_add(c.y as i64)
                .wrapping_add(c.z as i64)
                .rem_euclid(2);
            if parity == 0 { *a } else { *b }
        }
        Texture::Stripes { axis, period, a, b } => {
            let t = p.dot(*axis) / *period;
            if t - t.floor() < 0.5 { *a } else { *b }
        }
        Texture::Noise { scale, seed, a, b } => {
            let n = value_noise(p / *scale, *seed);
            std::array::from_fn(|ch| {
                let (lo, hi) = (a[ch].min(b[ch]), a[ch].max(b[ch]));
                (a[ch] + (b[ch] - a[ch]) * n).clamp(lo, hi)
            })
        }
    }
}

/// Smooth 3D value noise in [0, 1]: lattice values hashed from `seed` and the integer cell
/// corner, blended with Perlin's quintic fade (C² across cell faces). Deterministic.
pub(super) fn value_noise(p: DVec3, seed: u64) -> f64 {
    let f = p.floor();
    let (ix, iy, iz) = (f.x as i64, f.y as i64, f.z as i64);
    let t = p - f;
    let (u, v, w) = (fade(t.x), fade(t.y), fade(t.z));
    let l = |dx: i64, dy: i64, dz: i64| {
        lattice(
            seed,
            ix.wrapping_add(dx),
            iy.wrapping_add(dy),
            iz.wrapping_add(dz),
        )
    };
    let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
    let x00 = lerp(l(0, 0, 0), l(1, 0, 0), u);
    let x10 = lerp(l(0, 1, 0), l(1, 1, 0), u);
    let x01 = lerp(l(0, 0, 1), l(1, 0, 1), u);
    let x11 = lerp(l(0, 1, 1), l(1, 1, 1), u);
    let y0 = lerp(x00, x10, v);
    let y1 = lerp(x01, x11, v);
    lerp(y0, y1, w).clamp(0.0, 1.0)
}

/// Perlin's quintic fade curve 6t⁵ − 15t⁴ + 10t³ (Perlin 2002).
fn fade(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// The lattice value at an integer point, uniform in [0, 1): SplitMix64's output function
/// (Steele et al. 2014) chained over the seed and the three coordinates.
fn lattice(seed: u64, x: i64, y: i64, z: i64) -> f64 {
    use sss_util::splitmix64_mix as mix64;
    let mut h = sss_util::splitmix64(seed);
    h = mix64(h ^ x as u64);
    h = mix64(h.wrapping_add(0x632b_e59b_d9b4_e019) ^ y as u64);
    h = mix64(h.wrapping_add(0x8cb9_2ba7_2f3d_8dd7) ^ z as u64);
    (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

// ---------------------------------------------------------------------------------------------
// Shapes (object space)

/// The unit icosphere: positions on the unit sphere and outward counter-clockwise triangles.
/// 20·4ⁿ triangles.
fn icosphere(subdivisions: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut pos: Vec<DVec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, pos: &mut Vec<DVec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                pos.push(((pos[a as usize] + pos[b as usize]) * 0.5).normalize());
                (pos.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for &[a, b, c] in &tris {
            let ab = midpoint(a, b, &mut pos);
            let bc = midpoint(b, c, &mut pos);
            let ca = midpoint(c, a, &mut pos);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    orient_to_normals(&pos, &pos, &mut tris);
    (pos, tris)
}

/// A sphere of `radius` centred at the origin (icosphere, exact radial normals).
pub(super) fn sphere(radius: f64, subdivisions: u32) -> RawMesh {
    let (unit, triangles) = icosphere(subdivisions);
    RawMesh {
        positions: unit.iter().map(|&u| u * radius).collect(),
        normals: Some(unit),
        triangles,
    }
}

/// A sphere of `radius` displaced along its normal by `amplitude·(2n − 1)`, n the value noise
/// at `frequency·u` (u the unit direction, `seed` its seed). Normals come from the displaced
/// geometry. Needs `amplitude < radius`, so the surface stays star-shaped and keeps the
/// icosphere's outward winding.
pub(super) fn bumpy_sphere(
    radius: f64,
    amplitude: f64,
    frequency: f64,
    seed: u64,
    subdivisions: u32,
) -> RawMesh {
    let (unit, triangles) = icosphere(subdivisions);
    let positions = unit
        .iter()
        .map(|&u| u * (radius + amplitude * (2.0 * value_noise(u * frequency, seed) - 1.0)))
        .collect();
    RawMesh {
        positions,
        normals: None,
        triangles,
    }
}

/// A `width` × `depth` rectangle in the xz plane centred at the origin, facing +y, as an
/// `n` × `n` grid of quads (two triangles each).
pub(super) fn plane(width: f64, depth: f64, n: u32) -> RawMesh {
    let n = n.max(1);
    let mut positions = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
    for j in 0..=n {
        for i in 0..=n {
            positions.push(DVec3::new(
                width * (i as f64 / n as f64 - 0.5),
                0.0,
                depth * (j as f64 / n as f64 - 0.5),
            ));
        }
    }
    let idx = |i: u32, j: u32| j * (n + 1) + i;
    let mut triangles = Vec::with_capacity((2 * n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let (v00, v10, v01, v11) = (idx(i, j), idx(i + 1, j), idx(i, j + 1), idx(i + 1, j + 1));
            triangles.push([v00, v01, v10]);
            triangles.push([v10, v01, v11]);
        }
    }
    let normals = vec![DVec3::Y; positions.len()];
    orient_to_normals(&positions, &normals, &mut triangles);
    RawMesh {
        positions,
        normals: Some(normals),
        triangles,
    }
}

/// An axis-aligned box of extents `size` centred at the origin, with flat normals (four
/// vertices per face).
pub(super) fn cuboid(size: DVec3) -> RawMesh {
    let h = size * 0.5;
    // (normal, u, v) with u × v = normal.
    let faces = [
        (DVec3::X, DVec3::Y, DVec3::Z),
        (DVec3::NEG_X, DVec3::Z, DVec3::Y),
        (DVec3::Y, DVec3::Z, DVec3::X),
        (DVec3::NEG_Y, DVec3::X, DVec3::Z),
        (DVec3::Z, DVec3::X, DVec3::Y),
        (DVec3::NEG_Z, DVec3::Y, DVec3::X),
    ];
    let mut mesh = RawMesh {
        normals: Some(Vec::with_capacity(24)),
        ..Default::default()
    };
    let normals = mesh.normals.as_mut().expect("set above");
    for (n, u, v) in faces {
        let base = mesh.positions.len() as u32;
        for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            mesh.positions.push((n + u * su + v * sv) * h);
            normals.push(n);
        }
        mesh.triangles.push([base, base + 1, base + 2]);
        mesh.triangles.push([base, base + 2, base + 3]);
    }
    let normals = mesh.normals.as_deref().expect("set above");
    orient_to_normals(&mesh.positions, normals, &mut mesh.triangles);
    mesh
}

/// A torus around the y axis: tube centre circle of radius `major` in the xz plane, tube
/// radius `minor`; `nu` segments around the axis, `nv` around the tube. Exact normals.
pub(super) fn torus(major: f64, minor: f64, nu: u32, nv: u32) -> RawMesh {
    let tau = std::f64::consts::TAU;
    let mut positions = Vec::with_capacity((nu * nv) as usize);
    let mut normals = Vec::with_capacity((nu * nv) as usize);
    for i in 0..nu {
        let (su, cu) = (tau * i as f64 / nu as f64).sin_cos();
        for j in 0..nv {
            let (sv, cv) = (tau * j as f64 / nv as f64).sin_cos();
            let n = DVec3::new(cv * cu, sv, cv * su);
            positions.push(DVec3::new(major * cu, 0.0, major * su) + n * minor);
            normals.push(n);
        }
    }
    let idx = |i: u32, j: u32| (i % nu) * nv + (j % nv);
    let mut triangles = Vec::with_capacity((2 * nu * nv) as usize);
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    orient_to_normals(&positions, &normals, &mut triangles);
    RawMesh {
        positions,
        normals: Some(normals),
        triangles,
    }
}

/// Reverses every triangle whose geometric normal (b − a) × (c − a) points against the sum of
/// its vertices' normals, so procedural shapes are counter-clockwise seen from outside
/// whatever order their grids were written in.
fn orient_to_normals(positions: &[DVec3], normals: &[DVec3], tris: &mut [[u32; 3]]) {
    for t in tris {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let reference: DVec3 = t.iter().map(|&i| normals[i as usize]).sum();
        if (b - a).cross(c - a).dot(reference) < 0.0 {
            t.swap(1, 2);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Transforms

/// An affine map `x ↦ linear·x + translate`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Transform {
    /// Rotation times scale.
    pub linear: DMat3,
    /// Translation.
    pub translate: DVec3,
}

impl Transform {
    /// Scale, then rotate about X, then Y, then Z (degrees), then translate.
    pub fn new(scale: DVec3, rotate_deg: DVec3, translate: DVec3) -> Self {
        let r = DMat3::from_rotation_z(rotate_deg.z.to_radians())
            * DMat3::from_rotation_y(rotate_deg.y.to_radians())
            * DMat3::from_rotation_x(rotate_deg.x.to_radians());
        Transform {
            linear: r * DMat3::from_diagonal(scale),
            translate,
        }
    }

    /// The curvature of a shape after this map, from its object-space closed form: curvature
    /// scales as 1/s under a uniform scale s and is kept by rotations and translations; `None`
    /// under a non-uniform scale (the closed forms no longer hold).
    pub fn curvature(&self, c: crate::Curvature) -> Option<crate::Curvature> {
        // linear = R·S: its columns' lengths are |s_x|, |s_y|, |s_z|.
        let s = [0, 1, 2].map(|k| self.linear.col(k).length());
        let uniform = (s[0] - s[1]).abs() <= 1e-12 * s[0] && (s[0] - s[2]).abs() <= 1e-12 * s[0];
        if !(uniform && s[0] > 0.0 && s[0].is_finite()) {
            return None;
        }
        let s = s[0];
        Some(match c {
            crate::Curvature::Uniform(k) => crate::Curvature::Uniform(k / s),
            crate::Curvature::Torus {
                center,
                axis,
                major,
                minor,
            } => crate::Curvature::Torus {
                center: self.linear * center + self.translate,
                axis: (self.linear * axis).normalize(),
                major: major * s,
                minor: minor * s,
            },
        })
    }

    /// Applies the map to a mesh: positions, normals by the inverse transpose (renormalised in
    /// [`finish`]), and reversed winding when the map mirrors (negative determinant).
    pub fn apply(&self, mut mesh: RawMesh) -> RawMesh {
        for p in &mut mesh.positions {
            *p = self.linear * *p + self.translate;
        }
        if let Some(normals) = &mut mesh.normals {
            let nm = self.linear.inverse().transpose();
            for n in normals.iter_mut() {
                *n = (nm * *n).normalize_or_zero();
            }
        }
        if self.linear.determinant() < 0.0 {
            for t in &mut mesh.triangles {
                t.swap(1, 2);
            }
        }
        mesh
    }
}

// ---------------------------------------------------------------------------------------------
// Clean-up and normals

/// Relative area below which a triangle counts as degenerate: area < `DEGENERATE_AREA` ·
/// (bounding-box diagonal)². 1e-12 is a triangle whose sides are about 10⁻⁶ of the mesh size,
/// below the precision of the single-precision coordinates OBJ loaders produce.
pub(super) const DEGENERATE_AREA: f64 = 1e-12;

/// Drops degenerate triangles (a repeated index, or area below [`DEGENERATE_AREA`] relative to
/// the mesh scale), removes vertices no triangle uses and sets unit normals: the given ones
/// (flipped to agree with the geometry if they point inwards; computed where unusable), else
/// area-weighted smooth normals. Returns the mesh and the number of triangles dropped.
pub(super) fn finish(raw: RawMesh) -> (Mesh, usize) {
    let RawMesh {
        positions,
        normals,
        triangles,
    } = raw;
    let n = positions.len();
    let in_range = |t: &[u32; 3]| t.iter().all(|&i| (i as usize) < n);
    let (lo, hi) = triangles
        .iter()
        .filter(|t| in_range(t))
        .flat_map(|t| t.iter().map(|&i| positions[i as usize]))
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
    let diag2 = (hi - lo).length_squared();
    let min_area = DEGENERATE_AREA * diag2;
    let mut kept = Vec::with_capacity(triangles.len());
    for t in &triangles {
        if !in_range(t) || t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            continue;
        }
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let area = 0.5 * (b - a).cross(c - a).length();
        if area > min_area && area.is_finite() {
            kept.push(*t);
        }
    }
    let dropped = triangles.len() - kept.len();

    // Compact: keep used vertices in their original order.
    let mut remap = vec![u32::MAX; n];
    for t in &kept {
        for &i in t {
            remap[i as usize] = 0;
        }
    }
    let mut new_positions = Vec::new();
    let mut new_normals = Vec::new();
    for i in 0..n {
        if remap[i] == 0 {
            remap[i] = new_positions.len() as u32;
            new_positions.push(positions[i]);
            if let Some(ns) = &normals {
                new_normals.push(ns.get(i).copied().unwrap_or(DVec3::ZERO));
            }
        }
    }
    let triangles: Vec<[u32; 3]> = kept.iter().map(|t| t.map(|i| remap[i as usize])).collect();
    let computed = smooth_normals(&new_positions, &triangles);
    let normals = if normals.is_some() {
        new_normals
            .iter()
            .zip(&computed)
            .map(|(&given, &smooth)| {
                let g = given.normalize_or_zero();
                if g == DVec3::ZERO || !g.is_finite() {
                    smooth
                } else if g.dot(smooth) < 0.0 {
                    -g
                } else {
                    g
                }
            })
            .collect()
    } else {
        computed
    };
    (
        Mesh {
            positions: new_positions,
            normals,
            triangles,
        },
        dropped,
    )
}

/// Area-weighted vertex normals (Max 1999): the normalised sum of the unnormalised face
/// normals (b − a) × (c − a) of the triangles around each vertex. A vertex whose sum vanishes
/// takes the unit normal of its first triangle.
pub(super) fn smooth_normals(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<DVec3> {
    let mut sum = vec![DVec3::ZERO; positions.len()];
    let mut first = vec![DVec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in t {
            sum[i as usize] += n;
            if first[i as usize] == DVec3::ZERO {
                first[i as usize] = n.normalize_or_zero();
            }
        }
    }
    sum.iter()
        .zip(&first)
        .map(|(s, f)| {
            let u = s.normalize_or_zero();
            if u == DVec3::ZERO { *f } else { u }
        })
        .collect()
}

/// Signed volume enclosed by a triangle mesh, Σ a·(b × c)/6 (divergence theorem); positive
/// when a closed mesh is wound counter-clockwise seen from outside.
pub(super) fn signed_volume(positions: &[DVec3], triangles: &[[u32; 3]]) -> f64 {
    triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            a.dot(b.cross(c))
        })
        .sum::<f64>()
        / 6.0
}

/// Total area of a triangle mesh, Σ |(b − a) × (c − a)|/2.
pub(super) fn area(positions: &[DVec3], triangles: &[[u32; 3]]) -> f64 {
    triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// Whether every undirected edge is shared by exactly two triangles (a closed surface).
pub(super) fn is_closed(triangles: &[[u32; 3]]) -> bool {
    let mut count: HashMap<(u32, u32), u32> = HashMap::with_capacity(triangles.len() * 3 / 2);
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    !count.is_empty() && count.values().all(|&c| c == 2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The noise's lattice values along each axis on its own (the other two coordinates
    /// fixed) look like independent uniforms on [0, 1): all distinct, mean 1/2 and lag-one
    /// correlation 0, each within 5 standard deviations (1/√(12 n) and 1/√n).
    #[test]
    fn lattice_values_are_independent_uniforms_along_each_axis() {
        let n = 4096;
        for axis in 0..3 {
            for (seed, fixed) in [(1u64, 0i64), (7, -3), (u64::MAX, 1 << 40)] {
                let v: Vec<f64> = (-(n as i64) / 2..n as i64 / 2)
                    .map(|k| {
                        let mut c = [fixed; 3];
                        c[axis] = k;
                        lattice(seed, c[0], c[1], c[2])
                    })
                    .collect();
                assert!(v.iter().all(|x| (0.0..1.0).contains(x)));
                let mut sorted = v.clone();
                sorted.sort_by(f64::total_cmp);
                sorted.dedup();
                assert_eq!(sorted.len(), n, "axis {axis}, seed {seed}: repeated values");
                let nf = n as f64;
                let mean = v.iter().sum::<f64>() / nf;
                assert!((mean - 0.5).abs() < 5.0 / (12.0 * nf).sqrt(), "mean {mean}");
                let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / nf;
                let lag = v
                    .windows(2)
                    .map(|w| (w[0] - mean) * (w[1] - mean))
                    .sum::<f64>();
                let rho = lag / ((nf - 1.0) * var);
                assert!(
                    rho.abs() < 5.0 / nf.sqrt(),
                    "axis {axis}: correlation {rho}"
                );
            }
        }
    }
}
