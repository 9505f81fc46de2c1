//! Image error metrics, in one place for `sss diff`, `cargo xtask compare` and the tests: RMSE,
//! relative RMSE, the fraction of pixels within a relative error, the mean ratio against a
//! reference, and the fraction within k standard errors. All are taken over a list of pixel
//! indices (the pixels with translucent coverage, by convention) and never return NaN.
//!
//! At resolutions where a reference of every pixel is too slow, [`subset_pixels`] draws a
//! seeded uniform random subset of those pixels, the reference is computed there only
//! ([`crate::integrators::exact::shade_subset`]), and [`subset_error`] estimates the full
//! image's mean squared error from the subset, with its standard error.

use sss_bssrdf::Rgb;

/// Error figures of an image against a reference over a set of pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorFigures {
    /// Root mean square error over pixels and channels.
    pub rmse: f64,
    /// RMSE divided by the reference's mean over the same pixels and channels.
    pub rel_rmse: f64,
    /// Fraction of pixels whose relative error (per-pixel luminance-free: max over channels of
    /// |a − b| / max(b, floor)) is below `eps`.
    pub frac_within_eps: f64,
}

/// Per-pixel relative error: max over channels of |a − b| / max(b, floor), where `floor` is 1 %
/// of the reference's mean (so nearly black pixels do not dominate).
pub fn relative_errors(image: &[Rgb], reference: &[Rgb], pixels: &[usize]) -> Vec<f64> {
    let mean = reference_mean(reference, pixels);
    let floor = (mean * 0.01).max(1e-300);
    pixels
        .iter()
        .map(|&i| {
            (0..3)
                .map(|c| (image[i][c] - reference[i][c]).abs() / reference[i][c].max(floor))
                .fold(0.0, f64::max)
        })
        .collect()
}

/// Per-pixel signed relative error of the channel mean: (mean_c a − mean_c b) / max(mean_c b,
/// floor), with the `floor` of [`relative_errors`]: negative where the image is too dark.
pub fn signed_relative_errors(image: &[Rgb], reference: &[Rgb], pixels: &[usize]) -> Vec<f64> {
    let floor = (reference_mean(reference, pixels) * 0.01).max(1e-300);
    let mean = |p: &Rgb| p.iter().sum::<f64>() / 3.0;
    pixels
        .iter()
        .map(|&i| {
            let b = mean(&reference[i]);
            (mean(&image[i]) - b) / b.max(floor)
        })
        .collect()
}

fn reference_mean(reference: &[Rgb], pixels: &[usize]) -> f64 {
    if pixels.is_empty() {
        return 0.0;
    }
    pixels
        .iter()
        .map(|&i| reference[i].iter().sum::<f64>() / 3.0)
        .sum::<f64>()
        / pixels.len() as f64
}

/// RMSE, relative RMSE and the fraction of pixels within `eps` relative error, over `pixels`.
pub fn error_figures(image: &[Rgb], reference: &[Rgb], pixels: &[usize], eps: f64) -> ErrorFigures {
    if pixels.is_empty() {
        return ErrorFigures {
            rmse: 0.0,
            rel_rmse: 0.0,
            frac_within_eps: 1.0,
        };
    }
    let mut se = 0.0;
    for &i in pixels {
        for c in 0..3 {
            let d = image[i][c] - reference[i][c];
            se += d * d;
        }
    }
    let rmse = (se / (3 * pixels.len()) as f64).sqrt();
    let mean = reference_mean(reference, pixels);
    let rel = relative_errors(image, reference, pixels);
    let within = rel.iter().filter(|e| **e < eps).count();
    ErrorFigures {
        rmse,
        rel_rmse: if mean > 0.0 { rmse / mean } else { 0.0 },
        frac_within_eps: within as f64 / pixels.len() as f64,
    }
}

/// Ratio of the image's mean to the reference's over `pixels`, per channel (0 where the
/// reference's mean is 0).
pub fn mean_ratio_rgb(image: &[Rgb], reference: &[Rgb], pixels: &[usize]) -> Rgb {
    // The means share the pixel count, so their ratio is the ratio of the sums.
    let sum = |img: &[Rgb]| -> Rgb {
        let mut m = [0.0; 3];
        for &i in pixels {
            for c in 0..3 {
                m[c] += img[i][c];
            }
        }
        m
    };
    let (ma, mb) = (sum(image), sum(reference));
    [0, 1, 2].map(|c| if mb[c] > 0.0 { ma[c] / mb[c] } else { 0.0 })
}

/// Ratio of the image's sum to the reference's over `pixels` and all channels (0 when the
/// reference sums to 0): 1 for an unbiased method, up to noise.
pub fn mean_ratio(image: &[Rgb], reference: &[Rgb], pixels: &[usize]) -> f64 {
    let sum = |img: &[Rgb]| -> f64 { pixels.iter().map(|&i| img[i].iter().sum::<f64>()).sum() };
    let r = sum(reference);
    if r > 0.0 { sum(image) / r } else { 0.0 }
}

/// Fraction of `pixels` whose every channel lies within `k` standard errors `se` of the
/// reference (plus 1e-12 relative, so exact agreement with a zero error bar counts); `None`
/// for no pixels.
pub fn frac_within_se(
    image: &[Rgb],
    se: &[Rgb],
    reference: &[Rgb],
    pixels: &[usize],
    k: f64,
) -> Option<f64> {
    if pixels.is_empty() {
        return None;
    }
    let ok = pixels
        .iter()
        .filter(|&&i| {
            (0..3).all(|c| {
                let d = (image[i][c] - reference[i][c]).abs();
                d <= k * se[i][c] + 1e-12 * reference[i][c].abs()
            })
        })
        .count();
    Some(ok as f64 / pixels.len() as f64)
}

/// A seeded uniform random subset of `n` distinct entries of `pixels` (all of them when
/// `n ≥ pixels.len()`), in increasing order: a partial Fisher–Yates shuffle driven by
/// SplitMix64 (`sss_util::splitmix64`) from `seed`, each index drawn as ⌊x·m/2⁶⁴⌋ from a 64-bit
/// x (bias below m/2⁶⁴). The same seed gives the same subset on every machine.
pub fn subset_pixels(pixels: &[usize], n: usize, seed: u64) -> Vec<usize> {
    let mut v = pixels.to_vec();
    let n = n.min(v.len());
    let base = sss_util::splitmix64(seed ^ 0x5375_6273_6574_0000); // "Subset"
    for i in 0..n {
        let m = (v.len() - i) as u128;
        let x = sss_util::splitmix64(base.wrapping_add(i as u64)) as u128;
        let j = i + ((x * m) >> 64) as usize;
        v.swap(i, j);
    }
    v.truncate(n);
    v.sort_unstable();
    v
}

/// The error of an image estimated over a uniform random subset of the pixels it is scored on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SubsetError {
    /// Pixels in the subset (n).
    pub pixels: usize,
    /// Pixels the subset was drawn from (N): the pixels with translucent coverage.
    pub population: usize,
    /// The mean over the subset of each pixel's squared error averaged over channels: an
    /// unbiased estimate of the full image's MSE over the N pixels (the square of
    /// [`ErrorFigures::rmse`]).
    pub mse: f64,
    /// Its standard error, √((1 − n/N) s²/n) with s² the subset's sample variance of the
    /// per-pixel squared errors (sampling without replacement, with the finite-population
    /// correction: 0 when the subset is every pixel; Cochran, *Sampling Techniques*, 3rd ed.,
    /// Thm. 2.2 and Eq. 2.9).
    pub mse_se: f64,
    /// √mse: the RMSE estimate (biased low by O(mse_se²/mse^{3/2}), as any square root of an
    /// unbiased estimate).
    pub rmse: f64,
    /// The RMSE's standard error by the delta method, mse_se/(2 √mse) (0 when mse is 0).
    pub rmse_se: f64,
}

/// Estimates the MSE of `image` (every pixel) over the `population` pixels with translucent
/// coverage from the uniform random `subset` of them ([`subset_pixels`]) and the reference's
/// values there, `reference[k]` for pixel `subset[k]`. Errors on mismatched lengths, a subset
/// larger than the population, a repeated pixel or an index past the image; an empty subset
/// gives 0 with a 0 standard error (as [`error_figures`] does for no pixels).
pub fn subset_error(
    image: &[Rgb],
    subset: &[usize],
    reference: &[Rgb],
    population: usize,
) -> Result<SubsetError, crate::Error> {
    let fail = |m: String| Err(crate::Error::Input(format!("subset error: {m}")));
    if subset.len() != reference.len() {
        return fail(format!(
            "{} pixels but {} reference values",
            subset.len(),
            reference.len()
        ));
    }
    if subset.len() > population {
        return fail(format!(
            "a subset of {} pixels from a population of {population}",
            subset.len()
        ));
    }
    if let Some(&i) = subset.iter().find(|&&i| i >= image.len()) {
        return fail(format!(
            "pixel {i} is past the image's {} pixels",
            image.len()
        ));
    }
    let mut sorted = subset.to_vec();
    sorted.sort_unstable();
    if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
        return fail(format!("pixel {} appears twice", w[0]));
    }
    let n = subset.len();
    let e: Vec<f64> = subset
        .iter()
        .zip(reference)
        .map(|(&i, r)| (0..3).map(|c| (image[i][c] - r[c]).powi(2)).sum::<f64>() / 3.0)
        .collect();
    let mse = if n > 0 {
        e.iter().sum::<f64>() / n as f64
    } else {
        0.0
    };
    let mse_se = if n > 1 {
        let s2 = e.iter().map(|x| (x - mse).powi(2)).sum::<f64>() / (n - 1) as f64;
        let fpc = (1.0 - n as f64 / population as f64).max(0.0);
        (fpc * s2 / n as f64).sqrt()
    } else {
        0.0
    };
    let rmse = mse.sqrt();
    let figures = SubsetError {
        pixels: n,
        population,
        mse,
        mse_se,
        rmse,
        rmse_se: if rmse > 0.0 {
            mse_se / (2.0 * rmse)
        } else {
            0.0
        },
    };
    if [mse, mse_se, rmse].iter().all(|v| v.is_finite()) {
        Ok(figures)
    } else {
        Err(crate::Error::NonFinite(format!(
            "subset error: non-finite figures {figures:?} (a pixel value is not finite)"
        )))
    }
}

/// The pixels of `pixels` (ascending indices of a `width` × `height` image) whose eight
/// neighbours are in `pixels` too (none on the image's border): where a silhouette or a mask
/// is whole around a pixel, so that two renderers' pixels there mean the same thing.
pub fn interior_pixels(pixels: &[usize], width: u32, height: u32) -> Vec<usize> {
    let (w, h) = (width as usize, height as usize);
    let mut on = vec![false; w * h];
    for &i in pixels {
        if i < on.len() {
            on[i] = true;
        }
    }
    pixels
        .iter()
        .copied()
        .filter(|&i| {
            let (x, y) = (i % w, i / w);
            x > 0
                && y > 0
                && x + 1 < w
                && y + 1 < h
                && (0..9).all(|k| on[(y + k / 3 - 1) * w + x + k % 3 - 1])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(v: &[f64]) -> Vec<Rgb> {
        v.iter().map(|&x| [x, 2.0 * x, 3.0 * x]).collect()
    }

    /// A uniformly scaled image: every figure has a closed form.
    #[test]
    fn scaled_image_figures_are_closed_forms() {
        let reference = img(&[1.0, 2.0, 4.0, 0.0]);
        let image: Vec<Rgb> = reference.iter().map(|p| p.map(|v| 1.1 * v)).collect();
        let pixels = [0, 1, 2];
        let f = error_figures(&image, &reference, &pixels, 0.05);
        // Differences are 0.1·v; squares of (1,2,3)·(1,2,4) summed: (1+4+9)(1+4+16) = 294.
        let rmse = (0.01 * 294.0 / 9.0f64).sqrt();
        assert!((f.rmse - rmse).abs() < 1e-14 * rmse, "{}", f.rmse);
        // Reference mean over pixels and channels: (1+2+3)(1+2+4)/9 = 42/9.
        assert!((f.rel_rmse - rmse / (42.0 / 9.0)).abs() < 1e-14);
        assert_eq!(f.frac_within_eps, 0.0, "10 % is outside 5 %");
        let g = error_figures(&image, &reference, &pixels, 0.11);
        assert_eq!(g.frac_within_eps, 1.0);
        assert!((mean_ratio(&image, &reference, &pixels) - 1.1).abs() < 1e-14);
        for r in mean_ratio_rgb(&image, &reference, &pixels) {
            assert!((r - 1.1).abs() < 1e-14);
        }
    }

    /// Relative errors use a floor of 1 % of the reference mean for dark pixels.
    #[test]
    fn relative_error_floor_and_empty_sets() {
        let reference = img(&[100.0, 0.0]);
        let image = img(&[100.0, 1.0]);
        let rel = relative_errors(&image, &reference, &[0, 1]);
        assert_eq!(rel[0], 0.0);
        // Mean over both pixels and channels: 100·6/6 = 100, floor 1; blue differs by 3.
        assert!((rel[1] - 3.0).abs() < 1e-12, "{}", rel[1]);
        let e = error_figures(&image, &reference, &[], 0.05);
        assert_eq!((e.rmse, e.rel_rmse, e.frac_within_eps), (0.0, 0.0, 1.0));
        assert_eq!(mean_ratio(&image, &[[0.0; 3]; 2], &[0, 1]), 0.0);
        assert_eq!(frac_within_se(&image, &image, &reference, &[], 3.0), None);
    }

    /// The threshold is strict (an error of exactly eps is outside), and a black reference
    /// gives a relative RMSE of 0, never NaN or infinity.
    #[test]
    fn boundaries_are_strict_and_finite() {
        // 1.25·v − v = v/4 exactly for these powers of two.
        let reference = vec![[4.0, 8.0, 16.0]; 2];
        let image: Vec<Rgb> = reference.iter().map(|p| p.map(|v| 1.25 * v)).collect();
        let f = error_figures(&image, &reference, &[0, 1], 0.25);
        assert_eq!(f.frac_within_eps, 0.0);
        let black = vec![[0.0; 3]; 2];
        let g = error_figures(&image, &black, &[0, 1], 0.25);
        assert!(g.rmse > 0.0);
        assert_eq!(g.rel_rmse, 0.0);
        // A channel the reference lacks has ratio 0, the others their true ratio.
        let no_blue = vec![[4.0, 8.0, 0.0]; 2];
        assert_eq!(mean_ratio_rgb(&image, &no_blue, &[0, 1]), [1.25, 1.25, 0.0]);
    }

    #[test]
    fn within_k_standard_errors() {
        let reference = img(&[1.0, 1.0]);
        let image = vec![[1.2, 2.0, 3.0], [1.0, 2.0, 3.0]];
        let se = vec![[0.1; 3], [0.0; 3]];
        // Pixel 0 is 2 SE off in red; pixel 1 agrees exactly with a zero error bar.
        assert_eq!(
            frac_within_se(&image, &se, &reference, &[0, 1], 3.0),
            Some(1.0)
        );
        assert_eq!(
            frac_within_se(&image, &se, &reference, &[0, 1], 1.5),
            Some(0.5)
        );
        // With a zero error bar, agreement to 1e-12 of a large reference still counts.
        let big = vec![[1e6, 1.0, 1.0]];
        let near = vec![[1e6 + 1e-7, 1.0, 1.0]];
        assert_eq!(
            frac_within_se(&near, &[[0.0; 3]], &big, &[0], 3.0),
            Some(1.0)
        );
        let off = vec![[1e6 + 1e-5, 1.0, 1.0]];
        assert_eq!(
            frac_within_se(&off, &[[0.0; 3]], &big, &[0], 3.0),
            Some(0.0)
        );
    }

    /// The subset is uniform and seeded: distinct, sorted, drawn from the list, the same for the
    /// same seed; over many seeds every pixel is drawn about n/N of the time (binomial, 4.5 σ).
    #[test]
    fn subset_pixels_are_uniform_and_seeded() {
        let pool: Vec<usize> = (0..50).map(|k| 3 * k + 1).collect();
        let s = subset_pixels(&pool, 10, 7);
        assert_eq!(s.len(), 10);
        assert!(s.windows(2).all(|w| w[0] < w[1]));
        assert!(s.iter().all(|p| pool.contains(p)));
        assert_eq!(s, subset_pixels(&pool, 10, 7));
        assert_ne!(s, subset_pixels(&pool, 10, 8));
        assert_eq!(subset_pixels(&pool, 80, 1), pool);
        let trials = 4000;
        let mut count = [0usize; 50];
        for seed in 0..trials {
            for p in subset_pixels(&pool, 10, seed) {
                count[(p - 1) / 3] += 1;
            }
        }
        // Each pixel: Binomial(4000, 1/5), mean 800, σ = √(4000·0.2·0.8) ≈ 25.3.
        for (k, &c) in count.iter().enumerate() {
            assert!((c as f64 - 800.0).abs() < 4.5 * 25.3, "pixel {k}: {c}");
        }
    }

    /// Closed forms: per-pixel squared errors 1, 4, 9, 16 over a population of 8.
    #[test]
    fn subset_error_closed_form() {
        let image = vec![[0.0; 3]; 10];
        let reference = vec![[1.0; 3], [2.0; 3], [3.0; 3], [4.0; 3]];
        let e = subset_error(&image, &[0, 2, 4, 6], &reference, 8).unwrap();
        // Mean 7.5; s² = (6.5² + 3.5² + 1.5² + 8.5²)/3 = 129/3 = 43; SE = √((1 − 4/8)·43/4).
        assert!((e.mse - 7.5).abs() < 1e-14);
        assert!((e.mse_se - (0.5f64 * 43.0 / 4.0).sqrt()).abs() < 1e-14);
        assert!((e.rmse - 7.5f64.sqrt()).abs() < 1e-14);
        assert!((e.rmse_se - e.mse_se / (2.0 * 7.5f64.sqrt())).abs() < 1e-14);
        // The whole population: no sampling error.
        assert_eq!(
            subset_error(&image, &[0, 2, 4, 6], &reference, 4)
                .unwrap()
                .mse_se,
            0.0
        );
        // Bad input is an error, not a panic.
        assert!(subset_error(&image, &[0, 2], &reference, 8).is_err());
        assert!(subset_error(&image, &[0, 2, 4, 6], &reference, 3).is_err());
        assert!(subset_error(&image, &[0, 2, 4, 60], &reference, 8).is_err());
        assert!(subset_error(&image, &[0, 2, 2, 6], &reference, 8).is_err());
        let none = subset_error(&image, &[], &[], 8).unwrap();
        assert_eq!((none.mse, none.mse_se, none.rmse_se), (0.0, 0.0, 0.0));
    }
}
