//! Guided optimisation (Jimenez et al. 2015, Appendix A, Eq. 7–8).

use crate::common;

use sss_separable::guided::{self, GuidedOptions, GuidedResult};
use sss_separable::{Kernel2d, TapPlacement};

fn solve(k: &Kernel2d, kk: f64) -> GuidedResult {
    guided::optimize(
        k,
        &GuidedOptions {
            k: kk,
            ..Default::default()
        },
    )
    .unwrap()
}

/// ‖w·(K − a aᵀ)‖₂ / ‖w·K‖₂ per channel, w(x, y) = r^p.
fn distance(k: &Kernel2d, g: &GuidedResult, p: i32) -> [f64; 3] {
    let n = k.cells;
    std::array::from_fn(|c| {
        let (mut e, mut b) = (0.0, 0.0);
        for iy in 0..n {
            for ix in 0..n {
                let (x, y) = (k.offset_mm(ix), k.offset_mm(iy));
                let w = (x * x + y * y).sqrt().powi(p);
                let t = k.at(c, ix, iy);
                let d = t - g.profile.mass[ix][c] * g.profile.mass[iy][c];
                e += (w * d).powi(2);
                b += (w * t).powi(2);
            }
        }
        (e / b).sqrt()
    })
}

#[test]
fn guided_optimisation_meets_its_energy_constraint() {
    for preset in ["skin1", "marble", "ketchup"] {
        let m = common::model(preset);
        let k = common::kernel2d(m.as_ref(), 63);
        for kk in [0.0, 0.5, 1.0, 2.0, 3.0, 4.0] {
            let g = solve(&k, kk);
            assert!(g.converged(), "{preset} k={kk}: {:?}", g.channels);
            for c in 0..3 {
                let norm1: f64 = g.profile.mass.iter().map(|v| v[c].abs()).sum();
                let violation = ((norm1 * norm1 - k.total[c]) / k.total[c]).abs();
                assert!(violation < 1e-9, "{preset} k={kk} ch {c}: {violation:e}");
                let ch = g.channels[c];
                assert!(ch.constraint_violation < 1e-9);
                assert!(ch.objective.is_finite() && ch.relative_objective < 1.0);
                assert!(
                    g.profile
                        .mass
                        .iter()
                        .all(|v| v[c] >= 0.0 && v[c].is_finite())
                );
            }
            let kernel = g.kernel(TapPlacement::Importance(7)).unwrap();
            let t = kernel.total_weight();
            assert!((0..3).all(|c| ((t[c] - k.total[c]) / k.total[c]).abs() < 1e-12));
        }
    }
}

#[test]
fn k_2_approximates_the_kernel_best_in_the_r_weighted_norm_and_k_0_in_plain_l2() {
    // Appendix A: "k ≈ 2 yields the approximation of the actual diffusion kernel, k = 0 a
    // sharper variant, k = 4 a smoother one". In the L2 norm weighted by r (squared: r², the
    // guide of k = 2 without its centre-cross suppression), k = 2 is closer to the kernel than
    // k = 0 and k = 4 …
    for preset in ["skin1", "marble", "ketchup"] {
        let m = common::model(preset);
        let k = common::kernel2d(m.as_ref(), 127);
        let [d0, d2, d4] = [0.0, 2.0, 4.0].map(|kk| distance(&k, &solve(&k, kk), 1));
        for c in 0..3 {
            assert!(
                d2[c] < d0[c] && d2[c] < d4[c],
                "{preset} ch {c}: {d0:?} {d2:?} {d4:?}"
            );
        }
        // … while in the plain (unweighted) L2 norm the order is k = 0 < 2 < 4: k = 0's Γ is
        // flat outside the centre cross, so its optimum is (almost) the plain-L2 one.
        let [p0, p2, p4] = [0.0, 2.0, 4.0].map(|kk| distance(&k, &solve(&k, kk), 0));
        for c in 0..3 {
            assert!(
                p0[c] < p2[c] && p2[c] < p4[c],
                "{preset} ch {c}: {p0:?} {p2:?} {p4:?}"
            );
        }
    }
}

#[test]
fn a_guided_run_that_runs_out_of_iterations_says_so_and_still_meets_the_constraint() {
    let m = common::model("skin1");
    let k = common::kernel2d(m.as_ref(), 63);
    let g = guided::optimize(
        &k,
        &GuidedOptions {
            max_iterations: 2,
            tolerance: 1e-14,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(!g.converged());
    for ch in g.channels {
        assert!(!ch.converged);
        assert_eq!(ch.iterations, 2);
        assert!(ch.last_step.is_finite() && ch.last_step >= 1e-14);
        assert!(ch.objective.is_finite() && ch.constraint_violation < 1e-9);
    }
    for bad in [
        GuidedOptions {
            k: -0.1,
            ..Default::default()
        },
        GuidedOptions {
            k: 4.5,
            ..Default::default()
        },
        GuidedOptions {
            b: 0.0,
            ..Default::default()
        },
        GuidedOptions {
            k: f64::NAN,
            ..Default::default()
        },
    ] {
        assert!(guided::optimize(&k, &bad).is_err());
    }
}
