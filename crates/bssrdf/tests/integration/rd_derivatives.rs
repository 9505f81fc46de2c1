//! `Bssrdf::rd_derivatives`: the closed forms (dipoles, Christensen–Burley) and the spline
//! derivatives (photon beam diffusion, `mc-table`) against central differences of `rd` at
//! several radii, near r → 0 included, and finite values for huge and tiny coefficients.

use sss_bssrdf::*;

const RADIAL: [ModelKind; 5] = [
    ModelKind::StandardDipole,
    ModelKind::BetterDipole,
    ModelKind::Burley,
    ModelKind::PhotonBeamDiffusion,
    ModelKind::McTable,
];

/// The optical-radius knots of a tabulated model and the σ_t its profile is scaled by.
fn knots(kind: ModelKind, m: &Medium, ch: usize) -> Option<(Vec<f64>, f64)> {
    match kind {
        ModelKind::PhotonBeamDiffusion => Some((
            PhotonBeamDiffusion::new(m.clone())
                .table()
                .radius_samples()
                .to_vec(),
            m.sigma_t(ch),
        )),
        ModelKind::McTable => Some((
            McTableModel::new(m.clone())
                .table()
                .radius_samples()
                .to_vec(),
            m.sigma_t_reduced(ch),
        )),
        _ => None,
    }
}

/// For a tabulated model, `r` moved to the middle of its knot interval (the spline is C¹:
/// R″ jumps at knots), with the interval's width in mm; otherwise `r` and ∞.
fn placed(r: f64, k: &Option<(Vec<f64>, f64)>) -> (f64, f64) {
    let Some((knots, st)) = k else {
        return (r, f64::INFINITY);
    };
    let x = r * st;
    let i = knots.partition_point(|&k| k <= x).clamp(1, knots.len() - 1) - 1;
    (
        0.5 * (knots[i] + knots[i + 1]) / st,
        (knots[i + 1] - knots[i]) / st,
    )
}

#[test]
fn derivatives_match_central_differences_of_rd() {
    for preset in ["skin1", "marble", "ketchup"] {
        let m = Medium::preset(preset).unwrap();
        for kind in RADIAL {
            let model = make_model(kind, &m);
            for ch in 0..3 {
                let l = m.reduced_mean_free_path(ch);
                let k = knots(kind, &m, ch);
                for f in [1e-3, 0.03, 0.2, 0.7, 1.6, 4.0, 11.0] {
                    let (r, width) = placed(f * l, &k);
                    let (v, d1, d2) = model.rd_derivatives(ch, r);
                    let rd = model.rd(ch, r);
                    let label = format!("{kind} {preset} ch{ch} r = {r:e} mm");
                    assert!(
                        (v - rd).abs() <= 1e-12 * rd.abs(),
                        "{label}: value {v} vs rd {rd}"
                    );
                    if rd.is_nan() || rd <= 1e-200 {
                        continue;
                    }
                    let h = (1e-5 * r).min(1e-3 * width);
                    let (p, q) = (model.rd(ch, r + h), model.rd(ch, r - h));
                    let fd1 = (p - q) / (2.0 * h);
                    let fd2 = (p - 2.0 * rd + q) / (h * h);
                    // Scales: R/r and R/r² (the size of the derivatives of a power law).
                    let s1 = d1.abs() + rd / r;
                    let s2 = d2.abs() + rd / (r * r);
                    assert!(
                        (d1 - fd1).abs() <= 1e-6 * s1,
                        "{label}: R′ {d1:e} vs differences {fd1:e}"
                    );
                    assert!(
                        (d2 - fd2).abs() <= 2e-4 * s2,
                        "{label}: R″ {d2:e} vs differences {fd2:e}"
                    );
                    // The closed forms fall with r (a spline may wiggle near 0).
                    if k.is_none() {
                        assert!(d1 <= 0.0, "{label}: R′ = {d1:e} > 0");
                    }
                }
            }
        }
    }
}

#[test]
fn derivatives_are_finite_for_huge_and_tiny_coefficients_and_at_r_zero() {
    let mut kinds = RADIAL.to_vec();
    kinds.push(ModelKind::DirectionalDipole);
    for sigma_t in [1e-6, 1e-3, 1.0, 1e3, 1e6] {
        for albedo in [0.0, 1e-9, 0.5, 0.99, 1.0] {
            for eta in [1.0, 1.33] {
                let m = Medium::new(
                    [sigma_t * (1.0 - albedo); 3],
                    [sigma_t * albedo; 3],
                    0.0,
                    eta,
                )
                .unwrap();
                for &kind in &kinds {
                    let model = make_model(kind, &m);
                    let l = m.mean_free_path(0);
                    let mut radii = vec![0.0, 1e-300, 1e-12];
                    radii.extend([1e-9, 1e-6, 1e-3, 0.1, 1.0, 10.0, 1e3, 1e6].map(|k| k * l));
                    radii.push(1e300);
                    for r in radii {
                        let (v, d1, d2) = model.rd_derivatives(0, r);
                        let label = format!("{kind} σ_t {sigma_t} α {albedo} η {eta} r {r:e}");
                        assert!(
                            v.is_finite() && d1.is_finite() && d2.is_finite(),
                            "{label}: ({v}, {d1}, {d2})"
                        );
                        let rd = model.rd(0, r);
                        assert!(
                            (v - rd).abs() <= 1e-9 * rd.abs(),
                            "{label}: value {v} vs rd {rd}"
                        );
                        let closed =
                            !matches!(kind, ModelKind::PhotonBeamDiffusion | ModelKind::McTable);
                        if r == 0.0 && closed {
                            assert_eq!(d1, 0.0, "{label}: R′(0) = {d1}");
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn the_finite_difference_fallback_matches_a_closed_form() {
    // The default of the trait on a function with known derivatives: e^{−r}/(1 + r).
    let f = |r: f64| (-r).exp() / (1.0 + r);
    for r in [0.0, 1e-3, 0.5, 2.0, 7.0] {
        let (v, d1, d2) = rd_derivatives_by_differences(f, r, 1.0);
        // The even extension's derivatives: at r = 0 the first is 0 by symmetry.
        let e = (-r).exp();
        let want1 = -e / (1.0 + r) - e / ((1.0 + r) * (1.0 + r));
        let want2 = e / (1.0 + r) + 2.0 * e / (1.0 + r).powi(2) + 2.0 * e / (1.0 + r).powi(3);
        assert_eq!(v, f(r));
        if r > 0.0 {
            assert!((d1 - want1).abs() < 1e-6, "r {r}: {d1} vs {want1}");
            assert!((d2 - want2).abs() < 1e-5, "r {r}: {d2} vs {want2}");
        } else {
            assert_eq!(d1, 0.0);
        }
    }
}
