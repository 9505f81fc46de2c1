//! Property tests: energy conservation and finiteness over random inputs.
//!
//! Reproducible: the inputs come from a fixed seed, [`SEED`], so every run tries the
//! same cases and a failure replays as is; a failing case is also persisted by proptest under
//! `proptest-regressions/` next to this file (its default), to be committed with the fix. To
//! explore other inputs, change the seed here (the `PROPTEST_RNG_SEED` environment variable
//! does not override an explicit configuration).

use proptest::prelude::*;
use sss_bssrdf::{Medium, ModelKind, make_model};
use sss_separable::{Kernel2d, Kernel2dSpec, Profile1d, TapPlacement, preintegrated, svd, taps};

/// The seed of every property test in this file.
const SEED: u64 = 0x5eed_0014;

/// 64 cases from [`SEED`].
fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 64,
        rng_seed: proptest::test_runner::RngSeed::Fixed(SEED),
        ..ProptestConfig::default()
    }
}

/// The configuration draws the same inputs on every run (two fresh runners agree), and not a
/// constant: the draws differ from each other.
#[test]
fn inputs_are_the_same_every_run() {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::TestRunner;
    let draw = || {
        let mut runner = TestRunner::new(config());
        (0..8)
            .map(|_| (0.0f64..1.0).new_tree(&mut runner).unwrap().current())
            .collect::<Vec<f64>>()
    };
    let (a, b) = (draw(), draw());
    assert_eq!(a, b);
    assert!(a.windows(2).any(|w| w[0] != w[1]), "{a:?}");
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn tap_placements_conserve_every_channel(
        masses in prop::collection::vec((0.0f64..1.0, 0.0f64..1.0, 0.0f64..1.0), 1..40),
        n in 1usize..20,
        cell in 0.01f64..2.0,
    ) {
        // An odd, symmetric-or-not profile with a positive dominant channel.
        let mut m: Vec<[f64; 3]> = masses.iter().map(|&(a, b, c)| [a, b, c]).collect();
        if m.len().is_multiple_of(2) {
            m.push([0.5; 3]);
        }
        let p = Profile1d { cell_mm: cell, mass: m };
        let total = p.total();
        prop_assume!(total.iter().all(|t| *t > 1e-6));
        for placement in [TapPlacement::Uniform(n), TapPlacement::Importance(n)] {
            let k = taps::place(&p, placement).unwrap();
            prop_assert_eq!(k.taps.len(), n);
            prop_assert!(k.is_finite());
            prop_assert!(k.taps.windows(2).all(|w| w[0].offset_mm <= w[1].offset_mm));
            prop_assert!(k.radius_mm() <= p.half_width_mm() + 1e-12);
            let s = k.sum();
            for c in 0..3 {
                prop_assert!((s[c] - total[c]).abs() <= 1e-12 * total[c].max(1.0), "{:?} {} {}", placement, s[c], total[c]);
            }
        }
    }

    #[test]
    fn kernels_of_random_media_conserve_energy(
        sa in (0.001f64..2.0, 0.001f64..2.0, 0.001f64..2.0),
        ss in (0.05f64..20.0, 0.05f64..20.0, 0.05f64..20.0),
        g in -0.5f64..0.9,
        eta in 1.0f64..1.6,
    ) {
        let medium = Medium::new([sa.0, sa.1, sa.2], [ss.0, ss.1, ss.2], g, eta).unwrap();
        let model = make_model(ModelKind::BetterDipole, &medium);
        let k = Kernel2d::from_model(model.as_ref(), &Kernel2dSpec { cells: 21, ..Default::default() }).unwrap();
        let kernels = [
            preintegrated::kernel(&k, TapPlacement::Importance(7)).unwrap(),
            svd::decompose(&k).unwrap().separable(2, TapPlacement::Grid).unwrap(),
        ];
        for kernel in &kernels {
            prop_assert!(kernel.is_finite());
            for (c, t) in kernel.total_weight().into_iter().enumerate() {
                let want = model.total_diffuse_reflectance(c);
                prop_assert!((t - want).abs() <= 1e-11 * want, "{} vs {}", t, want);
            }
        }
    }
}
