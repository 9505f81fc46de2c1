//! Histopolation: the knot values of a spline whose integral over every tally bin equals its
//! tally, as a square linear system over the spline knots ([`Histopolation`]).

use super::*;
use crate::BssrdfError;
use crate::catmull_rom::catmull_rom_weights;
use crate::quadrature::gauss_legendre;

/// Where the extra spline knot of [`spline_knots`] sits in the first tally bin [0, x₁], as a
/// fraction of x₁.
const NEAR_ORIGIN_KNOT: f64 = 0.1;

/// The knots of the table's splines: the tally knots ([`radius_knots`]) with one more at
/// 0.1 x₁. The spline must be 0 at x = 0 (it is 2πx R_d), while the tallied profile T(x) tends
/// to a positive constant there (single scattering makes R_d ∝ 1/r near the entry point), so
/// a spline from 0 straight to x₁ would miss half of the first bin's light (≈ 0.3 % of the
/// total at albedo 0.8); with the extra knot the first bin's tally is fitted like the others.
pub fn spline_knots(knots: &[f64]) -> Vec<f64> {
    let mut x = Vec::with_capacity(knots.len() + 1);
    x.push(0.0);
    if knots.len() >= 2 {
        x.push(NEAR_ORIGIN_KNOT * knots[1]);
        x.extend_from_slice(&knots[1..]);
    }
    x
}

/// The histopolation system of the tally bins of a knot vector ([`tally_edges`]) and the
/// splines on its [`spline_knots`]: the matrix A with A_kj = ∫_{bin k} φ_j, φ_j the Catmull-Rom
/// cardinal function of spline knot j (the spline through the unit vector e_j), for every bin
/// k and every spline knot but the first (fixed at 0) — as many knots as bins —
/// LU-factorised with partial pivoting (Golub & Van Loan, *Matrix Computations*,
/// Algorithm 3.4.1).
#[derive(Clone, Debug)]
pub struct Histopolation {
    n: usize,
    lu: Vec<f64>,
    pivot: Vec<usize>,
}

impl Histopolation {
    /// The system of the tally `knots` (x₀ = 0, increasing). Each bin is split at the spline
    /// knots it contains and integrated with 3-point Gauss-Legendre, exact for the cubic
    /// pieces.
    pub fn new(knots: &[f64]) -> Result<Histopolation, BssrdfError> {
        let n_knots = knots.len();
        if n_knots < 3 || knots[0] != 0.0 || !knots.windows(2).all(|w| w[0] < w[1]) {
            return Err(BssrdfError::InvalidArgument(
                "histopolation: need ≥ 3 increasing knots from 0".into(),
            ));
        }
        let edges = tally_edges(knots);
        let xs = spline_knots(knots);
        let n = n_knots;
        let mut a = vec![0.0; n * n];
        let (gx, gw) = gauss_legendre(3);
        for k in 0..n {
            let (lo, hi) = (edges[k], edges[k + 1]);
            let mut cuts = vec![lo];
            cuts.extend(xs.iter().copied().filter(|&x| x > lo && x < hi));
            cuts.push(hi);
            for w in cuts.windows(2) {
                let (half, mid) = (0.5 * (w[1] - w[0]), 0.5 * (w[1] + w[0]));
                for (xi, wi) in gx.iter().zip(gw) {
                    let Some((offset, cw)) = catmull_rom_weights(&xs, mid + half * xi) else {
                        continue;
                    };
                    for (m, c) in cw.iter().enumerate() {
                        let j = offset + m as isize;
                        if *c != 0.0 && j >= 1 {
                            a[k * n + (j as usize - 1)] += half * wi * c;
                        }
                    }
                }
            }
        }
        // LU with partial pivoting, in place.
        let mut pivot = vec![0; n];
        for col in 0..n {
            let p = (col..n)
                .max_by(|&x, &y| a[x * n + col].abs().total_cmp(&a[y * n + col].abs()))
                .unwrap_or(col);
            if !(a[p * n + col].abs() > 0.0) {
                return Err(BssrdfError::InvalidArgument(
                    "histopolation: singular system".into(),
                ));
            }
            pivot[col] = p;
            if p != col {
                for c in 0..n {
                    a.swap(p * n + c, col * n + c);
                }
            }
            let d = a[col * n + col];
            for row in col + 1..n {
                let f = a[row * n + col] / d;
                a[row * n + col] = f;
                if f != 0.0 {
                    for c in col + 1..n {
                        a[row * n + c] -= f * a[col * n + c];
                    }
                }
            }
        }
        Ok(Histopolation { n, lu: a, pivot })
    }

    /// The values at spline knots 1.. (see [`spline_knots`]; knot 0 is 0) whose spline
    /// integrates to `masses[k]` over tally bin k, for every bin.
    pub fn solve(&self, masses: &[f64]) -> Vec<f64> {
        let n = self.n;
        let mut x: Vec<f64> = (0..n)
            .map(|k| masses.get(k).copied().unwrap_or(0.0))
            .collect();
        for col in 0..n {
            x.swap(col, self.pivot[col]);
        }
        // Forward substitution with the unit lower triangle, then back substitution.
        for row in 0..n {
            let lower = &self.lu[row * n..row * n + row];
            let s: f64 = lower.iter().zip(&x[..row]).map(|(l, v)| l * v).sum();
            x[row] -= s;
        }
        for row in (0..n).rev() {
            let upper = &self.lu[row * n + row + 1..(row + 1) * n];
            let s: f64 = upper.iter().zip(&x[row + 1..]).map(|(u, v)| u * v).sum();
            x[row] = (x[row] - s) / self.lu[row * n + row];
        }
        x
    }
}
