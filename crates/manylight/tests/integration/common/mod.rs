//! A tiny scene shared by the estimator tests, and an independent brute-force evaluation of
//! Eq. 1 (VPLs × fine midpoint quadrature over the triangles × shading points) that shares no
//! code with the crate's estimator.
#![allow(dead_code)]

use glam::DVec3;
use sss_manylight::*;

/// A seeded stream of uniforms in [0, 1) (splitmix64 over a Weyl sequence), for the tests'
/// random configurations.
pub struct U(pub u64);

impl U {
    /// A uniform in [0, 1).
    pub fn f(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        (sss_util::splitmix64_mix(self.0) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A point of the unit cube.
    pub fn v(&mut self) -> DVec3 {
        DVec3::new(self.f(), self.f(), self.f())
    }

    /// A uniformly distributed unit vector (Archimedes: z uniform in [−1, 1]).
    pub fn dir(&mut self) -> DVec3 {
        let z = 2.0 * self.f() - 1.0;
        let phi = std::f64::consts::TAU * self.f();
        let s = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(s * phi.cos(), s * phi.sin(), z)
    }
}

/// Decay lengths of the test profile per channel.
pub const ELL: [f64; 3] = [0.3, 0.2, 0.1];
/// Amplitudes of the test profile per channel.
pub const AMP: [f64; 3] = [1.0, 2.0, 4.0];
/// The G clamp.
pub const G_MAX: f64 = 100.0;

pub fn rd(r: f64) -> [f64; 3] {
    [0, 1, 2].map(|c| AMP[c] * (-r / ELL[c]).exp())
}

pub fn ft(c: f64) -> f64 {
    1.0 - 0.5 * (1.0 - c).powi(5)
}

/// A unit square at z = 0 as a 2 × 2 grid (8 triangles, normal +z), plus a strip tilted up
/// along x = 1 (2 triangles, normal −x … pointing back over the square).
pub fn mesh() -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            p.push(DVec3::new(0.5 * i as f64, 0.5 * j as f64, 0.0));
        }
    }
    let mut t = Vec::new();
    for j in 0..2u32 {
        for i in 0..2u32 {
            let a = j * 3 + i;
            t.push([a, a + 1, a + 4]);
            t.push([a, a + 4, a + 3]);
        }
    }
    // The wall x = 1, z in [0, 0.5], facing −x (wound so that the normal is −x).
    let base = p.len() as u32;
    p.push(DVec3::new(1.0, 0.0, 0.0));
    p.push(DVec3::new(1.0, 1.0, 0.0));
    p.push(DVec3::new(1.0, 1.0, 0.5));
    p.push(DVec3::new(1.0, 0.0, 0.5));
    t.push([base, base + 2, base + 1]);
    t.push([base, base + 3, base + 2]);
    (p, t)
}

/// Four VPLs: two point lights above, one oriented light facing down, one point light below
/// the square (its light only reaches the wall's back… which faces away: contributes 0), and
/// one close to the surface so the G clamp binds.
pub fn vpls() -> Vec<Vpl> {
    vec![
        Vpl::point(DVec3::new(0.3, 0.4, 0.8), [1.0, 0.5, 0.25]),
        Vpl::oriented(
            DVec3::new(0.7, 0.2, 0.6),
            DVec3::new(0.2, 0.1, -1.0),
            [0.3, 0.6, 0.9],
        ),
        Vpl::point(DVec3::new(0.5, 0.5, -0.5), [2.0, 2.0, 2.0]),
        Vpl::point(DVec3::new(0.6, 0.7, 0.05), [0.02, 0.03, 0.01]),
    ]
}

pub fn shading_points() -> Vec<ShadingPoint> {
    [
        (0.45, 0.5, 0.3),
        (0.55, 0.45, 0.2),
        (0.5, 0.6, 0.25),
        (0.4, 0.55, 0.25),
    ]
    .iter()
    .map(|&(x, y, w)| ShadingPoint {
        position: DVec3::new(x, y, 0.0),
        normal: DVec3::Z,
        weight: w,
    })
    .collect()
}

/// Light 0 is blocked for irradiance points with x > 0.5 (a grid line, so the quadrature
/// never straddles the shadow edge).
pub fn visibility(xi: DVec3, y: DVec3) -> bool {
    !(xi.x > 0.5 && (y - DVec3::new(0.3, 0.4, 0.8)).length() < 1e-12)
}

pub struct Scene {
    pub lights: LightTree,
    pub surface: TriangleClusterTree,
    pub profile: RadialProfile,
    pub ft: Transmittance,
    pub t: StudentT,
    pub shading: ShadingTree,
}

pub fn scene() -> Scene {
    let (p, t) = mesh();
    Scene {
        lights: LightTree::new(vpls()).unwrap(),
        surface: TriangleClusterTree::new(&p, &t).unwrap(),
        profile: RadialProfile::new(rd, 2.0).unwrap(),
        ft: Transmittance::new(ft).unwrap(),
        t: StudentT::new(0.95).unwrap(),
        shading: ShadingTree::new(shading_points()).unwrap(),
    }
}

/// Eq. 1 by brute force: Σ_{x_o} w Σ_y ∫ R_d I G V F_t dA with the midpoint rule on m² equal
/// sub-triangles of each triangle. Returns RGB.
pub fn brute_force(m: usize) -> [f64; 3] {
    let (p, tris) = mesh();
    let lights = vpls();
    let sps = shading_points();
    let mut out = [0.0; 3];
    for t in &tris {
        let (a, b, c) = (p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]);
        let n = (b - a).cross(c - a);
        let area = 0.5 * n.length();
        let n = n / n.length();
        let sub = area / (m * m) as f64;
        // Sub-triangle centroids of the regular subdivision, in barycentric steps of 1/m.
        let mut pts = Vec::with_capacity(m * m);
        for i in 0..m {
            for j in 0..(m - i) {
                let (fi, fj) = (i as f64, j as f64);
                let up = [(fi, fj), (fi + 1.0, fj), (fi, fj + 1.0)];
                pts.push(up);
                if j + 1 < m - i {
                    pts.push([(fi + 1.0, fj), (fi + 1.0, fj + 1.0), (fi, fj + 1.0)]);
                }
            }
        }
        assert_eq!(pts.len(), m * m);
        for tri in pts {
            let (u, v) = (
                (tri[0].0 + tri[1].0 + tri[2].0) / (3.0 * m as f64),
                (tri[0].1 + tri[1].1 + tri[2].1) / (3.0 * m as f64),
            );
            let xi = a + u * (b - a) + v * (c - a);
            // Irradiance at xi (transmitted), RGB.
            let mut e = [0.0; 3];
            for y in &lights {
                let to = y.position - xi;
                let d2 = to.length_squared();
                let dir = to / d2.sqrt();
                let cos_i = n.dot(dir);
                let cos_y = match y.normal {
                    None => 1.0,
                    Some(ny) => ny.dot(-dir),
                };
                if cos_i <= 0.0 || cos_y <= 0.0 || !visibility(xi, y.position) {
                    continue;
                }
                let g = cos_i * cos_y * (1.0 / d2).min(G_MAX) * ft(cos_i);
                for (e, i) in e.iter_mut().zip(y.intensity) {
                    *e += i * g;
                }
            }
            for s in &sps {
                let r = rd((xi - s.position).length());
                for ((o, r), e) in out.iter_mut().zip(r).zip(e) {
                    *o += s.weight * r * e * sub;
                }
            }
        }
    }
    out
}

pub fn lum(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}
