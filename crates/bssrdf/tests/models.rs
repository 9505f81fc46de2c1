//! Cross-model tests of the models crate against closed forms, independent quadrature,
//! published figures and the Monte Carlo reference.

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;
use sss_bssrdf::monte_carlo::{McConfig, simulate};
use sss_bssrdf::presets::PRESETS;
use sss_bssrdf::quadrature::{integrate, integrate_radial};
use sss_bssrdf::*;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

fn presets() -> impl Iterator<Item = (&'static str, Medium)> {
    PRESETS
        .iter()
        .map(|p| (p.name, Medium::preset(p.name).unwrap()))
}

#[test]
fn dipole_totals_equal_quadrature_of_their_profiles_for_every_preset() {
    for (name, m) in presets() {
        let sd = StandardDipole::new(m.clone());
        for kind in [ModelKind::StandardDipole, ModelKind::BetterDipole] {
            let model = make_model(kind, &m);
            for ch in 0..3 {
                let closed = model.total_diffuse_reflectance(ch);
                let quad =
                    integrate_radial(&|r| model.rd(ch, r), m.reduced_mean_free_path(ch)).min(1.0);
                let rel = (closed - quad).abs() / quad.max(1e-300);
                assert!(rel <= 1e-4, "{name} {kind} ch{ch}: {closed} vs {quad}");
            }
        }
        for ch in 0..3 {
            // The tail formula at r = 0 against the paper's own form of the total.
            let (a, b) = (sd.total_diffuse_reflectance(ch), sd.total_closed_form(ch));
            assert!((a - b).abs() <= 1e-12, "{name} ch{ch}: {a} vs {b}");
        }
    }
}

#[test]
fn standard_dipole_reproduces_published_reflectances() {
    // Jensen et al. 2001 Table 2 lists measured R_d next to the fitted coefficients; the
    // dipole computed from those coefficients (η = 1.3) must come back close to it. (Our F_dr
    // is exact rather than the paper's fit, and the published values are measurements with two
    // digits; marble's blue channel is the largest gap, 0.801 against 0.75.)
    for p in PRESETS.iter() {
        let m = Medium::preset(p.name).unwrap();
        let sd = make_model(ModelKind::StandardDipole, &m);
        for ch in 0..3 {
            let ours = sd.total_diffuse_reflectance(ch);
            let diff = (ours - p.published_rd[ch]).abs();
            assert!(
                diff <= 0.055,
                "{} ch{ch}: {ours} vs published {}",
                p.name,
                p.published_rd[ch]
            );
        }
    }
}

#[test]
fn better_dipole_conserves_energy_at_albedo_one() {
    for eta in [0.75, 1.0, 1.33, 2.5] {
        let m = Medium::new([0.0; 3], [1.0, 10.0, 100.0], 0.0, eta).unwrap();
        let bd = make_model(ModelKind::BetterDipole, &m);
        for ch in 0..3 {
            assert!((bd.total_diffuse_reflectance(ch) - 1.0).abs() < 1e-12);
        }
    }
}

/// ∫₀^∞ pdf(r) dr by panels between `knots` (pdfs of tabulated models are smooth only there).
fn pdf_mass(model: &dyn Bssrdf, ch: usize) -> f64 {
    let l = model.medium().reduced_mean_free_path(ch);
    let mut total = 0.0;
    let mut a = 0.0;
    let mut b = 1e-9 * l;
    while a < 1e9 * l {
        total += integrate(&|r| model.pdf_sr(ch, r), a, b, 16);
        a = b;
        b *= 1.01;
    }
    total
}

#[test]
fn every_pdf_integrates_to_one() {
    for name in ["skin1", "marble", "ketchup", "skimmilk"] {
        let m = Medium::preset(name).unwrap();
        for kind in ModelKind::ALL {
            let model = make_model(kind, &m);
            for ch in 0..3 {
                let mass = pdf_mass(model.as_ref(), ch);
                assert!((mass - 1.0).abs() < 1e-4, "{name} {kind} ch{ch}: {mass}");
            }
        }
    }
}

#[test]
fn sampled_radii_fit_the_profile() {
    // Kolmogorov-Smirnov test of seeded samples against the CDF of 2πr R_d(r) computed by
    // quadrature of the profile itself (not of the sampler's pdf). Critical value at
    // significance 0.001: 1.95/√n.
    let n = 20_000;
    for name in ["skin1", "marble"] {
        let m = Medium::preset(name).unwrap();
        for kind in ModelKind::ALL {
            let model = make_model(kind, &m);
            for ch in [0, 2] {
                let mut rng = Pcg64Mcg::seed_from_u64(0x5eed + ch as u64);
                let mut xs: Vec<f64> = (0..n).map(|_| model.sample_sr(ch, rng.random())).collect();
                xs.sort_by(f64::total_cmp);
                let g = |r: f64| TWO_PI * r * model.rd(ch, r);
                let norm = integrate_radial(&|r| model.rd(ch, r), m.reduced_mean_free_path(ch));
                let (mut cdf, mut prev, mut d) = (0.0, 0.0, 0.0f64);
                for (i, &x) in xs.iter().enumerate() {
                    cdf += integrate(&g, prev, x, 8) / norm;
                    prev = x;
                    let lo = i as f64 / n as f64;
                    let hi = (i + 1) as f64 / n as f64;
                    d = d.max((cdf - lo).abs()).max((hi - cdf).abs());
                }
                let crit = 1.95 / (n as f64).sqrt();
                assert!(d < crit, "{name} {kind} ch{ch}: KS D = {d} >= {crit}");
            }
        }
    }
}

#[test]
fn energy_radius_holds_the_stated_fraction() {
    let m = Medium::preset("skin2").unwrap();
    for kind in ModelKind::ALL {
        let model = make_model(kind, &m);
        for ch in 0..3 {
            let total = integrate_radial(&|r| model.rd(ch, r), m.reduced_mean_free_path(ch));
            for f in [0.5, 0.9, 0.99] {
                let r = model.radius_for_energy(ch, f);
                let inside = sss_bssrdf::quadrature::integrate_radial_range(
                    &|x| model.rd(ch, x),
                    m.reduced_mean_free_path(ch),
                    0.0,
                    r,
                );
                assert!(
                    (inside / total - f).abs() < 2e-3,
                    "{kind} ch{ch} f{f}: {}",
                    inside / total
                );
            }
        }
    }
}

#[test]
fn reflectance_inversion_round_trips() {
    let targets = [0.001, 0.01, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99, 0.999];
    for kind in [
        ModelKind::StandardDipole,
        ModelKind::BetterDipole,
        ModelKind::PhotonBeamDiffusion,
        ModelKind::Burley,
    ] {
        for (g, eta) in [(0.0, 1.33), (0.5, 1.5)] {
            for &t in &targets {
                match from_reflectance(kind, [t, t, t], [0.5, 1.0, 2.0], g, eta) {
                    Ok(m) => {
                        let model = make_model(kind, &m);
                        for ch in 0..3 {
                            let back = model.total_diffuse_reflectance(ch);
                            assert!((back - t).abs() <= 1e-6, "{kind} g{g}: {t} -> {back}");
                            assert!((m.mean_free_path(ch) - [0.5, 1.0, 2.0][ch]).abs() < 1e-12);
                        }
                    }
                    // pbrt's PBD table stops at ~200 mean free paths, which truncates the
                    // profile of forward-scattering media: their highest reflectances are out
                    // of reach, and must be reported as such, never silently clamped.
                    Err(BssrdfError::UnreachableReflectance { max, .. }) => {
                        assert!(
                            kind == ModelKind::PhotonBeamDiffusion && g > 0.0,
                            "{kind} g{g}: {t}"
                        );
                        assert!(t > max && max > 0.9, "{kind} g{g}: {t} vs max {max}");
                    }
                    Err(e) => panic!("{kind} {t}: {e}"),
                }
            }
        }
    }
    // The directional dipole's total does not tend to 0 with the albedo: small reflectances
    // are out of its reach and must be reported, reachable ones round-trip.
    let dd = ModelKind::DirectionalDipole;
    assert!(matches!(
        from_reflectance(dd, [0.01; 3], [1.0; 3], 0.0, 1.33),
        Err(BssrdfError::UnreachableReflectance { .. })
    ));
    let m = from_reflectance(dd, [0.5, 0.6, 0.7], [1.0; 3], 0.0, 1.33).unwrap();
    let model = make_model(dd, &m);
    for (ch, want) in [0.5, 0.6, 0.7].into_iter().enumerate() {
        assert!((model.total_diffuse_reflectance(ch) - want).abs() <= 1e-6);
    }
    // Bad input.
    assert!(
        from_reflectance(
            ModelKind::StandardDipole,
            [1.5, 0.5, 0.5],
            [1.0; 3],
            0.0,
            1.3
        )
        .is_err()
    );
    assert!(
        from_reflectance(
            ModelKind::StandardDipole,
            [0.5; 3],
            [0.0, 1.0, 1.0],
            0.0,
            1.3
        )
        .is_err()
    );
}

#[test]
fn models_against_monte_carlo() {
    // Error measure: relative L2 error of the energy in each radial bin, model against the
    // Monte Carlo tally. The dipoles model multiple scattering only, so they are measured
    // against the Monte Carlo multiple-scattering part (total minus photons that escaped after
    // one collision); photon beam diffusion models both and is measured against the total.
    // Orderings asserted, as the literature establishes them:
    // - d'Eon 2012: the better dipole is closer to multiple scattering than the standard one;
    // - Habel et al. 2013: PBD is closer to the full transport than either dipole.
    let m = Medium::preset("skin1").unwrap();
    let bins = 40;
    let mc = simulate(
        &m,
        &McConfig {
            photons: 100_000,
            seed: 11,
            r_max: 8.0,
            bins,
            channels: [true; 3],
        },
    )
    .unwrap();
    let error = |kind: ModelKind, ch: usize, reference: &[f64]| {
        let model = make_model(kind, &m);
        let (mut num, mut den) = (0.0, 0.0);
        for (edge, &want) in mc.bin_edges.windows(2).zip(reference) {
            let (lo, hi) = (edge[0], edge[1]);
            let area = std::f64::consts::PI * (hi * hi - lo * lo);
            let mass = integrate(&|r| TWO_PI * r * model.rd(ch, r), lo, hi, 8);
            num += (mass - want * area).powi(2);
            den += (want * area).powi(2);
        }
        (num / den).sqrt()
    };
    for ch in 0..3 {
        let multiple: Vec<f64> = mc.rd[ch]
            .iter()
            .zip(&mc.rd_single[ch])
            .map(|(t, s)| t - s)
            .collect();
        let sd = error(ModelKind::StandardDipole, ch, &multiple);
        let bd = error(ModelKind::BetterDipole, ch, &multiple);
        assert!(
            bd < sd,
            "ch{ch}: better dipole {bd} vs standard dipole {sd}"
        );
        let full = &mc.rd[ch];
        let pbd = error(ModelKind::PhotonBeamDiffusion, ch, full);
        assert!(pbd < 0.15, "ch{ch}: PBD error {pbd}");
        for kind in [ModelKind::StandardDipole, ModelKind::BetterDipole] {
            let e = error(kind, ch, full);
            assert!(pbd < e, "ch{ch}: PBD {pbd} vs {kind} {e}");
        }
        // Totals: PBD within 10 % of the Monte Carlo total reflectance.
        let pbd_total =
            make_model(ModelKind::PhotonBeamDiffusion, &m).total_diffuse_reflectance(ch);
        let rel = (pbd_total / mc.total[ch] - 1.0).abs();
        assert!(rel < 0.1, "ch{ch}: {pbd_total} vs {}", mc.total[ch]);
    }
}
