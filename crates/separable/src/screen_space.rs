//! The screen-space separable filter (Jimenez et al. 2015, §6; Jimenez, Sundstedt, Gutierrez
//! 2009 for the screen-space formulation): the irradiance image is convolved with a
//! [`SeparableKernel`] as one horizontal and one vertical 1D pass per term, summed.
//!
//! Per pixel:
//! - **Footprint.** A tap's offset in pixels is its offset in mm divided by the pixel's
//!   `mm_per_pixel` (the world-space size of one pixel on that pixel's surface), fetched
//!   bilinearly (clamp to edge). Pixels whose kernel diameter, 2·[`SeparableKernel::support_mm`]
//!   / mm_per_pixel, is under [`FilterOptions::min_footprint_px`] skip the blur: output =
//!   irradiance × the kernel's total weight.
//! - **Jitter.** Each pixel rotates its filter axes by a pseudo-random angle (one of
//!   [`ROTATION_STEPS`]), a seeded hash of its coordinates ([`rotation_angle`], so the result
//!   is deterministic), applied to the taps
//!   closer than [`FilterOptions::jitter_radius`] × support (the paper rotates only taps
//!   within 10 % of the kernel size, §6, to keep GPU caches warm; 30 % for extreme
//!   close-ups). Rotation breaks the cross pattern of separable kernels; since R_d is radial,
//!   no re-weighting is needed.
//! - **Silhouettes.** Each of the (up to four) texels a tap reads is dropped when it belongs
//!   to another object id or its depth differs from the centre pixel's by more than
//!   [`FilterOptions::depth_threshold`] × support (mm). The kept taps are then renormalised by
//!   the total weight kept, per channel (for a channel whose weights change sign, as in SVD
//!   terms of rank ≥ 2, or when under 10⁻⁶ of the weight is kept, the dropped weight is given
//!   the centre pixel's value instead). Either way a constant irradiance is reproduced and no
//!   light crosses to another object.
//!
//! Cost: each tap is two texel reads along the axis (four, bilinear, for rotated taps); a
//! pixel whose texels all pass the silhouette test takes a branch-light path, the others a
//! per-texel one. On the CPU this is compute-bound (tens of instructions per tap), far from
//! the memory bound a GPU's texture units reach; see `crates/bench/benches/separable.rs`.
//!
//! Output: per pixel, the diffuse exitance E ∗ R_d (with [`crate::Energy::TotalReflectance`]
//! kernels); the caller applies its Fresnel / π factors. Background pixels
//! ([`NO_OBJECT`]) output 0. Rows are processed in parallel with rayon; every pixel's value
//! depends only on the inputs, so the result is identical for any thread count.

use crate::error::{SeparableError, ensure};
use crate::kernel::{Kernel1d, SeparableKernel};
use rayon::prelude::*;
use sss_util::splitmix64;

/// The `mask` value of pixels that show no translucent object.
pub const NO_OBJECT: u32 = u32::MAX;

/// The screen-space inputs, as plain row-major buffers of `width × height` pixels.
#[derive(Clone, Copy, Debug)]
pub struct ScreenInput<'a> {
    /// Image width (pixels).
    pub width: usize,
    /// Image height (pixels).
    pub height: usize,
    /// Irradiance per pixel (any linear unit; the output has the same unit), finite.
    pub irradiance: &'a [[f32; 3]],
    /// View-space distance per pixel, in mm (the kernel's unit).
    pub depth: &'a [f32],
    /// Object id per pixel, [`NO_OBJECT`] for none.
    pub mask: &'a [u32],
    /// World-space size (mm) of one pixel at that pixel's surface.
    pub mm_per_pixel: &'a [f32],
}

impl ScreenInput<'_> {
    /// Checks that every buffer has width × height elements.
    pub fn validate(&self) -> Result<(), SeparableError> {
        let n = self
            .width
            .checked_mul(self.height)
            .ok_or_else(|| SeparableError::InvalidArgument("width × height overflows".into()))?;
        for (what, got) in [
            ("irradiance", self.irradiance.len()),
            ("depth", self.depth.len()),
            ("mask", self.mask.len()),
            ("mm_per_pixel", self.mm_per_pixel.len()),
        ] {
            if got != n {
                return Err(SeparableError::BufferSize {
                    what,
                    expected: n,
                    got,
                });
            }
        }
        ensure(
            self.width <= i32::MAX as usize && self.height <= i32::MAX as usize,
            || "image too large".into(),
        )
    }
}

/// Options of the screen-space filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterOptions {
    /// Taps closer than this fraction of the kernel's support are rotated by the pixel's
    /// random angle (0 = no jitter, 1 = every tap; default 0.1 as in the paper).
    pub jitter_radius: f32,
    /// Seed of the per-pixel rotation hash.
    pub seed: u64,
    /// A texel is dropped when |Δdepth| > depth_threshold × support (mm) (default 1).
    pub depth_threshold: f32,
    /// Pixels whose kernel diameter is below this many pixels skip the blur (default 1).
    pub min_footprint_px: f32,
}

impl Default for FilterOptions {
    fn default() -> Self {
        FilterOptions {
            jitter_radius: 0.1,
            seed: 0,
            depth_threshold: 1.0,
            min_footprint_px: 1.0,
        }
    }
}

impl FilterOptions {
    fn validate(&self) -> Result<(), SeparableError> {
        ensure(
            self.jitter_radius >= 0.0 && self.jitter_radius.is_finite(),
            || {
                format!(
                    "jitter_radius = {} must be finite and ≥ 0",
                    self.jitter_radius
                )
            },
        )?;
        ensure(self.depth_threshold > 0.0, || {
            format!(
                "depth_threshold = {} must be positive",
                self.depth_threshold
            )
        })?;
        ensure(
            self.min_footprint_px >= 0.0 && self.min_footprint_px.is_finite(),
            || {
                format!(
                    "min_footprint_px = {} must be finite and ≥ 0",
                    self.min_footprint_px
                )
            },
        )
    }
}

/// Number of distinct rotation angles (the hash picks one of them; a table of their cosines
/// and sines replaces a `sin_cos` per pixel).
pub const ROTATION_STEPS: usize = 256;

/// SplitMix64 hash of the pixel coordinates and `seed`, reduced to a rotation index.
#[inline(always)]
fn rotation_index(x: usize, y: usize, seed: u64) -> usize {
    let z = splitmix64(seed.wrapping_add(((y as u64) << 32) ^ (x as u64)));
    (z >> 56) as usize % ROTATION_STEPS
}

/// The rotation angle (radians, in [0, 2π), a multiple of 2π/[`ROTATION_STEPS`]) of pixel
/// (x, y): a SplitMix64 hash of the coordinates and `seed`. Deterministic.
pub fn rotation_angle(x: usize, y: usize, seed: u64) -> f32 {
    rotation_index(x, y, seed) as f32 * (std::f32::consts::TAU / ROTATION_STEPS as f32)
}

/// ⌊x⌋ for |x| < 2³¹ without a libm call (x86-64 without SSE4.1 has no rounding instruction).
#[inline(always)]
fn floor_i32(x: f32) -> i32 {
    let i = x as i32;
    i - ((i as f32) > x) as i32
}

/// The four texels (indices into a row-major image of width `w`, clamped to the edges
/// `wmax`, `hmax`) and the bilinear fractions (fx, fy) of the point (sx, sy).
#[inline(always)]
fn bilinear_cell(sx: f32, sy: f32, w: usize, wmax: i32, hmax: i32) -> ([usize; 4], f32, f32) {
    let (x0, y0) = (floor_i32(sx), floor_i32(sy));
    let (fx, fy) = (sx - x0 as f32, sy - y0 as f32);
    let (cx0, cx1) = (x0.clamp(0, wmax) as usize, (x0 + 1).clamp(0, wmax) as usize);
    let (cy0, cy1) = (
        y0.clamp(0, hmax) as usize * w,
        (y0 + 1).clamp(0, hmax) as usize * w,
    );
    ([cy0 + cx0, cy0 + cx1, cy1 + cx0, cy1 + cx1], fx, fy)
}

/// The per-pixel rules shared by the separable pass and the exact 2D convolution.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rules {
    pub support_mm: f32,
    pub depth_mm: f32,
    pub min_footprint_px: f32,
}

impl Rules {
    pub fn new(support_mm: f64, opts: &FilterOptions) -> Rules {
        Rules {
            support_mm: support_mm as f32,
            depth_mm: opts.depth_threshold * support_mm as f32,
            min_footprint_px: opts.min_footprint_px,
        }
    }

    /// 1/mm_per_pixel if the pixel is blurred, None if it skips the blur.
    #[inline(always)]
    pub fn inverse_scale(&self, mm_per_pixel: f32) -> Option<f32> {
        if !(mm_per_pixel > 0.0) || !mm_per_pixel.is_finite() {
            return None;
        }
        let inv = 1.0 / mm_per_pixel;
        (2.0 * self.support_mm * inv >= self.min_footprint_px && inv.is_finite()).then_some(inv)
    }
}

/// One pass's taps in f32.
struct PassTaps {
    offset: Vec<f32>,
    weight: Vec<[f32; 3]>,
    sum: [f32; 3],
    one_signed: [bool; 3],
}

impl PassTaps {
    fn new(k: &Kernel1d) -> PassTaps {
        let sum = k.sum();
        let one_signed = std::array::from_fn(|c| {
            k.taps.iter().all(|t| t.weight[c] >= 0.0) || k.taps.iter().all(|t| t.weight[c] <= 0.0)
        });
        PassTaps {
            offset: k.taps.iter().map(|t| t.offset_mm as f32).collect(),
            weight: k.taps.iter().map(|t| t.weight.map(|w| w as f32)).collect(),
            sum: sum.map(|s| s as f32),
            one_signed,
        }
    }
}

/// Final value of a pixel from the kept accumulation and the dropped weight.
#[inline(always)]
fn finish(
    acc: [f32; 3],
    dropped: [f32; 3],
    sum: [f32; 3],
    one_signed: [bool; 3],
    centre: [f32; 3],
) -> [f32; 3] {
    std::array::from_fn(|c| {
        let kept = sum[c] - dropped[c];
        if one_signed[c] && kept * sum[c] > 0.0 && kept.abs() > 1e-6 * sum[c].abs() {
            acc[c] * (sum[c] / kept)
        } else {
            acc[c] + dropped[c] * centre[c]
        }
    })
}

struct Pass<'a> {
    input: &'a ScreenInput<'a>,
    src: &'a [[f32; 3]],
    taps: &'a PassTaps,
    vertical: bool,
    rules: Rules,
    jitter: bool,
    rotate_limit_mm: f32,
    seed: u64,
    /// (cos, sin) of every rotation step.
    rotations: &'a [(f32, f32)],
}

/// Running sums of one pixel.
struct Acc {
    acc: [f32; 3],
    dropped: [f32; 3],
    any_drop: bool,
}

impl Pass<'_> {
    /// Whether texel `j` is dropped (another object, or a depth jump).
    #[inline(always)]
    fn dropped(&self, j: usize, id: u32, d0: f32) -> bool {
        let inp = self.input;
        inp.mask[j] != id || (inp.depth[j] - d0).abs() > self.rules.depth_mm
    }

    /// Adds texel `j` with weight `bw · wt`, or drops it (zero weights are skipped).
    #[inline(always)]
    fn texel(&self, j: usize, bw: f32, wt: &[f32; 3], id: u32, d0: f32, a: &mut Acc) {
        if bw == 0.0 {
            return;
        }
        let ww = [bw * wt[0], bw * wt[1], bw * wt[2]];
        if self.dropped(j, id, d0) {
            a.any_drop = true;
            for c in 0..3 {
                a.dropped[c] += ww[c];
            }
        } else {
            let s = self.src[j];
            for c in 0..3 {
                a.acc[c] += ww[c] * s[c];
            }
        }
    }

    /// The general per-pixel filter: every texel tested and dropped individually, the kept
    /// ones renormalised ([`finish`]). Used near silhouettes.
    #[inline(never)]
    fn pixel_slow(&self, x: usize, y: usize, id: u32, inv: f32) -> [f32; 3] {
        let inp = self.input;
        let w = inp.width;
        let i = y * w + x;
        let centre = self.src[i];
        let t = self.taps;
        let d0 = inp.depth[i];
        let (wmax, hmax) = (w as i32 - 1, inp.height as i32 - 1);
        let mut a = Acc {
            acc: [0.0; 3],
            dropped: [0.0; 3],
            any_drop: false,
        };
        let (rdx, rdy) = if self.jitter {
            let (c, s) = self.rotations[rotation_index(x, y, self.seed)];
            if self.vertical { (-s, c) } else { (c, s) }
        } else {
            (0.0, 0.0)
        };
        for (&o_mm, wt) in t.offset.iter().zip(&t.weight) {
            let o = o_mm * inv;
            if self.jitter && o_mm.abs() <= self.rotate_limit_mm {
                // Rotated axis: bilinear fetch at p − o·dir.
                let (sx, sy) = (x as f32 - o * rdx, y as f32 - o * rdy);
                let ([j00, j01, j10, j11], fx, fy) = bilinear_cell(sx, sy, w, wmax, hmax);
                self.texel(j00, (1.0 - fx) * (1.0 - fy), wt, id, d0, &mut a);
                self.texel(j01, fx * (1.0 - fy), wt, id, d0, &mut a);
                self.texel(j10, (1.0 - fx) * fy, wt, id, d0, &mut a);
                self.texel(j11, fx * fy, wt, id, d0, &mut a);
            } else {
                // Axis-aligned: linear fetch along the pass's axis.
                let (p, stride, lim, base) = if self.vertical {
                    (y as f32 - o, w, hmax, x)
                } else {
                    (x as f32 - o, 1, wmax, y * w)
                };
                let p0 = floor_i32(p);
                let f = p - p0 as f32;
                let j0 = base + p0.clamp(0, lim) as usize * stride;
                let j1 = base + (p0 + 1).clamp(0, lim) as usize * stride;
                self.texel(j0, 1.0 - f, wt, id, d0, &mut a);
                self.texel(j1, f, wt, id, d0, &mut a);
            }
        }
        if !a.any_drop {
            a.acc
        } else {
            finish(a.acc, a.dropped, t.sum, t.one_signed, centre)
        }
    }

    /// The common case: every texel the taps read is kept (same object, no depth jump). Sums
    /// the taps with two linear (or bilinear) fetches each and returns None as soon as a texel
    /// would be dropped, leaving the pixel to [`Pass::pixel_slow`].
    #[inline(always)]
    fn pixel_fast<const VERTICAL: bool, const JITTER: bool>(
        &self,
        x: usize,
        y: usize,
        id: u32,
        inv: f32,
    ) -> Option<[f32; 3]> {
        let inp = self.input;
        let (mask, depth, src) = (inp.mask, inp.depth, self.src);
        let w = inp.width;
        let d0 = depth[y * w + x];
        let thr = self.rules.depth_mm;
        let (wmax, hmax) = (w as i32 - 1, inp.height as i32 - 1);
        let t = self.taps;
        let (rdx, rdy) = if JITTER {
            let (c, s) = self.rotations[rotation_index(x, y, self.seed)];
            if VERTICAL { (-s, c) } else { (c, s) }
        } else {
            (0.0, 0.0)
        };
        let kept = |j: usize| mask[j] == id && (depth[j] - d0).abs() <= thr;
        let (mut r, mut g, mut b) = (0.0f32, 0.0f32, 0.0f32);
        let centre = src[y * w + x];
        for (&o_mm, wt) in t.offset.iter().zip(&t.weight) {
            let o = o_mm * inv;
            let v = if o_mm == 0.0 {
                // The centre tap reads the pixel itself, whatever the rotation.
                centre
            } else if JITTER && o_mm.abs() <= self.rotate_limit_mm {
                let (sx, sy) = (x as f32 - o * rdx, y as f32 - o * rdy);
                let ([j00, j01, j10, j11], fx, fy) = bilinear_cell(sx, sy, w, wmax, hmax);
                if !(kept(j00) && kept(j01) && kept(j10) && kept(j11)) {
                    return None;
                }
                let (a0, a1, b0, b1) = (src[j00], src[j01], src[j10], src[j11]);
                let lerp2 = |c: usize| {
                    let top = a0[c] + fx * (a1[c] - a0[c]);
                    let bottom = b0[c] + fx * (b1[c] - b0[c]);
                    top + fy * (bottom - top)
                };
                [lerp2(0), lerp2(1), lerp2(2)]
            } else {
                let (p, stride, lim) = if VERTICAL {
                    (y as f32 - o, w, hmax)
                } else {
                    (x as f32 - o, 1, wmax)
                };
                let base = if VERTICAL { x } else { y * w };
                let p0 = floor_i32(p);
                let f = p - p0 as f32;
                let j0 = base + p0.clamp(0, lim) as usize * stride;
                let j1 = base + (p0 + 1).clamp(0, lim) as usize * stride;
                if !(kept(j0) && kept(j1)) {
                    return None;
                }
                let (s0, s1) = (src[j0], src[j1]);
                [
                    s0[0] + f * (s1[0] - s0[0]),
                    s0[1] + f * (s1[1] - s0[1]),
                    s0[2] + f * (s1[2] - s0[2]),
                ]
            };
            r += wt[0] * v[0];
            g += wt[1] * v[1];
            b += wt[2] * v[2];
        }
        Some([r, g, b])
    }

    #[inline(always)]
    fn pixel<const VERTICAL: bool, const JITTER: bool>(&self, x: usize, y: usize) -> [f32; 3] {
        let inp = self.input;
        let i = y * inp.width + x;
        let id = inp.mask[i];
        if id == NO_OBJECT {
            return [0.0; 3];
        }
        let Some(inv) = self.rules.inverse_scale(inp.mm_per_pixel[i]) else {
            let (centre, sum) = (self.src[i], self.taps.sum);
            return [centre[0] * sum[0], centre[1] * sum[1], centre[2] * sum[2]];
        };
        match self.pixel_fast::<VERTICAL, JITTER>(x, y, id, inv) {
            Some(v) => v,
            None => self.pixel_slow(x, y, id, inv),
        }
    }

    fn run(&self, dst: &mut [[f32; 3]], accumulate: bool) {
        match (self.vertical, self.jitter) {
            (false, false) => self.run_as::<false, false>(dst, accumulate),
            (false, true) => self.run_as::<false, true>(dst, accumulate),
            (true, false) => self.run_as::<true, false>(dst, accumulate),
            (true, true) => self.run_as::<true, true>(dst, accumulate),
        }
    }

    fn run_as<const VERTICAL: bool, const JITTER: bool>(
        &self,
        dst: &mut [[f32; 3]],
        accumulate: bool,
    ) {
        let w = self.input.width;
        dst.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, out) in row.iter_mut().enumerate() {
                let v = self.pixel::<VERTICAL, JITTER>(x, y);
                if accumulate {
                    for c in 0..3 {
                        out[c] += v[c];
                    }
                } else {
                    *out = v;
                }
            }
        });
    }
}

/// Filters `input` with `kernel` into a new image (see the module documentation).
pub fn filter(
    input: &ScreenInput,
    kernel: &SeparableKernel,
    opts: &FilterOptions,
) -> Result<Vec<[f32; 3]>, SeparableError> {
    let n = input.width * input.height;
    let mut out = vec![[0.0; 3]; n];
    let mut scratch = Vec::new();
    filter_into(input, kernel, opts, &mut scratch, &mut out)?;
    Ok(out)
}

/// [`filter`] into caller-provided buffers: `out` must hold width × height pixels;
/// `scratch` (the intermediate image between the passes) is resized as needed and can be
/// reused across frames.
pub fn filter_into(
    input: &ScreenInput,
    kernel: &SeparableKernel,
    opts: &FilterOptions,
    scratch: &mut Vec<[f32; 3]>,
    out: &mut [[f32; 3]],
) -> Result<(), SeparableError> {
    input.validate()?;
    opts.validate()?;
    ensure(kernel.is_finite(), || "kernel has non-finite taps".into())?;
    ensure(!kernel.terms.is_empty(), || "kernel has no terms".into())?;
    let n = input.width * input.height;
    if out.len() != n {
        return Err(SeparableError::BufferSize {
            what: "out",
            expected: n,
            got: out.len(),
        });
    }
    if n == 0 {
        return Ok(());
    }
    scratch.resize(n, [0.0; 3]);
    let support = kernel.support_mm.max(kernel.radius_mm());
    let rules = Rules::new(support, opts);
    let jitter = opts.jitter_radius > 0.0;
    let rotate_limit_mm = opts.jitter_radius * support as f32;
    let rotations: Vec<(f32, f32)> = (0..ROTATION_STEPS)
        .map(|k| {
            let (s, c) = (std::f64::consts::TAU * k as f64 / ROTATION_STEPS as f64).sin_cos();
            (c as f32, s as f32)
        })
        .collect();
    for (k, term) in kernel.terms.iter().enumerate() {
        let (h, v) = (
            PassTaps::new(&term.horizontal),
            PassTaps::new(&term.vertical),
        );
        Pass {
            input,
            src: input.irradiance,
            taps: &h,
            vertical: false,
            rules,
            jitter,
            rotate_limit_mm,
            seed: opts.seed,
            rotations: &rotations,
        }
        .run(scratch, false);
        Pass {
            input,
            src: scratch,
            taps: &v,
            vertical: true,
            rules,
            jitter,
            rotate_limit_mm,
            seed: opts.seed,
            rotations: &rotations,
        }
        .run(out, k > 0);
    }
    Ok(())
}
