//! Procedural shapes (sphere, box, plane, torus, bumpy sphere) against closed forms, and
//! object transforms (scale, rotation order, translation, normals under non-uniform and
//! mirroring scales).

use crate::common::{HEAD, area, bbox, check_mesh, no_dirs, volume};
use glam::DVec3;
use sss_scene::{Mesh, Texture, load_str};
use std::f64::consts::PI;

/// The world-space mesh of a scene made of [`HEAD`] and one object with `body` (the lines
/// after `[[objects]]`, without `material`).
fn mesh_of(body: &str) -> Mesh {
    let text = format!("{HEAD}\n[[objects]]\nmaterial = \"m\"\n{body}\n");
    let scene = load_str(&text, "shape.toml", None, &no_dirs())
        .unwrap_or_else(|e| panic!("{e}\n--- scene ---\n{text}"));
    assert!(
        scene.warnings.is_empty(),
        "unexpected warnings: {:?}",
        scene.warnings
    );
    assert_eq!(scene.objects.len(), 1);
    let mesh = scene.objects[0].mesh.clone();
    check_mesh(&mesh);
    mesh
}

/// Area-weighted centroid of the surface.
fn centroid(m: &Mesh) -> DVec3 {
    let mut sum = DVec3::ZERO;
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        sum += (a + b + c) / 3.0 * 0.5 * (b - a).cross(c - a).length();
    }
    sum / area(m)
}

fn max_edge(m: &Mesh) -> f64 {
    m.triangles
        .iter()
        .flat_map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            [a.distance(b), b.distance(c), c.distance(a)]
        })
        .fold(0.0, f64::max)
}

#[test]
fn sphere_area_volume_and_normals() {
    let r = 1.7;
    let mut last_err = f64::INFINITY;
    for n in 1..=5 {
        let m = mesh_of(&format!(
            "shape = \"sphere\"\nradius = {r}\nsubdivisions = {n}"
        ));
        assert_eq!(m.triangles.len(), 20 * 4usize.pow(n));
        // An inscribed polyhedron whose triangles have sides ≤ h stays outside the ball of
        // radius √(r² − h²/3) (the farthest a triangle's nearest point can be from its
        // vertices), so its area and volume are bracketed.
        let h = max_edge(&m);
        let k = 1.0 - h * h / (3.0 * r * r);
        let (a, v) = (area(&m), volume(&m));
        let (a_exact, v_exact) = (4.0 * PI * r * r, 4.0 / 3.0 * PI * r.powi(3));
        assert!(
            a <= a_exact && a >= a_exact * k,
            "n={n}: area {a} vs {a_exact}"
        );
        assert!(
            v <= v_exact && v >= v_exact * k.powf(1.5),
            "n={n}: volume {v} vs {v_exact}"
        );
        let err = (a_exact - a) / a_exact;
        assert!(err < last_err, "area error must fall with subdivision");
        last_err = err;
        for (p, nrm) in m.positions.iter().zip(&m.normals) {
            assert!((p.length() - r).abs() < 1e-12);
            assert!(nrm.dot(*p) > 0.0);
            assert!((*nrm - *p / r).length() < 1e-12, "exact radial normals");
        }
    }
    assert!(last_err < 2e-3, "{last_err}");
}

#[test]
fn box_plane_torus_closed_forms() {
    let m = mesh_of("shape = \"box\"\nsize = [1.0, 2.0, 3.0]");
    assert_eq!(m.triangles.len(), 12);
    assert_eq!(m.positions.len(), 24);
    assert!((area(&m) - 2.0 * (2.0 + 6.0 + 3.0)).abs() < 1e-12);
    assert!((volume(&m) - 6.0).abs() < 1e-12);
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let face = (b - a).cross(c - a).normalize();
        for &i in t {
            assert!(
                (m.normals[i as usize] - face).length() < 1e-12,
                "flat normals"
            );
        }
        assert!(face.dot((a + b + c) / 3.0) > 0.0, "outward");
    }

    let m = mesh_of("shape = \"plane\"\nsize = [4.0, 2.5]");
    assert_eq!(m.triangles.len(), 2);
    assert!((area(&m) - 10.0).abs() < 1e-12);
    let m = mesh_of("shape = \"plane\"\nsize = [4.0, 2.5]\nsubdivisions = 3");
    assert_eq!(m.triangles.len(), 18);
    assert!((area(&m) - 10.0).abs() < 1e-12);
    let (lo, hi) = bbox(&m);
    assert!((lo - DVec3::new(-2.0, 0.0, -1.25)).length() < 1e-12);
    assert!((hi - DVec3::new(2.0, 0.0, 1.25)).length() < 1e-12);
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        assert!((b - a).cross(c - a).normalize().dot(DVec3::Y) > 1.0 - 1e-12);
    }
    assert!(m.normals.iter().all(|n| *n == DVec3::Y));

    let (big_r, small_r) = (1.0, 0.3);
    let mut last = f64::INFINITY;
    for seg in [16, 32, 64, 128] {
        let m = mesh_of(&format!(
            "shape = \"torus\"\nmajor = {big_r}\nminor = {small_r}\nsegments = [{seg}, {}]",
            seg / 2
        ));
        let a_exact = 4.0 * PI * PI * big_r * small_r;
        let v_exact = 2.0 * PI * PI * big_r * small_r * small_r;
        let (ea, ev) = (
            (area(&m) - a_exact).abs() / a_exact,
            (volume(&m) - v_exact).abs() / v_exact,
        );
        assert!(ea < last, "torus area error must fall");
        last = ea;
        if seg >= 64 {
            assert!(ea < 0.01 && ev < 0.01, "seg {seg}: {ea} {ev}");
        }
        assert!(volume(&m) > 0.0);
        for (p, n) in m.positions.iter().zip(&m.normals) {
            let ring = DVec3::new(p.x, 0.0, p.z).normalize() * big_r;
            assert!(n.dot(*p - ring) > 0.0, "outward torus normal");
        }
    }
    // Default segments and a single number.
    mesh_of("shape = \"torus\"\nmajor = 1.0\nminor = 0.3");
    let m = mesh_of("shape = \"torus\"\nmajor = 1.0\nminor = 0.3\nsegments = 12");
    assert_eq!(m.triangles.len(), 2 * 12 * 12);
}

#[test]
fn bumpy_sphere_is_displaced_smoothly_and_deterministically() {
    let body = |seed: u64| {
        format!(
            "shape = \"bumpy-sphere\"\nradius = 2.0\namplitude = 0.2\nfrequency = 3.0\n\
             seed = {seed}\nsubdivisions = 4"
        )
    };
    let m = mesh_of(&body(7));
    assert_eq!(m.triangles.len(), 20 * 256);
    let radii: Vec<f64> = m.positions.iter().map(|p| p.length()).collect();
    assert!(radii.iter().all(|&r| (1.8..=2.2).contains(&r)));
    let spread = radii.iter().cloned().fold(0.0, f64::max)
        - radii.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(spread > 0.1, "the surface is displaced ({spread})");
    // Displaced by amplitude·(2n − 1), n the value noise at frequency·u: the noise texture
    // at scale 1/frequency gives n (within rounding: it divides by the scale).
    let noise = Texture::Noise {
        scale: 1.0 / 3.0,
        seed: 7,
        a: [0.0; 3],
        b: [1.0; 3],
    };
    for (p, r) in m.positions.iter().zip(&radii) {
        let n = noise.eval(*p / *r)[0];
        assert!(
            (r - (2.0 + 0.2 * (2.0 * n - 1.0))).abs() < 1e-9,
            "{p}: {r}, noise {n}"
        );
    }
    assert!(volume(&m) > 0.0);
    for (p, n) in m.positions.iter().zip(&m.normals) {
        assert!(n.dot(*p) > 0.0, "outward");
    }
    // Normals come from the displaced geometry, not the sphere.
    let tilted = m
        .positions
        .iter()
        .zip(&m.normals)
        .filter(|(p, n)| n.dot(p.normalize()) < 0.99)
        .count();
    assert!(tilted > 100, "{tilted}");
    // Smooth (Lipschitz): each partial derivative of the value noise is at most
    // max fade' = 15/8 per lattice unit, so along an edge whose unit directions are a chord c
    // apart the radius changes by at most 2·amplitude·(15/8)·√3·frequency·c.
    let lipschitz = 2.0 * 0.2 * 1.875 * 3f64.sqrt() * 3.0;
    let mut steepest: f64 = 0.0;
    for t in &m.triangles {
        for k in 0..3 {
            let (i, j) = (t[k] as usize, t[(k + 1) % 3] as usize);
            let chord = (m.positions[i] / radii[i]).distance(m.positions[j] / radii[j]);
            let slope = (radii[i] - radii[j]).abs() / chord;
            assert!(slope <= lipschitz + 1e-9, "slope {slope}");
            steepest = steepest.max(slope);
        }
    }
    assert!(steepest > 0.05 * lipschitz, "{steepest}");
    assert_eq!(m, mesh_of(&body(7)));
    assert_ne!(m.positions, mesh_of(&body(8)).positions);
}

#[test]
fn transforms() {
    let base = mesh_of("shape = \"sphere\"\nradius = 1.0\nsubdivisions = 3");
    let scaled =
        mesh_of("shape = \"sphere\"\nradius = 1.0\nsubdivisions = 3\ntransform = { scale = 2.5 }");
    assert!((area(&scaled) / area(&base) - 6.25).abs() < 1e-12);
    assert!((volume(&scaled) / volume(&base) - 2.5f64.powi(3)).abs() < 1e-12);

    let moved = mesh_of(
        "shape = \"box\"\nsize = [1.0, 2.0, 3.0]\ntransform = { translate = [1.0, -2.0, 3.5] }",
    );
    assert!((centroid(&moved) - DVec3::new(1.0, -2.0, 3.5)).length() < 1e-12);
    assert!((area(&moved) - 22.0).abs() < 1e-12);

    // Non-uniform scale of a box: closed-form area.
    let m =
        mesh_of("shape = \"box\"\nsize = [1.0, 1.0, 1.0]\ntransform = { scale = [1.0, 2.0, 3.0] }");
    assert!((area(&m) - 22.0).abs() < 1e-12);

    // Rotation order: X first, then Y, then Z. A 1×2×3 box turned 90° about X becomes
    // 1×3×2, then 90° about Y becomes 2×3×1 (Y first would give 3×1×2).
    let m = mesh_of(
        "shape = \"box\"\nsize = [1.0, 2.0, 3.0]\ntransform = { rotate = [90.0, 90.0, 0.0] }",
    );
    let (lo, hi) = bbox(&m);
    assert!(
        (hi - lo - DVec3::new(2.0, 3.0, 1.0)).length() < 1e-9,
        "{}",
        hi - lo
    );
    let m = mesh_of(
        "shape = \"box\"\nsize = [1.0, 2.0, 3.0]\ntransform = { rotate = [0.0, 0.0, 90.0] }",
    );
    let (lo, hi) = bbox(&m);
    assert!((hi - lo - DVec3::new(2.0, 1.0, 3.0)).length() < 1e-9);
    // Scale before rotation: scale x by 3, then turn about Z: the long side ends up along y.
    let m = mesh_of(
        "shape = \"box\"\nsize = [1.0, 1.0, 1.0]\n\
         transform = { scale = [3.0, 1.0, 1.0], rotate = [0.0, 0.0, 90.0], translate = [0.0, 5.0, 0.0] }",
    );
    let (lo, hi) = bbox(&m);
    assert!((hi - lo - DVec3::new(1.0, 3.0, 1.0)).length() < 1e-9);
    assert!((centroid(&m) - DVec3::new(0.0, 5.0, 0.0)).length() < 1e-9);

    // Normals under a non-uniform scale: the ellipsoid's gradient direction (x/a², y/b², z/c²).
    let (a, b, c) = (1.0, 1.3, 0.06);
    let m = mesh_of(&format!(
        "shape = \"sphere\"\nradius = 1.0\nsubdivisions = 3\ntransform = {{ scale = [{a}, {b}, {c}] }}"
    ));
    for (p, n) in m.positions.iter().zip(&m.normals) {
        let g = DVec3::new(p.x / (a * a), p.y / (b * b), p.z / (c * c)).normalize();
        assert!((*n - g).length() < 1e-9, "{n} vs {g}");
    }

    // A mirroring scale keeps the surface facing outwards.
    let m = mesh_of(
        "shape = \"sphere\"\nradius = 1.0\nsubdivisions = 2\ntransform = { scale = [-1.0, 1.0, 1.0] }",
    );
    assert!(volume(&m) > 0.0);
    for (p, n) in m.positions.iter().zip(&m.normals) {
        assert!(n.dot(*p) > 0.0);
    }
}

/// The closed-form curvature of procedural shapes follows the object's transform: 1/(s r) for
/// a sphere under a uniform scale s, 0 for planes and boxes, none under a non-uniform scale or
/// for the bumpy sphere; a rotated, scaled, moved torus gives max(1/r, |cos v|/(R + r cos v))
/// at its vertices (R, r scaled), v the angle around the tube.
#[test]
fn analytic_curvature_follows_the_transform() {
    use sss_scene::Curvature;
    let curvature_of = |body: &str| {
        let text = format!("{HEAD}\n[[objects]]\nmaterial = \"m\"\n{body}\n");
        let scene = load_str(&text, "shape.toml", None, &no_dirs()).unwrap();
        (scene.objects[0].curvature, scene.objects[0].mesh.clone())
    };
    let (c, _) = curvature_of("shape = \"sphere\"\nradius = 0.5\ntransform = { scale = 2.0 }");
    // A scalar scale applies to every axis.
    match c {
        Some(Curvature::Uniform(k)) => assert!((k - 1.0).abs() < 1e-12, "{k}"),
        other => panic!("{other:?}"),
    }
    let (c, _) = curvature_of(
        "shape = \"sphere\"\nradius = 0.5\ntransform = { scale = [-3.0, 3.0, 3.0], rotate = [10.0, 20.0, 30.0], translate = [1.0, 2.0, 3.0] }",
    );
    match c {
        Some(Curvature::Uniform(k)) => assert!((k - 2.0 / 3.0).abs() < 1e-12, "{k}"),
        other => panic!("{other:?}"),
    }
    // Non-uniform along any one axis: no closed form.
    for scale in ["[1.0, 2.0, 1.0]", "[1.0, 1.0, 2.0]", "[2.0, 1.0, 1.0]"] {
        let (c, _) = curvature_of(&format!(
            "shape = \"sphere\"\nradius = 0.5\ntransform = {{ scale = {scale} }}"
        ));
        assert_eq!(c, None, "scale {scale}");
    }
    let (c, _) = curvature_of("shape = \"plane\"\nsize = [2.0, 3.0]");
    assert_eq!(c, Some(Curvature::Uniform(0.0)));
    let (c, _) = curvature_of("shape = \"box\"\nsize = [1.0, 2.0, 3.0]");
    assert_eq!(c, Some(Curvature::Uniform(0.0)));
    let (c, _) =
        curvature_of("shape = \"bumpy-sphere\"\nradius = 1.0\namplitude = 0.1\nfrequency = 3.0");
    assert_eq!(c, None);
    // The torus: at every vertex, compare with the closed form in the torus's own frame.
    let (c, mesh) = curvature_of(
        "shape = \"torus\"\nmajor = 1.0\nminor = 0.6\nsegments = [48, 24]\ntransform = { scale = 2.0, rotate = [90.0, 0.0, 30.0], translate = [5.0, -1.0, 2.0] }",
    );
    let c = c.expect("a torus under a uniform scale has a closed form");
    let (big_r, r) = (2.0, 1.2);
    let center = DVec3::new(5.0, -1.0, 2.0);
    // The local y axis, rotated 90° about x then 30° about z.
    let axis = glam::DMat3::from_rotation_z(30f64.to_radians())
        * glam::DMat3::from_rotation_x(90f64.to_radians())
        * DVec3::Y;
    let mut inner = 0;
    for p in &mesh.positions {
        let q = *p - center;
        let h = q.dot(axis);
        let rho = (q - axis * h).length();
        // cos v from the point's place around the tube.
        let cos_v = (rho - big_r) / r;
        let want = (1.0 / r).max((cos_v / (big_r + r * cos_v)).abs());
        let got = c.max_abs_at(*p);
        assert!((got - want).abs() < 1e-9 * want, "{got} vs {want} at {p:?}");
        if (cos_v / (big_r + r * cos_v)).abs() > 1.0 / r {
            inner += 1;
        }
    }
    // R < 2r (R = 2, r = 1.2): near the hole |κ₂| (up to 1/(R − r) = 1.25) beats 1/r = 0.83.
    assert!(inner > 20, "{inner} vertices where κ₂ wins");
    // On the inner equator, ρ = R − r = 0.8: κ₂ = −1/(R − r).
    let inner_point = center + axis.any_orthonormal_vector() * 0.8;
    assert!((c.max_abs_at(inner_point) - 1.25).abs() < 1e-12);
}
