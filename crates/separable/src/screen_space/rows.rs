//! The row-chunked form of one separable pass: the same taps at the same positions as
//! [`Pass::pixel`] (each pixel's tap positions are its f32 values), organised so the common
//! case runs near memory speed, and rounded differently (fused multiply-adds in the AVX2
//! build, rotated taps blended along y first and summed last): it matches the per-pixel form
//! within 10⁻⁵ relative per pixel and channel (see the module documentation of
//! [`super`]).
//!
//! A row is cut into chunks of [`CHUNK`] pixels. A chunk takes the fast path when every pixel
//! in it is blurred (not background, not under the sub-pixel skip) and every texel its taps
//! can reach shows the same object, with a depth within the rejection threshold of every
//! centre in the chunk. That test is hoisted out of the tap loop: a [`CellSummary`] holds, per row
//! and per cell of [`CELL`] pixels, whether the cell shows one object and its depth range, so
//! a chunk checks a few cells instead of every texel of every tap (conservatively: a chunk
//! whose reach touches a mixed cell goes pixel by pixel, through [`Pass::pixel`]). Cells are
//! joined into bands of 8 rows, and those into blocks of 64 pixels, tested first: away from
//! silhouettes and depth steps a chunk's reach is a handful of blocks.
//!
//! On x86-64 with AVX2 and FMA the chunks that pass are summed by [`super::avx2`]; the
//! loops of [`super::portable`] are the portable form, for other CPUs (and
//! `Evaluation::RowsBaseline`). The chunk is a flat run of 3 × [`CHUNK`] floats (the RGB
//! layout of the images) and each tap is one loop over it:
//! - an axis-aligned tap computes each pixel's position (then its fraction, repeated over its
//!   three channels). When the integer offset is the same across the chunk and inside the
//!   image, it blends two contiguous runs of the source row (horizontal pass) or of the source
//!   rows `y + k` and `y + k + 1` (vertical pass) — no clamps, no silhouette tests, no
//!   gathers; when the footprint changes across the chunk so that the offset takes two
//!   values, three contiguous runs, each pixel blending the first two or the last two; else
//!   (more offsets, or reads past the border) it reads per pixel with the border clamp;
//! - a rotated (jittered) tap is a bilinear read at a per-pixel angle: positions and cells
//!   are computed for all pixels at once; when every cell is inside the image, the tap is
//!   kept and, after the axis taps, each pixel sums its kept rotated taps with two 8-float
//!   loads per tap (the cell's two texels of a row are six contiguous floats); near the
//!   border each pixel reads its four clamped texels.

use super::NO_OBJECT;
use super::chunk::{CHUNK, Ctx, Lanes, RowOut, SUBCHUNK, store};
use super::pixel::Pass;
use super::portable::{SMALL, sum_chunk};

/// Filters row `y` of `pass` (VERTICAL: along columns) into `out`; returns how many pixels
/// took the fast path.
pub(super) fn row<const VERTICAL: bool, const JITTER: bool>(
    pass: &Pass,
    ctx: &Ctx,
    lanes: &mut Lanes,
    y: usize,
    out: RowOut,
) -> usize {
    #[cfg(target_arch = "x86_64")]
    if !ctx.baseline
        && std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("fma")
    {
        // SAFETY: the CPU was just checked to support AVX2 and FMA, the only requirement of
        // calling a function compiled with `target_feature(enable = "avx2,fma")`.
        return unsafe { row_avx2::<VERTICAL, JITTER>(pass, ctx, lanes, y, out) };
    }
    row_any::<VERTICAL, JITTER, false>(pass, ctx, lanes, y, out)
}

/// [`row_any`] compiled for AVX2 and FMA: the chunks that pass the test are summed by
/// [`super::avx2::chunk`] (multiply-adds fused, so its results differ from the baseline
/// build's by rounding: a few units in the last place of each sum), the rest as in the
/// baseline build.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
pub(super) fn row_avx2<const VERTICAL: bool, const JITTER: bool>(
    pass: &Pass,
    ctx: &Ctx,
    lanes: &mut Lanes,
    y: usize,
    out: RowOut,
) -> usize {
    row_any::<VERTICAL, JITTER, true>(pass, ctx, lanes, y, out)
}

#[inline(always)]
pub(super) fn row_any<const VERTICAL: bool, const JITTER: bool, const AVX2: bool>(
    pass: &Pass,
    ctx: &Ctx,
    lanes: &mut Lanes,
    y: usize,
    mut out: RowOut,
) -> usize {
    let w = pass.input.width;
    // The horizontal pass's padded source row (AVX2 build) and its padding, built for the
    // row's first chunk that passes the test.
    #[cfg(target_arch = "x86_64")]
    let mut pad = PadRow {
        row: std::mem::take(&mut lanes.padrow),
        pad: None,
    };
    #[cfg(not(target_arch = "x86_64"))]
    let mut pad = PadRow;
    let (mut x0, mut fast) = (0, 0);
    while x0 < w {
        let n = CHUNK.min(w - x0);
        if fast_chunk::<VERTICAL, JITTER, AVX2>(pass, ctx, lanes, &mut out, (x0, y, n), &mut pad) {
            fast += n;
        } else {
            // Near a silhouette: retry in smaller pieces (each reaches less far across the
            // pass), then pixel by pixel.
            let mut s0 = x0;
            while s0 < x0 + n {
                let k = SUBCHUNK.min(x0 + n - s0);
                if fast_chunk::<VERTICAL, JITTER, AVX2>(
                    pass,
                    ctx,
                    lanes,
                    &mut out,
                    (s0, y, k),
                    &mut pad,
                ) {
                    fast += k;
                } else {
                    for x in s0..s0 + k {
                        let v = pass.pixel::<VERTICAL, JITTER>(x, y);
                        store(&mut out, &v, x);
                    }
                }
                s0 += k;
            }
        }
        x0 += n;
    }
    #[cfg(target_arch = "x86_64")]
    {
        lanes.padrow = pad.row;
    }
    fast
}

/// The horizontal pass's padded source row of [`row_any`] (x86-64: built for the row's
/// first chunk that passes the test, `pad` its padding once built).
#[cfg(target_arch = "x86_64")]
pub(super) struct PadRow {
    row: Vec<f32>,
    pad: Option<usize>,
}

/// (No padded row outside x86-64.)
#[cfg(not(target_arch = "x86_64"))]
pub(super) struct PadRow;

/// Sums the chunk of `n` pixels of row `y` from `x0` through the fast path if it passes the
/// test ([`eligible`]). A function rather than a closure of [`row_any`] so that it is
/// inlined there and compiled with its target features (a closure is compiled without).
#[inline(always)]
pub(super) fn fast_chunk<const VERTICAL: bool, const JITTER: bool, const AVX2: bool>(
    pass: &Pass,
    ctx: &Ctx,
    lanes: &mut Lanes,
    out: &mut RowOut,
    (x0, y, n): (usize, usize, usize),
    #[allow(unused_variables)] padrow: &mut PadRow,
) -> bool {
    if !eligible::<VERTICAL, JITTER>(pass, ctx, x0, y, n) {
        return false;
    }
    #[cfg(target_arch = "x86_64")]
    if AVX2 {
        let w = pass.input.width;
        let pad = if VERTICAL {
            0
        } else {
            *padrow.pad.get_or_insert_with(|| {
                let pad = row_reach(ctx, y);
                super::avx2::pad_row(pass.src.as_flattened(), w, y, pad, &mut padrow.row);
                pad
            })
        };
        let srcs = super::avx2::Sources {
            src: pass.src.as_flattened(),
            row: &padrow.row,
            pad,
        };
        // SAFETY: `AVX2` is only true in `row_avx2`, which is only called after checking
        // that the CPU has AVX2 and FMA.
        unsafe { super::avx2::chunk::<VERTICAL, JITTER>(pass, ctx, &srcs, x0, y, n, out) };
        return true;
    }
    sum_chunk::<VERTICAL, JITTER>(pass, ctx, lanes, x0, y, n);
    store(out, &lanes.acc[..3 * n], x0);
    true
}

/// How far (pixels) the axis taps of row `y`'s blurred pixels reach along the row, plus
/// the bilinear neighbour and a margin for the group loop's three runs (capped: a group
/// whose reads pass the padding goes pixel by pixel).
#[cfg(target_arch = "x86_64")]
pub(super) fn row_reach(ctx: &Ctx, y: usize) -> usize {
    let inv_max = ctx.summary.row_inv_max(y);
    let reach = (ctx.taps.axis_mm * inv_max).ceil() + 4.0;
    if reach < 4096.0 { reach as usize } else { 4096 }
}

/// Whether the `n` pixels of row `y` from column `x0` can take the fast path: all blurred,
/// one object, and every texel their taps can reach kept (the silhouette test, hoisted into
/// the [`CellSummary`]).
#[inline(always)]
pub(super) fn eligible<const VERTICAL: bool, const JITTER: bool>(
    pass: &Pass,
    ctx: &Ctx,
    x0: usize,
    y: usize,
    n: usize,
) -> bool {
    let inp = pass.input;
    let (w, h) = (inp.width, inp.height);
    let i0 = y * w + x0;
    let id = inp.mask[i0];
    if id == NO_OBJECT || w + h >= SMALL {
        return false;
    }
    // One object with finite depths over the chunk's own cells, every pixel blurred; their
    // depth range and largest inverse footprint.
    let Some((dmin0, dmax0, inv_max)) = ctx.summary.range(id, y, (x0, x0 + n - 1)) else {
        return false;
    };

    // The rectangle every tap of every pixel can read (pixels; +2 covers the bilinear
    // neighbour and rounding), clamped to the image as the reads are.
    let taps = ctx.taps;
    let ra = (taps.axis_mm * inv_max).ceil() + 2.0;
    let rr = if JITTER && taps.rotated_mm > 0.0 {
        (taps.rotated_mm * inv_max).ceil() + 2.0
    } else {
        0.0
    };
    if !(ra < (w + h) as f32 && rr < (w + h) as f32) {
        return false;
    }
    let (along, across) = ((ra.max(rr)) as usize, rr as usize);
    let (xr, yr) = if VERTICAL {
        (across, along)
    } else {
        (along, across)
    };
    let xs = (x0.saturating_sub(xr), (x0 + n - 1 + xr).min(w - 1));
    let ys = (y.saturating_sub(yr), (y + yr).min(h - 1));
    // |d − d0| ≤ thr for every d in [lo, hi] and every centre d0 in [dmin0, dmax0], with a
    // margin far above f32 rounding so the per-texel test (|d − d0| ≤ thr in f32) keeps them.
    let thr = pass.rules.depth_mm;
    let margin = (dmin0.abs() + dmax0.abs() + thr) * (1.0 / 1_048_576.0);
    let (lo, hi) = (dmax0 - thr + margin, dmin0 + thr - margin);
    ctx.summary.clean(id, ys, xs, lo, hi)
}
