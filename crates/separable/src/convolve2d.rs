//! Ground truths: exact 2D convolutions with the full (non-separable) kernel.
//!
//! - [`exact`]: the screen-space reference for [`crate::screen_space::filter`]: at every
//!   pixel, the brute-force sum over all N × N cells of a [`Kernel2d`] at the pixel's own
//!   footprint (offset in mm / mm_per_pixel, bilinear fetch, clamp to edge), with the same
//!   footprint, silhouette and renormalisation rules, accumulated in f64. Cost N² taps per
//!   pixel: use it on small images or coarse kernels.
//! - [`grid_full`] / [`grid_separable`]: f64 "kernel-space" convolutions of an image whose
//!   pixels are the kernel's cells (one pixel = one cell, clamp to edge), free of f32 and
//!   footprint effects: the setting of the paper's Figure 7 (step-edge responses) and of
//!   the exactness of the pre-integrated kernel (§4).

use crate::Rgb;
use crate::error::{SeparableError, ensure};
use crate::kernel::SeparableKernel;
use crate::kernel2d::Kernel2d;
use crate::screen_space::{FilterOptions, NO_OBJECT, Rules, ScreenInput};
use rayon::prelude::*;

/// The exact screen-space convolution of `input` with the full kernel `kernel` (see the
/// module documentation). `opts.jitter_radius` is ignored (the full kernel is radial).
pub fn exact(
    input: &ScreenInput,
    kernel: &Kernel2d,
    opts: &FilterOptions,
) -> Result<Vec<[f32; 3]>, SeparableError> {
    input.validate()?;
    ensure(opts.depth_threshold > 0.0, || {
        "depth_threshold must be positive".into()
    })?;
    let (w, hgt) = (input.width, input.height);
    let n = kernel.cells;
    let rules = Rules::new(kernel.half_width_mm(), opts);
    let sum: Rgb = kernel.total;
    let one_signed: [bool; 3] = std::array::from_fn(|c| {
        kernel.mass[c].iter().all(|m| *m >= 0.0) || kernel.mass[c].iter().all(|m| *m <= 0.0)
    });
    let offsets: Vec<f64> = (0..n).map(|i| kernel.offset_mm(i)).collect();
    let mut out = vec![[0.0f32; 3]; w * hgt];
    out.par_chunks_mut(w.max(1))
        .enumerate()
        .for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let i = y * w + x;
                let id = input.mask[i];
                if id == NO_OBJECT {
                    *o = [0.0; 3];
                    continue;
                }
                let centre = input.irradiance[i];
                let Some(inv) = rules.inverse_scale(input.mm_per_pixel[i]) else {
                    *o = std::array::from_fn(|c| (centre[c] as f64 * sum[c]) as f32);
                    continue;
                };
                let inv = inv as f64;
                let d0 = input.depth[i];
                let mut acc = [0.0f64; 3];
                let mut dropped = [0.0f64; 3];
                let mut any = false;
                for iy in 0..n {
                    let sy = y as f64 - offsets[iy] * inv;
                    let y0 = sy.floor();
                    let fy = sy - y0;
                    for ix in 0..n {
                        let sx = x as f64 - offsets[ix] * inv;
                        let x0 = sx.floor();
                        let fx = sx - x0;
                        let m = [
                            kernel.mass[0][iy * n + ix],
                            kernel.mass[1][iy * n + ix],
                            kernel.mass[2][iy * n + ix],
                        ];
                        for (dx, dy, bw) in [
                            (0, 0, (1.0 - fx) * (1.0 - fy)),
                            (1, 0, fx * (1.0 - fy)),
                            (0, 1, (1.0 - fx) * fy),
                            (1, 1, fx * fy),
                        ] {
                            if bw == 0.0 {
                                continue;
                            }
                            let px = (x0 as i64 + dx).clamp(0, w as i64 - 1) as usize;
                            let py = (y0 as i64 + dy).clamp(0, hgt as i64 - 1) as usize;
                            let j = py * w + px;
                            if input.mask[j] != id || (input.depth[j] - d0).abs() > rules.depth_mm {
                                any = true;
                                for c in 0..3 {
                                    dropped[c] += bw * m[c];
                                }
                            } else {
                                let s = input.irradiance[j];
                                for c in 0..3 {
                                    acc[c] += bw * m[c] * s[c] as f64;
                                }
                            }
                        }
                    }
                }
                *o = std::array::from_fn(|c| {
                    let v = if !any {
                        acc[c]
                    } else {
                        let kept = sum[c] - dropped[c];
                        if one_signed[c] && kept * sum[c] > 0.0 && kept.abs() > 1e-6 * sum[c].abs()
                        {
                            acc[c] * sum[c] / kept
                        } else {
                            acc[c] + dropped[c] * centre[c] as f64
                        }
                    };
                    v as f32
                });
            }
        });
    Ok(out)
}

fn check_image(image: &[Rgb], width: usize, height: usize) -> Result<(), SeparableError> {
    let n = width
        .checked_mul(height)
        .ok_or_else(|| SeparableError::InvalidArgument("width × height overflows".into()))?;
    if image.len() != n {
        return Err(SeparableError::BufferSize {
            what: "image",
            expected: n,
            got: image.len(),
        });
    }
    ensure(n > 0, || "empty image".into())
}

/// Discrete 2D convolution (f64) of `image` (width × height, one pixel = one kernel cell)
/// with every cell of `kernel`: out(p) = Σ_cells mass · image(clamp(p − offset)).
pub fn grid_full(
    image: &[Rgb],
    width: usize,
    height: usize,
    kernel: &Kernel2d,
) -> Result<Vec<Rgb>, SeparableError> {
    check_image(image, width, height)?;
    let n = kernel.cells as i64;
    let half = n / 2;
    let mut out = vec![[0.0; 3]; width * height];
    out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let mut acc = [0.0; 3];
            for iy in 0..n {
                let py = (y as i64 - (iy - half)).clamp(0, height as i64 - 1) as usize;
                for ix in 0..n {
                    let px = (x as i64 - (ix - half)).clamp(0, width as i64 - 1) as usize;
                    let s = image[py * width + px];
                    let k = (iy * n + ix) as usize;
                    for c in 0..3 {
                        acc[c] += kernel.mass[c][k] * s[c];
                    }
                }
            }
            *o = acc;
        }
    });
    Ok(out)
}

/// Separable convolution (f64) of `image` with `kernel` on a grid of `cell_mm` per pixel:
/// per term a horizontal then a vertical pass, offsets offset_mm / cell_mm pixels, linear
/// interpolation, clamp to edge; terms summed.
pub fn grid_separable(
    image: &[Rgb],
    width: usize,
    height: usize,
    kernel: &SeparableKernel,
    cell_mm: f64,
) -> Result<Vec<Rgb>, SeparableError> {
    check_image(image, width, height)?;
    ensure(cell_mm > 0.0 && cell_mm.is_finite(), || {
        format!("cell_mm = {cell_mm} must be positive and finite")
    })?;
    let mut out = vec![[0.0; 3]; width * height];
    let mut tmp = vec![[0.0; 3]; width * height];
    let pass = |src: &[Rgb], dst: &mut [Rgb], k: &crate::kernel::Kernel1d, vertical: bool| {
        dst.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let mut acc = [0.0; 3];
                for t in &k.taps {
                    let s = if vertical { y as f64 } else { x as f64 } - t.offset_mm / cell_mm;
                    let s0 = s.floor();
                    let f = s - s0;
                    let lim = if vertical { height } else { width } as i64 - 1;
                    for (d, bw) in [(0, 1.0 - f), (1, f)] {
                        if bw == 0.0 {
                            continue;
                        }
                        let q = (s0 as i64 + d).clamp(0, lim) as usize;
                        let v = if vertical {
                            src[q * width + x]
                        } else {
                            src[y * width + q]
                        };
                        for c in 0..3 {
                            acc[c] += bw * t.weight[c] * v[c];
                        }
                    }
                }
                *o = acc;
            }
        });
    };
    let mut term_out = vec![[0.0; 3]; width * height];
    for term in &kernel.terms {
        pass(image, &mut tmp, &term.horizontal, false);
        pass(&tmp, &mut term_out, &term.vertical, true);
        for (o, t) in out.iter_mut().zip(&term_out) {
            for c in 0..3 {
                o[c] += t[c];
            }
        }
    }
    Ok(out)
}
