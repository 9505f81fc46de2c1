//! Error and cost measures of a model profile against the binned Monte Carlo reference.
//!
//! Monte Carlo bins hold *area averages* of R_d over annuli, so a model is compared through
//! its own area averages over the same annuli ([`bin_averages`]), not its values at the bin
//! centres (which differ by the profile's curvature over a bin).

use sss_bssrdf::quadrature::integrate_radial_range;
use std::hint::black_box;
use std::time::Instant;

/// Relative standard error below which a Monte Carlo bin counts for [`max_rel_error`].
pub const MAX_REL_SE: f64 = 0.05;

/// Area average of `rd` over each annulus `[edges[i], edges[i+1]]`:
/// ∫ 2πr rd(r) dr / (π(r₁² − r₀²)), by Gauss-Legendre panels geometric in r from 1e-8·`scale`
/// (so a peak or an integrable singularity at r = 0 is resolved). `scale` is the profile's
/// length scale (e.g. the reduced mean free path).
pub fn bin_averages(edges: &[f64], rd: &dyn Fn(f64) -> f64, scale: f64) -> Vec<f64> {
    edges
        .windows(2)
        .map(|e| {
            let area = std::f64::consts::PI * (e[1] * e[1] - e[0] * e[0]);
            let v = integrate_radial_range(&rd, scale, e[0], e[1]) / area;
            if v.is_finite() { v } else { 0.0 }
        })
        .collect()
}

/// Relative L2 error of the energy per bin, A_i·Rd_i (the bins have equal width, so this is
/// the L2 error of 2πr R_d weighted by dr): ‖A(model − mc)‖ / ‖A·mc‖. `None` when the
/// reference is all zero.
pub fn rel_l2_error(areas: &[f64], model: &[f64], mc: &[f64]) -> Option<f64> {
    let (mut num, mut den) = (0.0, 0.0);
    for ((a, m), r) in areas.iter().zip(model).zip(mc) {
        num += (a * (m - r)).powi(2);
        den += (a * r).powi(2);
    }
    (den > 0.0).then(|| (num / den).sqrt())
}

/// Relative error (model − mc)/mc of each bin where the reference is positive.
pub fn rel_errors(model: &[f64], mc: &[f64]) -> Vec<Option<f64>> {
    model
        .iter()
        .zip(mc)
        .map(|(m, r)| (*r > 0.0).then(|| (m - r) / r))
        .collect()
}

/// Largest |model − mc|/mc over the bins whose relative standard error is below
/// [`MAX_REL_SE`]; `None` when no bin is that well resolved.
pub fn max_rel_error(model: &[f64], mc: &[f64], se: &[f64]) -> Option<f64> {
    model
        .iter()
        .zip(mc)
        .zip(se)
        .filter(|((_, r), s)| **r > 0.0 && **s < MAX_REL_SE * **r)
        .map(|((m, r), _)| ((m - r) / r).abs())
        .fold(None, |acc: Option<f64>, e| {
            Some(acc.map_or(e, |a| a.max(e)))
        })
}

/// Wall-clock nanoseconds per call of `f` over `inputs` (cycled), best of three rounds of
/// `calls` calls each (the minimum is the least disturbed by other work on the machine).
pub fn ns_per_call<T>(inputs: &[f64], calls: usize, f: impl Fn(f64) -> T) -> f64 {
    if inputs.is_empty() || calls == 0 {
        return 0.0;
    }
    // Warm up caches and branch predictors.
    for &x in inputs.iter().cycle().take(calls.min(1000)) {
        black_box(f(black_box(x)));
    }
    (0..3)
        .map(|_| {
            let t0 = Instant::now();
            for &x in inputs.iter().cycle().take(calls) {
                black_box(f(black_box(x)));
            }
            t0.elapsed().as_secs_f64() * 1e9 / calls as f64
        })
        .fold(f64::INFINITY, f64::min)
}

/// The mean of the finite values; `None` when there are none.
pub fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// The median of the finite values; `None` when there are none.
pub fn median(values: impl Iterator<Item = f64>) -> Option<f64> {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bin_averages_of_exponential_are_exact() {
        // ∫ 2πr e^{-r} dr over [a, b] = 2π[(a+1)e^{-a} − (b+1)e^{-b}].
        let edges = [0.0, 0.5, 1.0, 4.0];
        let got = bin_averages(&edges, &|r: f64| (-r).exp(), 1.0);
        for (i, g) in got.iter().enumerate() {
            let (a, b) = (edges[i], edges[i + 1]);
            let exact = 2.0 * ((a + 1.0) * (-a).exp() - (b + 1.0) * (-b).exp()) / (b * b - a * a);
            assert!((g - exact).abs() < 1e-12 * exact, "{i}: {g} vs {exact}");
        }
    }

    #[test]
    fn errors() {
        let areas = [1.0, 3.0];
        let mc = [2.0, 1.0];
        assert_eq!(rel_l2_error(&areas, &mc, &mc), Some(0.0));
        let model = [2.0, 2.0];
        let e = rel_l2_error(&areas, &model, &mc).unwrap();
        assert!((e - (9.0f64 / 13.0).sqrt()).abs() < 1e-15);
        assert_eq!(rel_l2_error(&areas, &model, &[0.0, 0.0]), None);
        assert_eq!(rel_errors(&model, &[2.0, 0.0]), vec![Some(0.0), None]);
        // Only the second bin is well resolved.
        assert_eq!(max_rel_error(&model, &mc, &[1.0, 0.01]), Some(1.0));
        assert_eq!(max_rel_error(&model, &mc, &[1.0, 1.0]), None);
    }

    #[test]
    fn timing_is_positive() {
        let ns = ns_per_call(&[1.0, 2.0], 10_000, |x| x.sqrt());
        assert!(ns.is_finite() && ns >= 0.0);
        assert_eq!(ns_per_call(&[], 10, |x| x), 0.0);
    }
}
