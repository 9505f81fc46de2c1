//! The local-expansion dual tree (`dual-tree-fmm`) against `exact`, its thread-count
//! determinism, and the paper's `dual-tree` pinned bit for bit to the values it gave before
//! the local-expansion form was added.

use crate::common::{irradiance, run, scene};
use glam::DVec3;
use sss_bssrdf::Rgb;
use sss_bssrdf::{Medium, ModelKind, make_model};
use sss_render::frame::Frame;
use sss_render::integrators::Shaded;
use sss_render::integrators::dual_tree::DualTree;
use sss_render::integrators::dual_tree_fmm::{DualTreeFmm, LocalExpansion};
use sss_render::integrators::exact::Exact;
use sss_render::irradiance::IrradianceSettings;

/// FNV-1a over the bits of every value, in G-buffer order.
fn hash(values: &[Rgb]) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for v in values.iter().flatten() {
        for b in v.to_bits().to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

#[test]
fn the_papers_dual_tree_is_unchanged_bit_for_bit() {
    // Hashes of `dual-tree`'s values recorded from the code before the local-expansion form
    // existed: any change to the paper's Algorithm 2 (acceptance, SHADE, task split, order of
    // the sums) changes them.
    let cases: [(&str, u32, u32, f64, f64, u64); 3] = [
        ("sphere", 48, 36, 0.05, 0.75, 0x6392_b71b_4387_6ca9),
        ("slab", 40, 30, 0.2, 1.5, 0xe111_cb7c_00ff_527d),
        ("sphere", 160, 120, 0.01, 0.75, 0x7018_b6cc_7389_125a),
    ];
    let mut got = Vec::new();
    for (name, w, h, eps, rho, _) in cases {
        let s = scene(name, w, h);
        let frame = Frame::prepare(&s, 1);
        let out = run(
            &frame,
            &DualTree {
                irradiance: irradiance(1.5),
                eps,
                rho,
            },
        );
        got.push(hash(&out.values));
        println!(
            "{name} {w}x{h} eps {eps} rho {rho}: {:#018x}",
            hash(&out.values)
        );
    }
    for ((name, w, h, eps, rho, want), got) in cases.iter().zip(got) {
        assert_eq!(got, *want, "{name} {w}x{h} ε = {eps} ρ = {rho}");
    }
}

fn fmm(irr: IrradianceSettings, eps: f64, order: u8) -> DualTreeFmm {
    DualTreeFmm {
        irradiance: irr,
        eps,
        order,
        ..DualTreeFmm::default()
    }
}

/// Largest difference per G-buffer sample and channel relative to the reference's largest
/// value, and the relative RMSE over samples.
fn errors(a: &[Rgb], reference: &[Rgb]) -> (f64, f64) {
    let scale = reference.iter().flatten().fold(0.0f64, |m, &x| m.max(x));
    assert!(scale > 0.0);
    let (mut worst, mut se, mut sr) = (0.0f64, 0.0, 0.0);
    for (x, r) in a.iter().zip(reference) {
        for c in 0..3 {
            assert!(x[c].is_finite() && x[c] >= 0.0, "value {}", x[c]);
            worst = worst.max((x[c] - r[c]).abs() / scale);
            se += (x[c] - r[c]).powi(2);
            sr += r[c].powi(2);
        }
    }
    (worst, (se / sr).sqrt())
}

#[test]
fn local_expansions_equal_exact_when_nothing_is_accepted() {
    // ε = 0 accepts no pair: every pair reaches the leaves, summed sample by sample as
    // `exact` sums, so only the summation order differs.
    for (name, w, h) in [("sphere", 48, 36), ("slab", 40, 30)] {
        let s = scene(name, w, h);
        let frame = Frame::prepare(&s, 1);
        let irr = irradiance(1.5);
        let exact = run(&frame, &Exact { irradiance: irr });
        for order in [1, 2] {
            let out = run(&frame, &fmm(irr, 0.0, order));
            let (worst, _) = errors(&out.values, &exact.values);
            assert!(worst < 1e-12, "{name}, order {order}: differs by {worst:e}");
        }
    }
}

#[test]
fn local_expansion_error_is_small_and_falls_with_eps() {
    let s = scene("sphere", 96, 72);
    let frame = Frame::prepare(&s, 1);
    let irr = irradiance(1.5);
    let exact = run(&frame, &Exact { irradiance: irr });
    let mut last = f64::INFINITY;
    // Measured relative RMSE against exact on this frame (order 2 / order 1):
    // ε = 0.2: 2.4e-3 / 9.4e-3; 0.05: 1.8e-4 / 8.6e-4; 0.01: 9.5e-7 / 3.9e-6. Pinned at about
    // twice order 2's (a lost or doubled expansion is far above these).
    for (eps, bound) in [(0.2, 5e-3), (0.05, 4e-4), (0.01, 2e-6)] {
        let two = run(&frame, &fmm(irr, eps, 2));
        let one = run(&frame, &fmm(irr, eps, 1));
        let (_, e2) = errors(&two.values, &exact.values);
        let (_, e1) = errors(&one.values, &exact.values);
        println!("eps {eps}: order 2 {e2:.4e}, order 1 {e1:.4e}");
        assert!(e2 < bound, "order 2 at ε = {eps}: {e2}");
        assert!(e2 < last, "order 2 error grew as ε shrank");
        assert!(
            e2 <= e1,
            "order 2 ({e2}) worse than order 1 ({e1}) at ε = {eps}"
        );
        last = e2;
    }
}

#[test]
fn local_expansions_do_not_depend_on_the_thread_count() {
    // Large enough for several tasks of the pixel tree.
    let s = scene("sphere", 200, 150);
    let frame = Frame::prepare(&s, 1);
    let m = fmm(irradiance(1.5), 0.05, 2);
    let on = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| run(&frame, &m))
    };
    let (a, b) = (on(1), on(2));
    assert_eq!(hash(&a.values), hash(&b.values));
    assert_eq!(a.stats, b.stats);
    let tasks = frame
        .gbuffer
        .samples
        .iter()
        .filter(|g| frame.shading_of(g.object).is_some())
        .count();
    assert!(
        tasks > 2 * sss_render::integrators::dual_tree::TASK_ITEMS,
        "{tasks} points"
    );
}

/// For a tabulated model, the channel's knot interval around `r` (mm): its midpoint and width.
fn knot_interval(kind: ModelKind, m: &Medium, ch: usize, r: f64) -> Option<(f64, f64)> {
    let (knots, st) = match kind {
        ModelKind::PhotonBeamDiffusion => (
            sss_bssrdf::PhotonBeamDiffusion::new(m.clone())
                .table()
                .radius_samples()
                .to_vec(),
            m.sigma_t(ch),
        ),
        ModelKind::McTable => (
            sss_bssrdf::McTableModel::new(m.clone())
                .table()
                .radius_samples()
                .to_vec(),
            m.sigma_t_reduced(ch),
        ),
        _ => return None,
    };
    let x = r * st;
    let i = knots.partition_point(|&k| k <= x).clamp(1, knots.len() - 1) - 1;
    Some((
        0.5 * (knots[i] + knots[i + 1]) / st,
        (knots[i + 1] - knots[i]) / st,
    ))
}

#[test]
fn one_expanded_source_converges_with_the_order_it_claims() {
    // A source at the origin expanded about a point at distance r₀; the expansion at
    // points h away (a direction oblique to the radial one) against R_d there. The error
    // of order p is O(h^{p+1}): the fitted log-log slope over four h must be p + 1.
    let m = Medium::preset("skin1").unwrap();
    let dir = DVec3::new(0.6, 0.7, -0.4).normalize();
    for kind in [
        ModelKind::StandardDipole,
        ModelKind::BetterDipole,
        ModelKind::Burley,
        ModelKind::PhotonBeamDiffusion,
        ModelKind::McTable,
    ] {
        let model = make_model(kind, &m);
        for ch in 0..3 {
            let l = m.reduced_mean_free_path(ch);
            for f in [0.8, 2.5] {
                // The spline is C¹ (R″ jumps at knots): stay inside one knot interval.
                let (r0, hmax) = match knot_interval(kind, &m, ch, f * l) {
                    Some((mid, width)) => (mid, 0.15 * width),
                    None => (f * l, 0.04 * l),
                };
                let centre = DVec3::new(r0, 0.0, 0.0);
                let rd = std::array::from_fn(|c| {
                    let (v, d1, d2) = model.rd_derivatives(c, r0);
                    [v, d1, d2]
                });
                for order in [1u8, 2] {
                    let mut e = LocalExpansion::default();
                    e.add_radial(centre, &rd, [1.0; 3], order);
                    let pts: Vec<(f64, f64)> = (0..4)
                        .map(|k| {
                            let h = hmax * 0.5f64.powi(k);
                            let x = centre + dir * h;
                            let want = model.rd(ch, x.length());
                            let got = e.eval(x - centre, order)[ch];
                            (h.ln(), ((got - want).abs() / want).max(1e-300).ln())
                        })
                        .collect();
                    let n = pts.len() as f64;
                    let (mx, my) = (
                        pts.iter().map(|p| p.0).sum::<f64>() / n,
                        pts.iter().map(|p| p.1).sum::<f64>() / n,
                    );
                    let slope = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>()
                        / pts.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
                    let want = f64::from(order) + 1.0;
                    assert!(
                        (slope - want).abs() < 0.2,
                        "{kind} ch{ch} r₀ = {r0:e} mm, order {order}: slope {slope:.3}, \
                         want {want}"
                    );
                }
            }
        }
    }
}

fn stat(out: &Shaded, name: &str) -> f64 {
    out.stats
        .iter()
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("no stat {name}"))
        .value
}

#[test]
fn samples_expanded_one_by_one_keep_the_near_field_accurate() {
    // Pixels finer than the irradiance samples (0.011 units a pixel, samples 1 mean free path
    // = 0.034 units apart in blue): pixel nodes pass the pixel test against single samples
    // too near to be clustered, and take them as expansions one by one (particle to local).
    // Each sample must pass the pixel test itself, at its own distance (a leaf's box can be
    // disjoint from the node's while one of its samples lies within the node's radius) and in
    // the profile's own decay length. Measured against exact on this frame: relative RMSE
    // 3.90e-4, worst 1.19e-3 of the largest value; with the samples expanded under their
    // leaf's test alone, 4.84e-4 and 1.68e-3. Pinned between the two (the values are
    // deterministic: same frame, same samples, same order of the sums).
    let s = scene("sphere", 320, 240);
    let frame = Frame::prepare(&s, 1);
    let irr = irradiance(1.0);
    let exact = run(&frame, &Exact { irradiance: irr });
    let out = run(&frame, &fmm(irr, 0.05, 2));
    let (worst, rel) = errors(&out.values, &exact.values);
    let expanded = stat(&out, "sample_expansions");
    println!("relative RMSE {rel:.3e}, worst {worst:.3e}, sample expansions {expanded}");
    assert!(
        expanded > 1e5,
        "only {expanded} samples expanded one by one"
    );
    assert!(rel < 4.4e-4, "relative RMSE {rel:e}");
    assert!(worst < 1.45e-3, "worst error {worst:e}");
}
