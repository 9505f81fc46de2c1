//! One tabulated radial profile at table speed: a Catmull-Rom row with its coefficients
//! precomputed, a constant-time knot lookup, and exact sampling of the spline.
//!
//! The tabulated models (photon beam diffusion, `mc-table`) interpolate a 2D table over
//! (albedo, optical radius) with tensor-product Catmull-Rom splines (pbrt 3rd ed. §11.4.2,
//! §8.6.1). For one medium the albedo of each channel is fixed, and every spline operation is
//! linear in the tabulated values, so blending the albedo rows *once* when the model is built
//! gives exactly the same 1D spline in radius that the per-call tensor interpolation gives
//! (up to rounding, ~10⁻¹⁵ relative). [`SplineRow`] holds that blended row:
//!
//! - per knot interval the Hermite data (f₀, f₁, d₀, d₁) of pbrt Eq. 8.27-8.28 and the
//!   power-basis coefficients of p(t), so an evaluation is one lookup and one Horner step;
//! - the running integral at the knots (pbrt §8.6.1 `IntegrateCatmullRom`, blended from the
//!   table's row integrals), so [`SplineRow::sample`] inverts exactly the CDF of the spline
//!   (pbrt §8.6.2 `SampleCatmullRom2D` with the albedo weights already applied);
//! - a [`KnotIndex`]: the interval of x from a bucket table over an approximate log₂ x (the
//!   exponent and mantissa bits), corrected by comparisons with the knots, so the interval
//!   is exactly the one a bisection would find.

use crate::catmull_rom::{apply_weights, catmull_rom_weights, invert_segment_integral};

/// Buckets per octave of [`KnotIndex`].
const BUCKETS_PER_OCTAVE: f64 = 8.0;

/// A monotone, continuous approximation of log₂ x for positive normal x: exponent plus
/// mantissa fraction (within 0.086 of log₂ x).
#[inline]
fn approx_log2(x: f64) -> f64 {
    let bits = x.to_bits();
    let exponent = ((bits >> 52) & 0x7ff) as f64 - 1023.0;
    let mantissa = (bits & ((1u64 << 52) - 1)) as f64 * (1.0 / (1u64 << 52) as f64);
    exponent + mantissa
}

/// Constant-time interval lookup over increasing knots x₀ < x₁ < … whose knots from x₁ on are
/// positive (x₀ may be 0), for knot spacings that are roughly geometric.
#[derive(Clone, Debug)]
pub struct KnotIndex {
    knots: Vec<f64>,
    /// approx_log2(x₁).
    l_min: f64,
    /// Per bucket, the interval of the bucket's smallest x.
    lut: Vec<u32>,
}

impl KnotIndex {
    /// Builds the lookup for `knots`; `None` unless there are at least two, strictly
    /// increasing and finite, with x₀ ≥ 0 and x₁ > 0.
    pub fn new(knots: &[f64]) -> Option<Self> {
        let n = knots.len();
        let valid = n >= 2
            && knots[0] >= 0.0
            && knots[1] > 0.0
            && knots.iter().all(|k| k.is_finite())
            && knots.windows(2).all(|w| w[0] < w[1]);
        if !valid {
            return None;
        }
        let l_min = approx_log2(knots[1]);
        let l_max = approx_log2(knots[n - 1]);
        let buckets = ((l_max - l_min) * BUCKETS_PER_OCTAVE).ceil() as usize + 1;
        let lut = (0..buckets)
            .map(|b| {
                let start = l_min + b as f64 / BUCKETS_PER_OCTAVE;
                // Knots at or below the bucket start (knot 0 always counts).
                let count = 1 + knots[1..]
                    .iter()
                    .take_while(|&&k| approx_log2(k) <= start)
                    .count();
                (count - 1).min(n - 2) as u32
            })
            .collect();
        Some(KnotIndex {
            knots: knots.to_vec(),
            l_min,
            lut,
        })
    }

    /// The knots.
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// The interval i ∈ [0, n − 2] with xᵢ ≤ x < xᵢ₊₁ (the last interval for x ≥ xₙ₋₁, the
    /// first for x < x₁), for finite x ≥ 0.
    #[inline]
    pub fn interval(&self, x: f64) -> usize {
        let n = self.knots.len();
        if !(x >= self.knots[1]) {
            return 0;
        }
        let b = ((approx_log2(x) - self.l_min) * BUCKETS_PER_OCTAVE) as usize;
        let mut i = self.lut[b.min(self.lut.len() - 1)] as usize;
        while i + 2 < n && self.knots[i + 1] <= x {
            i += 1;
        }
        while i > 0 && self.knots[i] > x {
            i -= 1;
        }
        i
    }
}

/// True when p(t) = c₀ + c₁t + c₂t² + c₃t³ is negative somewhere on [0, 1]: at an end or at
/// a stationary point (a root of p′(t) = c₁ + 2c₂t + 3c₃t² inside the interval).
fn dips_below_zero(c: &[f64; 4]) -> bool {
    let p = |t: f64| c[0] + t * (c[1] + t * (c[2] + t * c[3]));
    if p(0.0) < 0.0 || p(1.0) < 0.0 {
        return true;
    }
    let (a, b, cc) = (3.0 * c[3], 2.0 * c[2], c[1]);
    let roots: [f64; 2] = if a == 0.0 {
        if b == 0.0 { [-1.0; 2] } else { [-cc / b, -1.0] }
    } else {
        let disc = b * b - 4.0 * a * cc;
        if disc < 0.0 {
            [-1.0; 2]
        } else {
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            let r1 = q / a;
            let r2 = if q != 0.0 { cc / q } else { -1.0 };
            [r1, r2]
        }
    };
    roots.into_iter().any(|t| t > 0.0 && t < 1.0 && p(t) < 0.0)
}

/// Hermite data and power-basis coefficients of one knot interval.
#[derive(Clone, Copy, Debug, Default)]
struct Segment {
    x0: f64,
    width: f64,
    inv_width: f64,
    f0: f64,
    f1: f64,
    d0: f64,
    d1: f64,
    /// p(t) = c₀ + c₁t + c₂t² + c₃t³.
    c: [f64; 4],
}

impl Segment {
    /// p(t), t in [0, 1] across the segment.
    #[inline(always)]
    fn at(&self, t: f64) -> f64 {
        self.c[0] + t * (self.c[1] + t * (self.c[2] + t * self.c[3]))
    }

    /// dp/dt.
    fn slope_at(&self, t: f64) -> f64 {
        self.c[1] + t * (2.0 * self.c[2] + 3.0 * t * self.c[3])
    }

    /// The straight line between the segment's knot values (d₀ = d₁ = f₁ − f₀).
    fn straight(&self) -> Segment {
        let slope = self.f1 - self.f0;
        Segment {
            d0: slope,
            d1: slope,
            c: [self.f0, slope, 0.0, 0.0],
            ..*self
        }
    }
}

/// A 1D Catmull-Rom spline row with its running integral (see the module docs).
#[derive(Clone, Debug)]
pub struct SplineRow {
    index: KnotIndex,
    segments: Vec<Segment>,
    cdf: Vec<f64>,
}

impl SplineRow {
    /// The albedo-blended row of a 2D table: `values` and `cdf` are row-major
    /// `rows.len() × index.knots().len()` arrays (each cdf row the running integral of its
    /// values row, as from [`crate::catmull_rom::integrate_catmull_rom`]), blended with the
    /// spline weights of `alpha` over `rows`. `None` when `alpha` lies outside `rows`.
    pub fn blend(
        index: &KnotIndex,
        rows: &[f64],
        values: &[f64],
        cdf: &[f64],
        alpha: f64,
    ) -> Option<Self> {
        let n = index.knots().len();
        if values.len() < rows.len() * n || cdf.len() < rows.len() * n {
            return None;
        }
        let (offset, w) = catmull_rom_weights(rows, alpha)?;
        let blend = |array: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|k| apply_weights(offset, &w, |row| array[row * n + k]))
                .collect()
        };
        Some(SplineRow::with_cdf(index, &blend(values), blend(cdf)))
    }

    /// The row through `values` at `index`'s knots with the given running integral.
    fn with_cdf(index: &KnotIndex, values: &[f64], cdf: Vec<f64>) -> Self {
        let xs = index.knots();
        let n = xs.len();
        let segments = (0..n - 1)
            .map(|i| {
                let (d0, d1) = crate::catmull_rom::segment_derivatives(xs, |k| values[k], i);
                let (f0, f1) = (values[i], values[i + 1]);
                let width = xs[i + 1] - xs[i];
                Segment {
                    x0: xs[i],
                    width,
                    inv_width: 1.0 / width,
                    f0,
                    f1,
                    d0,
                    d1,
                    c: [
                        f0,
                        d0,
                        -3.0 * f0 + 3.0 * f1 - 2.0 * d0 - d1,
                        2.0 * f0 - 2.0 * f1 + d0 + d1,
                    ],
                }
            })
            .collect();
        SplineRow {
            index: index.clone(),
            segments,
            cdf,
        }
    }

    /// The same row with every segment made non-negative: where a segment's cubic dips below
    /// 0 (its minimum over [0, 1], at an end or a root of p′, is negative) or has a negative
    /// knot value, d₀ is raised to at least −3f₀ and d₁ lowered to at most 3f₁, which makes all four
    /// Bernstein coefficients non-negative and so p ≥ 0 on the segment (the sufficient
    /// condition of positivity-preserving Hermite interpolation, e.g. Schmidt & Heß,
    /// *Positivity of cubic polynomials on intervals and positive spline interpolation*, BIT
    /// 28, 1988). Knot values are kept (negative ones set to 0) and the running integral is
    /// recomputed from the limited segments, so [`SplineRow::sample`] draws exactly from
    /// [`SplineRow::eval`] of the result divided by [`SplineRow::total`]. Segments that need no
    /// limiting are unchanged.
    pub fn non_negative(&self) -> SplineRow {
        let mut segments = self.segments.clone();
        let mut cdf = vec![0.0; segments.len() + 1];
        for (i, s) in segments.iter_mut().enumerate() {
            let (f0, f1) = (s.f0.max(0.0), s.f1.max(0.0));
            let (mut d0, mut d1) = (s.d0, s.d1);
            if f0 != s.f0 || f1 != s.f1 || dips_below_zero(&s.c) {
                d0 = d0.max(-3.0 * f0);
                d1 = d1.min(3.0 * f1);
                *s = Segment {
                    f0,
                    f1,
                    d0,
                    d1,
                    c: [
                        f0,
                        d0,
                        -3.0 * f0 + 3.0 * f1 - 2.0 * d0 - d1,
                        2.0 * f0 - 2.0 * f1 + d0 + d1,
                    ],
                    ..*s
                };
            }
            // ∫ over the segment: w ((f₀ + f₁)/2 + (d₀ − d₁)/12) (pbrt §8.6.1).
            cdf[i + 1] = cdf[i] + s.width * (0.5 * (s.f0 + s.f1) + (s.d0 - s.d1) / 12.0);
        }
        SplineRow {
            index: self.index.clone(),
            segments,
            cdf,
        }
    }

    /// The same row with its first segment replaced by the straight line between its knot
    /// values (d₀ = d₁ = f₁ − f₀) and the running integral recomputed. For a row of 2πx R_d
    /// that starts at 0 this makes R_d constant on the first interval: a Catmull-Rom first
    /// segment from 0 has R_d ∝ f₁ + (f₁ − d₁) t(1 − t), a bump of (f₁ − d₁)/4 in the middle of
    /// the interval whenever the next knot's slope differs from the segment's own (the
    /// `mc-table` profile, whose 2πx R_d is nearly flat near 0, would bump by up to 22 %).
    pub fn with_linear_first_segment(&self) -> SplineRow {
        let mut segments = self.segments.clone();
        if let Some(s) = segments.first_mut() {
            *s = s.straight();
        }
        self.with_segments(segments)
    }

    /// A row of this row's knots with `segments`, its running integral recomputed.
    fn with_segments(&self, segments: Vec<Segment>) -> SplineRow {
        let mut cdf = vec![0.0; segments.len() + 1];
        for (i, s) in segments.iter().enumerate() {
            // ∫ over the segment: w ((f₀ + f₁)/2 + (d₀ − d₁)/12) (pbrt §8.6.1).
            cdf[i + 1] = cdf[i] + s.width * (0.5 * (s.f0 + s.f1) + (s.d0 - s.d1) / 12.0);
        }
        SplineRow {
            index: self.index.clone(),
            segments,
            cdf,
        }
    }

    /// The same row with every segment on which p(x)/x rises (tested at 17 points per
    /// segment: p′(x) x > p(x), relative 10⁻¹²) replaced by the straight line between its knot
    /// values (d₀ = d₁ = f₁ − f₀), and the running integral recomputed. For a row of
    /// T = 2πx R_d whose knot values have R_d non-increasing (T₁/x₁ ≤ T₀/x₀), a straight
    /// segment of slope s keeps R_d non-increasing: x² (T/x)′ = x₀ (s − T₀/x₀) ≤ 0. Catmull-Rom
    /// segments can rise after a flat stretch (their end slopes come from the neighbours).
    /// Segments starting at x ≤ 0 are kept.
    pub fn monotone_over_x(&self) -> SplineRow {
        let mut segments = self.segments.clone();
        for s in segments.iter_mut() {
            if !(s.x0 > 0.0) {
                continue;
            }
            let rises = (0..=16).any(|k| {
                let t = k as f64 / 16.0;
                let (p, dp) = (s.at(t), s.slope_at(t));
                let x = s.x0 + t * s.width;
                dp * x > s.width * p + 1e-12 * (s.width * p).abs()
            });
            if rises {
                *s = s.straight();
            }
        }
        self.with_segments(segments)
    }

    /// The row through `values` (one per knot of `index`), its integral computed as in
    /// [`crate::catmull_rom::integrate_catmull_rom`].
    pub fn new(index: &KnotIndex, values: &[f64]) -> Self {
        let (_, cdf) = crate::catmull_rom::integrate_catmull_rom(index.knots(), values);
        SplineRow::with_cdf(index, values, cdf)
    }

    /// Largest knot; the spline is not defined beyond it.
    pub fn x_max(&self) -> f64 {
        *self.index.knots().last().unwrap_or(&0.0)
    }

    /// The integral of the spline over all knots.
    pub fn total(&self) -> f64 {
        *self.cdf.last().unwrap_or(&0.0)
    }

    /// The spline at x, or 0 outside [x₀, xₙ₋₁] or for NaN.
    #[inline]
    pub fn eval(&self, x: f64) -> f64 {
        if !(x >= self.index.knots[0] && x <= self.x_max()) {
            return 0.0;
        }
        let s = &self.segments[self.index.interval(x)];
        let t = ((x - s.x0) * s.inv_width).min(1.0);
        s.at(t)
    }

    /// The spline divided by x, for a row that vanishes at x₀ = 0 (a tabulated 2πr R_d): in
    /// the first interval p(t)/x = (c₁ + c₂t + c₃t²)/w exactly (c₀ = 0), the limit at 0
    /// included. 0 beyond the last knot or for x < 0 or NaN.
    #[inline]
    pub fn eval_over_x(&self, x: f64) -> f64 {
        if !(x >= 0.0 && x <= self.x_max()) {
            return 0.0;
        }
        let i = self.index.interval(x);
        let s = &self.segments[i];
        let t = ((x - s.x0) * s.inv_width).min(1.0);
        if i == 0 && s.x0 == 0.0 {
            (s.c[1] + t * (s.c[2] + t * s.c[3])) * s.inv_width
        } else {
            (s.c[0] + t * (s.c[1] + t * (s.c[2] + t * s.c[3]))) / x
        }
    }

    /// [`eval_over_x`](Self::eval_over_x) g(x) = p(x)/x with its first two derivatives,
    /// (g, g′, g″), from the segment's polynomial: g′ = p′/x − p/x², g″ = p″/x − 2p′/x² +
    /// 2p/x³; in a first interval from x₀ = 0 (c₀ = 0) exactly g = (c₁ + c₂t + c₃t²)/w,
    /// g′ = (c₂ + 2c₃t)/w², g″ = 2c₃/w³, so the limit at 0 is finite. The spline is C¹, so g″
    /// jumps at the knots (the segment of `interval(x)` is used). (0, 0, 0) where
    /// `eval_over_x` is 0 by definition (beyond the last knot, x < 0, NaN); non-finite results
    /// are clamped ([`crate::finite_or_zero`]).
    #[inline]
    pub fn eval_over_x_derivatives(&self, x: f64) -> (f64, f64, f64) {
        if !(x >= 0.0 && x <= self.x_max()) {
            return (0.0, 0.0, 0.0);
        }
        let i = self.index.interval(x);
        let s = &self.segments[i];
        let t = ((x - s.x0) * s.inv_width).min(1.0);
        let c = &s.c;
        let w = s.inv_width;
        let (g0, g1, g2) = if i == 0 && s.x0 == 0.0 {
            (
                (c[1] + t * (c[2] + t * c[3])) * w,
                (c[2] + 2.0 * t * c[3]) * w * w,
                2.0 * c[3] * w * w * w,
            )
        } else {
            let p = s.at(t);
            let p1 = s.slope_at(t) * w;
            let p2 = (2.0 * c[2] + 6.0 * c[3] * t) * w * w;
            (
                p / x,
                p1 / x - p / (x * x),
                p2 / x - 2.0 * p1 / (x * x) + 2.0 * p / (x * x * x),
            )
        };
        (
            crate::finite_or_zero(g0),
            crate::finite_or_zero(g1),
            crate::finite_or_zero(g2),
        )
    }

    /// Samples x with density p(x)/∫p from `u ∈ [0, 1)`: the interval by bisection over the
    /// running integral, then Newton-bisection on the segment's integral (pbrt 3rd ed. §8.6.2).
    /// Returns `None` when the row has no positive mass.
    pub fn sample(&self, u: f64) -> Option<f64> {
        let total = self.total();
        if !(total > 0.0) || !total.is_finite() {
            return None;
        }
        let u = if u.is_finite() {
            u.clamp(0.0, 1.0)
        } else {
            0.0
        } * total;
        let n = self.cdf.len();
        let i = self.cdf.partition_point(|&c| c <= u).clamp(1, n - 1) - 1;
        let s = &self.segments[i];
        if !(s.width > 0.0) {
            return Some(s.x0);
        }
        let target = (u - self.cdf[i]) * s.inv_width;
        let (t, _) = invert_segment_integral(s.f0, s.f1, s.d0, s.d1, target);
        Some(s.x0 + s.width * t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn monotone_over_x_straightens_only_the_segments_where_value_over_x_rises() {
        // T = x R with R flat from 2 to 4, then dropping: the Catmull-Rom segment [3, 4] takes
        // its end slope from the drop and bulges, so T/x rises inside it.
        let knots = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let r = [1.0, 1.0, 0.5, 0.5, 0.5, 0.05, 0.04];
        let values: Vec<f64> = knots.iter().zip(r).map(|(x, r)| x * r).collect();
        let index = KnotIndex::new(&knots).unwrap();
        let row = SplineRow::new(&index, &values);
        let rises = |row: &SplineRow| {
            // The largest rise of T/x over its running minimum, from the first knot after 0
            // (the segment from x = 0 is kept as it is).
            let mut least = f64::INFINITY;
            let mut worst: f64 = 0.0;
            for k in 1000..=6000 {
                let x = k as f64 * 1e-3;
                let v = row.eval(x) / x;
                worst = worst.max(v - least);
                least = least.min(v);
            }
            worst
        };
        assert!(rises(&row) > 1e-3, "the example must rise: {}", rises(&row));
        let mono = row.monotone_over_x();
        assert!(rises(&mono) <= 1e-12, "{}", rises(&mono));
        // Each segment is either unchanged or the line between its knots; [3, 4] is straight,
        // the first is kept (x₀ = 0).
        let (mut kept, mut straight) = (0, 0);
        for i in 0..knots.len() - 1 {
            let mid = 0.5 * (knots[i] + knots[i + 1]);
            let line = 0.5 * (values[i] + values[i + 1]);
            if mono.eval(mid) == row.eval(mid) {
                kept += 1;
            } else {
                assert!((mono.eval(mid) - line).abs() < 1e-14, "segment {i}");
                straight += 1;
            }
        }
        assert!((mono.eval(3.5) - 0.5 * (values[3] + values[4])).abs() < 1e-14);
        assert_eq!(mono.eval(0.5), row.eval(0.5));
        assert!(
            kept >= 2 && straight >= 1,
            "{kept} kept, {straight} straight"
        );
        // Straightened are exactly the segments (past x = 0) on which the original T/x rises
        // somewhere, found here on a grid of 2000 points per segment.
        for i in 1..knots.len() - 1 {
            let (a, b) = (knots[i], knots[i + 1]);
            let at = |k: usize| {
                let x = a + (b - a) * k as f64 / 2000.0;
                row.eval(x) / x
            };
            let rises = (1..=2000).any(|k| at(k) > at(k - 1) * (1.0 + 1e-12));
            let mid = 0.5 * (a + b);
            let straightened = mono.eval(mid) != row.eval(mid);
            assert_eq!(straightened, rises, "segment [{a}, {b}]");
        }
        // The running integral is that of the new segments.
        let want = quadrature_cdf(&mono, &knots, 6.0);
        assert!(
            (mono.total() - want).abs() < 1e-12,
            "{} vs {want}",
            mono.total()
        );
        assert!((mono.total() - row.total()).abs() > 1e-6);
    }

    /// ∫₀ˣ of the row by Gauss–Legendre quadrature over each knot interval: an integral
    /// independent of the row's own running sums.
    fn quadrature_cdf(row: &SplineRow, knots: &[f64], x: f64) -> f64 {
        let f = |t: f64| row.eval(t);
        knots
            .windows(2)
            .filter(|w| x > w[0])
            .map(|w| crate::quadrature::integrate(&f, w[0], x.min(w[1]), 8))
            .sum()
    }

    /// The linear first segment: a straight line between the first two knot values, the
    /// other segments unchanged, and the running integral that of the new spline (Gauss
    /// quadrature of `eval` per segment), so sampling still inverts it.
    #[test]
    fn linear_first_segment_is_a_line_and_its_integral_is_exact() {
        let knots = [0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0];
        let values = [0.0, 0.9, 0.7, 0.3, 0.6, 0.2, 0.05];
        let index = KnotIndex::new(&knots).unwrap();
        let row = SplineRow::new(&index, &values).with_linear_first_segment();
        for k in 0..=10 {
            let x = 0.05 * k as f64;
            assert!((row.eval(x) - 0.9 * x / 0.5).abs() < 1e-14, "x {x}");
        }
        assert_eq!(row.eval(2.7), SplineRow::new(&index, &values).eval(2.7));
        let cdf = |x: f64| quadrature_cdf(&row, &knots, x);
        assert!((row.total() - cdf(4.0)).abs() < 1e-13, "{}", row.total());
        for u in [0.01, 0.3, 0.5, 0.77, 0.99] {
            let x = row.sample(u).unwrap();
            assert!((cdf(x) / row.total() - u).abs() < 1e-10, "u {u}: x {x}");
        }
    }

    #[test]
    fn non_negative_row_is_non_negative_and_sampled_exactly() {
        // A spike: Catmull-Rom overshoots below 0 next to it.
        let knots = [0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0];
        let values = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0];
        let index = KnotIndex::new(&knots).unwrap();
        let row = SplineRow::new(&index, &values);
        let grid: Vec<f64> = (0..=4000).map(|k| 4.0 * k as f64 / 4000.0).collect();
        assert!(grid.iter().any(|&x| row.eval(x) < -1e-3));
        let limited = row.non_negative();
        assert!(grid.iter().all(|&x| limited.eval(x) >= 0.0));
        // Knot values are kept, and segments away from the spike are unchanged.
        for (x, v) in knots.iter().zip(values) {
            assert!((limited.eval(*x) - v).abs() < 1e-15);
        }
        assert_eq!(limited.eval(3.5), row.eval(3.5));
        // The running integral is that of the limited spline (quadrature), and sampling
        // inverts it.
        let cdf = |x: f64| quadrature_cdf(&limited, &knots, x);
        assert!(
            (limited.total() - cdf(4.0)).abs() < 1e-13,
            "{}",
            limited.total()
        );
        for u in [0.01, 0.3, 0.5, 0.77, 0.99] {
            let x = limited.sample(u).unwrap();
            assert!((cdf(x) / limited.total() - u).abs() < 1e-10, "u {u}: x {x}");
        }
        // Limiting never applies to a row that stays non-negative.
        let smooth = SplineRow::new(&index, &[0.0, 0.4, 0.7, 0.8, 0.7, 0.4, 0.1]);
        let same = smooth.non_negative();
        assert!(grid.iter().all(|&x| smooth.eval(x) == same.eval(x)));
        assert_eq!(smooth.total(), same.total());
    }

    #[test]
    fn knot_index_equals_bisection() {
        // The PBD grid (0, 2.5e-3 × 1.2^k) and an irregular one.
        let mut pbd = vec![0.0, 2.5e-3];
        for _ in 0..62 {
            let v = pbd.last().unwrap() * 1.2;
            pbd.push(v);
        }
        let irregular = vec![0.0, 1e-3, 1.1e-3, 0.5, 0.51, 2.0, 64.0, 65.0, 1e4];
        for knots in [pbd, irregular] {
            let index = KnotIndex::new(&knots).unwrap();
            let n = knots.len();
            let hi = knots[n - 1];
            let mut probes: Vec<f64> = knots.clone();
            probes.extend(knots.iter().map(|k| k * (1.0 + 1e-15)));
            probes.extend(knots.iter().map(|k| k * (1.0 - 1e-15)));
            for k in 0..20000 {
                probes.push(hi * (k as f64 / 20000.0).powi(3));
            }
            for x in probes.into_iter().filter(|x| *x >= 0.0 && *x <= hi) {
                let want = crate::catmull_rom::find_interval(n, |i| knots[i] <= x);
                assert_eq!(index.interval(x), want, "x {x}");
            }
        }
        assert!(KnotIndex::new(&[0.0, 0.0, 1.0]).is_none());
        assert!(KnotIndex::new(&[1.0]).is_none());
        assert!(KnotIndex::new(&[0.0, 1.0, f64::NAN]).is_none());
    }
}

/// Implements [`crate::Bssrdf`] for a tabulated model, once for all of them (pbrt 3rd ed.'s
/// `TabulatedBSSRDF`, §11.4.2): `$model` has fields `medium: Medium` and `profile:
/// OpticalProfile` and an inherent `effective_albedo(ch)`, and is of kind `$kind`. R_d, its
/// derivatives, sampling and density are the [`OpticalProfile`]'s; the total diffuse
/// reflectance is the effective albedo; the radius holding a fraction of the energy inverts
/// the same row CDF as `sample_sr` (pbrt uses `Sample_Sr(ch, 0.999)` for its probe radius the
/// same way).
macro_rules! optical_profile_bssrdf {
    ($model:ty, $kind:expr) => {
        impl $crate::Bssrdf for $model {
            fn kind(&self) -> $crate::ModelKind {
                $kind
            }

            fn medium(&self) -> &$crate::Medium {
                &self.medium
            }

            fn rd(&self, ch: usize, r: f64) -> f64 {
                self.profile.rd(ch, r)
            }

            fn rd_rgb(&self, r: f64) -> $crate::Rgb {
                self.profile.rd_rgb(r)
            }

            /// The derivatives of the blended Catmull-Rom spline
            /// ([`crate::spline_row::OpticalProfile::rd_derivatives`]).
            fn rd_derivatives(&self, ch: usize, r: f64) -> (f64, f64, f64) {
                self.profile.rd_derivatives(ch, r.abs())
            }

            fn total_diffuse_reflectance(&self, ch: usize) -> f64 {
                self.effective_albedo(ch)
            }

            fn sample_sr(&self, ch: usize, u: f64) -> f64 {
                self.profile.sample_sr(ch, u)
            }

            fn pdf_sr(&self, ch: usize, r: f64) -> f64 {
                self.profile.pdf_sr(ch, r)
            }

            /// Inverts the interpolated row CDF: the same spline inversion as
            /// [`crate::Bssrdf::sample_sr`] (pbrt uses `Sample_Sr(ch, 0.999)` for its probe
            /// radius the same way).
            fn radius_for_energy(&self, ch: usize, fraction: f64) -> f64 {
                self.profile.sample_sr(ch, fraction)
            }
        }
    };
}
pub(crate) use optical_profile_bssrdf;

/// The radial profile of a tabulated model in optical units, per channel: R_d(r) =
/// σ_t² T(σ_t r)/(2π) from a blended row T, sampled from the row made non-negative, with the
/// exponential σ_t e^{−σ_t r} where a channel has no tabulated mass. Photon beam diffusion and
/// `mc-table` differ only in how they fill the rows; their `rd`, `sample_sr` and `pdf_sr` are
/// these.
#[derive(Clone, Debug)]
pub struct OpticalProfile {
    /// σ_t per channel (the optical scale).
    pub sigma_t: [f64; 3],
    /// The blended rows T per channel (`None`: R_d = 0).
    pub rows: [Option<SplineRow>; 3],
    /// The rows made non-negative, with positive finite total (`None`: exponential fallback).
    pub sampling: [Option<SplineRow>; 3],
}

impl OpticalProfile {
    /// The profile of `rows` at scale `sigma_t`; the sampling rows are the non-negative rows
    /// of positive, finite total.
    pub fn new(sigma_t: [f64; 3], rows: [Option<SplineRow>; 3]) -> OpticalProfile {
        let sampling = std::array::from_fn(|ch| {
            rows[ch]
                .as_ref()
                .map(SplineRow::non_negative)
                .filter(|row| row.total() > 0.0 && row.total().is_finite())
        });
        OpticalProfile {
            sigma_t,
            rows,
            sampling,
        }
    }

    /// R_d(r) of the three channels, each as [`OpticalProfile::rd`] computes it (one call
    /// instead of three through a model's `dyn Bssrdf`, on the disk average's hot path).
    #[inline]
    pub fn rd_rgb(&self, r: f64) -> crate::Rgb {
        [self.rd(0, r), self.rd(1, r), self.rd(2, r)]
    }

    /// R_d(r) of channel `ch`: finite and ≥ 0, 0 for r < 0 or not finite.
    #[inline]
    pub fn rd(&self, ch: usize, r: f64) -> f64 {
        if !(r >= 0.0) || !r.is_finite() {
            return 0.0;
        }
        let st = self.sigma_t[ch];
        let Some(row) = &self.rows[ch] else {
            return 0.0;
        };
        let v = row.eval_over_x(r * st) * (st * st / (2.0 * std::f64::consts::PI));
        if v.is_finite() { v.max(0.0) } else { 0.0 }
    }

    /// (R_d, R_d′, R_d″) of channel `ch` at r: the row's
    /// [`SplineRow::eval_over_x_derivatives`] at x = σ_t r scaled by σ_t²/(2π), σ_t³/(2π),
    /// σ_t⁴/(2π); (0, 0, 0) wherever [`OpticalProfile::rd`] is 0 (its clamp at 0 included).
    pub fn rd_derivatives(&self, ch: usize, r: f64) -> (f64, f64, f64) {
        let v = self.rd(ch, r);
        if !(v > 0.0) {
            return (0.0, 0.0, 0.0);
        }
        let st = self.sigma_t[ch];
        let Some(row) = &self.rows[ch] else {
            return (0.0, 0.0, 0.0);
        };
        let (_, g1, g2) = row.eval_over_x_derivatives(r * st);
        let k = st * st / (2.0 * std::f64::consts::PI);
        (
            v,
            crate::finite_or_zero(g1 * k * st),
            crate::finite_or_zero(g2 * k * st * st),
        )
    }

    /// The radius of quantile `u` of channel `ch`'s sampling distribution (finite, ≥ 0).
    pub fn sample_sr(&self, ch: usize, u: f64) -> f64 {
        let u = if u.is_finite() {
            u.clamp(0.0, 1.0 - f64::EPSILON)
        } else {
            0.0
        };
        let st = self.sigma_t[ch];
        let r = match &self.sampling[ch] {
            None => -(-u).ln_1p() / st,
            Some(row) => row.sample(u).unwrap_or(0.0) / st,
        };
        if r.is_finite() { r.max(0.0) } else { 0.0 }
    }

    /// The density of [`OpticalProfile::sample_sr`] at r (finite, ≥ 0).
    pub fn pdf_sr(&self, ch: usize, r: f64) -> f64 {
        if !(r >= 0.0) || !r.is_finite() {
            return 0.0;
        }
        let st = self.sigma_t[ch];
        let v = match &self.sampling[ch] {
            None => st * (-st * r).exp(),
            Some(row) => row.eval(r * st).max(0.0) * st / row.total(),
        };
        if v.is_finite() { v } else { 0.0 }
    }
}
