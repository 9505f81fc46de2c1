//! `compare`'s error figures (`sss_render::metrics`) on a small synthetic image whose answers
//! are worked out by hand below: unequal per-channel differences, a black reference
//! pixel (the relative-error floor), and a pixel outside the evaluated set that must not count.

use sss_render::metrics::{
    error_figures, frac_within_se, mean_ratio, mean_ratio_rgb, relative_errors,
};

/// Reference and image, four pixels; pixel 3 is left out of every figure.
///
/// | pixel | reference | image | difference |
/// |---|---|---|---|
/// | 0 | (1, 2, 3) | (1.5, 2, 3) | (0.5, 0, 0) |
/// | 1 | (2, 2, 2) | (2, 1, 2) | (0, −1, 0) |
/// | 2 | (0, 0, 0) | (0, 0, 0.3) | (0, 0, 0.3) |
/// | 3 | (10, 10, 10) | (99, 99, 99) | not evaluated |
fn images() -> (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<usize>) {
    let reference = vec![
        [1.0, 2.0, 3.0],
        [2.0, 2.0, 2.0],
        [0.0, 0.0, 0.0],
        [10.0, 10.0, 10.0],
    ];
    let image = vec![
        [1.5, 2.0, 3.0],
        [2.0, 1.0, 2.0],
        [0.0, 0.0, 0.3],
        [99.0, 99.0, 99.0],
    ];
    (image, reference, vec![0, 1, 2])
}

/// RMSE over 3 pixels × 3 channels: √((0.25 + 1 + 0.09)/9) = √(1.34/9); the reference's mean
/// over the same values is (6 + 6 + 0)/9 = 4/3, so the relative RMSE is √(1.34/9)·3/4.
/// Margins 1e-15 relative: a handful of f64 operations.
#[test]
fn rmse_and_relative_rmse() {
    let (image, reference, px) = images();
    let f = error_figures(&image, &reference, &px, 0.6);
    let rmse = (1.34f64 / 9.0).sqrt();
    assert!(
        (f.rmse - rmse).abs() < 1e-15 * rmse,
        "rmse {} vs {rmse}",
        f.rmse
    );
    let rel = rmse * 0.75;
    assert!(
        (f.rel_rmse - rel).abs() < 1e-15 * rel,
        "rel_rmse {} vs {rel}",
        f.rel_rmse
    );
    // √(1.34/9) = 0.38586..., by hand to 5 digits.
    assert!((f.rmse - 0.38586).abs() < 1e-5);
}

/// Relative errors, max over channels of |a − b| / max(b, floor) with floor = 1 % of the mean
/// 4/3: pixel 0 → 0.5/1, pixel 1 → 1/2, pixel 2 → 0.3/(4/300) = 22.5. Within ε (strictly
/// below): none at 0.5, two of three at 0.6, all at 30.
#[test]
fn relative_errors_and_fraction_within_eps() {
    let (image, reference, px) = images();
    let rel = relative_errors(&image, &reference, &px);
    let want = [0.5, 0.5, 22.5];
    for (k, (got, w)) in rel.iter().zip(want).enumerate() {
        assert!((got - w).abs() < 1e-12 * w, "pixel {k}: {got} vs {w}");
    }
    let at = |eps: f64| error_figures(&image, &reference, &px, eps).frac_within_eps;
    assert_eq!(at(0.5), 0.0);
    assert!((at(0.6) - 2.0 / 3.0).abs() < 1e-15);
    assert_eq!(at(30.0), 1.0);
}

/// Mean ratios: all channels (6.5 + 5 + 0.3)/(6 + 6 + 0) = 11.8/12; per channel red 3.5/3,
/// green 3/4, blue 5.3/5.
#[test]
fn mean_ratios() {
    let (image, reference, px) = images();
    let r = mean_ratio(&image, &reference, &px);
    assert!((r - 11.8 / 12.0).abs() < 1e-15, "{r}");
    let rgb = mean_ratio_rgb(&image, &reference, &px);
    for (got, want) in rgb.iter().zip([3.5 / 3.0, 0.75, 5.3 / 5.0]) {
        assert!((got - want).abs() < 1e-15, "{rgb:?}");
    }
}

/// Within k standard errors, every channel: with errors pixel 0 (0.2, 1, 1), pixel 1
/// (1, 0.3, 1), pixel 2 (1, 1, 0.2), the worst channel needs k ≥ 2.5 (pixel 0: 0.5/0.2),
/// 3.33 (pixel 1: 1/0.3) and 1.5 (pixel 2: 0.3/0.2). So k = 2 keeps pixel 2 only, k = 3
/// pixels 0 and 2, k = 4 all three.
#[test]
fn fraction_within_k_standard_errors() {
    let (image, reference, px) = images();
    let se = vec![
        [0.2, 1.0, 1.0],
        [1.0, 0.3, 1.0],
        [1.0, 1.0, 0.2],
        [0.0, 0.0, 0.0],
    ];
    let at = |k: f64| frac_within_se(&image, &se, &reference, &px, k).unwrap();
    assert!((at(2.0) - 1.0 / 3.0).abs() < 1e-15);
    assert!((at(3.0) - 2.0 / 3.0).abs() < 1e-15);
    assert_eq!(at(4.0), 1.0);
}
