//! The stiff and extreme grid: every model and channel stays finite and non-negative.

use proptest::prelude::*;
use proptest::test_runner::{FileFailurePersistence, RngSeed};
use sss_bssrdf::*;

const ALBEDOS: [f64; 10] = [
    0.0,
    1e-9,
    0.1,
    0.5,
    0.9,
    0.99,
    0.9987,
    0.99999,
    1.0 - 1e-9,
    1.0,
];
const SIGMA_T: [f64; 5] = [1e-6, 1e-3, 1.0, 1e3, 1e6];
const ETAS: [f64; 6] = [0.75, 1.0, 1.0001, 1.33, 1.5, 2.5];
const GS: [f64; 3] = [-0.9, 0.0, 0.9];
const COSINES: [f64; 4] = [0.0, 1e-9, 0.5, 1.0];

fn check_model(model: &dyn Bssrdf, label: &str) {
    let m = model.medium();
    for ch in 0..3 {
        let mfp = m.mean_free_path(ch);
        let total = model.total_diffuse_reflectance(ch);
        assert!(
            total.is_finite() && (0.0..=1.0).contains(&total),
            "{label} ch{ch}: total {total}"
        );
        let mut radii = vec![0.0, 1e-12];
        radii.extend([1e-6, 1e-3, 0.1, 1.0, 10.0, 1e2, 1e4].map(|k| k * mfp));
        for &r in &radii {
            let v = model.rd(ch, r);
            assert!(v.is_finite() && v >= 0.0, "{label} ch{ch}: rd({r}) = {v}");
            let p = model.pdf_sr(ch, r);
            assert!(p.is_finite() && p >= 0.0, "{label} ch{ch}: pdf({r}) = {p}");
        }
        for u in [1e-6, 0.3, 0.7, 0.999] {
            let r = model.sample_sr(ch, u);
            let p = model.pdf_sr(ch, r);
            assert!(
                r.is_finite() && r >= 0.0,
                "{label} ch{ch}: sample({u}) = {r}"
            );
            assert!(
                p.is_finite() && p > 0.0,
                "{label} ch{ch}: pdf(sample({u}) = {r}) = {p}"
            );
        }
        let e = model.radius_for_energy(ch, 0.99);
        assert!(
            e.is_finite() && e >= 0.0,
            "{label} ch{ch}: energy radius {e}"
        );
    }
    // The full S at a few distances and incidence/exitance cosines.
    let n = DVec3::Z;
    let mfp = m.mean_free_path(0);
    for r in [0.0, 1e-12, mfp, 100.0 * mfp] {
        for &ci in &COSINES {
            for &co in &COSINES {
                let dir = |c: f64| DVec3::new((1.0 - c * c).max(0.0).sqrt(), 0.0, c);
                let xi = SurfacePoint { p: DVec3::ZERO, n };
                let xo = SurfacePoint {
                    p: DVec3::new(r, 0.0, 0.0),
                    n,
                };
                for v in model.s(&xi, dir(ci), &xo, dir(co)) {
                    assert!(
                        v.is_finite() && v >= 0.0,
                        "{label}: S(r={r}, {ci}, {co}) = {v}"
                    );
                }
            }
        }
    }
}

#[test]
fn fresnel_without_a_valid_interface_reflects_nothing() {
    // fr_dielectric's guard: an index ratio that is not a positive finite number describes no
    // interface, so nothing is reflected (as at η = 1) — never NaN, never total reflection.
    // (cargo-mutants: with the guard's first `||` made `&&`, η = 0 gave 1 and η < 0 a clamped
    // value; no test noticed.)
    for eta in [
        0.0,
        -0.0,
        -1.5,
        -1e-300,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        1.0,
    ] {
        for cos in [0.0, 0.3, 1.0, -0.7] {
            let f = sss_bssrdf::fresnel::fr_dielectric(cos, eta);
            assert_eq!(f, 0.0, "eta {eta} cos {cos}: {f}");
            assert_eq!(sss_bssrdf::fresnel::ft_dielectric(cos, eta), 1.0);
        }
    }
    // A valid interface at normal incidence: ((η − 1)/(η + 1))² (Born & Wolf §1.5.2).
    for eta in [0.5, 1.3, 2.0] {
        let f = sss_bssrdf::fresnel::fr_dielectric(1.0, eta);
        let want = ((eta - 1.0) / (eta + 1.0)).powi(2);
        assert!((f - want).abs() < 1e-15, "eta {eta}: {f} vs {want}");
    }
}

#[test]
fn stiff_and_extreme_grid() {
    let mut checked = 0;
    for &eta in &ETAS {
        for &g in &GS {
            for &a in &ALBEDOS {
                for &st in &SIGMA_T {
                    let m = Medium::from_extinction_albedo([st; 3], [a; 3], g, eta).unwrap();
                    for kind in ModelKind::ALL {
                        let model = make_model(kind, &m);
                        check_model(
                            model.as_ref(),
                            &format!("{kind} a={a} st={st} eta={eta} g={g}"),
                        );
                        checked += 1;
                    }
                }
            }
        }
    }
    assert_eq!(
        checked,
        ETAS.len() * GS.len() * ALBEDOS.len() * SIGMA_T.len() * ModelKind::ALL.len()
    );
}

proptest! {
    // Reproducible: a fixed seed, so every run draws the same 48 media and a failure
    // replays as is; a failing case (e.g. found after changing the seed) is also saved under
    // crates/bssrdf/proptest-regressions/ and replayed first from then on.
    #![proptest_config(ProptestConfig {
        cases: 48,
        rng_seed: RngSeed::Fixed(0x1455_5eed),
        failure_persistence: Some(Box::new(FileFailurePersistence::SourceParallel(
            "proptest-regressions",
        ))),
        ..ProptestConfig::default()
    })]
    #[test]
    fn random_valid_media_stay_physical(
        la in -3.0f64..3.0, ls in -3.0f64..3.0, g in -0.95f64..0.95, eta in 0.6f64..3.0,
    ) {
        let m = Medium::new([10f64.powf(la), 0.01, 1.0], [10f64.powf(ls), 1.0, 0.0], g, eta).unwrap();
        for kind in ModelKind::ALL {
            let model = make_model(kind, &m);
            check_model(model.as_ref(), &format!("{kind} {m:?}"));
            for ch in 0..3 {
                let (r50, r90) = (model.radius_for_energy(ch, 0.5), model.radius_for_energy(ch, 0.9));
                prop_assert!(r50 <= r90, "{} ch{}: {} > {}", kind, ch, r50, r90);
            }
        }
    }
}
