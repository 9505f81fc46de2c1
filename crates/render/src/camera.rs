//! The pinhole camera: primary rays and pixel-sample positions.

use crate::rng::{Stream, rng};
use glam::DVec3;
use rand::RngExt;
use sss_scene::Camera;

/// An orthonormal camera frame ready to generate rays.
#[derive(Clone, Debug)]
pub struct CameraFrame {
    origin: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    tan_half: f64,
    width: u32,
    height: u32,
}

impl CameraFrame {
    /// The frame of a (validated) camera.
    pub fn new(c: &Camera) -> Self {
        let forward = (c.target - c.position).normalize_or(DVec3::NEG_Z);
        let mut right = forward.cross(c.up).normalize_or_zero();
        if right == DVec3::ZERO {
            right = forward.any_orthonormal_vector();
        }
        let up = right.cross(forward);
        CameraFrame {
            origin: c.position,
            forward,
            right,
            up,
            tan_half: (c.vfov_deg.to_radians() * 0.5).tan(),
            width: c.width.max(1),
            height: c.height.max(1),
        }
    }

    /// Eye position.
    pub fn origin(&self) -> DVec3 {
        self.origin
    }

    /// The unit direction through image position (x, y), in pixels from the top-left corner.
    pub fn direction(&self, x: f64, y: f64) -> DVec3 {
        let h = self.height as f64;
        let w = self.width as f64;
        let sx = (2.0 * x / w - 1.0) * self.tan_half * (w / h);
        let sy = (1.0 - 2.0 * y / h) * self.tan_half;
        (self.forward + self.right * sx + self.up * sy).normalize()
    }

    /// The angle one pixel subtends at the image centre (radians): a surface at distance d seen
    /// head-on has a pixel footprint of d times this.
    pub fn pixel_angle(&self) -> f64 {
        2.0 * self.tan_half / self.height as f64
    }

    /// Projects a world point to image coordinates (pixels, top-left origin) if it is in front
    /// of the camera.
    pub fn project(&self, p: DVec3) -> Option<(f64, f64)> {
        let d = p - self.origin;
        let z = d.dot(self.forward);
        if !(z > 0.0) {
            return None;
        }
        let (w, h) = (self.width as f64, self.height as f64);
        let sx = d.dot(self.right) / (z * self.tan_half * (w / h));
        let sy = d.dot(self.up) / (z * self.tan_half);
        Some(((sx + 1.0) * 0.5 * w, (1.0 - sy) * 0.5 * h))
    }
}

/// The `n` sample positions inside pixel (px, py): the centre for n = 1, otherwise a jittered
/// Latin hypercube (n strata on each axis, shuffled), deterministic for the seed and pixel.
pub fn pixel_samples(seed: u64, pixel: u64, px: u32, py: u32, n: u32) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n.max(1) as usize);
    pixel_samples_into(seed, pixel, px, py, n, &mut out);
    out
}

/// [`pixel_samples`] written into `out` (cleared first), so that a loop over pixels can reuse
/// one buffer instead of allocating per pixel. The positions are bit-identical.
pub fn pixel_samples_into(
    seed: u64,
    pixel: u64,
    px: u32,
    py: u32,
    n: u32,
    out: &mut Vec<(f64, f64)>,
) {
    out.clear();
    let (x0, y0) = (px as f64, py as f64);
    if n <= 1 {
        out.push((x0 + 0.5, y0 + 0.5));
        return;
    }
    let mut r = rng(seed, Stream::Camera, pixel);
    // The y strata, shuffled (Fisher–Yates) in place in the second component.
    out.extend((0..n).map(|k| (0.0, k as f64)));
    for i in (1..n as usize).rev() {
        let j = r.random_range(0..=i);
        let (a, b) = (out[i].1, out[j].1);
        out[i].1 = b;
        out[j].1 = a;
    }
    for (k, s) in out.iter_mut().enumerate() {
        let fx = (k as f64 + r.random::<f64>()) / n as f64;
        let fy = (s.1 + r.random::<f64>()) / n as f64;
        *s = (x0 + fx, y0 + fy);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The jittered Latin hypercube written out directly: shuffle a stratum permutation, then
    /// jitter within the strata (the order of the random draws defines the positions).
    fn latin_hypercube(seed: u64, pixel: u64, px: u32, py: u32, n: u32) -> Vec<(f64, f64)> {
        let (x0, y0) = (px as f64, py as f64);
        if n <= 1 {
            return vec![(x0 + 0.5, y0 + 0.5)];
        }
        let mut r = rng(seed, Stream::Camera, pixel);
        let mut perm: Vec<u32> = (0..n).collect();
        for i in (1..n as usize).rev() {
            let j = r.random_range(0..=i);
            perm.swap(i, j);
        }
        let mut out = Vec::new();
        for k in 0..n {
            let fx = (k as f64 + r.random::<f64>()) / n as f64;
            let fy = (perm[k as usize] as f64 + r.random::<f64>()) / n as f64;
            out.push((x0 + fx, y0 + fy));
        }
        out
    }

    #[test]
    fn pixel_samples_into_reuses_its_buffer_and_matches_the_latin_hypercube() {
        let mut buf = vec![(f64::NAN, f64::NAN); 40];
        for n in [0, 1, 2, 3, 7, 16] {
            for pixel in [0u64, 1, 12345] {
                let (px, py) = ((pixel % 97) as u32, (pixel / 97) as u32);
                pixel_samples_into(3, pixel, px, py, n, &mut buf);
                let want = latin_hypercube(3, pixel, px, py, n);
                assert_eq!(buf, want, "n {n} pixel {pixel}");
                assert_eq!(pixel_samples(3, pixel, px, py, n), want);
                // One sample per stratum on each axis, inside the pixel.
                let m = n.max(1) as usize;
                let mut seen = (vec![0; m], vec![0; m]);
                for &(x, y) in &buf {
                    let (fx, fy) = (x - px as f64, y - py as f64);
                    assert!((0.0..1.0).contains(&fx) && (0.0..1.0).contains(&fy));
                    seen.0[(fx * m as f64) as usize] += 1;
                    seen.1[(fy * m as f64) as usize] += 1;
                }
                assert!(seen.0.iter().chain(&seen.1).all(|&c| c == 1), "n {n}");
            }
        }
    }
}
