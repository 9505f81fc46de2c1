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

#![forbid(unsafe_code)]

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

/// Radius (mm) of the sphere in [`Frame::closeup`]: a head's size.
pub const CLOSEUP_RADIUS_MM: f64 = 90.0;

/// Footprint (mm per pixel) at the centre of [`Frame::closeup`].
pub const CLOSEUP_MM_PER_PIXEL: f64 = 0.06;

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

    /// The `1080p-closeup` frame: the same texture on a face-sized sphere (radius
    /// [`CLOSEUP_RADIUS_MM`], a head's) seen in an orthographic close-up that the sphere fills,
    /// [`CLOSEUP_MM_PER_PIXEL`] across at its centre. A pixel at distance ρ (mm) from the
    /// centre sees the surface tilted by θ with sin θ = ρ / R, so its footprint is
    /// 0.06 / cos θ mm (0.060 at the centre to 0.088 in the corners of a 1920 × 1080 frame)
    /// and its depth 600 + R − R cos θ mm. At this scale a skin kernel's taps land tens of
    /// pixels from the centre: the close-ups engine developers render most often.
    pub fn closeup(width: usize, height: usize) -> Frame {
        let mut f = Frame::new(width, height);
        let (cx, cy) = (0.5 * width as f64, 0.5 * height as f64);
        let r = CLOSEUP_RADIUS_MM;
        for (i, (d, m)) in f.depth.iter_mut().zip(&mut f.mm_per_pixel).enumerate() {
            let u = ((i % width) as f64 + 0.5 - cx) * CLOSEUP_MM_PER_PIXEL;
            let v = ((i / width) as f64 + 0.5 - cy) * CLOSEUP_MM_PER_PIXEL;
            // Frames larger than the sphere clamp at a grazing 0.05 (never a zero cosine).
            let cos = (1.0 - (u * u + v * v) / (r * r)).max(0.0025).sqrt();
            *m = (CLOSEUP_MM_PER_PIXEL / cos) as f32;
            *d = (600.0 + r * (1.0 - cos)) as f32;
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

    #[test]
    fn closeup_is_a_sphere_at_the_stated_scale() {
        let f = Frame::closeup(1920, 1080);
        let (lo, hi) = f
            .mm_per_pixel
            .iter()
            .fold((f32::MAX, 0.0f32), |(a, b), &m| (a.min(m), b.max(m)));
        // The close-up range, 0.05-0.1 mm a pixel: 0.06 at the centre, 1/cos θ out.
        assert!(
            (lo - 0.06).abs() < 1e-4 && hi > 0.085 && hi < 0.09,
            "{lo} {hi}"
        );
        // Depth and footprint on one sphere: depth − 600 = R (1 − 0.06 / footprint).
        for i in [0, 1919, 960 * 1080 + 7, 1920 * 1080 - 1, 540 * 1920 + 960] {
            let want = CLOSEUP_RADIUS_MM * (1.0 - CLOSEUP_MM_PER_PIXEL / f.mm_per_pixel[i] as f64);
            assert!((f.depth[i] as f64 - 600.0 - want).abs() < 1e-3, "pixel {i}");
        }
        // A frame wider than the sphere stays finite.
        let g = Frame::closeup(6000, 100);
        assert!(
            g.mm_per_pixel
                .iter()
                .chain(&g.depth)
                .all(|v| v.is_finite() && *v > 0.0)
        );
    }
}
