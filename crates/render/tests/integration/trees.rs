//! The single-tree (Jensen & Buhler 2002) and dual-tree (Milaenen et al. 2019) integrators
//! against `exact` over the same irradiance samples: equal to rounding when nothing is
//! clustered (ε → 0, and ρ → 0 for the dual tree), a bounded error that shrinks with ε, pixel
//! clusters that do not make the dual tree worse than shading every pixel, and the directional
//! dipole refused with an error naming the material.

use crate::common::{irradiance, run, scene};
use sss_bssrdf::Rgb;
use sss_render::frame::Frame;
use sss_render::integrators::dual_tree::DualTree;
use sss_render::integrators::exact::Exact;
use sss_render::integrators::single_tree::SingleTree;
use sss_render::integrators::{Integrator, Shaded};
use sss_render::progress::NoProgress;

/// Largest relative difference per G-buffer sample and channel (relative to the largest value
/// of the reference, so dark samples do not dominate), and the relative RMSE over samples.
fn errors(a: &[Rgb], reference: &[Rgb]) -> (f64, f64) {
    let scale = reference.iter().flatten().fold(0.0f64, |m, &x| m.max(x));
    assert!(scale > 0.0);
    let (mut worst, mut se, mut sr, mut n) = (0.0f64, 0.0, 0.0, 0.0);
    for (x, r) in a.iter().zip(reference) {
        for c in 0..3 {
            worst = worst.max((x[c] - r[c]).abs() / scale);
            se += (x[c] - r[c]).powi(2);
            sr += r[c].powi(2);
            n += 1.0;
        }
    }
    assert!(n > 0.0);
    (worst, (se / sr).sqrt())
}

#[test]
fn trees_equal_exact_when_nothing_is_clustered() {
    // Sphere (better dipole) and slab (standard dipole): every pair reaches the leaves and the
    // leaves sum sample by sample, so only the summation order differs.
    for (name, w, h) in [("sphere", 48, 36), ("slab", 40, 30)] {
        let s = scene(name, w, h);
        let frame = Frame::prepare(&s, 1);
        let irr = irradiance(1.5);
        let exact = run(&frame, &Exact { irradiance: irr });
        let single = run(
            &frame,
            &SingleTree {
                irradiance: irr,
                eps: 0.0,
            },
        );
        let dual = run(
            &frame,
            &DualTree {
                irradiance: irr,
                eps: 0.0,
                rho: 0.0,
            },
        );
        let (w1, _) = errors(&single.values, &exact.values);
        let (w2, _) = errors(&dual.values, &exact.values);
        assert!(w1 < 1e-12, "{name}: single tree differs by {w1:e}");
        assert!(w2 < 1e-12, "{name}: dual tree differs by {w2:e}");
    }
}

#[test]
fn tree_error_is_small_and_shrinks_with_eps() {
    let s = scene("sphere", 48, 36);
    let frame = Frame::prepare(&s, 1);
    let irr = irradiance(1.5);
    let exact = run(&frame, &Exact { irradiance: irr });
    let mut last_single = f64::INFINITY;
    // Measured relative RMSE against exact on this frame (single / dual at ρ = 0.75):
    // ε = 0.2: 0.33 % / 0.85 %; 0.05: 0.021 % / 0.027 %; 0.01: 1.2e-6 / 1.3e-6. Pinned at
    // about twice the larger (a bug that loses or double-counts a node is far above these).
    for (eps, bound) in [(0.2, 0.02), (0.05, 6e-4), (0.01, 3e-6)] {
        let single = run(
            &frame,
            &SingleTree {
                irradiance: irr,
                eps,
            },
        );
        let dual = run(
            &frame,
            &DualTree {
                irradiance: irr,
                eps,
                rho: 0.75,
            },
        );
        let (_, e1) = errors(&single.values, &exact.values);
        let (_, e2) = errors(&dual.values, &exact.values);
        println!("eps {eps}: single {e1:.4e}, dual {e2:.4e}");
        assert!(e1 < bound, "single tree at ε = {eps}: {e1}");
        assert!(e2 < bound, "dual tree at ε = {eps}: {e2}");
        assert!(e1 < last_single, "single tree error grew as ε shrank");
        last_single = e1;
    }
}

#[test]
fn shading_every_pixel_is_no_worse_than_pixel_clusters() {
    // A frame large enough that s_p < 1, so ρ = 0.75 clusters pixels (P = ρ / max s_p > 1).
    let s = scene("sphere", 256, 192);
    let frame = Frame::prepare(&s, 1);
    let irr = irradiance(5.0);
    let exact = run(&frame, &Exact { irradiance: irr });
    let at = |rho| {
        run(
            &frame,
            &DualTree {
                irradiance: irr,
                eps: 0.05,
                rho,
            },
        )
    };
    let clustered = at(0.75);
    let every = at(0.0);
    let coarse = at(8.0);
    let (_, e_clustered) = errors(&clustered.values, &exact.values);
    let (_, e_every) = errors(&every.values, &exact.values);
    let (_, e_coarse) = errors(&coarse.values, &exact.values);
    // Measured (samples 5 mean free paths apart; at 3, 42 s instead of 24 s and the same
    // ordering): ρ = 0: 0.00015 %, 0.75: 0.72 %, 8: 2.9 %.
    println!("rho 0: {e_every:.4e}, 0.75: {e_clustered:.4e}, 8: {e_coarse:.4e}");
    assert!(e_every < 1e-4 && e_clustered < 0.015 && e_coarse < 0.05);
    assert!(e_every <= e_clustered * (1.0 + 1e-9));
    assert!(e_clustered <= e_coarse);
    // Clustering pixels must do less work than shading each one (measured: 0.917 of the
    // evaluations at this size, where s_p is near 1 and few clusters form).
    let evals = |s: &Shaded| {
        s.stats
            .iter()
            .filter(|x| x.name.ends_with("evaluations"))
            .map(|x| x.value)
            .sum::<f64>()
    };
    println!("evaluations: {:.4}", evals(&clustered) / evals(&every));
    assert!(
        evals(&clustered) < 0.95 * evals(&every),
        "{} vs {}",
        evals(&clustered),
        evals(&every)
    );
    // ρ = 0 shades every sample by itself: the same work as the single tree at that ε would
    // do is not required, but the result must be close to it (same ε, different Δω origin).
    let single = run(
        &frame,
        &SingleTree {
            irradiance: irr,
            eps: 0.05,
        },
    );
    let (_, e_single) = errors(&single.values, &exact.values);
    assert!(e_every < 2.0 * e_single + 1e-3, "{e_every} vs {e_single}");
}

#[test]
fn trees_refuse_the_directional_dipole_naming_the_material() {
    let s = scene("toad", 32, 24);
    let frame = Frame::prepare(&s, 1);
    let methods: [Box<dyn Integrator>; 2] = [
        Box::new(SingleTree::default()),
        Box::new(DualTree::default()),
    ];
    for m in methods {
        let e = m.integrate(&frame, &NoProgress).unwrap_err();
        assert!(matches!(e, sss_render::Error::Unsupported(_)), "{e}");
        let msg = e.to_string();
        assert!(
            msg.contains("directional dipole") && msg.contains(m.name()),
            "{msg}"
        );
    }
}

#[test]
fn tree_structures_count_against_the_memory_budget() {
    use sss_render::{RenderSettings, render};
    let s = scene("sphere", 1600, 1200);
    let exact_need = {
        let est = sss_render::budget::irradiance_estimate(&s, &irradiance(0.5));
        est.iter().map(|e| e.2).sum::<u64>()
            + sss_render::budget::frame_bytes(1600, 1200, s.camera.pixel_samples)
    };
    // A budget that fits the frame and the samples but not the pixel tree over 1.9 M points.
    let settings = RenderSettings {
        max_memory: exact_need + (8 << 20),
        ..RenderSettings::default()
    };
    let err = render(&s, &DualTree::default(), &settings, &NoProgress).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("structures") && msg.contains("--max-memory"),
        "{msg}"
    );
}

#[test]
fn curvature_at_the_hits_matches_the_analytic_sphere() {
    use sss_render::integrators::dual_tree::curvature_at_hits;
    // The built-in sphere has radius 1: k = 1 everywhere (the procedural shape's analytic
    // curvature), estimated per vertex and interpolated at each hit.
    // The procedural sphere carries its curvature in closed form, and that is what the hits
    // get; without it (as for a mesh from a file) the estimator must agree within 2 %.
    let s = scene("sphere", 80, 60);
    let frame = Frame::prepare(&s, 1);
    let o = frame.visible[0];
    assert_eq!(
        s.objects[o as usize].curvature,
        Some(sss_render::scene::Curvature::Uniform(1.0))
    );
    let (index, k) = curvature_at_hits(&frame, o).unwrap();
    assert!(index.len() > 1000);
    assert!(k.iter().all(|&x| x == 1.0));
    let mut estimated = s.clone();
    estimated.objects[o as usize].curvature = None;
    let frame = Frame::prepare(&estimated, 1);
    let (index_e, k) = curvature_at_hits(&frame, o).unwrap();
    assert_eq!(index_e, index);
    let worst = k.iter().fold(0.0f64, |m, &x| m.max((x - 1.0).abs()));
    assert!(worst < 0.02, "sphere: |k − 1/R| up to {worst}");
    assert!(worst > 0.0, "the estimate is not the closed form");
    // The slab's top face, estimated: flat, k = 0 away from its edges (the box's edge
    // vertices see the 90° turn, so only hits well inside a face are checked).
    let mut s = scene("slab", 80, 60);
    for obj in &mut s.objects {
        obj.curvature = None;
    }
    let frame = Frame::prepare(&s, 1);
    for &o in &frame.visible {
        let (index, k) = curvature_at_hits(&frame, o).unwrap();
        let mut interior = 0;
        for (&i, &kk) in index.iter().zip(&k) {
            let g = &frame.gbuffer.samples[i as usize];
            assert!(kk.is_finite() && kk >= 0.0);
            // The slab is 4 × 0.4 × 3 centred at (0, 0.2, 0): its top face is y = 0.4.
            if (g.p.y - 0.4).abs() < 1e-9 && g.p.x.abs() < 1.5 && g.p.z.abs() < 1.0 {
                interior += 1;
                assert!(kk < 1e-9, "flat face curvature {kk} at {:?}", g.p);
            }
        }
        if o == frame.visible[0] {
            assert!(interior > 50, "{interior} interior hits");
        }
    }
}
