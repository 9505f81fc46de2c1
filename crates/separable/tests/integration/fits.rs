//! The fitted models: d'Eon et al.'s sum of Gaussians and the artist-friendly two-Gaussian
//! model with the paper's Table 2 presets.

use crate::common;

use sss_separable::artist::{self, ArtistParams};
use sss_separable::{TapPlacement, gaussians, preintegrated};

#[test]
fn sum_of_gaussians_error_does_not_increase_from_1_to_6_on_skin1() {
    let m = common::model("skin1");
    let fits = gaussians::fit_model(m.as_ref(), 6).unwrap();
    assert_eq!(fits.len(), 6);
    let total = |f: &gaussians::GaussianFit| f.rel_error.iter().map(|e| e * e).sum::<f64>();
    for (n, f) in fits.iter().enumerate() {
        assert_eq!(f.len(), n + 1);
        assert!(f.variances.windows(2).all(|v| v[0] <= v[1]));
        assert!(f.variances.iter().all(|v| *v > 0.0 && v.is_finite()));
        assert!(
            f.weights
                .iter()
                .flatten()
                .all(|w| *w >= 0.0 && w.is_finite())
        );
        assert!(f.rel_error.iter().all(|e| e.is_finite() && *e <= 1.0));
    }
    for w in fits.windows(2) {
        assert!(
            total(&w[1]) <= total(&w[0]),
            "N={} error {} > N={} error {}",
            w[1].len(),
            total(&w[1]),
            w[0].len(),
            total(&w[0])
        );
    }
    // One Gaussian is a poor fit of a diffusion profile; six are good (d'Eon et al. fit skin
    // with six).
    assert!(
        fits[0].rel_error.iter().all(|e| *e > 0.1),
        "{:?}",
        fits[0].rel_error
    );
    assert!(
        fits[5].rel_error.iter().all(|e| *e < 0.05),
        "{:?}",
        fits[5].rel_error
    );
    // The fitted profile is what the error says it is: check one radius directly.
    let r = 1.0;
    let f6 = &fits[5];
    assert!(((f6.eval(0, r) - m.rd(0, r)) / m.rd(0, r)).abs() < 0.1);
}

#[test]
fn the_artist_fitter_recovers_the_parameters_of_an_eq6_profile() {
    let truth = ArtistParams {
        sigma_near: [0.034, 0.1, 0.2],
        sigma_far: [1.0, 0.6, 0.9],
        w: [0.37, 0.5, 0.8],
    };
    // Cells of 0.01 mm resolve the narrowest lobe.
    let profile = artist::profile(&truth, 1001, 5.0).unwrap();
    let fit = artist::fit(&profile).unwrap();
    for c in 0..3 {
        let rel = |a: f64, b: f64| ((a - b) / b).abs();
        let p = fit.params;
        assert!(
            rel(p.sigma_near[c], truth.sigma_near[c]) < 1e-6,
            "{c}: {p:?}"
        );
        assert!(rel(p.sigma_far[c], truth.sigma_far[c]) < 1e-6, "{c}: {p:?}");
        assert!(rel(p.w[c], truth.w[c]) < 1e-6, "{c}: {p:?}");
        assert!(fit.rel_error[c] < 1e-8, "{c}: {:?}", fit.rel_error);
        assert!(fit.converged[c]);
    }
}

#[test]
fn table_2_presets_are_the_published_numbers() {
    // Jimenez et al. 2015, Table 2:
    //   Close fit   σn [0.034, 0.029, 0.016]  σf [1, 0.48, 0.2]  w 0.37
    //   Production  σn [0.25, 0.08, 0.02]     σf [1, 0.3, 0.05]  w 0.6
    let close = artist::preset("close-fit").unwrap();
    assert_eq!(close.sigma_near, [0.034, 0.029, 0.016]);
    assert_eq!(close.sigma_far, [1.0, 0.48, 0.2]);
    assert_eq!(close.w, [0.37; 3]);
    let prod = artist::preset("Production").unwrap();
    assert_eq!(prod.sigma_near, [0.25, 0.08, 0.02]);
    assert_eq!(prod.sigma_far, [1.0, 0.3, 0.05]);
    assert_eq!(prod.w, [0.6; 3]);
    assert!(artist::preset("nope").is_err());
    // Eq. 6 discretised from them has the variance w σn² + (1 − w) σf² per axis: on a grid of
    // 4 µm cells over ±8 mm (no truncation), after Sheppard's correction h²/12 for the grid.
    for p in [close, prod] {
        let profile = artist::profile(&p, 4001, 8.0).unwrap();
        let h = profile.cell_mm;
        assert!(h <= 0.004);
        for (c, mass) in profile.total().into_iter().enumerate() {
            assert!((mass - 1.0).abs() < 1e-12, "{c}: mass {mass}");
            let second: f64 = (0..profile.cells())
                .map(|i| profile.mass[i][c] * profile.offset_mm(i).powi(2))
                .sum();
            let var = second / mass - h * h / 12.0;
            let want = p.w[c] * p.sigma_near[c].powi(2) + (1.0 - p.w[c]) * p.sigma_far[c].powi(2);
            assert!(((var - want) / want).abs() < 1e-6, "{c}: {var} vs {want}");
        }
        // The default kernel builder truncates at 4 σ_max and uses cells of σ_min/4: its taps'
        // variance is within 1.1e-3 (truncation) + 1.7e-3 (grid) of Eq. 6's.
        let k = artist::kernel(&p, [1.0; 3], TapPlacement::Grid).unwrap();
        let taps = &k.terms[0].horizontal;
        for (c, mass) in taps.sum().into_iter().enumerate() {
            let var: f64 = taps
                .taps
                .iter()
                .map(|t| t.weight[c] * t.offset_mm * t.offset_mm)
                .sum::<f64>()
                / mass;
            let want = p.w[c] * p.sigma_near[c].powi(2) + (1.0 - p.w[c]) * p.sigma_far[c].powi(2);
            assert!(((var - want) / want).abs() < 3e-3, "{c}: {var} vs {want}");
        }
    }
}

#[test]
fn the_artist_fitter_runs_on_a_diffusion_profile() {
    // Not an Eq. 6 profile: the fit is approximate but finite, ordered and converged.
    let m = common::model("skin1");
    let k = common::kernel2d(m.as_ref(), 127);
    let fit = artist::fit(&preintegrated::profile(&k)).unwrap();
    for c in 0..3 {
        let p = fit.params;
        assert!(p.sigma_near[c] <= p.sigma_far[c]);
        assert!((0.0..=1.0).contains(&p.w[c]));
        assert!(fit.rel_error[c].is_finite() && fit.rel_error[c] < 0.5);
    }
}

/// Eq. 6's a_m against its closed form: a mix of two normalised Gaussians, so its integral is
/// 1, its second moment is w σ_n² + (1 − w) σ_f², and its value at 0 is
/// w/(√(2π) σ_n) + (1 − w)/(√(2π) σ_f). Integrated here by the trapezoid rule on a grid a
/// hundredth of the near σ wide (error ≪ 10⁻⁶ for a Gaussian).
#[test]
fn the_artist_profile_is_a_normalised_two_gaussian_mix() {
    for preset in artist::PRESETS {
        let p = preset.params;
        // √(2π), written out.
        const SQRT_2PI: f64 = 2.506_628_274_631;
        for c in 0..3 {
            let (sn, sf, w) = (p.sigma_near[c], p.sigma_far[c], p.w[c]);
            let at0 = w / (SQRT_2PI * sn) + (1.0 - w) / (SQRT_2PI * sf);
            assert!(
                (p.eval(c, 0.0) - at0).abs() < 1e-12 * at0,
                "{} channel {c}: a_m(0) = {} vs {at0}",
                preset.name,
                p.eval(c, 0.0)
            );
            let h = sn.min(sf) / 100.0;
            let n = (10.0 * sn.max(sf) / h).ceil() as i64;
            let (mut m0, mut m2) = (0.0, 0.0);
            for i in -n..=n {
                let x = i as f64 * h;
                let v = p.eval(c, x);
                m0 += v * h;
                m2 += x * x * v * h;
            }
            assert!(
                (m0 - 1.0).abs() < 1e-6,
                "{} channel {c}: ∫ a_m = {m0}",
                preset.name
            );
            let var = w * sn * sn + (1.0 - w) * sf * sf;
            assert!(
                (m2 - var).abs() < 1e-6 * var,
                "{} channel {c}: ∫ x² a_m = {m2} vs {var}",
                preset.name
            );
            assert!((p.variance(c) - var).abs() < 1e-12 * var);
        }
    }
}

/// Each term of a sum-of-Gaussians kernel is the 1D Gaussian of its own variance on both
/// axes: with every grid cell a tap, the taps' second moment Σ w x² / Σ w is vᵢ (less the
/// 0.11 % of a Gaussian's variance beyond ±4σ, where the grid stops) per channel.
#[test]
fn each_gaussian_term_has_its_variance() {
    let m = common::model("skin1");
    let fits = gaussians::fit_model(m.as_ref(), 4).unwrap();
    let f = &fits[3];
    let k = f.kernel([0.5, 0.4, 0.3], TapPlacement::Grid).unwrap();
    assert_eq!(k.terms.len(), 4);
    for (term, &v) in k.terms.iter().zip(&f.variances) {
        for pass in [&term.horizontal, &term.vertical] {
            for c in 0..3 {
                let (mut m0, mut m2) = (0.0, 0.0);
                for t in &pass.taps {
                    m0 += t.weight[c];
                    m2 += t.weight[c] * t.offset_mm * t.offset_mm;
                }
                if m0 == 0.0 {
                    continue;
                }
                let got = m2 / m0;
                assert!(
                    (got / (v * 0.99889) - 1.0).abs() < 2e-3,
                    "variance {v}: taps' second moment {got} (channel {c})"
                );
            }
        }
    }
}
