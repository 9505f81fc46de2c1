//! Blue-noise sampling on meshes: spacing, count, areas, determinism, degenerate input.

use crate::common::*;
use glam::DVec3;
use proptest::prelude::*;
use rand::RngExt;
use sss_hierarchy::{BlueNoiseStats, SurfaceSample, blue_noise_on_mesh};

fn min_pairwise_distance(s: &[SurfaceSample]) -> f64 {
    let mut best = f64::INFINITY;
    for i in 0..s.len() {
        for j in i + 1..s.len() {
            best = best.min((s[i].position - s[j].position).length());
        }
    }
    best
}

fn area_cv(s: &[SurfaceSample]) -> f64 {
    let n = s.len() as f64;
    let mean = s.iter().map(|x| x.area).sum::<f64>() / n;
    (s.iter().map(|x| (x.area - mean).powi(2)).sum::<f64>() / n).sqrt() / mean
}

fn bits(s: &[SurfaceSample], st: &BlueNoiseStats) -> Vec<u64> {
    let mut out = vec![
        st.radius.to_bits(),
        st.candidates as u64,
        st.surface_area.to_bits(),
    ];
    for x in s {
        out.extend([
            u64::from(x.triangle),
            x.u.to_bits(),
            x.v.to_bits(),
            x.position.x.to_bits(),
            x.position.y.to_bits(),
            x.position.z.to_bits(),
            x.area.to_bits(),
        ]);
    }
    out
}

/// Checks every invariant that holds for any input.
fn check_invariants(
    tris: &[Tri],
    radius: f64,
    max_count: usize,
    s: &[SurfaceSample],
    st: &BlueNoiseStats,
) {
    assert!(s.len() <= max_count);
    let area = total_area(tris);
    assert!((st.surface_area - area).abs() <= 1e-12 * area);
    if s.is_empty() {
        return;
    }
    if radius.is_finite() && radius > 0.0 {
        assert!(st.radius >= radius);
    }
    assert!(st.radius > 0.0 && st.radius.is_finite());
    let sum: f64 = s.iter().map(|x| x.area).sum();
    assert!(
        (sum - area).abs() <= 1e-9 * area,
        "areas sum to {sum}, surface area {area}"
    );
    for x in s {
        let t = tris[x.triangle as usize];
        assert!(area_of(&t) > 0.0);
        assert!(x.u >= 0.0 && x.v >= 0.0 && x.u + x.v <= 1.0 + 1e-12);
        let p = (1.0 - x.u - x.v) * t[0] + x.u * t[1] + x.v * t[2];
        assert_eq!(p, x.position);
        assert!(x.area.is_finite() && x.area >= 0.0);
    }
}

fn area_of(t: &Tri) -> f64 {
    let a = area(t);
    if a.is_finite() { a } else { 0.0 }
}

#[test]
fn sphere_spacing_count_and_areas() {
    let tris = icosphere(5, DVec3::new(0.2, 0.1, -0.3), 1.0);
    let a = total_area(&tris);
    let r = 0.06;
    let (s, st) = blue_noise_on_mesh(&tris, r, usize::MAX, 11);
    check_invariants(&tris, r, usize::MAX, &s, &st);
    // The requested radius is kept when max_count does not bind.
    assert_eq!(st.radius, r);
    // Hard minimum spacing (brute force over all pairs of the ~2300 samples).
    assert!(min_pairwise_distance(&s) >= r);
    // Count vs the Poisson-disk expectation. Dart throwing to saturation (random sequential
    // adsorption) of disks of diameter r jams at a covered fraction of 0.547 (Feder 1980),
    // i.e. N = 0.547 A / (pi r^2 / 4) = 0.697 A / r^2; the hexagonal packing bound is
    // 1.155 A / r^2. This sampler is maximal w.r.t. a dense stratified candidate set and
    // measures 0.65-0.66 on spheres (sub-Poissonian count fluctuations, ~0.5%). A
    // non-maximal (stopped too early) or over-dense sampler falls outside [0.60, 0.72].
    let density = s.len() as f64 * r * r / a;
    assert!((0.60..=0.72).contains(&density), "N r^2 / A = {density}");
    // Blue-noise areas are even: the Voronoi cells of a Poisson (white-noise) point set
    // have a coefficient of variation of 0.53; maximal Poisson-disk sets measure ~0.15.
    let cv = area_cv(&s);
    assert!(cv < 0.2, "area cv {cv}");
    // Every cell holds at least the disk of radius r/2 around its sample (minus curvature),
    // and a maximal set leaves no gap wider than ~r: areas stay within a factor of ~2 of
    // the mean.
    let mean = a / s.len() as f64;
    assert!(s.iter().all(|x| x.area > 0.4 * mean && x.area < 2.2 * mean));
}

#[test]
fn plane_count_with_rim_correction() {
    let tris = plane(3, 1.0, 0.5);
    for (r, seed) in [(0.02, 1), (0.01, 2)] {
        let (s, st) = blue_noise_on_mesh(&tris, r, usize::MAX, seed);
        check_invariants(&tris, r, usize::MAX, &s, &st);
        assert_eq!(st.radius, r);
        if s.len() < 3000 {
            assert!(min_pairwise_distance(&s) >= r);
        }
        // On an open square, disks of diameter r around samples can overhang the border by
        // r/2: the jammed density applies to the square dilated by r/2 (A + P r/2 + pi r^2/4).
        let a_eff = 1.0 + 4.0 * r / 2.0 + std::f64::consts::PI * r * r / 4.0;
        let density = s.len() as f64 * r * r / a_eff;
        assert!(
            (0.60..=0.72).contains(&density),
            "r={r}: N r^2 / A_eff = {density}"
        );
        // Boundary cells are clipped, so the spread is a bit larger than on closed surfaces.
        let cv = area_cv(&s);
        assert!(cv < 0.25, "r={r}: area cv {cv}");
    }
}

/// Exact Voronoi cell of sample `i` in the plane, clipped to the square [0,1]^2 (2D
/// Sutherland-Hodgman clipping by the bisectors of the nearby samples).
fn exact_cell_area(pts: &[(f64, f64)], i: usize, reach: f64) -> f64 {
    let (px, py) = pts[i];
    let mut poly = vec![(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
    for (j, &(qx, qy)) in pts.iter().enumerate() {
        if j == i || (qx - px).hypot(qy - py) > reach {
            continue;
        }
        // Keep points x with (x - m) . (q - p) <= 0, m the midpoint.
        let (nx, ny) = (qx - px, qy - py);
        let (mx, my) = ((px + qx) / 2.0, (py + qy) / 2.0);
        let side = |(x, y): (f64, f64)| (x - mx) * nx + (y - my) * ny;
        let mut out = Vec::new();
        for k in 0..poly.len() {
            let a = poly[k];
            let b = poly[(k + 1) % poly.len()];
            let (sa, sb) = (side(a), side(b));
            if sa <= 0.0 {
                out.push(a);
            }
            if (sa < 0.0 && sb > 0.0) || (sa > 0.0 && sb < 0.0) {
                let t = sa / (sa - sb);
                out.push((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)));
            }
        }
        poly = out;
    }
    let mut a = 0.0;
    for k in 0..poly.len() {
        let (x0, y0) = poly[k];
        let (x1, y1) = poly[(k + 1) % poly.len()];
        a += x0 * y1 - x1 * y0;
    }
    0.5 * a.abs()
}

/// The per-sample areas match the exact (clipped) Voronoi cell areas on a plane to within
/// the discretisation error of the sub-triangles (~1.5% rms), far tighter than the spread
/// of the cell areas themselves (cv ~0.17): assigning equal or shuffled areas would fail.
#[test]
fn areas_match_exact_voronoi_cells_on_a_plane() {
    let tris = plane(3, 1.0, 0.25);
    let r = 0.025;
    let (s, st) = blue_noise_on_mesh(&tris, r, usize::MAX, 17);
    check_invariants(&tris, r, usize::MAX, &s, &st);
    let pts: Vec<(f64, f64)> = s.iter().map(|x| (x.position.x, x.position.y)).collect();
    let n = s.len() as f64;
    let mut sq = 0.0;
    let mut worst: f64 = 0.0;
    for (i, x) in s.iter().enumerate() {
        // Cells of a maximal set lie within ~1.3 r of their site: neighbours within 3r
        // are enough.
        let exact = exact_cell_area(&pts, i, 3.0 * r);
        let rel = (x.area - exact) / exact;
        sq += rel * rel;
        worst = worst.max(rel.abs());
    }
    let rms = (sq / n).sqrt();
    assert!(rms < 0.03, "rms relative area error {rms}");
    assert!(worst < 0.15, "worst relative area error {worst}");
    assert!(
        area_cv(&s) > 0.1,
        "the test needs uneven cells to be meaningful"
    );
}

#[test]
fn max_count_enlarges_the_radius_and_still_covers_everything() {
    let tris = icosphere(4, DVec3::ZERO, 1.0);
    let max_count = 700;
    for radius in [0.001, 0.0, f64::NAN, -1.0, f64::INFINITY] {
        let (s, st) = blue_noise_on_mesh(&tris, radius, max_count, 3);
        check_invariants(&tris, radius, max_count, &s, &st);
        assert!(
            s.len() <= max_count && s.len() > max_count * 9 / 10,
            "{}",
            s.len()
        );
        assert!(st.radius > 0.05);
        assert!(min_pairwise_distance(&s) >= st.radius);
        // Coverage: every point of the surface is within r + (stratum size) of a sample, so
        // the cap did not stop the sampler over part of the surface.
        let mut g = rng(4);
        let mut worst: f64 = 0.0;
        for _ in 0..5000 {
            let t = tris[g.random_range(0..tris.len())];
            let (a, b): (f64, f64) = (g.random(), g.random());
            let (a, b) = if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            let p = t[0] + a * (t[1] - t[0]) + b * (t[2] - t[0]);
            let d = s
                .iter()
                .map(|x| x.position.distance(p))
                .fold(f64::INFINITY, f64::min);
            worst = worst.max(d);
        }
        assert!(
            worst < 1.3 * st.radius,
            "gap of {} for r = {}",
            worst,
            st.radius
        );
        // Even across the surface: each octant holds 1/8 of the samples.
        for oct in 0..8 {
            let n = s
                .iter()
                .filter(|x| {
                    let p = x.position;
                    ((p.x > 0.0) as usize)
                        | (((p.y > 0.0) as usize) << 1)
                        | (((p.z > 0.0) as usize) << 2)
                        == oct
                })
                .count() as f64;
            let expect = s.len() as f64 / 8.0;
            assert!(
                (n - expect).abs() < 0.2 * expect,
                "octant {oct}: {n} vs {expect}"
            );
        }
    }
}

#[test]
fn same_seed_same_bits_different_seed_differs() {
    let tris = icosphere(3, DVec3::ZERO, 2.0);
    let (a, sa) = blue_noise_on_mesh(&tris, 0.15, 5000, 42);
    let (b, sb) = blue_noise_on_mesh(&tris, 0.15, 5000, 42);
    assert_eq!(bits(&a, &sa), bits(&b, &sb));
    let (c, sc) = blue_noise_on_mesh(&tris, 0.15, 5000, 43);
    assert_ne!(bits(&a, &sa), bits(&c, &sc));
    let moved = a
        .iter()
        .zip(&c)
        .filter(|(x, y)| x.position != y.position)
        .count();
    assert!(moved > a.len().min(c.len()) / 2);
}

#[test]
fn output_is_independent_of_the_thread_count() {
    let tris = icosphere(4, DVec3::new(1.0, 2.0, 3.0), 1.3);
    let run = |threads: usize, radius: f64, max_count: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let (s, st) = blue_noise_on_mesh(&tris, radius, max_count, 9);
            bits(&s, &st)
        })
    };
    for (radius, max_count) in [(0.05, usize::MAX), (0.0, 500)] {
        let one = run(1, radius, max_count);
        let two = run(2, radius, max_count);
        let three = run(3, radius, max_count);
        assert!(one.len() > 100);
        assert_eq!(one, two);
        assert_eq!(one, three);
    }
}

#[test]
fn degenerate_inputs() {
    // Empty mesh, max_count 0, zero-area mesh: empty.
    let (s, st) = blue_noise_on_mesh(&[], 0.1, 100, 1);
    assert!(s.is_empty() && st.surface_area == 0.0 && st.radius == 0.0);
    let tris = icosphere(2, DVec3::ZERO, 1.0);
    assert!(blue_noise_on_mesh(&tris, 0.1, 0, 1).0.is_empty());
    let flat: Vec<Tri> = vec![
        [DVec3::ZERO, DVec3::X, DVec3::X * 2.0],
        [DVec3::ONE, DVec3::ONE, DVec3::ONE],
        [DVec3::splat(f64::NAN), DVec3::X, DVec3::Y],
    ];
    let (s, st) = blue_noise_on_mesh(&flat, 0.1, 100, 1);
    assert!(s.is_empty() && st.surface_area == 0.0 && !st.radius.is_nan());

    // Bad triangles mixed in are ignored (never sampled, no area).
    let mut mixed = flat.clone();
    mixed.extend(tris.iter().copied());
    mixed.push([DVec3::ZERO, DVec3::new(f64::INFINITY, 0.0, 0.0), DVec3::Y]);
    mixed.push([
        DVec3::ZERO,
        DVec3::new(1e300, 0.0, 0.0),
        DVec3::new(0.0, 1e300, 0.0),
    ]);
    let (s, st) = blue_noise_on_mesh(&mixed, 0.1, 10_000, 1);
    check_invariants(&mixed, 0.1, 10_000, &s, &st);
    assert!(s.len() > 500);
    assert!(
        s.iter()
            .all(|x| (3..3 + tris.len() as u32).contains(&x.triangle))
    );

    // max_count 1: one sample carrying the whole area.
    for mesh in [&tris, &plane(2, 1.0, 0.0)] {
        let (s, st) = blue_noise_on_mesh(mesh, 0.01, 1, 5);
        check_invariants(mesh, 0.01, 1, &s, &st);
        assert_eq!(s.len(), 1);
        assert!((s[0].area - total_area(mesh)).abs() < 1e-12);
    }

    // A radius larger than the object: one sample.
    let (s, _) = blue_noise_on_mesh(&tris, 10.0, 100, 5);
    assert_eq!(s.len(), 1);

    // Very skinny triangles and mixed scales.
    let skinny: Vec<Tri> = (0..50)
        .map(|i| {
            let y = i as f64 * 0.01;
            [
                DVec3::new(0.0, y, 0.0),
                DVec3::new(5.0, y, 0.0),
                DVec3::new(0.0, y + 1e-4, 1e-5),
            ]
        })
        .collect();
    let (s, st) = blue_noise_on_mesh(&skinny, 0.05, 100_000, 5);
    check_invariants(&skinny, 0.05, 100_000, &s, &st);
    assert!(!s.is_empty());
}

proptest! {
    // A fixed seed, so a failure replays (and CI sees the same cases every run).
    #![proptest_config(ProptestConfig {
        cases: 64,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x5eed_0064),
        ..ProptestConfig::default()
    })]
    /// Random triangle soups, radii and caps: the invariants always hold.
    #[test]
    fn random_meshes_keep_the_invariants(
        seed in any::<u64>(),
        n in 1usize..40,
        radius in prop_oneof![Just(0.0), 0.02f64..0.5, Just(f64::NAN)],
        max_count in prop_oneof![1usize..50, 50usize..2000],
    ) {
        let mut g = rng(seed);
        let tris: Vec<Tri> = (0..n)
            .map(|_| {
                let a = random_in_cube(&mut g, 1.0);
                [a, a + random_in_cube(&mut g, 0.5), a + random_in_cube(&mut g, 0.5)]
            })
            .collect();
        let (s, st) = blue_noise_on_mesh(&tris, radius, max_count, seed);
        check_invariants(&tris, radius, max_count, &s, &st);
        prop_assert!(!s.is_empty());
        prop_assert!(min_pairwise_distance(&s) >= st.radius);
    }
}

/// A long strip narrower than the radius: the count scales like L / r, not A / r², so the
/// radius from `max_count` is badly underestimated at first. The cap must still hold and
/// the strip must still be covered end to end.
#[test]
fn narrow_strip_respects_the_cap_and_is_covered() {
    let (l, w) = (1000.0, 0.01);
    let tris: Vec<Tri> = (0..100)
        .flat_map(|i| {
            let x0 = i as f64 * l / 100.0;
            let x1 = x0 + l / 100.0;
            let p = |x: f64, y: f64| DVec3::new(x, y, 0.0);
            [
                [p(x0, 0.0), p(x1, 0.0), p(x1, w)],
                [p(x0, 0.0), p(x1, w), p(x0, w)],
            ]
        })
        .collect();
    let (s, st) = blue_noise_on_mesh(&tris, 0.0, 200, 1);
    check_invariants(&tris, 0.0, 200, &s, &st);
    assert!(s.len() > 100, "{}", s.len());
    let mut xs: Vec<f64> = s.iter().map(|x| x.position.x).collect();
    xs.sort_by(f64::total_cmp);
    let gap = xs.windows(2).map(|p| p[1] - p[0]).fold(xs[0], f64::max);
    let gap = gap.max(l - xs[xs.len() - 1]);
    assert!(
        gap < 2.5 * st.radius,
        "gap {gap}, r {}, n {}",
        st.radius,
        s.len()
    );
}
