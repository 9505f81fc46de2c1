//! The row-chunked form of one separable pass: the same arithmetic as [`Pass::pixel`], in the
//! same order, so the result is identical bit for bit, organised so the common case runs near
//! memory speed.
//!
//! A row is cut into chunks of [`CHUNK`] pixels. A chunk takes the fast path when every pixel
//! in it is blurred (not background, not under the sub-pixel skip) and every texel its taps
//! can reach shows the same object, with a depth within the rejection threshold of every
//! centre in the chunk. That test is hoisted out of the tap loop: a [`Summary`] holds, per row
//! and per cell of [`CELL`] pixels, whether the cell shows one object and its depth range, so
//! a chunk checks a few cells instead of every texel of every tap (conservatively: a chunk
//! whose reach touches a mixed cell goes pixel by pixel, through [`Pass::pixel`]).
//!
//! On the fast path the chunk is a flat run of 3 × [`CHUNK`] floats (the RGB layout of the
//! images) and each tap is one loop over it:
//! - an axis-aligned tap computes each pixel's fractional position (repeated over its three
//!   channels) and, when the integer offset is the same across the chunk and inside the image,
//!   blends two contiguous runs of the source row (horizontal pass) or of the source rows
//!   `y + k` and `y + k + 1` (vertical pass) — no clamps, no silhouette tests, no gathers;
//!   where the offset varies (the footprint changes across the chunk) or reaches past the
//!   border, it reads per pixel with the border clamp;
//! - a rotated (jittered) tap is a bilinear read at a per-pixel angle: positions and cells
//!   are computed for all pixels at once, then each pixel reads its four texels as 4-float
//!   loads and blends them in one 4-wide vector.

use super::pixel::{Pass, PassTaps};
use super::{NO_OBJECT, ScreenInput, rotation_index};
use rayon::prelude::*;

/// Pixels per chunk.
pub(super) const CHUNK: usize = 64;
/// Pixels per piece of a chunk that failed the test.
const SUBCHUNK: usize = 16;
/// Floats per chunk (RGB).
const FLOATS: usize = 3 * CHUNK;
/// Pixels per summary cell.
const CELL: usize = 16;

/// One summary cell: a run of up to [`CELL`] pixels of one row.
#[derive(Clone, Copy, Debug)]
struct Cell {
    /// The object id of the cell's first pixel.
    id: u32,
    /// Every pixel has that id (not [`NO_OBJECT`]) and a finite depth.
    uniform: bool,
    /// Smallest depth in the cell.
    dmin: f32,
    /// Largest depth in the cell.
    dmax: f32,
}

/// Per-row cells of object id and depth range, built once per frame (the silhouette test of a
/// chunk, hoisted).
pub(super) struct Summary {
    cols: usize,
    cells: Vec<Cell>,
    /// `bands[y * cols + c]` combines cells (y..y + BAND, c), for y + BAND ≤ height.
    bands: Vec<Cell>,
}

/// Rows per band of the summary (so a vertical pass checks a few bands, not every row).
const BAND: usize = 8;

impl Cell {
    /// The cell covering both.
    #[inline]
    fn join(self, o: Cell) -> Cell {
        Cell {
            id: self.id,
            uniform: self.uniform && o.uniform && self.id == o.id,
            dmin: self.dmin.min(o.dmin),
            dmax: self.dmax.max(o.dmax),
        }
    }

    /// Whether the cell shows `id` only, with depths in [lo, hi].
    #[inline(always)]
    fn within(&self, id: u32, lo: f32, hi: f32) -> bool {
        self.uniform & (self.id == id) & (self.dmin >= lo) & (self.dmax <= hi)
    }
}

impl Summary {
    /// Scans `input`'s mask and depth once.
    pub fn new(input: &ScreenInput) -> Summary {
        let w = input.width;
        let cols = w.div_ceil(CELL);
        let blank = Cell {
            id: NO_OBJECT,
            uniform: false,
            dmin: 0.0,
            dmax: 0.0,
        };
        let mut cells = vec![blank; cols * input.height];
        cells
            .par_chunks_mut(cols.max(1))
            .enumerate()
            .for_each(|(y, row)| {
                for (c, cell) in row.iter_mut().enumerate() {
                    let a = y * w + c * CELL;
                    let b = (a + CELL).min(y * w + w);
                    let id = input.mask[a];
                    let mut odd = 0u32;
                    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
                    for (&m, &d) in input.mask[a..b].iter().zip(&input.depth[a..b]) {
                        odd |= (m ^ id) | u32::from(!d.is_finite());
                        lo = lo.min(d);
                        hi = hi.max(d);
                    }
                    *cell = Cell {
                        id,
                        uniform: id != NO_OBJECT && odd == 0,
                        dmin: lo,
                        dmax: hi,
                    };
                }
            });
        let h = input.height;
        let mut bands = vec![blank; cols * (h + 1).saturating_sub(BAND)];
        bands
            .par_chunks_mut(cols.max(1))
            .enumerate()
            .for_each(|(y, row)| {
                for (c, band) in row.iter_mut().enumerate() {
                    *band = (y + 1..y + BAND)
                        .fold(cells[y * cols + c], |b, r| b.join(cells[r * cols + c]));
                }
            });
        Summary { cols, cells, bands }
    }

    /// The cells holding columns `xs.0..=xs.1` of row `y`.
    #[inline]
    fn cells(&self, y: usize, xs: (usize, usize)) -> &[Cell] {
        let r = y * self.cols;
        &self.cells[r + xs.0 / CELL..=r + xs.1 / CELL]
    }

    /// The depth range of columns `xs.0..=xs.1` of row `y` if they all show object `id` with
    /// finite depths (a superset: whole cells).
    #[inline]
    fn range(&self, id: u32, y: usize, xs: (usize, usize)) -> Option<(f32, f32)> {
        let (mut ok, mut lo, mut hi) = (true, f32::INFINITY, f32::NEG_INFINITY);
        for c in self.cells(y, xs) {
            ok &= c.uniform & (c.id == id);
            lo = lo.min(c.dmin);
            hi = hi.max(c.dmax);
        }
        ok.then_some((lo, hi))
    }

    /// Whether every pixel of rows `ys.0..=ys.1`, columns `xs.0..=xs.1` (and the rest of
    /// their cells) shows object `id` with a depth in [lo, hi].
    #[inline]
    fn clean(&self, id: u32, ys: (usize, usize), xs: (usize, usize), lo: f32, hi: f32) -> bool {
        let ok = |cells: &[Cell]| cells.iter().fold(true, |a, c| a & c.within(id, lo, hi));
        if ys.1 + 1 - ys.0 < BAND {
            return (ys.0..=ys.1).all(|y| ok(self.cells(y, xs)));
        }
        // Bands of BAND rows from ys.0, the last one ending at ys.1 (overlaps are harmless).
        let (c0, c1) = (xs.0 / CELL, xs.1 / CELL);
        let mut y = ys.0;
        loop {
            let start = y.min(ys.1 + 1 - BAND);
            let r = start * self.cols;
            if !ok(&self.bands[r + c0..=r + c1]) {
                return false;
            }
            if start + BAND > ys.1 {
                return true;
            }
            y += BAND;
        }
    }
}

/// The rotation step of every pixel ([`rotation_index`]), shared by every pass and term:
/// computed once per frame when the filter jitters.
pub(super) struct PixelTable {
    /// Rotation step of each pixel (empty without jitter).
    rotation: Vec<u8>,
}

impl PixelTable {
    /// The table of `input`; rotations only when `jitter`.
    pub fn new(input: &ScreenInput, seed: u64, jitter: bool) -> PixelTable {
        let w = input.width;
        let mut rotation = vec![0u8; if jitter { input.mask.len() } else { 0 }];
        rotation
            .par_chunks_mut(w.max(1))
            .enumerate()
            .for_each(|(y, row)| {
                for (x, r) in row.iter_mut().enumerate() {
                    *r = rotation_index(x, y, seed) as u8;
                }
            });
        PixelTable { rotation }
    }
}

/// A pass's taps laid out for the flat chunk loops.
pub(super) struct ChunkTaps {
    /// Per tap, its RGB weights repeated over a chunk's floats.
    pattern: Vec<[f32; FLOATS]>,
    /// Largest |offset| (mm) of the axis-aligned taps.
    axis_mm: f32,
    /// Largest |offset| (mm) of the rotated taps (0 without jitter).
    rotated_mm: f32,
}

impl ChunkTaps {
    /// The layout of `pass`'s taps.
    pub fn new(pass: &Pass) -> ChunkTaps {
        let t: &PassTaps = pass.taps;
        let (mut axis_mm, mut rotated_mm) = (0.0f32, 0.0f32);
        for &o in &t.offset {
            if pass.jitter && o.abs() <= pass.rotate_limit_mm {
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
            axis_mm,
            rotated_mm,
        }
    }
}

/// What every chunk of a pass reads besides the pass itself.
#[derive(Clone, Copy)]
pub(super) struct Ctx<'a> {
    pub summary: &'a Summary,
    pub table: &'a PixelTable,
    pub taps: &'a ChunkTaps,
    /// Use the x86-64 baseline code even where AVX2 is available (to test it).
    pub baseline: bool,
}

/// Per-thread scratch of the chunked pass (structure of arrays over a chunk's pixels, and
/// the same repeated over their channels).
pub(super) struct Lanes {
    /// Pixel index in the chunk, as f32.
    lane: [f32; CHUNK],
    /// x coordinate.
    px: [f32; CHUNK],
    /// 1 / mm_per_pixel.
    inv: [f32; CHUNK],
    /// An axis tap's first texel (minus the lane's own offset).
    cell: [f32; CHUNK],
    /// An axis tap's fractional position (in `fx`), repeated over the channels.
    frac3: [f32; FLOATS],
    /// A rotated tap's weighted value per pixel (RGB and a spare float).
    term4: [[f32; 4]; CHUNK],
    /// Rotated axis direction.
    rdx: [f32; CHUNK],
    rdy: [f32; CHUNK],
    /// Bilinear fractions and the four texel indices of a rotated tap.
    fx: [f32; CHUNK],
    fy: [f32; CHUNK],
    j: [[u32; CHUNK]; 4],
    /// The chunk's running sums, RGB per pixel.
    acc: [f32; FLOATS],
}

impl Lanes {
    /// Fresh scratch.
    pub fn new() -> Box<Lanes> {
        Box::new(Lanes {
            lane: std::array::from_fn(|l| l as f32),
            px: [0.0; CHUNK],
            inv: [0.0; CHUNK],
            cell: [0.0; CHUNK],
            frac3: [0.0; FLOATS],
            term4: [[0.0; 4]; CHUNK],
            rdx: [0.0; CHUNK],
            rdy: [0.0; CHUNK],
            fx: [0.0; CHUNK],
            fy: [0.0; CHUNK],
            j: [[0; CHUNK]; 4],
            acc: [0.0; FLOATS],
        })
    }
}

/// Where a row's values go: a row of an RGB image (flat), overwritten or added to.
pub(super) struct RowOut<'a> {
    pub row: &'a mut [f32],
    pub accumulate: bool,
}

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
    if !ctx.baseline && std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU was just checked to support AVX2, the only requirement of calling
        // a function compiled with `target_feature(enable = "avx2")`.
        return unsafe { row_avx2::<VERTICAL, JITTER>(pass, ctx, lanes, y, out) };
    }
    row_any::<VERTICAL, JITTER>(pass, ctx, lanes, y, out)
}

/// [`row_any`] compiled for AVX2: twice the vector width of the x86-64 baseline (SSE2). The
/// arithmetic is the same IEEE operations in the same order (Rust never fuses a multiply and
/// an add), so the result is identical.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn row_avx2<const VERTICAL: bool, const JITTER: bool>(
    pass: &Pass,
    ctx: &Ctx,
    lanes: &mut Lanes,
    y: usize,
    out: RowOut,
) -> usize {
    row_any::<VERTICAL, JITTER>(pass, ctx, lanes, y, out)
}

#[inline(always)]
fn row_any<const VERTICAL: bool, const JITTER: bool>(
    pass: &Pass,
    ctx: &Ctx,
    lanes: &mut Lanes,
    y: usize,
    mut out: RowOut,
) -> usize {
    let w = pass.input.width;
    let (mut x0, mut fast) = (0, 0);
    while x0 < w {
        let n = CHUNK.min(w - x0);
        if chunk::<VERTICAL, JITTER>(pass, ctx, lanes, x0, y, n) {
            store(&mut out, &lanes.acc[..3 * n], x0);
            fast += n;
        } else {
            // Near a silhouette: retry in smaller pieces (each reaches less far across the
            // pass), then pixel by pixel.
            let mut s0 = x0;
            while s0 < x0 + n {
                let k = SUBCHUNK.min(x0 + n - s0);
                if chunk::<VERTICAL, JITTER>(pass, ctx, lanes, s0, y, k) {
                    store(&mut out, &lanes.acc[..3 * k], s0);
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
    fast
}

/// Writes (or adds) the RGB values `v` at pixel `x0` of the output row.
#[inline(always)]
fn store(out: &mut RowOut, v: &[f32], x0: usize) {
    let dst = &mut out.row[3 * x0..3 * x0 + v.len()];
    if out.accumulate {
        for (d, a) in dst.iter_mut().zip(v) {
            *d += a;
        }
    } else {
        dst.copy_from_slice(v);
    }
}

/// Image coordinates (and tap positions, which stay within w + h of the image) below this
/// keep [`floor_small`] and [`small_u32`] exact.
const SMALL: usize = 1 << 20;

/// ⌊x⌋ for |x| < 2²², in float arithmetic that vectorises (a saturating `as i32` cast does
/// not): adding and subtracting 1.5 · 2²³ rounds to the nearest integer exactly in that
/// range, and one is taken off where that rounded up. Equals `floor_i32(x) as f32` there.
#[inline(always)]
fn floor_small(x: f32) -> f32 {
    const ROUND: f32 = 12_582_912.0;
    let r = (x + ROUND) - ROUND;
    r - if r > x { 1.0 } else { 0.0 }
}

/// `v as u32` for an integer-valued 0 ≤ v < 2²³, through its bits (vectorises): v + 2²³ has
/// v in its mantissa.
#[inline(always)]
fn small_u32(v: f32) -> u32 {
    (v + 8_388_608.0).to_bits() - 0x4B00_0000
}

/// `dst[3 l + c] = src[l]`: per-pixel values repeated over the three channels, eight pixels
/// at a time as one fixed shuffle (which compiles to a few vector permutes).
#[inline(always)]
fn spread3(src: &[f32], dst: &mut [f32]) {
    let mut blocks = dst.chunks_exact_mut(24);
    let mut sources = src.chunks_exact(8);
    for (d, s) in (&mut blocks).zip(&mut sources) {
        let s: &[f32; 8] = s.try_into().expect("8 values");
        let d: &mut [f32; 24] = d.try_into().expect("24 values");
        *d = std::array::from_fn(|i| s[i / 3]);
    }
    for (d, &s) in blocks
        .into_remainder()
        .chunks_exact_mut(3)
        .zip(sources.remainder())
    {
        d.fill(s);
    }
}

/// Texel `j` of a flat RGB image as 4 floats: RGB and the float after it (0 past the end).
#[inline(always)]
fn texel4(src: &[f32], j: u32) -> [f32; 4] {
    let i = 3 * j as usize;
    match src.get(i..i + 4).and_then(|s| <[f32; 4]>::try_from(s).ok()) {
        Some(v) => v,
        None => [src[i], src[i + 1], src[i + 2], 0.0],
    }
}

#[inline(always)]
fn splat(v: f32) -> [f32; 4] {
    [v; 4]
}

#[inline(always)]
fn add4(a: [f32; 4], b: [f32; 4]) -> [f32; 4] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3]]
}

#[inline(always)]
fn sub4(a: [f32; 4], b: [f32; 4]) -> [f32; 4] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2], a[3] - b[3]]
}

#[inline(always)]
fn mul4(a: [f32; 4], b: [f32; 4]) -> [f32; 4] {
    [a[0] * b[0], a[1] * b[1], a[2] * b[2], a[3] * b[3]]
}

/// The fast path for the `n` pixels of row `y` from column `x0`: true with their values in
/// `lanes.acc`, or false when the chunk needs the per-pixel path.
#[inline(always)]
fn chunk<const VERTICAL: bool, const JITTER: bool>(
    pass: &Pass,
    ctx: &Ctx,
    lanes: &mut Lanes,
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
    // Every pixel blurred (an integer OR fold rather than an early exit, so the loop
    // vectorises).
    let mut skipped = 0u32;
    for (v, &mm) in lanes.inv[..n].iter_mut().zip(&inp.mm_per_pixel[i0..i0 + n]) {
        let (inv, ok) = pass.rules.inverse_scale_lane(mm);
        *v = inv;
        skipped |= u32::from(!ok);
    }
    let inv_max = lanes.inv[..n].iter().fold(0.0f32, |a, &v| a.max(v));
    // One object with finite depths over the chunk's own cells, and their depth range.
    let Some((dmin0, dmax0)) = ctx.summary.range(id, y, (x0, x0 + n - 1)) else {
        return false;
    };
    if skipped != 0 {
        return false;
    }

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
    if !ctx.summary.clean(id, ys, xs, lo, hi) {
        return false;
    }

    // Every texel is kept: the taps in order, as `Pass::pixel_fast` sums them.
    let src = pass.src.as_flattened();
    let m = 3 * n;
    let (wmax, hmax) = (w as i32 - 1, h as i32 - 1);
    let lanes = &mut *lanes;
    let x0f = x0 as f32;
    for l in 0..n {
        lanes.px[l] = x0f + lanes.lane[l];
    }
    if JITTER {
        let rot = &ctx.table.rotation[i0..i0 + n];
        for l in 0..n {
            let (c, s) = pass.rotations[rot[l] as usize];
            (lanes.rdx[l], lanes.rdy[l]) = if VERTICAL { (-s, c) } else { (c, s) };
        }
    }
    lanes.acc[..m].fill(0.0);
    let yf = y as f32;
    let step = usize::from(!VERTICAL);
    let lim = if VERTICAL { hmax } else { wmax };
    let t = pass.taps;
    for (k, (&o_mm, wt)) in t.offset.iter().zip(&t.weight).enumerate() {
        let pattern = &taps.pattern[k][..m];
        if o_mm == 0.0 {
            // The centre tap reads the pixel itself.
            let s = &src[3 * i0..3 * i0 + m];
            for i in 0..m {
                lanes.acc[i] += pattern[i] * s[i];
            }
        } else if JITTER && o_mm.abs() <= pass.rotate_limit_mm {
            // Rotated tap: a bilinear read at p − o·dir. Positions and cells for all pixels,
            // then per pixel four 4-float reads and the blend.
            let (wf, hf) = (wmax as f32, hmax as f32);
            for l in 0..n {
                let o = o_mm * lanes.inv[l];
                let (sx, sy) = (lanes.px[l] - o * lanes.rdx[l], yf - o * lanes.rdy[l]);
                let (cx, cy) = (floor_small(sx), floor_small(sy));
                lanes.fx[l] = sx - cx;
                lanes.fy[l] = sy - cy;
                let (cx0, cx1) = (
                    small_u32(cx.clamp(0.0, wf)),
                    small_u32((cx + 1.0).clamp(0.0, wf)),
                );
                let (cy0, cy1) = (
                    small_u32(cy.clamp(0.0, hf)) * w as u32,
                    small_u32((cy + 1.0).clamp(0.0, hf)) * w as u32,
                );
                lanes.j[0][l] = cy0 + cx0;
                lanes.j[1][l] = cy0 + cx1;
                lanes.j[2][l] = cy1 + cx0;
                lanes.j[3][l] = cy1 + cx1;
            }
            // Per pixel: the four texels as 4-float reads (RGB and one float past it,
            // unused), blended in one 4-wide vector; the sums are updated in a second loop
            // (in place, 4-float stores overlapping the next pixel's would stall the loads
            // behind them).
            let w4 = [wt[0], wt[1], wt[2], 0.0];
            for l in 0..n {
                let a0 = texel4(src, lanes.j[0][l]);
                let a1 = texel4(src, lanes.j[1][l]);
                let b0 = texel4(src, lanes.j[2][l]);
                let b1 = texel4(src, lanes.j[3][l]);
                let (fx, fy) = (splat(lanes.fx[l]), splat(lanes.fy[l]));
                let top = add4(a0, mul4(fx, sub4(a1, a0)));
                let bottom = add4(b0, mul4(fx, sub4(b1, b0)));
                lanes.term4[l] = mul4(w4, add4(top, mul4(fy, sub4(bottom, top))));
            }
            for (a, t) in lanes.acc[..m].chunks_exact_mut(3).zip(&lanes.term4) {
                (a[0], a[1], a[2]) = (a[0] + t[0], a[1] + t[1], a[2] + t[2]);
            }
        } else {
            // Axis-aligned tap: a linear read at p − o along the axis.
            // Per pixel, then the fractions repeated over the channels.
            for l in 0..n {
                let o = o_mm * lanes.inv[l];
                let p = if VERTICAL { yf } else { lanes.px[l] } - o;
                let p0 = floor_small(p);
                lanes.fx[l] = p - p0;
                lanes.cell[l] = p0 - lanes.lane[l] * step as f32;
            }
            spread3(&lanes.fx[..n], &mut lanes.frac3[..m]);
            // cell is the first texel's coordinate minus the pixel's own offset in the
            // chunk: one value for the whole chunk unless the footprint changes across it.
            let cells = &lanes.cell[..n];
            let c0f = cells[0];
            // Equal floats here have equal bits (no −0, no NaN): an integer OR reduction,
            // which vectorises where a float comparison fold does not.
            let differ = cells
                .iter()
                .fold(0u32, |a, &c| a | (c.to_bits() ^ c0f.to_bits()));
            let c0 = c0f as i32;
            let last = c0 + (n - 1) as i32 * step as i32 + 1;
            let frac = &lanes.frac3[..m];
            if differ == 0 && c0 >= 0 && last <= lim {
                let first = if VERTICAL {
                    c0 as usize * w + x0
                } else {
                    y * w + c0 as usize
                };
                let next = first + if VERTICAL { w } else { 1 };
                let (s0, s1) = (&src[3 * first..3 * first + m], &src[3 * next..3 * next + m]);
                for i in 0..m {
                    lanes.acc[i] += pattern[i] * (s0[i] + frac[i] * (s1[i] - s0[i]));
                }
            } else {
                for l in 0..n {
                    let p0 = lanes.cell[l] as i32 + (l * step) as i32;
                    let (q0, q1) = (p0.clamp(0, lim) as usize, (p0 + 1).clamp(0, lim) as usize);
                    let (j0, j1) = if VERTICAL {
                        (q0 * w + x0 + l, q1 * w + x0 + l)
                    } else {
                        (y * w + q0, y * w + q1)
                    };
                    for c in 0..3 {
                        let (s0, s1) = (src[3 * j0 + c], src[3 * j1 + c]);
                        lanes.acc[3 * l + c] += wt[c] * (s0 + frac[3 * l] * (s1 - s0));
                    }
                }
            }
        }
    }
    true
}
