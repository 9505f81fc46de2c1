//! Every model against MCML, an independent Monte Carlo code (part of the "profiles"
//! experiment).
//!
//! MCML (L. Wang, S. L. Jacques, L. Zheng, *MCML — Monte Carlo modeling of light transport in
//! multi-layered tissues*, Comput. Methods Programs Biomed. 47, 1995) was run for a few
//! semi-infinite media under a normally incident pencil beam; the shared folder
//! (`<workspace>/../shared/reference/mcml`, or `SSS_MCML_DIR`) holds per case the medium, the
//! radial bin width, MCML's total diffuse reflectance with its standard error (`cases.csv`)
//! and Rd_r per radial bin, the bin's area average, with its standard error (`<case>.csv`).
//! The comparison follows `crates/bssrdf/tests/mcml.rs`, which holds `mc-table` to it:
//!
//! - MCML counts its photons before the specular reflection at the boundary,
//!   R_sp = ((η − 1)/(η + 1))² (Wang, Jacques & Zheng 1995, Eq. 3.1), while the models' R_d is
//!   per unit power entering, so MCML's values are divided by 1 − R_sp.
//! - A model's value for a bin is its area average over the MCML annulus (Gauss–Legendre over
//!   the bin of 2πr R_d, divided by the area).
//! - MCML's per-bin standard errors come from 5 batches and are themselves uncertain, so each
//!   is replaced by one pooled over the 21 bins around it ([`Case::normalised_bins`]).
//! - A bin's excess is (|model − MCML| − 3 SE)/MCML; a bin counts only as far as the 5 bins
//!   around it (masses summed, variances added) are beyond it too ([`worst`]), since single
//!   MCML bins have heavy-tailed errors.
//!
//! The models are compared as they are: the standard and better dipoles model multiple
//! scattering only, while MCML (like the other models) has every scattering order.

use super::output::{csv_num, md_num, md_pct, md_table, write_atomic};
use super::profiles::{ModelMethod, ProfileMethod};
use super::reference::McPart;
use super::{Error, Section};
use rayon::prelude::*;
use sss_bssrdf::quadrature::integrate;
use sss_bssrdf::{Bssrdf, Medium, ModelKind, make_model};
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The subsection's heading.
pub const TITLE: &str = "Against MCML (independent Monte Carlo)";

/// The file written next to `profiles.csv`.
pub const CSV_NAME: &str = "mcml.csv";

/// The header of `mcml.csv` (documented in `docs/compare.md`).
pub const CSV_HEADER: &str = "case,model,model_part,eta,g,reduced_albedo,mfp_mm,near_excess,near_at_mfp,near_rel_error,near_single_excess,near_median_abs_error,far_excess,far_at_mfp,far_rel_error,far_single_excess,total_model,total_mcml,total_mcml_se,total_rel_error,bins,bins_forgiven";

/// The near range, in reduced mean free paths.
pub const NEAR: (f64, f64) = (0.25, 10.0);
/// The far range (beyond [`NEAR`]), in reduced mean free paths.
pub const FAR_END: f64 = 16.0;
/// MCML standard errors a model may differ by before its difference counts.
pub const SE_ALLOWANCE: f64 = 3.0;
/// The margins of `crates/bssrdf/tests/mcml.rs` for the near and far ranges; a bin beyond its
/// margin alone but within it over its 5 bins is counted as *forgiven*.
pub const MARGINS: (f64, f64) = (0.03, 0.10);
/// Bins on each side of a bin in the forgiving rule's neighbourhood (5 bins in all).
const NEIGHBOURS: usize = 2;
/// Bins on each side over which the standard error is pooled (21 bins in all).
const POOL_HALF: usize = 10;
/// Gauss–Legendre points per MCML bin.
const GAUSS_POINTS: usize = 6;

/// The folder of the MCML profiles: `SSS_MCML_DIR` when set, else
/// `<workspace>/../shared/reference/mcml`.
pub fn reference_dir() -> PathBuf {
    dir_from(std::env::var_os("SSS_MCML_DIR"))
}

fn dir_from(env: Option<std::ffi::OsString>) -> PathBuf {
    match env {
        Some(d) if !d.is_empty() => PathBuf::from(d),
        _ => crate::workspace_root().join("../shared/reference/mcml"),
    }
}

/// One MCML case: the medium, MCML's total and its profile.
#[derive(Clone, Debug)]
pub struct Case {
    /// Name (also the profile's file name without `.csv`).
    pub name: String,
    /// The medium (the same coefficients in all three channels; channel 0 is used).
    pub medium: Medium,
    /// Radial bin width (mm).
    pub dr: f64,
    /// MCML's total diffuse reflectance per incident photon (specular reflection excluded).
    pub total: f64,
    /// Its standard error.
    pub total_se: f64,
    /// (bin centre (mm), Rd_r (1/mm²), SE (1/mm²)) per incident photon; bins without a tally
    /// are absent.
    pub bins: Vec<(f64, f64, f64)>,
}

/// The shared folder, read.
#[derive(Debug)]
pub enum Reference {
    /// No folder (or no `cases.csv` in it): the comparison is skipped.
    Absent(String),
    /// `cases.csv` is there but unusable: the comparison is skipped.
    Unusable(String),
    /// The cases read, and a note per case that was skipped (naming its file and why).
    Found {
        /// The usable cases, in `cases.csv` order.
        cases: Vec<Case>,
        /// One line per skipped case.
        skipped: Vec<String>,
    },
}

/// Reads the cases of `dir`. Never panics: a malformed `cases.csv` makes the whole folder
/// [`Reference::Unusable`]; a malformed row or profile skips that case with a note.
pub fn load(dir: &Path) -> Reference {
    let path = dir.join("cases.csv");
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Reference::Absent(format!("there is no `{}`", path.display()));
        }
        Err(e) => return Reference::Unusable(format!("cannot read `{}`: {e}", path.display())),
    };
    let mut lines = text.lines().enumerate();
    let Some((_, header)) = lines.next() else {
        return Reference::Unusable(format!("`{}` is empty", path.display()));
    };
    let header: Vec<&str> = header.split(',').map(str::trim).collect();
    let required = [
        "case",
        "sigma_a_per_mm",
        "sigma_s_per_mm",
        "g",
        "eta",
        "dr_mm",
        "total_diffuse_reflectance",
        "total_se",
    ];
    let mut cols = [0usize; 8];
    for (c, name) in cols.iter_mut().zip(required) {
        match header.iter().position(|h| *h == name) {
            Some(i) => *c = i,
            None => {
                return Reference::Unusable(format!("`{}` has no column `{name}`", path.display()));
            }
        }
    }
    let above = header.iter().position(|h| *h == "eta_above");
    let (mut cases, mut skipped) = (Vec::new(), Vec::new());
    for (i, line) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        match parse_case(dir, line, &cols, above) {
            Ok(c) => cases.push(c),
            Err(e) => skipped.push(format!("`cases.csv` line {}: {e}; skipped", i + 1)),
        }
    }
    Reference::Found { cases, skipped }
}

fn parse_case(
    dir: &Path,
    line: &str,
    cols: &[usize; 8],
    above: Option<usize>,
) -> Result<Case, String> {
    let f: Vec<&str> = line.split(',').map(str::trim).collect();
    let field = |c: usize| f.get(c).copied().ok_or("too few fields");
    let name = field(cols[0])?.to_string();
    let valid_name = !name.is_empty()
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_.-".contains(c));
    if !valid_name {
        return Err(format!("case name `{name}` is not a plain file name"));
    }
    let num = |c: usize, what: &str| -> Result<f64, String> {
        let s = field(c)?;
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(format!("{name}: {what} `{s}` is not a finite number")),
        }
    };
    let (sigma_a, sigma_s, g, eta) = (
        num(cols[1], "sigma_a_per_mm")?,
        num(cols[2], "sigma_s_per_mm")?,
        num(cols[3], "g")?,
        num(cols[4], "eta")?,
    );
    let (dr, total, total_se) = (
        num(cols[5], "dr_mm")?,
        num(cols[6], "total_diffuse_reflectance")?,
        num(cols[7], "total_se")?,
    );
    if let Some(c) = above {
        let a = num(c, "eta_above")?;
        if a != 1.0 {
            return Err(format!(
                "{name}: eta_above {a} (the models assume a medium of index 1 above)"
            ));
        }
    }
    let medium =
        Medium::new([sigma_a; 3], [sigma_s; 3], g, eta).map_err(|e| format!("{name}: {e}"))?;
    if dr <= 0.0 {
        return Err(format!("{name}: dr_mm {dr} is not positive"));
    }
    if total <= 0.0 || total > 1.0 || total_se < 0.0 {
        return Err(format!(
            "{name}: total {total} ± {total_se} is not a reflectance in (0, 1] with SE ≥ 0"
        ));
    }
    let file = format!("{name}.csv");
    let bins = parse_profile(&dir.join(&file)).map_err(|e| format!("`{file}`: {e}"))?;
    Ok(Case {
        name,
        medium,
        dr,
        total,
        total_se,
        bins,
    })
}

/// `r_mm,rd_per_mm2,se_per_mm2` (columns found by name), radii increasing, values finite and
/// non-negative, at least one bin.
fn parse_profile(path: &Path) -> Result<Vec<(f64, f64, f64)>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read ({e})"))?;
    let mut lines = text.lines().enumerate();
    let header: Vec<&str> = lines
        .next()
        .ok_or("empty")?
        .1
        .split(',')
        .map(str::trim)
        .collect();
    let col = |n: &str| {
        header
            .iter()
            .position(|h| *h == n)
            .ok_or(format!("no column `{n}`"))
    };
    let (cr, cv, cs) = (col("r_mm")?, col("rd_per_mm2")?, col("se_per_mm2")?);
    let mut bins: Vec<(f64, f64, f64)> = Vec::new();
    for (i, line) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let get = |c: usize| -> Result<f64, String> {
            let s = f.get(c).ok_or(format!("line {}: too few fields", i + 1))?;
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v >= 0.0)
                .ok_or(format!(
                    "line {}: `{s}` is not a finite non-negative number",
                    i + 1
                ))
        };
        let bin = (get(cr)?, get(cv)?, get(cs)?);
        if bins.last().is_some_and(|b| b.0 >= bin.0) {
            return Err(format!("line {}: radii must increase", i + 1));
        }
        bins.push(bin);
    }
    if bins.is_empty() {
        return Err("no bins".into());
    }
    Ok(bins)
}

impl Case {
    /// The fraction of the beam that enters: 1 − R_sp, R_sp = ((η − 1)/(η + 1))².
    pub fn entering(&self) -> f64 {
        let eta = self.medium.eta();
        1.0 - ((eta - 1.0) / (eta + 1.0)).powi(2)
    }

    fn area(&self, r: f64) -> f64 {
        let (lo, hi) = ((r - 0.5 * self.dr).max(0.0), r + 0.5 * self.dr);
        PI * (hi * hi - lo * lo)
    }

    /// The bins per unit power entering, each SE replaced by a pooled one: at a fixed weight
    /// per photon a bin average's variance is c·Rd_r/area, so over the 21 bins around each bin
    /// c = Σ SE²·area / Σ Rd_r and Rd_r is averaged by area, and SE = √(c Rd_r / area) (as in
    /// `crates/bssrdf/tests/mcml.rs`).
    pub fn normalised_bins(&self) -> Vec<(f64, f64, f64)> {
        let k = 1.0 / self.entering();
        let n = self.bins.len();
        (0..n)
            .map(|i| {
                let (r, rd, _) = self.bins[i];
                let window = &self.bins[i.saturating_sub(POOL_HALF)..(i + POOL_HALF + 1).min(n)];
                let (mut v, mut sum, mut m, mut a) = (0.0, 0.0, 0.0, 0.0);
                for &(rj, rdj, sej) in window {
                    let aj = self.area(rj);
                    v += sej * sej * aj;
                    sum += rdj;
                    m += rdj * aj;
                    a += aj;
                }
                let c = v / sum.max(f64::MIN_POSITIVE);
                let se = (c * (m / a.max(f64::MIN_POSITIVE)) / self.area(r).max(f64::MIN_POSITIVE))
                    .sqrt();
                (r, k * rd, k * se)
            })
            .collect()
    }

    /// Per bin within [`NEAR`].0–[`FAR_END`] reduced mean free paths with a positive MCML
    /// value: x (mfp), the model's light in the annulus, MCML's, and the variance of MCML's.
    pub fn rows(&self, model: &dyn Bssrdf) -> Vec<BinRow> {
        let mfp = self.medium.reduced_mean_free_path(0);
        self.normalised_bins()
            .into_iter()
            .filter_map(|(r, rd, se)| {
                let x = r / mfp;
                if !(NEAR.0..=FAR_END).contains(&x) || rd <= 0.0 {
                    return None;
                }
                let (lo, hi) = ((r - 0.5 * self.dr).max(0.0), r + 0.5 * self.dr);
                let area = PI * (hi * hi - lo * lo);
                let model_mass =
                    integrate(&|s| 2.0 * PI * s * model.rd(0, s), lo, hi, GAUSS_POINTS);
                Some(BinRow {
                    x,
                    model: model_mass,
                    mcml: rd * area,
                    var: (se * area).powi(2),
                })
            })
            .collect()
    }
}

/// One MCML bin as compared: light in the annulus per unit power entering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BinRow {
    /// Radius in reduced mean free paths.
    pub x: f64,
    /// The model's light in the annulus.
    pub model: f64,
    /// MCML's.
    pub mcml: f64,
    /// Variance of MCML's.
    pub var: f64,
}

/// The worst bin of a range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Worst {
    /// Largest effective excess (|model − MCML| − 3 SE)/MCML, at least 0.
    pub excess: f64,
    /// Where (reduced mean free paths).
    pub at: f64,
    /// (model − MCML)/MCML in that bin.
    pub rel_error: f64,
    /// Largest single-bin excess, before the neighbourhood rule (at least 0).
    pub single: f64,
    /// Bins beyond the range's margin ([`MARGINS`]) alone but within it over their 5 bins.
    pub forgiven: usize,
    /// Bins in the range.
    pub bins: usize,
}

fn excess(model: f64, mcml: f64, var: f64) -> f64 {
    ((model - mcml).abs() - SE_ALLOWANCE * var.sqrt()) / mcml
}

/// The two ranges of radii compared.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Range {
    /// [`NEAR`]: 0.25–10 reduced mean free paths.
    Near,
    /// Beyond [`NEAR`] up to [`FAR_END`]: 10–16.
    Far,
}

impl Range {
    /// Whether x (reduced mean free paths) lies in the range.
    pub fn contains(self, x: f64) -> bool {
        match self {
            Range::Near => (NEAR.0..=NEAR.1).contains(&x),
            Range::Far => x > NEAR.1 && x <= FAR_END,
        }
    }

    /// The margin of `crates/bssrdf/tests/mcml.rs` for the range ([`MARGINS`]).
    pub fn margin(self) -> f64 {
        match self {
            Range::Near => MARGINS.0,
            Range::Far => MARGINS.1,
        }
    }
}

/// The worst bin of `rows` in `range`: a bin's effective excess is the smaller of its own
/// and that of the 5 bins of `rows` around it (masses summed, variances added; fewer at the
/// ends of `rows`, which may reach into the other range). `None` without bins in the range.
pub fn worst(rows: &[BinRow], range: Range) -> Option<Worst> {
    let margin = range.margin();
    let mut w: Option<Worst> = None;
    for (i, b) in rows.iter().enumerate() {
        if !range.contains(b.x) {
            continue;
        }
        let single = excess(b.model, b.mcml, b.var);
        let around = &rows[i.saturating_sub(NEIGHBOURS)..(i + NEIGHBOURS + 1).min(rows.len())];
        let (sm, sf, sv) = around.iter().fold((0.0, 0.0, 0.0), |(a, c, v), r| {
            (a + r.model, c + r.mcml, v + r.var)
        });
        let effective = single.min(excess(sm, sf, sv));
        let w = w.get_or_insert(Worst {
            excess: f64::NEG_INFINITY,
            at: b.x,
            rel_error: 0.0,
            single: 0.0,
            forgiven: 0,
            bins: 0,
        });
        w.bins += 1;
        if single > margin && effective <= margin {
            w.forgiven += 1;
        }
        if effective > w.excess {
            (w.excess, w.at, w.rel_error) = (effective, b.x, b.model / b.mcml - 1.0);
        }
        w.single = w.single.max(single);
    }
    w.map(|w| Worst {
        excess: w.excess.max(0.0),
        ..w
    })
}

/// The median of |model − MCML|/MCML over the bins in `range`.
pub fn median_abs_error(rows: &[BinRow], range: Range) -> Option<f64> {
    let mut v: Vec<f64> = rows
        .iter()
        .filter(|b| range.contains(b.x))
        .map(|b| (b.model / b.mcml - 1.0).abs())
        .filter(|e| e.is_finite())
        .collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

/// One model against one case.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// Case name.
    pub case: String,
    /// Model name.
    pub model: String,
    /// What the model models: [`McPart::Multiple`] for the standard and better dipoles
    /// (MCML always has every order).
    pub part: McPart,
    /// The case's η.
    pub eta: f64,
    /// Anisotropy.
    pub g: f64,
    /// Reduced albedo.
    pub reduced_albedo: f64,
    /// Reduced mean free path (mm).
    pub mfp: f64,
    /// Over [`NEAR`].
    pub near: Option<Worst>,
    /// Median |model − MCML|/MCML over [`NEAR`].
    pub near_median: Option<f64>,
    /// Over [`NEAR`].1–[`FAR_END`].
    pub far: Option<Worst>,
    /// The model's total diffuse reflectance.
    pub total_model: f64,
    /// MCML's total diffuse reflectance per unit power entering.
    pub total_mcml: f64,
    /// Standard error of `total_mcml`.
    pub total_mcml_se: f64,
}

impl Comparison {
    /// (model total − MCML total)/MCML total.
    pub fn total_rel_error(&self) -> Option<f64> {
        let e = self.total_model / self.total_mcml - 1.0;
        e.is_finite().then_some(e)
    }

    fn bins(&self) -> usize {
        self.near.map_or(0, |w| w.bins) + self.far.map_or(0, |w| w.bins)
    }

    fn forgiven(&self) -> usize {
        self.near.map_or(0, |w| w.forgiven) + self.far.map_or(0, |w| w.forgiven)
    }
}

/// `model` (named `name`, modelling `part`) against `case`.
pub fn compare(case: &Case, name: &str, part: McPart, model: &dyn Bssrdf) -> Comparison {
    let rows = case.rows(model);
    let total_model = model.total_diffuse_reflectance(0);
    Comparison {
        case: case.name.clone(),
        model: name.to_string(),
        part,
        eta: case.medium.eta(),
        g: case.medium.g(),
        reduced_albedo: case.medium.reduced_albedo(0),
        mfp: case.medium.reduced_mean_free_path(0),
        near: worst(&rows, Range::Near),
        near_median: median_abs_error(&rows, Range::Near),
        far: worst(&rows, Range::Far),
        total_model: if total_model.is_finite() {
            total_model
        } else {
            0.0
        },
        total_mcml: case.total / case.entering(),
        total_mcml_se: case.total_se / case.entering(),
    }
}

/// Every model of [`ModelKind::ALL`] against every case (cases in order, models in order).
pub fn compare_all(cases: &[Case]) -> Vec<Comparison> {
    let jobs: Vec<(&Case, ModelKind)> = cases
        .iter()
        .flat_map(|c| ModelKind::ALL.into_iter().map(move |k| (c, k)))
        .collect();
    jobs.into_par_iter()
        .map(|(case, kind)| {
            let method = ModelMethod(kind);
            let model = make_model(kind, &case.medium);
            compare(
                case,
                &method.name(),
                method.reference_part(),
                model.as_ref(),
            )
        })
        .collect()
}

/// `mcml.csv`: one row per (case, model).
pub fn results_csv(rows: &[Comparison]) -> String {
    let mut s = String::from(CSV_HEADER);
    s.push('\n');
    for c in rows {
        let w = |w: Option<Worst>, f: fn(Worst) -> f64| csv_num(w.map(f));
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            c.case,
            c.model,
            c.part.name(),
            csv_num(Some(c.eta)),
            csv_num(Some(c.g)),
            csv_num(Some(c.reduced_albedo)),
            csv_num(Some(c.mfp)),
            w(c.near, |w| w.excess),
            w(c.near, |w| w.at),
            w(c.near, |w| w.rel_error),
            w(c.near, |w| w.single),
            csv_num(c.near_median),
            w(c.far, |w| w.excess),
            w(c.far, |w| w.at),
            w(c.far, |w| w.rel_error),
            w(c.far, |w| w.single),
            csv_num(Some(c.total_model)),
            csv_num(Some(c.total_mcml)),
            csv_num(Some(c.total_mcml_se)),
            csv_num(c.total_rel_error()),
            c.bins(),
            c.forgiven(),
        );
    }
    s
}

fn max_of(values: impl Iterator<Item = Option<f64>>) -> Option<f64> {
    values.flatten().filter(|v| v.is_finite()).reduce(f64::max)
}

fn dagger(part: McPart) -> &'static str {
    match part {
        McPart::Multiple => " †",
        McPart::All => "",
    }
}

/// The subsection and the summary line of a successful comparison.
fn report(rows: &[Comparison], cases: &[Case], skipped: &[String], dir: &Path) -> (String, String) {
    let mut models: Vec<(&str, McPart)> = Vec::new();
    for c in rows {
        if !models.iter().any(|(m, _)| *m == c.model) {
            models.push((&c.model, c.part));
        }
    }
    fn of<'a>(rows: &'a [Comparison], m: &'a str) -> impl Iterator<Item = &'a Comparison> {
        rows.iter().filter(move |c| c.model == m)
    }
    let worst_near = |m: &str| max_of(of(rows, m).map(|c| c.near.map(|w| w.excess)));
    let mut summary = format!(
        "Against MCML (Wang, Jacques & Zheng 1995; {} media, per medium below and in \
         `{CSV_NAME}`): worst excess beyond 3 MCML standard errors over 0.25–10 reduced mean \
         free paths — ",
        cases.len()
    );
    let parts: Vec<String> = models
        .iter()
        .map(|(m, p)| format!("`{m}`{} {}", dagger(*p), md_pct(worst_near(m))))
        .collect();
    let _ = writeln!(
        summary,
        "{} († multiple scattering only).",
        parts.join(", ")
    );

    let mut body = format!("### {TITLE}\n\n");
    let _ = writeln!(
        body,
        "Each model against MCML (Wang, Jacques & Zheng 1995), a Monte Carlo code independent \
         of this project's walk, on {} semi-infinite media under a normally incident pencil \
         beam (`{}`). MCML counts its photons before the specular reflection \
         R_sp = ((η − 1)/(η + 1))² at the boundary; the models are per unit power entering, so \
         MCML's profile and total are divided by 1 − R_sp. A model's value for a bin is its \
         area average over the MCML annulus ({GAUSS_POINTS}-point Gauss–Legendre of 2πr R_d). \
         MCML's standard error per bin comes from 5 batches; as in \
         `crates/bssrdf/tests/mcml.rs` it is pooled over the 21 bins around each bin.\n\n\
         - *excess*: (|model − MCML| − 3 SE)/MCML, worst over the bins of the range (0 when \
         every bin is within 3 SE), in reduced mean free paths x = r/ℓ, ℓ = 1/(σ_a + σ_s(1 − g)). \
         Single MCML bins have heavy-tailed errors (a few photons of large weight), so a bin \
         counts only as far as its neighbourhood agrees: its effective excess is the smaller \
         of its own and that of the 5 bins around it (light summed, variances added). \
         *forgiven*: bins beyond the test's margin (3 % within 10 ℓ, 10 % beyond) alone but \
         within it over their 5 bins; the worst single-bin excess is in `{CSV_NAME}`.\n\
         - *median error*: median of |model − MCML|/MCML over the bins in 0.25–10 ℓ, for \
         reference (it includes MCML's noise).\n\
         - *total*: (model − MCML)/MCML of the total diffuse reflectance (MCML: all radii).\n\
         - † The standard and better dipoles model multiple scattering only; MCML has every \
         scattering order, so their figures include the missing single scattering (they are \
         measured against our walk's multiple-scattering part above).\n",
        cases.len(),
        dir.display()
    );
    for note in skipped {
        let _ = writeln!(body, "- Skipped: {note}.");
    }
    body.push('\n');
    let model_rows: Vec<Vec<String>> = models
        .iter()
        .map(|(m, p)| {
            vec![
                format!("`{m}`{}", dagger(*p)),
                md_pct(worst_near(m)),
                md_pct(max_of(of(rows, m).map(|c| c.far.map(|w| w.excess)))),
                md_pct(max_of(
                    of(rows, m).map(|c| c.total_rel_error().map(f64::abs)),
                )),
                md_pct(max_of(of(rows, m).map(|c| c.near_median))),
            ]
        })
        .collect();
    let _ = writeln!(body, "Worst over the {} media, per model:\n", cases.len());
    body.push_str(&md_table(
        &[
            "model",
            "excess 0.25–10 ℓ",
            "excess 10–16 ℓ",
            "abs. total error",
            "largest median error 0.25–10 ℓ",
        ],
        &model_rows,
    ));
    body.push('\n');
    let at = |w: Option<Worst>| match w {
        Some(w) if w.excess > 0.0 => {
            format!("{} at {}", md_pct(Some(w.excess)), md_num(Some(w.at), 3))
        }
        Some(_) => "0 %".into(),
        None => "–".into(),
    };
    let detail: Vec<Vec<String>> = rows
        .iter()
        .map(|c| {
            vec![
                c.case.clone(),
                md_num(Some(c.reduced_albedo), 4),
                format!("`{}`{}", c.model, dagger(c.part)),
                at(c.near),
                md_pct(c.near_median),
                at(c.far),
                md_pct(c.total_rel_error()),
                format!("{} / {}", c.forgiven(), c.bins()),
            ]
        })
        .collect();
    let _ = writeln!(body, "Per medium and model:\n");
    body.push_str(&md_table(
        &[
            "case",
            "α′",
            "model",
            "excess 0.25–10 ℓ (at x)",
            "median error 0.25–10 ℓ",
            "excess 10–16 ℓ (at x)",
            "total vs MCML",
            "forgiven / bins",
        ],
        &detail,
    ));
    (summary, body)
}

/// The MCML part of the profiles experiment: compares every model with the cases in `dir`,
/// writes `out/mcml.csv` and returns (summary line, body subsection). When the folder is
/// absent or unusable it says so in both, writes no `mcml.csv` and removes one left by an
/// earlier run. Errors only when an output cannot be written.
pub fn run(dir: &Path, out: &Path) -> Result<Section, Error> {
    let csv = out.join(CSV_NAME);
    let skip = |why: String| -> Result<Section, Error> {
        if csv.exists() {
            std::fs::remove_file(&csv)
                .map_err(|e| Error(format!("cannot remove stale '{}': {e}", csv.display())))?;
        }
        let line = format!(
            "The comparison with MCML was skipped: {why} (set `SSS_MCML_DIR` to the folder of \
             the MCML profiles)."
        );
        Ok(Section {
            title: TITLE.into(),
            summary: format!("{line}\n"),
            body: format!("### {TITLE}\n\n{line}\n"),
        })
    };
    let (cases, skipped) = match load(dir) {
        Reference::Absent(why) | Reference::Unusable(why) => return skip(why),
        Reference::Found { cases, skipped } => (cases, skipped),
    };
    if cases.is_empty() {
        return skip(format!(
            "no usable case in `{}` ({})",
            dir.display(),
            skipped.join("; ")
        ));
    }
    let rows = compare_all(&cases);
    write_atomic(&csv, results_csv(&rows).as_bytes())?;
    let (summary, body) = report(&rows, &cases, &skipped, dir);
    Ok(Section {
        title: TITLE.into(),
        summary,
        body,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A temporary folder, removed on drop.
    struct TempDir(PathBuf);

    impl TempDir {
        fn new(tag: &str) -> TempDir {
            let d = std::env::temp_dir().join(format!("xtask-mcml-{tag}-{}", std::process::id()));
            let _ = std::fs::remove_dir_all(&d);
            std::fs::create_dir_all(&d).unwrap();
            TempDir(d)
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    const HEADER: &str = "case,sigma_a_per_mm,sigma_s_per_mm,g,eta,eta_above,dr_mm,batches,photons,total_diffuse_reflectance,total_se";

    /// Writes a case whose profile is `factor` × the standard dipole's area averages per
    /// incident photon (its total likewise), with zero standard errors, 0–20 mfp.
    fn synthetic(dir: &Path, name: &str, eta: f64, factor: f64) -> Medium {
        let medium = Medium::new([0.01; 3], [1.0; 3], 0.0, eta).unwrap();
        let model = make_model(ModelKind::StandardDipole, &medium);
        let entering = 1.0 - ((eta - 1.0) / (eta + 1.0)).powi(2);
        let dr = 0.1;
        let mut profile = String::from("r_mm,rd_per_mm2,se_per_mm2\n");
        for i in 0..200 {
            let (lo, hi) = (i as f64 * dr, (i + 1) as f64 * dr);
            let mass = integrate(&|s| 2.0 * PI * s * model.rd(0, s), lo, hi, GAUSS_POINTS);
            let avg = factor * entering * mass / (PI * (hi * hi - lo * lo));
            let _ = writeln!(profile, "{},{avg:e},0", (i as f64 + 0.5) * dr);
        }
        std::fs::write(dir.join(format!("{name}.csv")), profile).unwrap();
        let total = factor * entering * model.total_diffuse_reflectance(0);
        let cases = dir.join("cases.csv");
        let mut text = std::fs::read_to_string(&cases).unwrap_or(format!("{HEADER}\n"));
        let _ = writeln!(text, "{name},0.01,1.0,0,{eta},1.0,{dr},5,1000,{total:e},0");
        std::fs::write(cases, text).unwrap();
        medium
    }

    fn one(dir: &Path) -> (Vec<Case>, Vec<String>) {
        match load(dir) {
            Reference::Found { cases, skipped } => (cases, skipped),
            other => panic!("{other:?}"),
        }
    }

    fn against_dipole(case: &Case) -> Comparison {
        let model = make_model(ModelKind::StandardDipole, &case.medium);
        compare(case, "standard-dipole", McPart::Multiple, model.as_ref())
    }

    #[test]
    fn a_model_equal_to_the_profile_has_no_error_and_ten_percent_reads_ten_percent() {
        let tmp = TempDir::new("equal");
        synthetic(&tmp.0, "same", 1.3, 1.0);
        // The model 10 % above MCML: MCML = model / 1.1.
        synthetic(&tmp.0, "low", 1.0, 1.0 / 1.1);
        let (cases, skipped) = one(&tmp.0);
        assert!(skipped.is_empty(), "{skipped:?}");
        assert_eq!(cases.len(), 2);
        // Normalised per entering photon (η = 1.3: R_sp = 0.017).
        assert!((cases[0].entering() - (1.0 - (0.3f64 / 2.3).powi(2))).abs() < 1e-15);
        let same = against_dipole(&cases[0]);
        let near = same.near.unwrap();
        assert!(near.excess < 1e-12, "{near:?}");
        assert!(near.rel_error.abs() < 1e-9, "{near:?}");
        assert!(same.near_median.unwrap() < 1e-9);
        assert!(same.total_rel_error().unwrap().abs() < 1e-12);
        let low = against_dipole(&cases[1]);
        for w in [low.near.unwrap(), low.far.unwrap()] {
            assert!((w.excess - 0.1).abs() < 1e-9, "{w:?}");
            assert!((w.rel_error - 0.1).abs() < 1e-9, "{w:?}");
        }
        // 10 % is beyond the near margin (3 %) in every bin and its neighbourhood alike.
        // (It is the far margin itself, so rounding decides there.)
        assert_eq!(low.near.unwrap().forgiven, 0);
        assert!((low.near_median.unwrap() - 0.1).abs() < 1e-9);
        assert!((low.total_rel_error().unwrap() - 0.1).abs() < 1e-12);
        // Bins: ℓ = 1/1.01 mm, bins of 0.1 mm: 0.25–10 ℓ holds centres 0.25–9.9 mm.
        let mfp = cases[1].medium.reduced_mean_free_path(0);
        let expect = (0..200)
            .map(|i| (i as f64 + 0.5) * 0.1 / mfp)
            .filter(|x| (0.25..=10.0).contains(x))
            .count();
        assert_eq!(low.near.unwrap().bins, expect);
        let csv = results_csv(&[same, low]);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[0], CSV_HEADER);
        for l in &lines[1..] {
            assert_eq!(l.split(',').count(), CSV_HEADER.split(',').count(), "{l}");
            assert!(
                !l.to_lowercase().contains("nan") && !l.contains("inf"),
                "{l}"
            );
        }
        assert!(
            lines[2].starts_with("low,standard-dipole,multiple,1e0,0e0,"),
            "{}",
            lines[2]
        );
    }

    #[test]
    fn an_isolated_outlier_is_forgiven_but_a_shifted_neighbourhood_is_not() {
        // Eleven bins of equal light at 1–6 ℓ, SE 1 % each: 3 SE = 3 %.
        let row = |x: f64, model: f64| BinRow {
            x,
            model,
            mcml: 1.0,
            var: 1e-4,
        };
        let mut rows: Vec<BinRow> = (0..11).map(|i| row(1.0 + 0.5 * i as f64, 1.0)).collect();
        // One bin 20 % high: alone 17 % beyond 3 SE; over its 5 bins the excess is
        // (0.2 − 3·√5·0.01)/5 = 2.66 %, so it counts as 2.66 % and is forgiven (< 3 %).
        rows[5].model = 1.2;
        let w = worst(&rows, Range::Near).unwrap();
        let group = (0.2 - 3.0 * (5e-4f64).sqrt()) / 5.0;
        assert!((w.excess - group).abs() < 1e-12, "{w:?}");
        assert!((w.single - 0.17).abs() < 1e-12, "{w:?}");
        assert_eq!((w.forgiven, w.bins, w.at), (1, 11, 3.5));
        // The whole neighbourhood 20 % high: every bin counts 17 %.
        for r in &mut rows[3..8] {
            r.model = 1.2;
        }
        let w = worst(&rows, Range::Near).unwrap();
        assert!((w.excess - 0.17).abs() < 1e-12, "{w:?}");
        assert_eq!((w.forgiven, w.at), (0, 3.5));
        assert!((w.rel_error - 0.2).abs() < 1e-12);
        // Within 3 SE everywhere: 0; an empty range: undefined.
        let ok: Vec<BinRow> = (0..11).map(|i| row(1.0 + 0.5 * i as f64, 1.02)).collect();
        assert_eq!(worst(&ok, Range::Near).unwrap().excess, 0.0);
        assert!(worst(&ok, Range::Far).is_none());
    }

    #[test]
    fn the_pooled_standard_error_follows_the_bin_variance_law() {
        // SE² · area / Rd constant over the window: the pooled SE is the bins' own SE.
        let medium = Medium::new([0.01; 3], [1.0; 3], 0.0, 1.0).unwrap();
        let mut case = Case {
            name: "c".into(),
            medium,
            dr: 0.5,
            total: 0.5,
            total_se: 0.0,
            bins: Vec::new(),
        };
        let bins: Vec<(f64, f64, f64)> = (0..30)
            .map(|i| {
                let r = (i as f64 + 0.5) * 0.5;
                (r, 2.0, (2.0 * 1e-3 / case.area(r)).sqrt())
            })
            .collect();
        case.bins = bins.clone();
        for (a, b) in case.normalised_bins().iter().zip(&bins) {
            assert_eq!(a.1, b.1);
            assert!((a.2 / b.2 - 1.0).abs() < 1e-12, "{a:?} {b:?}");
        }
    }

    #[test]
    fn an_absent_folder_is_skipped_and_writes_no_csv() {
        let tmp = TempDir::new("absent");
        let out = tmp.0.join("out");
        std::fs::create_dir_all(&out).unwrap();
        std::fs::write(out.join(CSV_NAME), "stale").unwrap();
        let s = run(&tmp.0.join("no-such-folder"), &out).unwrap();
        assert!(
            s.body.starts_with(&format!("### {TITLE}\n\n")),
            "{}",
            s.body
        );
        assert!(s.body.contains("was skipped: there is no `"), "{}", s.body);
        assert!(s.summary.contains("skipped"));
        assert!(!out.join(CSV_NAME).exists());
    }

    #[test]
    fn malformed_files_are_skipped_with_a_note_naming_them() {
        let tmp = TempDir::new("malformed");
        let out = tmp.0.join("out");
        std::fs::create_dir_all(&out).unwrap();
        synthetic(&tmp.0, "good", 1.0, 1.0);
        synthetic(&tmp.0, "broken", 1.0, 1.0);
        std::fs::write(
            tmp.0.join("broken.csv"),
            "r_mm,rd_per_mm2,se_per_mm2\n0.05,1e-2,0\n0.15,NaN,0\n",
        )
        .unwrap();
        let mut cases = std::fs::read_to_string(tmp.0.join("cases.csv")).unwrap();
        cases.push_str("missing,0.01,1.0,0,1.0,1.0,0.1,5,1000,0.5,0\n");
        cases.push_str("../evil,0.01,1.0,0,1.0,1.0,0.1,5,1000,0.5,0\n");
        cases.push_str("short,0.01\n");
        std::fs::write(tmp.0.join("cases.csv"), cases).unwrap();
        let s = run(&tmp.0, &out).unwrap();
        for note in [
            "`broken.csv`: line 3: `NaN` is not a finite non-negative number",
            "`cases.csv` line 4: `missing.csv`: cannot read",
            "`cases.csv` line 5: case name `../evil` is not a plain file name",
            "`cases.csv` line 6: too few fields",
        ] {
            assert!(s.body.contains(note), "{note}\n{}", s.body);
        }
        let csv = std::fs::read_to_string(out.join(CSV_NAME)).unwrap();
        assert_eq!(csv.lines().count(), 1 + ModelKind::ALL.len());
        assert!(
            s.summary.contains("Wang, Jacques & Zheng 1995"),
            "{}",
            s.summary
        );
        // A cases.csv without a needed column: the whole comparison is skipped, no CSV.
        std::fs::write(tmp.0.join("cases.csv"), "case,eta\ngood,1\n").unwrap();
        let s = run(&tmp.0, &out).unwrap();
        assert!(
            s.body.contains("has no column `sigma_a_per_mm`"),
            "{}",
            s.body
        );
        assert!(!out.join(CSV_NAME).exists());
    }

    #[test]
    fn the_folder_is_the_environment_variable_or_next_to_the_workspace() {
        assert_eq!(dir_from(Some("/x/y".into())), PathBuf::from("/x/y"));
        let d = dir_from(None);
        assert!(d.ends_with("../shared/reference/mcml"), "{}", d.display());
        assert_eq!(
            d.parent()
                .unwrap()
                .parent()
                .unwrap()
                .parent()
                .unwrap()
                .parent()
                .unwrap(),
            crate::workspace_root().as_path()
        );
    }
}
