//! The fast samplers and table lookups
//! against independent references, for every model over extreme media.
//!
//! - `pdf_sr` integrates to 1 and `sample_sr(u)` is the exact u-quantile of `pdf_sr`: the
//!   CDF is computed here by Gauss-Legendre quadrature of `pdf_sr` on a fine geometric grid,
//!   independently of the samplers' tables.
//! - A Kolmogorov-Smirnov test of seeded random samples against the same CDF.
//! - Photon beam diffusion's per-channel rows give the same values and samples as the
//!   tensor-product interpolation of the shared table (the code path before this change).

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;
use sss_bssrdf::catmull_rom::sample_catmull_rom_2d;
use sss_bssrdf::quadrature::integrate;
use sss_bssrdf::*;
use std::f64::consts::PI;

/// Media with extreme albedos (0, 10⁻⁶, near 1, 1), tiny and huge extinction, and a spread of
/// g and η; three albedos per medium, one per channel.
fn media() -> Vec<Medium> {
    let mut out = Vec::new();
    for st in [1e-4, 1.0, 1e4] {
        for (g, eta) in [(0.0, 1.33), (0.9, 1.5), (-0.5, 1.0)] {
            for albedos in [[1e-6, 0.3, 0.9], [0.999, 1.0 - 1e-9, 1.0]] {
                let sigma_t = [st, 2.0 * st, 0.5 * st];
                out.push(Medium::from_extinction_albedo(sigma_t, albedos, g, eta).unwrap());
            }
        }
    }
    out.push(Medium::from_extinction_albedo([1.0; 3], [0.0, 0.5, 0.999999], 0.0, 1.33).unwrap());
    out
}

/// Cumulative integral of `pdf_sr` on a geometric grid (ratio 1.01 from 10⁻⁹ reduced mean
/// free paths to 10⁹, plus the end of the sampler's support, 6-point Gauss-Legendre per
/// panel), with Gauss-Legendre from the last knot for values between knots.
struct Cdf<'a> {
    model: &'a dyn Bssrdf,
    ch: usize,
    grid: Vec<f64>,
    cum: Vec<f64>,
}

impl<'a> Cdf<'a> {
    fn new(model: &'a dyn Bssrdf, ch: usize) -> Self {
        let scale = model.medium().reduced_mean_free_path(ch).min(1e300);
        let mut grid = vec![0.0];
        let mut r = 1e-9 * scale;
        while r < 1e9 * scale {
            grid.push(r);
            r *= 1.01;
        }
        // The end of a tabulated support (PBD, mc-table: the last radius node, where the pdf
        // drops to 0) must be a panel edge.
        let end = model.sample_sr(ch, 1.0);
        if end > 0.0 && end < *grid.last().unwrap() {
            let k = grid.partition_point(|&g| g < end);
            grid.insert(k, end);
        }
        let pdf = |r: f64| model.pdf_sr(ch, r);
        let mut cum = vec![0.0];
        for w in grid.windows(2) {
            let last = *cum.last().unwrap();
            cum.push(last + integrate(&pdf, w[0], w[1], 6));
        }
        Cdf {
            model,
            ch,
            grid,
            cum,
        }
    }

    fn total(&self) -> f64 {
        *self.cum.last().unwrap()
    }

    fn at(&self, x: f64) -> f64 {
        let k = self.grid.partition_point(|&g| g <= x);
        if k >= self.grid.len() {
            return self.total();
        }
        let k = k.max(1) - 1;
        self.cum[k] + integrate(&|r: f64| self.model.pdf_sr(self.ch, r), self.grid[k], x, 6)
    }
}

/// Quadrature tolerance of the quantile check: the directional dipole's pdf is piecewise
/// linear (kinks inside Gauss panels), and so are the segments of `mc-table` rows straightened
/// to keep R_d non-increasing (`SplineRow::monotone_over_x`); the others are smooth or C¹
/// splines.
fn tolerance(kind: ModelKind) -> f64 {
    match kind {
        ModelKind::DirectionalDipole | ModelKind::McTable => 2e-7,
        _ => 1e-8,
    }
}

#[test]
fn pdf_integrates_to_one_and_samples_are_its_quantiles() {
    // Largest |∫ pdf − 1| and |CDF(sample(u)) − u| per model, with where they occurred.
    const N: usize = ModelKind::ALL.len();
    let mut worst_total: [(f64, String); N] = std::array::from_fn(|_| (0.0, String::new()));
    let mut worst_quantile: [(f64, String); N] = std::array::from_fn(|_| (0.0, String::new()));
    for m in media() {
        for (ki, kind) in ModelKind::ALL.into_iter().enumerate() {
            let model = make_model(kind, &m);
            for ch in 0..3 {
                let label = format!(
                    "{kind} ch{ch} albedo {} σt {} g {} η {}",
                    m.albedo(ch),
                    m.sigma_t(ch),
                    m.g(),
                    m.eta()
                );
                let cdf = Cdf::new(model.as_ref(), ch);
                let err = (cdf.total() - 1.0).abs();
                if err > worst_total[ki].0 {
                    worst_total[ki] = (err, label.clone());
                }
                for k in 0..=64 {
                    let u = (k as f64 + 0.5) / 65.5;
                    let r = model.sample_sr(ch, u);
                    assert!(r.is_finite() && r >= 0.0, "{label}: sample({u}) = {r}");
                    let p = model.pdf_sr(ch, r);
                    assert!(p.is_finite() && p > 0.0, "{label}: pdf({r}) = {p}");
                    let err = (cdf.at(r) - u).abs();
                    if err > worst_quantile[ki].0 {
                        worst_quantile[ki] = (err, format!("{label} u {u}"));
                    }
                }
                for u in [0.0, 1e-12, 1.0 - 1e-12, 1.0, f64::NAN] {
                    let r = model.sample_sr(ch, u);
                    assert!(r.is_finite() && r >= 0.0, "{label}: sample({u}) = {r}");
                }
            }
        }
    }
    for (ki, kind) in ModelKind::ALL.into_iter().enumerate() {
        println!(
            "{kind}: |∫pdf − 1| ≤ {:.3e} ({}), |CDF(sample(u)) − u| ≤ {:.3e} ({})",
            worst_total[ki].0, worst_total[ki].1, worst_quantile[ki].0, worst_quantile[ki].1
        );
    }
    for (ki, kind) in ModelKind::ALL.into_iter().enumerate() {
        let tol = tolerance(kind);
        assert!(
            worst_total[ki].0 < tol,
            "{kind}: ∫ pdf off by {:?}",
            worst_total[ki]
        );
        assert!(
            worst_quantile[ki].0 < tol,
            "{kind}: quantile off by {:?}",
            worst_quantile[ki]
        );
    }
}

#[test]
fn ks_test_of_random_samples() {
    // Critical value at significance 10⁻⁶ per case: √(ln(2·10⁶)/2)/√n ≈ 2.69/√n.
    let n = 10_000;
    let crit = 2.69 / (n as f64).sqrt();
    for (mi, m) in media().into_iter().enumerate() {
        for kind in ModelKind::ALL {
            let model = make_model(kind, &m);
            for ch in 0..3 {
                let cdf = Cdf::new(model.as_ref(), ch);
                let mut rng = Pcg64Mcg::seed_from_u64(1000 * mi as u64 + ch as u64);
                let mut xs: Vec<f64> = (0..n)
                    .map(|_| model.sample_sr(ch, rng.random::<f64>()))
                    .collect();
                xs.sort_by(f64::total_cmp);
                let mut d = 0.0f64;
                for (i, &x) in xs.iter().enumerate() {
                    let c = cdf.at(x) / cdf.total();
                    d = d
                        .max((c - i as f64 / n as f64).abs())
                        .max((c - (i + 1) as f64 / n as f64).abs());
                }
                assert!(
                    d < crit,
                    "{kind} ch{ch} albedo {} σt {}: KS {d} >= {crit}",
                    m.albedo(ch),
                    m.sigma_t(ch)
                );
            }
        }
    }
}

#[test]
fn pbd_rows_equal_the_tensor_interpolation() {
    // The pre-blended rows must reproduce the per-call tensor spline of the shared table
    // (`PbdTable::interpolate_profile`, `sample_catmull_rom_2d`: the code path before the
    // rows) up to rounding: 10⁻¹² relative, plus 10⁻¹⁴ of the largest tabulated value of the
    // four knots around x (the power-basis evaluation rounds at the scale of the segment's
    // values, which matters only where the tail falls by 10¹⁵ within one interval).
    let mut compared = 0;
    for m in media() {
        let model = PhotonBeamDiffusion::new(m.clone());
        let t = model.table();
        let knots = t.radius_samples();
        for ch in 0..3 {
            let (st, rho) = (m.sigma_t(ch), m.albedo(ch));
            for k in 1..=400 {
                let x = t.max_optical_radius() * (k as f64 / 400.0).powi(4);
                let r = x / st;
                let p = t.interpolate_profile(rho, x).unwrap();
                let to_rd = |p: f64| p / (2.0 * PI * x) * st * st;
                let reference = to_rd(p).max(0.0);
                let i = knots.partition_point(|&k| k <= x).clamp(1, knots.len() - 1) - 1;
                let local = (i.saturating_sub(1)..(i + 3).min(knots.len()))
                    .map(|j| t.interpolate_profile(rho, knots[j]).unwrap().abs())
                    .fold(0.0, f64::max);
                let got = model.rd(ch, r);
                assert!(
                    (got - reference).abs() <= 1e-12 * reference + 1e-14 * to_rd(local),
                    "ch {ch} x {x}: {got} vs {reference}"
                );
            }
            // Samples: the same as before wherever the old spline had no negative lobe (where
            // it had one, the old pair was inconsistent and the quantile test above covers
            // the new one).
            let negative = (0..=20_000).any(|k| {
                let x = t.max_optical_radius() * (k as f64 / 20_000.0).powi(3);
                t.interpolate_profile(rho, x).unwrap() < 0.0
            });
            if negative || model.total_diffuse_reflectance(ch) <= 0.0 {
                continue;
            }
            compared += 1;
            for k in 0..200 {
                let u = (k as f64 + 0.5) / 200.0;
                let (x, _, _) = sample_catmull_rom_2d(
                    t.rho_samples(),
                    t.radius_samples(),
                    t.profile_values(),
                    t.profile_cdf_values(),
                    rho,
                    u,
                );
                let got = model.sample_sr(ch, u) * st;
                // Both solve CDF(x) = u by Newton-bisection to ~10⁻¹³ of the segment's
                // values: compare the mass between the two answers (trapezoid, so an answer
                // at r = 0, where the pdf in r vanishes, still counts).
                let pdf_mean = 0.5 * (model.pdf_sr(ch, x / st) + model.pdf_sr(ch, got / st));
                let mass = (got - x).abs() * pdf_mean / st;
                assert!(mass <= 1e-10, "ch {ch} u {u}: {got} vs {x}");
            }
        }
    }
    println!("{compared} channels sampled identically");
    assert!(compared >= 20, "{compared}");
}
