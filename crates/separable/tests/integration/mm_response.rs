//! The screen-space filter's response in millimetres: a hand-built kernel applied to
//! a single bright pixel at a known mm-per-pixel puts each tap's weight at the pixel offset
//! offset_mm / mm_per_pixel, split linearly between the two neighbouring pixels when the offset
//! is fractional. The expected image is written here from the taps alone (no helper of the
//! crate), so a wrong mm → pixel conversion (say offsets scaled by 1.25) fails.

use sss_separable::screen_space::{FilterOptions, filter};
use sss_separable::{Kernel1d, ScreenInput, SeparableKernel, SeparableTerm, Tap};

const W: usize = 64;
const H: usize = 48;
const X0: usize = 30;
const Y0: usize = 22;
const BRIGHT: [f32; 3] = [1.0, 0.5, 2.0];

fn taps(list: &[(f64, [f64; 3])]) -> Kernel1d {
    Kernel1d {
        taps: list
            .iter()
            .map(|&(offset_mm, weight)| Tap { offset_mm, weight })
            .collect(),
    }
}

/// Two separable terms with asymmetric taps at offsets that are fractional in pixels at the
/// scales tested (weights are arbitrary positive numbers; nothing here needs a physical
/// kernel).
fn kernel() -> SeparableKernel {
    SeparableKernel {
        terms: vec![
            SeparableTerm {
                horizontal: taps(&[
                    (-1.1, [0.10, 0.20, 0.05]),
                    (0.0, [0.50, 0.40, 0.60]),
                    (0.45, [0.25, 0.20, 0.30]),
                    (1.7, [0.15, 0.20, 0.05]),
                ]),
                vertical: taps(&[
                    (-0.8, [0.30, 0.10, 0.20]),
                    (0.0, [0.60, 0.70, 0.50]),
                    (1.25, [0.10, 0.20, 0.30]),
                ]),
            },
            SeparableTerm {
                horizontal: taps(&[(-0.6, [0.05, 0.10, 0.02]), (0.9, [0.08, 0.04, 0.10])]),
                vertical: taps(&[(0.0, [0.20, 0.30, 0.10]), (1.5, [0.10, 0.05, 0.20])]),
            },
        ],
        support_mm: 2.0,
    }
}

/// The hat function: the weight linear interpolation gives a pixel `d` pixels from the point
/// fetched.
fn tent(d: f64) -> f64 {
    (1.0 - d.abs()).max(0.0)
}

/// Filters the single bright pixel at (X0, Y0) on a flat, one-object frame.
fn response(mm_per_pixel: f32) -> Vec<[f32; 3]> {
    let n = W * H;
    let mut irradiance = vec![[0.0f32; 3]; n];
    irradiance[Y0 * W + X0] = BRIGHT;
    let depth = vec![1000.0f32; n];
    let mask = vec![0u32; n];
    let mpp = vec![mm_per_pixel; n];
    let input = ScreenInput {
        width: W,
        height: H,
        irradiance: &irradiance,
        depth: &depth,
        mask: &mask,
        mm_per_pixel: &mpp,
    };
    let opts = FilterOptions {
        jitter_radius: 0.0,
        seed: 0,
        depth_threshold: 1.0,
        min_footprint_px: 1.0,
    };
    filter(&input, &kernel(), &opts).unwrap()
}

/// Each pass computes out(x) = Σ_taps w · in(x − o/mpp) with linear interpolation, so a unit
/// impulse at x0 ends up at x0 + o/mpp: pixel ⌊x0 + o/mpp⌋ gets w·(1 − frac) and the next one
/// w·frac, i.e. w·tent(x − x0 − o/mpp). The vertical pass does the same down the rows (a
/// positive offset lands in a larger row index), and the terms add:
/// out(x, y) = I Σ_terms [Σ_h w_h tent(x − x0 − o_h/mpp)] [Σ_v w_v tent(y − y0 − o_v/mpp)].
///
/// Margin: 2e-5 of the bright pixel's value per pixel. The filter works in f32; the tap
/// position x − o/mpp ≈ 30 carries a rounding error of ≈ 30 · 6e-8 = 2e-6 pixels, which moves
/// ≤ 2e-6 of a tap's weight (≤ 0.6) between neighbours, and the ≤ 8 products per pixel add
/// ~1e-7 relative each. A 1.25 × error in offset_mm / mm_per_pixel moves whole taps by ≥ 0.1
/// pixel (the 0.45 mm tap at 0.4 mm/px: 1.125 → 1.406 px), changing pixels by ≥ 0.02 ≫ 2e-5.
#[test]
fn impulse_lands_at_offset_over_mm_per_pixel() {
    let k = kernel();
    for mpp in [0.4f32, 0.25, 0.7] {
        let out = response(mpp);
        let m = mpp as f64;
        let mut worst = 0.0f64;
        for y in 0..H {
            for x in 0..W {
                for c in 0..3 {
                    let mut want = 0.0;
                    for term in &k.terms {
                        let h: f64 = term
                            .horizontal
                            .taps
                            .iter()
                            .map(|t| t.weight[c] * tent(x as f64 - X0 as f64 - t.offset_mm / m))
                            .sum();
                        let v: f64 = term
                            .vertical
                            .taps
                            .iter()
                            .map(|t| t.weight[c] * tent(y as f64 - Y0 as f64 - t.offset_mm / m))
                            .sum();
                        want += h * v;
                    }
                    want *= BRIGHT[c] as f64;
                    let got = out[y * W + x][c] as f64;
                    let err = (got - want).abs();
                    worst = worst.max(err / BRIGHT[c] as f64);
                    assert!(
                        err <= 2e-5 * BRIGHT[c] as f64,
                        "mpp {mpp}, pixel ({x},{y}) ch {c}: {got} vs {want}"
                    );
                }
            }
        }
        eprintln!("mpp {mpp}: worst per-pixel error {worst:.2e} of the impulse");
    }
}

/// The same response seen through its moments, in mm: the image's total is
/// I Σ_terms (Σ w_h)(Σ w_v), and its centroid (pixel offsets × mm_per_pixel) is the
/// weight-averaged tap offset in mm (linear interpolation preserves the first moment),
/// whatever mm_per_pixel is. Margin 1e-5 relative for the total (f32 sums of ~60 values) and
/// 1e-4 mm for the centroid (f32 rounding ≈ 2e-6 px × 0.7 mm/px, summed with the weights); a
/// 1.25 × offset error moves the centroids (0.1–0.4 mm) by 25 %.
#[test]
fn response_moments_in_mm_match_the_taps() {
    let k = kernel();
    for mpp in [0.4f32, 0.25, 0.7] {
        let out = response(mpp);
        let m = mpp as f64;
        for c in 0..3 {
            // Closed forms from the taps.
            let mut total = 0.0;
            let (mut mx, mut my) = (0.0, 0.0);
            for term in &k.terms {
                let sh: f64 = term.horizontal.taps.iter().map(|t| t.weight[c]).sum();
                let sv: f64 = term.vertical.taps.iter().map(|t| t.weight[c]).sum();
                let oh: f64 = term
                    .horizontal
                    .taps
                    .iter()
                    .map(|t| t.weight[c] * t.offset_mm)
                    .sum();
                let ov: f64 = term
                    .vertical
                    .taps
                    .iter()
                    .map(|t| t.weight[c] * t.offset_mm)
                    .sum();
                total += sh * sv;
                mx += oh * sv;
                my += sh * ov;
            }
            let (cx_want, cy_want) = (mx / total, my / total);
            let total_want = total * BRIGHT[c] as f64;
            // Measured from the image.
            let (mut s, mut sx, mut sy) = (0.0f64, 0.0f64, 0.0f64);
            for y in 0..H {
                for x in 0..W {
                    let v = out[y * W + x][c] as f64;
                    s += v;
                    sx += v * (x as f64 - X0 as f64) * m;
                    sy += v * (y as f64 - Y0 as f64) * m;
                }
            }
            let (cx, cy) = (sx / s, sy / s);
            eprintln!(
                "mpp {mpp} ch {c}: total {s:.7} (taps {total_want:.7}), centroid ({cx:.6}, \
                 {cy:.6}) mm (taps ({cx_want:.6}, {cy_want:.6}))"
            );
            assert!(
                (s - total_want).abs() < 1e-5 * total_want,
                "mpp {mpp} ch {c}: total {s} vs {total_want}"
            );
            assert!(
                (cx - cx_want).abs() < 1e-4 && (cy - cy_want).abs() < 1e-4,
                "mpp {mpp} ch {c}: centroid ({cx}, {cy}) mm vs ({cx_want}, {cy_want})"
            );
            // The moments are large enough that a 25 % scale error would show.
            assert!(cx_want.abs().max(cy_want.abs()) > 0.05);
        }
    }
}
