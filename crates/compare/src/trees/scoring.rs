//! Scoring a render against the subset reference, and the comparisons between runs: time at
//! equal error, the equal-time pair.

use super::*;

/// An image's error on the subset: RMSE (over pixels and channels) with its standard error,
/// and the RMSE relative to the reference's root mean square over the subset.
#[derive(Clone, Copy, Debug)]
pub(super) struct Score {
    pub(super) rmse: f64,
    pub(super) rmse_se: f64,
    pub(super) rel_rmse: f64,
}

pub(super) fn score(image: &[Rgb], r: &SubsetReference) -> Result<Score, Error> {
    let e = r.error(image)?;
    let n = r.values.len().max(1) as f64;
    let ref_ms = r
        .values
        .iter()
        .map(|v| (0..3).map(|c| v[c] * v[c]).sum::<f64>() / 3.0)
        .sum::<f64>()
        / n;
    Ok(Score {
        rmse: e.rmse,
        rmse_se: e.rmse_se,
        rel_rmse: if ref_ms > 0.0 {
            e.rmse / ref_ms.sqrt()
        } else {
            0.0
        },
    })
}

/// The dual tree's total time at the single tree's RMSE `target`, interpolated log-log along
/// the dual tree's (time, RMSE) points; `None` outside their range.
pub(super) fn time_at_rmse(points: &[(f64, f64)], target: f64) -> Option<f64> {
    let mut pts: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|p| p.0 > 0.0 && p.1 > 0.0)
        .collect();
    pts.sort_by(|a, b| a.1.total_cmp(&b.1));
    if let Some(p) = pts.iter().find(|p| p.1 == target) {
        return Some(p.0);
    }
    pts.windows(2).find_map(|w| {
        let (a, b) = (w[0], w[1]);
        if a.1 < target && target < b.1 {
            let f = (target.ln() - a.1.ln()) / (b.1.ln() - a.1.ln());
            Some((a.0.ln() + f * (b.0.ln() - a.0.ln())).exp())
        } else {
            None
        }
    })
}

/// The equal-time pair of the pictures: the paper's dual tree at [`FIXED_EPS`] and ρ = [`RHO`],
/// and the most accurate `dual-tree-fmm` run of the sweep that took no more total time (the
/// fastest one if none did).
pub(super) fn equal_time_pair<'r>(sweep: &[&'r TreeRun]) -> Option<(&'r TreeRun, &'r TreeRun)> {
    let d = *sweep
        .iter()
        .find(|r| r.method == "dual-tree" && r.rho == Some(RHO) && r.eps == FIXED_EPS)?;
    let fmm: Vec<&TreeRun> = sweep
        .iter()
        .copied()
        .filter(|r| r.method == "dual-tree-fmm")
        .collect();
    let within = fmm
        .iter()
        .copied()
        .filter(|r| r.total() <= d.total())
        .min_by(|a, b| a.score.rmse.total_cmp(&b.score.rmse));
    let f = within.or_else(|| {
        fmm.iter()
            .copied()
            .min_by(|a, b| a.total().total_cmp(&b.total()))
    })?;
    Some((d, f))
}
