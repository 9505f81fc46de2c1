//! Test meshes shared by the integration tests.
#![allow(dead_code)]

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

pub type Tri = [DVec3; 3];

pub fn rng(seed: u64) -> Pcg64Mcg {
    Pcg64Mcg::seed_from_u64(seed)
}

/// Icosphere with `level` subdivisions (20 * 4^level triangles), all vertices on the sphere
/// of the given centre and radius. Shared vertices are bit-identical (watertight).
pub fn icosphere(level: u32, centre: DVec3, radius: f64) -> Vec<Tri> {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let v = [
        DVec3::new(-1.0, t, 0.0),
        DVec3::new(1.0, t, 0.0),
        DVec3::new(-1.0, -t, 0.0),
        DVec3::new(1.0, -t, 0.0),
        DVec3::new(0.0, -1.0, t),
        DVec3::new(0.0, 1.0, t),
        DVec3::new(0.0, -1.0, -t),
        DVec3::new(0.0, 1.0, -t),
        DVec3::new(t, 0.0, -1.0),
        DVec3::new(t, 0.0, 1.0),
        DVec3::new(-t, 0.0, -1.0),
        DVec3::new(-t, 0.0, 1.0),
    ]
    .map(|p| p.normalize());
    let faces = [
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
    let mut tris: Vec<Tri> = faces.iter().map(|f| [v[f[0]], v[f[1]], v[f[2]]]).collect();
    for _ in 0..level {
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            // (x + y) is commutative in IEEE arithmetic, so shared edges get identical midpoints.
            let ab = (a + b).normalize();
            let bc = (b + c).normalize();
            let ca = (c + a).normalize();
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        tris = next;
    }
    tris.into_iter()
        .map(|t| t.map(|p| centre + radius * p))
        .collect()
}

/// The square [0, size]² in the z = z0 plane, as 2 n² triangles.
pub fn plane(n: usize, size: f64, z0: f64) -> Vec<Tri> {
    let mut out = Vec::new();
    let h = size / n as f64;
    for j in 0..n {
        for i in 0..n {
            let p = |a: usize, b: usize| DVec3::new(a as f64 * h, b as f64 * h, z0);
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            out.push([a, b, c]);
            out.push([a, c, d]);
        }
    }
    out
}

pub fn area(t: &Tri) -> f64 {
    0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()
}

pub fn total_area(tris: &[Tri]) -> f64 {
    tris.iter().map(area).filter(|a| a.is_finite()).sum()
}

/// Uniform direction on the unit sphere.
pub fn random_dir(r: &mut Pcg64Mcg) -> DVec3 {
    let z: f64 = r.random_range(-1.0..1.0);
    let phi: f64 = r.random_range(0.0..std::f64::consts::TAU);
    let s = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// Uniform point in the cube [-h, h]³.
pub fn random_in_cube(r: &mut Pcg64Mcg, h: f64) -> DVec3 {
    DVec3::new(
        r.random_range(-h..h),
        r.random_range(-h..h),
        r.random_range(-h..h),
    )
}

/// Minimal OBJ reader (positions and faces, polygons fanned into triangles) for the
/// optional measurements in `examples/`.
pub fn load_obj(path: &str) -> Vec<Tri> {
    let text = std::fs::read_to_string(path).expect("read obj");
    let mut v = Vec::new();
    let mut tris = Vec::new();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let p: Vec<f64> = it.take(3).map(|x| x.parse().expect("vertex")).collect();
                v.push(DVec3::new(p[0], p[1], p[2]));
            }
            Some("f") => {
                let idx: Vec<usize> = it
                    .map(|x| {
                        let i: i64 = x.split('/').next().unwrap().parse().expect("index");
                        if i < 0 {
                            (v.len() as i64 + i) as usize
                        } else {
                            i as usize - 1
                        }
                    })
                    .collect();
                for k in 1..idx.len().saturating_sub(1) {
                    tris.push([v[idx[0]], v[idx[k]], v[idx[k + 1]]]);
                }
            }
            _ => {}
        }
    }
    tris
}
