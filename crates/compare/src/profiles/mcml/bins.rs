//! A case's bins per unit power entering, with pooled standard errors, beside a model's area
//! averages; the worst excess over a range of radii and the median error.

use super::*;

impl Case {
    /// The fraction of the beam that enters: 1 − R_sp, R_sp = ((η − 1)/(η + 1))².
    pub fn entering(&self) -> f64 {
        let eta = self.medium.eta();
        1.0 - ((eta - 1.0) / (eta + 1.0)).powi(2)
    }

    pub(super) fn area(&self, r: f64) -> f64 {
        let (lo, hi) = ((r - 0.5 * self.dr).max(0.0), r + 0.5 * self.dr);
        PI * (hi * hi - lo * lo)
    }

    /// The bins per unit power entering, each SE replaced by a pooled one: at a fixed weight
    /// per photon a bin average's variance is c·Rd_r/area, so over the 21 bins around each bin
    /// c = Σ SE²·area / Σ Rd_r and Rd_r is averaged by area, and SE = √(c Rd_r / area) (as in
    /// `crates/bssrdf/tests/integration/mcml.rs`).
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

pub(super) fn excess(model: f64, mcml: f64, var: f64) -> f64 {
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

    /// The margin of `crates/bssrdf/tests/integration/mcml.rs` for the range ([`MARGINS`]).
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
    median(
        rows.iter()
            .filter(|b| range.contains(b.x))
            .map(|b| (b.model / b.mcml - 1.0).abs()),
    )
}
