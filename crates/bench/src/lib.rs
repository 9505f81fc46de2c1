//! # sss-bench: criterion benchmarks of the subsurface-scattering toolkit
//!
//! The benchmarks live in `benches/` (run `cargo bench -p sss-bench -- --noplot`); this
//! library holds the fixed inputs they share, so every model is timed on exactly the same
//! radii and random numbers:
//!
//! ```
//! let r = sss_bench::radii(64);
//! let u = sss_bench::uniforms(64, 1);
//! assert_eq!(r.len(), 64);
//! assert!(u.iter().all(|x| (0.0..1.0).contains(x)));
//! ```
//!
//! ## Papers
//! None of its own: it times the models of `sss-bssrdf` (Jensen et al. 2001, d'Eon 2012,
//! Frisvad et al. 2014, Habel et al. 2013).

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// Smallest radius of [`radii`] (mm).
pub const R_MIN: f64 = 0.01;
/// Largest radius of [`radii`] (mm).
pub const R_MAX: f64 = 30.0;

/// `n` radii log-spaced from [`R_MIN`] to [`R_MAX`] mm, covering the peak and the tail of every
/// measured material's profile.
pub fn radii(n: usize) -> Vec<f64> {
    let (a, b) = (R_MIN.ln(), R_MAX.ln());
    (0..n)
        .map(|i| {
            let t = if n > 1 {
                i as f64 / (n - 1) as f64
            } else {
                0.0
            };
            (a + (b - a) * t).exp()
        })
        .collect()
}

/// `n` uniform numbers in [0, 1) from a PCG seeded with `seed` (deterministic).
pub fn uniforms(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    (0..n).map(|_| rng.random::<f64>()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inputs_are_fixed() {
        let r = radii(5);
        assert!((r[0] - R_MIN).abs() < 1e-15 && (r[4] - R_MAX).abs() < 1e-12);
        assert!(r.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(uniforms(8, 3), uniforms(8, 3));
        assert_ne!(uniforms(8, 3), uniforms(8, 4));
    }
}
