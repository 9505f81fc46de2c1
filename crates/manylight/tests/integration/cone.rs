//! The cosine bound of normal cones (`cone::cos_upper`, MDLC's bound) bounds every cosine it
//! stands for, is attained in closed-form configurations, and makes the estimator treat
//! triangles that face away from the light as exact zeros.

use glam::DVec3;
use sss_manylight::cone::{NormalCone, cos_upper};
use sss_manylight::*;

use crate::common::U;

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
    let tree = TriangleClusterTree::new(&positions, &tris).unwrap();
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

/// Unit vector at `angle` from `a` towards `b` (both unit, not parallel), in their plane.
fn towards(a: DVec3, b: DVec3, angle: f64) -> DVec3 {
    let p = (b - a * a.dot(b)).normalize();
    a * angle.cos() + p * angle.sin()
}

/// The angle between two unit vectors, as `acos` of the clamped dot product: an independent
/// measure (the crate uses atan2).
fn angle(a: DVec3, b: DVec3) -> f64 {
    a.dot(b).clamp(-1.0, 1.0).acos()
}

/// `NormalCone::union` against the geometry of two cones sharing a plane: the smallest cone
/// around both spans, in that plane, from the first cone's far edge to the second's, so its
/// half-angle is (φ + θ₁ + θ₂)/2 and its axis lies (φ + θ₂ − θ₁)/2 from the first axis towards
/// the second (φ the angle between the axes).
#[test]
fn the_union_of_two_cones_is_the_smallest_cone_around_both() {
    // Two directions 90° apart: the bisector, half-angle 45°.
    let x = NormalCone {
        axis: DVec3::X,
        half_angle: 0.0,
    };
    let y = NormalCone {
        axis: DVec3::Y,
        half_angle: 0.0,
    };
    let c = x.union(y);
    assert!(
        (c.half_angle - std::f64::consts::FRAC_PI_4).abs() < 1e-12,
        "{c:?}"
    );
    assert!(
        c.axis.distance(DVec3::new(1.0, 1.0, 0.0).normalize()) < 1e-12,
        "{c:?}"
    );
    // 10° and 20° cones whose axes are 60° apart: half-angle 45°, axis 35° from the first.
    let a = DVec3::new(1.0, 2.0, -0.5).normalize();
    let far = DVec3::new(-0.3, 0.4, 1.0).normalize();
    let b = towards(a, far, 60f64.to_radians());
    let (ca, cb) = (
        NormalCone {
            axis: a,
            half_angle: 10f64.to_radians(),
        },
        NormalCone {
            axis: b,
            half_angle: 20f64.to_radians(),
        },
    );
    let c = ca.union(cb);
    assert!((c.half_angle - 45f64.to_radians()).abs() < 1e-12, "{c:?}");
    let expect = towards(a, b, 35f64.to_radians());
    assert!(
        c.axis.distance(expect) < 1e-12,
        "{:?} vs {expect:?}",
        c.axis
    );
    // Both far edges lie on its boundary; directions of either cone lie inside; a direction
    // just beyond a far edge does not.
    let edge_a = towards(a, b, -10f64.to_radians());
    let edge_b = towards(a, b, 80f64.to_radians());
    for e in [edge_a, edge_b] {
        assert!((angle(c.axis, e) - c.half_angle).abs() < 1e-9);
        assert!(c.contains(e));
    }
    assert!(!c.contains(towards(a, b, -10.1f64.to_radians())));
    assert!(!c.contains(towards(a, b, 80.1f64.to_radians())));
    // The other order gives the same cone.
    let d = cb.union(ca);
    assert!((d.half_angle - c.half_angle).abs() < 1e-12);
    assert!(d.axis.distance(c.axis) < 1e-12);
    // A cone that holds the other is its own union with it, whichever comes first.
    let big = NormalCone {
        axis: a,
        half_angle: 1.0,
    };
    let small = NormalCone {
        axis: towards(a, far, 0.3),
        half_angle: 0.5,
    };
    assert_eq!(big.union(small), big);
    assert_eq!(small.union(big), big);
}

/// Cones whose union needs the whole sphere, or that point in opposite directions (no plane
/// to rotate in): the union is a finite cone, of half-angle at most π (the field's range),
/// that holds every direction of both.
#[test]
fn unions_of_opposite_or_wide_cones_hold_both_and_stay_in_range() {
    let mut u = U(11);
    let cases = [
        // Opposite axes, 1 rad each: the smallest cone has half-angle (π + 2)/2 < π.
        (DVec3::X, 1.0, DVec3::NEG_X, 1.0),
        (DVec3::Z, 0.0, DVec3::NEG_Z, 0.0),
        // 90° apart, 2.5 rad each: together they cover the sphere ((φ + θ₁ + θ₂)/2 > π).
        (DVec3::X, 2.5, DVec3::Y, 2.5),
    ];
    for (a, ta, b, tb) in cases {
        let (ca, cb) = (
            NormalCone {
                axis: a,
                half_angle: ta,
            },
            NormalCone {
                axis: b,
                half_angle: tb,
            },
        );
        let c = ca.union(cb);
        assert!(c.axis.is_finite() && c.half_angle.is_finite(), "{c:?}");
        assert!((c.axis.length() - 1.0).abs() < 1e-12, "{c:?}");
        assert!(
            c.half_angle <= std::f64::consts::PI,
            "{c:?}: half-angle beyond π"
        );
        assert!(
            c.half_angle >= (0.5 * (angle(a, b) + ta + tb)).min(std::f64::consts::PI) - 1e-12,
            "{c:?} is narrower than the smallest cone"
        );
        for (k, (axis, half)) in [(a, ta), (b, tb)].into_iter().enumerate() {
            for _ in 0..500 {
                let n = in_cone(axis, half, &mut u);
                assert!(
                    c.contains(n),
                    "cone {k} of {a:?}/{b:?}: {n:?} outside {c:?}"
                );
            }
        }
    }
}

/// `contains` against directions at known angles from the axis.
#[test]
fn contains_holds_exactly_the_directions_within_the_half_angle() {
    let axis = DVec3::new(0.2, 1.0, 0.3).normalize();
    let side = DVec3::new(1.0, -0.1, 0.4).normalize();
    let cone = NormalCone {
        axis,
        half_angle: 30f64.to_radians(),
    };
    for (deg, inside) in [
        (0.0, true),
        (29.9, true),
        (30.0, true),
        (30.1, false),
        (90.0, false),
        (150.0, false),
        (180.0, false),
    ] {
        let d = towards(axis, side, f64::to_radians(deg));
        assert_eq!(cone.contains(d), inside, "{deg}°");
    }
    let none = NormalCone {
        axis,
        half_angle: 0.0,
    };
    assert!(none.contains(axis));
    assert!(!none.contains(towards(axis, side, 1e-6)));
}

/// The bound is an upper bound of the cosines computed in f64, with no tolerance: at the
/// cone's edge towards a point, n · d equals cos(angle − half-angle) to rounding, and the
/// slack of [`cone::ANGLE_SLACK`] keeps the bound above it; it is still tight (within 1e-9).
#[test]
fn the_bound_covers_the_computed_cosine_at_the_cones_edge() {
    let origin = Aabb::point(DVec3::ZERO);
    let axis = DVec3::new(0.3, 1.0, -0.2).normalize();
    let side = DVec3::new(1.0, 0.1, 0.7).normalize();
    for half_deg in [0.0, 10.0, 30.0, 55.0] {
        for at_deg in [5.0, 20.0, 45.0, 60.0, 75.0, 100.0, 130.0] {
            let (half, at) = (f64::to_radians(half_deg), f64::to_radians(at_deg));
            let cone = NormalCone {
                axis,
                half_angle: half,
            };
            let p = 2.5 * towards(axis, side, at);
            let bound = cos_upper(&cone, &origin, &Aabb::point(p));
            // The cone's normal nearest to the direction of p.
            let n = towards(axis, side, half.min(at));
            let c = n.dot(p.normalize()).clamp(0.0, 1.0);
            assert!(
                bound >= c,
                "{half_deg}° cone, point at {at_deg}°: {bound} < {c}"
            );
            assert!(bound <= c + 1e-9, "{half_deg}°, {at_deg}°: {bound} vs {c}");
        }
    }
}

/// A box lying on the axis's negative ray and ending at the other box: every direction
/// between them is exactly opposite the axis, so no cosine is positive (the zero vector, from
/// the shared end point, has no direction).
#[test]
fn a_box_straight_behind_the_axis_gets_a_zero_bound() {
    let cone = NormalCone {
        axis: DVec3::X,
        half_angle: 0.0,
    };
    let segment = Aabb {
        min: DVec3::ZERO,
        max: DVec3::X,
    };
    let end = Aabb::point(DVec3::ZERO);
    let c = cos_upper(&cone, &segment, &end);
    assert!((0.0..=1e-9).contains(&c), "{c}");
    // Away from the end point: also 0.
    let c = cos_upper(&cone, &segment, &Aabb::point(-DVec3::X));
    assert!((0.0..=1e-9).contains(&c), "{c}");
}

/// The documented trivial bound 1 for empty boxes (`Aabb::is_empty`: `min > max` on some
/// axis, with finite corners too) and non-finite ones, in configurations where the bound
/// computed from the corners would be about 0.
#[test]
fn empty_and_non_finite_boxes_get_the_trivial_bound() {
    let up = NormalCone {
        axis: DVec3::Y,
        half_angle: 0.0,
    };
    let origin = Aabb::point(DVec3::ZERO);
    let below = Aabb::point(DVec3::new(0.0, -2.0, 0.0));
    // The corners alone give 0 (the other box lies below).
    assert_eq!(cos_upper(&up, &origin, &below), 0.0);
    let inverted_at_origin = Aabb {
        min: DVec3::ZERO,
        max: DVec3::new(-1.0, 0.0, 0.0),
    };
    assert!(inverted_at_origin.is_empty());
    assert_eq!(cos_upper(&up, &inverted_at_origin, &below), 1.0);
    let inverted_below = Aabb {
        min: DVec3::new(1.0, -2.0, 0.0),
        max: DVec3::new(0.0, -2.0, 0.0),
    };
    assert!(inverted_below.is_empty());
    assert_eq!(cos_upper(&up, &origin, &inverted_below), 1.0);
    assert_eq!(cos_upper(&up, &Aabb::EMPTY, &below), 1.0);
    assert_eq!(cos_upper(&up, &origin, &Aabb::EMPTY), 1.0);
    // A ray of points below the plane, reaching to +∞ along x: one infinite corner, with the
    // other box's corners and the cone's axis finite.
    let ray_below = Aabb {
        min: DVec3::new(0.0, -1.0, 0.0),
        max: DVec3::new(f64::INFINITY, -1.0, 0.0),
    };
    assert_eq!(cos_upper(&up, &origin, &ray_below), 1.0);
    assert_eq!(cos_upper(&up, &ray_below, &origin), 1.0);
    let ray_behind = Aabb {
        min: DVec3::new(f64::NEG_INFINITY, -1.0, 0.0),
        max: DVec3::new(0.0, -1.0, 0.0),
    };
    assert_eq!(cos_upper(&up, &origin, &ray_behind), 1.0);
    // A non-finite axis.
    let nan = NormalCone {
        axis: DVec3::NAN,
        half_angle: 0.0,
    };
    assert_eq!(cos_upper(&nan, &origin, &below), 1.0);
}
