//! Low-rank separable approximations of the 2D kernel by singular value decomposition
//! (Jimenez et al. 2015, §3, Eq. 2 and Figures 2 and 4).
//!
//! Per channel, the N × N mass matrix K (rows y, columns x) is decomposed as
//! K = Σᵢ sᵢ uᵢ vᵢᵀ with faer (sequential: faer is built without its `rayon` feature and the
//! decomposition is called with `Par::Seq`). By Eckart–Young the rank-k truncation is the best
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
use faer::Mat;
use faer::Par;
use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::svd::{ComputeSvdVectors, svd, svd_scratch};

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

/// Decomposes every channel of `kernel`.
pub fn decompose(kernel: &Kernel2d) -> Result<SvdKernel, SeparableError> {
    let n = kernel.cells;
    let mut channels = Vec::with_capacity(3);
    for c in 0..3 {
        let a = Mat::<f64>::from_fn(n, n, |i, j| kernel.mass[c][i * n + j]);
        let mut s = Diag::<f64>::zeros(n);
        let mut u = Mat::<f64>::zeros(n, n);
        let mut v = Mat::<f64>::zeros(n, n);
        let par = Par::Seq;
        let mut buf = MemBuffer::new(svd_scratch::<f64>(
            n,
            n,
            ComputeSvdVectors::Full,
            ComputeSvdVectors::Full,
            par,
            Default::default(),
        ));
        svd(
            a.as_ref(),
            s.as_mut(),
            Some(u.as_mut()),
            Some(v.as_mut()),
            par,
            MemStack::new(&mut buf),
            Default::default(),
        )
        .map_err(|e| SeparableError::Svd(format!("{e:?}")))?;
        let sv: Vec<f64> = (0..n).map(|i| s.column_vector()[i]).collect();
        let flat = |m: &Mat<f64>| -> Vec<f64> {
            let mut out = Vec::with_capacity(n * n);
            for i in 0..n {
                for r in 0..n {
                    out.push(m[(r, i)]);
                }
            }
            out
        };
        let ch = SvdChannel {
            singular_values: sv,
            u: flat(&u),
            v: flat(&v),
        };
        let finite = ch
            .singular_values
            .iter()
            .chain(&ch.u)
            .chain(&ch.v)
            .all(|x| x.is_finite());
        if !finite {
            return Err(SeparableError::Svd(format!(
                "non-finite result in channel {c}"
            )));
        }
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
