//! B_s of the models of `sss-bssrdf`: convergence of the grid, growth with σ_tr, the exact
//! scaling law, and finiteness on extreme media.

use sss_bandwidth::spatial::{model_grid, spatial_bandwidth_on_grid};
use sss_bandwidth::spectrum::SpectrumGrid;
use sss_bandwidth::{
    BandwidthError, MaterialBandwidth, SpatialOptions, spatial_bandwidth_cycles_per_mm,
    spatial_bandwidths_cycles_per_mm,
};
use sss_bssrdf::{Medium, ModelKind, make_model};

#[test]
fn halving_the_step_changes_b_s_by_less_than_one_percent() {
    let opts = SpatialOptions::default();
    for preset in ["skin1", "marble", "ketchup"] {
        let medium = Medium::preset(preset).unwrap();
        for kind in ModelKind::ALL {
            let model = make_model(kind, &medium);
            for ch in [0, 2] {
                let grid = model_grid(model.as_ref(), ch, &opts).unwrap();
                // Same extent, half the step.
                let fine = SpectrumGrid::new(grid.step_mm() / 2.0, 2 * grid.cells()).unwrap();
                let b = spatial_bandwidth_on_grid(model.as_ref(), ch, &grid, &opts).unwrap();
                let b_fine = spatial_bandwidth_on_grid(model.as_ref(), ch, &fine, &opts).unwrap();
                let rel = (b_fine - b).abs() / b;
                assert!(
                    rel < 0.01,
                    "{preset} {kind} ch {ch}: {b} vs {b_fine} ({rel:.2e})"
                );
                if kind != ModelKind::DirectionalDipole {
                    // The automatic choice is this grid (checked for the cheap models).
                    assert_eq!(
                        b,
                        spatial_bandwidth_cycles_per_mm(model.as_ref(), ch, &opts).unwrap()
                    );
                }
            }
        }
    }
}

#[test]
fn b_s_grows_with_sigma_tr() {
    // σ_a up at fixed σ_s: σ_tr = √(3σ_a σ'_t) grows, the profile narrows.
    let opts = SpatialOptions::default();
    for kind in ModelKind::ALL {
        let mut previous = 0.0;
        for sigma_a in [1e-3, 1e-2, 0.1, 1.0, 10.0] {
            let medium = Medium::new([sigma_a; 3], [1.0; 3], 0.0, 1.3).unwrap();
            let b = spatial_bandwidth_cycles_per_mm(make_model(kind, &medium).as_ref(), 1, &opts)
                .unwrap();
            assert!(
                b > previous,
                "{kind}: σ_a = {sigma_a} gives {b} ≤ {previous}"
            );
            previous = b;
        }
        // From σ_tr ≈ 0.05 to ≈ 18 per mm the bandwidth grows severalfold.
        let lo = Medium::new([1e-3; 3], [1.0; 3], 0.0, 1.3).unwrap();
        let b_lo =
            spatial_bandwidth_cycles_per_mm(make_model(kind, &lo).as_ref(), 0, &opts).unwrap();
        assert!(previous > 5.0 * b_lo, "{kind}: {previous} vs {b_lo}");
    }
}

#[test]
fn b_s_scales_exactly_with_the_coefficients() {
    // Multiplying σ_a and σ_s by c divides every length by c (the diffusion models are
    // functions of σ·r), so B_s is multiplied by c, for every model and every channel.
    let opts = SpatialOptions::default();
    let skin = Medium::preset("skin1").unwrap();
    for kind in ModelKind::ALL {
        let base =
            spatial_bandwidths_cycles_per_mm(make_model(kind, &skin).as_ref(), &opts).unwrap();
        for c in [1e-3, 7.0, 1e4] {
            let scaled = Medium::new(
                skin.sigma_a().map(|v| v * c),
                skin.sigma_s().map(|v| v * c),
                skin.g(),
                skin.eta(),
            )
            .unwrap();
            let b = spatial_bandwidths_cycles_per_mm(make_model(kind, &scaled).as_ref(), &opts)
                .unwrap();
            for ch in 0..3 {
                let rel = (b[ch] / (c * base[ch]) - 1.0).abs();
                assert!(
                    rel < 1e-3,
                    "{kind} ×{c} ch {ch}: {} vs {}",
                    b[ch],
                    c * base[ch]
                );
            }
        }
        // Red scatters farthest in skin: the lowest bandwidth.
        assert!(base[0] < base[1] && base[1] < base[2], "{kind}: {base:?}");
    }
}

#[test]
fn the_directional_dipole_takes_the_maximum_over_incidence() {
    // At normal incidence the directional dipole's profile is radial and its 2-D grid gives
    // the same B_s as a radial transform of R(r) = rd(r); oblique incidence can only raise
    // the maximum.
    let opts = SpatialOptions::default();
    let medium = Medium::preset("marble").unwrap();
    let model = make_model(ModelKind::DirectionalDipole, &medium);
    let grid = model_grid(model.as_ref(), 1, &opts).unwrap();
    let r_floor = opts.floor_mfp_fraction / medium.sigma_t_reduced(1);
    let normal = sss_bandwidth::spectrum::radial_bandwidth_cycles_per_mm(
        |r| model.rd(1, r.hypot(r_floor)),
        &grid,
        opts.energy_fraction,
    )
    .unwrap();
    let max = spatial_bandwidth_on_grid(model.as_ref(), 1, &grid, &opts).unwrap();
    assert!(max >= normal * 0.99, "{max} vs {normal}");
}

#[test]
fn extreme_media_give_finite_bandwidths() {
    let opts = SpatialOptions::default();
    let cases: [([f64; 3], [f64; 3], f64, f64); 8] = [
        ([0.0; 3], [1.0; 3], 0.0, 1.3),   // albedo 1
        ([1.0; 3], [0.0; 3], 0.0, 1.3),   // albedo 0
        ([1e-6; 3], [1e-6; 3], 0.0, 1.3), // tiny coefficients
        ([1e6; 3], [1e6; 3], 0.0, 1.3),   // huge coefficients
        ([1e-8; 3], [1e6; 3], 0.9, 1.0),  // albedo → 1, forward scattering, η = 1
        ([1e6; 3], [1e-8; 3], -0.9, 0.7), // albedo → 0, η < 1
        ([0.01, 1.0, 100.0], [10.0, 1.0, 0.01], 0.0, 0.5),
        ([1e-3, 0.0, 5.0], [0.0, 3.0, 1e3], 0.5, 2.5),
    ];
    for (sigma_a, sigma_s, g, eta) in cases {
        let medium = Medium::new(sigma_a, sigma_s, g, eta).unwrap();
        for kind in ModelKind::ALL {
            let b = spatial_bandwidths_cycles_per_mm(make_model(kind, &medium).as_ref(), &opts)
                .unwrap();
            for (ch, v) in b.iter().enumerate() {
                assert!(
                    v.is_finite() && *v >= 0.0,
                    "{kind} {sigma_a:?} {sigma_s:?} ch {ch}: {v}"
                );
                // No scattering, no subsurface transport: a zero profile has bandwidth 0;
                // otherwise the bandwidth is positive.
                if sigma_s[ch] == 0.0 {
                    assert_eq!(*v, 0.0, "{kind} ch {ch}");
                } else {
                    assert!(*v > 0.0, "{kind} {sigma_a:?} {sigma_s:?} ch {ch}");
                }
            }
        }
    }
}

#[test]
fn absurd_coefficients_follow_the_scaling_law() {
    // Outside σ'_t ∈ [1e-3, 1e3] the profiles over- or underflow f64; B_s still scales as c.
    let opts = SpatialOptions::default();
    let unit = Medium::new([0.05; 3], [0.95; 3], 0.0, 1.3).unwrap();
    for kind in ModelKind::ALL {
        let b1 =
            spatial_bandwidth_cycles_per_mm(make_model(kind, &unit).as_ref(), 0, &opts).unwrap();
        for c in [1e-300, 1e-150, 1e150, 1e300] {
            let m = Medium::new([0.05 * c; 3], [0.95 * c; 3], 0.0, 1.3).unwrap();
            let b =
                spatial_bandwidth_cycles_per_mm(make_model(kind, &m).as_ref(), 0, &opts).unwrap();
            assert!(
                b.is_finite() && (b / (c * b1) - 1.0).abs() < 1e-3,
                "{kind} ×{c}: {b} vs {}",
                c * b1
            );
        }
        // Wildly different scales per channel, and an albedo of 1e-300.
        let m = Medium::new([1e150, 1.0, 1e-3], [1e-150, 1e-300, 1e-200], 0.0, 1.3).unwrap();
        let b = spatial_bandwidths_cycles_per_mm(make_model(kind, &m).as_ref(), &opts).unwrap();
        assert!(
            b.iter().all(|v| v.is_finite() && *v >= 0.0),
            "{kind}: {b:?}"
        );
    }
}

#[test]
fn bad_options_are_errors() {
    let model = make_model(ModelKind::BetterDipole, &Medium::preset("skin1").unwrap());
    let d = SpatialOptions::default();
    for bad in [
        SpatialOptions {
            energy_fraction: 0.0,
            ..d
        },
        SpatialOptions {
            floor_mfp_fraction: 0.0,
            ..d
        },
        SpatialOptions {
            floor_mfp_fraction: f64::NAN,
            ..d
        },
        SpatialOptions {
            steps_per_floor: 0.5,
            ..d
        },
        SpatialOptions { cells: 8, ..d },
        SpatialOptions {
            coarse_cells: 1 << 20,
            ..d
        },
        SpatialOptions {
            nyquist_factor: 0.5,
            ..d
        },
    ] {
        assert!(matches!(
            spatial_bandwidth_cycles_per_mm(model.as_ref(), 0, &bad),
            Err(BandwidthError::InvalidArgument(_))
        ));
    }
    assert!(spatial_bandwidth_cycles_per_mm(model.as_ref(), 3, &d).is_err());
    assert!(
        MaterialBandwidth::with_options(
            model.as_ref(),
            &d,
            &sss_bandwidth::AngularOptions::default(),
            0.0
        )
        .is_err()
    );
}
