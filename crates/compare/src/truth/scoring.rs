//! How a render is scored against the truth: its image mean per channel over the reference's,
//! and its relative RMSE with the reference's own noise removed; and when `volpath` itself
//! reaches a given error (the crossover).

use super::*;

/// A render's figures against the truth, over the reference's translucent pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Score {
    /// Image mean over the reference's mean, per channel.
    pub mean_ratio: Rgb,
    /// Relative RMSE: √(mean over pixels and channels of (x − r)² − σ_r²) over the reference's
    /// mean, where σ_r is the reference's standard error at the pixel (its noise adds σ_r² to
    /// the expected squared difference, which is removed; 0 if the result would be negative).
    pub rel_rmse: f64,
}

/// `image` scored against `truth`.
pub(crate) fn score(image: &[Rgb], truth: &Truth) -> Score {
    score_without_noise(image, &[], truth)
}

/// `image`, whose pixels have standard errors `se` (empty: none), scored against `truth` with
/// both noises removed: each squared difference minus σ_r² + σ_x², so that the relative RMSE
/// estimates the bias of what the image converges to.
pub(crate) fn score_without_noise(image: &[Rgb], se: &[Rgb], truth: &Truth) -> Score {
    let mut mean_ratio = [0.0; 3];
    let (mut sum_i, mut sum_r) = ([0.0; 3], [0.0; 3]);
    let mut sq = 0.0;
    for &p in &truth.pixels {
        for c in 0..3 {
            let (x, r, s) = (image[p][c], truth.image[p][c], truth.se[p][c]);
            let s_x = se.get(p).map_or(0.0, |v| v[c]);
            sum_i[c] += x;
            sum_r[c] += r;
            sq += (x - r) * (x - r) - s * s - s_x * s_x;
        }
    }
    for c in 0..3 {
        mean_ratio[c] = if sum_r[c] > 0.0 {
            sum_i[c] / sum_r[c]
        } else {
            0.0
        };
    }
    let n = (3 * truth.pixels.len()) as f64;
    let mean = (sum_r[0] + sum_r[1] + sum_r[2]) / n.max(1.0);
    let rel_rmse = if n > 0.0 && mean > 0.0 {
        (sq / n).max(0.0).sqrt() / mean
    } else {
        0.0
    };
    Score {
        mean_ratio,
        rel_rmse,
    }
}

/// `volpath`'s error against time, fitted to its sweep: error = a / √(t − t₀), t₀ its fixed
/// cost (the stages before the paths: BVHs, G-buffer, models), a from the runs of at least 4
/// paths per pixel (Monte Carlo error falls as one over the square root of the paths, so of
/// the shading time).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Crossover {
    /// The fixed cost t₀ (seconds).
    pub overhead: f64,
    /// a (relative RMSE × √seconds).
    pub a: f64,
}

impl Crossover {
    /// The fit to `runs`: (paths per pixel, total seconds, shading seconds, relative RMSE).
    /// None without a usable run.
    pub fn fit(runs: &[(u32, f64, f64, f64)]) -> Option<Crossover> {
        let usable: Vec<&(u32, f64, f64, f64)> = runs
            .iter()
            .filter(|r| r.0 >= 4 && r.2 > 0.0 && r.3 > 0.0)
            .collect();
        if usable.is_empty() {
            return None;
        }
        let k = usable.len() as f64;
        // Least squares in log space with the slope fixed at −1/2.
        let log_a = usable
            .iter()
            .map(|r| r.3.ln() + 0.5 * r.2.ln())
            .sum::<f64>()
            / k;
        let overhead = usable.iter().map(|r| (r.1 - r.2).max(0.0)).sum::<f64>() / k;
        Some(Crossover {
            overhead,
            a: log_a.exp(),
        })
    }

    /// The total seconds at which `volpath` reaches relative RMSE `error` (None for an error
    /// of 0, which it never reaches).
    pub fn seconds_for(&self, error: f64) -> Option<f64> {
        (error > 0.0 && error.is_finite()).then(|| self.overhead + (self.a / error).powi(2))
    }
}
