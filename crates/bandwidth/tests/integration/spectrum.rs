//! The discrete spectra against closed forms: Gaussians in 2-D (spatial) and 1-D (windowed
//! angular transform).
//!
//! For f(r) = exp(−r²/(2σ²)) on the plane, F(ρ) = 2πσ² exp(−2π²σ²ρ²), so the power is
//! ∝ exp(−4π²σ²ρ²) and the energy below ρ is ∫₀^ρ exp(−4π²σ²u²) 2πu du / ∫₀^∞ (same)
//! = 1 − exp(−4π²σ²ρ²): ρ_f = √(−ln(1 − f))/(2πσ), √(ln 20)/(2πσ) at f = 0.95.
//! In 1-D, a Gaussian of standard deviation s has power ∝ exp(−4π²s²ν²) and the energy in
//! [−ν, ν] is erf(2πsν): ν_f = erf⁻¹(f)/(2πs).

use sss_bandwidth::spectrum::{
    SpectrumGrid, bandwidth_2d_cycles_per_mm, radial_bandwidth_cycles_per_mm,
    smoothed_bandwidth_2d_cycles_per_mm,
};
use sss_bandwidth::{
    AngularOptions, AngularTable, BandwidthError, SpatialOptions,
    profile_spatial_bandwidth_cycles_per_mm,
};
use std::f64::consts::PI;

fn gaussian_2d_bandwidth(sigma: f64, fraction: f64) -> f64 {
    (-(1.0 - fraction).ln()).sqrt() / (2.0 * PI * sigma)
}

/// erf⁻¹(0.95) and erf⁻¹(0.5), from tables (Abramowitz & Stegun 7.1; e.g. erf(1.3859038) =
/// 0.95000000, erf(0.4769363) = 0.50000000).
const ERF_INV_095: f64 = 1.385_903_824_349_678;
const ERF_INV_050: f64 = 0.476_936_276_204_470;

#[test]
fn gaussian_profile_matches_the_analytic_95_percent_frequency() {
    let opts = SpatialOptions::default();
    for sigma in [1e-3, 0.05, 1.0, 40.0] {
        let expected = gaussian_2d_bandwidth(sigma, 0.95);
        assert!((expected - (20f64.ln()).sqrt() / (2.0 * PI * sigma)).abs() < 1e-12 * expected);
        // Any floor leaves a Gaussian's shape unchanged: f(√(r² + r_f²)) = const · f(r).
        for floor in [0.01 * sigma, sigma] {
            let got = profile_spatial_bandwidth_cycles_per_mm(
                |r| (-r * r / (2.0 * sigma * sigma)).exp(),
                floor,
                &opts,
            )
            .unwrap();
            let rel = (got - expected).abs() / expected;
            // Measured: −2.8e-4 for every σ.
            assert!(
                rel < 0.002,
                "σ = {sigma}, floor {floor}: {got} vs {expected} ({rel:.2e})"
            );
        }
    }
}

#[test]
fn gaussian_energy_fraction_is_configurable() {
    let sigma = 0.7;
    for fraction in [0.5, 0.9, 0.99] {
        let opts = SpatialOptions {
            energy_fraction: fraction,
            ..Default::default()
        };
        let got = profile_spatial_bandwidth_cycles_per_mm(
            |r| (-r * r / (2.0 * sigma * sigma)).exp(),
            sigma,
            &opts,
        )
        .unwrap();
        let expected = gaussian_2d_bandwidth(sigma, fraction);
        assert!(
            (got - expected).abs() < 0.01 * expected,
            "f = {fraction}: {got} vs {expected}"
        );
    }
}

#[test]
fn explicit_grid_gaussian_and_scale_invariance() {
    // σ = 1 mm on a 256² grid of step 0.25 mm (extent ±32 σ): Nyquist 2 cycles/mm ≫ ρ₉₅ = 0.276.
    let grid = SpectrumGrid::new(0.25, 256).unwrap();
    let g = |r: f64| (-r * r / 2.0).exp();
    let b = radial_bandwidth_cycles_per_mm(g, &grid, 0.95).unwrap();
    let expected = gaussian_2d_bandwidth(1.0, 0.95);
    assert!((b - expected).abs() < 0.01 * expected, "{b} vs {expected}");
    // The amplitude does not matter, whatever its magnitude.
    for scale in [1e-300, 1e300] {
        let bs = radial_bandwidth_cycles_per_mm(|r| scale * g(r), &grid, 0.95).unwrap();
        assert!((bs - b).abs() <= 1e-9 * b, "scale {scale}: {bs} vs {b}");
    }
    // An anisotropic Gaussian exp(−x²/(2a²) − y²/(2b²)) with a = b reduces to the radial one;
    // stretching it along y lowers the bandwidth.
    let iso =
        bandwidth_2d_cycles_per_mm(|x, y| (-(x * x + y * y) / 2.0).exp(), &grid, 0.95).unwrap();
    assert!((iso - b).abs() < 1e-12 * b);
    let aniso =
        bandwidth_2d_cycles_per_mm(|x, y| (-(x * x) / 2.0 - y * y / 8.0).exp(), &grid, 0.95)
            .unwrap();
    assert!(aniso < 0.9 * iso, "{aniso} vs {iso}");
}

#[test]
fn gaussian_smoothing_adds_variances() {
    // A Gaussian of σ convolved with one of s is a Gaussian of √(σ² + s²).
    let grid = SpectrumGrid::new(0.2, 512).unwrap();
    let (sigma, s) = (1.0, 0.75);
    let b = smoothed_bandwidth_2d_cycles_per_mm(
        |x, y| (-(x * x + y * y) / (2.0 * sigma * sigma)).exp(),
        &grid,
        0.95,
        s,
    )
    .unwrap();
    let expected = gaussian_2d_bandwidth((sigma * sigma + s * s).sqrt(), 0.95);
    assert!((b - expected).abs() < 0.01 * expected, "{b} vs {expected}");
}

#[test]
fn zero_profile_has_zero_bandwidth_and_bad_input_is_an_error() {
    let grid = SpectrumGrid::new(0.1, 64).unwrap();
    assert_eq!(
        radial_bandwidth_cycles_per_mm(|_| 0.0, &grid, 0.95).unwrap(),
        0.0
    );
    for f in [0.0, 1.0, -0.5, f64::NAN] {
        assert!(matches!(
            radial_bandwidth_cycles_per_mm(|_| 1.0, &grid, f),
            Err(BandwidthError::InvalidArgument(_))
        ));
    }
    assert!(matches!(
        radial_bandwidth_cycles_per_mm(|r| if r < 0.5 { f64::NAN } else { 1.0 }, &grid, 0.95),
        Err(BandwidthError::NonFiniteProfile { .. })
    ));
    for (step, cells) in [
        (0.0, 64),
        (-1.0, 64),
        (f64::INFINITY, 64),
        (0.1, 4),
        (0.1, 1 << 20),
    ] {
        assert!(SpectrumGrid::new(step, cells).is_err(), "{step} {cells}");
    }
    assert!(
        profile_spatial_bandwidth_cycles_per_mm(|_| 1.0, 0.0, &SpatialOptions::default()).is_err()
    );
    assert!(smoothed_bandwidth_2d_cycles_per_mm(|_, _| 1.0, &grid, 0.95, -1.0).is_err());
}

#[test]
fn windowed_transform_of_a_flat_signal_is_the_window_bandwidth() {
    // g = 1: the windowed signal is the Gaussian window itself.
    for (window, fraction, erf_inv) in [
        (0.1, 0.95, ERF_INV_095),
        (0.05, 0.95, ERF_INV_095),
        (0.2, 0.5, ERF_INV_050),
    ] {
        let opts = AngularOptions {
            window_rad: window,
            energy_fraction: fraction,
            ..Default::default()
        };
        let table = AngularTable::from_signal(|_| 1.0, 1.0, &opts).unwrap();
        let expected = erf_inv / (2.0 * PI * window);
        for v in table.values() {
            assert!((v - expected).abs() < 0.005 * expected, "{v} vs {expected}");
        }
    }
}

#[test]
fn windowed_transform_of_a_gaussian_narrows_the_window() {
    // g(θ) = exp(−θ²/(2s²)) times the window at θ₀ = 0: a Gaussian with 1/σ² = 1/s² + 1/σ_w².
    let opts = AngularOptions::default();
    let s = 0.08;
    let table = AngularTable::from_signal(|t| (-t * t / (2.0 * s * s)).exp(), 1.0, &opts).unwrap();
    let sigma = 1.0 / (1.0 / (s * s) + 1.0 / (opts.window_rad * opts.window_rad)).sqrt();
    let expected = ERF_INV_095 / (2.0 * PI * sigma);
    let got = table.cycles_per_radian(0.0);
    assert!(
        (got - expected).abs() < 0.005 * expected,
        "{got} vs {expected}"
    );
}

#[test]
fn fresnel_table_is_flat_at_normal_view_and_grows_at_grazing() {
    let opts = AngularOptions::default();
    let floor = ERF_INV_095 / (2.0 * PI * opts.window_rad);
    // η = 1: F_t = 1 up to the horizon, so only the horizon adds bandwidth.
    let clear = AngularTable::new(1.0, &opts).unwrap();
    assert!((clear.cycles_per_radian(0.0) - floor).abs() < 0.005 * floor);
    assert!((clear.cycles_per_radian(45f64.to_radians()) - floor).abs() < 0.005 * floor);
    for eta in [1.3, 1.5, 2.5] {
        let t = AngularTable::new(eta, &opts).unwrap();
        assert_eq!(t.eta(), eta);
        // F_t varies by < 2 % over the window at normal view: within 1 % of the floor.
        assert!((t.cycles_per_radian(0.0) - floor).abs() < 0.01 * floor);
        // Towards grazing, the fall of F_t to 0 widens the spectrum (Milaenen §3.1).
        let grazing = t.cycles_per_radian(89f64.to_radians());
        assert!(grazing > 1.4 * floor, "η = {eta}: {grazing} vs {floor}");
        // Non-decreasing from 0 to 90° (1° steps, 0.1 % slack for rounding).
        let v = t.values();
        for w in v.windows(2) {
            assert!(w[1] >= w[0] * 0.999, "η = {eta}: {v:?}");
        }
        // Interpolation: between neighbouring entries, symmetric in θ, clamped, NaN → grazing.
        let mid = t.cycles_per_radian(60.5f64.to_radians());
        assert!((mid - 0.5 * (v[60] + v[61])).abs() < 1e-9 * mid);
        assert_eq!(t.cycles_per_radian(-0.3), t.cycles_per_radian(0.3));
        assert_eq!(t.cycles_per_radian(7.0), v[90]);
        assert_eq!(t.cycles_per_radian(f64::NAN), v[90]);
        assert_eq!(t.cycles_per_radian_at_cos(1.0), v[0]);
        assert_eq!(t.cycles_per_radian_at_cos(0.0), v[90]);
        assert_eq!(t.cycles_per_radian_at_cos(-1.0), v[0]);
        assert_eq!(t.cycles_per_radian_at_cos(2.0), v[0]);
    }
    // Every η gives finite values, total internal reflection included.
    for eta in [0.3, 0.7, 0.999, 1.001, 10.0, 1e6] {
        let t = AngularTable::new(eta, &opts).unwrap();
        assert!(
            t.values().iter().all(|v| v.is_finite() && *v >= 0.0),
            "η = {eta}"
        );
    }
    for eta in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(AngularTable::new(eta, &opts).is_err());
    }
    for bad in [
        AngularOptions {
            window_rad: 0.0,
            ..opts
        },
        AngularOptions {
            period_rad: 1.0,
            ..opts
        },
        AngularOptions { samples: 8, ..opts },
        AngularOptions {
            table_size: 1,
            ..opts
        },
        AngularOptions {
            energy_fraction: 1.0,
            ..opts
        },
    ] {
        assert!(AngularTable::new(1.3, &bad).is_err());
    }
}
