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

/// A screen-space filter frame of the benchmarks (`benches/separable.rs`, `benches/gpu.rs`):
/// the irradiance, depth (mm), object ids and footprint (mm per pixel) of every pixel.
pub struct Frame {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Irradiance per pixel.
    pub irradiance: Vec<[f32; 3]>,
    /// Depth per pixel (mm).
    pub depth: Vec<f32>,
    /// Object id per pixel (all 0: one object).
    pub mask: Vec<u32>,
    /// Footprint per pixel (mm).
    pub mm_per_pixel: Vec<f32>,
}

impl Frame {
    /// The `1080p` frame at its size: a random two-level texture (10 % dark) at 0.5 mm per
    /// pixel, depth growing slowly across the frame (under the rejection threshold).
    pub fn new(width: usize, height: usize) -> Frame {
        let n = width * height;
        let u = uniforms(n, 11);
        Frame {
            width,
            height,
            irradiance: u
                .iter()
                .map(|v| if *v < 0.1 { [0.1; 3] } else { [1.0, 0.9, 0.8] })
                .collect(),
            depth: (0..n).map(|i| 600.0 + (i % width) as f32 * 0.05).collect(),
            mask: vec![0; n],
            mm_per_pixel: vec![0.5; n],
        }
    }

    /// The `1080p-tilted` frame: the same texture on a surface whose footprint grows across
    /// the frame (0.3 to 0.75 mm per pixel), so every pixel's taps differ from its neighbours'.
    pub fn tilted(width: usize, height: usize) -> Frame {
        let mut f = Frame::new(width, height);
        let (wf, hf) = (width.max(2) as f32 - 1.0, height.max(2) as f32 - 1.0);
        for (i, (d, m)) in f.depth.iter_mut().zip(&mut f.mm_per_pixel).enumerate() {
            let (x, y) = ((i % width) as f32, (i / width) as f32);
            *m = 0.3 + 0.4 * x / wf + 0.05 * y / hf;
            *d = 600.0 + 0.1 * x + 0.05 * y;
        }
        f
    }

    /// The frame as the filter's input.
    pub fn input(&self) -> sss_separable::ScreenInput<'_> {
        sss_separable::ScreenInput {
            width: self.width,
            height: self.height,
            irradiance: &self.irradiance,
            depth: &self.depth,
            mask: &self.mask,
            mm_per_pixel: &self.mm_per_pixel,
        }
    }
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
