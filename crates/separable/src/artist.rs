//! The artist-friendly separable model (Jimenez et al. 2015, §5, Eq. 6): a mixture of a near
//! and a far 1D Gaussian per channel,
//! a_m(x) = w G(x, σ_n) + (1 − w) G(x, σ_f), A_m(x, y) = a_m(x) a_m(y),
//! a rank-1 kernel (unlike d'Eon's 2D Gaussian mixture, where two Gaussians are rank 2). The
//! paper's Table 2 parameter sets are the presets [`CLOSE_FIT`] and [`PRODUCTION`].
//!
//! [`fit`] finds (σ_n, σ_f, w) per channel for a given 1D profile (e.g. the pre-integrated
//! a_p of [`crate::preintegrated::profile`]): for fixed σ's the best non-negative amplitudes
//! of the two Gaussians are a 2 × 2 non-negative least-squares problem solved in closed form
//! (variable projection), and (ln σ_n, ln σ_f) are found by a grid search followed by
//! Nelder–Mead, minimising the L2 distance of the cell masses.
//!
//! Table 2 is not a fit of this workspace's presets: fitted to the pre-integrated profile of
//! Jensen et al.'s skin1 (better dipole), Eq. 6 gives σ_n ≈ [1.08, 0.67, 0.43] mm,
//! σ_f ≈ [3.2, 1.7, 1.0] mm, w ≈ 0.36–0.42 (1D relative L2 error 1.6–3.1 %), about three times
//! wider than the close fit, which the paper matched to its own skin profile.

use crate::Rgb;
use crate::error::{SeparableError, ensure};
use crate::kernel::{Profile1d, SeparableKernel};
use crate::optimize::nelder_mead;
use crate::special::gaussian_mass;
use crate::taps::{self, TapPlacement};

/// Parameters of Eq. 6 per channel. Lengths in mm (the paper does not print the unit of
/// Table 2; its profile plots, Figure 5, are in mm, and we read the table in mm as well).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArtistParams {
    /// Standard deviation σ_n of the near-scattering Gaussian (mm), per channel.
    pub sigma_near: Rgb,
    /// Standard deviation σ_f of the far-scattering Gaussian (mm), per channel.
    pub sigma_far: Rgb,
    /// Weight w of the near Gaussian, in [0, 1], per channel (Table 2 uses one w for all).
    pub w: Rgb,
}

/// Table 2, "Close fit": σ_n = [0.034, 0.029, 0.016], σ_f = [1, 0.48, 0.2], w = 0.37 (the
/// kernel matched to the skin diffusion profile, Figures 6, 7 and 9).
pub const CLOSE_FIT: ArtistParams = ArtistParams {
    sigma_near: [0.034, 0.029, 0.016],
    sigma_far: [1.0, 0.48, 0.2],
    w: [0.37; 3],
};

/// Table 2, "Production": σ_n = [0.25, 0.08, 0.02], σ_f = [1, 0.3, 0.05], w = 0.6 (the
/// kernel an artist tuned for the paper's assets).
pub const PRODUCTION: ArtistParams = ArtistParams {
    sigma_near: [0.25, 0.08, 0.02],
    sigma_far: [1.0, 0.3, 0.05],
    w: [0.6; 3],
};

/// A named parameter set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArtistPreset {
    /// Name (`close-fit`, `production`).
    pub name: &'static str,
    /// The parameters.
    pub params: ArtistParams,
}

/// The paper's Table 2.
pub const PRESETS: [ArtistPreset; 2] = [
    ArtistPreset {
        name: "close-fit",
        params: CLOSE_FIT,
    },
    ArtistPreset {
        name: "production",
        params: PRODUCTION,
    },
];

/// A Table 2 preset by name (one of [`PRESETS`]: `close-fit` or `production`,
/// case-insensitive, `_`/space as `-`); the error lists the names of [`PRESETS`].
pub fn preset(name: &str) -> Result<ArtistParams, SeparableError> {
    let key: String = name
        .trim()
        .chars()
        .map(|c| if c == '_' || c == ' ' { '-' } else { c })
        .flat_map(char::to_lowercase)
        .collect();
    PRESETS
        .iter()
        .find(|p| p.name == key)
        .map(|p| p.params)
        .ok_or_else(|| {
            let names: Vec<&str> = PRESETS.iter().map(|p| p.name).collect();
            SeparableError::InvalidArgument(format!(
                "unknown artist preset `{name}` (known: {})",
                names.join(", ")
            ))
        })
}

impl ArtistParams {
    /// Checks σ's > 0 and finite, w in [0, 1].
    pub fn validate(&self) -> Result<(), SeparableError> {
        for c in 0..3 {
            for (what, s) in [
                ("sigma_near", self.sigma_near[c]),
                ("sigma_far", self.sigma_far[c]),
            ] {
                ensure(s > 0.0 && s.is_finite(), || {
                    format!("{what}[{c}] = {s} must be positive and finite")
                })?;
            }
            ensure((0.0..=1.0).contains(&self.w[c]), || {
                format!("w[{c}] = {} must be in [0, 1]", self.w[c])
            })?;
        }
        Ok(())
    }

    /// a_m(x) of channel c (1/mm; integrates to 1 over ℝ).
    pub fn eval(&self, c: usize, x: f64) -> f64 {
        let g =
            |s: f64| (-(x * x) / (2.0 * s * s)).exp() / ((2.0 * std::f64::consts::PI).sqrt() * s);
        self.w[c] * g(self.sigma_near[c]) + (1.0 - self.w[c]) * g(self.sigma_far[c])
    }

    /// Variance of a_m in channel c: w σ_n² + (1 − w) σ_f² (mm²).
    pub fn variance(&self, c: usize) -> f64 {
        self.w[c] * self.sigma_near[c].powi(2) + (1.0 - self.w[c]) * self.sigma_far[c].powi(2)
    }

    /// A grid half-width holding all but ~6e-5 of every channel: 4 max σ (mm).
    pub fn default_half_width_mm(&self) -> f64 {
        4.0 * self
            .sigma_near
            .iter()
            .chain(&self.sigma_far)
            .fold(0.0f64, |a, b| a.max(*b))
    }
}

/// a_m discretised on `cells` (odd) cells over [−half_width, half_width]: exact cell masses
/// (error functions), unit mass per channel over ℝ (slightly less on the truncated grid).
pub fn profile(
    params: &ArtistParams,
    cells: usize,
    half_width_mm: f64,
) -> Result<Profile1d, SeparableError> {
    params.validate()?;
    ensure(half_width_mm > 0.0 && half_width_mm.is_finite(), || {
        format!("half_width_mm = {half_width_mm} must be positive and finite")
    })?;
    ensure(cells >= 1, || "cells must be at least 1".into())?;
    Profile1d::from_cells(cells, 2.0 * half_width_mm / cells as f64, |a, b| {
        std::array::from_fn(|c| {
            params.w[c] * gaussian_mass(a, b, params.sigma_near[c])
                + (1.0 - params.w[c]) * gaussian_mass(a, b, params.sigma_far[c])
        })
    })
}

/// The separable kernel A_m (Eq. 6) with energy `energy` per channel (e.g. a model's total
/// diffuse reflectance, or 1): the profile on [−4σ_max, 4σ_max] with cells no wider than a
/// quarter of the smallest σ (at most 20001), placed with `placement`, then h = v scaled.
pub fn kernel(
    params: &ArtistParams,
    energy: Rgb,
    placement: TapPlacement,
) -> Result<SeparableKernel, SeparableError> {
    params.validate()?;
    let w = params.default_half_width_mm();
    let smallest = params
        .sigma_near
        .iter()
        .chain(&params.sigma_far)
        .fold(f64::INFINITY, |a, b| a.min(*b));
    let cells = ((2.0 * w / (0.25 * smallest)).ceil() as usize).clamp(255, 20001) | 1;
    let p = profile(params, cells, w)?;
    let t = taps::place(&p, placement)?;
    SeparableKernel::symmetric(&t, energy, w)
}

/// Result of [`fit`].
#[derive(Clone, Debug, PartialEq)]
pub struct ArtistFit {
    /// The fitted parameters (σ_n ≤ σ_f).
    pub params: ArtistParams,
    /// The fitted mass per channel (the profile's mass as seen by the fit; a_m itself has unit
    /// mass).
    pub scale: Rgb,
    /// ‖target − fit‖₂ / ‖target‖₂ over the cell masses, per channel.
    pub rel_error: Rgb,
    /// Whether Nelder–Mead met its tolerances per channel: simplex diameter ≤ 1e-9 in ln σ and
    /// spread of the relative objective ≤ 1e-12 × best + 1e-16; otherwise the best point
    /// found (within 4000 evaluations) is returned.
    pub converged: [bool; 3],
    /// Objective evaluations over the three channels.
    pub evaluations: usize,
}

/// Best (α, β) ≥ 0 minimising ‖t − α gn − β gf‖², and that residual ‖·‖² (evaluated
/// directly, not from the normal equations, so it resolves exact fits down to rounding).
fn two_nnls(t: &[f64], gn: &[f64], gf: &[f64]) -> (f64, f64, f64) {
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let (nn, ff, nf) = (dot(gn, gn), dot(gf, gf), dot(gn, gf));
    let (nt, ft) = (dot(gn, t), dot(gf, t));
    let resid = |a: f64, b: f64| {
        t.iter()
            .zip(gn.iter().zip(gf))
            .map(|(t, (n, f))| {
                let r = t - a * n - b * f;
                r * r
            })
            .sum::<f64>()
    };
    let mut candidates = Vec::with_capacity(3);
    let det = nn * ff - nf * nf;
    if det > 1e-14 * nn * ff {
        let a = (nt * ff - ft * nf) / det;
        let b = (ft * nn - nt * nf) / det;
        if a >= 0.0 && b >= 0.0 {
            candidates.push((a, b));
        }
    }
    if nn > 0.0 {
        candidates.push(((nt / nn).max(0.0), 0.0));
    }
    if ff > 0.0 {
        candidates.push((0.0, (ft / ff).max(0.0)));
    }
    let mut best = (0.0, 0.0, dot(t, t));
    for (a, b) in candidates {
        let r = resid(a, b);
        if r < best.2 {
            best = (a, b, r);
        }
    }
    best
}

/// Fits Eq. 6 to every channel of `profile` (non-negative masses, positive total per
/// channel). σ's are searched in [cell/8, 2 × half-width]; a σ well below the cell width
/// cannot be told apart from a narrower one (all its mass is in the centre cell), so use a
/// grid fine enough for the near lobe.
pub fn fit(profile: &Profile1d) -> Result<ArtistFit, SeparableError> {
    ensure(profile.cells() % 2 == 1 && profile.cell_mm > 0.0, || {
        "profile must have an odd number of cells of positive width".into()
    })?;
    let h = profile.cell_mm;
    let w = profile.half_width_mm();
    let edges: Vec<(f64, f64)> = (0..profile.cells())
        .map(|i| {
            let x = profile.offset_mm(i);
            (x - 0.5 * h, x + 0.5 * h)
        })
        .collect();
    let masses =
        |s: f64| -> Vec<f64> { edges.iter().map(|&(a, b)| gaussian_mass(a, b, s)).collect() };
    let (lo, hi) = ((h / 8.0).ln(), (2.0 * w).ln());
    let grid_n = 24;
    let grid: Vec<f64> = (0..grid_n)
        .map(|i| lo + (hi - lo) * i as f64 / (grid_n - 1) as f64)
        .collect();
    let grid_masses: Vec<Vec<f64>> = grid.iter().map(|l| masses(l.exp())).collect();
    let mut out = ArtistFit {
        params: ArtistParams {
            sigma_near: [0.0; 3],
            sigma_far: [0.0; 3],
            w: [0.0; 3],
        },
        scale: [0.0; 3],
        rel_error: [0.0; 3],
        converged: [false; 3],
        evaluations: 0,
    };
    for c in 0..3 {
        let t: Vec<f64> = profile.mass.iter().map(|m| m[c]).collect();
        ensure(t.iter().all(|v| *v >= 0.0 && v.is_finite()), || {
            format!("profile channel {c} must be finite and non-negative")
        })?;
        let tt: f64 = t.iter().map(|v| v * v).sum();
        if !(tt > 0.0) {
            return Err(SeparableError::ZeroEnergy { channel: c });
        }
        // Grid search over σ pairs.
        let mut start = (grid[0], grid[1], f64::INFINITY);
        for i in 0..grid_n {
            for j in i + 1..grid_n {
                let r = two_nnls(&t, &grid_masses[i], &grid_masses[j]).2;
                if r < start.2 {
                    start = (grid[i], grid[j], r);
                }
            }
        }
        let clamp = |l: f64| l.clamp(lo, hi);
        let mut objective = |p: &[f64]| -> f64 {
            let (a, b) = (clamp(p[0]), clamp(p[1]));
            two_nnls(&t, &masses(a.exp()), &masses(b.exp())).2 / tt
        };
        let m = nelder_mead(
            &mut objective,
            &[start.0, start.1],
            0.25,
            1e-12,
            1e-16,
            1e-9,
            4000,
        );
        out.evaluations += m.evaluations + grid_n * (grid_n - 1) / 2;
        out.converged[c] = m.converged;
        let (mut sn, mut sf) = (clamp(m.x[0]).exp(), clamp(m.x[1]).exp());
        let (gn, gf) = (masses(sn), masses(sf));
        let (mut a, mut b, r) = two_nnls(&t, &gn, &gf);
        if sn > sf {
            std::mem::swap(&mut sn, &mut sf);
            std::mem::swap(&mut a, &mut b);
        }
        let s = a + b;
        out.params.sigma_near[c] = sn;
        out.params.sigma_far[c] = sf;
        out.params.w[c] = if s > 0.0 {
            (a / s).clamp(0.0, 1.0)
        } else {
            1.0
        };
        out.scale[c] = s;
        out.rel_error[c] = (r / tt).max(0.0).sqrt();
    }
    Ok(out)
}
