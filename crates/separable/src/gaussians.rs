//! The sum-of-Gaussians baseline (d'Eon, Luebke, Enderton 2007; Jimenez et al. 2015, Eq. 3):
//! R_d(r) ≈ Σᵢ wᵢ G(vᵢ, r), G(v, r) = e^{−r²/2v} / (2πv), a 2D Gaussian of variance v per
//! axis and unit mass, with variances shared by the three channels and one non-negative
//! weight per Gaussian and channel, as in d'Eon et al.'s skin fits.
//!
//! Each Gaussian is separable, G(v, r) = g(x; √v) g(y; √v), so it is exactly a rank-1
//! separable kernel and the sum of N costs N two-pass convolutions
//! ([`GaussianFit::kernel`]).
//!
//! Fit: d'Eon et al.'s error ∫₀^{r_max} r (R_d(r) − Σ wᵢ G(vᵢ, r))² dr, relative to
//! ∫ r R_d² dr, summed over channels. For given variances the weights are a non-negative
//! least-squares problem per channel, solved exactly by enumerating the supports (N ≤ 6, at
//! most 63 small Cholesky solves); the log-variances are found by Nelder–Mead. The fits for
//! N = 1, 2, … are chained: fit N + 1 starts from fit N's variances plus the best of several
//! new ones, a point whose error is at most fit N's (the new weight may be 0), and the
//! minimiser never leaves its best point, so the error is non-increasing in N by
//! construction.

use crate::Rgb;
use crate::error::{SeparableError, ensure};
use crate::kernel::{Profile1d, SeparableKernel, SeparableTerm};
use crate::optimize::nelder_mead;
use crate::special::gaussian_mass;
use crate::taps::{self, TapPlacement};
use sss_bssrdf::Bssrdf;
use sss_bssrdf::quadrature::gauss_legendre;
use std::f64::consts::PI;

/// The largest number of Gaussians fitted (d'Eon et al. use up to 6 for skin).
pub const MAX_GAUSSIANS: usize = 6;

/// A fitted sum of N Gaussians.
#[derive(Clone, Debug, PartialEq)]
pub struct GaussianFit {
    /// Variances vᵢ (mm²), increasing.
    pub variances: Vec<f64>,
    /// Weight (energy) of each Gaussian per channel, as fitted (≥ 0).
    pub weights: Vec<Rgb>,
    /// √(∫ r (R_d − fit)² dr / ∫ r R_d² dr) over [0, r_max], per channel.
    pub rel_error: Rgb,
    /// The radius the fit covered (mm).
    pub r_max_mm: f64,
    /// Whether Nelder–Mead met its tolerances within its budget (1500 N evaluations): simplex
    /// diameter ≤ 1e-6 in ln v and objective spread ≤ 1e-10 × best + 1e-14; otherwise the
    /// best point found is kept.
    pub converged: bool,
    /// Objective evaluations used for this N.
    pub evaluations: usize,
}

impl GaussianFit {
    /// Number of Gaussians.
    pub fn len(&self) -> usize {
        self.variances.len()
    }

    /// Whether there are no Gaussians.
    pub fn is_empty(&self) -> bool {
        self.variances.is_empty()
    }

    /// The fitted profile Σ wᵢ G(vᵢ, r) of channel c (1/mm²).
    pub fn eval(&self, c: usize, r: f64) -> f64 {
        self.variances
            .iter()
            .zip(&self.weights)
            .map(|(v, w)| w[c] * gauss2d(*v, r))
            .sum()
    }

    /// Σ wᵢ per channel: the fit's energy.
    pub fn total(&self) -> Rgb {
        let mut t = [0.0; 3];
        for w in &self.weights {
            for c in 0..3 {
                t[c] += w[c];
            }
        }
        t
    }

    /// The N-term separable kernel, weights rescaled so its energy is `energy` per channel.
    /// Term i is h = v = taps of the unit 1D Gaussian of σᵢ = √vᵢ on [−4σᵢ, 4σᵢ] (255
    /// cells, taps renormalised to unit mass) × √(wᵢᶜ · energyᶜ / Σⱼ wⱼᶜ). Errors if a
    /// channel has no weight but a positive target.
    pub fn kernel(
        &self,
        energy: Rgb,
        placement: TapPlacement,
    ) -> Result<SeparableKernel, SeparableError> {
        let total = self.total();
        let mut scale = [0.0; 3];
        for c in 0..3 {
            ensure(energy[c] >= 0.0 && energy[c].is_finite(), || {
                format!(
                    "energy[{c}] = {} must be finite and non-negative",
                    energy[c]
                )
            })?;
            if energy[c] == 0.0 {
                continue;
            }
            if !(total[c] > 0.0) {
                return Err(SeparableError::ZeroEnergy { channel: c });
            }
            scale[c] = energy[c] / total[c];
        }
        let mut terms = Vec::with_capacity(self.len());
        for (v, w) in self.variances.iter().zip(&self.weights) {
            let sigma = v.sqrt();
            let cells = 255;
            let p = Profile1d::from_cells(cells, 8.0 * sigma / cells as f64, |a, b| {
                [gaussian_mass(a, b, sigma); 3]
            })?;
            let t = taps::place(&p, placement)?;
            let s = t.sum();
            let f: Rgb = std::array::from_fn(|c| {
                if s[c] > 0.0 {
                    (w[c] * scale[c]).max(0.0).sqrt() / s[c]
                } else {
                    0.0
                }
            });
            let h = t.scaled(f);
            terms.push(SeparableTerm {
                horizontal: h.clone(),
                vertical: h,
            });
        }
        let k = SeparableKernel {
            terms,
            support_mm: 0.0,
        };
        let support = self.r_max_mm.max(k.radius_mm());
        Ok(SeparableKernel {
            support_mm: support,
            ..k
        })
    }
}

/// G(v, r) = e^{−r²/2v} / (2πv).
fn gauss2d(v: f64, r: f64) -> f64 {
    if !(v > 0.0) {
        return 0.0;
    }
    (-(r * r) / (2.0 * v)).exp() / (2.0 * PI * v)
}

/// Quadrature of ∫₀^{r_max} r f(r) dr: nodes and weights (the weights include r).
fn radial_nodes(r_max: f64) -> (Vec<f64>, Vec<f64>) {
    let (gx, gw) = gauss_legendre(4);
    let mut nodes = Vec::new();
    let mut weights = Vec::new();
    let mut add = |a: f64, b: f64| {
        for (x, w) in gx.iter().zip(gw) {
            let r = 0.5 * (a + b) + 0.5 * (b - a) * x;
            nodes.push(r);
            weights.push(0.5 * (b - a) * w * r);
        }
    };
    let first = r_max * 1e-4;
    add(0.0, first);
    let panels = 96;
    let ratio = (r_max / first).powf(1.0 / panels as f64);
    let mut a = first;
    for _ in 0..panels {
        add(a, a * ratio);
        a *= ratio;
    }
    (nodes, weights)
}

/// The target profile at the quadrature nodes and the fit's workspace.
struct Problem {
    nodes: Vec<f64>,
    weights: Vec<f64>,
    target: [Vec<f64>; 3],
    norm2: Rgb,
    ln_v_range: (f64, f64),
}

/// Cholesky solve of the small SPD system `a x = b` (n × n, row-major); None if not SPD.
fn cholesky_solve(a: &[f64], b: &[f64], n: usize) -> Option<Vec<f64>> {
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= l[i * n + k] * l[j * n + k];
            }
            if i == j {
                if !(s > 1e-13 * a[i * n + i].abs()) || !(s > 0.0) {
                    return None;
                }
                l[i * n + i] = s.sqrt();
            } else {
                l[i * n + j] = s / l[j * n + j];
            }
        }
    }
    let mut y = vec![0.0; n];
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i * n + k] * y[k];
        }
        y[i] = s / l[i * n + i];
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let mut s = y[i];
        for k in i + 1..n {
            s -= l[k * n + i] * x[k];
        }
        x[i] = s / l[i * n + i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

impl Problem {
    /// The optimal non-negative weights for `ln_v` per channel and the summed relative
    /// squared error (‖R‖² − bᵀw at the optimum of the best feasible support, over ‖R‖²).
    fn solve(&self, ln_v: &[f64]) -> (Vec<Rgb>, f64, Rgb) {
        let n = ln_v.len();
        let (lo, hi) = self.ln_v_range;
        let vars: Vec<f64> = ln_v.iter().map(|l| l.clamp(lo, hi).exp()).collect();
        let basis: Vec<Vec<f64>> = vars
            .iter()
            .map(|v| self.nodes.iter().map(|r| gauss2d(*v, *r)).collect())
            .collect();
        let mut gram = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..=i {
                let s: f64 = (0..self.nodes.len())
                    .map(|q| self.weights[q] * basis[i][q] * basis[j][q])
                    .sum();
                gram[i * n + j] = s;
                gram[j * n + i] = s;
            }
        }
        let mut weights = vec![[0.0; 3]; n];
        let mut total = 0.0;
        let mut rel = [0.0; 3];
        for c in 0..3 {
            if !(self.norm2[c] > 0.0) {
                continue;
            }
            let b: Vec<f64> = (0..n)
                .map(|i| {
                    (0..self.nodes.len())
                        .map(|q| self.weights[q] * basis[i][q] * self.target[c][q])
                        .sum()
                })
                .collect();
            // Exact NNLS: the best support whose unconstrained solution is non-negative.
            let mut best = (self.norm2[c], vec![0.0; n]);
            for mask in 1u32..(1 << n) {
                let idx: Vec<usize> = (0..n).filter(|i| mask & (1 << i) != 0).collect();
                let m = idx.len();
                let a: Vec<f64> = idx
                    .iter()
                    .flat_map(|&i| idx.iter().map(move |&j| (i, j)))
                    .map(|(i, j)| gram[i * n + j])
                    .collect();
                let bs: Vec<f64> = idx.iter().map(|&i| b[i]).collect();
                let Some(x) = cholesky_solve(&a, &bs, m) else {
                    continue;
                };
                if x.iter().any(|v| *v < 0.0) {
                    continue;
                }
                let value = self.norm2[c] - bs.iter().zip(&x).map(|(p, q)| p * q).sum::<f64>();
                if value < best.0 {
                    let mut w = vec![0.0; n];
                    for (k, &i) in idx.iter().enumerate() {
                        w[i] = x[k];
                    }
                    best = (value, w);
                }
            }
            let r = (best.0 / self.norm2[c]).max(0.0);
            rel[c] = r.sqrt();
            total += r;
            for i in 0..n {
                weights[i][c] = best.1[i];
            }
        }
        (weights, total, rel)
    }
}

/// Fits N = 1, …, `max_n` (≤ [`MAX_GAUSSIANS`]) Gaussians to `model`'s R_d over
/// [0, r_max], r_max the radius holding 99.9 % of the widest channel's energy.
pub fn fit_model(model: &dyn Bssrdf, max_n: usize) -> Result<Vec<GaussianFit>, SeparableError> {
    let r_max = (0..3)
        .map(|c| model.radius_for_energy(c, 0.999))
        .fold(0.0, f64::max);
    fit_radial(&|c, r| model.rd(c, r), r_max, max_n)
}

/// Fits N = 1, …, `max_n` Gaussians to any radial profile `rd(channel, r)` (1/mm²) over
/// [0, r_max_mm]. Variances are searched in [10⁻⁸ r_max², r_max²].
pub fn fit_radial(
    rd: &dyn Fn(usize, f64) -> f64,
    r_max_mm: f64,
    max_n: usize,
) -> Result<Vec<GaussianFit>, SeparableError> {
    ensure((1..=MAX_GAUSSIANS).contains(&max_n), || {
        format!("max_n = {max_n} must be in 1..={MAX_GAUSSIANS}")
    })?;
    ensure(r_max_mm > 0.0 && r_max_mm.is_finite(), || {
        format!("r_max_mm = {r_max_mm} must be positive and finite")
    })?;
    let (nodes, weights) = radial_nodes(r_max_mm);
    let target: [Vec<f64>; 3] = std::array::from_fn(|c| {
        nodes
            .iter()
            .map(|r| {
                let v = rd(c, *r);
                if v.is_finite() { v } else { 0.0 }
            })
            .collect()
    });
    let norm2: Rgb =
        std::array::from_fn(|c| target[c].iter().zip(&weights).map(|(t, w)| w * t * t).sum());
    ensure(norm2.iter().any(|n| *n > 0.0), || {
        "the profile is zero on [0, r_max]".into()
    })?;
    let ln_v_range = (
        (1e-8 * r_max_mm * r_max_mm).ln(),
        (r_max_mm * r_max_mm).ln(),
    );
    let problem = Problem {
        nodes,
        weights,
        target,
        norm2,
        ln_v_range,
    };
    let (lo, hi) = ln_v_range;
    let candidates: Vec<f64> = (0..25).map(|i| lo + (hi - lo) * i as f64 / 24.0).collect();
    let mut fits: Vec<GaussianFit> = Vec::with_capacity(max_n);
    let mut current: Vec<f64> = Vec::new();
    for n in 1..=max_n {
        // Start: the previous variances plus the best new one.
        let mut start = (Vec::new(), f64::INFINITY);
        for &cand in &candidates {
            let mut x = current.clone();
            x.push(cand);
            let f = problem.solve(&x).1;
            if f < start.1 {
                start = (x, f);
            }
        }
        let mut evals = candidates.len();
        let mut objective = |x: &[f64]| problem.solve(x).1;
        let m = nelder_mead(&mut objective, &start.0, 0.7, 1e-10, 1e-14, 1e-6, 1500 * n);
        evals += m.evaluations;
        current = m.x.iter().map(|l| l.clamp(lo, hi)).collect();
        let (w, _, rel) = problem.solve(&current);
        let mut pairs: Vec<(f64, Rgb)> = current.iter().map(|l| l.exp()).zip(w).collect();
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        fits.push(GaussianFit {
            variances: pairs.iter().map(|p| p.0).collect(),
            weights: pairs.iter().map(|p| p.1).collect(),
            rel_error: rel,
            r_max_mm,
            converged: m.converged,
            evaluations: evals,
        });
    }
    Ok(fits)
}
