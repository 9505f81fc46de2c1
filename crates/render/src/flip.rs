//! FLIP: NVIDIA's perceptual difference between a reference and a test image, as rendering
//! papers quote it. [`hdr_flip`] for linear, unbounded renders (what the toolkit writes);
//! [`ldr_flip`] for images already in [0, 1].
//!
//! **LDR-FLIP** (Andersson et al. 2020, *FLIP: A Difference Evaluator for Alternating Images*,
//! §4): both images go to the opponent space YCxCz and are filtered by the contrast sensitivity
//! of the eye in each channel (sums of Gaussians over visual degrees, `ppd` pixels per
//! degree), clamped to [0, 1] in linear RGB, taken to Hunt-adjusted L\*a\*b\* and compared
//! with the HyAB distance; that colour difference, raised to q_c = 0.7 and remapped to [0, 1],
//! is raised to the power 1 − Δf, where Δf is the difference of edges and points of the
//! luminance (first and second derivatives of a Gaussian of 0.5 · 0.082 degrees). The per-pixel
//! error is in [0, 1]; its mean is the figure quoted.
//!
//! **HDR-FLIP** (Andersson et al. 2021, *Visualizing Errors in Rendered High Dynamic Range
//! Images*, §3): both images are exposed by 2^c and tone-mapped with ACES (fitted by Narkowicz,
//! with the 0.6 pre-exposure cancelled) at exposures c from c_start = log2(x_max / Y_max) to
//! c_stop = log2(x_max / Y_median) of the reference's luminance, where ACES(x_max) = 0.85, at
//! max(2, ⌈c_stop − c_start⌉) exposures; each pixel keeps its largest LDR-FLIP.
//!
//! The constants and the separated filters follow NVIDIA's reference implementation (the
//! `flip-evaluator` package, checked against it in `tests/integration/flip_evaluator.rs`);
//! the arithmetic is in f32 as there. Where it leaves a case undefined this module decides:
//! non-finite or negative input values count as 0; a black reference is seen at exposure 0
//! only; where half or more of the reference is black (a render on a black background), the
//! median is taken over its non-black pixels (the reference implementation then divides by
//! zero and evaluates no exposure at all); at most [`MAX_EXPOSURES`] exposures.
//!
//! ```
//! use sss_render::flip::{FlipParams, hdr_flip};
//! let reference = vec![[0.5, 0.4, 0.3]; 32 * 32];
//! let mut test = reference.clone();
//! test[16 * 32 + 16] = [2.0, 2.0, 2.0];
//! let same = hdr_flip(&reference, &reference, 32, 32, &FlipParams::default());
//! let diff = hdr_flip(&reference, &test, 32, 32, &FlipParams::default());
//! assert_eq!(same.mean, 0.0);
//! // The error peaks at the changed pixel and is 0 far from it.
//! let peak = (0..32 * 32).max_by(|&a, &b| diff.map[a].total_cmp(&diff.map[b]));
//! assert_eq!(peak, Some(16 * 32 + 16));
//! assert!(diff.mean > 0.0 && diff.map[0] == 0.0);
//! ```

use rayon::prelude::*;
use sss_bssrdf::Rgb;

/// Pixels per degree of visual angle FLIP assumes by default: a 0.7 m wide 3840-pixel
/// monitor seen from 0.7 m (3840 · π / 180).
pub const DEFAULT_PPD: f64 = 3840.0 * std::f64::consts::PI / 180.0;

/// The most exposures HDR-FLIP evaluates (one per stop; 64 stops is far beyond any render).
pub const MAX_EXPOSURES: usize = 64;

/// How FLIP looks at the images.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlipParams {
    /// Pixels per degree of visual angle ([`DEFAULT_PPD`]).
    pub ppd: f64,
    /// HDR-FLIP's first and last exposure (stops), or `None` to take them from the reference.
    pub exposures: Option<(f64, f64)>,
    /// How many exposures, or `None` for max(2, ⌈c_stop − c_start⌉).
    pub count: Option<usize>,
}

impl Default for FlipParams {
    fn default() -> Self {
        FlipParams {
            ppd: DEFAULT_PPD,
            exposures: None,
            count: None,
        }
    }
}

/// The result of [`hdr_flip`].
#[derive(Clone, Debug, PartialEq)]
pub struct FlipMap {
    /// Per-pixel error in [0, 1], row-major.
    pub map: Vec<f32>,
    /// The mean of `map` (0 for an empty image).
    pub mean: f64,
    /// The first and last exposure evaluated (stops).
    pub exposures: (f64, f64),
    /// How many exposures were evaluated.
    pub count: usize,
}

// The constants of the reference implementation (Andersson et al. 2020, §4 and Table 1).
const QC: f32 = 0.7;
const PC: f32 = 0.4;
const PT: f32 = 0.95;
const W: f32 = 0.082;
const QF: f32 = 0.5;
/// The contrast sensitivity functions as sums of Gaussians a·√(π/b)·exp(−π²x²/b) in degrees:
/// (a1, b1) for Y, Cx and the first term of Cz, (a2, b2) for Cz's second term.
const A1: [f32; 3] = [1.0, 1.0, 34.1];
const B1: [f32; 3] = [0.0047, 0.0053, 0.04];
const A2: f32 = 13.5;
const B2: f32 = 0.025;
/// D65's white point, which XYZ is divided by before YCxCz and L\*a\*b\*.
const WHITE: [f32; 3] = [0.950_428_5, 1.0, 1.088_900_4];
/// ACES (Narkowicz 2015) as (c0·x² + c1·x + c2) / (c3·x² + c4·x + c5), with the 0.6
/// pre-exposure folded in, as the reference implementation has it.
const ACES: [f32; 6] = [
    0.6 * 0.6 * 2.51,
    0.6 * 0.03,
    0.0,
    0.6 * 0.6 * 2.43,
    0.6 * 0.59,
    0.14,
];

/// Relative luminance of linear sRGB (Rec. 709 weights).
fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

fn rgb_to_xyz(c: [f32; 3]) -> [f32; 3] {
    // sRGB primaries, D65, as the exact ratios the reference implementation uses.
    [
        (10_135_552.0 * c[0] + 8_788_810.0 * c[1] + 4_435_075.0 * c[2]) / 24_577_794.0,
        (2_613_072.0 * c[0] + 8_788_810.0 * c[1] + 887_015.0 * c[2]) / 12_288_897.0,
        (1_425_312.0 * c[0] + 8_788_810.0 * c[1] + 70_074_185.0 * c[2]) / 73_733_382.0,
    ]
}

fn xyz_to_rgb(c: [f32; 3]) -> [f32; 3] {
    [
        3.241_003_3 * c[0] - 1.537_398_9 * c[1] - 0.498_615_87 * c[2],
        -0.969_224_3 * c[0] + 1.875_930_1 * c[1] + 0.041_554_224 * c[2],
        0.055_639_423 * c[0] - 0.204_011_2 * c[1] + 1.057_148_9 * c[2],
    ]
}

fn xyz_to_ycxcz(c: [f32; 3]) -> [f32; 3] {
    let [x, y, z] = [c[0] / WHITE[0], c[1] / WHITE[1], c[2] / WHITE[2]];
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn ycxcz_to_xyz(c: [f32; 3]) -> [f32; 3] {
    let y = (c[0] + 16.0) / 116.0;
    [
        (y + c[1] / 500.0) * WHITE[0],
        y * WHITE[1],
        (y - c[2] / 200.0) * WHITE[2],
    ]
}

fn xyz_to_lab(c: [f32; 3]) -> [f32; 3] {
    const DELTA: f32 = 6.0 / 29.0;
    let f = |t: f32| {
        if t > DELTA * DELTA * DELTA {
            t.cbrt()
        } else {
            t / (3.0 * DELTA * DELTA) + 4.0 / 29.0
        }
    };
    let [x, y, z] = [f(c[0] / WHITE[0]), f(c[1] / WHITE[1]), f(c[2] / WHITE[2])];
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// Hunt-adjusted L\*a\*b\* (chroma scaled by 0.01·L\*) of linear RGB clamped to [0, 1].
fn hunt_lab(rgb: [f32; 3]) -> [f32; 3] {
    let lab = xyz_to_lab(rgb_to_xyz(rgb.map(|v| v.clamp(0.0, 1.0))));
    [lab[0], 0.01 * lab[0] * lab[1], 0.01 * lab[0] * lab[2]]
}

/// HyAB: city-block distance in lightness plus Euclidean distance in chroma.
fn hyab(a: [f32; 3], b: [f32; 3]) -> f32 {
    (a[0] - b[0]).abs() + ((a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The largest colour difference FLIP expects (pure green against pure blue), raised to q_c.
fn max_colour_distance() -> f32 {
    hyab(hunt_lab([0.0, 1.0, 0.0]), hunt_lab([0.0, 0.0, 1.0])).powf(QC)
}

/// The separated spatial filters at `ppd`: per tap (Y, Cx) weights, each summing to 1, and
/// the two Cz terms' weights, whose outer products sum to a 2D kernel of total weight 1.
fn spatial_filters(ppd: f32) -> (Vec<[f32; 2]>, Vec<[f32; 2]>) {
    use std::f32::consts::PI;
    let b_max = B1.iter().copied().fold(B2, f32::max);
    let radius = (3.0 * (b_max / (2.0 * PI * PI)).sqrt() * ppd)
        .ceil()
        .max(0.0) as i64;
    let gauss = |x2: f32, a: f32, b: f32| a * (PI / b).sqrt() * (-PI * PI * x2 / b).exp();
    let gauss_sqrt =
        |x2: f32, a: f32, b: f32| (a * (PI / b).sqrt()).sqrt() * (-PI * PI * x2 / b).exp();
    let mut ycx = Vec::new();
    let mut cz = Vec::new();
    for i in -radius..=radius {
        let x = i as f32 / ppd;
        let x2 = x * x;
        ycx.push([gauss(x2, A1[0], B1[0]), gauss(x2, A1[1], B1[1])]);
        cz.push([gauss_sqrt(x2, A1[2], B1[2]), gauss_sqrt(x2, A2, B2)]);
    }
    let sum = |v: &[[f32; 2]], k: usize| v.iter().map(|w| w[k]).sum::<f32>();
    let (sy, sx) = (sum(&ycx, 0), sum(&ycx, 1));
    let norm_cz = 1.0 / (sum(&cz, 0).powi(2) + sum(&cz, 1).powi(2)).sqrt();
    for w in &mut ycx {
        *w = [w[0] / sy, w[1] / sx];
    }
    for w in &mut cz {
        *w = [w[0] * norm_cz, w[1] * norm_cz];
    }
    (ycx, cz)
}

/// The separated feature filters at `ppd`: per tap a Gaussian (sum 1), its first derivative
/// and its second derivative (positive and negative weights each summing to ±1).
fn feature_filter(ppd: f32) -> Vec<[f32; 3]> {
    let sd = 0.5 * W * ppd;
    let radius = (3.0 * sd).ceil().max(0.0) as i64;
    let mut taps: Vec<[f32; 3]> = (-radius..=radius)
        .map(|i| {
            let x = i as f32;
            let g = (-(x * x) / (2.0 * sd * sd)).exp();
            [g, -x * g, (x * x / (sd * sd) - 1.0) * g]
        })
        .collect();
    let g_sum: f32 = taps.iter().map(|t| t[0]).sum();
    let signed_sums = |k: usize| {
        let pos: f32 = taps.iter().map(|t| t[k].max(0.0)).sum();
        let neg: f32 = taps.iter().map(|t| (-t[k]).max(0.0)).sum();
        (pos, neg)
    };
    let (dp, dn) = signed_sums(1);
    let (ddp, ddn) = signed_sums(2);
    let scale = |v: f32, pos: f32, neg: f32| {
        let s = if v > 0.0 { pos } else { neg };
        if s > 0.0 { v / s } else { 0.0 }
    };
    for t in &mut taps {
        *t = [t[0] / g_sum, scale(t[1], dp, dn), scale(t[2], ddp, ddn)];
    }
    taps
}

/// Index of `i + d` clamped to [0, n − 1] (the reference implementation's border).
fn clamped(i: usize, d: i64, n: usize) -> usize {
    (i as i64 + d).clamp(0, n as i64 - 1) as usize
}

/// What LDR-FLIP needs at one `ppd`, built once for every exposure of an HDR-FLIP.
struct Filters {
    /// The spatial filters' taps: (Y, Cx) and the two Cz terms ([`spatial_filters`]).
    ycx: Vec<[f32; 2]>,
    cz: Vec<[f32; 2]>,
    /// The feature filter's taps ([`feature_filter`]).
    feature: Vec<[f32; 3]>,
    /// [`max_colour_distance`].
    c_max: f32,
}

impl Filters {
    /// The filters at `ppd` ([`DEFAULT_PPD`] for a non-finite or non-positive one).
    fn new(ppd: f64) -> Self {
        let ppd = if ppd.is_finite() && ppd > 0.0 {
            ppd as f32
        } else {
            DEFAULT_PPD as f32
        };
        let (ycx, cz) = spatial_filters(ppd);
        Filters {
            ycx,
            cz,
            feature: feature_filter(ppd),
            c_max: max_colour_distance(),
        }
    }
}

/// LDR-FLIP of two linear-RGB images with values in [0, 1] (others are clamped): the
/// per-pixel error in [0, 1], row-major. Images of a size other than `width` × `height`, or
/// empty, give an empty map.
pub fn ldr_flip(
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    width: usize,
    height: usize,
    ppd: f64,
) -> Vec<f32> {
    ldr_flip_with(&Filters::new(ppd), reference, test, width, height)
}

/// [`ldr_flip`] with its filters built.
fn ldr_flip_with(
    filters: &Filters,
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    width: usize,
    height: usize,
) -> Vec<f32> {
    let n = width * height;
    if n == 0 || reference.len() != n || test.len() != n {
        return Vec::new();
    }
    let to_ycxcz = |img: &[[f32; 3]]| -> Vec<[f32; 3]> {
        img.iter()
            .map(|c| xyz_to_ycxcz(rgb_to_xyz(c.map(|v| v.clamp(0.0, 1.0)))))
            .collect()
    };
    let (r, t) = (to_ycxcz(reference), to_ycxcz(test));
    let colour = colour_difference(filters, &r, &t, width, height);
    let feature = feature_difference(filters, &r, &t, width, height);
    colour
        .iter()
        .zip(&feature)
        .map(|(&c, &f)| c.powf(1.0 - f))
        .collect()
}

/// Filters both images by the contrast sensitivity functions and returns the remapped colour
/// difference per pixel.
fn colour_difference(
    filters: &Filters,
    r: &[[f32; 3]],
    t: &[[f32; 3]],
    w: usize,
    h: usize,
) -> Vec<f32> {
    let (ycx, cz) = (filters.ycx.as_slice(), filters.cz.as_slice());
    let half = (ycx.len() / 2) as i64;
    // Along rows: per image (Y, Cx, Cz term 1, Cz term 2).
    let rows = |img: &[[f32; 3]]| -> Vec<[f32; 4]> {
        let mut out = vec![[0.0f32; 4]; w * h];
        out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let mut acc = [0.0f32; 4];
                for (k, (a, b)) in ycx.iter().zip(cz).enumerate() {
                    let p = img[y * w + clamped(x, k as i64 - half, w)];
                    acc[0] += a[0] * p[0];
                    acc[1] += a[1] * p[1];
                    acc[2] += b[0] * p[2];
                    acc[3] += b[1] * p[2];
                }
                *o = acc;
            }
        });
        out
    };
    let (rr, tr) = (rows(r), rows(t));
    let c_max = filters.c_max;
    let pc_max = PC * c_max;
    let mut out = vec![0.0f32; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let mut fr = [0.0f32; 4];
            let mut ft = [0.0f32; 4];
            for (k, (a, b)) in ycx.iter().zip(cz).enumerate() {
                let i = clamped(y, k as i64 - half, h) * w + x;
                let weights = [a[0], a[1], b[0], b[1]];
                for c in 0..4 {
                    fr[c] += weights[c] * rr[i][c];
                    ft[c] += weights[c] * tr[i][c];
                }
            }
            let lab = |f: [f32; 4]| hunt_lab(xyz_to_rgb(ycxcz_to_xyz([f[0], f[1], f[2] + f[3]])));
            let d = hyab(lab(fr), lab(ft)).powf(QC);
            // Below p_c · c_max onto [0, p_t], the rest onto (p_t, 1].
            *o = if d < pc_max {
                d * PT / pc_max
            } else {
                PT + (d - pc_max) / (c_max - pc_max) * (1.0 - PT)
            };
        }
    });
    out
}

/// The feature (edge and point) difference per pixel, from the luminance of both images.
fn feature_difference(
    filters: &Filters,
    r: &[[f32; 3]],
    t: &[[f32; 3]],
    w: usize,
    h: usize,
) -> Vec<f32> {
    let filter = &filters.feature;
    let half = (filter.len() / 2) as i64;
    // Along rows: (first derivative, second derivative, Gaussian) of the luminance in [0, 1].
    let rows = |img: &[[f32; 3]]| -> Vec<[f32; 3]> {
        let mut out = vec![[0.0f32; 3]; w * h];
        out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let mut acc = [0.0f32; 3];
                for (k, f) in filter.iter().enumerate() {
                    let v = (img[y * w + clamped(x, k as i64 - half, w)][0] + 16.0) / 116.0;
                    acc[0] += f[1] * v;
                    acc[1] += f[2] * v;
                    acc[2] += f[0] * v;
                }
                *o = acc;
            }
        });
        out
    };
    let (rr, tr) = (rows(r), rows(t));
    let mut out = vec![0.0f32; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            // (dx, ddx, dy, ddy) of each image.
            let mut fr = [0.0f32; 4];
            let mut ft = [0.0f32; 4];
            for (k, f) in filter.iter().enumerate() {
                let i = clamped(y, k as i64 - half, h) * w + x;
                for (acc, p) in [(&mut fr, rr[i]), (&mut ft, tr[i])] {
                    acc[0] += f[0] * p[0];
                    acc[1] += f[0] * p[1];
                    acc[2] += f[1] * p[2];
                    acc[3] += f[2] * p[2];
                }
            }
            let edge = (fr[0].hypot(fr[2]) - ft[0].hypot(ft[2])).abs();
            let point = (fr[1].hypot(fr[3]) - ft[1].hypot(ft[3])).abs();
            *o = (edge.max(point) / std::f32::consts::SQRT_2).powf(QF);
        }
    });
    out
}

/// A linear image as FLIP reads it: f32, non-finite and negative values as 0.
fn sanitised(img: &[Rgb]) -> Vec<[f32; 3]> {
    img.iter()
        .map(|p| {
            p.map(|v| {
                if v.is_finite() && v > 0.0 {
                    v as f32
                } else {
                    0.0
                }
            })
        })
        .collect()
}

/// HDR-FLIP's exposure range from the reference's luminance: (c_start, c_stop) in stops.
fn exposure_range(reference: &[[f32; 3]]) -> (f64, f64) {
    // ACES(x) = 0.85 for x = x_max, the larger root of (c0 − t·c3)x² + (c1 − t·c4)x + c2 − t·c5.
    let t = 0.85f32;
    let (a, b, c) = (
        ACES[0] - t * ACES[3],
        ACES[1] - t * ACES[4],
        ACES[2] - t * ACES[5],
    );
    let d1 = -0.5 * b / a;
    let x_max = d1 + (d1 * d1 - c / a).max(0.0).sqrt();
    let mut lum: Vec<f32> = reference.iter().map(|&p| luminance(p)).collect();
    let y_max = lum.iter().copied().fold(0.0f32, f32::max);
    if !(y_max > 0.0) {
        return (0.0, 0.0);
    }
    let mid = lum.len() / 2;
    let (_, &mut median, _) = lum.select_nth_unstable_by(mid, f32::total_cmp);
    let median = if median > 0.0 {
        median
    } else {
        let mut lit: Vec<f32> = lum.into_iter().filter(|&v| v > 0.0).collect();
        let mid = lit.len() / 2;
        *lit.select_nth_unstable_by(mid, f32::total_cmp).1
    };
    let x = f64::from(x_max);
    (
        (x / f64::from(y_max)).log2(),
        (x / f64::from(median)).log2(),
    )
}

/// ACES of one exposed channel value, clamped to [0, 1].
fn tone_map(v: f32) -> f32 {
    // Beyond 10^15 the squares overflow f32; the ratio's limit, c0 / c3 > 1, clamps to 1.
    if !(v < 1e15) {
        return if v.is_nan() { 0.0 } else { 1.0 };
    }
    let num = (ACES[0] * v + ACES[1]) * v + ACES[2];
    let den = (ACES[3] * v + ACES[4]) * v + ACES[5];
    (num / den).clamp(0.0, 1.0)
}

/// HDR-FLIP of two linear-RGB renders of `width` × `height` pixels (see the module doc):
/// the per-pixel error, its mean and the exposures evaluated. Mismatched sizes or an empty
/// image give an empty map of mean 0.
pub fn hdr_flip(
    reference: &[Rgb],
    test: &[Rgb],
    width: usize,
    height: usize,
    params: &FlipParams,
) -> FlipMap {
    let n = width * height;
    if n == 0 || reference.len() != n || test.len() != n {
        return FlipMap {
            map: Vec::new(),
            mean: 0.0,
            exposures: (0.0, 0.0),
            count: 0,
        };
    }
    let (r, t) = (sanitised(reference), sanitised(test));
    let (start, stop) = match params.exposures {
        Some((a, b)) if a.is_finite() && b.is_finite() => (a.min(b), a.max(b)),
        _ => exposure_range(&r),
    };
    let count = params
        .count
        .unwrap_or_else(|| (stop - start).ceil().max(2.0) as usize)
        .clamp(2, MAX_EXPOSURES);
    let filters = Filters::new(params.ppd);
    let step = (stop - start) / (count - 1) as f64;
    let mut map = vec![0.0f32; n];
    for i in 0..count {
        let scale = (start + i as f64 * step).exp2() as f32;
        let expose = |img: &[[f32; 3]]| -> Vec<[f32; 3]> {
            img.iter().map(|p| p.map(|v| tone_map(v * scale))).collect()
        };
        let ldr = ldr_flip_with(&filters, &expose(&r), &expose(&t), width, height);
        for (m, e) in map.iter_mut().zip(ldr) {
            *m = m.max(e);
        }
    }
    let mean = map.iter().map(|&v| f64::from(v)).sum::<f64>() / n as f64;
    FlipMap {
        map,
        mean,
        exposures: (start, stop),
        count,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spatial_filters_conserve_a_flat_image() {
        for ppd in [10.0f32, 67.02, 120.0] {
            let (ycx, cz) = spatial_filters(ppd);
            assert_eq!(ycx.len() % 2, 1);
            for k in 0..2 {
                let s: f32 = ycx.iter().map(|w| w[k]).sum();
                assert!((s - 1.0).abs() < 1e-5, "ppd {ppd}: sum {s}");
            }
            // The 2D Cz kernel is Σ_terms g_k(x) g_k(y): its total is (Σg1)² + (Σg2)².
            let s1: f32 = cz.iter().map(|w| w[0]).sum();
            let s2: f32 = cz.iter().map(|w| w[1]).sum();
            assert!((s1 * s1 + s2 * s2 - 1.0).abs() < 1e-5);
        }
        // Radius: 3 standard deviations of the widest Gaussian, √(0.04 / 2π²) degrees.
        let (ycx, _) = spatial_filters(DEFAULT_PPD as f32);
        let sd = (0.04f64 / (2.0 * std::f64::consts::PI.powi(2))).sqrt() * DEFAULT_PPD;
        assert_eq!(ycx.len(), 2 * (3.0 * sd).ceil() as usize + 1);
    }

    #[test]
    fn feature_filter_weights_are_normalised() {
        let f = feature_filter(DEFAULT_PPD as f32);
        let sd = 0.5 * 0.082 * DEFAULT_PPD;
        assert_eq!(f.len(), 2 * (3.0 * sd).ceil() as usize + 1);
        let g: f32 = f.iter().map(|t| t[0]).sum();
        assert!((g - 1.0).abs() < 1e-6);
        for k in 1..3 {
            let pos: f32 = f.iter().map(|t| t[k].max(0.0)).sum();
            let neg: f32 = f.iter().map(|t| t[k].min(0.0)).sum();
            assert!((pos - 1.0).abs() < 1e-6 && (neg + 1.0).abs() < 1e-6);
        }
        // The first derivative is odd, the second even.
        let n = f.len();
        for i in 0..n {
            assert!((f[i][1] + f[n - 1 - i][1]).abs() < 1e-7);
            assert!((f[i][2] - f[n - 1 - i][2]).abs() < 1e-7);
        }
    }

    #[test]
    fn colour_conversions_round_trip_and_white_is_neutral() {
        for c in [[0.2f32, 0.5, 0.9], [1.0, 1.0, 1.0], [0.0, 0.0, 0.0]] {
            let back = xyz_to_rgb(ycxcz_to_xyz(xyz_to_ycxcz(rgb_to_xyz(c))));
            for k in 0..3 {
                assert!((back[k] - c[k]).abs() < 1e-5, "{c:?} -> {back:?}");
            }
        }
        // White: L* = 100, no chroma; Y of white is 1.
        let lab = hunt_lab([1.0, 1.0, 1.0]);
        assert!((lab[0] - 100.0).abs() < 1e-3 && lab[1].abs() < 1e-3 && lab[2].abs() < 1e-3);
        assert!((rgb_to_xyz([1.0, 1.0, 1.0])[1] - 1.0).abs() < 1e-6);
        // Green against blue: the largest difference, finite and positive.
        let c = max_colour_distance();
        assert!(c.is_finite() && c > 10.0);
    }

    #[test]
    fn aces_maps_x_max_to_0_85() {
        let (start, _) = exposure_range(&[[1.0, 1.0, 1.0], [0.5, 0.5, 0.5]]);
        // c_start = log2(x_max / Y_max) with Y_max = 1: 2^c_start is x_max.
        assert!((tone_map(start.exp2() as f32) - 0.85).abs() < 1e-5);
        assert_eq!(tone_map(0.0), 0.0);
        assert!(tone_map(1e30) <= 1.0);
    }

    #[test]
    fn identical_images_score_zero_and_a_changed_pixel_scores_there() {
        let (w, h) = (24, 20);
        let reference: Vec<Rgb> = (0..w * h)
            .map(|i| {
                [
                    0.1 + (i % w) as f64 * 0.02,
                    0.3,
                    0.05 + (i / w) as f64 * 0.01,
                ]
            })
            .collect();
        let same = hdr_flip(&reference, &reference, w, h, &FlipParams::default());
        assert_eq!(same.mean, 0.0);
        assert!(same.count >= 2);
        let mut test = reference.clone();
        test[10 * w + 12] = [3.0, 0.0, 0.0];
        let d = hdr_flip(&reference, &test, w, h, &FlipParams::default());
        let peak = d
            .map
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(i, _)| i);
        assert_eq!(peak, Some(10 * w + 12));
        assert!(d.map.iter().all(|v| (0.0..=1.0).contains(v)));
        // Far from the change (beyond both filters' reach) nothing differs.
        assert_eq!(d.map[0], 0.0);
    }

    #[test]
    fn black_backgrounds_and_bad_values_are_defined() {
        let (w, h) = (16, 16);
        let mut reference = vec![[0.0; 3]; w * h];
        for p in reference.iter_mut().take(40) {
            *p = [0.5, 0.5, 0.5];
        }
        let (start, stop) = exposure_range(&sanitised(&reference));
        assert!(start.is_finite() && stop.is_finite());
        assert!(
            (start - stop).abs() < 1e-9,
            "one luminance: one exposure range point"
        );
        let mut test = reference.clone();
        test[3] = [f64::NAN, f64::INFINITY, -1.0];
        let d = hdr_flip(&reference, &test, w, h, &FlipParams::default());
        assert!(d.mean.is_finite() && d.mean > 0.0);
        let black = hdr_flip(&[[0.0; 3]; 4], &[[0.0; 3]; 4], 2, 2, &FlipParams::default());
        assert_eq!((black.mean, black.exposures), (0.0, (0.0, 0.0)));
        assert!(
            hdr_flip(&reference, &test, w + 1, h, &FlipParams::default())
                .map
                .is_empty()
        );
    }
}
