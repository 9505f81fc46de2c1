//! The `mc-table` model against fresh runs of the ordinary photon random walk.
//!
//! - The stored table entries (bin masses of the condensed walk, `McTableData`) agree with an
//!   independent run of [`simulate`] — implicit capture at the row's own albedo, no albedo
//!   rescaling, no strata — on the same bins, within their joint standard errors.
//! - The accuracy goal, off the table's nodes (albedos between rows, η between
//!   tables): within 3 % of a fresh Monte Carlo reference plus 3 of its standard errors over
//!   0.25–16 mean free paths for albedo ≥ 0.5, and the total reflectance within 1 % plus 3
//!   standard errors.
//! - Monotonicity: R_d is non-increasing in r (what the many-light bounds need) and the total
//!   reflectance non-decreasing in the albedo (what `from_reflectance` needs).
//!
//! Sampling (`pdf_sr`, quantiles, Kolmogorov-Smirnov) and the extreme media are covered with
//! the other models in `sampling_at_table_speed.rs`, `models.rs` and `extremes.rs`.

use sss_bssrdf::mc_table::{ETAS, GS, McTable, McTableData, tally_edges};
use sss_bssrdf::monte_carlo::{BinSpacing, WalkConfig, simulate};
use sss_bssrdf::quadrature::integrate_radial_range;
use sss_bssrdf::*;

/// A fresh run of the ordinary walk for one channel of `medium` on `spacing`'s bins.
fn fresh(
    medium: &Medium,
    ch: usize,
    photons: u64,
    seed: u64,
    spacing: BinSpacing,
) -> monte_carlo::WalkProfile {
    let (bins, r_max) = match &spacing {
        BinSpacing::Edges(e) => (e.len() - 1, e[e.len() - 1]),
        BinSpacing::Linear => unreachable!("the tests give edges"),
    };
    simulate(
        medium,
        &WalkConfig {
            photons,
            seed,
            r_max,
            bins,
            channels: std::array::from_fn(|c| c == ch),
            spacing,
        },
    )
    .unwrap()
}

#[test]
fn table_entries_agree_with_a_fresh_ordinary_walk() {
    // (g index, η index, albedo row, photons): one row from a single-stratum band and three
    // from stratified bands, at three η, for g = 0, and three rows of the tables of g ≠ 0. A
    // table of g ≠ 0 is in reduced units: its row ρ' and radius x' are those of the medium
    // σ_a = 1 − ρ', σ_s = ρ'/(1 − g) (σ'_t = 1), simulated here with its true g. A fresh bin
    // enters the test when it has at least ~25 photons' worth of tally (relative standard
    // error ≤ 20 %, where its error is close to normal). Margins: every |z| < 4.5 (≈ 500
    // bins: a false alarm below 0.4 %) and χ² within 4 standard deviations of its mean.
    let data = McTableData::embedded().unwrap();
    let edges = tally_edges(data.knots());
    let cases = [
        (0, 3, 40, 200_000),
        (0, 3, 75, 40_000),
        (0, 0, 20, 200_000),
        (0, 5, 88, 15_000),
        (1, 3, 30, 100_000),
        (3, 0, 55, 40_000),
        (4, 4, 70, 10_000),
    ];
    let (mut chi2, mut dof) = (0.0, 0usize);
    let mut worst: f64 = 0.0;
    for (gi, e, i, photons) in cases {
        let (g, eta, rho) = (GS[gi], ETAS[e], data.rho_samples()[i]);
        let m = Medium::new([1.0 - rho; 3], [rho / (1.0 - g); 3], g, eta).unwrap();
        let e = data.table_index(gi, e);
        let mc = fresh(
            &m,
            0,
            photons,
            0xF00D + i as u64,
            BinSpacing::Edges(edges.clone()),
        );
        let (table, table_se) = (data.mass(e, i), data.mass_se(e, i));
        let mut used = 0;
        for (b, area) in mc.bin_areas().iter().enumerate() {
            let (f, f_se) = (mc.rd[0][b] * area, mc.se[0][b] * area);
            if !(f > 0.0 && f_se <= 0.2 * f) {
                continue;
            }
            let z = (table[b] - f) / (table_se[b].powi(2) + f_se.powi(2)).sqrt();
            assert!(
                z.abs() < 4.5,
                "g {g} eta {eta} rho {rho} bin {b} [{}, {}]: table {} ± {} vs fresh {f} ± {f_se}",
                edges[b],
                edges[b + 1],
                table[b],
                table_se[b]
            );
            worst = worst.max(z.abs());
            chi2 += z * z;
            used += 1;
        }
        assert!(
            used >= 30,
            "g {g} eta {eta} rho {rho}: only {used} bins compared"
        );
        dof += used;
        let (t, t_se) = data.total(e, i);
        let z = (t - mc.total[0]) / (t_se.powi(2) + mc.total_se[0].powi(2)).sqrt();
        println!(
            "g {g} eta {eta} rho {rho:.6}: {used} bins, total {t:.5} ± {t_se:.1e} vs fresh {:.5} ± \
             {:.1e} (z {z:.2})",
            mc.total[0], mc.total_se[0]
        );
        assert!(z.abs() < 4.0, "g {g} eta {eta} rho {rho}: total z {z}");
    }
    let bound = dof as f64 + 4.0 * (2.0 * dof as f64).sqrt();
    println!("{dof} bins: chi2 {chi2:.1} (bound {bound:.1}), worst |z| {worst:.2}");
    assert!(chi2 < bound, "chi2 {chi2} over {dof} bins");
}

/// One medium of the accuracy test, with photons per channel.
struct Case {
    label: &'static str,
    medium: Medium,
    photons: [u64; 3],
}

/// `m` (g = 0) with anisotropy `g` and the same reduced scattering coefficient.
fn with_g(m: Medium, g: f64) -> Medium {
    Medium::new(m.sigma_a(), m.sigma_s().map(|s| s / (1.0 - g)), g, m.eta()).unwrap()
}

fn accuracy_cases() -> Vec<Case> {
    vec![
        // Jensen et al. 2001 (g = 0, η = 1.3): albedos 0.958, 0.838, 0.678 and 0.999, 0.998,
        // 0.998, none on a table row.
        Case {
            label: "skin1",
            medium: Medium::preset("skin1").unwrap(),
            photons: [200_000; 3],
        },
        Case {
            label: "marble",
            medium: Medium::preset("marble").unwrap(),
            photons: [30_000; 3],
        },
        // Anisotropic media between the tables of g: the measured reduced coefficients of
        // marble with g = 0.5 (σ_s = σ'_s/(1 − g)) and of skin1 with g = 0.8.
        Case {
            label: "marble g 0.5",
            medium: with_g(Medium::preset("marble").unwrap(), 0.5),
            photons: [20_000; 3],
        },
        Case {
            label: "skin1 g 0.8",
            medium: with_g(Medium::preset("skin1").unwrap(), 0.8),
            photons: [60_000; 3],
        },
        // η = 1.33 lies between the 1.3 and 1.4 tables; albedos between rows.
        Case {
            label: "water-like",
            medium: Medium::from_extinction_albedo(
                [2.0, 0.5, 1.0],
                [0.55, 0.93, 0.9935],
                0.0,
                1.33,
            )
            .unwrap(),
            photons: [200_000, 200_000, 60_000],
        },
    ]
}

#[test]
fn within_three_percent_of_monte_carlo_off_the_nodes() {
    // Bins: [0, 0.25] then 24 log-spaced up to 16 reduced mean free paths (1/σ'_t; 1/σ_t for
    // g = 0) of the channel; the
    // model's area average over each bin by quadrature of its rd. A bin passes when
    // |model − MC| ≤ 3 % MC + 3 SE(MC); the total when |model − MC| ≤ 1 % MC + 3 SE(MC).
    let mut worst_excess: f64 = 0.0;
    let mut worst_total: f64 = 0.0;
    for case in accuracy_cases() {
        let model = make_model(ModelKind::McTable, &case.medium);
        for ch in 0..3 {
            let mfp = case.medium.reduced_mean_free_path(ch);
            let spacing = BinSpacing::geometric(0.25 * mfp, 16.0 * mfp, 25).unwrap();
            let mc = fresh(
                &case.medium,
                ch,
                case.photons[ch],
                0xACC + ch as u64,
                spacing,
            );
            let albedo = case.medium.reduced_albedo(ch);
            let mut line = format!("{} ch{ch} albedo {albedo:.5}:", case.label);
            for (b, w) in mc.bin_edges.windows(2).enumerate().skip(1) {
                let area = mc.bin_areas()[b];
                let m = integrate_radial_range(&|r| model.rd(ch, r), mfp, w[0], w[1]) / area;
                let (f, se) = (mc.rd[ch][b], mc.se[ch][b]);
                let excess = ((m - f).abs() - 3.0 * se) / f;
                if b % 6 == 1 {
                    line += &format!(
                        " {:.2}mfp {:+.1}%±{:.1}",
                        w[0] / mfp,
                        100.0 * (m / f - 1.0),
                        100.0 * se / f
                    );
                }
                if albedo >= 0.5 {
                    worst_excess = worst_excess.max(excess);
                    assert!(
                        excess <= 0.03,
                        "{} ch{ch} bin [{}, {}] mfp: model {m} vs MC {f} ± {se}",
                        case.label,
                        w[0] / mfp,
                        w[1] / mfp
                    );
                }
            }
            let total = model.total_diffuse_reflectance(ch);
            let (t, t_se) = (mc.total[ch], mc.total_se[ch]);
            let excess = ((total - t).abs() - 3.0 * t_se) / t;
            worst_total = worst_total.max(excess);
            println!("{line}; total {total:.5} vs {t:.5} ± {t_se:.1e}");
            assert!(
                excess <= 0.01,
                "{} ch{ch}: total {total} vs MC {t} ± {t_se}",
                case.label
            );
        }
    }
    println!(
        "worst bin excess over 3 SE: {:.2} %, worst total excess: {:.2} %",
        100.0 * worst_excess,
        100.0 * worst_total
    );
}

/// Largest relative rise of R_d over its running minimum on a fine log grid (ignoring values
/// below 10⁻⁹ of the peak, as `RadialProfile::with_tolerance` does).
fn worst_rise(model: &dyn Bssrdf, ch: usize) -> f64 {
    let st = model.medium().sigma_t_reduced(ch);
    let peak = model.rd(ch, 0.0);
    let mut run_min = f64::INFINITY;
    let mut worst: f64 = 0.0;
    for k in 0..=6000 {
        let r = 1e-4 * 10f64.powf(7.0 * k as f64 / 6000.0) / st;
        let v = model.rd(ch, r);
        if v > run_min + 1e-9 * peak {
            worst = worst.max(v / run_min - 1.0);
        }
        run_min = run_min.min(v);
    }
    worst
}

#[test]
fn profiles_are_non_increasing_and_totals_non_decreasing() {
    // Every table row and the midpoints between rows, at every η of the tables and between
    // two of them (g = 0), and at every g of the tables and between two of them (the media
    // of reduced albedo ρ' and σ'_t = 1).
    let rows = McTable::new(1.3).rho_samples().to_vec();
    let mut albedos = rows.clone();
    albedos.extend(rows.windows(2).map(|w| 0.5 * (w[0] + w[1])));
    let mut worst: (f64, String) = (0.0, String::new());
    let cases = ETAS
        .into_iter()
        .chain([1.35])
        .map(|eta| (eta, 0.0))
        .chain(GS[1..].iter().chain(&[0.5]).map(|&g| (1.3, g)))
        .chain([(1.0, 0.9), (1.5, 0.7)]);
    let medium = |a: [f64; 3], g: f64, eta: f64| {
        Medium::new(a.map(|a| 1.0 - a), a.map(|a| a / (1.0 - g)), g, eta).unwrap()
    };
    for (eta, g) in cases {
        for chunk in albedos.chunks(3) {
            let mut a = [0.0; 3];
            a[..chunk.len()].copy_from_slice(chunk);
            let m = medium(a, g, eta);
            let model = McTableModel::new(m);
            for (ch, &rho) in chunk.iter().enumerate() {
                let rise = worst_rise(&model, ch);
                if rise > worst.0 {
                    worst = (rise, format!("eta {eta} g {g} rho {rho}"));
                }
            }
        }
        // The model's total reflectance non-decreasing in ρ on a fine grid, within [0, 1].
        let mut prev = 0.0;
        for k in 0..=4000 {
            let rho = k as f64 / 4000.0;
            let v = McTableModel::new(medium([rho; 3], g, eta)).total_diffuse_reflectance(0);
            assert!(
                v >= prev - 1e-12 && v <= 1.0,
                "eta {eta} g {g} rho {rho}: {v} after {prev}"
            );
            prev = v;
        }
    }
    println!(
        "worst rise of R_d over its running minimum: {:.3} % ({})",
        100.0 * worst.0,
        worst.1
    );
    assert!(worst.0 < 0.02, "{worst:?}");
}

#[test]
fn table_totals_hold_the_monte_carlo_totals() {
    // The spline's integral (ρ_eff) against the tallied total reflectance of each row, from
    // the same photons: the table misses only what escapes beyond its last knot (≈ 960 mean
    // free paths) and what the tail treatment and the isotonic fit move. Measured: at most
    // 0.25 % for albedo ≥ 0.5 (at albedo 1); dropping the unresolved far tail instead of
    // keeping its tallied mass loses 0.9 % there.
    let data = McTableData::embedded().unwrap();
    let mut worst: (f64, String) = (0.0, String::new());
    for (gi, e) in (0..GS.len()).flat_map(|g| (0..ETAS.len()).map(move |e| (g, e))) {
        let (g, eta) = (GS[gi], ETAS[e]);
        let table = McTable::anisotropic(eta, g);
        let e = data.table_index(gi, e);
        for (i, &rho) in data.rho_samples().iter().enumerate() {
            if rho < 0.5 {
                continue;
            }
            let inside: f64 = data.mass(e, i).iter().sum();
            let got = table.rho_eff_samples()[i];
            let rel = (got - inside).abs() / inside;
            if rel > worst.0 {
                worst = (
                    rel,
                    format!(
                        "eta {eta} g {g} rho {rho}: {got} vs {inside} (all radii {})",
                        data.total(e, i).0
                    ),
                );
            }
        }
    }
    println!(
        "worst relative difference: {:.3} % ({})",
        100.0 * worst.0,
        worst.1
    );
    assert!(worst.0 < 0.004, "{worst:?}");
}

#[test]
fn splines_integrate_to_the_tallies() {
    // The knot values are solved so that each row's spline integrates to every tallied bin
    // (histopolation). Only the pooled near-origin bins, the regularised far tail and the
    // isotonic fit may move a bin's integral, and only within its noise: over every resolved
    // bin (relative standard error ≤ 20 %) of every row of every η table, the mean squared
    // z = (∫_bin spline − tally)/SE stays below 1 (0.23 measured). Knot values taken as bin
    // averages (no histopolation) give 1.18.
    let data = McTableData::embedded().unwrap();
    let edges = tally_edges(data.knots());
    let (mut sum, mut n) = (0.0, 0usize);
    for (gi, e) in (0..GS.len()).flat_map(|g| (0..ETAS.len()).map(move |e| (g, e))) {
        let table = McTable::anisotropic(ETAS[e], GS[gi]);
        let e = data.table_index(gi, e);
        let xs = table.radius_samples().to_vec();
        for i in 0..data.rho_samples().len() {
            let (mass, se) = (data.mass(e, i), data.mass_se(e, i));
            for k in 0..mass.len() {
                if !(mass[k] > 0.0 && se[k] > 0.0 && se[k] <= 0.2 * mass[k]) {
                    continue;
                }
                let (lo, hi) = (edges[k], edges[k + 1]);
                let mut cuts = vec![lo];
                cuts.extend(xs.iter().copied().filter(|&x| x > lo && x < hi));
                cuts.push(hi);
                let integral: f64 = cuts
                    .windows(2)
                    .map(|w| {
                        sss_bssrdf::quadrature::integrate(
                            &|x| table.row_spline(i, x).unwrap_or(0.0),
                            w[0],
                            w[1],
                            4,
                        )
                    })
                    .sum();
                let z = (integral - mass[k]) / se[k];
                sum += z * z;
                n += 1;
            }
        }
    }
    let mean = sum / n as f64;
    println!("{n} resolved bins: mean z² {mean:.3}");
    assert!(n > 150_000 && mean < 1.0, "{n} bins, mean z² {mean}");
}
