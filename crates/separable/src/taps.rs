//! Discrete 1D taps from a fine profile (Jimenez et al. 2015, §6 "Importance sampling"): all
//! channels are sampled at the same positions, placed from the *dominant* channel's CDF, with
//! per-channel weights; or uniformly, for comparison.
//!
//! Both placements split the profile's span [−W, W] into n intervals and give each tap the
//! exact mass of its interval in every channel (the profile's density is constant inside a
//! grid cell), so the weights sum to the profile's mass: energy is preserved exactly.
//! - **Importance** ([`importance`]): interval k is [F⁻¹(k/n), F⁻¹((k+1)/n)], F the dominant
//!   channel's CDF, so every tap carries 1/n of the dominant channel's energy; the tap sits at
//!   the dominant channel's centroid of its interval, so the tap set also reproduces each
//!   interval's first moment (a linear irradiance ramp is filtered exactly within each
//!   interval). Taps crowd near the centre, where the energy is.
//! - **Uniform** ([`uniform`]): n intervals of equal width 2W/n, taps at their centres.
//!
//! Jimenez's public code (2012) places taps with a fixed power warp of a uniform grid and
//! weights them by the profile times the spacing; the CDF placement here is the paper's
//! "importance sampling on the 1D function" made exact in energy.

use crate::Rgb;
use crate::error::{SeparableError, ensure};
use crate::kernel::{Kernel1d, Profile1d, Tap};

/// The number of taps the paper uses per pass (§6: "only seven samples per pixel").
pub const DEFAULT_TAPS: usize = 7;

/// How a fine [`Profile1d`] becomes the taps of one pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TapPlacement {
    /// Every grid cell is a tap (exact with respect to the profile; many taps).
    Grid,
    /// n taps at the centres of n equal intervals ([`uniform`]).
    Uniform(usize),
    /// n taps placed from the dominant channel's CDF ([`importance`]).
    Importance(usize),
}

impl Default for TapPlacement {
    fn default() -> Self {
        TapPlacement::Importance(DEFAULT_TAPS)
    }
}

/// The taps of `profile` for `placement`.
pub fn place(profile: &Profile1d, placement: TapPlacement) -> Result<Kernel1d, SeparableError> {
    match placement {
        TapPlacement::Grid => Ok(profile.to_kernel1d()),
        TapPlacement::Uniform(n) => uniform(profile, n),
        TapPlacement::Importance(n) => importance(profile, n, None),
    }
}

/// The channel with the widest distribution (largest standard deviation of its non-negative
/// mass), the one whose CDF places the taps; ties and degenerate profiles give channel 0.
pub fn dominant_channel(profile: &Profile1d) -> usize {
    let mut best = (0, -1.0);
    for c in 0..3 {
        let (mut m0, mut m2) = (0.0, 0.0);
        for (i, m) in profile.mass.iter().enumerate() {
            let x = profile.offset_mm(i);
            m0 += m[c].max(0.0);
            m2 += m[c].max(0.0) * x * x;
        }
        if m0 > 0.0 {
            let sd = (m2 / m0).max(0.0).sqrt();
            if sd > best.1 {
                best = (c, sd);
            }
        }
    }
    best.0
}

/// Integral of every channel's (piecewise-constant) density over [a, b], and the first
/// moment ∫ x ρ of channel `moment_ch`.
fn integrate(profile: &Profile1d, a: f64, b: f64, moment_ch: usize) -> (Rgb, f64) {
    let mut mass = [0.0; 3];
    let mut moment = 0.0;
    if !(b > a) {
        return (mass, moment);
    }
    let h = profile.cell_mm;
    let w = profile.half_width_mm();
    let n = profile.cells();
    let first = (((a + w) / h).floor().max(0.0) as usize).min(n - 1);
    let last = (((b + w) / h).ceil().max(0.0) as usize).min(n);
    for i in first..last {
        let lo = -w + i as f64 * h;
        let (l, r) = (a.max(lo), b.min(lo + h));
        if r <= l {
            continue;
        }
        let frac = (r - l) / h;
        for c in 0..3 {
            mass[c] += profile.mass[i][c] * frac;
        }
        moment += profile.mass[i][moment_ch] * frac * 0.5 * (l + r);
    }
    (mass, moment)
}

fn check(profile: &Profile1d, n: usize) -> Result<(), SeparableError> {
    ensure(n >= 1, || "the number of taps must be at least 1".into())?;
    ensure(profile.cells() % 2 == 1 && profile.cell_mm > 0.0, || {
        "profile must have an odd number of cells of positive width".into()
    })?;
    ensure(
        profile.mass.iter().all(|m| m.iter().all(|v| v.is_finite())),
        || "profile masses must be finite".into(),
    )
}

/// n taps over equal intervals of the profile's span, at the interval centres, weights the
/// exact interval masses (signed profiles allowed).
pub fn uniform(profile: &Profile1d, n: usize) -> Result<Kernel1d, SeparableError> {
    check(profile, n)?;
    let w = profile.half_width_mm();
    let step = 2.0 * w / n as f64;
    let taps = (0..n)
        .map(|k| {
            let a = -w + k as f64 * step;
            let b = if k + 1 == n { w } else { a + step };
            Tap {
                offset_mm: 0.5 * (a + b),
                weight: integrate(profile, a, b, 0).0,
            }
        })
        .collect();
    Ok(Kernel1d { taps })
}

/// n taps placed from the CDF of channel `dominant` (default [`dominant_channel`]), which
/// must be non-negative with positive mass: interval k = [F⁻¹(k/n), F⁻¹((k+1)/n)], tap at the
/// dominant channel's centroid of the interval, weights the exact interval masses of every
/// channel.
pub fn importance(
    profile: &Profile1d,
    n: usize,
    dominant: Option<usize>,
) -> Result<Kernel1d, SeparableError> {
    check(profile, n)?;
    let d = dominant.unwrap_or_else(|| dominant_channel(profile));
    ensure(d < 3, || format!("dominant channel {d} is not 0, 1 or 2"))?;
    ensure(profile.mass.iter().all(|m| m[d] >= 0.0), || {
        format!("importance placement needs a non-negative dominant channel ({d})")
    })?;
    let total: f64 = profile.mass.iter().map(|m| m[d]).sum();
    if !(total > 0.0) {
        return Err(SeparableError::ZeroEnergy { channel: d });
    }
    let h = profile.cell_mm;
    let w = profile.half_width_mm();
    // Cumulative mass at the left edge of every cell.
    let mut cdf = Vec::with_capacity(profile.cells() + 1);
    let mut acc = 0.0;
    cdf.push(0.0);
    for m in &profile.mass {
        acc += m[d];
        cdf.push(acc);
    }
    let inverse = |q: f64| -> f64 {
        // First cell whose right-edge CDF reaches q (leftmost x with F(x) = q).
        let i = cdf[1..]
            .partition_point(|&c| c < q)
            .min(profile.cells() - 1);
        let m = profile.mass[i][d];
        let t = if m > 0.0 {
            ((q - cdf[i]) / m).clamp(0.0, 1.0)
        } else {
            0.0
        };
        -w + (i as f64 + t) * h
    };
    let mut edges: Vec<f64> = (0..=n)
        .map(|k| {
            if k == 0 {
                -w
            } else if k == n {
                w
            } else {
                inverse(acc * k as f64 / n as f64)
            }
        })
        .collect();
    for k in 1..edges.len() {
        edges[k] = edges[k].max(edges[k - 1]);
    }
    let taps = edges
        .windows(2)
        .map(|e| {
            let (mass, moment) = integrate(profile, e[0], e[1], d);
            let offset = if mass[d] > 0.0 {
                (moment / mass[d]).clamp(e[0], e[1])
            } else {
                0.5 * (e[0] + e[1])
            };
            // The centre tap of a symmetric profile is 0 up to rounding: make it exactly 0.
            let offset = if offset.abs() < 1e-12 * w {
                0.0
            } else {
                offset
            };
            Tap {
                offset_mm: offset,
                weight: mass,
            }
        })
        .collect();
    Ok(Kernel1d { taps })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn laplace_profile() -> Profile1d {
        // Three channels of different widths: e^{-|x|/s} with s = 2, 1, 0.5 mm.
        Profile1d::from_cells(401, 0.05, |a, b| {
            let x = 0.5 * (a + b);
            [2.0, 1.0, 0.5].map(|s: f64| (-(x.abs()) / s).exp() * (b - a))
        })
        .unwrap()
    }

    #[test]
    fn placements_preserve_energy_and_symmetry() {
        let p = laplace_profile();
        assert_eq!(dominant_channel(&p), 0);
        let total = p.total();
        for placement in [
            TapPlacement::Grid,
            TapPlacement::Uniform(7),
            TapPlacement::Importance(7),
            TapPlacement::Importance(1),
            TapPlacement::Importance(8),
        ] {
            let k = place(&p, placement).unwrap();
            let s = k.sum();
            for c in 0..3 {
                assert!(
                    ((s[c] - total[c]) / total[c]).abs() < 1e-13,
                    "{placement:?} ch {c}: {} vs {}",
                    s[c],
                    total[c]
                );
            }
            // Symmetric profile → symmetric taps.
            let n = k.taps.len();
            for i in 0..n {
                let (a, b) = (k.taps[i], k.taps[n - 1 - i]);
                assert!((a.offset_mm + b.offset_mm).abs() < 1e-9, "{placement:?}");
                assert!((a.weight[0] - b.weight[0]).abs() < 1e-9 * total[0]);
            }
        }
    }

    #[test]
    fn importance_taps_share_the_dominant_energy_equally() {
        let p = laplace_profile();
        let k = importance(&p, 7, None).unwrap();
        let t = p.total()[0];
        for tap in &k.taps {
            assert!((tap.weight[0] - t / 7.0).abs() < 1e-12 * t, "{tap:?}");
        }
        // Centre tap exactly at 0, and taps denser near the centre than uniform ones.
        assert_eq!(k.taps[3].offset_mm, 0.0);
        let u = uniform(&p, 7).unwrap();
        assert!(k.taps[4].offset_mm < u.taps[4].offset_mm);
    }

    #[test]
    fn rejects_bad_input() {
        let p = laplace_profile();
        assert!(importance(&p, 0, None).is_err());
        assert!(importance(&p, 3, Some(3)).is_err());
        let mut neg = p.clone();
        neg.mass[10][0] = -1.0;
        assert!(importance(&neg, 3, Some(0)).is_err());
        assert!(uniform(&neg, 3).is_ok());
    }
}
