//! Importance sampling of radial profiles: r distributed as 2πr R_d(r) / R_total.
//!
//! Two tools, for the two kinds of model:
//! - [`invert_tail`]: models whose tail mass T(r) = ∫_r^∞ 2πr' R_d(r') dr' has a closed form
//!   (standard and better dipole) sample exactly by solving T(r) = (1 − u) T(0) with a
//!   safeguarded Newton iteration; their pdf is the model itself.
//! - [`RadialTable`]: any other profile is tabulated on a geometric radius grid; samples are
//!   drawn from the piecewise-linear interpolant of 2πr R_d(r), and [`RadialTable::pdf`] returns
//!   exactly that interpolant's density, so sampling and pdf always agree.

use crate::quadrature::integrate;

/// Solves `tail(r) = target` for r ≥ 0, where `tail` is a non-increasing function with
/// derivative `-density(r)` (density = 2πr R_d(r) ≥ 0) and `scale` is the profile's length
/// scale. Uses bracketing plus Newton steps, falling back to bisection; relative accuracy
/// ~1e-13. Returns 0 when `target >= tail(0)` and the largest bracket when the target is below
/// what the tail resolves.
pub fn invert_tail(
    tail: &impl Fn(f64) -> f64,
    density: &impl Fn(f64) -> f64,
    target: f64,
    scale: f64,
) -> f64 {
    let scale = if scale > 0.0 && scale.is_finite() {
        scale
    } else {
        1.0
    };
    if !(target < tail(0.0)) {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0f64, scale);
    let mut steps = 0;
    while tail(hi) > target {
        lo = hi;
        hi *= 4.0;
        steps += 1;
        if steps > 60 {
            return hi;
        }
    }
    let mut r = 0.5 * (lo + hi);
    for _ in 0..200 {
        let f = tail(r) - target;
        if f > 0.0 {
            lo = r;
        } else {
            hi = r;
        }
        if hi - lo <= 1e-14 * hi {
            break;
        }
        let d = density(r);
        let newton = if d > 0.0 { r + f / d } else { f64::NAN };
        r = if newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
    }
    r.clamp(lo, hi)
}

/// A tabulated radial distribution for one channel: a geometric grid of radii with the values
/// of g(r) = 2πr R_d(r), its piecewise-linear CDF for sampling, and the accurate (quadrature)
/// cumulative mass for energy radii.
#[derive(Clone, Debug)]
pub struct RadialTable {
    radii: Vec<f64>,
    density: Vec<f64>,
    /// Cumulative trapezoid mass of the piecewise-linear interpolant, normalised to 1.
    cdf_linear: Vec<f64>,
    /// Cumulative Gauss-Legendre mass of g, not normalised.
    mass: Vec<f64>,
    linear_total: f64,
    /// Fallback scale: when the profile is identically 0, samples are exponential in it.
    scale: f64,
}

impl RadialTable {
    /// Tabulates `rd` (R_d in 1/mm²) for a profile of length scale `scale` (mm; the reduced
    /// mean free path): 48 radii per decade from 1e-6·scale to `r_max` (clamped to
    /// [10·scale, 1e7·scale]), plus r = 0. Each interval's mass uses a 6-point Gauss-Legendre
    /// rule.
    pub fn new(rd: impl Fn(f64) -> f64, scale: f64, r_max: f64) -> Self {
        let scale = if scale > 0.0 && scale.is_finite() {
            scale
        } else {
            1.0
        };
        let r_max = if r_max.is_finite() {
            r_max
        } else {
            1e7 * scale
        }
        .clamp(10.0 * scale, 1e7 * scale);
        let g = |r: f64| {
            let v = 2.0 * std::f64::consts::PI * r * rd(r);
            if v.is_finite() && v > 0.0 { v } else { 0.0 }
        };
        let r_min = 1e-6 * scale;
        let per_decade = 48.0;
        let n = ((r_max / r_min).log10() * per_decade).ceil() as usize + 1;
        let ratio = (r_max / r_min).powf(1.0 / (n - 1) as f64);
        let mut radii = Vec::with_capacity(n + 1);
        radii.push(0.0);
        let mut r = r_min;
        for _ in 0..n {
            radii.push(r);
            r *= ratio;
        }
        let density: Vec<f64> = radii.iter().map(|&r| g(r)).collect();
        let mut cdf_linear = vec![0.0; radii.len()];
        let mut mass = vec![0.0; radii.len()];
        for i in 1..radii.len() {
            let (a, b) = (radii[i - 1], radii[i]);
            cdf_linear[i] = cdf_linear[i - 1] + 0.5 * (density[i - 1] + density[i]) * (b - a);
            mass[i] = mass[i - 1] + integrate(&g, a, b, 6);
        }
        let linear_total = *cdf_linear.last().unwrap_or(&0.0);
        if linear_total > 0.0 {
            for c in &mut cdf_linear {
                *c /= linear_total;
            }
        }
        RadialTable {
            radii,
            density,
            cdf_linear,
            mass,
            linear_total,
            scale,
        }
    }

    /// True when the tabulated profile is identically zero (albedo 0); sampling then falls back
    /// to an exponential distribution in the length scale so that pdfs stay positive.
    pub fn is_zero(&self) -> bool {
        !(self.linear_total > 0.0)
    }

    /// Accurate total mass ∫ 2πr R_d(r) dr over the tabulated range.
    pub fn total(&self) -> f64 {
        *self.mass.last().unwrap_or(&0.0)
    }

    /// Largest tabulated radius; [`RadialTable::pdf`] is 0 beyond it.
    pub fn r_max(&self) -> f64 {
        *self.radii.last().unwrap_or(&0.0)
    }

    /// Samples r from the piecewise-linear interpolant of 2πr R_d(r).
    pub fn sample(&self, u: f64) -> f64 {
        let u = if u.is_finite() {
            u.clamp(0.0, 1.0 - f64::EPSILON)
        } else {
            0.0
        };
        if self.is_zero() {
            return -self.scale * (-u).ln_1p();
        }
        // First index with cdf > u.
        let i = self
            .cdf_linear
            .partition_point(|&c| c <= u)
            .clamp(1, self.radii.len() - 1);
        let (a, b) = (self.radii[i - 1], self.radii[i]);
        let (ga, gb) = (self.density[i - 1], self.density[i]);
        let seg_mass = self.cdf_linear[i] - self.cdf_linear[i - 1];
        if !(seg_mass > 0.0) {
            return a;
        }
        // Fraction of this interval's mass to cover, then solve the quadratic
        // (gb - ga)/2 t² + ga t = frac (ga + gb)/2 for t in [0, 1].
        let frac = ((u - self.cdf_linear[i - 1]) / seg_mass).clamp(0.0, 1.0);
        let target = frac * 0.5 * (ga + gb);
        let slope = gb - ga;
        let t = if slope.abs() <= 1e-12 * (ga + gb) {
            frac
        } else {
            // Stable root of 0.5 slope t² + ga t - target = 0.
            let disc = (ga * ga + 2.0 * slope * target).max(0.0);
            2.0 * target / (ga + disc.sqrt())
        };
        let t = if t.is_finite() {
            t.clamp(0.0, 1.0)
        } else {
            frac
        };
        a + t * (b - a)
    }

    /// Density (per unit radius) of [`RadialTable::sample`] at r.
    pub fn pdf(&self, r: f64) -> f64 {
        if !(r >= 0.0) || !r.is_finite() {
            return 0.0;
        }
        if self.is_zero() {
            return (-r / self.scale).exp() / self.scale;
        }
        if r > self.r_max() {
            return 0.0;
        }
        let i = self
            .radii
            .partition_point(|&x| x <= r)
            .clamp(1, self.radii.len() - 1);
        let (a, b) = (self.radii[i - 1], self.radii[i]);
        let t = if b > a {
            ((r - a) / (b - a)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let g = self.density[i - 1] + t * (self.density[i] - self.density[i - 1]);
        g / self.linear_total
    }

    /// The radius holding `fraction` of the tabulated mass (linear within an interval).
    pub fn radius_for_energy(&self, fraction: f64) -> f64 {
        let total = self.total();
        if !(total > 0.0) {
            return -self.scale * (-fraction.clamp(0.0, 1.0 - f64::EPSILON)).ln_1p();
        }
        let target = fraction.clamp(0.0, 1.0) * total;
        let i = self
            .mass
            .partition_point(|&m| m < target)
            .clamp(1, self.radii.len() - 1);
        let (a, b) = (self.radii[i - 1], self.radii[i]);
        let (ma, mb) = (self.mass[i - 1], self.mass[i]);
        if mb > ma {
            a + (b - a) * ((target - ma) / (mb - ma)).clamp(0.0, 1.0)
        } else {
            a
        }
    }
}

/// Fallback for an identically zero profile (albedo 0): r exponential with mean `scale`, so
/// that samples stay finite with a positive density even though they carry no energy.
pub fn exponential_sample(scale: f64, u: f64) -> f64 {
    let u = if u.is_finite() {
        u.clamp(0.0, 1.0 - f64::EPSILON)
    } else {
        0.0
    };
    -scale * (-u).ln_1p()
}

/// Density of [`exponential_sample`].
pub fn exponential_pdf(scale: f64, r: f64) -> f64 {
    if !(r >= 0.0) || !r.is_finite() {
        return 0.0;
    }
    (-r / scale).exp() / scale
}

/// A guide table for exact, fast sampling of a [`ClosedFormTail`] profile.
///
/// Built once per channel when the model is built: the tail T and the density g = 2πr R_d at
/// r = 0 and on a geometric grid of 32 radii per decade from 10⁻⁶ of the length scale until
/// T(r) < 10⁻¹⁷ T(0) (at most 10⁸ length scales, so ≤ 450 knots and ≤ 450 tail evaluations).
/// [`TailTable::sample`] finds the knot interval holding T(r) = (1 − u) T(0) by bisection over
/// the tabulated tails, guesses r by cubic Hermite interpolation of the inverse r(T) (whose
/// slopes −1/g are known at the knots; √ of the mass fraction in the first interval, where
/// g ∝ r), then polishes with safeguarded Newton steps on the closed-form tail inside that
/// bracket. The guess is typically within 10⁻⁶ relative, so one Newton step usually ends the
/// iteration (a step smaller than 10⁻⁷ r leaves an error of order its square); the result
/// solves the same equation as [`invert_tail`] to ~10⁻¹² relative, so the samples have
/// exactly the density [`ClosedFormTail::pdf`] (tested against [`invert_tail`] and by KS
/// tests).
#[derive(Clone, Debug, Default)]
pub struct TailTable {
    radii: Vec<f64>,
    tails: Vec<f64>,
    density: Vec<f64>,
}

impl TailTable {
    /// Tabulates `profile`'s tail and density (see [`TailTable`]); empty when the profile is
    /// identically zero.
    pub fn new(profile: &impl ClosedFormTail) -> Self {
        let total = profile.total();
        if !(total > 0.0) || !total.is_finite() {
            return TailTable::default();
        }
        let scale = {
            let s = profile.scale();
            if s > 0.0 && s.is_finite() { s } else { 1.0 }
        };
        let ratio = 10f64.powf(1.0 / 32.0);
        let t0 = profile.tail(0.0);
        let mut radii = vec![0.0];
        let mut tails = vec![t0];
        let mut density = vec![0.0];
        let mut r = 1e-6 * scale;
        while r <= 1e8 * scale {
            let (t, g) = profile.tail_and_density(r);
            radii.push(r);
            tails.push(t);
            density.push(g);
            if !(t >= 1e-17 * t0) {
                break;
            }
            r *= ratio;
        }
        TailTable {
            radii,
            tails,
            density,
        }
    }

    /// Number of tabulated radii (0 for an identically zero profile).
    pub fn len(&self) -> usize {
        self.radii.len()
    }

    /// True when nothing is tabulated (identically zero profile).
    pub fn is_empty(&self) -> bool {
        self.radii.is_empty()
    }

    /// r with T(r) = (1 − u) T(0), i.e. density g(r)/T(0): the same result as
    /// [`ClosedFormTail::sample`] (to ~10⁻¹² relative), at the cost of a bisection over the
    /// table and usually one or two closed-form evaluations.
    pub fn sample(&self, profile: &impl ClosedFormTail, u: f64) -> f64 {
        let total = profile.total();
        if self.radii.len() < 2 || !(total > 0.0) {
            return profile.sample(u);
        }
        let u = if u.is_finite() {
            u.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let target = (1.0 - u) * total;
        let n = self.radii.len();
        if !(target < self.tails[0]) {
            return 0.0;
        }
        if !(target >= self.tails[n - 1]) {
            // Beyond the table (a fraction below 10⁻¹⁷ of the draws): the general solver.
            return profile.sample(u);
        }
        // First knot whose tail is at or below the target: T(r_{k−1}) > target ≥ T(r_k).
        let k = self.tails.partition_point(|&t| t > target).clamp(1, n - 1);
        let (mut lo, mut hi) = (self.radii[k - 1], self.radii[k]);
        let (ta, tb) = (self.tails[k - 1], self.tails[k]);
        let span = ta - tb;
        let s = if span > 0.0 {
            ((ta - target) / span).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let (ga, gb) = (self.density[k - 1], self.density[k]);
        let width = hi - lo;
        let guess = if k == 1 || !(ga > 0.0) || !(gb > 0.0) {
            // Mass ∝ r² near r = 0.
            if k == 1 {
                hi * s.sqrt()
            } else {
                lo + s * width
            }
        } else {
            // Cubic Hermite in s of r(T), slopes dr/ds = span / g at the two ends.
            let (ma, mb) = (span / ga, span / gb);
            let (s2, s3) = (s * s, s * s * s);
            (2.0 * s3 - 3.0 * s2 + 1.0) * lo
                + (s3 - 2.0 * s2 + s) * ma
                + (-2.0 * s3 + 3.0 * s2) * hi
                + (s3 - s2) * mb
        };
        let mut r = if guess > lo && guess < hi {
            guess
        } else {
            lo + s * width
        };
        for _ in 0..60 {
            let (t, g) = profile.tail_and_density(r);
            let f = t - target;
            if f > 0.0 {
                lo = r;
            } else if f < 0.0 {
                hi = r;
            } else {
                return r;
            }
            let step = f / g;
            let next = r + step;
            let next = if next > lo && next < hi && step.is_finite() {
                next
            } else {
                0.5 * (lo + hi)
            };
            if (next - r).abs() <= 1e-7 * next || hi - lo <= 1e-15 * hi {
                return next;
            }
            r = next;
        }
        r
    }
}

/// √(r² + z²): the plain formula (faster than `hypot`, which is a library call) where the
/// squares can neither overflow nor lose precision to subnormals, `hypot` otherwise (NaN in,
/// NaN out). Within 2ε relative of `hypot` (unit test below).
#[inline]
pub fn distance(r: f64, z: f64) -> f64 {
    let big = r.abs().max(z.abs());
    if big < 1e150 && big > 1e-150 {
        (r * r + z * z).sqrt()
    } else {
        r.hypot(z)
    }
}

/// A radial profile whose tail mass T(r) = ∫_r^∞ 2πr' R_d(r') dr' has a closed form (the
/// standard and better dipole). Implementors give T, the density 2πr R_d(r) and a length
/// scale; exact sampling, pdf and energy radii follow from [`invert_tail`], with the
/// exponential fallback when the profile is identically zero.
pub trait ClosedFormTail {
    /// T(r); T(0) is the total diffuse reflectance.
    fn tail(&self, r: f64) -> f64;
    /// 2πr R_d(r).
    fn density(&self, r: f64) -> f64;
    /// (T(r), 2πr R_d(r)) together; implementors override it to share the distances and
    /// exponentials of the two.
    fn tail_and_density(&self, r: f64) -> (f64, f64) {
        (self.tail(r), self.density(r))
    }
    /// The total T(0), clamped to [0, 1].
    fn total(&self) -> f64;
    /// Length scale of the profile (mm): the reduced mean free path.
    fn scale(&self) -> f64;

    /// r with density 2πr R_d(r)/T(0), by solving T(r) = (1 − u) T(0).
    fn sample(&self, u: f64) -> f64 {
        if !(self.total() > 0.0) {
            return exponential_sample(self.scale(), u);
        }
        let u = if u.is_finite() {
            u.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let target = (1.0 - u) * self.total();
        invert_tail(
            &|r| self.tail(r),
            &|r| self.density(r),
            target,
            self.scale(),
        )
    }

    /// Density of [`ClosedFormTail::sample`] per unit radius.
    fn pdf(&self, r: f64) -> f64 {
        if !(self.total() > 0.0) {
            return exponential_pdf(self.scale(), r);
        }
        if !(r >= 0.0) || !r.is_finite() {
            return 0.0;
        }
        self.density(r) / self.total()
    }

    /// The radius holding `fraction` of the total.
    fn radius_for_energy(&self, fraction: f64) -> f64 {
        self.sample(fraction.clamp(0.0, 1.0 - 1e-15))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distance_is_hypot_within_rounding_everywhere() {
        // Over 600 orders of magnitude, either sign, and both branches (the plain formula
        // and `hypot` past 1e±150): within 2ε relative of libm's `hypot` (the plain formula
        // rounds three times), and the special values as `hypot` gives them.
        let mags = (-320..=307).step_by(7).map(|e| 1.7 * 10f64.powi(e));
        let values: Vec<f64> = [0.0, 1.0, 3.0, f64::MAX, f64::MIN_POSITIVE]
            .into_iter()
            .chain(mags)
            .flat_map(|v| [v, -v])
            .collect();
        for &r in &values {
            for &z in &values {
                let (d, h) = (distance(r, z), r.hypot(z));
                // (Both overflow where the distance exceeds f64::MAX.)
                assert_eq!(
                    d.is_finite(),
                    h.is_finite(),
                    "distance({r:e}, {z:e}) = {d:e}"
                );
                assert!(
                    d >= 0.0 && (d == h || (d - h).abs() <= 2.0 * f64::EPSILON * h),
                    "distance({r:e}, {z:e}) = {d:e}, hypot {h:e}"
                );
            }
        }
        assert!(distance(f64::NAN, 1.0).is_nan() && distance(1.0, f64::NAN).is_nan());
        assert_eq!(distance(f64::INFINITY, 1.0), f64::INFINITY);
        assert_eq!(distance(-3.0, 4.0), 5.0);
    }

    #[test]
    fn table_of_exponential_samples_and_integrates() {
        // R_d ∝ e^{-r}/r gives 2πr R_d ∝ e^{-r}: CDF 1 - e^{-r}.
        let t = RadialTable::new(
            |r: f64| (-r).exp() / (2.0 * std::f64::consts::PI * r),
            1.0,
            60.0,
        );
        assert!((t.total() - 1.0).abs() < 1e-9, "{}", t.total());
        for u in [0.01, 0.3, 0.5, 0.9, 0.999] {
            let r = t.sample(u);
            let exact = -(1.0f64 - u).ln();
            assert!(
                (r - exact).abs() < 2e-3 * exact.max(1.0),
                "u {u}: {r} vs {exact}"
            );
        }
        // The pdf is piecewise linear between the table radii: integrate it interval by interval
        // (Gauss-Legendre is exact there), up to the last radius and a little beyond.
        let mut integral = 0.0;
        for w in t.radii.windows(2) {
            integral += crate::quadrature::integrate(&|r: f64| t.pdf(r), w[0], w[1], 4);
        }
        integral += crate::quadrature::integrate(&|r: f64| t.pdf(r), t.r_max(), 2.0 * t.r_max(), 4);
        assert!((integral - 1.0).abs() < 1e-6, "{integral}");
        assert!((t.radius_for_energy(0.5) - 2f64.ln()).abs() < 1e-4);
    }

    /// T(r) = A z/√(r² + z²) e^{−σ(√(r² + z²) − z)}: one dipole source term, total A.
    struct OneSource {
        a: f64,
        z: f64,
        sigma: f64,
    }

    impl ClosedFormTail for OneSource {
        fn tail(&self, r: f64) -> f64 {
            let d = r.hypot(self.z);
            self.a * self.z / d * (-self.sigma * (d - self.z)).exp()
        }
        fn density(&self, r: f64) -> f64 {
            let d = r.hypot(self.z);
            let s = self.sigma * d;
            self.a * self.z * r * (1.0 + s) * (-self.sigma * (d - self.z)).exp() / (d * d * d)
        }
        fn total(&self) -> f64 {
            self.a
        }
        fn scale(&self) -> f64 {
            self.z
        }
    }

    #[test]
    fn tail_table_sampling_equals_the_closed_form_inverse() {
        // σ = 0 has the closed-form inverse r = z √(1/(1 − u)² − 1); σ > 0 is compared with
        // the bracketed Newton solver `invert_tail`.
        for (z, sigma) in [
            (1e-3, 0.0),
            (1.0, 0.0),
            (2.0, 0.1),
            (0.5, 30.0),
            (1e4, 1e-2),
        ] {
            let p = OneSource { a: 0.7, z, sigma };
            let table = TailTable::new(&p);
            assert!(table.len() > 100 && table.len() < 460, "{}", table.len());
            for k in 0..=1000 {
                let u = k as f64 / 1000.0 * (1.0 - 1e-9);
                let r = table.sample(&p, u);
                let want = if sigma == 0.0 {
                    z * (1.0 / ((1.0 - u) * (1.0 - u)) - 1.0).sqrt()
                } else {
                    p.sample(u)
                };
                assert!(
                    (r - want).abs() <= 1e-10 * want + 1e-300,
                    "z {z} σ {sigma} u {u}: {r} vs {want}"
                );
            }
        }
        // An identically zero profile: the exponential fallback, like `ClosedFormTail`.
        let zero = OneSource {
            a: 0.0,
            z: 1.0,
            sigma: 1.0,
        };
        let table = TailTable::new(&zero);
        assert!(table.is_empty());
        assert_eq!(table.sample(&zero, 0.5), exponential_sample(1.0, 0.5));
    }

    #[test]
    fn invert_tail_solves_exponential() {
        let tail = |r: f64| (-r).exp();
        let dens = |r: f64| (-r).exp();
        // Solving on the tail loses relative precision in r for u below ~1e-8 (the tail is
        // 1 - O(u) there); above that the answer is exact to the solver tolerance.
        for u in [1e-6f64, 0.1, 0.5, 0.99, 1.0 - 1e-12] {
            let target = (-u).ln_1p().exp();
            let r = invert_tail(&tail, &dens, target, 1.0);
            let exact = -(-u).ln_1p();
            assert!((r - exact).abs() <= 1e-9 * exact, "u {u}: {r} vs {exact}");
        }
    }
}
