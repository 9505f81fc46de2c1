//! The Rusinkiewicz estimator against analytic curvature: sphere (κ₁ = κ₂ = 1/R), cylinder
//! (1/R and 0), plane (0), on meshes generated here; finiteness on degenerate meshes.

use sss_bandwidth::BandwidthError;
use sss_bandwidth::curvature::{VertexCurvature, vertex_curvatures, vertex_max_abs_curvature};
use std::collections::HashMap;

/// An icosphere of radius `r` centred at `c`: the icosahedron subdivided `levels` times, every
/// vertex projected onto the sphere. Outward winding.
fn icosphere(levels: u32, r: f64, c: [f64; 3]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<[f64; 3]> = vec![
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let mut f: Vec<[u32; 3]> = vec![
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
    let unit = |p: [f64; 3]| {
        let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        [p[0] / l, p[1] / l, p[2] / l]
    };
    for p in &mut v {
        *p = unit(*p);
    }
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::with_capacity(f.len() * 4);
        for tri in &f {
            let mut m = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                m[k] = *mid.entry(key).or_insert_with(|| {
                    let (pa, pb) = (v[a as usize], v[b as usize]);
                    v.push(unit([pa[0] + pb[0], pa[1] + pb[1], pa[2] + pb[2]]));
                    (v.len() - 1) as u32
                });
            }
            next.push([tri[0], m[0], m[2]]);
            next.push([tri[1], m[1], m[0]]);
            next.push([tri[2], m[2], m[1]]);
            next.push([m[0], m[1], m[2]]);
        }
        f = next;
    }
    let v = v
        .into_iter()
        .map(|p| [c[0] + r * p[0], c[1] + r * p[1], c[2] + r * p[2]])
        .collect();
    (v, f)
}

/// An open cylinder of radius `r` about the z axis, `seg` segments around, `rings` rows of
/// quads of height `h`, each split into two triangles. Outward winding.
fn cylinder(r: f64, seg: u32, rings: u32, h: f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut v = Vec::new();
    for j in 0..=rings {
        for i in 0..seg {
            let a = std::f64::consts::TAU * f64::from(i) / f64::from(seg);
            v.push([r * a.cos(), r * a.sin(), h * f64::from(j)]);
        }
    }
    let id = |i: u32, j: u32| j * seg + (i % seg);
    let mut f = Vec::new();
    for j in 0..rings {
        for i in 0..seg {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            f.push([a, b, c]);
            f.push([a, c, d]);
        }
    }
    (v, f)
}

/// A jittered `n × n` grid on the plane through `origin` spanned by `u`, `w`.
fn plane(n: u32, origin: [f64; 3], u: [f64; 3], w: [f64; 3]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut v = Vec::new();
    let mut state = 12345u64;
    let mut jitter = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.4
    };
    for j in 0..n {
        for i in 0..n {
            let (a, b) = (f64::from(i) + jitter(), f64::from(j) + jitter());
            v.push([0, 1, 2].map(|k| origin[k] + a * u[k] + b * w[k]));
        }
    }
    let mut f = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i;
            f.push([a, a + 1, a + n + 1]);
            f.push([a, a + n + 1, a + n]);
        }
    }
    (v, f)
}

fn check_all_finite(c: &[VertexCurvature]) {
    for (i, v) in c.iter().enumerate() {
        for x in [v.k1, v.k2, v.max_abs(), v.mean(), v.gaussian()] {
            assert!(x.is_finite(), "vertex {i}: {v:?}");
        }
        for d in [v.dir1, v.dir2, v.normal] {
            assert!(d.is_finite(), "vertex {i}: {v:?}");
        }
        assert!(v.k1 >= v.k2);
    }
}

#[test]
fn sphere_has_curvature_one_over_r_everywhere() {
    for (r, centre) in [
        (1.0, [0.0; 3]),
        (2.5, [10.0, -3.0, 7.0]),
        (1e-3, [1e-3; 3]),
        (1e3, [0.0; 3]),
    ] {
        let (v, f) = icosphere(4, r, centre);
        assert_eq!(v.len(), 2562);
        let c = vertex_curvatures(&v, &f).unwrap();
        check_all_finite(&c);
        let mut worst = 0.0f64;
        for (i, vc) in c.iter().enumerate() {
            assert!(vc.valid, "vertex {i}");
            for k in [vc.k1, vc.k2] {
                worst = worst.max((k * r - 1.0).abs());
            }
            // The normal points outward.
            let p = v[i];
            let radial = [0, 1, 2].map(|k| (p[k] - centre[k]) / r);
            let dot = vc.normal.x * radial[0] + vc.normal.y * radial[1] + vc.normal.z * radial[2];
            assert!(dot > 0.999, "vertex {i}: {dot}");
        }
        assert!(worst < 0.02, "R = {r}: worst relative error {worst}");
    }
}

#[test]
fn inward_winding_flips_the_sign_but_not_k() {
    let (v, mut f) = icosphere(3, 2.0, [0.0; 3]);
    for t in &mut f {
        t.swap(1, 2);
    }
    let c = vertex_curvatures(&v, &f).unwrap();
    let k = vertex_max_abs_curvature(&v, &f).unwrap();
    for (vc, k) in c.iter().zip(&k) {
        assert!(
            (vc.k1 + 0.5).abs() < 0.01 && (vc.k2 + 0.5).abs() < 0.01,
            "{vc:?}"
        );
        assert!((k - 0.5).abs() < 0.01);
    }
}

#[test]
fn cylinder_has_curvatures_one_over_r_and_zero() {
    for r in [1.0, 40.0] {
        let (seg, rings) = (96, 30);
        let h = 2.0 * std::f64::consts::PI * r / f64::from(seg); // square-ish quads
        let (v, f) = cylinder(r, seg, rings, h);
        let c = vertex_curvatures(&v, &f).unwrap();
        check_all_finite(&c);
        for (i, vc) in c.iter().enumerate() {
            let ring = i as u32 / seg;
            assert!(vc.valid);
            if ring == 0 || ring == rings {
                continue; // boundary: one-sided, only finiteness (checked above)
            }
            assert!((vc.k1 * r - 1.0).abs() < 0.02, "vertex {i}: {vc:?}");
            assert!(vc.k2.abs() * r < 0.02, "vertex {i}: {vc:?}");
            assert!((vc.max_abs() * r - 1.0).abs() < 0.02);
            // κ₁ runs around the axis, κ₂ along it.
            assert!(vc.dir1.z.abs() < 0.05, "vertex {i}: {vc:?}");
            assert!(vc.dir2.z.abs() > 0.99, "vertex {i}: {vc:?}");
        }
    }
}

#[test]
fn torus_matches_its_analytic_principal_curvatures() {
    // Torus of radii (a, b): at tube angle φ (0 outside), κ = 1/b around the tube and
    // cos φ / (a + b cos φ) around the axis (positive outside, negative inside: both signs).
    let (a, b) = (3.0, 1.0);
    let (nu, nv) = (192u32, 96u32);
    let mut v = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let th = std::f64::consts::TAU * f64::from(i) / f64::from(nu);
            let ph = std::f64::consts::TAU * f64::from(j) / f64::from(nv);
            let rr = a + b * ph.cos();
            v.push([rr * th.cos(), rr * th.sin(), b * ph.sin()]);
        }
    }
    let id = |i: u32, j: u32| (j % nv) * nu + (i % nu);
    let mut f = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let (p, q, r, s) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            f.push([p, q, r]);
            f.push([p, r, s]);
        }
    }
    let c = vertex_curvatures(&v, &f).unwrap();
    check_all_finite(&c);
    for (idx, vc) in c.iter().enumerate() {
        let ph = std::f64::consts::TAU * f64::from(idx as u32 / nu) / f64::from(nv);
        let tube = 1.0 / b;
        let axis = ph.cos() / (a + b * ph.cos());
        let (k1, k2) = (tube.max(axis), tube.min(axis));
        assert!(
            (vc.k1 - k1).abs() < 0.02 * tube,
            "vertex {idx} φ {ph}: {vc:?} vs {k1}, {k2}"
        );
        assert!(
            (vc.k2 - k2).abs() < 0.02 * tube,
            "vertex {idx} φ {ph}: {vc:?} vs {k1}, {k2}"
        );
        assert!((vc.max_abs() - tube).abs() < 0.02 * tube);
    }
}

#[test]
fn plane_has_zero_curvature() {
    let s = 1.0 / 3f64.sqrt();
    for (origin, u, w) in [
        ([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        (
            [5.0, -2.0, 1.0],
            [s, s, s],
            [0.0, 2f64.sqrt() / 2.0, -(2f64.sqrt()) / 2.0],
        ),
    ] {
        let (v, f) = plane(16, origin, u, w);
        let c = vertex_curvatures(&v, &f).unwrap();
        check_all_finite(&c);
        for vc in &c {
            assert!(vc.valid);
            assert!(vc.max_abs() < 1e-9, "{vc:?}");
        }
    }
}

#[test]
fn degenerate_and_boundary_vertices_are_finite() {
    let (mut v, mut f) = plane(4, [0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
    // Bend one vertex up so the patch is curved, with every vertex on the boundary or next to it.
    v[5][2] = 0.3;
    let n = v.len() as u32;
    // A zero-area triangle (three collinear points) and a sliver touching the patch.
    v.push([10.0, 0.0, 0.0]);
    v.push([11.0, 0.0, 0.0]);
    v.push([12.0, 0.0, 0.0]);
    f.push([n, n + 1, n + 2]);
    f.push([0, n, n + 1]);
    // A triangle with a repeated index, and two coincident vertices.
    f.push([1, 1, 2]);
    v.push(v[3]);
    f.push([2, 3, n + 3]);
    // An isolated vertex.
    v.push([-5.0, -5.0, -5.0]);
    let c = vertex_curvatures(&v, &f).unwrap();
    assert_eq!(c.len(), v.len());
    check_all_finite(&c);
    // The collinear triangle's own vertices and the isolated one have no usable face except
    // the sliver: vertices n + 2 and n + 4 are invalid with curvature 0.
    for i in [n + 2, n + 4] {
        let vc = c[i as usize];
        assert!(
            !vc.valid && vc.k1 == 0.0 && vc.k2 == 0.0,
            "vertex {i}: {vc:?}"
        );
    }
    // The bent vertex is curved.
    assert!(c[5].max_abs() > 0.1, "{:?}", c[5]);
    // Only degenerate input: every vertex invalid, no error.
    let c = vertex_curvatures(&[[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], &[[0, 1, 2]]).unwrap();
    assert!(c.iter().all(|vc| !vc.valid && vc.max_abs() == 0.0));
    assert!(vertex_curvatures(&[], &[]).unwrap().is_empty());
}

#[test]
fn bad_meshes_are_errors() {
    let v = [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    assert!(matches!(
        vertex_curvatures(&v, &[[0, 1, 3]]),
        Err(BandwidthError::InvalidMesh(_))
    ));
    assert!(matches!(
        vertex_curvatures(
            &[[0.0; 3], [f64::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]],
            &[[0, 1, 2]]
        ),
        Err(BandwidthError::InvalidMesh(_))
    ));
}
