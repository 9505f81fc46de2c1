//! Shared inputs of the integration tests.
#![allow(dead_code)]

use sss_bssrdf::{Bssrdf, Medium, ModelKind, make_model};
use sss_separable::{
    Kernel2d, Kernel2dSpec, NO_OBJECT, ScreenInput, SeparableKernel, TapPlacement, gaussians,
    preintegrated, svd,
};

/// The better dipole for a measured material.
pub fn model(preset: &str) -> Box<dyn Bssrdf> {
    make_model(
        ModelKind::BetterDipole,
        &Medium::preset(preset).expect("preset"),
    )
}

/// The model's kernel on an N × N grid holding 99 % of the energy.
pub fn kernel2d(m: &dyn Bssrdf, cells: usize) -> Kernel2d {
    Kernel2d::from_model(
        m,
        &Kernel2dSpec {
            cells,
            ..Default::default()
        },
    )
    .expect("kernel")
}

/// The screen-space tests' kernels (skin1, 31² grid): pre-integrated with 7 importance taps,
/// SVD rank 3 (signed terms) and 3 Gaussians (several terms).
pub fn screen_kernels() -> Vec<(&'static str, SeparableKernel)> {
    let m = model("skin1");
    let k = kernel2d(m.as_ref(), 31);
    let g = gaussians::fit_model(m.as_ref(), 3).unwrap();
    vec![
        (
            "pre-integrated 7",
            preintegrated::kernel(&k, TapPlacement::Importance(7)).unwrap(),
        ),
        (
            "svd rank 3",
            svd::decompose(&k)
                .unwrap()
                .separable(3, TapPlacement::Grid)
                .unwrap(),
        ),
        (
            "3 gaussians",
            g[2].kernel(k.total, TapPlacement::Importance(7)).unwrap(),
        ),
    ]
}

/// Owned buffers of a screen-space test image.
pub struct Frame {
    pub width: usize,
    pub height: usize,
    pub irradiance: Vec<[f32; 3]>,
    pub depth: Vec<f32>,
    pub mask: Vec<u32>,
    pub mm_per_pixel: Vec<f32>,
}

impl Frame {
    /// One flat object (id 0) at depth 1000 mm, zero irradiance.
    pub fn flat(width: usize, height: usize, mm_per_pixel: f32) -> Frame {
        let n = width * height;
        Frame {
            width,
            height,
            irradiance: vec![[0.0; 3]; n],
            depth: vec![1000.0; n],
            mask: vec![0; n],
            mm_per_pixel: vec![mm_per_pixel; n],
        }
    }

    pub fn input(&self) -> ScreenInput<'_> {
        ScreenInput {
            width: self.width,
            height: self.height,
            irradiance: &self.irradiance,
            depth: &self.depth,
            mask: &self.mask,
            mm_per_pixel: &self.mm_per_pixel,
        }
    }

    pub fn set_irradiance(&mut self, f: impl Fn(usize, usize) -> f32) {
        for y in 0..self.height {
            for x in 0..self.width {
                self.irradiance[y * self.width + x] = [f(x, y); 3];
            }
        }
    }
}

/// A deterministic hash in [0, 1) (for test textures).
pub fn hash01(x: usize, y: usize) -> f32 {
    let mut z = (x as u64) << 32 ^ (y as u64) ^ 0x1234_5678;
    z = (z ^ (z >> 33)).wrapping_mul(0xff51_afd7_ed55_8ccd);
    z = (z ^ (z >> 33)).wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    z ^= z >> 33;
    (z >> 40) as f32 / (1u64 << 24) as f32
}

pub const BACKGROUND: u32 = NO_OBJECT;
