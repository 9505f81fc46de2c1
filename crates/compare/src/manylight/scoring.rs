//! Scoring an estimate against the path-traced reference: per pixel within ε at the
//! interval's confidence, pooled over scenes, and the accuracy a calibrated interval would
//! score against a reference with its own noise.

use super::*;

/// Luminance (Rec. 709), the scalar the estimators' error is controlled on.
pub(super) use sss_util::luminance as lum;

/// What a run's estimates score against the reference.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Score {
    /// Fraction of the scored pixels with |Î − I| < ε I (luminance).
    pub(super) accuracy: f64,
    /// Pixels scored at ε: those whose reference resolves it ([`Reference::resolves`]).
    pub(super) scored: usize,
    /// RMSE over the subset (pixels and channels).
    pub(super) rmse: f64,
    /// Relative bias of the summed luminance over the subset, Σ (Î − I) / Σ I.
    pub(super) bias: f64,
    /// Standard error of `bias`, from the pixels' errors themselves (√Σ(Î − I)² / Σ I: every
    /// source of noise, the reference's, the estimate's and a baseline's point set's, whether
    /// or not the method reports it; an upper bound where there is a bias).
    pub(super) bias_se: f64,
}

/// Scores the estimates `out` of the reference's pixels at `eps`. The bias is over every
/// subset pixel (a method that estimates another integral shows there, where RMSE cannot tell
/// bias from noise).
pub(super) fn score(out: &[PixelResult], r: &Reference, eps: f64) -> Score {
    let (mut n, mut ok, mut se) = (0usize, 0usize, 0.0);
    let (mut d, mut t, mut var) = (0.0, 0.0, 0.0);
    for (k, (o, v)) in out.iter().zip(&r.values).enumerate() {
        for (x, y) in o.subsurface.iter().zip(v) {
            se += (x - y) * (x - y);
        }
        let (a, b) = (lum(o.subsurface), lum(*v));
        d += a - b;
        t += b;
        var += (a - b) * (a - b);
        if r.resolves(k, eps) {
            n += 1;
            if (a - b).abs() < eps * b {
                ok += 1;
            }
        }
    }
    Score {
        accuracy: if n > 0 { ok as f64 / n as f64 } else { 0.0 },
        scored: n,
        rmse: (se / (3 * out.len().max(1)) as f64).sqrt(),
        bias: if t > 0.0 { d / t } else { 0.0 },
        bias_se: if t > 0.0 { var.sqrt() / t } else { 0.0 },
    }
}

/// Mean accuracy over seeds and its binomial standard error over all pixel estimates.
pub(super) fn pooled(rows: &[&Row]) -> (f64, f64, usize) {
    let n: usize = rows.iter().map(|r| r.pixels).sum();
    if n == 0 {
        return (0.0, 0.0, 0);
    }
    let ok: f64 = rows.iter().map(|r| r.accuracy * r.pixels as f64).sum();
    let a = ok / n as f64;
    (a, (a * (1.0 - a) / n as f64).sqrt(), n)
}

/// The accuracy rows of `method` on `scene` at `eps` (every stream).
pub(super) fn accuracy_rows<'a>(
    rows: &'a [Row],
    scene: &str,
    method: &str,
    eps: f64,
) -> Vec<&'a Row> {
    rows.iter()
        .filter(|r| {
            r.scene == scene && r.experiment == "accuracy" && r.method == method && r.eps == eps
        })
        .collect()
}

/// The accuracy at `eps` that an estimate with a normal error and a 95 % interval of exactly
/// ±ε (standard deviation ε/1.96) scores on average against `r` on the pixels that resolve
/// `eps`: the mean over them of P(|e| < ε) for e normal with variance (ε/1.96)² + σ_ref².
pub(super) fn calibrated(r: &Reference, eps: f64) -> f64 {
    let (mut n, mut sum) = (0usize, 0.0);
    for k in 0..r.pixels.len() {
        if r.resolves(k, eps) {
            let s = ((eps / 1.96).powi(2) + r.rel_se[k].powi(2)).sqrt();
            n += 1;
            sum += erf(eps / (s * std::f64::consts::SQRT_2));
        }
    }
    if n > 0 { sum / n as f64 } else { 0.0 }
}
