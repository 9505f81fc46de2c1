//! Eq. 3–5: the operators, B_a and s_p against closed forms computed by hand, and their edge
//! cases (grazing view, k = 0, negative k, d → 0).

use sss_bandwidth::transport::{curvature_operator, projection_operator, travel_operator};
use sss_bandwidth::{
    AngularOptions, AngularTable, BandwidthVector, MIN_COS_THETA_O, MaterialBandwidth,
    PixelFootprint, ShadeGeometry, sampling_rate_per_pixel, screen_angular_bandwidth,
};
use sss_bssrdf::{Medium, ModelKind, make_model};

fn geometry(k: f64, d: f64, cos: f64) -> ShadeGeometry {
    ShadeGeometry {
        curvature_per_mm: k,
        distance_mm: d,
        cos_theta_o: cos,
    }
}

const HD: PixelFootprint = PixelFootprint {
    fov_x_rad: 0.7,
    fov_y_rad: 0.4,
    width_px: 1920,
    height_px: 1080,
};

#[test]
fn plane_facing_the_camera_matches_eq_4_and_5_by_hand() {
    // B_s = 0.5 cycles/mm, B_θ = 2.2 cycles/rad, k = 0, θ_o = 0, d = 1000 mm:
    // B_a = 2.2 + 1000 · 0.5 / 1 = 502.2 cycles/rad. Pixels: 0.7/1920 = 3.6458e-4 rad,
    // 0.4/1080 = 3.7037e-4 rad, so s_p = 2 · 502.2 · 0.4/1080 = 0.372000 samples per pixel.
    let b = BandwidthVector {
        spatial_cycles_per_mm: 0.5,
        angular_cycles_per_radian: 2.2,
    };
    let ba = screen_angular_bandwidth(b, &geometry(0.0, 1000.0, 1.0), MIN_COS_THETA_O).unwrap();
    assert!((ba - 502.2).abs() < 1e-12);
    let sp = sampling_rate_per_pixel(ba, &HD).unwrap();
    assert!((sp - 0.372_000).abs() < 1e-6, "{sp}");
    assert!((HD.radians_per_pixel().unwrap() - 0.4 / 1080.0).abs() < 1e-18);

    // wave2.md F1.2's worked example: B_s ≈ 300 cycles/m = 0.3 cycles/mm, d = 1 m, a 40° field
    // of view over 1920 px (3.6e-4 rad/px): s_p ≈ 0.22, so P = 0.75/s_p ≈ 3.4 px.
    let skin = BandwidthVector {
        spatial_cycles_per_mm: 0.3,
        angular_cycles_per_radian: 0.0,
    };
    let square = PixelFootprint {
        fov_x_rad: 40f64.to_radians(),
        fov_y_rad: 40f64.to_radians(),
        width_px: 1920,
        height_px: 1920,
    };
    let sp = sampling_rate_per_pixel(
        screen_angular_bandwidth(skin, &geometry(0.0, 1000.0, 1.0), MIN_COS_THETA_O).unwrap(),
        &square,
    )
    .unwrap();
    assert!((sp - 0.218).abs() < 0.002, "{sp}");
    assert!((0.75 / sp - 3.4).abs() < 0.05);
}

#[test]
fn material_plane_facing_the_camera() {
    // The cached material: B_a = B_θ(0) + d · max_ch B_s at k = 0, θ_o = 0.
    let model = make_model(
        ModelKind::StandardDipole,
        &Medium::preset("marble").unwrap(),
    );
    let m = MaterialBandwidth::new(model.as_ref()).unwrap();
    let bs = m.spatial_cycles_per_mm();
    let max_bs = bs[0].max(bs[1]).max(bs[2]);
    assert_eq!(m.max_spatial_cycles_per_mm(), max_bs);
    let b_theta = m.angular().cycles_per_radian(0.0);
    let d = 2500.0;
    let by_hand = 2.0 * (b_theta + d * max_bs) * (0.4 / 1080.0);
    let sp = m
        .sampling_rate_per_pixel(&geometry(0.0, d, 1.0), &HD)
        .unwrap();
    assert!((sp - by_hand).abs() < 1e-12 * by_hand, "{sp} vs {by_hand}");
    assert_eq!(m.kind(), ModelKind::StandardDipole);
    assert_eq!(m.min_cos(), MIN_COS_THETA_O);
}

#[test]
fn operators_compose_to_eq_4() {
    // T_d P_x C_k [B_s, B_θ]ᵀ literally, against B_θ + d (B_s + k B_θ)/cos θ for k ≥ 0.
    let b = BandwidthVector {
        spatial_cycles_per_mm: 1.7,
        angular_cycles_per_radian: 3.1,
    };
    for (k, d, cos) in [
        (0.0, 10.0, 1.0),
        (0.2, 300.0, 0.5),
        (5.0, 0.5, 0.9),
        (0.01, 1e4, 0.05),
    ] {
        let out = b
            .apply(&curvature_operator(k))
            .apply(&projection_operator(cos))
            .apply(&travel_operator(d));
        let eq4 = 3.1 + d * (1.7 + k * 3.1) / cos;
        assert!((out.angular_cycles_per_radian - eq4).abs() < 1e-12 * eq4);
        // B_p, the spatial component after travel, is (B_s + k B_θ)/cos θ.
        assert!((out.spatial_cycles_per_mm - (1.7 + k * 3.1) / cos).abs() < 1e-12 * eq4);
        let ba = screen_angular_bandwidth(b, &geometry(k, d, cos), MIN_COS_THETA_O).unwrap();
        assert!((ba - eq4).abs() < 1e-12 * eq4);
    }
}

#[test]
fn edge_cases_are_finite_and_conservative() {
    let b = BandwidthVector {
        spatial_cycles_per_mm: 0.8,
        angular_cycles_per_radian: 2.5,
    };
    let ba = |k: f64, d: f64, cos: f64| {
        screen_angular_bandwidth(b, &geometry(k, d, cos), MIN_COS_THETA_O).unwrap()
    };
    // Grazing: 1/cos capped at 1/MIN_COS_THETA_O = 1000.
    let cap = 2.5 + 100.0 * (0.8 + 0.1 * 2.5) * 1000.0;
    for cos in [0.0, 1e-300, 1e-4, -0.0, -1e-6] {
        assert!((ba(0.1, 100.0, cos) - cap).abs() < 1e-9 * cap, "cos {cos}");
    }
    // Growing with obliquity up to the cap.
    assert!(ba(0.1, 100.0, 0.5) < ba(0.1, 100.0, 0.1));
    assert!(ba(0.1, 100.0, 0.1) < ba(0.1, 100.0, 0.01));
    // Back-facing cosines count as |cos|.
    assert_eq!(ba(0.1, 100.0, -0.3), ba(0.1, 100.0, 0.3));
    // Negative curvature counts as |k|; k = 0 leaves B_s alone.
    assert_eq!(ba(-0.4, 100.0, 0.7), ba(0.4, 100.0, 0.7));
    assert!((ba(0.0, 100.0, 0.7) - (2.5 + 100.0 * 0.8 / 0.7)).abs() < 1e-12);
    assert!(ba(0.4, 100.0, 0.7) > ba(0.0, 100.0, 0.7));
    // d → 0: B_a → B_θ, at any angle and curvature.
    for (k, cos) in [(0.0, 1.0), (10.0, 0.0), (-3.0, 0.2)] {
        assert_eq!(ba(k, 0.0, cos), 2.5);
        assert!((ba(k, 1e-12, cos) - 2.5).abs() < 1e-6);
    }
    // A caller's own clamp.
    let wide = screen_angular_bandwidth(b, &geometry(0.0, 1.0, 0.0), 0.1).unwrap();
    assert!((wide - (2.5 + 0.8 / 0.1)).abs() < 1e-12);
}

#[test]
fn material_at_grazing_angles_uses_the_grazing_angular_bandwidth() {
    let table = AngularTable::new(1.3, &AngularOptions::default()).unwrap();
    let grazing = table.cycles_per_radian(std::f64::consts::FRAC_PI_2);
    let m = MaterialBandwidth::from_parts(ModelKind::BetterDipole, [0.2, 0.4, 0.6], table, 0.01)
        .unwrap();
    let g = geometry(-0.05, 800.0, 0.0);
    let expected = grazing + 800.0 * (0.6 + 0.05 * grazing) / 0.01;
    let ba = m.screen_angular_bandwidth(&g).unwrap();
    assert!(
        (ba - expected).abs() < 1e-9 * expected,
        "{ba} vs {expected}"
    );
    let sp = m.sampling_rate_per_pixel(&g, &HD).unwrap();
    assert!(sp.is_finite() && sp > 0.0);
}

#[test]
fn bad_input_is_an_error() {
    let b = BandwidthVector {
        spatial_cycles_per_mm: 0.8,
        angular_cycles_per_radian: 2.5,
    };
    for g in [
        geometry(f64::NAN, 1.0, 1.0),
        geometry(f64::INFINITY, 1.0, 1.0),
        geometry(0.0, -1.0, 1.0),
        geometry(0.0, f64::NAN, 1.0),
        geometry(0.0, f64::INFINITY, 1.0),
        geometry(0.0, 1.0, f64::NAN),
    ] {
        assert!(
            screen_angular_bandwidth(b, &g, MIN_COS_THETA_O).is_err(),
            "{g:?}"
        );
    }
    for bad in [
        BandwidthVector {
            spatial_cycles_per_mm: -1.0,
            angular_cycles_per_radian: 1.0,
        },
        BandwidthVector {
            spatial_cycles_per_mm: 1.0,
            angular_cycles_per_radian: f64::NAN,
        },
        // Each check on its own: an infinite B_s, a negative or infinite B_θ.
        BandwidthVector {
            spatial_cycles_per_mm: f64::INFINITY,
            angular_cycles_per_radian: 1.0,
        },
        BandwidthVector {
            spatial_cycles_per_mm: 1.0,
            angular_cycles_per_radian: -1.0,
        },
        BandwidthVector {
            spatial_cycles_per_mm: 1.0,
            angular_cycles_per_radian: f64::INFINITY,
        },
    ] {
        assert!(screen_angular_bandwidth(bad, &geometry(0.0, 1.0, 1.0), MIN_COS_THETA_O).is_err());
    }
    for min_cos in [0.0, -0.1, 1.5, f64::NAN] {
        assert!(screen_angular_bandwidth(b, &geometry(0.0, 1.0, 1.0), min_cos).is_err());
    }
    // Overflow is reported, not returned as ∞.
    let huge = BandwidthVector {
        spatial_cycles_per_mm: 1e300,
        angular_cycles_per_radian: 0.0,
    };
    assert!(screen_angular_bandwidth(huge, &geometry(0.0, 1e300, 1.0), MIN_COS_THETA_O).is_err());
    for fp in [
        PixelFootprint {
            fov_x_rad: 0.0,
            ..HD
        },
        PixelFootprint {
            fov_y_rad: f64::NAN,
            ..HD
        },
        PixelFootprint {
            fov_x_rad: 7.0,
            ..HD
        },
        // The documented interval (0, 2π) is open: a full turn is refused.
        PixelFootprint {
            fov_y_rad: std::f64::consts::TAU,
            ..HD
        },
        PixelFootprint { width_px: 0, ..HD },
        PixelFootprint { height_px: 0, ..HD },
    ] {
        assert!(sampling_rate_per_pixel(1.0, &fp).is_err(), "{fp:?}");
    }
    assert!(sampling_rate_per_pixel(-1.0, &HD).is_err());
    assert!(sampling_rate_per_pixel(f64::INFINITY, &HD).is_err());
    let table = AngularTable::new(1.3, &AngularOptions::default()).unwrap();
    assert!(
        MaterialBandwidth::from_parts(ModelKind::Burley, [f64::NAN, 0.0, 0.0], table.clone(), 0.1)
            .is_err()
    );
    assert!(
        MaterialBandwidth::from_parts(ModelKind::Burley, [1.0; 3], table.clone(), 2.0).is_err()
    );
    // Each condition on its own: a finite negative bandwidth, an infinite one, and
    // min_cos = 0 (the interval (0, 1] is open at 0).
    for b in [[-1.0, 0.0, 0.0], [0.0, f64::INFINITY, 0.0]] {
        assert!(
            MaterialBandwidth::from_parts(ModelKind::Burley, b, table.clone(), 0.1).is_err(),
            "{b:?}"
        );
    }
    assert!(
        MaterialBandwidth::from_parts(ModelKind::Burley, [1.0; 3], table.clone(), 0.0).is_err()
    );
    assert!(MaterialBandwidth::from_parts(ModelKind::Burley, [1.0; 3], table, 1.0).is_ok());
}
