//! The ball's walk against closed forms and an independent quadrature, and the reshaped
//! profile's consistency (it ends at the diameter, its sampling and totals agree, a huge ball
//! is the half-space).

use super::*;
use crate::monte_carlo::{BinSpacing, WalkConfig, simulate_analog, simulate_sphere};
use crate::quadrature::integrate;
use crate::{Bssrdf, McTableModel, Medium};

fn skin1() -> Medium {
    Medium::new([0.032, 0.17, 0.48], [0.74, 0.88, 1.01], 0.0, 1.3).unwrap()
}

fn config(photons: u64, r_max: f64, bins: usize) -> WalkConfig {
    WalkConfig {
        photons,
        seed: 7,
        r_max,
        bins,
        channels: [true, false, false],
        spacing: BinSpacing::Linear,
    }
}

/// Without absorption and without a boundary (η = 1) every photon that collides leaves the
/// ball, and only those that cross it uncollided (probability e^{−2σ_t R} along the diameter)
/// are not tallied: total = 1 − e^{−2σ_t R}, for both absorption estimators.
#[test]
fn a_lossless_ball_returns_all_but_the_uncollided_light() {
    let medium = Medium::new([0.0; 3], [1.0; 3], 0.0, 1.0).unwrap();
    let n = 1 << 15;
    for radius in [0.25_f64, 1.0, 3.0] {
        let expected = 1.0 - (-2.0 * radius).exp();
        let se = (expected * (1.0 - expected) / n as f64).sqrt().max(1e-4);
        let cfg = config(n, 2.0 * radius, 8);
        let implicit = simulate_sphere(&medium, radius, &cfg).unwrap();
        let analog = simulate_analog(&medium, &cfg, Some(radius)).unwrap();
        for (name, p) in [("implicit", &implicit), ("analog", &analog)] {
            let got = p.total[0];
            assert!(
                (got - expected).abs() < 4.0 * se,
                "R {radius} {name}: total {got:.5}, closed form {expected:.5} (se {se:.1e})"
            );
            // Every escape is tallied inside the diameter.
            let binned: f64 = p.rd[0].iter().zip(p.bin_areas()).map(|(v, a)| v * a).sum();
            assert!((binned - got).abs() < 1e-9, "{name}: {binned} vs {got}");
        }
    }
}

/// Single scattering in an index-matched ball, by quadrature: the beam enters at the top
/// heading down the diameter, collides at depth t (density σ_t e^{−σ_t t}), scatters
/// isotropically into direction cosine μ (against +z, density 1/2) and escapes unattenuated
/// by a second collision with probability e^{−σ_t s}, s the distance to the sphere
/// (s = −(R − t)μ + √((R − t)²μ² + R² − (R − t)²)), at the chord |y| of its exit point y.
/// The walk's single-scattering tally per chord bin must match the quadrature (a geometry
/// written again here: the sphere's intersection, the chord, the bins' area normalisation).
#[test]
fn single_scattering_in_a_ball_matches_quadrature() {
    let (sigma_s, sigma_a) = (0.8, 0.2);
    let medium = Medium::new([sigma_a; 3], [sigma_s; 3], 0.0, 1.0).unwrap();
    let (radius, bins) = (1.5, 6);
    let n = 1 << 17;
    let p = simulate_sphere(&medium, radius, &config(n, 2.0 * radius, bins)).unwrap();
    let sigma_t = sigma_s + sigma_a;
    let albedo = sigma_s / sigma_t;
    let width = 2.0 * radius / bins as f64;
    // Mass escaping into chord bin k, by 2D quadrature over (t, μ).
    let mass = |k: usize| {
        let (lo, hi) = (k as f64 * width, (k + 1) as f64 * width);
        integrate(
            &|t: f64| {
                let h = radius - t;
                let inner = |mu: f64| {
                    let s = -h * mu + (h * h * mu * mu + radius * radius - h * h).max(0.0).sqrt();
                    let (x, z) = (s * (1.0 - mu * mu).max(0.0).sqrt(), -t + s * mu);
                    let chord = x.hypot(z);
                    if chord >= lo && chord < hi {
                        0.5 * (-sigma_t * s).exp()
                    } else {
                        0.0
                    }
                };
                // The chord jumps between bins along μ: many panels.
                let panels = 400;
                let mut sum = 0.0;
                for j in 0..panels {
                    let a = -1.0 + 2.0 * j as f64 / panels as f64;
                    sum += integrate(&inner, a, a + 2.0 / panels as f64, 4);
                }
                albedo * sigma_t * (-sigma_t * t).exp() * sum
            },
            0.0,
            2.0 * radius,
            64,
        )
    };
    let areas = p.bin_areas();
    let mut total = 0.0;
    for (k, area) in areas.iter().enumerate() {
        let walk = p.rd_single[0][k] * area;
        let quad = mass(k);
        total += quad;
        // Binomial standard error of a fraction `quad` of n photons, times 5.
        let tol = 5.0 * (quad / n as f64).sqrt() + 2e-3 * quad;
        assert!(
            (walk - quad).abs() < tol,
            "chord bin {k}: walk {walk:.5}, quadrature {quad:.5} (tolerance {tol:.1e})"
        );
    }
    let walk_total = p.total_single[0];
    assert!(
        (walk_total - total).abs() < 5.0 * (total / n as f64).sqrt(),
        "single scattering: walk {walk_total:.5}, quadrature {total:.5}"
    );
}

/// A ball a thousand times wider than the light travels is the half-space: the same totals
/// and profile within 0.5 %.
#[test]
fn a_huge_ball_is_the_half_space() {
    let base = McTableModel::new(skin1());
    let ball = SphereProfile::new(Box::new(base.clone()), 5.0e3).unwrap();
    for ch in 0..3 {
        let (a, b) = (
            ball.total_diffuse_reflectance(ch),
            base.total_diffuse_reflectance(ch),
        );
        assert!((a / b - 1.0).abs() < 5e-3, "channel {ch}: {a} vs {b}");
        let (s_ball, s_flat) = ball.delta().totals(ch);
        assert!(
            (s_ball / s_flat - 1.0).abs() < 5e-3,
            "walks {s_ball} {s_flat}"
        );
        for r in [0.1, 1.0, 4.0] {
            let (x, y) = (ball.rd(ch, r), base.rd(ch, r));
            assert!(
                (x / y - 1.0).abs() < 5e-3,
                "channel {ch}, r {r}: {x} vs {y}"
            );
        }
        // The bins start at a tenth of a reduced mean free path (the first centre at half of
        // it) and grow to the diameter.
        let bins = ball.delta_se(ch);
        assert_eq!(bins.len(), BINS);
        let first = 0.05 * skin1().reduced_mean_free_path(ch);
        assert!(
            (bins[0].0 / first - 1.0).abs() < 1e-9,
            "{} vs {first}",
            bins[0].0
        );
        assert!(bins.windows(2).all(|w| w[0].0 < w[1].0) && bins[BINS - 1].0 < 1.0e4);
    }
}

/// On a small ball the light comes back more than from the half-space (less medium absorbs
/// it), the more so the longer the channel's mean free path; the ball's profile is zero beyond
/// its diameter; its total is its own integral (by quadrature here, not the table's sum) and
/// the walk's ball total within 1 %; its sampling density integrates to one and its samples
/// stay within the diameter.
#[test]
fn a_small_ball_returns_more_light_and_ends_at_its_diameter() {
    let radius = 5.0;
    let base = McTableModel::new(skin1());
    let ball = SphereProfile::new(Box::new(base.clone()), radius).unwrap();
    let mut gains = [0.0; 3];
    for ch in 0..3 {
        let total = ball.total_diffuse_reflectance(ch);
        gains[ch] = total / base.total_diffuse_reflectance(ch);
        let (walk_ball, _) = ball.delta().totals(ch);
        assert!(
            (total / walk_ball - 1.0).abs() < 0.01,
            "channel {ch}: profile {total}, walk {walk_ball}"
        );
        let two_pi_r = |r: f64| 2.0 * std::f64::consts::PI * r * ball.rd(ch, r);
        let mut edges = vec![0.0];
        edges.extend((0..=60).map(|k| 1e-4 * (2.0 * radius / 1e-4_f64).powf(k as f64 / 60.0)));
        let quad: f64 = edges
            .windows(2)
            .map(|e| integrate(&two_pi_r, e[0], e[1], 8))
            .sum();
        assert!(
            (quad / total - 1.0).abs() < 5e-3,
            "channel {ch}: {quad} vs {total}"
        );
        assert_eq!(ball.rd(ch, 2.0 * radius * (1.0 + 1e-9)), 0.0);
        assert_eq!(ball.pdf_sr(ch, 2.5 * radius), 0.0);
        let pdf: f64 = edges
            .windows(2)
            .map(|e| integrate(&|r| ball.pdf_sr(ch, r), e[0], e[1], 8))
            .sum();
        assert!(
            (pdf - 1.0).abs() < 5e-3,
            "channel {ch}: pdf integrates to {pdf}"
        );
        // Stratified samples: within the diameter, with the mean radius of 2πr R_d^S / total
        // (by quadrature) within 2 %.
        let mut mean = 0.0;
        for k in 0..2000 {
            let r = ball.sample_sr(ch, (k as f64 + 0.5) / 2000.0);
            assert!(r.is_finite() && (0.0..=2.0 * radius).contains(&r), "{r}");
            mean += r / 2000.0;
        }
        let mean_quad: f64 = edges
            .windows(2)
            .map(|e| integrate(&|r| r * two_pi_r(r), e[0], e[1], 8))
            .sum::<f64>()
            / quad;
        assert!(
            (mean / mean_quad - 1.0).abs() < 0.02,
            "channel {ch}: {mean} vs {mean_quad}"
        );
        // The radius holding 90 % of the energy holds it by quadrature.
        let r90 = ball.radius_for_energy(ch, 0.9);
        assert!(r90 > 0.0 && r90 <= 2.0 * radius, "{r90}");
        let inside: f64 = edges
            .windows(2)
            .map(|e| integrate(&two_pi_r, e[0].min(r90), e[1].min(r90), 8))
            .sum();
        assert!(
            (inside / quad - 0.9).abs() < 0.01,
            "channel {ch}: {}",
            inside / quad
        );
    }
    assert_eq!((ball.radius(), ball.delta().radius()), (radius, radius));
    let shown = format!("{ball:?}");
    assert!(
        shown.contains("SphereProfile") && shown.contains("5.0"),
        "{shown}"
    );
    // The first bin ends at a tenth of a reduced mean free path, or at a hundredth of the
    // diameter when that is smaller (red: 0.130 mm against 0.1 mm).
    for ch in 0..3 {
        let edge = (0.1 * skin1().reduced_mean_free_path(ch)).min(0.02 * radius);
        let centre = ball.delta_se(ch)[0].0;
        assert!(
            (centre / (0.5 * edge) - 1.0).abs() < 1e-9,
            "channel {ch}: {centre}"
        );
    }
    // Between 1 and 6 mm the difference is resolved: more than 3 standard errors, positive.
    for ch in 0..3 {
        for (centre, se) in ball.delta_se(ch) {
            if (1.0..6.0).contains(&centre) {
                let d = ball.delta().delta(ch, centre);
                assert!(
                    d > 3.0 * se && se > 0.0,
                    "channel {ch}, {centre} mm: {d} ± {se}"
                );
            }
        }
    }
    // Jensen's skin1 reduced mean free paths are 1.30 / 0.95 / 0.67 mm: red gains most.
    assert!(
        gains[0] > gains[1] && gains[1] > gains[2] && gains[2] > 1.0,
        "{gains:?}"
    );
    assert!(gains[0] > 1.3, "{gains:?}");
}

/// Bad radii and the directional dipole are refused with a message; absorption-only media
/// (albedo 0) give a zero profile, never NaN.
#[test]
fn refusals_and_extremes() {
    for r in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = SphereDelta::with_photons(&skin1(), r, 64).unwrap_err();
        assert!(e.to_string().contains("radius"), "{e}");
    }
    let dd = crate::make_model(crate::ModelKind::DirectionalDipole, &skin1());
    let e = SphereProfile::new(dd, 5.0).unwrap_err();
    assert!(e.to_string().contains("directional dipole"), "{e}");
    let black = Medium::new([1.0; 3], [0.0; 3], 0.0, 1.3).unwrap();
    let delta = Arc::new(SphereDelta::with_photons(&black, 2.0, 4096).unwrap());
    let ball = SphereProfile::with_delta(Box::new(McTableModel::new(black)), delta);
    for r in [0.0, 0.5, 3.9, 4.1] {
        assert_eq!(ball.rd(0, r), 0.0);
    }
    assert_eq!(ball.total_diffuse_reflectance(0), 0.0);
    let s = ball.sample_sr(0, 0.5);
    assert!(s.is_finite() && ball.pdf_sr(0, s) > 0.0);
}
