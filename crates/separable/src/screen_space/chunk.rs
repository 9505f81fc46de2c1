//! What the chunk loops share, whichever instruction set sums them: the chunk size
//! ([`CHUNK`]), the pass's taps as the chunks use them ([`ChunkTaps`]), the frame's context
//! ([`Ctx`]: summary, rotation table, taps), the per-thread scratch ([`Lanes`]) and the
//! output row ([`RowOut`], [`store`]).

use super::pixel::{Pass, PassTaps};
use super::rotation::PixelTable;
use super::summary::CellSummary;

/// Pixels per chunk.
pub(super) const CHUNK: usize = 64;

/// Pixels per piece of a chunk that failed the test.
pub(super) const SUBCHUNK: usize = 16;

/// Floats per chunk (RGB).
pub(super) const FLOATS: usize = 3 * CHUNK;

/// Rotated taps whose positions a chunk holds at once (more are summed in batches).
pub(super) const ROTATED: usize = 4;

/// Per held rotated tap, one value per pixel of a chunk.
pub(super) type Slots<T> = [[T; CHUNK]; ROTATED];

/// A pass's taps laid out for the flat chunk loops.
pub(super) struct ChunkTaps {
    /// Per tap, its RGB weights repeated over a chunk's floats.
    pub(super) pattern: Vec<[f32; FLOATS]>,
    /// Per tap, the weights of a rotated read's row pair (RGB of the left texel, RGB of the
    /// right one, two unused lanes) at fx = 0, and their change per unit of fx: the weights
    /// are `lo + fx · d` = [(1 − fx)·wt, fx·wt, 0, 0]. Runtime arrays, so the compiler keeps
    /// the 8-lane arithmetic whole instead of folding the constant lanes.
    pub(super) rot_lo: Vec<[f32; 8]>,
    pub(super) rot_d: Vec<[f32; 8]>,
    /// Largest |offset| (mm) of the axis-aligned taps.
    pub(super) axis_mm: f32,
    /// Largest |offset| (mm) of the rotated taps (0 without jitter).
    pub(super) rotated_mm: f32,
}

impl ChunkTaps {
    /// The layout of `pass`'s taps.
    pub fn new(pass: &Pass) -> ChunkTaps {
        let t: &PassTaps = pass.taps;
        let (mut axis_mm, mut rotated_mm) = (0.0f32, 0.0f32);
        for &o in &t.offset {
            if pass.rotates(o) {
                rotated_mm = rotated_mm.max(o.abs());
            } else {
                axis_mm = axis_mm.max(o.abs());
            }
        }
        ChunkTaps {
            pattern: t
                .weight
                .iter()
                .map(|w| std::array::from_fn(|i| w[i % 3]))
                .collect(),
            rot_lo: t
                .weight
                .iter()
                .map(|w| [w[0], w[1], w[2], 0.0, 0.0, 0.0, 0.0, 0.0])
                .collect(),
            rot_d: t
                .weight
                .iter()
                .map(|w| [-w[0], -w[1], -w[2], w[0], w[1], w[2], 0.0, 0.0])
                .collect(),
            axis_mm,
            rotated_mm,
        }
    }
}

/// What every chunk of a pass reads besides the pass itself.
#[derive(Clone, Copy)]
pub(super) struct Ctx<'a> {
    pub summary: &'a CellSummary,
    pub table: &'a PixelTable,
    pub taps: &'a ChunkTaps,
    /// The same taps for the AVX2 group loop.
    #[cfg(target_arch = "x86_64")]
    pub groups: &'a super::avx2::GroupTaps,
    /// Use the x86-64 baseline code even where AVX2 is available (to test it).
    pub baseline: bool,
}

/// Per-thread scratch of the chunked pass (structure of arrays over a chunk's pixels, and
/// the same repeated over their channels).
pub(super) struct Lanes {
    /// Pixel index in the chunk, as f32.
    pub(super) lane: [f32; CHUNK],
    /// x coordinate.
    pub(super) px: [f32; CHUNK],
    /// 1 / mm_per_pixel.
    pub(super) inv: [f32; CHUNK],
    /// The horizontal pass's source row padded by its edge pixels (AVX2 build).
    #[cfg(target_arch = "x86_64")]
    pub(super) padrow: Vec<f32>,
    /// An axis tap's fractional position per pixel, and the same repeated over the channels.
    pub(super) frac: [f32; CHUNK],
    pub(super) frac3: [f32; FLOATS],
    /// An axis tap's first texel minus the pixel's own offset, + 2²³, as bits.
    pub(super) key: [u32; CHUNK],
    /// An axis tap's choice between two offsets (1: the larger) per pixel, and the same
    /// repeated over the channels.
    pub(super) hi: [f32; CHUNK],
    pub(super) hi3: [f32; FLOATS],
    /// Per rotated tap inside the image: each pixel's first texel, bilinear fractions, and
    /// the tap's index (grown to the most such taps seen).
    pub(super) rj: Slots<u32>,
    pub(super) rfx: Slots<f32>,
    pub(super) rfy: Slots<f32>,
    pub(super) rtap: [usize; ROTATED],
    /// The folded rotated sums, RGB per pixel (and one float written past the last pixel).
    pub(super) rot3: [f32; FLOATS + 1],
    /// A rotated tap's cell (floored position) per pixel.
    pub(super) cx: [f32; CHUNK],
    pub(super) cy: [f32; CHUNK],
    /// Rotated axis direction.
    pub(super) rdx: [f32; CHUNK],
    pub(super) rdy: [f32; CHUNK],
    /// The four texel indices of a rotated tap near the border.
    pub(super) j: [[u32; CHUNK]; 4],
    /// The chunk's running sums, RGB per pixel.
    pub(super) acc: [f32; FLOATS],
}

impl Lanes {
    /// Fresh scratch.
    pub fn new() -> Box<Lanes> {
        Box::new(Lanes {
            lane: std::array::from_fn(|l| l as f32),
            px: [0.0; CHUNK],
            inv: [0.0; CHUNK],
            frac: [0.0; CHUNK],
            frac3: [0.0; FLOATS],
            key: [0; CHUNK],
            hi: [0.0; CHUNK],
            hi3: [0.0; FLOATS],
            rj: [[0; CHUNK]; ROTATED],
            rfx: [[0.0; CHUNK]; ROTATED],
            rfy: [[0.0; CHUNK]; ROTATED],
            rtap: [0; ROTATED],
            rot3: [0.0; FLOATS + 1],
            cx: [0.0; CHUNK],
            cy: [0.0; CHUNK],
            rdx: [0.0; CHUNK],
            rdy: [0.0; CHUNK],

            j: [[0; CHUNK]; 4],
            acc: [0.0; FLOATS],
            #[cfg(target_arch = "x86_64")]
            padrow: Vec::new(),
        })
    }
}

/// Where a row's values go: a row of an RGB image (flat), overwritten or added to.
pub(super) struct RowOut<'a> {
    pub row: &'a mut [f32],
    pub accumulate: bool,
}

/// Writes (or adds) the RGB values `v` at pixel `x0` of the output row.
#[inline(always)]
pub(super) fn store(out: &mut RowOut, v: &[f32], x0: usize) {
    let dst = &mut out.row[3 * x0..3 * x0 + v.len()];
    if out.accumulate {
        for (d, a) in dst.iter_mut().zip(v) {
            *d += a;
        }
    } else {
        dst.copy_from_slice(v);
    }
}
