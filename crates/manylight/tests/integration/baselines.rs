//! The two baselines (MDLC and EELC) on the tiny scene of `common/mod.rs`, against brute-force
//! sums written here independently of the crate: over their own point sets (Σ_i Σ_y S_i I_y H,
//! every pair evaluated) and, for importance-sampled points, against the brute-force integral of
//! `common::brute_force`.

use crate::common::*;
use glam::DVec3;
use sss_manylight::*;

/// A seeded stream of uniforms for the tests' point sets.
fn stream(seed: u64) -> U {
    U(sss_util::splitmix64(seed))
}

/// H(y, x) by hand: cos θ_i cos θ_y min(1/d², G_MAX) F_t(cos θ_i) V, 0 facing away.
fn h(y: &Vpl, x: DVec3, n: DVec3) -> f64 {
    let to = y.position - x;
    let d2 = to.length_squared();
    let dir = to / d2.sqrt();
    let cos_i = n.dot(dir);
    let cos_y = y.normal.map_or(1.0, |ny| ny.dot(-dir));
    if cos_i <= 0.0 || cos_y <= 0.0 || !visibility(x, y.position) {
        return 0.0;
    }
    cos_i * cos_y * (1.0 / d2).min(G_MAX) * ft(cos_i)
}

/// Σ over the given gather points and VPLs of S ⊙ I · H, per channel.
fn point_set_sum(points: &[&GatherPoint], lights: &[&Vpl]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for x in points {
        for y in lights {
            let v = h(y, x.position, x.normal);
            for (c, o) in out.iter_mut().enumerate() {
                *o += x.strength[c] * y.intensity[c] * v;
            }
        }
    }
    out
}

/// N uniform points per shading point of the tiny scene (density 1/A over the whole mesh, A/N
/// each), as gather points.
fn uniform_gather(s: &Scene, n: usize, seed: u64) -> Vec<GatherPoint> {
    let mut u = stream(seed);
    let mut next = || u.f();
    let mut out = Vec::new();
    for sp in shading_points() {
        let mut pts = Vec::new();
        uniform_points(&s.surface, n, &mut next, &mut pts);
        gather_points(&sp, &pts, &s.profile, &mut out);
    }
    out
}

/// Total mesh area of the tiny scene: the unit square and the 1 × 0.5 wall.
const MESH_AREA: f64 = 1.5;
/// Length of the test's planar importance sampling around a shading point.
const ELL_IS: f64 = 0.15;

/// N importance-sampled points per shading point, by a defensive mixture written here: with
/// probability 1/2 a point uniform over the mesh (found by the test's own triangle walk), with
/// probability 1/2 a point of the plane z = 0 around x_o with density e^{−r/ℓ}/(2πℓ²) (r from a
/// Gamma(2, ℓ) draw), kept if it falls on the unit square. The density of a point is
/// q = ½/A + ½ e^{−r/ℓ}/(2πℓ²) [on the square], and each point carries A_k = 1/(N q).
fn importance_gather(s: &Scene, n: usize, seed: u64) -> Vec<GatherPoint> {
    let (pos, tris) = mesh();
    let areas: Vec<f64> = tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| pos[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .collect();
    assert!((areas.iter().sum::<f64>() - MESH_AREA).abs() < 1e-12);
    let mut u = stream(seed);
    let mut out = Vec::new();
    for sp in shading_points() {
        let mut pts = Vec::new();
        let q_plane = |x: DVec3| {
            let on_square = x.z == 0.0 && (0.0..=1.0).contains(&x.x) && (0.0..=1.0).contains(&x.y);
            let r = x.distance(sp.position);
            0.5 / MESH_AREA
                + if on_square {
                    0.5 * (-r / ELL_IS).exp() / (std::f64::consts::TAU * ELL_IS * ELL_IS)
                } else {
                    0.0
                }
        };
        for _ in 0..n {
            if u.f() < 0.5 {
                // A triangle by area (a linear walk), then the square-root parameterisation.
                let mut pick = u.f() * MESH_AREA;
                let mut k = 0;
                while k + 1 < tris.len() && pick >= areas[k] {
                    pick -= areas[k];
                    k += 1;
                }
                let [a, b, c] = tris[k].map(|i| pos[i as usize]);
                let (r1, r2) = (u.f().sqrt(), u.f());
                let x = a * (1.0 - r1) + b * (r1 * (1.0 - r2)) + c * (r1 * r2);
                let normal = (b - a).cross(c - a).normalize();
                pts.push(IrradiancePoint {
                    position: x,
                    normal,
                    geometric: normal,
                    area: 1.0 / (n as f64 * q_plane(x)),
                });
            } else {
                let r = -ELL_IS * ((1.0 - u.f()) * (1.0 - u.f())).ln();
                let phi = std::f64::consts::TAU * u.f();
                let x = sp.position + DVec3::new(r * phi.cos(), r * phi.sin(), 0.0);
                if (0.0..=1.0).contains(&x.x) && (0.0..=1.0).contains(&x.y) {
                    pts.push(IrradiancePoint {
                        position: x,
                        normal: DVec3::Z,
                        geometric: DVec3::Z,
                        area: 1.0 / (n as f64 * q_plane(x)),
                    });
                }
            }
        }
        gather_points(&sp, &pts, &s.profile, &mut out);
    }
    out
}

/// The leaves below a node, by walking `children` (the test's own traversal).
fn leaves(root: u32, children: impl Fn(u32) -> Option<[u32; 2]>) -> Vec<u32> {
    let mut out = Vec::new();
    let mut stack = vec![root];
    while let Some(n) = stack.pop() {
        match children(n) {
            Some([a, b]) => {
                stack.push(a);
                stack.push(b);
            }
            None => out.push(n),
        }
    }
    out
}

fn mean_se(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let v = x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (n - 1.0);
    (m, (v / n).sqrt())
}

fn eelc<'a>(s: &'a Scene, st: EelcSettings) -> EelcEstimator<'a> {
    EelcEstimator::new(&s.lights, &s.ft, &s.t, st).unwrap()
}

#[test]
fn the_gather_tree_holds_every_point_once_and_samples_by_strength() {
    let s = scene();
    let points = uniform_gather(&s, 200, 1);
    let n = points.len();
    assert!(n > 700, "{n} gather points");
    let tree = GatherTree::new(points.clone(), 9).unwrap();
    // Every point is one leaf; the root's strength is the sum.
    let mut seen: Vec<u32> = leaves(0, |k| tree.node(k).children)
        .into_iter()
        .map(|l| tree.leaf_point(l).unwrap())
        .collect();
    seen.sort_unstable();
    assert_eq!(seen, (0..n as u32).collect::<Vec<_>>());
    for c in 0..3 {
        let sum: f64 = points.iter().map(|p| p.strength[c]).sum();
        assert!((tree.node(0).rgb[c] - sum).abs() <= 1e-12 * sum);
    }
    // Each node's box holds its points, its cone their normals, its chroma bounds theirs.
    for (id, node) in tree.nodes().iter().enumerate() {
        for l in leaves(id as u32, |k| tree.node(k).children) {
            let p = &points[tree.leaf_point(l).unwrap() as usize];
            assert!(node.bbox.contains(p.position));
            assert!(node.cone.unwrap().contains(p.normal));
            let lum = lum(p.strength);
            assert!(
                p.strength
                    .iter()
                    .all(|v| *v <= node.chroma * lum * (1.0 + 1e-12))
            );
        }
    }
    // Sampling from the root picks point i with probability S_i / S (luminance): compare the
    // frequency of the 8 strongest points over 200 000 draws with a binomial 5σ margin.
    let total: f64 = points.iter().map(|p| p.scalar()).sum();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| points[b].scalar().total_cmp(&points[a].scalar()));
    let draws = 200_000;
    let mut count = vec![0u32; n];
    let mut u = stream(5);
    for _ in 0..draws {
        count[tree.sample(0, u.f()) as usize] += 1;
    }
    for &i in &order[..8] {
        let p = points[i].scalar() / total;
        let expect = p * draws as f64;
        let sd = (draws as f64 * p * (1.0 - p)).sqrt();
        assert!(
            (f64::from(count[i]) - expect).abs() < 5.0 * sd,
            "point {i}: {} draws, {expect} expected",
            count[i]
        );
    }
    // The root's representative over seeds: chosen in proportion to strength as well.
    let mut rep = vec![0u32; n];
    for seed in 0..20_000 {
        let t = GatherTree::new(points.clone(), seed).unwrap();
        rep[t.node(0).representative as usize] += 1;
    }
    let i = order[0];
    let p = points[i].scalar() / total;
    let sd = (20_000.0 * p * (1.0 - p)).sqrt();
    assert!(
        (f64::from(rep[i]) - 20_000.0 * p).abs() < 5.0 * sd,
        "{} vs {}",
        rep[i],
        20_000.0 * p
    );
}

#[test]
fn uniform_points_cover_the_mesh_with_its_area() {
    let s = scene();
    let mut u = stream(3);
    let mut next = || u.f();
    let mut pts = Vec::new();
    uniform_points(&s.surface, 30_000, &mut next, &mut pts);
    let total: f64 = pts.iter().map(|p| p.area).sum();
    assert!((total - MESH_AREA).abs() < 1e-9, "{total}");
    // The wall (x = 1, normal −x) holds a third of the area: a third of the points, ±5σ.
    let wall = pts.iter().filter(|p| p.normal.x < -0.5).count() as f64;
    let (p, n) = (0.5 / MESH_AREA, 30_000.0);
    assert!(
        (wall - p * n).abs() < 5.0 * (n * p * (1.0 - p)).sqrt(),
        "{wall}"
    );
    for q in &pts {
        let on_square = q.position.z == 0.0 && q.normal == DVec3::Z;
        let on_wall = (q.position.x - 1.0).abs() < 1e-12 && q.normal.x < -0.5;
        assert!(on_square || on_wall, "{q:?}");
    }
}

/// At a fixed stratum count the partition does not depend on the samples, so EELC's mean over
/// seeds equals the brute-force sum over its own point set: within 4 standard errors per
/// channel at 1, 40 and 300 strata (1 stratum: heavy-tailed, the near-surface VPL is rare and
/// heavy, hence 200 000 runs).
#[test]
fn eelc_is_unbiased_for_its_point_set() {
    let s = scene();
    let points = uniform_gather(&s, 96, 2);
    let vpls = vpls();
    let truth = point_set_sum(
        &points.iter().collect::<Vec<_>>(),
        &vpls.iter().collect::<Vec<_>>(),
    );
    let tree = GatherTree::new(points, 4).unwrap();
    for (j, runs) in [(1usize, 200_000u64), (40, 4000), (300, 4000)] {
        let mut st = EelcSettings::new(G_MAX);
        st.epsilon = 0.0;
        st.max_pairs = j;
        let e = eelc(&s, st);
        let v = visibility;
        let out: Vec<[f64; 3]> = (0..runs)
            .map(|seed| {
                let px = e.estimate(&tree, &v, pixel_seed(17, seed));
                assert_eq!((px.status, px.triplets), (Status::TripletCap, j));
                px.rgb
            })
            .collect();
        for c in 0..3 {
            let x: Vec<f64> = out.iter().map(|r| r[c]).collect();
            let (m, se) = mean_se(&x);
            let z = (m - truth[c]) / se;
            assert!(
                z.abs() < 4.0,
                "J={j} ch {c}: mean {m}, truth {}, se {se}",
                truth[c]
            );
            assert!(se < 0.05 * truth[c], "J={j}: se {se} vs {}", truth[c]);
        }
    }
}

/// With the test's importance-sampled points, EELC (fixed stratum count, so unbiased for its
/// point set) is unbiased for the integral: the mean over seeds, each with fresh points,
/// equals the brute-force quadrature of Eq. 1 within 4 standard errors. Also at convergence
/// (ε = 2 %, the stopping time depends on the samples), within 4 standard errors plus 0.5 %.
#[test]
fn eelc_with_importance_sampled_points_is_unbiased_for_the_integral() {
    let s = scene();
    let truth = brute_force(128);
    let mut fixed = EelcSettings::new(G_MAX);
    fixed.epsilon = 0.0;
    fixed.max_pairs = 60;
    let mut stop = EelcSettings::new(G_MAX);
    stop.epsilon = 0.02;
    for (st, slack) in [(fixed, 0.0), (stop, 5e-3)] {
        let e = eelc(&s, st);
        let runs = 3000u64;
        let out: Vec<[f64; 3]> = (0..runs)
            .map(|seed| {
                let tree = GatherTree::new(importance_gather(&s, 48, 1000 + seed), seed).unwrap();
                e.estimate(&tree, &visibility, pixel_seed(3, seed)).rgb
            })
            .collect();
        for c in 0..3 {
            let x: Vec<f64> = out.iter().map(|r| r[c]).collect();
            let (m, se) = mean_se(&x);
            assert!(
                (m - truth[c]).abs() < 4.0 * se + slack * truth[c],
                "ε = {} ch {c}: mean {m}, truth {}, se {se}",
                st.epsilon,
                truth[c]
            );
            assert!(se < 0.03 * truth[c], "se {se} vs {}", truth[c]);
        }
    }
}

/// MDLC's claims, checked pair by pair against a brute force over each pair's members: every
/// pair's estimate is within its bound of the pair's true value, every bound of a converged cut
/// is below ε times the estimate, and the total error is within the sum of the bounds.
#[test]
fn mdlc_is_within_its_bounds_of_the_point_set_sum() {
    let s = scene();
    let vpls = vpls();
    for (seed, eps) in [(1u64, 0.1), (2, 0.02), (3, 0.005)] {
        let points = uniform_gather(&s, 128, seed);
        let all: Vec<&GatherPoint> = points.iter().collect();
        let truth = point_set_sum(&all, &vpls.iter().collect::<Vec<_>>());
        let tree = GatherTree::new(points.clone(), seed).unwrap();
        let mut st = MdlcSettings::new(G_MAX);
        st.epsilon = eps;
        let mdlc = MdlcCut::new(&s.lights, &s.ft, st).unwrap();
        let (px, cut) = mdlc.estimate_cut(&tree, &visibility);
        assert_eq!(px.status, Status::Converged, "ε = {eps}");
        assert_eq!(px.triplets, cut.len());
        assert!(cut.len() > 10, "a non-trivial cut: {}", cut.len());
        let mut bound_sum = 0.0;
        for p in &cut {
            let g: Vec<&GatherPoint> = leaves(p.gather, |k| tree.node(k).children)
                .into_iter()
                .map(|l| &points[tree.leaf_point(l).unwrap() as usize])
                .collect();
            let l: Vec<&Vpl> = leaves(p.light, |k| s.lights.node(k).children)
                .into_iter()
                .map(|k| &s.lights.vpls()[s.lights.node(k).vpl as usize])
                .collect();
            let t = lum(point_set_sum(&g, &l));
            let err = (lum(p.rgb) - t).abs();
            assert!(
                err <= p.bound + 1e-12 * t,
                "pair {p:?}: estimate {} truth {t} bound {}",
                lum(p.rgb),
                p.bound
            );
            assert!(p.bound < eps * px.value);
            bound_sum += p.bound;
        }
        assert!((bound_sum - px.delta).abs() <= 1e-9 * px.delta.max(1e-300));
        let err = (px.value - lum(truth)).abs();
        assert!(
            err <= px.delta * (1.0 + 1e-9),
            "error {err}, bound {}",
            px.delta
        );
        eprintln!(
            "ε = {eps}: cut {}, relative error {:.5}, bound {:.4}",
            cut.len(),
            err / lum(truth),
            px.delta / lum(truth)
        );
        // The estimate is close to the truth (a loose check of the cut as a whole: the
        // representatives' errors mostly cancel).
        assert!(err < 0.25 * lum(truth) * (eps / 0.02).max(1.0), "{err}");
    }
}

/// A pixel whose every shadow ray is blocked terminates: EELC declares it 0 after `min_pairs`
/// strata, MDLC refines until every pair is exact (at most points × VPLs pairs) and reports 0.
/// Black lights give exact zeros at once, and no gather point is a clear error.
#[test]
fn shadowed_and_black_pixels_terminate() {
    let s = scene();
    let points = uniform_gather(&s, 16, 8);
    let n = points.len();
    let tree = GatherTree::new(points.clone(), 1).unwrap();
    let dark = |_: DVec3, _: DVec3| false;
    let st = EelcSettings::new(G_MAX);
    let px = eelc(&s, st).estimate(&tree, &dark, 3);
    assert_eq!((px.status, px.rgb), (Status::Zero, [0.0; 3]));
    // min_pairs sampled strata, and maybe a few exact zeros (pairs facing away).
    assert!(
        px.triplets >= st.min_pairs && px.triplets < 2 * st.min_pairs,
        "{px:?}"
    );
    let mdlc = MdlcCut::new(&s.lights, &s.ft, MdlcSettings::new(G_MAX)).unwrap();
    let px = mdlc.estimate(&tree, &dark);
    assert_eq!(
        (px.status, px.rgb, px.delta),
        (Status::Exact, [0.0; 3], 0.0)
    );
    assert!(px.triplets <= n * vpls().len());
    // The cap holds.
    let mut capped = MdlcSettings::new(G_MAX);
    capped.max_pairs = 50;
    let px = MdlcCut::new(&s.lights, &s.ft, capped)
        .unwrap()
        .estimate(&tree, &dark);
    assert_eq!((px.status, px.triplets), (Status::TripletCap, 50));
    // Black lights: the root's bound is 0.
    let black = LightTree::new(
        vpls()
            .into_iter()
            .map(|v| Vpl {
                intensity: [0.0; 3],
                ..v
            })
            .collect(),
    )
    .unwrap();
    let px = MdlcCut::new(&black, &s.ft, MdlcSettings::new(G_MAX))
        .unwrap()
        .estimate(&tree, &visibility);
    assert_eq!((px.status, px.triplets, px.samples), (Status::Exact, 1, 0));
    let px = EelcEstimator::new(&black, &s.ft, &s.t, EelcSettings::new(G_MAX))
        .unwrap()
        .estimate(&tree, &visibility, 1);
    assert_eq!((px.status, px.triplets, px.samples), (Status::Exact, 1, 0));
    // Zero-weight shading points give no gather points: the tree refuses to be empty.
    let zero = ShadingPoint {
        weight: 0.0,
        ..shading_points()[0]
    };
    let mut none = Vec::new();
    let pts = [IrradiancePoint {
        position: DVec3::new(0.5, 0.5, 0.0),
        normal: DVec3::Z,
        geometric: DVec3::Z,
        area: 1.0,
    }];
    gather_points(&zero, &pts, &s.profile, &mut none);
    assert!(none.is_empty());
    let e = GatherTree::new(none, 1).unwrap_err().to_string();
    assert!(e.contains("no gather points"), "{e}");
}

#[test]
fn both_are_bit_identical_across_runs_and_threads() {
    let s = scene();
    let trees: Vec<GatherTree> = (0..8)
        .map(|k| GatherTree::new(uniform_gather(&s, 32, 40 + k), k).unwrap())
        .collect();
    let e = eelc(&s, EelcSettings::new(G_MAX));
    let m = MdlcCut::new(&s.lights, &s.ft, MdlcSettings::new(G_MAX)).unwrap();
    let run = |ts: &[GatherTree], base: u64| -> Vec<(PixelEstimate, PixelEstimate)> {
        ts.iter()
            .enumerate()
            .map(|(k, t)| {
                (
                    e.estimate(t, &visibility, pixel_seed(5, base + k as u64)),
                    m.estimate(t, &visibility),
                )
            })
            .collect()
    };
    let serial = run(&trees, 0);
    let (a, b) = trees.split_at(4);
    let (ra, rb) = std::thread::scope(|sc| {
        let ha = sc.spawn(|| run(a, 0));
        let hb = sc.spawn(|| run(b, 4));
        (ha.join().unwrap(), hb.join().unwrap())
    });
    let threaded: Vec<_> = ra.into_iter().chain(rb).collect();
    let bits = |v: &[(PixelEstimate, PixelEstimate)]| -> Vec<u64> {
        v.iter()
            .flat_map(|(x, y)| x.rgb.into_iter().chain(y.rgb).chain([x.delta, y.delta]))
            .map(f64::to_bits)
            .collect()
    };
    assert_eq!(bits(&serial), bits(&threaded));
    assert_eq!(bits(&serial), bits(&run(&trees, 0)));
}

#[test]
fn bad_inputs_are_errors() {
    let s = scene();
    let p = GatherPoint {
        position: DVec3::ZERO,
        normal: DVec3::Z,
        geometric: DVec3::Z,
        strength: [1.0; 3],
    };
    for bad in [
        GatherPoint {
            position: DVec3::splat(f64::NAN),
            ..p
        },
        GatherPoint {
            strength: [1.0, -1.0, 1.0],
            ..p
        },
        GatherPoint {
            strength: [f64::INFINITY; 3],
            ..p
        },
        GatherPoint {
            normal: DVec3::new(0.0, 0.0, 2.0),
            ..p
        },
        GatherPoint {
            geometric: DVec3::new(0.0, 3.0, 0.0),
            ..p
        },
    ] {
        let e = GatherTree::new(vec![p, bad], 1).unwrap_err();
        assert!(matches!(e, Error::InvalidInput(_)), "{e}");
        assert!(e.to_string().contains("gather point 1"), "{e}");
    }
    for f in [
        |st: &mut MdlcSettings| st.epsilon = -1.0,
        |st: &mut MdlcSettings| st.g_max = 0.0,
        |st: &mut MdlcSettings| st.max_pairs = 0,
    ] {
        let mut st = MdlcSettings::new(G_MAX);
        f(&mut st);
        assert!(MdlcCut::new(&s.lights, &s.ft, st).is_err(), "{st:?}");
    }
    for f in [
        |st: &mut EelcSettings| st.epsilon = f64::NAN,
        |st: &mut EelcSettings| st.g_max = f64::INFINITY,
        |st: &mut EelcSettings| st.max_pairs = 0,
        |st: &mut EelcSettings| st.min_pairs = 0,
    ] {
        let mut st = EelcSettings::new(G_MAX);
        f(&mut st);
        assert!(
            EelcEstimator::new(&s.lights, &s.ft, &s.t, st).is_err(),
            "{st:?}"
        );
    }
}
