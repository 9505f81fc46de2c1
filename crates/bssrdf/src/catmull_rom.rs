//! Catmull-Rom spline interpolation, integration, inversion and sampling over non-uniform
//! knots.
//!
//! This is the machinery of Pharr, Jakob, Humphreys, *Physically Based Rendering* 3rd ed.
//! §8.6.1 (spline weights, Eq. 8.27-8.28, used by the Fourier BSDF) and §15.4.2 (sampling the
//! tabulated BSSRDF), re-derived here in `f64`:
//!
//! - On an interval [x₀, x₁] of width w = x₁ − x₀ with t = (x − x₀)/w the spline is the cubic
//!   Hermite polynomial (pbrt Eq. 8.27)
//!   p(t) = (2t³ − 3t² + 1) f₀ + (−2t³ + 3t²) f₁ + (t³ − 2t² + t) d₀ + (t³ − t²) d₁,
//!   with the derivatives (scaled by w) estimated by finite differences over the neighbouring
//!   knots, d₀ = w (f₁ − f₋₁)/(x₁ − x₋₁) and d₁ = w (f₂ − f₀)/(x₂ − x₀) (pbrt Eq. 8.28).
//! - At the ends of the knot vector the missing neighbour is replaced by the one-sided
//!   difference d = f₁ − f₀, as pbrt does; [`catmull_rom_weights`] folds the corresponding
//!   weight into the two interval nodes so that every function here uses the same spline.
//!
//! Every function is linear in the tabulated values, so interpolating tabulated CDFs across a
//! first dimension (as [`sample_catmull_rom_2d`] does) gives exactly the CDF of the
//! interpolated spline.

#![allow(
    clippy::neg_cmp_op_on_partial_ord,
    reason = "`!(x > 0.0)` deliberately treats NaN as failing the guard"
)]

/// The largest index `i` in `[0, size − 2]` for which `pred(i)` holds, assuming `pred` is
/// true on a prefix of `0..size` and false after it (pbrt 3rd ed. §A.5 `FindInterval`).
/// Returns 0 when `pred(0)` is false and `size − 2` when `pred` holds everywhere; `size` must
/// be at least 2 (smaller sizes return 0).
pub fn find_interval(size: usize, pred: impl Fn(usize) -> bool) -> usize {
    if size < 2 {
        return 0;
    }
    // Binary search for the first index where pred is false.
    let (mut first, mut len) = (0usize, size);
    while len > 0 {
        let half = len / 2;
        let middle = first + half;
        if pred(middle) {
            first = middle + 1;
            len -= half + 1;
        } else {
            len = half;
        }
    }
    first.saturating_sub(1).min(size - 2)
}

/// Spline weights of the four knots around `x` (pbrt 3rd ed. §8.6.1 `CatmullRomWeights`,
/// Eq. 8.27-8.28).
///
/// Returns `Some((offset, w))` such that the spline through `(xs[k], f[k])` evaluates to
/// Σₖ `w[k] · f[offset + k]` for k = 0..4. `offset` may be −1 and `offset + 3` may be
/// `xs.len()`: the corresponding weights are then exactly 0 (the missing neighbour's
/// contribution is folded into the interval nodes) and must be skipped. Returns `None` when `x`
/// lies outside `[xs[0], xs[n − 1]]`, is NaN, or there are fewer than two knots. The knots must
/// be strictly increasing.
pub fn catmull_rom_weights(xs: &[f64], x: f64) -> Option<(isize, [f64; 4])> {
    let n = xs.len();
    if n < 2 || !(x >= xs[0] && x <= xs[n - 1]) {
        return None;
    }
    let idx = find_interval(n, |i| xs[i] <= x);
    let (x0, x1) = (xs[idx], xs[idx + 1]);
    let width = x1 - x0;
    let t = if width > 0.0 {
        ((x - x0) / width).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (t2, t3) = (t * t, t * t * t);
    let mut w = [0.0; 4];
    // Hermite basis functions of the two interval nodes (pbrt Eq. 8.27).
    w[1] = 2.0 * t3 - 3.0 * t2 + 1.0;
    w[2] = -2.0 * t3 + 3.0 * t2;
    // Basis of d₀ = w (f₁ − f₋₁)/(x₁ − x₋₁), or of d₀ = f₁ − f₀ at the first interval.
    let h10 = t3 - 2.0 * t2 + t;
    let left = if idx > 0 { x1 - xs[idx - 1] } else { 0.0 };
    if idx > 0 && left > 0.0 {
        let w0 = h10 * width / left;
        w[0] = -w0;
        w[2] += w0;
    } else {
        w[1] -= h10;
        w[2] += h10;
    }
    // Basis of d₁ = w (f₂ − f₀)/(x₂ − x₀), or of d₁ = f₁ − f₀ at the last interval.
    let h11 = t3 - t2;
    let right = if idx + 2 < n { xs[idx + 2] - x0 } else { 0.0 };
    if idx + 2 < n && right > 0.0 {
        let w3 = h11 * width / right;
        w[1] -= w3;
        w[3] = w3;
    } else {
        w[1] -= h11;
        w[2] += h11;
    }
    Some((idx as isize - 1, w))
}

/// The spline through `(xs[k], values[k])` evaluated at `x`, or `None` outside the knots
/// (the weights of [`catmull_rom_weights`] applied to `values`).
pub fn interpolate_catmull_rom(xs: &[f64], values: &[f64], x: f64) -> Option<f64> {
    let (offset, w) = catmull_rom_weights(xs, x)?;
    Some(apply_weights(offset, &w, |k| values[k]))
}

/// Σₖ `w[k] · value(offset + k)` for the `(offset, w)` of [`catmull_rom_weights`], skipping
/// the zero weights (whose index may be out of range). `value` is only called with valid
/// indices.
pub fn apply_weights(offset: isize, w: &[f64; 4], value: impl Fn(usize) -> f64) -> f64 {
    let mut sum = 0.0;
    for (k, &wk) in w.iter().enumerate() {
        if wk != 0.0 {
            let idx = offset + k as isize;
            if idx >= 0 {
                sum += wk * value(idx as usize);
            }
        }
    }
    sum
}

/// Scaled end derivatives (d₀, d₁) of the spline on interval `i` (pbrt Eq. 8.28, one-sided
/// differences at the ends of the knot vector).
pub(crate) fn segment_derivatives(xs: &[f64], f: impl Fn(usize) -> f64, i: usize) -> (f64, f64) {
    let n = xs.len();
    let (x0, x1) = (xs[i], xs[i + 1]);
    let width = x1 - x0;
    let (f0, f1) = (f(i), f(i + 1));
    let d0 = if i > 0 && x1 - xs[i - 1] > 0.0 {
        width * (f1 - f(i - 1)) / (x1 - xs[i - 1])
    } else {
        f1 - f0
    };
    let d1 = if i + 2 < n && xs[i + 2] - x0 > 0.0 {
        width * (f(i + 2) - f0) / (xs[i + 2] - x0)
    } else {
        f1 - f0
    };
    (d0, d1)
}

/// Integral of the spline over each interval: returns the total ∫ p(x) dx over
/// `[xs[0], xs[n−1]]` and the running integral at every knot (`cdf[0] = 0`, unnormalised),
/// pbrt 3rd ed. §8.6.1 `IntegrateCatmullRom`.
///
/// Integrating Eq. 8.27 over t ∈ [0, 1] gives w ((f₀ + f₁)/2 + (d₀ − d₁)/12) per interval.
pub fn integrate_catmull_rom(xs: &[f64], values: &[f64]) -> (f64, Vec<f64>) {
    let n = xs.len().min(values.len());
    let mut cdf = vec![0.0; n];
    let mut sum = 0.0;
    for i in 0..n.saturating_sub(1) {
        let width = xs[i + 1] - xs[i];
        let (d0, d1) = segment_derivatives(&xs[..n], |k| values[k], i);
        sum += ((d0 - d1) / 12.0 + 0.5 * (values[i] + values[i + 1])) * width;
        cdf[i + 1] = sum;
    }
    (sum, cdf)
}

/// Cubic Hermite polynomial of one interval: value and t-derivative at t (pbrt Eq. 8.27).
fn hermite(f0: f64, f1: f64, d0: f64, d1: f64, t: f64) -> (f64, f64) {
    let (t2, t3) = (t * t, t * t * t);
    let value = (2.0 * t3 - 3.0 * t2 + 1.0) * f0
        + (-2.0 * t3 + 3.0 * t2) * f1
        + (t3 - 2.0 * t2 + t) * d0
        + (t3 - t2) * d1;
    let slope = (6.0 * t2 - 6.0 * t) * f0
        + (-6.0 * t2 + 6.0 * t) * f1
        + (3.0 * t2 - 4.0 * t + 1.0) * d0
        + (3.0 * t2 - 2.0 * t) * d1;
    (value, slope)
}

/// Newton-bisection on t ∈ [0, 1] for `fun(t) = (F(t), F'(t))` reaching `target`, with F
/// non-decreasing (pbrt 3rd ed. §8.6.1-8.6.2). `scale` sets the absolute tolerance.
fn newton_bisect(fun: impl Fn(f64) -> (f64, f64), target: f64, t0: f64, scale: f64) -> f64 {
    let tol = 1e-13 * scale.abs().max(f64::MIN_POSITIVE);
    let (mut a, mut b, mut t) = (0.0f64, 1.0f64, t0);
    for _ in 0..200 {
        if !(t >= a && t <= b) {
            t = 0.5 * (a + b);
        }
        let (value, slope) = fun(t);
        let err = value - target;
        if err.abs() < tol || b - a < 1e-15 {
            break;
        }
        if err < 0.0 {
            a = t;
        } else {
            b = t;
        }
        let step = err / slope;
        t = if step.is_finite() { t - step } else { f64::NAN };
    }
    if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.5 * (a + b)
    }
}

/// The x at which the spline through monotonically increasing `values` takes the value `y`
/// (pbrt 3rd ed. §8.6.2 `InvertCatmullRom`): the interval is found by bisection over the
/// knots, then Newton-bisection on the cubic. Returns `xs[0]` for `y <= values[0]` and
/// `xs[n−1]` for `y >= values[n−1]`; 0 for fewer than two knots.
pub fn invert_catmull_rom(xs: &[f64], values: &[f64], y: f64) -> f64 {
    let n = xs.len().min(values.len());
    if n < 2 {
        return xs.first().copied().unwrap_or(0.0);
    }
    if !(y > values[0]) {
        return xs[0];
    }
    if !(y < values[n - 1]) {
        return xs[n - 1];
    }
    let i = find_interval(n, |k| values[k] <= y);
    let (x0, x1) = (xs[i], xs[i + 1]);
    let (f0, f1) = (values[i], values[i + 1]);
    let (d0, d1) = segment_derivatives(&xs[..n], |k| values[k], i);
    let scale = f0.abs().max(f1.abs());
    let t = newton_bisect(|t| hermite(f0, f1, d0, d1, t), y, 0.5, scale);
    x0 + t * (x1 - x0)
}

/// Samples the second dimension of a 2D tabulated function at an interpolated first-dimension
/// parameter (pbrt 3rd ed. §8.6.2 / §15.4.2 `SampleCatmullRom2D`).
///
/// `values` and `cdf` are row-major `nodes1.len() × nodes2.len()` arrays; each row of `cdf`
/// is the running integral of the same row of `values` from [`integrate_catmull_rom`]. The
/// rows are blended with the spline weights of `alpha` over `nodes1`; `u ∈ [0, 1)` picks the
/// interval by bisection on the blended CDF, then the integral of the blended cubic on that
/// interval is inverted by Newton-bisection, starting from the root of the linear interpolant.
///
/// Returns `(x, f(x), pdf(x))`: the sample in the units of `nodes2`, the blended spline at
/// it, and its density f(x)/∫f. Returns `(0, 0, 0)` when `alpha` is outside `nodes1`, the
/// arrays are inconsistent, or the blended row has no positive mass.
pub fn sample_catmull_rom_2d(
    nodes1: &[f64],
    nodes2: &[f64],
    values: &[f64],
    cdf: &[f64],
    alpha: f64,
    u: f64,
) -> (f64, f64, f64) {
    let (n1, n2) = (nodes1.len(), nodes2.len());
    if n2 < 2 || values.len() < n1 * n2 || cdf.len() < n1 * n2 {
        return (0.0, 0.0, 0.0);
    }
    let Some((offset, weights)) = catmull_rom_weights(nodes1, alpha) else {
        return (0.0, 0.0, 0.0);
    };
    let interp =
        |array: &[f64], idx: usize| apply_weights(offset, &weights, |row| array[row * n2 + idx]);
    let maximum = interp(cdf, n2 - 1);
    if !(maximum > 0.0) || !maximum.is_finite() {
        return (0.0, 0.0, 0.0);
    }
    let u = if u.is_finite() {
        u.clamp(0.0, 1.0)
    } else {
        0.0
    } * maximum;
    let idx = find_interval(n2, |i| interp(cdf, i) <= u);
    let (f0, f1) = (interp(values, idx), interp(values, idx + 1));
    let (x0, x1) = (nodes2[idx], nodes2[idx + 1]);
    let width = x1 - x0;
    if !(width > 0.0) {
        return (x0, f0, (f0 / maximum).max(0.0));
    }
    let (d0, d1) = segment_derivatives(nodes2, |k| interp(values, k), idx);
    // Mass to cover inside the interval, in units of f (the interval integral is w ∫₀ᵗ p).
    let target = (u - interp(cdf, idx)) / width;
    let (t, fval) = invert_segment_integral(f0, f1, d0, d1, target);
    (x0 + width * t, fval, (fval / maximum).max(0.0))
}

/// Inverts the integral of one Hermite segment (pbrt Eq. 8.27 with end values `f0`, `f1` and
/// scaled derivatives `d0`, `d1`): the t ∈ [0, 1] with ∫₀ᵗ p(s) ds = `target`, by
/// Newton-bisection started from the root of the linear interpolant's integral (pbrt 3rd ed.
/// §8.6.2 `SampleCatmullRom2D`). Returns (t, p(t)).
pub(crate) fn invert_segment_integral(
    f0: f64,
    f1: f64,
    d0: f64,
    d1: f64,
    target: f64,
) -> (f64, f64) {
    // Initial guess: invert the integral of the linear interpolant f₀ + (f₁ − f₀) t.
    let t0 = if f0 != f1 {
        (f0 - (f0 * f0 + 2.0 * target * (f1 - f0)).max(0.0).sqrt()) / (f0 - f1)
    } else if f0 != 0.0 {
        target / f0
    } else {
        0.5
    };
    // ∫₀ᵗ p(s) ds of Eq. 8.27 in Horner form, and p(t) itself.
    let integral = |t: f64| {
        let big = t
            * (f0
                + t * (0.5 * d0
                    + t * ((-2.0 * d0 - d1) / 3.0 + f1 - f0
                        + t * (0.25 * (d0 + d1) + 0.5 * (f0 - f1)))));
        let small = f0
            + t * (d0 + t * (-2.0 * d0 - d1 + 3.0 * (f1 - f0) + t * (d0 + d1 + 2.0 * (f0 - f1))));
        (big, small)
    };
    let scale = f0.abs().max(f1.abs()).max(d0.abs()).max(d1.abs());
    let t = newton_bisect(integral, target, t0, scale);
    (t, integral(t).1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::integrate;
    use rand::{RngExt, SeedableRng};
    use rand_pcg::Pcg64Mcg;

    fn nonuniform_knots() -> Vec<f64> {
        // 0, then geometric as in the PBD radius grid, plus a few irregular steps.
        let mut xs = vec![0.0, 0.05, 0.07, 0.2];
        let mut x = 0.2;
        while x < 8.0 {
            x *= 1.3;
            xs.push(x);
        }
        xs
    }

    #[test]
    fn weights_sum_to_one_and_reproduce_linear_functions() {
        let xs = nonuniform_knots();
        let f = |x: f64| 3.0 - 0.7 * x;
        let values: Vec<f64> = xs.iter().map(|&x| f(x)).collect();
        let hi = *xs.last().unwrap();
        for k in 0..=1000 {
            let x = hi * k as f64 / 1000.0;
            let (offset, w) = catmull_rom_weights(&xs, x).unwrap();
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-13, "x {x}: {w:?}");
            if offset < 0 {
                assert_eq!(w[0], 0.0);
            }
            if offset + 3 >= xs.len() as isize {
                assert_eq!(w[3], 0.0);
            }
            let got = interpolate_catmull_rom(&xs, &values, x).unwrap();
            assert!((got - f(x)).abs() < 1e-12, "x {x}: {got} vs {}", f(x));
        }
        // The knots themselves are reproduced exactly for any data.
        let data: Vec<f64> = xs.iter().map(|x| (x * 3.0).sin()).collect();
        for (x, v) in xs.iter().zip(&data) {
            assert!((interpolate_catmull_rom(&xs, &data, *x).unwrap() - v).abs() < 1e-14);
        }
        assert!(catmull_rom_weights(&xs, -1e-9).is_none());
        assert!(catmull_rom_weights(&xs, hi * (1.0 + 1e-12)).is_none());
        assert!(catmull_rom_weights(&xs, f64::NAN).is_none());
        assert!(catmull_rom_weights(&[1.0], 1.0).is_none());
    }

    #[test]
    fn interpolant_integral_matches_integrate_catmull_rom() {
        // The closed-form interval integrals equal quadrature of the interpolant itself.
        let xs = nonuniform_knots();
        let values: Vec<f64> = xs.iter().map(|x| (-x).exp() * (1.0 + x * x)).collect();
        let (total, cdf) = integrate_catmull_rom(&xs, &values);
        let mut acc = 0.0;
        for i in 0..xs.len() - 1 {
            let p = |x: f64| interpolate_catmull_rom(&xs, &values, x).unwrap();
            acc += integrate(&p, xs[i], xs[i + 1], 8);
            assert!(
                (cdf[i + 1] - acc).abs() < 1e-13,
                "interval {i}: {} vs {acc}",
                cdf[i + 1]
            );
        }
        assert!((total - acc).abs() < 1e-13);
    }

    #[test]
    fn integration_of_smooth_function_converges() {
        // ∫₀^π sin = 2; the error must fall by ~O(h³) or faster as the grid is refined.
        let mut errors = Vec::new();
        for n in [10usize, 20, 40, 80, 160] {
            let xs: Vec<f64> = (0..=n)
                .map(|i| std::f64::consts::PI * ((i as f64 / n as f64).powf(1.3)))
                .collect();
            let values: Vec<f64> = xs.iter().map(|x| x.sin()).collect();
            let (total, _) = integrate_catmull_rom(&xs, &values);
            errors.push((total - 2.0).abs());
        }
        assert!(errors[4] < 1e-5, "{errors:?}");
        for k in 1..errors.len() {
            assert!(errors[k] < errors[k - 1] / 3.0, "{errors:?}");
        }
    }

    #[test]
    fn inversion_round_trips() {
        let xs = nonuniform_knots();
        let values: Vec<f64> = xs.iter().map(|x| 1.0 - (-x).exp() + 0.1 * x).collect();
        let hi = *xs.last().unwrap();
        for k in 0..=200 {
            let x = hi * k as f64 / 200.0;
            let y = interpolate_catmull_rom(&xs, &values, x).unwrap();
            let back = invert_catmull_rom(&xs, &values, y);
            assert!((back - x).abs() < 1e-9 * hi, "x {x}: back {back}");
        }
        assert_eq!(invert_catmull_rom(&xs, &values, -1.0), 0.0);
        assert_eq!(invert_catmull_rom(&xs, &values, 1e9), hi);
    }

    /// A 2D table whose rows are positive profiles of varying width.
    fn table() -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        let nodes1 = vec![0.0, 0.2, 0.5, 0.6, 1.0];
        let nodes2 = nonuniform_knots();
        let mut values = Vec::new();
        let mut cdf = Vec::new();
        for &a in &nodes1 {
            let row: Vec<f64> = nodes2
                .iter()
                .map(|&x| x * (-x / (0.5 + a)).exp() + 0.01)
                .collect();
            let (_, c) = integrate_catmull_rom(&nodes2, &row);
            values.extend(row);
            cdf.extend(c);
        }
        (nodes1, nodes2, values, cdf)
    }

    #[test]
    fn sampling_matches_the_spline_cdf() {
        let (n1, n2, values, cdf) = table();
        let rows = n2.len();
        let hi = *n2.last().unwrap();
        for alpha in [0.0, 0.35, 0.6, 1.0] {
            let (offset, w) = catmull_rom_weights(&n1, alpha).unwrap();
            let f = |x: f64| {
                let (o2, w2) = catmull_rom_weights(&n2, x).unwrap();
                apply_weights(offset, &w, |i| {
                    apply_weights(o2, &w2, |j| values[i * rows + j])
                })
            };
            // The spline's own CDF by quadrature over each knot interval.
            let mut acc = vec![0.0];
            for k in 0..rows - 1 {
                let v = acc[k] + integrate(&f, n2[k], n2[k + 1], 10);
                acc.push(v);
            }
            let total = acc[rows - 1];
            let spline_cdf = |x: f64| {
                let k = find_interval(rows, |i| n2[i] <= x);
                (acc[k] + integrate(&f, n2[k], x, 10)) / total
            };
            // Exact quantiles: the sampler inverts the CDF.
            for u in [0.0, 1e-6, 0.1, 0.5, 0.9, 0.999] {
                let (x, fx, pdf) = sample_catmull_rom_2d(&n1, &n2, &values, &cdf, alpha, u);
                assert!(
                    (spline_cdf(x) - u).abs() < 1e-9,
                    "alpha {alpha} u {u}: x {x}"
                );
                assert!((fx - f(x)).abs() < 1e-9 * fx.abs().max(1e-3));
                assert!((pdf - f(x) / total).abs() < 1e-9 * pdf.max(1e-3));
            }
            // KS test of random samples against the same CDF.
            let mut rng = Pcg64Mcg::seed_from_u64(7);
            let n = 5000;
            let mut xs: Vec<f64> = (0..n)
                .map(|_| {
                    sample_catmull_rom_2d(&n1, &n2, &values, &cdf, alpha, rng.random::<f64>()).0
                })
                .collect();
            xs.sort_by(f64::total_cmp);
            let mut d: f64 = 0.0;
            for (i, &x) in xs.iter().enumerate() {
                assert!((0.0..=hi).contains(&x));
                let c = spline_cdf(x);
                d = d
                    .max((c - i as f64 / n as f64).abs())
                    .max((c - (i + 1) as f64 / n as f64).abs());
            }
            assert!(d < 1.95 / (n as f64).sqrt(), "alpha {alpha}: KS {d}");
        }
        assert_eq!(
            sample_catmull_rom_2d(&n1, &n2, &values, &cdf, 1.5, 0.5),
            (0.0, 0.0, 0.0)
        );
        // Inconsistent arrays (one value or one CDF entry short) give zeros, not a panic.
        let n = values.len();
        for (v, c) in [(&values[..n - 1], &cdf[..]), (&values[..], &cdf[..n - 1])] {
            assert_eq!(
                sample_catmull_rom_2d(&n1, &n2, v, c, 0.5, 0.5),
                (0.0, 0.0, 0.0)
            );
        }
    }
}
