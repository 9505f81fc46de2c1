//! Cross-model tests of the models crate against closed forms, independent quadrature,
//! published figures and the Monte Carlo reference.

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;
use sss_bssrdf::monte_carlo::{BinSpacing, WalkConfig, simulate};
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

/// One row of [`JENSEN_TABLE2`]: material, R_d as printed for red, green, blue, and the
/// number of decimals printed for σ'_s and for σ_a of each channel.
type Table2Row = (&'static str, [f64; 3], [i32; 3], [i32; 3]);

/// Jensen, Marschner, Levoy, Hanrahan, *A Practical Model for Subsurface Light Transport*,
/// SIGGRAPH 2001, Table 2, typed in again here.
#[rustfmt::skip]
const JENSEN_TABLE2: [Table2Row; 12] = [
    ("apple", [0.85, 0.84, 0.53], [2, 2, 2], [4, 4, 3]),
    ("chicken1", [0.31, 0.15, 0.10], [2, 2, 2], [3, 3, 2]),
    ("chicken2", [0.32, 0.16, 0.10], [2, 2, 2], [3, 3, 2]),
    ("cream", [0.98, 0.90, 0.73], [2, 2, 2], [4, 4, 4]),
    ("ketchup", [0.16, 0.01, 0.00], [2, 2, 2], [3, 2, 2]),
    ("marble", [0.83, 0.79, 0.75], [2, 2, 2], [4, 4, 4]),
    ("potato", [0.77, 0.62, 0.21], [2, 2, 2], [4, 4, 2]),
    ("skimmilk", [0.81, 0.81, 0.69], [2, 2, 2], [4, 4, 4]),
    ("skin1", [0.44, 0.22, 0.13], [2, 2, 2], [3, 2, 2]),
    ("skin2", [0.63, 0.44, 0.34], [2, 2, 2], [3, 3, 3]),
    ("spectralon", [1.00, 1.00, 1.00], [1, 1, 1], [2, 2, 2]),
    ("wholemilk", [0.91, 0.88, 0.76], [2, 2, 2], [4, 4, 3]),
];

/// The printed R_d values that the paper's own formula (Jensen et al. 2001, the total below
/// Eq. 5, with their F_dr fit, Eq. 7) does not give for the printed coefficients, beyond the
/// rounding tolerance: (material, channel, the formula's value for the printed coefficients,
/// computed by hand from the paper's equations). Table 2 does not say how R_d was obtained;
/// for these entries it is not the formula's output.
const TABLE2_INCONSISTENT: [(&str, usize, f64); 5] = [
    ("chicken1", 2, 0.1264),
    ("marble", 0, 0.8665),
    ("marble", 1, 0.8338),
    ("marble", 2, 0.8010),
    ("skimmilk", 2, 0.6823),
];

/// Jensen et al. 2001's total diffuse reflectance of the dipole (below their Eq. 5) for
/// reduced scattering `s`, absorption `a` and internal diffuse Fresnel reflectance `f_dr`.
fn jensen_rd(s: f64, a: f64, f_dr: f64) -> f64 {
    let big_a = (1.0 + f_dr) / (1.0 - f_dr);
    let alpha_p = s / (s + a);
    let x = (3.0 * (1.0 - alpha_p)).max(0.0).sqrt();
    0.5 * alpha_p * (1.0 + (-(4.0 / 3.0) * big_a * x).exp()) * (-x).exp()
}

#[test]
fn standard_dipole_reproduces_published_reflectances() {
    // Each printed R_d of Jensen et al. 2001 Table 2 is its own assertion with its own
    // tolerance, the sum of:
    // - 0.005: R_d is printed with two decimals;
    // - the change of R_d (the paper's formula) over the rounding box of the printed
    //   coefficients, half a unit of their last printed digit (σ_a ≥ 0: spectralon's 0.00);
    // - the change of R_d when F_dr moves by 1 %, the accuracy Egan & Hilgeman's fit (the
    //   paper's Eq. 7) has against the exact F_dr the crate uses.
    // This is 0.0053-0.015 for every value except spectralon (0.07-0.10, from σ_a = 0.00).
    // For the five entries of TABLE2_INCONSISTENT the tolerance is widened by the distance
    // between the printed value and the formula's value for the printed coefficients.
    // A 10 % change of z_v moves R_d by 1-3.5 % (0.01-0.03 on the bright materials): several
    // values fail.
    let f_fit = {
        let eta: f64 = presets::PRESET_ETA;
        -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta
    };
    let mut failures = Vec::new();
    for (name, published, s_dec, a_dec) in JENSEN_TABLE2 {
        let preset = presets::find(name).unwrap();
        // The crate's copy of the table is the paper's.
        assert_eq!(preset.published_rd, published, "{name}: published R_d");
        let m = Medium::preset(name).unwrap();
        let sd = make_model(ModelKind::StandardDipole, &m);
        for ch in 0..3 {
            let (s, a) = (preset.sigma_s_reduced[ch], preset.sigma_a[ch]);
            let (hs, ha) = (0.5 * 10f64.powi(-s_dec[ch]), 0.5 * 10f64.powi(-a_dec[ch]));
            let centre = jensen_rd(s, a, f_fit);
            let mut coef = 0.0f64;
            for (ds, da) in [(-hs, -ha), (-hs, ha), (hs, -ha), (hs, ha)] {
                let v = jensen_rd(s + ds, (a + da).max(0.0), f_fit);
                coef = coef.max((v - centre).abs());
            }
            let fit = (jensen_rd(s, a, 1.01 * f_fit) - centre)
                .abs()
                .max((jensen_rd(s, a, 0.99 * f_fit) - centre).abs());
            let mut tol = 0.005 + coef + fit;
            if let Some((_, _, formula)) = TABLE2_INCONSISTENT
                .iter()
                .find(|(n, c, _)| *n == name && *c == ch)
            {
                // The hand value is the formula's (to its four printed decimals) ...
                assert!((formula - centre).abs() < 6e-5, "{name} ch{ch}: {centre}");
                // ... and outside the rounding tolerance of the printed R_d.
                assert!((formula - published[ch]).abs() > tol, "{name} ch{ch}");
                tol += (formula - published[ch]).abs();
            }
            let ours = sd.total_diffuse_reflectance(ch);
            let diff = ours - published[ch];
            println!(
                "{name} ch{ch}: {ours:.4} vs published {:.2} ({diff:+.4}, tolerance {tol:.4})",
                published[ch]
            );
            if diff.abs() > tol {
                failures.push(format!(
                    "{name} ch{ch}: R_d {ours:.4} vs published {:.2} ± {tol:.4}",
                    published[ch]
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn separable_directional_factor_is_normalised() {
    // pbrt 3rd ed. Eq. 11.6-11.7: S = F_t(cos θ_o) R_d F_t(cos θ_i)/(cπ), c = 1 − 2C₁, so that
    // ∫ F_t(cos θ)/(cπ) cos θ dω = 1. With R_d = 1 and normal incidence, the outgoing
    // projected integral ∫ S cos θ_o dω_o is therefore F_t(1) = 1 − ((η − 1)/(η + 1))² (Born &
    // Wolf §1.5.2). Quadrature over μ = cos θ_o (the azimuth gives 2π); F_t is smooth for
    // η > 1. (cargo-mutants: ft_dielectric → −1 survived, its sign cancelling in F_t·F_t.)
    for eta in [1.1, 1.3, 1.5, 2.0] {
        let m = Medium::new([0.1; 3], [1.0; 3], 0.0, eta).unwrap();
        let f = |mu: f64| sss_bssrdf::separable_s(&m, [1.0; 3], 1.0, mu)[0] * mu;
        let projected = TWO_PI
            * (0..16)
                .map(|k| integrate(&f, k as f64 / 16.0, (k + 1) as f64 / 16.0, 16))
                .sum::<f64>();
        let want = 1.0 - ((eta - 1.0) / (eta + 1.0)).powi(2);
        assert!(
            (projected - want).abs() < 1e-9,
            "eta {eta}: {projected} vs {want}"
        );
        // Below the surface on either side: nothing.
        assert_eq!(sss_bssrdf::separable_s(&m, [1.0; 3], -0.2, 0.5), [0.0; 3]);
        assert_eq!(sss_bssrdf::separable_s(&m, [1.0; 3], 0.5, 0.0), [0.0; 3]);
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
        ModelKind::McTable,
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
                    // The mc-table profile is the random walk's: at albedo 1 it reflects
                    // 0.98-0.995 (what escapes beyond ≈ 960 mean free paths and after 10⁶
                    // collisions is missing), so 0.99 and 0.999 may be out of its reach.
                    Err(BssrdfError::UnreachableReflectance { max, .. }) => {
                        assert!(
                            (kind == ModelKind::PhotonBeamDiffusion && g > 0.0)
                                || (kind == ModelKind::McTable && t >= 0.99 && max > 0.98),
                            "{kind} g{g}: {t} (max {max})"
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
        &WalkConfig {
            photons: 100_000,
            seed: 11,
            r_max: 8.0,
            bins,
            channels: [true; 3],
            spacing: BinSpacing::Linear,
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

/// The three-channel forms agree with the per-channel profile: `rd_rgb(r)` is
/// `[rd(0, r), rd(1, r), rd(2, r)]` and `sp` is R_d of the distance between the two points,
/// for every model (renderers call these, the other tests mostly `rd`).
#[test]
fn rgb_and_spatial_forms_are_the_channel_profiles() {
    let m = Medium::preset("skin1").unwrap();
    let xi = SurfacePoint {
        p: DVec3::new(0.3, -0.2, 1.0),
        n: DVec3::Z,
    };
    for kind in ModelKind::ALL {
        let model = make_model(kind, &m);
        for r in [0.01, 0.2, 1.0, 3.0] {
            let rgb = model.rd_rgb(r);
            let xo = SurfacePoint {
                p: xi.p + DVec3::new(0.6 * r, 0.8 * r, 0.0),
                n: DVec3::Z,
            };
            let sp = model.sp(&xi, &xo);
            for ch in 0..3 {
                let want = model.rd(ch, r);
                assert!(want > 0.0, "{kind} ch{ch} r {r}: R_d = {want}");
                assert_eq!(rgb[ch], want, "{kind} ch{ch} r {r}: rd_rgb");
                assert!(
                    (sp[ch] - want).abs() <= 1e-12 * want,
                    "{kind} ch{ch} r {r}: sp"
                );
            }
        }
    }
}

/// The unknown-model message lists exactly the models of `ModelKind::ALL`, in its order, so
/// a model added to the enum cannot be missing from it.
#[test]
fn the_unknown_model_message_lists_every_model() {
    let msg = "nope".parse::<ModelKind>().unwrap_err().to_string();
    let list = msg
        .split_once("(expected ")
        .and_then(|(_, rest)| rest.strip_suffix(')'))
        .unwrap_or_else(|| panic!("no list in {msg}"));
    let (head, last) = list.rsplit_once(" or ").expect("`a, b or c`");
    let listed: Vec<&str> = head.split(", ").chain([last]).collect();
    let all: Vec<&str> = ModelKind::ALL.iter().map(|k| k.name()).collect();
    assert_eq!(listed, all, "{msg}");
    assert!(msg.contains("'nope'"), "{msg}");
    // Every listed name parses back.
    for name in listed {
        assert_eq!(name.parse::<ModelKind>().unwrap().name(), name);
    }
}
