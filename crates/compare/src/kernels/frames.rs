//! The experiment's test images: the diagonal shadow edge with a bright spot, and the single
//! lit pixel of the point-light response.

use super::*;

/// Millimetres per pixel of the test images: skin1's red kernel spans ~100 pixels.
pub(super) const MM_PER_PIXEL: f32 = 0.1;

/// Side of the error test image.
pub(super) const TEST_SIDE: usize = 256;

/// A test image: irradiance, mask, depth and footprint buffers.
pub(super) struct Frame {
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) irradiance: Vec<[f32; 3]>,
    pub(super) depth: Vec<f32>,
    pub(super) mask: Vec<u32>,
    pub(super) mm: Vec<f32>,
}

impl Frame {
    /// A diagonal shadow edge (lit below the line y = 0.6 x + 0.2 h) plus a bright 3-pixel spot
    /// in the shadow, one object, constant depth.
    pub(super) fn edge(width: usize, height: usize) -> Frame {
        let mut irradiance = vec![[0.0f32; 3]; width * height];
        let (sx, sy) = (width as f64 * 0.7, height as f64 * 0.25);
        for y in 0..height {
            for x in 0..width {
                let lit = (y as f64) > 0.6 * x as f64 + 0.2 * height as f64;
                let spot = ((x as f64 - sx).powi(2) + (y as f64 - sy).powi(2)) < 2.25;
                let v = if spot {
                    20.0
                } else if lit {
                    1.0
                } else {
                    0.0
                };
                irradiance[y * width + x] = [v; 3];
            }
        }
        Frame {
            width,
            height,
            irradiance,
            depth: vec![1000.0; width * height],
            mask: vec![0; width * height],
            mm: vec![MM_PER_PIXEL; width * height],
        }
    }

    /// One lit pixel in the middle (the point-light response).
    pub(super) fn point(side: usize) -> Frame {
        let mut f = Frame::edge(side, side);
        f.irradiance = vec![[0.0; 3]; side * side];
        f.irradiance[(side / 2) * side + side / 2] = [1.0; 3];
        f
    }

    pub(super) fn input(&self) -> ScreenInput<'_> {
        ScreenInput {
            width: self.width,
            height: self.height,
            irradiance: &self.irradiance,
            depth: &self.depth,
            mask: &self.mask,
            mm_per_pixel: &self.mm,
        }
    }
}

/// A test image's `f32` pixels as the renderer's colours.
pub(super) fn to_rgb(v: &[[f32; 3]]) -> Vec<Rgb> {
    v.iter()
        .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
        .collect()
}
