//! From one row's tallies to its knot values: the noisy bins near the origin pooled
//! ([`inner_masses`]), the poorly resolved tail regularised ([`tail_masses`]) and replaced by
//! a fitted diffusion far field ([`asymptotic_tail`]), a non-increasing R_d by isotonic
//! regression ([`non_increasing_fit`]), then the histopolation ([`row_nodes`]).

use super::*;
use std::f64::consts::PI;
use std::ops::Range;

/// A tallied bin is resolved when its relative standard error is at most this.
pub const RESOLVED_REL_SE: f64 = 0.2;

/// Resolved bins fitted by the exponential that continues a row's tail.
const TAIL_FIT_BINS: usize = 6;

/// Largest relative standard error of the pooled groups near the origin ([`inner_masses`]).
pub const INNER_REL_SE: f64 = 0.01;

/// The bin masses of one row with the narrow bins near the origin pooled (see
/// [`row_nodes`]).
///
/// The first bins are narrow (5·10⁻⁴ mean free paths at x₁) and their tallies noisy (several
/// % at albedos near 1, whose bands have fewer photons), and the histopolation system, whose
/// first bin is 10 times wider than its second, turns that noise into oscillations of the knot
/// values of 20 % and more. So from bin 0 outward, consecutive bins are pooled into groups
/// whose relative standard error is at most [`INNER_REL_SE`], until a bin is that precise on
/// its own (or the bin of largest mass is reached); each group keeps its tallied mass, spread
/// over its bins by the density interpolated log-linearly between the groups' mean densities.
/// Near the origin 2πx R_d is smooth (single scattering makes it tend to a constant), so this
/// changes the profile only within the noise, below 0.1 mean free paths.
pub fn inner_masses(edges: &[f64], mass: &[f64], se: &[f64]) -> Vec<f64> {
    let bins = mass.len();
    let precise = |m: f64, s2: f64| m > 0.0 && s2.sqrt() <= INNER_REL_SE * m;
    let peak = (0..bins)
        .max_by(|&a, &b| mass[a].total_cmp(&mass[b]))
        .unwrap_or(0);
    let mut groups: Vec<Range<usize>> = Vec::new();
    let mut k = 0;
    while k < peak {
        let (mut m, mut v, mut j) = (0.0, 0.0, k);
        while j < bins && !precise(m, v) {
            m += mass[j];
            v += se[j].powi(2);
            j += 1;
        }
        if !precise(m, v) || j - k == 1 {
            break;
        }
        groups.push(k..j);
        k = j;
    }
    let mut out = mass.to_vec();
    if groups.is_empty() {
        return out;
    }
    // Mean densities at the groups' centres and at the two bins after them (if any).
    let end = groups[groups.len() - 1].end;
    let mut points: Vec<(f64, f64)> = groups
        .iter()
        .map(|g| {
            let (lo, hi) = (edges[g.start], edges[g.end]);
            (
                0.5 * (lo + hi),
                mass[g.clone()].iter().sum::<f64>() / (hi - lo),
            )
        })
        .collect();
    for k in end..(end + 2).min(bins) {
        if mass[k] > 0.0 {
            points.push((
                0.5 * (edges[k] + edges[k + 1]),
                mass[k] / (edges[k + 1] - edges[k]),
            ));
        }
    }
    let log_density_at = |x: f64| -> f64 {
        if points.len() < 2 {
            return points[0].1.ln();
        }
        let j = points
            .partition_point(|p| p.0 <= x)
            .clamp(1, points.len() - 1);
        let ((c0, d0), (c1, d1)) = (points[j - 1], points[j]);
        let t = (x - c0) / (c1 - c0);
        (1.0 - t) * d0.ln() + t * d1.ln()
    };
    for g in &groups {
        let target: f64 = mass[g.clone()].iter().sum();
        let shape: Vec<f64> = g
            .clone()
            .map(|k| {
                let c = 0.5 * (edges[k] + edges[k + 1]);
                log_density_at(c).exp() * (edges[k + 1] - edges[k])
            })
            .collect();
        let total: f64 = shape.iter().sum();
        for (k, v) in g.clone().zip(&shape) {
            let m = target * v / total;
            out[k] = if m.is_finite() { m.max(0.0) } else { mass[k] };
        }
    }
    out
}

/// The bin masses of one row with its tail beyond the resolved bins regularised (see
/// [`row_nodes`]); also returns the last resolved bin K.
///
/// - K: outward from the bin of largest mass, the last bin before the first one whose
///   relative standard error exceeds [`RESOLVED_REL_SE`] (the small bins near the origin may
///   be noisier than the tail's start, and are kept as tallied).
/// - Beyond K, consecutive bins are pooled into groups just large enough to be resolved; each
///   group keeps its tallied mass, spread over its bins by the density interpolated
///   log-linearly between the groups' (and the last resolved bins') mean densities.
/// - What cannot be pooled into a resolved group (the last bins, reached by too few photons)
///   keeps its total tallied mass, spread over its bins like the exponential e^{−κx} fitted
///   to the last resolved bins and groups (weights (mass/se)², the bin averages'
///   sinh(κw/2)/(κw/2) factor accounted for), or like 1/x² if that fit does not decay.
pub fn tail_masses(edges: &[f64], mass: &[f64], se: &[f64]) -> (Vec<f64>, usize) {
    let bins = mass.len();
    let resolved = |m: f64, s2: f64| m > 0.0 && s2.sqrt() <= RESOLVED_REL_SE * m;
    let peak = (1..bins)
        .max_by(|&a, &b| mass[a].total_cmp(&mass[b]))
        .unwrap_or(0);
    let last = if peak >= 1 && resolved(mass[peak], se[peak].powi(2)) {
        (peak..bins)
            .take_while(|&k| resolved(mass[k], se[k].powi(2)))
            .last()
            .unwrap_or(peak)
    } else {
        0
    };
    let mut out = mass.to_vec();
    // Nothing resolved (an empty row), or nothing beyond K: the tally as it is.
    if last == 0 || last + 1 >= bins {
        return (out, last);
    }
    // Pool the bins beyond K into resolved groups.
    let mut groups: Vec<Range<usize>> = Vec::new();
    let mut k = last + 1;
    let mut rest = bins;
    while k < bins {
        let (mut m, mut v, mut j) = (0.0, 0.0, k);
        while j < bins && !resolved(m, v) {
            m += mass[j];
            v += se[j].powi(2);
            j += 1;
        }
        if resolved(m, v) {
            groups.push(k..j);
            k = j;
        } else {
            rest = k;
            break;
        }
    }
    // Points (centre, mean density, weight, lo, hi): the last resolved bins, then the groups.
    struct Point {
        lo: f64,
        hi: f64,
        density: f64,
        weight: f64,
    }
    let first = last.saturating_sub(TAIL_FIT_BINS - 1).max(1);
    let mut points: Vec<Point> = (first..=last)
        .map(|k| Point {
            lo: edges[k],
            hi: edges[k + 1],
            density: mass[k] / (edges[k + 1] - edges[k]),
            weight: if se[k] > 0.0 {
                (mass[k] / se[k]).powi(2)
            } else {
                1.0
            },
        })
        .collect();
    for g in &groups {
        let m: f64 = mass[g.clone()].iter().sum();
        let v: f64 = se[g.clone()].iter().map(|s| s * s).sum();
        let (lo, hi) = (edges[g.start], edges[g.end]);
        points.push(Point {
            lo,
            hi,
            density: m / (hi - lo),
            weight: if v > 0.0 { m * m / v } else { 1.0 },
        });
    }
    // Groups: log-linear density between neighbouring points' centres, rescaled to the
    // group's tallied mass.
    let centre = |p: &Point| 0.5 * (p.lo + p.hi);
    let log_density_at = |x: f64| -> f64 {
        if points.len() < 2 {
            return points.first().map_or(0.0, |p| p.density.ln());
        }
        let j = points
            .partition_point(|p| centre(p) <= x)
            .clamp(1, points.len() - 1);
        let (a, b) = (&points[j - 1], &points[j]);
        let slope = (b.density.ln() - a.density.ln()) / (centre(b) - centre(a));
        if x > centre(b) {
            // Beyond the last point the density may only fall (a noisy last group must not
            // pile its mass up at its far end).
            return b.density.ln() + slope.min(0.0) * (x - centre(b));
        }
        a.density.ln() + slope * (x - centre(a))
    };
    for g in &groups {
        let target: f64 = mass[g.clone()].iter().sum();
        let shape: Vec<f64> = g
            .clone()
            .map(|k| {
                let c = 0.5 * (edges[k] + edges[k + 1]);
                log_density_at(c).exp() * (edges[k + 1] - edges[k])
            })
            .collect();
        let total: f64 = shape.iter().sum();
        for (k, v) in g.clone().zip(&shape) {
            out[k] = if total > 0.0 && total.is_finite() {
                target * v / total
            } else {
                target / g.len() as f64
            };
        }
    }
    if rest >= bins {
        return (out, last);
    }
    // The unresolved rest keeps its tallied mass (noisy, but without the bias of dropping
    // it: at albedo 1 it is ≈ 1 % of the light), spread like the exponential fitted to the
    // last points, or like 1/x² (the albedo-1 tail of 2πx R_d) if that fit does not decay.
    let rest_mass: f64 = mass[rest..].iter().sum();
    let fit_from = points.len().saturating_sub(TAIL_FIT_BINS);
    let fit = &points[fit_from..];
    let (kappa, _) = fit_exponential(fit.iter().map(|p| (p.lo, p.hi, p.density, p.weight)));
    let x0 = edges[rest];
    let shape: Vec<f64> = (rest..bins)
        .map(|k| {
            let (lo, hi) = (edges[k], edges[k + 1]);
            if kappa > 1e-3 {
                // ∫ e^{−κ(x − x₀)} dx over the bin.
                (-kappa * (lo - x0)).exp() * (-(-kappa * (hi - lo)).exp_m1()) / kappa
            } else {
                1.0 / lo - 1.0 / hi
            }
        })
        .collect();
    let total: f64 = shape.iter().sum();
    for (k, v) in (rest..bins).zip(&shape) {
        let m = rest_mass * v / total;
        out[k] = if m.is_finite() { m.max(0.0) } else { 0.0 };
    }
    (out, last)
}

/// Weighted least squares of ln(mean density) = a − κc + ln(sinh(κw/2)/(κw/2)) over intervals
/// (lo, hi, mean density, weight) of width w and centre c: the exponential e^{a − κx} whose
/// interval means match. Returns (κ, a); κ is NaN when fewer than two intervals are given.
fn fit_exponential(points: impl Iterator<Item = (f64, f64, f64, f64)> + Clone) -> (f64, f64) {
    let solve = |kappa: f64| -> Option<(f64, f64)> {
        let (mut sw, mut sx, mut sy, mut sxx, mut sxy, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0, 0);
        for (lo, hi, d, w) in points.clone() {
            let c = 0.5 * (lo + hi);
            let h = 0.5 * kappa * (hi - lo);
            let factor = if h > 1e-12 { (h.sinh() / h).ln() } else { 0.0 };
            let y = d.ln() - factor;
            if !(y.is_finite() && w > 0.0) {
                continue;
            }
            sw += w;
            sx += w * c;
            sy += w * y;
            sxx += w * c * c;
            sxy += w * c * y;
            n += 1;
        }
        let det = sw * sxx - sx * sx;
        if n < 2 || !(det > 0.0) {
            return None;
        }
        let k = -(sw * sxy - sx * sy) / det;
        Some((k, (sy + k * sx) / sw))
    };
    let Some((mut kappa, mut a)) = solve(0.0) else {
        return (f64::NAN, f64::NAN);
    };
    // Fixed-point rounds for the sinh factor (exact at once for equal widths).
    for _ in 0..6 {
        if !(kappa > 1e-3) {
            break;
        }
        match solve(kappa) {
            Some((k, b)) => (kappa, a) = (k, b),
            None => break,
        }
    }
    (kappa, a)
}

/// Past the start of the far-field fit, the tallies give way to the fit from the first bin
/// whose relative standard error exceeds this ([`asymptotic_tail`]).
pub const ASYMPTOTE_SWITCH_REL_SE: f64 = 0.01;

/// ∫ 2πx R dx over [lo, hi] for R(x) = e^{−κd}(1 + κd)/d³, d = √(x² + z²): the far field of
/// one diffusion pole at depth z (a point source's flux gradient through the surface), whose
/// integral is closed: d(−e^{−κd}/d)/dd = e^{−κd}(1 + κd)/d² and x dx = d dd.
fn pole_mass(kappa: f64, z: f64, lo: f64, hi: f64) -> f64 {
    let e = |x: f64| {
        let d = (x * x + z * z).sqrt();
        if d > 0.0 { (-kappa * d).exp() / d } else { 0.0 }
    };
    2.0 * PI * (e(lo) - e(hi))
}

/// The amplitude a and χ² of the weighted least-squares fit of a·pole_mass(κ, z) to the bins
/// (lo, hi, mass, 1/se²).
fn pole_fit(kappa: f64, z: f64, bins: &[(f64, f64, f64, f64)]) -> (f64, f64) {
    let (mut sff, mut sfm) = (0.0, 0.0);
    let shapes: Vec<f64> = bins
        .iter()
        .map(|&(lo, hi, m, w)| {
            let f = pole_mass(kappa, z, lo, hi);
            sff += w * f * f;
            sfm += w * f * m;
            f
        })
        .collect();
    if !(sff > 0.0) {
        return (0.0, f64::INFINITY);
    }
    let a = sfm / sff;
    let chi2 = bins
        .iter()
        .zip(&shapes)
        .map(|(&(_, _, m, w), f)| w * (a * f - m).powi(2))
        .sum();
    (a, chi2)
}

/// Where the far-field fit may start (optical radii, mean free paths): the first at which
/// the fit is consistent with the tallies (see [`asymptotic_tail`]).
pub const ASYMPTOTE_STARTS: [f64; 5] = [3.0, 4.5, 6.0, 8.0, 10.0];

/// Optical radii at which the far-field fit may stop replacing the tallies
/// ([`asymptotic_tail`]), tried from the farthest.
pub const ASYMPTOTE_ENDS: [f64; 4] = [64.0, 32.0, 20.0, 16.0];

/// A far-field fit is accepted when its χ² per degree of freedom is at most this. The
/// tallies' errors far out are heavier-tailed than normal (few photons of large weight), so
/// good fits run at 1–3 (ketchup's rows near albedo 0.75: 1.9 from 3 mean free paths,
/// κ = 0.745 against the transport value 0.78); a wrong shape gives far more.
pub const ASYMPTOTE_MAX_CHI2: f64 = 4.0;

/// The (κ, z, a) of the far field a·pole_mass(κ, z) fitted to `fit` (lo, hi, mass, 1/se²)
/// by weighted least squares (a in closed form; κ in [0, 2], z in [0, 8] on a grid, then
/// boxes shrinking around the best), and its χ².
fn fit_pole(fit: &[(f64, f64, f64, f64)]) -> (f64, f64, f64, f64) {
    let (mut kappa, mut z, mut step_k, mut step_z) = (1.0, 4.0, 0.1, 0.4);
    let mut best = (f64::INFINITY, kappa, z);
    for round in 0..6 {
        let n: i32 = if round == 0 { 10 } else { 4 };
        for i in -n..=n {
            for j in -n..=n {
                let (k, zz) = (kappa + i as f64 * step_k, z + j as f64 * step_z);
                if !(0.0..=2.0).contains(&k) || !(0.0..=8.0).contains(&zz) {
                    continue;
                }
                let (_, chi2) = pole_fit(k, zz, fit);
                if chi2 < best.0 {
                    best = (chi2, k, zz);
                }
            }
        }
        (kappa, z) = (best.1, best.2);
        step_k *= 0.3;
        step_z *= 0.3;
    }
    let (a, chi2) = pole_fit(kappa, z, fit);
    (kappa, z, a, chi2)
}

/// The masses of one row with its noisy far tail replaced by the fitted diffusion far field
/// (see [`row_nodes`]); `last` is the last resolved bin of [`tail_masses`].
///
/// - The fit: a·pole_mass(κ, z) (R_d ∝ e^{−κd}(1 + κd)/d³, d = √(x² + z²)) by weighted
///   least squares over the resolved bins from the first start of [`ASYMPTOTE_STARTS`] at
///   which χ²/(n − 3) ≤ [`ASYMPTOTE_MAX_CHI2`] (at least 4 bins); no such start: the row is
///   kept as it is.
/// - The tallies give way to the fit from the first bin past that start whose relative
///   standard error exceeds [`ASYMPTOTE_SWITCH_REL_SE`], up to the table's end, or, when the
///   fit's light over the replaced bins would differ from the tallied light by more than 3
///   standard errors, up to the last resolved bin `last` or the first of the radii
///   [`ASYMPTOTE_ENDS`] at which it agrees (near albedo 1 a per cent of the light escapes
///   beyond 16 mean free paths, and a fitted κ slightly above 0 would lose it); none: the
///   row is kept as it is. The replaced bins are rescaled to their tallied light (a change
///   within 3 standard errors of it), so the row's total stays the tallied one.
pub fn asymptotic_tail(edges: &[f64], mass: &[f64], se: &[f64], last: usize) -> Vec<f64> {
    let mut out = mass.to_vec();
    let bins = mass.len();
    let last = last.min(bins.saturating_sub(1));
    let mut accepted = None;
    for start in ASYMPTOTE_STARTS {
        let fit: Vec<(f64, f64, f64, f64)> = (0..=last)
            .filter(|&k| edges[k] >= start && mass[k] > 0.0 && se[k] > 0.0)
            .map(|k| (edges[k], edges[k + 1], mass[k], se[k].powi(-2)))
            .collect();
        if fit.len() < 4 {
            break;
        }
        let (kappa, z, a, chi2) = fit_pole(&fit);
        if a > 0.0 && a.is_finite() && chi2 <= ASYMPTOTE_MAX_CHI2 * (fit.len() - 3) as f64 {
            accepted = Some((start, kappa, z, a));
            break;
        }
    }
    let Some((start, kappa, z, a)) = accepted else {
        return out;
    };
    let fitted = |k: usize| {
        let m = a * pole_mass(kappa, z, edges[k], edges[k + 1]);
        if m.is_finite() { m.max(0.0) } else { 0.0 }
    };
    let Some(switch) = (0..bins).find(|&k| {
        edges[k] >= start && !(mass[k] > 0.0 && se[k] <= ASYMPTOTE_SWITCH_REL_SE * mass[k])
    }) else {
        return out;
    };
    // The replaced bins [switch, end): the farthest end among the table's end, the last
    // resolved bin and the radii of ASYMPTOTE_ENDS at which the fit's light over the replaced
    // bins agrees with the tallied light within 3 standard errors.
    let ends = std::iter::once(bins)
        .chain(std::iter::once(last + 1))
        .chain(
            ASYMPTOTE_ENDS
                .iter()
                .map(|&x| edges.partition_point(|&e| e < x).min(bins)),
        );
    for end in ends {
        if end <= switch {
            continue;
        }
        let tallied: f64 = mass[switch..end].iter().sum();
        let var: f64 = se[switch..end].iter().map(|s| s * s).sum();
        let replaced: Vec<f64> = (switch..end).map(fitted).collect();
        let light: f64 = replaced.iter().sum();
        if light > 0.0 && (light - tallied).abs() <= 3.0 * var.sqrt() {
            // Rescaled to the tallied light of the replaced bins: no light gained or lost.
            let scale = tallied / light;
            for (o, v) in out[switch..end].iter_mut().zip(&replaced) {
                let m = v * scale;
                *o = if m.is_finite() { m.max(0.0) } else { 0.0 };
            }
            break;
        }
    }
    out
}

/// Weighted isotonic regression: the non-increasing sequence closest to `y` in the weighted
/// least-squares sense, by pooling adjacent violators (Ayer, Brunk, Ewing, Reid, Silverman,
/// *An empirical distribution function for sampling with incomplete information*, Ann. Math.
/// Statist. 26(4), 1955; Barlow et al., *Statistical Inference under Order Restrictions*,
/// 1972).
pub fn non_increasing_fit(y: &[f64], w: &[f64]) -> Vec<f64> {
    // Blocks of (mean, weight, count).
    let mut blocks: Vec<(f64, f64, usize)> = Vec::with_capacity(y.len());
    for (&v, &wt) in y.iter().zip(w) {
        let wt = if wt > 0.0 && wt.is_finite() {
            wt
        } else {
            1e-300
        };
        blocks.push((v, wt, 1));
        while blocks.len() >= 2 {
            let (m1, w1, c1) = blocks[blocks.len() - 1];
            let (m0, w0, c0) = blocks[blocks.len() - 2];
            if m1 <= m0 {
                break;
            }
            blocks.pop();
            let wsum = w0 + w1;
            let last = blocks.len() - 1;
            blocks[last] = ((w0 * m0 + w1 * m1) / wsum, wsum, c0 + c1);
        }
    }
    blocks
        .into_iter()
        .flat_map(|(m, _, c)| std::iter::repeat_n(m, c))
        .collect()
}

/// The bin masses of one row that [`row_nodes`] fits its spline to (steps 1 and 2 there).
pub fn row_masses(knots: &[f64], mass: &[f64], se: &[f64]) -> Vec<f64> {
    let edges = tally_edges(knots);
    let inner = inner_masses(&edges, mass, se);
    let (pooled, last) = tail_masses(&edges, &inner, se);
    let tail = asymptotic_tail(&edges, &pooled, se, last);
    // R_d averaged over each bin's annulus, made non-increasing with the annuli's areas as
    // weights: pooled bins share their total mass, so no light is gained or lost.
    let areas: Vec<f64> = edges
        .windows(2)
        .map(|e| PI * (e[1] * e[1] - e[0] * e[0]))
        .collect();
    let averages: Vec<f64> = tail.iter().zip(&areas).map(|(m, a)| m / a).collect();
    non_increasing_fit(&averages, &areas)
        .iter()
        .zip(&areas)
        .map(|(d, a)| d * a)
        .collect()
}

/// The values of one row's spline at its [`spline_knots`] from the row's tallies (bins of
/// [`tally_edges`]):
/// 1. the narrow bins near the origin are pooled by [`inner_masses`], the tail beyond the
///    resolved bins is regularised by [`tail_masses`] (pooled groups, the unresolved rest
///    spread like the fitted exponential), and the noisy far tail is replaced by the fitted
///    diffusion far field of [`asymptotic_tail`];
/// 2. the bins' R_d averages over their annuli are made non-increasing by isotonic regression
///    with the annuli's areas as weights (mass-conserving: pooled bins share their tallied
///    light), which changes nothing where the tallies are ordered and pools neighbours where
///    noise reverses them;
/// 3. the histopolation system gives the knot values whose spline integrates to every bin;
/// 4. negative values are set to 0, and R_d = T/(2πx) at the knots is made non-increasing by
///    isotonic regression weighted by the light each knot carries (a knot value can overshoot
///    its neighbour a little even when the bin averages are ordered).
pub fn row_nodes(system: &Histopolation, knots: &[f64], mass: &[f64], se: &[f64]) -> Vec<f64> {
    let xs = spline_knots(knots);
    let n = xs.len();
    let edges = tally_edges(knots);
    let masses = row_masses(knots, mass, se);
    let v = system.solve(&masses);
    // The spline's own R_d at the knots, made non-increasing too (the bin averages are, but a
    // knot value can still overshoot its neighbour by a little), weighted by the mass each
    // knot carries (x times the width of its bin), which keeps the total.
    let mut u = Vec::with_capacity(n - 1);
    let mut w = Vec::with_capacity(n - 1);
    for j in 1..n {
        let value = v[j - 1];
        let value = if value.is_finite() {
            value.max(0.0)
        } else {
            0.0
        };
        u.push(value / xs[j]);
        w.push(xs[j] * (edges[j] - edges[j - 1]));
    }
    let fitted = non_increasing_fit(&u, &w);
    let mut out = vec![0.0; n];
    for j in 1..n {
        let v = fitted[j - 1] * xs[j];
        out[j] = if v.is_finite() { v.max(0.0) } else { 0.0 };
    }
    out
}
