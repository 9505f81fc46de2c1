//! Low-rank separable approximations of the 2D kernel by singular value decomposition
//! (Jimenez et al. 2015, §3, Eq. 2 and Figures 2 and 4).
//!
//! Per channel, the N × N mass matrix K (rows y, columns x) is decomposed as
//! K = Σᵢ sᵢ uᵢ vᵢᵀ by one-sided Jacobi rotations ([`jacobi_svd`], accurate to the last
//! digits on these small grids; it replaced the `faer` crate, whose build was a tenth of the
//! workspace's compile time for this one call). By Eckart–Young the rank-k truncation is the best
//! rank-k approximation in the Frobenius norm, with error ‖K − K_k‖_F = √(Σ_{i>k} sᵢ²).
//!
//! As a screen-space kernel, term i is the pair (horizontal = √sᵢ vᵢ, vertical = √sᵢ uᵢ), on
//! the grid's N offsets (or resampled to fewer uniform taps). The truncation loses energy
//! (the paper's "rather large energy loss" of rank 1), so [`SvdKernel::separable`]
//! renormalises it to the kernel's energy per channel. Higher singular vectors change sign,
//! so importance placement is not offered for them.

use crate::Rgb;
use crate::error::{SeparableError, ensure};
use crate::kernel::{Kernel1d, Profile1d, SeparableKernel, SeparableTerm};
use crate::kernel2d::Kernel2d;
use crate::taps::{self, TapPlacement};

/// The largest rank [`SvdKernel::separable`] accepts (the paper studies N ≈ 1–6).
pub const MAX_RANK: usize = 6;

/// The SVD of one channel's kernel matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct SvdChannel {
    /// Singular values s₀ ≥ s₁ ≥ … ≥ 0 (the spectrum of the paper's Figure 2).
    pub singular_values: Vec<f64>,
    /// Left singular vectors (functions of y), column-major: `u[i * n + row]` is uᵢ(row).
    pub u: Vec<f64>,
    /// Right singular vectors (functions of x), column-major: `v[i * n + col]` is vᵢ(col).
    pub v: Vec<f64>,
}

/// The SVD of a [`Kernel2d`], per channel.
#[derive(Clone, Debug, PartialEq)]
pub struct SvdKernel {
    /// Grid size N.
    pub cells: usize,
    /// Cell side (mm).
    pub cell_mm: f64,
    /// The decomposed kernel's energy per channel (what [`SvdKernel::separable`] restores).
    pub total: Rgb,
    /// One decomposition per channel.
    pub channels: [SvdChannel; 3],
}

/// Decomposes every channel of `kernel` ([`jacobi_svd`]).
pub fn decompose(kernel: &Kernel2d) -> Result<SvdKernel, SeparableError> {
    let n = kernel.cells;
    let mut channels = Vec::with_capacity(3);
    for c in 0..3 {
        let ch = jacobi_svd(&kernel.mass[c], n)
            .map_err(|e| SeparableError::Svd(format!("channel {c}: {e}")))?;
        channels.push(ch);
    }
    let channels: [SvdChannel; 3] = channels
        .try_into()
        .map_err(|_| SeparableError::Svd("expected three channels".into()))?;
    Ok(SvdKernel {
        cells: n,
        cell_mm: kernel.cell_mm,
        total: kernel.total,
        channels,
    })
}

/// Most sweeps [`jacobi_svd`] makes before giving up (it converges quadratically; the
/// kernels' grids take 6–10).
const MAX_SWEEPS: usize = 60;

/// The SVD of the n × n row-major matrix `a` by one-sided Jacobi rotations (Hestenes 1958;
/// Demmel & Veselić, *Jacobi's method is more accurate than QR*, SIAM J. Matrix Anal. Appl.
/// 13(4), 1992): pairs of columns of W = A are rotated until every pair is orthogonal to
/// working precision, |wₚ·w_q| ≤ n·ε·‖wₚ‖‖w_q‖, the rotations accumulated in V, so that
/// A V = W = U Σ: sᵢ = ‖wᵢ‖, uᵢ = wᵢ / sᵢ. Each rotation is the one that zeroes wₚ·w_q
/// (Golub & Van Loan, *Matrix Computations*, 4th ed., §8.6.3: ζ = (β − α) / 2γ,
/// t = sign(ζ) / (|ζ| + √(1 + ζ²)), c = 1 / √(1 + t²), s = c t). Sorted by decreasing sᵢ; each
/// pair (uᵢ, vᵢ) signed so that Σ vᵢ ≥ 0 (the first term of a positive kernel is then
/// positive); left vectors of zero singular values complete U to an orthonormal basis.
/// O(n³) per sweep: the default 127-cell grid's three channels take about 0.2 s (`sss kernel
/// --method svd3`, AMD EPYC), and the time grows as n³.
/// Errors on non-finite input or when the sweeps do not converge.
pub fn jacobi_svd(a: &[f64], n: usize) -> Result<SvdChannel, String> {
    if a.len() != n * n {
        return Err(format!("{} values for a {n} × {n} matrix", a.len()));
    }
    if !a.iter().all(|x| x.is_finite()) {
        return Err("non-finite matrix entry".into());
    }
    // Column-major working copies: column j of W is w[j * n..(j + 1) * n].
    let mut w: Vec<f64> = (0..n * n).map(|k| a[(k % n) * n + k / n]).collect();
    let mut v = vec![0.0; n * n];
    for j in 0..n {
        v[j * n + j] = 1.0;
    }
    let tol = n.max(1) as f64 * f64::EPSILON;
    // Columns below 10⁻²⁰ of the matrix's Frobenius norm are zero to working precision: they
    // take no rotations (their products with others can underflow, and rotating them would
    // only move rounding about).
    let frob = w.iter().map(|x| x * x).sum::<f64>().sqrt();
    let negligible = (1e-20 * frob) * (1e-20 * frob);
    let mut converged = false;
    for _ in 0..MAX_SWEEPS {
        let mut rotated = false;
        for p in 0..n {
            for q in p + 1..n {
                let (wp, wq) = (&w[p * n..(p + 1) * n], &w[q * n..(q + 1) * n]);
                let (mut alpha, mut beta, mut gamma) = (0.0, 0.0, 0.0);
                for (x, y) in wp.iter().zip(wq) {
                    alpha += x * x;
                    beta += y * y;
                    gamma += x * y;
                }
                if gamma == 0.0
                    || alpha <= negligible
                    || beta <= negligible
                    || gamma.abs() <= tol * (alpha.sqrt() * beta.sqrt())
                {
                    continue;
                }
                let zeta = (beta - alpha) / (2.0 * gamma);
                // For |ζ| beyond 10¹⁵⁰, ζ² would overflow: t ≈ 1 / 2ζ there.
                let t = if zeta.abs() > 1e150 {
                    0.5 / zeta
                } else {
                    zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt())
                };
                let cs = 1.0 / (1.0 + t * t).sqrt();
                let sn = cs * t;
                if sn == 0.0 {
                    continue;
                }
                rotated = true;
                for m in [&mut w, &mut v] {
                    let (left, right) = m.split_at_mut(q * n);
                    let (cp, cq) = (&mut left[p * n..(p + 1) * n], &mut right[..n]);
                    for (x, y) in cp.iter_mut().zip(cq.iter_mut()) {
                        let (xp, yq) = (*x, *y);
                        *x = cs * xp - sn * yq;
                        *y = sn * xp + cs * yq;
                    }
                }
            }
        }
        if !rotated {
            converged = true;
            break;
        }
    }
    if !converged {
        return Err(format!("no convergence in {MAX_SWEEPS} Jacobi sweeps"));
    }
    let norms: Vec<f64> = (0..n)
        .map(|j| {
            w[j * n..(j + 1) * n]
                .iter()
                .map(|x| x * x)
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| norms[j].total_cmp(&norms[i]).then(i.cmp(&j)));
    let mut sv = Vec::with_capacity(n);
    let (mut u, mut vs) = (Vec::with_capacity(n * n), Vec::with_capacity(n * n));
    for &j in &order {
        let (s, vj) = (norms[j], &v[j * n..(j + 1) * n]);
        let flip = if vj.iter().sum::<f64>() < 0.0 {
            -1.0
        } else {
            1.0
        };
        sv.push(s);
        vs.extend(vj.iter().map(|x| flip * x));
        if s > 0.0 {
            u.extend(w[j * n..(j + 1) * n].iter().map(|x| flip * x / s));
        } else {
            u.extend(std::iter::repeat_n(0.0, n));
        }
    }
    complete_basis(&mut u, &sv, n);
    Ok(SvdChannel {
        singular_values: sv,
        u,
        v: vs,
    })
}

/// Replaces the columns of the column-major `u` whose singular value is zero by unit vectors
/// orthogonal to every other column (Gram–Schmidt, twice, over the coordinate vectors).
fn complete_basis(u: &mut [f64], sv: &[f64], n: usize) {
    for i in 0..n {
        if sv[i] > 0.0 {
            continue;
        }
        for e in 0..n {
            let mut x = vec![0.0; n];
            x[e] = 1.0;
            for _ in 0..2 {
                for k in (0..n).filter(|&k| k != i && (sv[k] > 0.0 || k < i)) {
                    let col = &u[k * n..(k + 1) * n];
                    let d: f64 = col.iter().zip(&x).map(|(a, b)| a * b).sum();
                    for (xr, cr) in x.iter_mut().zip(col) {
                        *xr -= d * cr;
                    }
                }
            }
            let norm = x.iter().map(|a| a * a).sum::<f64>().sqrt();
            if norm > 0.5 {
                for (dst, xr) in u[i * n..(i + 1) * n].iter_mut().zip(&x) {
                    *dst = xr / norm;
                }
                break;
            }
        }
    }
}

impl SvdKernel {
    /// The singular values of channel `c`, non-increasing.
    pub fn spectrum(&self, c: usize) -> &[f64] {
        &self.channels[c].singular_values
    }

    /// The rank-`rank` truncation of channel `c`'s matrix (row-major masses, *not*
    /// renormalised), for error measurements.
    pub fn reconstruct(&self, c: usize, rank: usize) -> Vec<f64> {
        let n = self.cells;
        let ch = &self.channels[c];
        let mut out = vec![0.0; n * n];
        for i in 0..rank.min(n) {
            let s = ch.singular_values[i];
            let (u, v) = (&ch.u[i * n..(i + 1) * n], &ch.v[i * n..(i + 1) * n]);
            for r in 0..n {
                let su = s * u[r];
                for (o, vj) in out[r * n..(r + 1) * n].iter_mut().zip(v) {
                    *o += su * vj;
                }
            }
        }
        out
    }

    /// The Eckart–Young error of the rank-`rank` truncation of channel `c`:
    /// √(Σ_{i ≥ rank} sᵢ²).
    pub fn frobenius_error(&self, c: usize, rank: usize) -> f64 {
        self.channels[c].singular_values[rank.min(self.cells)..]
            .iter()
            .map(|s| s * s)
            .sum::<f64>()
            .sqrt()
    }

    /// Term `i` as two profiles on the grid (horizontal √sᵢ vᵢ, vertical √sᵢ uᵢ per channel),
    /// before renormalisation.
    pub fn term_profiles(&self, i: usize) -> (Profile1d, Profile1d) {
        let n = self.cells;
        let pick = |which: fn(&SvdChannel) -> &Vec<f64>| Profile1d {
            cell_mm: self.cell_mm,
            mass: (0..n)
                .map(|r| {
                    std::array::from_fn(|c| {
                        let ch = &self.channels[c];
                        ch.singular_values[i].max(0.0).sqrt() * which(ch)[i * n + r]
                    })
                })
                .collect(),
        };
        (pick(|ch| &ch.v), pick(|ch| &ch.u))
    }

    /// The rank-`rank` (1..=[`MAX_RANK`]) separable kernel, renormalised so its energy equals
    /// [`SvdKernel::total`] per channel. `placement` is [`TapPlacement::Grid`] (the N grid
    /// offsets) or [`TapPlacement::Uniform`] (resampled); importance placement is rejected
    /// because singular vectors beyond the first change sign. Errors (never a silent garbage
    /// kernel) when the truncation's energy is not positive in a channel whose target is.
    pub fn separable(
        &self,
        rank: usize,
        placement: TapPlacement,
    ) -> Result<SeparableKernel, SeparableError> {
        ensure((1..=MAX_RANK.min(self.cells)).contains(&rank), || {
            format!("rank {rank} must be in 1..={}", MAX_RANK.min(self.cells))
        })?;
        ensure(!matches!(placement, TapPlacement::Importance(_)), || {
            "SVD terms change sign: use TapPlacement::Grid or Uniform".into()
        })?;
        let mut terms = Vec::with_capacity(rank);
        for i in 0..rank {
            let (h, v) = self.term_profiles(i);
            let (h, v): (Kernel1d, Kernel1d) =
                (taps::place(&h, placement)?, taps::place(&v, placement)?);
            terms.push(SeparableTerm {
                horizontal: h,
                vertical: v,
            });
        }
        let raw = SeparableKernel {
            terms,
            support_mm: 0.5 * self.cells as f64 * self.cell_mm,
        };
        raw.with_energy(self.total)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An n × n orthogonal matrix (row-major): a product of Givens rotations at seeded angles.
    fn orthogonal(n: usize, seed: u64) -> Vec<f64> {
        let mut q = vec![0.0; n * n];
        for i in 0..n {
            q[i * n + i] = 1.0;
        }
        for k in 0..4 * n * n {
            let h = sss_util::splitmix64(seed.wrapping_mul(1_000_003) + k as u64);
            let (i, j) = ((h % n as u64) as usize, ((h >> 20) % n as u64) as usize);
            if i == j {
                continue;
            }
            let a = (h >> 40) as f64 / (1u64 << 24) as f64 * std::f64::consts::TAU;
            let (sn, cs) = a.sin_cos();
            for r in 0..n {
                let (x, y) = (q[r * n + i], q[r * n + j]);
                q[r * n + i] = cs * x - sn * y;
                q[r * n + j] = sn * x + cs * y;
            }
        }
        q
    }

    /// Jacobi's SVD against matrices built as U Σ Vᵀ with known singular values: distinct,
    /// repeated, spanning 10¹² and exactly zero (rank deficient). The values come back to
    /// 10⁻¹³ relative (of the largest), U and V orthonormal, U Σ Vᵀ the matrix.
    #[test]
    fn jacobi_svd_recovers_constructed_singular_values() {
        let cases: [(usize, Vec<f64>); 4] = [
            (7, vec![9.0, 5.0, 4.0, 2.5, 1.0, 0.5, 0.25]),
            (6, vec![3.0, 3.0, 3.0, 1.0, 1.0, 1e-3]),
            (9, (0..9i32).map(|i| 10f64.powi(-i * 3 / 2)).collect()),
            (8, vec![4.0, 2.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
        ];
        for (case, (n, sigma)) in cases.into_iter().enumerate() {
            let (u0, v0) = (
                orthogonal(n, 2 * case as u64 + 1),
                orthogonal(n, 2 * case as u64 + 2),
            );
            let mut a = vec![0.0; n * n];
            for r in 0..n {
                for c in 0..n {
                    a[r * n + c] = (0..n)
                        .map(|k| u0[r * n + k] * sigma[k] * v0[c * n + k])
                        .sum();
                }
            }
            let got = jacobi_svd(&a, n).unwrap();
            let top = sigma[0];
            for (k, (g, want)) in got.singular_values.iter().zip(&sigma).enumerate() {
                assert!(
                    (g - want).abs() <= 1e-13 * top,
                    "case {case}: s{k} = {g} vs {want}"
                );
            }
            let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
            for i in 0..n {
                for j in 0..n {
                    let want = if i == j { 1.0 } else { 0.0 };
                    let (ui, uj) = (&got.u[i * n..(i + 1) * n], &got.u[j * n..(j + 1) * n]);
                    let (vi, vj) = (&got.v[i * n..(i + 1) * n], &got.v[j * n..(j + 1) * n]);
                    assert!(
                        (dot(vi, vj) - want).abs() < 1e-12,
                        "case {case}: V not orthonormal"
                    );
                    if got.singular_values[i] > 1e-9 * top && got.singular_values[j] > 1e-9 * top
                        || sigma[i] == 0.0
                    {
                        assert!(
                            (dot(ui, uj) - want).abs() < 1e-9,
                            "case {case}: U columns {i}, {j}: {}",
                            dot(ui, uj)
                        );
                    }
                }
            }
            for r in 0..n {
                for c in 0..n {
                    let back: f64 = (0..n)
                        .map(|k| got.u[k * n + r] * got.singular_values[k] * got.v[k * n + c])
                        .sum();
                    assert!((back - a[r * n + c]).abs() <= 1e-13 * top, "case {case}");
                }
            }
            // Each pair is signed so that Σ vᵢ ≥ 0.
            assert!((0..n).all(|i| got.v[i * n..(i + 1) * n].iter().sum::<f64>() >= 0.0));
        }
    }

    #[test]
    fn jacobi_svd_refuses_bad_input() {
        assert!(
            jacobi_svd(&[1.0, 2.0, 3.0], 2)
                .unwrap_err()
                .contains("3 values")
        );
        assert!(
            jacobi_svd(&[1.0, f64::NAN, 0.0, 1.0], 2)
                .unwrap_err()
                .contains("non-finite")
        );
        // The zero matrix: all singular values 0, U and V still orthonormal bases.
        let z = jacobi_svd(&[0.0; 9], 3).unwrap();
        assert_eq!(z.singular_values, vec![0.0; 3]);
        let u = &z.u;
        for i in 0..3 {
            let norm: f64 = u[i * 3..(i + 1) * 3].iter().map(|x| x * x).sum();
            assert!((norm - 1.0).abs() < 1e-15);
        }
        // A 0 × 0 matrix is an empty decomposition.
        assert!(jacobi_svd(&[], 0).unwrap().singular_values.is_empty());
    }

    #[test]
    fn a_separable_matrix_has_rank_one() {
        // A product of two 1D Gaussians is exactly rank 1.
        let k = Kernel2d::from_density(21, 0.25, 2, |x, y| {
            let g = (-(x * x) / 2.0).exp() * (-(y * y) / 0.5).exp();
            [g, 2.0 * g, 0.5 * g]
        })
        .unwrap();
        let s = decompose(&k).unwrap();
        for c in 0..3 {
            let sp = s.spectrum(c);
            assert!(sp[1] < 1e-13 * sp[0], "{:?}", &sp[..3]);
        }
        let sep = s.separable(1, TapPlacement::Grid).unwrap();
        let t = sep.total_weight();
        for c in 0..3 {
            assert!(((t[c] - k.total[c]) / k.total[c]).abs() < 1e-12);
        }
        assert!(s.separable(0, TapPlacement::Grid).is_err());
        assert!(s.separable(7, TapPlacement::Grid).is_err());
        assert!(s.separable(1, TapPlacement::Importance(7)).is_err());
    }
}
