//! The cosine bound of normal cones (`cone::cos_upper`, MDLC's bound) bounds every cosine it
//! stands for, is attained in closed-form configurations, and makes the estimator treat
//! triangles that face away from the light as exact zeros.

use glam::DVec3;
use sss_manylight::cone::{NormalCone, cos_upper};
use sss_manylight::*;

mod common;
use common::U;

fn random_box(u: &mut U, spread: f64) -> Aabb {
    let c = (u.v() - 0.5) * spread;
    let h = u.v() * u.v() * 0.5;
    Aabb {
        min: c - h,
        max: c + h,
    }
}

fn point_in(b: &Aabb, u: &mut U) -> DVec3 {
    b.min + u.v() * (b.max - b.min)
}

/// A unit vector within `half` radians of `axis`, uniform in angle (edge of the cone included
/// often).
fn in_cone(axis: DVec3, half: f64, u: &mut U) -> DVec3 {
    let (a, b) = axis.any_orthonormal_pair();
    let theta = half * u.f().sqrt().max(if u.f() < 0.2 { 1.0 } else { 0.0 });
    let phi = std::f64::consts::TAU * u.f();
    (axis * theta.cos() + (a * phi.cos() + b * phi.sin()) * theta.sin()).normalize()
}

#[test]
fn the_cosine_bound_is_never_exceeded() {
    let mut u = U(5);
    let mut zero = 0usize;
    let mut tight = 0usize;
    for trial in 0..2000 {
        let from = random_box(&mut u, 3.0);
        let to = random_box(&mut u, 3.0);
        let half = match trial % 4 {
            0 => 0.0,
            1 => 0.3 * u.f(),
            2 => 1.5 * u.f(),
            _ => std::f64::consts::PI * u.f(),
        };
        let cone = NormalCone {
            axis: u.dir(),
            half_angle: half,
        };
        let bound = cos_upper(&cone, &from, &to);
        assert!((0.0..=1.0).contains(&bound), "trial {trial}: {bound}");
        let mut seen = f64::NEG_INFINITY;
        for _ in 0..400 {
            let (x, y) = (point_in(&from, &mut u), point_in(&to, &mut u));
            let d = y - x;
            if d.length_squared() < 1e-20 {
                continue;
            }
            let n = in_cone(cone.axis, half, &mut u);
            let c = n.dot(d.normalize());
            assert!(
                c <= bound + 1e-12,
                "trial {trial}: cos {c} > bound {bound} (cone {cone:?}, {from:?} -> {to:?})"
            );
            seen = seen.max(c);
        }
        if bound == 0.0 {
            zero += 1;
        }
        if seen > 0.0 && seen >= bound - 0.1 {
            tight += 1;
        }
    }
    // Not vacuous: some pairs are ruled out entirely, and most bounds are within 0.1 of a
    // cosine the 400 random samples reach.
    assert!(zero > 100, "{zero} of 2000 bounds are 0");
    assert!(
        tight > 1000,
        "{tight} of 2000 bounds within 0.1 of a sampled cosine"
    );
}

#[test]
fn the_cosine_bound_matches_closed_forms() {
    let b = |lo: [f64; 3], hi: [f64; 3]| Aabb {
        min: DVec3::from(lo),
        max: DVec3::from(hi),
    };
    let up = NormalCone {
        axis: DVec3::Y,
        half_angle: 0.0,
    };
    let origin = b([0.0; 3], [0.0; 3]);
    // A point straight above a point: cos = 1.
    assert_eq!(
        cos_upper(&up, &origin, &b([0.0, 2.0, 0.0], [0.0, 2.0, 0.0])),
        1.0
    );
    // Straight below, or in the plane: 0.
    assert_eq!(
        cos_upper(&up, &origin, &b([0.0, -2.0, 0.0], [0.0, -2.0, 0.0])),
        0.0
    );
    // (In the plane the bound is cos(π/2 − slack) ≈ 1e-10, below the estimator's GRAZING_COS,
    // so `bounds::cos_i_upper` makes it 0.)
    let c = cos_upper(&up, &origin, &b([3.0, 0.0, 0.0], [3.0, 0.0, 0.0]));
    assert!((0.0..=1e-9).contains(&c), "{c}");
    assert_eq!(
        bounds::cos_i_upper(Some(&up), &origin, &b([3.0, 0.0, 0.0], [3.0, 0.0, 0.0])),
        0.0
    );
    // At 45° above the plane: cos = 1/√2 (to the slack of 1e-9 rad).
    let c = cos_upper(&up, &origin, &b([1.0, 1.0, 0.0], [1.0, 1.0, 0.0]));
    assert!((c - 0.5f64.sqrt()).abs() < 1e-8, "{c}");
    // A cone of half-angle 30° about +y towards a point 60° from +y: cos(30°).
    let cone = NormalCone {
        axis: DVec3::Y,
        half_angle: 30f64.to_radians(),
    };
    let p = DVec3::new(60f64.to_radians().sin(), 60f64.to_radians().cos(), 0.0);
    let c = cos_upper(&cone, &origin, &Aabb::point(p));
    assert!((c - 30f64.to_radians().cos()).abs() < 1e-8, "{c}");
    // The underside of a slab (normal −y) and a light high above: 0. A light in the slab's
    // plane far to the side (a grazing one): 0. One just above the plane: small but > 0.
    let down = NormalCone {
        axis: -DVec3::Y,
        half_angle: 0.0,
    };
    let slab_bottom = b([-2.0, 0.0, -1.5], [2.0, 0.0, 1.5]);
    let sun = Aabb::point(DVec3::new(-1e6, 6e5, 0.0));
    assert_eq!(cos_upper(&down, &slab_bottom, &sun), 0.0);
    assert!(cos_upper(&up, &slab_bottom, &sun) > 0.5);
    // Overlapping solid boxes allow every direction; within one plane, only in-plane ones.
    let solid = b([-1.0; 3], [1.0; 3]);
    assert_eq!(cos_upper(&down, &solid, &solid), 1.0);
    assert!(cos_upper(&down, &slab_bottom, &slab_bottom) <= 1e-9);
}

/// A closed box (12 triangles, outward normals) lit by one point light above it: the bound of
/// every triangle of the bottom face is 0, so the estimator never samples or refines them, and
/// the estimate still agrees with a brute-force integral over the lit top face.
#[test]
fn faces_turned_away_from_the_light_are_exact_zeros() {
    // The box [−1, 1] × [0, 0.2] × [−1, 1].
    let (x0, x1, y0, y1, z0, z1) = (-1.0, 1.0, 0.0, 0.2, -1.0, 1.0);
    let p = |x, y, z| DVec3::new(x, y, z);
    let positions = vec![
        p(x0, y0, z0),
        p(x1, y0, z0),
        p(x1, y0, z1),
        p(x0, y0, z1),
        p(x0, y1, z0),
        p(x1, y1, z0),
        p(x1, y1, z1),
        p(x0, y1, z1),
    ];
    // Counter-clockwise seen from outside.
    let tris: Vec<[u32; 3]> = vec![
        [0, 1, 2],
        [0, 2, 3], // bottom (−y)
        [4, 6, 5],
        [4, 7, 6], // top (+y)
        [0, 4, 5],
        [0, 5, 1], // −z
        [3, 2, 6],
        [3, 6, 7], // +z
        [0, 3, 7],
        [0, 7, 4], // −x
        [1, 5, 6],
        [1, 6, 2], // +x
    ];
    let tree = IrradianceTree::new(&positions, &tris).unwrap();
    for (k, t) in tree.triangles().iter().enumerate() {
        let expect = [
            DVec3::NEG_Y,
            DVec3::Y,
            DVec3::NEG_Z,
            DVec3::Z,
            DVec3::NEG_X,
            DVec3::X,
        ][k / 2];
        assert!(
            t.normal.distance(expect) < 1e-12,
            "triangle {k}: {:?}",
            t.normal
        );
    }
    let light = DVec3::new(0.0, 3.0, 0.0);
    let lights = LightTree::new(vec![Vpl::point(light, [1.0; 3])]).unwrap();
    let sigma = 3.0;
    let rd = move |r: f64| [(-sigma * r).exp() * sigma * sigma / std::f64::consts::TAU; 3];
    let profile = RadialProfile::new(rd, 4.0).unwrap();
    let ft = Transmittance::new(|_| 1.0).unwrap();
    let t = StudentT::new(0.95).unwrap();
    let mut settings = Settings::new(1e6);
    settings.epsilon = 0.0;
    settings.max_triplets = 4096;
    let est = Estimator::new(&lights, &tree, &profile, &ft, &t, settings).unwrap();
    let xo = DVec3::new(0.3, 0.2, -0.2);
    let shading = ShadingTree::new(vec![ShadingPoint {
        position: xo,
        normal: DVec3::Y,
        weight: 1.0,
    }])
    .unwrap();
    let open = |_: DVec3, _: DVec3| true;
    let mut refs = Refinements::new(1 << 20);
    let px = est.estimate_with(&shading, &open, 7, &mut refs);
    // Every split made is of a triangle the light can reach: the top face (y = 0.2) or the
    // four sides' upper parts; none lies in the bottom plane.
    let bottom_splits = refs
        .nodes()
        .iter()
        .filter(|s| s.triangle.normal.y < -0.5)
        .count();
    assert_eq!(
        bottom_splits, 0,
        "{} splits of bottom triangles",
        bottom_splits
    );
    assert!(refs.splits() > 100);
    // Brute force: the top face only (the sides see the light at grazing angles and add
    // little, so they are included too), a 400 × 400 midpoint rule per face.
    let n = 400;
    let mut sum = 0.0;
    let faces: [(DVec3, DVec3, DVec3, DVec3); 5] = [
        (p(x0, y1, z0), DVec3::X * 2.0, DVec3::Z * 2.0, DVec3::Y),
        (p(x0, y0, z0), DVec3::X * 2.0, DVec3::Y * 0.2, DVec3::NEG_Z),
        (p(x0, y0, z1), DVec3::X * 2.0, DVec3::Y * 0.2, DVec3::Z),
        (p(x0, y0, z0), DVec3::Z * 2.0, DVec3::Y * 0.2, DVec3::NEG_X),
        (p(x1, y0, z0), DVec3::Z * 2.0, DVec3::Y * 0.2, DVec3::X),
    ];
    for (o, e1, e2, nrm) in faces {
        let da = e1.length() * e2.length() / (n * n) as f64;
        for i in 0..n {
            for j in 0..n {
                let x = o + e1 * ((i as f64 + 0.5) / n as f64) + e2 * ((j as f64 + 0.5) / n as f64);
                let d = light - x;
                let d2 = d.length_squared();
                let cos = nrm.dot(d / d2.sqrt());
                if cos > 0.0 {
                    sum += rd(x.distance(xo))[0] * cos / d2 * da;
                }
            }
        }
    }
    let se = px.std_error;
    assert!(
        (px.value - sum).abs() < 4.0 * se + 1e-3 * sum,
        "estimate {} ± {se} vs brute force {sum}",
        px.value
    );
    assert!(se < 0.02 * sum, "se {se} of {sum}");
}

/// The default caps' memory, as the settings' doc states it (about 110 MB per pixel at most),
/// counted from the sizes of the entries: a triplet and its queue entry per retired or live
/// triplet, two triangles per split.
#[test]
fn default_caps_take_about_110_mb() {
    let s = Settings::new(1.0);
    assert_eq!((s.max_triplets, s.max_splits), (200_000, 200_000));
    let b = s.peak_pixel_bytes() as f64 / 1e6;
    assert!((80.0..140.0).contains(&b), "{b} MB");
    let mut small = s;
    small.max_splits = 1;
    small.max_triplets = 1;
    assert!(small.peak_pixel_bytes() < 1000);
}
