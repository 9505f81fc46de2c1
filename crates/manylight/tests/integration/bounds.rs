//! The bounds bound: on random cluster triplets, R_d^u, G^u, F_t^u, the sample bound M_j, the
//! error bound e_j and the common upper term of Eq. 11–13 are never below the values they
//! bound, sampled densely inside the clusters (corners included). Also the model checks and
//! the Student-t table against published quantiles.

use glam::DVec3;
use sss_manylight::bounds::*;
use sss_manylight::*;

use crate::common::U;

/// A dipole-like profile: (1 + σr) e^{−σr} / (r² + z²)^{3/2}-shaped, strictly decreasing.
fn rd(r: f64) -> [f64; 3] {
    [(2.0, 0.1), (5.0, 0.05), (12.0, 0.02)].map(|(s, z): (f64, f64)| {
        let d = (r * r + z * z).sqrt();
        (1.0 + s * d) * (-s * d).exp() / (d * d * d) * z
    })
}

/// Exact dielectric transmittance 1 − F_r for η = 1.4 (Fresnel equations, unpolarised).
fn ft(cos_i: f64) -> f64 {
    let eta: f64 = 1.4;
    let sin_t2 = (1.0 - cos_i * cos_i) / (eta * eta);
    let cos_t = (1.0 - sin_t2).max(0.0).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    1.0 - 0.5 * (rs * rs + rp * rp)
}

/// Points in a random box: its 8 corners and `n` random interior points.
fn points_in(b: &Aabb, n: usize, u: &mut U) -> Vec<DVec3> {
    let mut p: Vec<DVec3> = (0..8)
        .map(|k| {
            DVec3::new(
                if k & 1 == 0 { b.min.x } else { b.max.x },
                if k & 2 == 0 { b.min.y } else { b.max.y },
                if k & 4 == 0 { b.min.z } else { b.max.z },
            )
        })
        .collect();
    p.extend((0..n).map(|_| b.min + u.v() * (b.max - b.min)));
    p
}

fn random_box(u: &mut U, spread: f64) -> Aabb {
    let c = (u.v() - 0.5) * spread;
    let h = u.v() * u.v() * 0.5; // from points to wide boxes
    Aabb {
        min: c - h,
        max: c + h,
    }
}

#[test]
fn rd_g_ft_and_error_bounds_are_never_exceeded() {
    let profile = RadialProfile::new(rd, 10.0).unwrap();
    let trans = Transmittance::new(ft).unwrap();
    let g_max = 400.0;
    let mut u = U(11);
    let mut tight = 0usize;
    for trial in 0..400 {
        let (lc, ic, sc) = (
            random_box(&mut u, 2.0),
            random_box(&mut u, 2.0),
            random_box(&mut u, 2.0),
        );
        let (ps_l, ps_i, ps_s) = (
            points_in(&lc, 12, &mut u),
            points_in(&ic, 12, &mut u),
            points_in(&sc, 12, &mut u),
        );
        let rd_u = rd_upper(&profile, &ic, &sc);
        let g_u = g_upper(&lc, &ic, g_max);
        let ft_u = ft_upper(&trans, 1.0);
        let (a, w, i) = (0.1 + u.f(), 0.1 + u.f(), 0.1 + u.f());
        let m = sample_bound(a, w, i, rd_u, g_u, ft_u);
        let e = error_bound(m, 2);
        assert!((e - m / (2.0 * 2f64.sqrt())).abs() <= 1e-15 * m);
        let sphere_upper =
            selection_upper(&lc.sphere(), &ic.sphere(), &sc.sphere(), &profile, g_max);
        let lower = selection_lower(&lc.sphere(), &ic.sphere(), &sc.sphere(), &profile, g_max);
        for l in lower {
            assert!(
                l <= sphere_upper * (1.0 + 1e-12),
                "lower {l} above upper {sphere_upper}"
            );
        }
        // Exhaustive over the point sets: all L × I × S combinations.
        let mut values = Vec::new();
        let mut rd_seen = 0.0f64;
        for xi in &ps_i {
            for xo in &ps_s {
                let r = xi.distance(*xo);
                let v = rd(r);
                let vmax = v[0].max(v[1]).max(v[2]);
                assert!(
                    vmax <= rd_u * (1.0 + 1e-12),
                    "trial {trial}: R_d {vmax} > {rd_u}"
                );
                rd_seen = rd_seen.max(vmax);
                for y in &ps_l {
                    let d2 = y.distance_squared(*xi);
                    let g = (1.0 / d2).min(g_max);
                    assert!(g <= g_u * (1.0 + 1e-12), "trial {trial}: G {g} > {g_u}");
                    // R_d/d² against the sphere-based common upper term of Eq. 11–13.
                    assert!(vmax * g <= sphere_upper * (1.0 + 1e-12));
                    // A sample with random cosines, colour and transmittance.
                    let (ci, cy) = (u.f(), u.f());
                    let col = [u.f(), u.f(), u.f()];
                    let lum = luminance(col);
                    let rho = (0..3).map(|c| LUMINANCE[c] * col[c] * v[c]).sum::<f64>() / lum;
                    let f = a * w * i * rho * ci * cy * g * ft(ci);
                    assert!(ft(ci) <= ft_u * (1.0 + 1e-12));
                    assert!(f <= m * (1.0 + 1e-12), "trial {trial}: sample {f} > M {m}");
                    values.push(f);
                }
            }
        }
        // Popoviciu: the standard deviation of any such sample set is ≤ M/2, so that of the
        // two-sample mean is ≤ e_j.
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let sd = (values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n).sqrt();
        assert!(
            sd / 2f64.sqrt() <= e * (1.0 + 1e-12),
            "trial {trial}: {sd} vs e {e}"
        );
        // The R_d bound is attained when the boxes are apart (a corner pair realises r_min
        // along one axis only, so count how often it is within 1 %).
        if rd_seen >= 0.99 * rd_u {
            tight += 1;
        }
    }
    // The bound is not vacuous: often nearly attained by the sampled points.
    assert!(
        tight > 40,
        "R_d bound nearly attained in {tight} of 400 trials"
    );
}

#[test]
fn box_distances_bound_point_distances() {
    let mut u = U(5);
    for _ in 0..300 {
        let (a, b) = (random_box(&mut u, 3.0), random_box(&mut u, 3.0));
        let (pa, pb) = (points_in(&a, 20, &mut u), points_in(&b, 20, &mut u));
        let (lo, hi) = (a.min_distance_sq(&b), a.max_distance_sq(&b));
        let mut seen_lo = f64::INFINITY;
        let mut seen_hi = 0.0f64;
        for p in &pa {
            for q in &pb {
                let d = p.distance_squared(*q);
                assert!(d >= lo * (1.0 - 1e-12) - 1e-15 && d <= hi * (1.0 + 1e-12) + 1e-15);
                seen_lo = seen_lo.min(d);
                seen_hi = seen_hi.max(d);
            }
        }
        // The maximum is attained at corners, exactly.
        assert!((seen_hi - hi).abs() <= 1e-12 * hi);
    }
}

#[test]
fn monotone_models_are_accepted_and_others_refused() {
    assert!(RadialProfile::new(rd, 10.0).is_ok());
    // Rising somewhere: refused with a clear error.
    let bump = |r: f64| [(-r).exp() + if (1.0..1.5).contains(&r) { 0.1 } else { 0.0 }; 3];
    assert!(matches!(
        RadialProfile::new(bump, 2.0),
        Err(Error::InvalidModel(_))
    ));
    assert!(matches!(
        RadialProfile::new(|_| [f64::NAN; 3], 1.0),
        Err(Error::InvalidModel(_))
    ));
    assert!(matches!(
        RadialProfile::new(|r| [-r; 3], 1.0),
        Err(Error::InvalidModel(_))
    ));
    assert!(RadialProfile::new(rd, 0.0).is_err());
    // Dielectric F_t rises with cos θ: accepted, bound = normal incidence = 1 − ((η−1)/(η+1))².
    let t = Transmittance::new(ft).unwrap();
    assert!((t.max() - (1.0 - (0.4f64 / 2.4).powi(2))).abs() < 1e-12);
    assert!(Transmittance::new(|c| 1.0 - c).is_err());
    assert!(Transmittance::new(|_| 1.5).is_err());
}

/// Two-sided 95 % and 99 % quantiles against printed tables (e.g. NIST/SEMATECH e-Handbook
/// §1.3.6.7.2), and the large-ν expansion against t_{0.975, 10⁴} = 1.960201 and the normal
/// quantile 1.959964.
#[test]
fn student_t_quantiles_match_published_tables() {
    let t95 = StudentT::new(0.95).unwrap();
    for (nu, want) in [
        (1, 12.706),
        (2, 4.303),
        (5, 2.571),
        (10, 2.228),
        (30, 2.042),
        (100, 1.984),
    ] {
        assert!(
            (t95.quantile(nu) - want).abs() < 6e-4,
            "ν = {nu}: {}",
            t95.quantile(nu)
        );
    }
    assert!((t95.quantile(10_000) - 1.960201).abs() < 2e-6);
    assert!((t95.quantile(10_000_000) - 1.959964).abs() < 2e-6);
    // Decreasing in ν and smooth across the table edge: the step from the last tabulated
    // value to the first expanded one equals the step before it (≈ 1.4e-7) to 1e-9.
    let edge = confidence::TABLE_DOF;
    let q = |nu| t95.quantile(nu);
    assert!(q(edge - 1) > q(edge) && q(edge) > q(edge + 1));
    assert!(((q(edge) - q(edge + 1)) - (q(edge - 1) - q(edge))).abs() < 1e-9);
    let t99 = StudentT::new(0.99).unwrap();
    assert!((t99.quantile(1) - 63.657).abs() < 1e-3);
    assert!((t99.quantile(10) - 3.169).abs() < 1e-3);
    assert!(StudentT::new(1.0).is_err() && StudentT::new(0.0).is_err());
}
