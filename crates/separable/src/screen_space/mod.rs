//! The screen-space separable filter (Jimenez et al. 2015, §6; Jimenez, Sundstedt, Gutierrez
//! 2009 for the screen-space formulation): the irradiance image is convolved with a
//! [`SeparableKernel`] as one horizontal and one vertical 1D pass per term, summed.
//!
//! Per pixel:
//! - **Footprint.** A tap's offset in pixels is its offset in mm divided by the pixel's
//!   `mm_per_pixel` (the world-space size of one pixel on that pixel's surface), fetched
//!   bilinearly (clamp to edge). Pixels whose kernel diameter, 2·[`SeparableKernel::support_mm`]
//!   / mm_per_pixel, is under [`FilterOptions::min_footprint_px`] (or over 2²⁴ pixels: a
//!   broken footprint) skip the blur: output = irradiance × the kernel's total weight.
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
//! Evaluation: rows are cut into chunks of 64 pixels (`rows.rs`, the chunk driver; `chunk.rs`, what the chunk loops share). A chunk whose pixels all
//! show one blurred object, and whose taps can only reach texels of that object within the
//! depth threshold, runs every tap over the chunk with contiguous reads and no per-texel
//! tests; that test is hoisted into a per-frame summary of object ids, depth ranges and
//! footprints per 16-pixel cell (and per 8-row band, and per block of 8 rows by 64 pixels,
//! checked first), so a chunk checks a few blocks or cells. The others
//! (near silhouettes, mixed or skipped pixels) retry as 16-pixel pieces, then go pixel by
//! pixel (`pixel.rs`: the straightforward form, each texel tested, the reference). The chunked
//! form computes the same taps at the same positions (each pixel's tap positions are the
//! per-pixel form's f32 values), but rounds differently: fused multiply-adds, rotated taps
//! blended along y first and summed after the axis taps. It matches the per-pixel form within
//! 10⁻⁵ relative per pixel and channel, with an absolute floor of 10⁻⁶ of the channel's
//! largest value for pixels near zero (signed kernels cancel); tested on synthetic frames and
//! on every built-in scene. Which pixels take which form depends only on the inputs, so the
//! result is identical for any thread count.
//!
//! Files by concern: `summary.rs` (the per-frame cells, bands and blocks the chunks are
//! tested against), `rotation.rs` (the per-pixel rotation table), `chunk.rs` (what the chunk
//! loops share: taps, context, scratch, output), `rows.rs` (the driver: which chunks take the
//! fast path, and which loops sum them), `portable.rs` (the portable loops), `avx2.rs` (every
//! AVX2 + FMA form: the group loops, the summary's cells and the rotation table), `pixel.rs`
//! (the per-pixel reference). Only this file chooses between the instruction sets' forms of
//! the summary and table; the driver chooses the chunk loops.
//!
//! On x86-64 with AVX2 and FMA (checked at run time) the chunks run in `avx2.rs`: groups
//! of 8 pixels whose 24 sums are three 8-lane vectors, taps as the outer loop so that a
//! tap's integer offset and runs are found once per chunk, per-pixel fractions spread over
//! the channels by permutes, rotated taps as two 8-float loads per pixel. It is written with
//! intrinsics; its `unsafe` parts are the call into it after the CPU check, the gathers of
//! the rotation table and the rotated taps' loads from cells checked inside the image once
//! per group. The portable loops (`portable.rs`, kept for other CPUs and tested against the same
//! reference as `Evaluation::RowsBaseline`) keep their sums in memory and, compiled for
//! AVX2, took 1.2–1.4× the time without jitter on the benchmark frames (`docs/benchmarks.md`). The
//! baseline build multiplies and adds separately, so the two builds differ by rounding. There
//! is no AVX-512 form: a 16-pixel form of the same loops gave the AVX2 loops' bits and gained
//! 1.09× in the benchmark's full run on an AVX-512 Xeon (1.1–1.35× in other runs), too little
//! for six hundred lines of `unsafe` code that no CI machine without AVX-512 runs. Cost and its
//! breakdown: `crates/bench/benches/separable.rs` and `docs/benchmarks.md`.
//!
//! Output: per pixel, the diffuse exitance E ∗ R_d (with [`crate::Energy::TotalReflectance`]
//! kernels); the caller applies its Fresnel / π factors. Background pixels
//! ([`NO_OBJECT`]) output 0. Rows are processed in parallel with rayon; every pixel's value
//! depends only on the inputs, so the result is identical for any thread count.

#[cfg(target_arch = "x86_64")]
mod avx2;
mod chunk;
mod pixel;
mod portable;
mod rotation;
mod rows;
mod summary;
#[cfg(test)]
mod tests;

use crate::error::{SeparableError, ensure};
use crate::kernel::SeparableKernel;
use chunk::{ChunkTaps, Ctx, Lanes, RowOut};
use pixel::{Pass, PassTaps};
use rayon::prelude::*;
use rotation::PixelTable;
use sss_util::splitmix64;
use std::sync::atomic::{AtomicUsize, Ordering};
use summary::{Cell, CellSummary};

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

/// The widest kernel, in pixels, that a pixel blurs with (2²⁴): a footprint so small that
/// the kernel spans more skips the blur like a sub-pixel one. Tap positions then stay within
/// ±2²⁴ pixels, where f32 holds them exactly and their integer parts fit an i32: a footprint
/// of 10⁻³⁰ mm per pixel (a broken G-buffer) had put taps 10³¹ pixels away, whose bilinear
/// fractions, taken from a saturated integer part, came out near 10³¹ and summed to ±∞ and
/// NaN. Such a kernel reads nothing but the clamped edge texels of any real image, so
/// skipping (irradiance × the kernel's total weight: locally flat light) is the better
/// answer as well as the finite one.
pub(crate) const MAX_SPAN_PX: f32 = 16_777_216.0;

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
        let (inv, blurred) = self.inverse_scale_lane(mm_per_pixel);
        blurred.then_some(inv)
    }

    /// [`Rules::inverse_scale`] without branches (so a loop over pixels vectorises):
    /// 1/mm_per_pixel, and whether the pixel is blurred (a positive, finite footprint whose
    /// kernel spans at least `min_footprint_px` and at most [`MAX_SPAN_PX`]).
    #[inline(always)]
    pub fn inverse_scale_lane(&self, mm_per_pixel: f32) -> (f32, bool) {
        let inv = 1.0 / mm_per_pixel;
        let span = 2.0 * self.support_mm * inv;
        let ok = (mm_per_pixel > 0.0)
            & mm_per_pixel.is_finite()
            & (span >= self.min_footprint_px)
            & (span <= MAX_SPAN_PX)
            & inv.is_finite();
        (inv, ok)
    }
}

/// Buffers the filter keeps from one frame to the next ([`filter_into`]): the intermediate
/// image between the passes, the per-frame silhouette summary, and the per-pixel rotation
/// table, which depends only on the image size and the seed and so is computed once for a
/// run of frames that share them. Reusing one across frames saves their allocation (and the
/// page faults of fresh memory) and the table; a fresh one gives the same output.
#[derive(Default)]
pub struct FilterScratch {
    image: Vec<[f32; 3]>,
    /// The silhouette summary's cells, bands, the bands' working rows and blocks.
    summary: [Vec<Cell>; 4],
    rotation: Vec<u8>,
    /// (width, height, seed) of the table in `rotation`, if it holds one.
    rotation_key: Option<(usize, usize, u64)>,
}

impl std::fmt::Debug for FilterScratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FilterScratch")
            .field("pixels", &self.image.len())
            .field("rotation_key", &self.rotation_key)
            .finish_non_exhaustive()
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
    filter_into(input, kernel, opts, &mut FilterScratch::default(), &mut out)?;
    Ok(out)
}

/// [`filter`] into caller-provided buffers: `out` must hold width × height pixels; `scratch`
/// ([`FilterScratch`]) is resized as needed and is meant to be kept across frames.
pub fn filter_into(
    input: &ScreenInput,
    kernel: &SeparableKernel,
    opts: &FilterOptions,
    scratch: &mut FilterScratch,
    out: &mut [[f32; 3]],
) -> Result<(), SeparableError> {
    run(
        input,
        kernel,
        opts,
        scratch,
        out,
        Evaluation::Rows,
        &AtomicUsize::new(0),
    )
}

/// How the passes are evaluated; they agree within rounding (see the module documentation).
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Evaluation {
    /// Row chunks with the silhouette test hoisted ([`filter_into`]).
    Rows,
    /// [`Evaluation::Rows`] in the x86-64 baseline instruction set even where AVX2 and FMA
    /// are available (multiplies and adds not fused: the two agree within rounding), the
    /// per-frame summary and rotation table included (the same bits either way).
    RowsBaseline,
    /// Every tap of every pixel fetched and tested on its own: the plain form the chunked one
    /// is tested against (and measured against in `crates/bench/benches/separable.rs`).
    PerPixel,
}

/// [`filter_into`] with a choice of [`Evaluation`], for tests and benchmarks; returns the
/// fraction of pixel passes that took the row-chunked fast path (0 for
/// [`Evaluation::PerPixel`]).
#[doc(hidden)]
pub fn filter_into_with(
    input: &ScreenInput,
    kernel: &SeparableKernel,
    opts: &FilterOptions,
    scratch: &mut FilterScratch,
    out: &mut [[f32; 3]],
    evaluation: Evaluation,
) -> Result<f64, SeparableError> {
    let fast = AtomicUsize::new(0);
    run(input, kernel, opts, scratch, out, evaluation, &fast)?;
    let passes = 2 * kernel.terms.len() * input.width * input.height;
    Ok(fast.into_inner() as f64 / passes.max(1) as f64)
}

fn run(
    input: &ScreenInput,
    kernel: &SeparableKernel,
    opts: &FilterOptions,
    scratch: &mut FilterScratch,
    out: &mut [[f32; 3]],
    evaluation: Evaluation,
    fast: &AtomicUsize,
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
    let image = &mut scratch.image;
    image.resize(n, [0.0; 3]);
    let support = kernel.support_mm.max(kernel.radius_mm());
    let rules = Rules::new(support, opts);
    let jitter = opts.jitter_radius > 0.0;
    let rotate_limit_mm = opts.jitter_radius * support as f32;
    let rotations: Vec<[f32; 2]> = (0..ROTATION_STEPS)
        .map(|k| {
            let (s, c) = (std::f64::consts::TAU * k as f64 / ROTATION_STEPS as f64).sin_cos();
            [c as f32, s as f32]
        })
        .collect();
    // The chunked form indexes texels, and the SIMD loops their floats (3 per texel, and a
    // row and 8 floats past a cell), in i32 / u32 lanes: larger frames (over 715 M pixels)
    // go pixel by pixel.
    let chunked =
        evaluation != Evaluation::PerPixel && 3 * (n + input.width) + 8 <= i32::MAX as usize;
    let isa = match evaluation {
        Evaluation::RowsBaseline => Isa::Baseline,
        _ => Isa::Best,
    };
    let tables = chunked.then(|| {
        (
            CellSummary::new(
                input,
                &rules,
                std::mem::take(&mut scratch.summary),
                &summary_rows(isa),
            ),
            PixelTable::new(
                input,
                opts.seed,
                jitter,
                std::mem::take(&mut scratch.rotation),
                &mut scratch.rotation_key,
                &rotation_rows(isa),
            ),
        )
    });
    for (k, term) in kernel.terms.iter().enumerate() {
        let (h, v) = (
            PassTaps::new(&term.horizontal),
            PassTaps::new(&term.vertical),
        );
        let horizontal = Pass {
            input,
            src: input.irradiance,
            taps: &h,
            vertical: false,
            rules,
            jitter,
            rotate_limit_mm,
            seed: opts.seed,
            rotations: &rotations,
        };
        run_pass(&horizontal, tables.as_ref(), isa, image, false, fast);
        let vertical = Pass {
            src: image,
            taps: &v,
            vertical: true,
            ..horizontal
        };
        run_pass(&vertical, tables.as_ref(), isa, out, k > 0, fast);
    }
    if let Some((summary, table)) = tables {
        scratch.summary = summary.into_buffers();
        scratch.rotation = table.rotation;
    }
    Ok(())
}

/// Which instruction set the row-chunked form may use (the widest the CPU has, unless a
/// test asks for a narrower one).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Isa {
    /// The x86-64 baseline ([`Evaluation::RowsBaseline`]).
    Baseline,
    /// AVX2 and FMA where the CPU has them.
    Best,
}

/// Whether the AVX2 code may run: the CPU has it and `isa` allows it.
fn use_avx2(isa: Isa) -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        isa != Isa::Baseline && std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = isa;
        false
    }
}

/// The summary's row builder for `isa`: [`avx2::summary_row_avx2`] where it may run, else the
/// portable [`summary::summary_row`] (the same cells either way).
fn summary_rows(isa: Isa) -> impl Fn(&ScreenInput, &Rules, usize, &mut [Cell]) + Sync {
    let avx2 = use_avx2(isa);
    move |input, rules, y, row| {
        #[cfg(target_arch = "x86_64")]
        if avx2 {
            // SAFETY: `use_avx2` checked that the CPU supports AVX2, the only requirement of
            // calling a function compiled with it.
            return unsafe { avx2::summary_row_avx2(input, rules, y, row) };
        }
        let _ = avx2;
        summary::summary_row(input, rules, y, row)
    }
}

/// The rotation table's row builder for `isa`, as [`summary_rows`] (the same bytes either
/// way).
fn rotation_rows(isa: Isa) -> impl Fn(usize, u64, &mut [u8]) + Sync {
    let avx2 = use_avx2(isa);
    move |y, seed, row| {
        #[cfg(target_arch = "x86_64")]
        if avx2 {
            // SAFETY: as in `summary_rows`.
            return unsafe { avx2::rotation_row_avx2(y, seed, row) };
        }
        let _ = avx2;
        rotation::rotation_row(y, seed, row)
    }
}

/// One pass over every row: `pass.src` into `dst`, added to it when `accumulate`.
fn run_pass(
    pass: &Pass,
    tables: Option<&(CellSummary, PixelTable)>,
    isa: Isa,
    dst: &mut [[f32; 3]],
    accumulate: bool,
    fast: &AtomicUsize,
) {
    match (pass.vertical, pass.jitter) {
        (false, false) => rows_of::<false, false>(pass, tables, isa, dst, accumulate, fast),
        (false, true) => rows_of::<false, true>(pass, tables, isa, dst, accumulate, fast),
        (true, false) => rows_of::<true, false>(pass, tables, isa, dst, accumulate, fast),
        (true, true) => rows_of::<true, true>(pass, tables, isa, dst, accumulate, fast),
    }
}

fn rows_of<const VERTICAL: bool, const JITTER: bool>(
    pass: &Pass,
    tables: Option<&(CellSummary, PixelTable)>,
    isa: Isa,
    dst: &mut [[f32; 3]],
    accumulate: bool,
    fast: &AtomicUsize,
) {
    let w = pass.input.width;
    let rows = dst.par_chunks_mut(w).enumerate();
    match tables {
        Some((summary, table)) => {
            let taps = ChunkTaps::new(pass);
            #[cfg(target_arch = "x86_64")]
            let groups = avx2::GroupTaps::new(pass, &taps);
            let ctx = Ctx {
                summary,
                table,
                taps: &taps,
                #[cfg(target_arch = "x86_64")]
                groups: &groups,
                baseline: isa == Isa::Baseline,
            };
            rows.for_each_init(Lanes::new, |lanes, (y, row)| {
                let out = RowOut {
                    row: row.as_flattened_mut(),
                    accumulate,
                };
                let k = rows::row::<VERTICAL, JITTER>(pass, &ctx, lanes, y, out);
                fast.fetch_add(k, Ordering::Relaxed);
            })
        }
        None => rows.for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let v = pass.pixel::<VERTICAL, JITTER>(x, y);
                if accumulate {
                    for c in 0..3 {
                        o[c] += v[c];
                    }
                } else {
                    *o = v;
                }
            }
        }),
    }
}
