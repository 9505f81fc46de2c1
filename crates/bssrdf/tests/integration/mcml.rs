//! `mc-table` against MCML (Wang, Jacques & Zheng 1995), an independent Monte Carlo code.
//!
//! Reads the shared MCML profiles (`../shared/reference/mcml/` next to the workspace, or the
//! folder in `SSS_MCML_DIR`): per case the coefficients, MCML's total diffuse reflectance with
//! its standard error, and Rd_r per radial bin (the bin's area average) with its standard
//! error. Skips, saying so, when the folder is absent.

use sss_bssrdf::quadrature::integrate;
use sss_bssrdf::*;
use std::path::PathBuf;

/// One MCML case of `cases.csv` with its profile.
struct McmlCase {
    name: String,
    sigma_a: f64,
    sigma_s: f64,
    g: f64,
    eta: f64,
    dr: f64,
    total: f64,
    total_se: f64,
    /// (r centre, Rd_r, SE), mm and 1/mm².
    bins: Vec<(f64, f64, f64)>,
}

fn mcml_dir() -> PathBuf {
    match std::env::var_os("SSS_MCML_DIR") {
        Some(d) => PathBuf::from(d),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/reference/mcml"),
    }
}

/// The cases, or `None` (with the reason printed) when the folder is absent.
fn load_cases() -> Option<Vec<McmlCase>> {
    let dir = mcml_dir();
    let Ok(text) = std::fs::read_to_string(dir.join("cases.csv")) else {
        eprintln!(
            "skipped: no MCML reference at {} (set SSS_MCML_DIR)",
            dir.display()
        );
        return None;
    };
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next()?.split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h.trim() == name)
            .unwrap_or_else(|| panic!("cases.csv: no column {name}"))
    };
    let (c_name, c_a, c_s, c_g, c_eta, c_dr, c_t, c_tse) = (
        col("case"),
        col("sigma_a_per_mm"),
        col("sigma_s_per_mm"),
        col("g"),
        col("eta"),
        col("dr_mm"),
        col("total_diffuse_reflectance"),
        col("total_se"),
    );
    let mut cases = Vec::new();
    for line in lines.filter(|l| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let num = |c: usize| -> f64 { f[c].parse().unwrap() };
        let name = f[c_name].to_string();
        let profile = std::fs::read_to_string(dir.join(format!("{name}.csv")))
            .unwrap_or_else(|e| panic!("{name}.csv: {e}"));
        let bins = profile
            .lines()
            .skip(1)
            .filter(|l| !l.trim().is_empty())
            .map(|l| {
                let v: Vec<f64> = l.split(',').map(|x| x.trim().parse().unwrap()).collect();
                (v[0], v[1], v[2])
            })
            .collect();
        cases.push(McmlCase {
            name,
            sigma_a: num(c_a),
            sigma_s: num(c_s),
            g: num(c_g),
            eta: num(c_eta),
            dr: num(c_dr),
            total: num(c_t),
            total_se: num(c_tse),
            bins,
        });
    }
    Some(cases)
}

/// The worst deviations of one case.
#[derive(Debug, Default)]
struct Deviation {
    /// Largest effective excess (see [`McmlCase::deviation`]) over 0.25–10 reduced mfp, and
    /// where (mfp).
    near: (f64, f64),
    /// The same over 10–16 reduced mfp.
    far: (f64, f64),
    /// (model − MCML)/MCML in the bins of `near` and `far`.
    near_signed: f64,
    far_signed: f64,
    /// The largest single-bin excesses, before the 5-bin check.
    near_single: f64,
    far_single: f64,
    /// (model total − MCML total)/MCML total.
    total: f64,
    /// Bins compared, and bins beyond the margin alone but within it over their 5 bins.
    bins: usize,
    forgiven: usize,
}

impl McmlCase {
    fn medium(&self) -> Medium {
        Medium::new([self.sigma_a; 3], [self.sigma_s; 3], self.g, self.eta).unwrap()
    }

    /// The fraction of the beam that enters: MCML counts its photons before the specular
    /// reflection at normal incidence, R_sp = ((η − 1)/(η + 1))² (from a medium of index 1;
    /// Wang, Jacques & Zheng 1995, Eq. 3.1), while this crate's R_d is per unit power that
    /// entered (see `monte_carlo`).
    fn entering(&self) -> f64 {
        1.0 - ((self.eta - 1.0) / (self.eta + 1.0)).powi(2)
    }

    /// The bins (r, Rd_r, SE) per unit power entering, with each bin's standard error
    /// replaced by a locally pooled one. MCML's SE per bin comes from 5 batches, so it is
    /// itself uncertain (4 degrees of freedom: a bin's estimate is below half its true value
    /// in about 1 bin in 20, which makes "3 SE" a 6–10 SE test there). At a fixed weight per
    /// photon the variance of a bin average is c·Rd_r/area, so over the 21 bins around each
    /// bin c = Σ SE²·area / Σ Rd_r (≈ 84 degrees of freedom) and Rd_r is averaged (by area;
    /// a single bin's own value is too noisy to set its error), and SE = √(c Rd_r / area).
    fn normalised_bins(&self) -> Vec<(f64, f64, f64)> {
        let k = 1.0 / self.entering();
        let area = |r: f64| {
            let (lo, hi) = ((r - 0.5 * self.dr).max(0.0), r + 0.5 * self.dr);
            std::f64::consts::PI * (hi * hi - lo * lo)
        };
        const HALF: usize = 10;
        (0..self.bins.len())
            .map(|i| {
                let (r, rd, _) = self.bins[i];
                let window =
                    &self.bins[i.saturating_sub(HALF)..(i + HALF + 1).min(self.bins.len())];
                let (mut v, mut sum, mut m, mut a) = (0.0, 0.0, 0.0, 0.0);
                for &(rj, rdj, sej) in window {
                    v += sej * sej * area(rj);
                    sum += rdj.max(0.0);
                    m += rdj.max(0.0) * area(rj);
                    a += area(rj);
                }
                let (c, smooth) = (v / sum.max(f64::MIN_POSITIVE), m / a);
                (r, k * rd, k * (c * smooth / area(r)).sqrt())
            })
            .collect()
    }

    fn reduced_albedo(&self) -> f64 {
        self.medium().reduced_albedo(0)
    }

    /// Compares `model` (channel 0) with the profile: the model's area average over every
    /// MCML bin (Gauss-Legendre over the bin of 2πr R_d, divided by the annulus' area).
    ///
    /// A bin's excess is (|model − MCML| − 3 SE)/MCML. MCML's bin values have a heavy tail
    /// beyond their (pooled) standard error — a few photons of large weight make single bins
    /// 20–30 % low or high among neighbours that agree with each other (ketchup at
    /// 36.825 mm, skin1 B at 6.635 mm) — while the model, a spline with knots 0.75 mfp
    /// apart, cannot bend within a few bins. So a bin beyond the margin counts as a
    /// deviation of the model only when the 5 bins around it (masses summed, variances
    /// added) are beyond it too: a bin's effective excess is the smaller of the two, and
    /// the bins forgiven that way are counted.
    fn deviation(&self, model: &dyn Bssrdf) -> Deviation {
        let mfp = self.medium().reduced_mean_free_path(0);
        let mut d = Deviation::default();
        // (x, model mass, MCML mass, MCML variance of the mass) per bin in 0.25–16 mfp.
        let mut rows = Vec::new();
        for (r, rd, se) in self.normalised_bins() {
            let x = r / mfp;
            if !(0.25..=16.0).contains(&x) || rd.is_nan() || rd <= 0.0 {
                continue;
            }
            let (lo, hi) = ((r - 0.5 * self.dr).max(0.0), r + 0.5 * self.dr);
            let area = std::f64::consts::PI * (hi * hi - lo * lo);
            let mass = integrate(
                &|s| 2.0 * std::f64::consts::PI * s * model.rd(0, s),
                lo,
                hi,
                6,
            );
            rows.push((x, mass, rd * area, (se * area).powi(2)));
        }
        let excess = |m: f64, f: f64, v: f64| ((m - f).abs() - 3.0 * v.sqrt()) / f;
        for (i, &(x, m, f, v)) in rows.iter().enumerate() {
            let margin = if x <= 10.0 { 0.03 } else { 0.10 };
            let single = excess(m, f, v);
            let around = &rows[i.saturating_sub(2)..(i + 3).min(rows.len())];
            let (sm, sf, sv) = around
                .iter()
                .fold((0.0, 0.0, 0.0), |(a, b, c), r| (a + r.1, b + r.2, c + r.3));
            let effective = single.min(excess(sm, sf, sv));
            d.bins += 1;
            if single > margin && effective <= margin {
                d.forgiven += 1;
            }
            let (worst, signed) = if x <= 10.0 {
                (&mut d.near, &mut d.near_signed)
            } else {
                (&mut d.far, &mut d.far_signed)
            };
            if effective > worst.0 {
                *worst = (effective, x);
                *signed = m / f - 1.0;
            }
            let raw = if x <= 10.0 {
                &mut d.near_single
            } else {
                &mut d.far_single
            };
            *raw = raw.max(single);
        }
        d.total = model.total_diffuse_reflectance(0) / (self.total / self.entering()) - 1.0;
        d
    }
}

/// The goal: for every case with reduced albedo ≥ 0.5 (all 12), the model's area average
/// over every MCML bin within 3 % + 3 MCML standard errors of MCML's Rd_r over 0.25–10
/// reduced mean free paths and within 10 % + 3 SE over 10–16 (each bin's effective excess,
/// see `McmlCase::deviation`; at most 1 % of the bins forgiven by their 5-bin
/// neighbourhood), and the total diffuse reflectance within 1 % of MCML's (per entering
/// photon). Achieved: effective excess beyond 3 SE at most 0.71 % (0.25–10 mfp) and 6.4 %
/// (10–16 mfp, skin1 G at 15.3), at most 3 bins of ≈ 1300 forgiven per case, totals
/// within 0.46 % (the MCML totals' own SE is 0.004–0.03 %). Before the fitted far field
/// the 10–16 mfp excess reached 26 % (ketchup) and 16 % (skin1 G).
#[test]
fn mc_table_matches_mcml() {
    let Some(cases) = load_cases() else {
        return;
    };
    let mut failures = Vec::new();
    for case in &cases {
        let medium = case.medium();
        let model = make_model(ModelKind::McTable, &medium);
        let d = case.deviation(model.as_ref());
        println!(
            "{:<24} albedo' {:.5}: 0.25–10 mfp {:+6.2} % at {:5.2} ({:+6.2} %; single bins \
             {:+6.2} %), 10–16 mfp {:+6.2} % at {:5.2} ({:+6.2} %; single {:+7.2} %), total \
             {:+6.3} % (MCML ±{:.3} %), {} of {} bins forgiven",
            case.name,
            case.reduced_albedo(),
            100.0 * d.near.0,
            d.near.1,
            100.0 * d.near_signed,
            100.0 * d.near_single,
            100.0 * d.far.0,
            d.far.1,
            100.0 * d.far_signed,
            100.0 * d.far_single,
            100.0 * d.total,
            100.0 * case.total_se / case.total,
            d.forgiven,
            d.bins,
        );
        if case.reduced_albedo() < 0.5 {
            continue;
        }
        if d.near.0 > 0.03 || d.far.0 > 0.10 || d.total.abs() > 0.01 || d.forgiven * 100 > d.bins {
            failures.push(format!("{}: {d:?}", case.name));
        }
    }
    assert!(failures.is_empty(), "off MCML: {failures:#?}");
}

/// Per-stage figures (printed when `SSS_MCML_STAGES` is set, e.g.
/// `SSS_MCML_STAGES=1 cargo test --release -p sss-bssrdf --test integration -- --nocapture mcml::stages`):
/// on the table's own tally bins (reduced units, 0.25–16 mfp), MCML's light per bin (its bins'
/// masses, split by area where a table edge cuts one) against (a) the raw tallies blended at
/// the case's reduced albedo with the model's Catmull-Rom weights, (b) the tallies after the
/// pooling and isotonic fit that `row_nodes` feeds to the histopolation, (c) the model itself
/// (its spline, integrated over the bin).
#[test]
fn stages() {
    use sss_bssrdf::catmull_rom::{apply_weights, catmull_rom_weights};
    use sss_bssrdf::mc_table::{ETAS, GS, McTableData, row_masses};
    if std::env::var_os("SSS_MCML_STAGES").is_none() {
        return;
    }
    let Some(cases) = load_cases() else {
        return;
    };
    let data = McTableData::embedded().unwrap();
    let edges = data.edges().to_vec();
    for case in &cases {
        let medium = case.medium();
        let model = make_model(ModelKind::McTable, &medium);
        let st = medium.sigma_t_reduced(0);
        let rho = medium.reduced_albedo(0);
        let e = ETAS.iter().position(|&x| x == case.eta).unwrap();
        let gi = GS.iter().position(|&x| x == case.g).unwrap();
        let t = data.table_index(gi, e);
        let (off, w) = catmull_rom_weights(data.rho_samples(), rho).unwrap();
        let spec = ((case.eta - 1.0) / (case.eta + 1.0)).powi(2);
        let blend = |f: &dyn Fn(usize) -> f64| apply_weights(off, &w, f);
        let processed = |i: usize| -> Vec<f64> {
            row_masses(data.knots(), data.mass(t, i), data.mass_se(t, i))
        };
        let rows: Vec<(usize, Vec<f64>)> = (0..4)
            .filter_map(|m| {
                let i = off + m as isize;
                (i >= 0 && (i as usize) < data.rho_samples().len())
                    .then(|| (i as usize, processed(i as usize)))
            })
            .collect();
        println!("{} (albedo' {rho:.5}, table {t}):", case.name);
        println!("   x_lo   x_hi |  MCML mass ±SE%  | raw tally ±SE% | pooled+isotonic | model");
        for k in 0..edges.len() - 1 {
            let (xl, xh) = (edges[k], edges[k + 1]);
            if xh < 0.25 || xl > 16.0 {
                continue;
            }
            let (rl, rh) = (xl / st, xh / st);
            let (mut mm, mut mv, mut covered) = (0.0, 0.0, 0.0);
            for &(r, rd, se) in &case.bins {
                let (lo, hi) = ((r - 0.5 * case.dr).max(0.0), r + 0.5 * case.dr);
                let (a, b) = (lo.max(rl), hi.min(rh));
                if b <= a {
                    continue;
                }
                let area = std::f64::consts::PI * (b * b - a * a);
                mm += rd * area;
                mv += (se * area).powi(2);
                covered += area;
            }
            let _ = covered;
            let (mm, msd) = (mm / (1.0 - spec), mv.sqrt() / (1.0 - spec));
            let raw = blend(&|i| data.mass(t, i)[k]);
            let raw_se = w
                .iter()
                .enumerate()
                .map(|(m, wm)| {
                    let i = (off + m as isize).clamp(0, 99) as usize;
                    (wm * data.mass_se(t, i)[k]).powi(2)
                })
                .sum::<f64>()
                .sqrt();
            let pooled = blend(&|i| {
                rows.iter()
                    .find(|(j, _)| *j == i)
                    .map_or(0.0, |(_, v)| v[k])
            });
            let m = integrate(
                &|s| 2.0 * std::f64::consts::PI * s * model.rd(0, s),
                rl,
                rh,
                16,
            );
            println!(
                "{xl:7.3} {xh:7.3} | {mm:10.4e} {:5.2} | {:+6.2}% {:5.2} | {:+6.2}% | {:+6.2}%",
                100.0 * msd / mm,
                100.0 * (raw / mm - 1.0),
                100.0 * raw_se / mm,
                100.0 * (pooled / mm - 1.0),
                100.0 * (m / mm - 1.0),
            );
        }
    }
}
