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
//! centre in the chunk. That test is hoisted out of the tap loop: a [`Summary`] holds, per row
//! and per cell of [`CELL`] pixels, whether the cell shows one object and its depth range, so
//! a chunk checks a few cells instead of every texel of every tap (conservatively: a chunk
//! whose reach touches a mixed cell goes pixel by pixel, through [`Pass::pixel`]). Cells are
//! joined into bands of 8 rows, and those into blocks of 64 pixels, tested first: away from
//! silhouettes and depth steps a chunk's reach is a handful of blocks.
//!
//! On x86-64 with AVX2 and FMA the chunks that pass are summed by [`super::groups`]; the
//! loops here are the portable form, for other CPUs (and `Evaluation::RowsBaseline`). The
//! chunk is a flat run of 3 × [`CHUNK`] floats (the RGB layout of the images) and each tap
//! is one loop over it:
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

use super::pixel::{Pass, PassTaps};
use super::{NO_OBJECT, Rules, ScreenInput, rotation_index};
use rayon::prelude::*;

/// Pixels per chunk.
pub(super) const CHUNK: usize = 64;
/// Pixels per piece of a chunk that failed the test.
const SUBCHUNK: usize = 16;
/// Floats per chunk (RGB).
const FLOATS: usize = 3 * CHUNK;
/// Rotated taps whose positions a chunk holds at once (more are summed in batches).
const ROTATED: usize = 4;
/// Per held rotated tap, one value per pixel of a chunk.
type Slots<T> = [[T; CHUNK]; ROTATED];
/// Pixels per summary cell.
const CELL: usize = 16;

/// One summary cell: a run of up to [`CELL`] pixels of one row.
#[derive(Clone, Copy, Debug)]
pub(super) struct Cell {
    /// The object id of the cell's first pixel.
    id: u32,
    /// Every pixel has that id (not [`NO_OBJECT`]) and a finite depth.
    uniform: bool,
    /// Smallest depth in the cell.
    dmin: f32,
    /// Largest depth in the cell.
    dmax: f32,
    /// Every pixel is blurred (a valid footprint over the sub-pixel limit, [`Rules`]).
    blurred: bool,
    /// The largest 1 / mm_per_pixel of the cell's blurred pixels (0 if none).
    inv_max: f32,
}

/// Per-row cells of object id and depth range, built once per frame (the silhouette test of a
/// chunk, hoisted).
pub(super) struct Summary {
    cols: usize,
    cells: Vec<Cell>,
    /// `bands[y * cols + c]` combines cells (y..y + BAND, c), for y + BAND ≤ height.
    bands: Vec<Cell>,
    /// Working rows of the bands (combinations of 4 rows), kept for the next frame.
    quads: Vec<Cell>,
    /// `blocks[y * ⌈cols / BLOCK⌉ + b]` combines bands (y, BLOCK·b..BLOCK·(b + 1)): 8 rows
    /// by 64 pixels, tested before the bands so a chunk far from any silhouette checks a few
    /// blocks instead of every cell its taps reach.
    blocks: Vec<Cell>,
}

/// Cells per block of the summary.
const BLOCK: usize = 4;

/// `dst` row y = `src` rows y and y + `step` joined, for `rows` rows of `cols` cells.
fn join_rows(
    src: &[Cell],
    dst: &mut Vec<Cell>,
    cols: usize,
    rows: usize,
    step: usize,
    blank: Cell,
) {
    dst.resize(cols * rows, blank);
    dst.par_chunks_mut(cols.max(1))
        .enumerate()
        .for_each(|(y, row)| {
            let (a, b) = (&src[y * cols..], &src[(y + step) * cols..]);
            for ((d, a), b) in row.iter_mut().zip(a).zip(b) {
                *d = a.join(*b);
            }
        });
}

/// Rows per band of the summary (so a vertical pass checks a few bands, not every row).
const BAND: usize = 8;

impl Cell {
    /// The cell covering both. (Plain comparisons, not `f32::min`: a NaN depth bound only
    /// occurs in a cell with no finite depth, which is not uniform, and neither is any join
    /// of it, so its bounds are never read.)
    #[inline]
    fn join(self, o: Cell) -> Cell {
        Cell {
            id: self.id,
            uniform: self.uniform & o.uniform & (self.id == o.id),
            dmin: if o.dmin < self.dmin {
                o.dmin
            } else {
                self.dmin
            },
            dmax: if o.dmax > self.dmax {
                o.dmax
            } else {
                self.dmax
            },
            blurred: self.blurred & o.blurred,
            inv_max: if o.inv_max > self.inv_max {
                o.inv_max
            } else {
                self.inv_max
            },
        }
    }

    /// Whether the cell shows `id` only, with depths in [lo, hi].
    #[inline(always)]
    fn within(&self, id: u32, lo: f32, hi: f32) -> bool {
        self.uniform & (self.id == id) & (self.dmin >= lo) & (self.dmax <= hi)
    }

    /// Whether every cell of `cells` is [`Cell::within`] (no early exit: the fold vectorises).
    #[inline(always)]
    fn all_within(cells: &[Cell], id: u32, lo: f32, hi: f32) -> bool {
        cells.iter().fold(true, |a, c| a & c.within(id, lo, hi))
    }
}

/// A key of f32 bits that orders like the floats (negative ones reversed below the
/// positive ones; −0 just below +0).
#[inline(always)]
fn order_key(bits: u32) -> u32 {
    let neg = 0u32.wrapping_sub(bits >> 31);
    bits ^ (neg | 0x8000_0000)
}

/// The f32 bits of an [`order_key`].
#[inline(always)]
fn order_bits(key: u32) -> u32 {
    let pos = 0u32.wrapping_sub(key >> 31);
    key ^ (!pos | 0x8000_0000)
}

/// [`summary_row`] in AVX2: each whole cell of [`CELL`] pixels as two 8-lane halves
/// ([`summary_cell_avx2`]), a partial last cell as the scalar form.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn summary_row_avx2(input: &ScreenInput, rules: &Rules, y: usize, row: &mut [Cell]) {
    let w = input.width;
    for (c, cell) in row.iter_mut().enumerate() {
        let a = y * w + c * CELL;
        let b = (a + CELL).min(y * w + w);
        let (mask, depth, mm) = (
            &input.mask[a..b],
            &input.depth[a..b],
            &input.mm_per_pixel[a..b],
        );
        *cell = match (mask.try_into(), depth.try_into(), mm.try_into()) {
            (Ok(mask), Ok(depth), Ok(mm)) => summary_cell_avx2(mask, depth, mm, rules),
            _ => summary_cell(mask, depth, mm, rules),
        };
    }
}

/// [`summary_cell`] of a whole cell in AVX2, the same bits: the folds are integer
/// (order-preserving keys of the depths, bits of the positive inverse footprints) and the
/// footprint rule is [`Rules::inverse_scale_lane`]'s f32 operations, lane by lane.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn summary_cell_avx2(
    mask: &[u32; CELL],
    depth: &[f32; CELL],
    mm: &[f32; CELL],
    rules: &Rules,
) -> Cell {
    use std::arch::x86_64::*;
    const _: () = assert!(CELL == 16, "two 8-lane halves");
    let id = mask[0];
    let idv = _mm256_set1_epi32(id as i32);
    let exp = _mm256_set1_epi32(0x7F80_0000);
    let sign = _mm256_set1_epi32(i32::MIN);
    let (one, zero) = (_mm256_set1_ps(1.0), _mm256_setzero_ps());
    let (twice_support, min_fp) = (
        _mm256_set1_ps(2.0 * rules.support_mm),
        _mm256_set1_ps(rules.min_footprint_px),
    );
    let (mut odd, mut inv_bits) = (_mm256_setzero_si256(), _mm256_setzero_si256());
    let (mut lo, mut hi) = (_mm256_set1_epi32(-1), _mm256_setzero_si256());
    let mut ok_all = -1i32;
    for half in 0..2 {
        // SAFETY: each array holds 16 values; the loads read 8 from 0 or 8.
        let (m, bits, f) = unsafe {
            (
                _mm256_loadu_si256(mask.as_ptr().add(8 * half).cast()),
                _mm256_loadu_si256(depth.as_ptr().add(8 * half).cast()),
                _mm256_loadu_ps(mm.as_ptr().add(8 * half)),
            )
        };
        // `odd`: another id, or a non-finite depth.
        let non_finite = _mm256_cmpeq_epi32(_mm256_and_si256(bits, exp), exp);
        odd = _mm256_or_si256(odd, _mm256_or_si256(_mm256_xor_si256(m, idv), non_finite));
        // order_key: bits ^ (neg | 0x8000_0000), neg = all ones for a set sign bit.
        let key = _mm256_xor_si256(bits, _mm256_or_si256(_mm256_srai_epi32::<31>(bits), sign));
        lo = _mm256_min_epu32(lo, key);
        hi = _mm256_max_epu32(hi, key);
        // inverse_scale_lane: (mm > 0) & mm finite & 2·support·inv ≥ min & inv finite.
        let inv = _mm256_div_ps(one, f);
        let ok = _mm256_and_ps(
            _mm256_and_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(f, zero), finite_lanes(f)),
            _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GE_OQ>(_mm256_mul_ps(twice_support, inv), min_fp),
                finite_lanes(inv),
            ),
        );
        ok_all &= _mm256_movemask_ps(ok);
        inv_bits = _mm256_max_epu32(inv_bits, _mm256_castps_si256(_mm256_and_ps(ok, inv)));
    }
    let odd = _mm256_testz_si256(odd, odd) == 0;
    Cell {
        id,
        uniform: id != NO_OBJECT && !odd,
        dmin: f32::from_bits(order_bits(fold_u32::<false>(lo))),
        dmax: f32::from_bits(order_bits(fold_u32::<true>(hi))),
        blurred: ok_all & 0xFF == 0xFF,
        inv_max: f32::from_bits(fold_u32::<true>(inv_bits)),
    }
}

/// The largest (`MAX`) or smallest of the 8 unsigned lanes of `v`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn fold_u32<const MAX: bool>(v: std::arch::x86_64::__m256i) -> u32 {
    use std::arch::x86_64::*;
    let mut v = v;
    for step in 0..3 {
        let other = match step {
            0 => _mm256_permute2x128_si256::<1>(v, v),
            1 => _mm256_shuffle_epi32::<0b01_00_11_10>(v),
            _ => _mm256_shuffle_epi32::<0b10_11_00_01>(v),
        };
        v = if MAX {
            _mm256_max_epu32(v, other)
        } else {
            _mm256_min_epu32(v, other)
        };
    }
    _mm256_cvtsi256_si32(v) as u32
}

/// All ones in the lanes of `v` that are finite, zeros elsewhere.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn finite_lanes(v: std::arch::x86_64::__m256) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    let exp = _mm256_set1_epi32(0x7F80_0000);
    let e = _mm256_and_si256(_mm256_castps_si256(v), exp);
    _mm256_castsi256_ps(_mm256_xor_si256(
        _mm256_cmpeq_epi32(e, exp),
        _mm256_set1_epi32(-1),
    ))
}

/// The cells of row `y`.
#[inline(always)]
fn summary_row(input: &ScreenInput, rules: &Rules, y: usize, row: &mut [Cell]) {
    let w = input.width;
    for (c, cell) in row.iter_mut().enumerate() {
        let a = y * w + c * CELL;
        let b = (a + CELL).min(y * w + w);
        *cell = summary_cell(
            &input.mask[a..b],
            &input.depth[a..b],
            &input.mm_per_pixel[a..b],
            rules,
        );
    }
}

/// The cell of one run of pixels (their masks, depths and footprints).
#[inline(always)]
fn summary_cell(mask: &[u32], depth: &[f32], mm: &[f32], rules: &Rules) -> Cell {
    let id = mask[0];
    // Integer folds (they vectorise; float min/max folds do not): a non-finite depth sets
    // `odd`, and the depth range is the range of order-preserving keys of the depths (of
    // use only when all are finite); the largest inverse footprint is the largest of their
    // bits (positive floats order as their bits).
    let mut odd = 0u32;
    let (mut lo, mut hi) = (u32::MAX, 0u32);
    for (&m, &d) in mask.iter().zip(depth) {
        let bits = d.to_bits();
        odd |= (m ^ id) | u32::from(bits & 0x7F80_0000 == 0x7F80_0000);
        let key = order_key(bits);
        lo = lo.min(key);
        hi = hi.max(key);
    }
    let (mut skipped, mut inv_bits) = (0u32, 0u32);
    for &mm in mm {
        let (inv, ok) = rules.inverse_scale_lane(mm);
        skipped |= u32::from(!ok);
        inv_bits = inv_bits.max(if ok { inv.to_bits() } else { 0 });
    }
    Cell {
        id,
        uniform: id != NO_OBJECT && odd == 0,
        dmin: f32::from_bits(order_bits(lo)),
        dmax: f32::from_bits(order_bits(hi)),
        blurred: skipped == 0,
        inv_max: f32::from_bits(inv_bits),
    }
}

impl Summary {
    /// Scans `input`'s mask, depth and footprint once (`rules`: which pixels are blurred).
    /// The summary of `input`, in `buffers` (cells, bands and the bands' working rows, from
    /// an earlier frame: every element used is written).
    ///
    /// `simd`: build the cells with AVX2 where the CPU has it (false: the portable code
    /// everywhere, for [`super::Evaluation::RowsBaseline`]; both give the same cells).
    pub fn new(
        input: &ScreenInput,
        rules: &Rules,
        buffers: [Vec<Cell>; 4],
        #[cfg_attr(not(target_arch = "x86_64"), allow(unused_variables))] simd: bool,
    ) -> Summary {
        let [mut cells, mut bands, mut quads, mut blocks] = buffers;
        let w = input.width;
        let cols = w.div_ceil(CELL);
        let blank = Cell {
            id: NO_OBJECT,
            uniform: false,
            dmin: 0.0,
            dmax: 0.0,
            blurred: false,
            inv_max: 0.0,
        };
        cells.resize(cols * input.height, blank);
        cells
            .par_chunks_mut(cols.max(1))
            .enumerate()
            .for_each(|(y, row)| {
                #[cfg(target_arch = "x86_64")]
                if simd && std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the CPU was just checked to support AVX2, the only requirement
                    // of calling a function compiled with it.
                    return unsafe { summary_row_avx2(input, rules, y, row) };
                }
                summary_row(input, rules, y, row)
            });
        // Bands of 8 rows by doubling: pairs of rows, then pairs of pairs, then of quads
        // (3 joins per cell instead of 7).
        const _: () = assert!(BAND == 8, "three doublings");
        let h = input.height;
        join_rows(&cells, &mut bands, cols, h.saturating_sub(1), 1, blank);
        join_rows(&bands, &mut quads, cols, h.saturating_sub(3), 2, blank);
        let band_rows = (h + 1).saturating_sub(BAND);
        join_rows(&quads, &mut bands, cols, band_rows, 4, blank);
        let per_row = cols.div_ceil(BLOCK);
        blocks.resize(per_row * band_rows, blank);
        blocks
            .par_chunks_mut(per_row.max(1))
            .enumerate()
            .for_each(|(y, row)| {
                let src = &bands[y * cols..(y + 1) * cols];
                for (d, part) in row.iter_mut().zip(src.chunks(BLOCK)) {
                    *d = part[1..].iter().fold(part[0], |a, c| a.join(*c));
                }
            });
        Summary {
            cols,
            cells,
            bands,
            quads,
            blocks,
        }
    }

    /// The buffers, for the next frame.
    pub fn into_buffers(self) -> [Vec<Cell>; 4] {
        [self.cells, self.bands, self.quads, self.blocks]
    }

    /// The cells holding columns `xs.0..=xs.1` of row `y`.
    #[inline]
    fn cells(&self, y: usize, xs: (usize, usize)) -> &[Cell] {
        let r = y * self.cols;
        &self.cells[r + xs.0 / CELL..=r + xs.1 / CELL]
    }

    /// The depth range and the largest 1 / mm_per_pixel of columns `xs.0..=xs.1` of row `y`
    /// if they all show object `id` with finite depths and are all blurred (whole cells: a
    /// chunk is a whole number of cells).
    #[inline]
    fn range(&self, id: u32, y: usize, xs: (usize, usize)) -> Option<(f32, f32, f32)> {
        let (mut ok, mut lo, mut hi, mut inv) = (true, f32::INFINITY, f32::NEG_INFINITY, 0.0f32);
        for c in self.cells(y, xs) {
            ok &= c.uniform & (c.id == id) & c.blurred;
            lo = lo.min(c.dmin);
            hi = hi.max(c.dmax);
            inv = inv.max(c.inv_max);
        }
        ok.then_some((lo, hi, inv))
    }

    /// The largest 1 / mm_per_pixel of row `y`'s blurred pixels.
    #[cfg(target_arch = "x86_64")]
    fn row_inv_max(&self, y: usize) -> f32 {
        let r = y * self.cols;
        self.cells[r..r + self.cols]
            .iter()
            .fold(0.0f32, |a, c| a.max(c.inv_max))
    }

    /// Whether every pixel of rows `ys.0..=ys.1`, columns `xs.0..=xs.1` (and the rest of
    /// their cells) shows object `id` with a depth in [lo, hi].
    #[inline]
    fn clean(&self, id: u32, ys: (usize, usize), xs: (usize, usize), lo: f32, hi: f32) -> bool {
        if ys.1 + 1 - ys.0 < BAND {
            return (ys.0..=ys.1).all(|y| Cell::all_within(self.cells(y, xs), id, lo, hi));
        }
        // Whole blocks first: they cover the rectangle and more, so if they pass, so would
        // its cells; if not (another object or a depth step within a block), its cells.
        self.banded::<true>(id, ys, xs, lo, hi) || self.banded::<false>(id, ys, xs, lo, hi)
    }

    /// [`Summary::clean`] of `ys.1 + 1 − ys.0 ≥ BAND` rows through bands of BAND rows from
    /// ys.0, the last one ending at ys.1 (overlaps are harmless), of cells or of whole
    /// `BLOCKS` (a stricter test: blocks cover whole 64-pixel runs).
    #[inline]
    fn banded<const BLOCKS: bool>(
        &self,
        id: u32,
        ys: (usize, usize),
        xs: (usize, usize),
        lo: f32,
        hi: f32,
    ) -> bool {
        let (grid, per_row, span) = if BLOCKS {
            (&self.blocks, self.cols.div_ceil(BLOCK), BLOCK * CELL)
        } else {
            (&self.bands, self.cols, CELL)
        };
        let (c0, c1) = (xs.0 / span, xs.1 / span);
        let mut y = ys.0;
        loop {
            let start = y.min(ys.1 + 1 - BAND);
            let r = start * per_row;
            if !Cell::all_within(&grid[r + c0..=r + c1], id, lo, hi) {
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
/// computed when the filter jitters, and kept in the caller's [`super::FilterScratch`] for
/// the next frame of the same size and seed. (One byte per pixel: a table of its cosine and
/// sine would save the per-chunk lookup but is 8 times the memory.)
pub(super) struct PixelTable {
    /// Rotation step of each pixel (not read without jitter).
    pub(super) rotation: Vec<u8>,
}

impl PixelTable {
    /// The table of `input` (rotations only when `jitter`), in `rotation`: the table of an
    /// earlier frame, kept as it is when that frame had the same size and seed (`key`).
    /// `simd` as for [`Summary::new`] (both give the same table).
    pub fn new(
        input: &ScreenInput,
        seed: u64,
        jitter: bool,
        mut rotation: Vec<u8>,
        key: &mut Option<(usize, usize, u64)>,
        #[cfg_attr(not(target_arch = "x86_64"), allow(unused_variables))] simd: bool,
    ) -> PixelTable {
        let w = input.width;
        let now = (w, input.height, seed);
        if !jitter {
            return PixelTable { rotation };
        }
        if *key == Some(now) && rotation.len() == input.mask.len() {
            return PixelTable { rotation };
        }
        *key = None;
        rotation.resize(input.mask.len(), 0);
        rotation
            .par_chunks_mut(w.max(1))
            .enumerate()
            .for_each(|(y, row)| {
                #[cfg(target_arch = "x86_64")]
                if simd && std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the CPU was just checked to support AVX2, the only requirement
                    // of calling a function compiled with it.
                    return unsafe { rotation_row_avx2(y, seed, row) };
                }
                rotation_row(y, seed, row)
            });
        *key = Some(now);
        PixelTable { rotation }
    }
}

/// The rotation steps of the pixels of row `y` ([`rotation_index`]).
fn rotation_row(y: usize, seed: u64, row: &mut [u8]) {
    for (x, r) in row.iter_mut().enumerate() {
        *r = rotation_index(x, y, seed) as u8;
    }
}

/// [`rotation_row`] four pixels at a time in AVX2's 64-bit lanes: the SplitMix64 finaliser
/// with each 64-bit product built from three 32-bit ones (AVX2 has no 64-bit multiply), so
/// every index is the scalar one, bit for bit (integer arithmetic).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn rotation_row_avx2(y: usize, seed: u64, row: &mut [u8]) {
    use std::arch::x86_64::*;
    /// a · m (mod 2⁶⁴) per lane, m = (m_hi, m_lo) as 32-bit halves in each lane.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn mul64(a: __m256i, m_lo: __m256i, m_hi: __m256i) -> __m256i {
        let lo = _mm256_mul_epu32(a, m_lo);
        let cross = _mm256_add_epi64(
            _mm256_mul_epu32(_mm256_srli_epi64::<32>(a), m_lo),
            _mm256_mul_epu32(a, m_hi),
        );
        _mm256_add_epi64(lo, _mm256_slli_epi64::<32>(cross))
    }
    /// The multipliers of `splitmix64_mix` as (low, high) 32-bit halves in 64-bit lanes.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn halves(m: u64) -> (__m256i, __m256i) {
        (
            _mm256_set1_epi64x((m & 0xffff_ffff) as i64),
            _mm256_set1_epi64x((m >> 32) as i64),
        )
    }
    const _: () = assert!(super::ROTATION_STEPS == 256, "the index is the top byte");
    let (m1_lo, m1_hi) = halves(0xbf58_476d_1ce4_e5b9);
    let (m2_lo, m2_hi) = halves(0x94d0_49bb_1331_11eb);
    // splitmix64(seed + ((y << 32) ^ x)) = mix(seed + (y << 32) + x + γ): x < 2³² (the image
    // width is at most i32::MAX), so the xor is an add.
    let start = seed
        .wrapping_add((y as u64) << 32)
        .wrapping_add(sss_util::GOLDEN_GAMMA);
    let mut z0 = _mm256_add_epi64(
        _mm256_set1_epi64x(start as i64),
        _mm256_setr_epi64x(0, 1, 2, 3),
    );
    let four = _mm256_set1_epi64x(4);
    let done = row.len() / 4 * 4;
    let mut quads = row.chunks_exact_mut(4);
    for q in &mut quads {
        let mut z = _mm256_xor_si256(z0, _mm256_srli_epi64::<30>(z0));
        z = mul64(z, m1_lo, m1_hi);
        z = _mm256_xor_si256(z, _mm256_srli_epi64::<27>(z));
        z = mul64(z, m2_lo, m2_hi);
        z = _mm256_xor_si256(z, _mm256_srli_epi64::<31>(z));
        // The top byte of each lane (`>> 56`; ROTATION_STEPS = 256 makes the `%` a no-op).
        let top = _mm256_srli_epi64::<56>(z);
        let mut v = [0u64; 4];
        // SAFETY: `v` holds four 64-bit lanes.
        unsafe { _mm256_storeu_si256(v.as_mut_ptr().cast(), top) };
        for (r, v) in q.iter_mut().zip(v) {
            *r = v as u8;
        }
        z0 = _mm256_add_epi64(z0, four);
    }
    for (x, r) in quads.into_remainder().iter_mut().enumerate() {
        *r = rotation_index(done + x, y, seed) as u8;
    }
}

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
    pub summary: &'a Summary,
    pub table: &'a PixelTable,
    pub taps: &'a ChunkTaps,
    /// The same taps for the AVX2 group loop.
    #[cfg(target_arch = "x86_64")]
    pub groups: &'a super::groups::GroupTaps,
    /// Use the x86-64 baseline code even where AVX2 is available (to test it).
    pub baseline: bool,
    /// Sum the chunks in 16-pixel AVX-512 groups (the CPU has AVX-512F and the caller did
    /// not ask for AVX2).
    #[cfg(target_arch = "x86_64")]
    pub avx512: bool,
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
    /// The horizontal pass's source row padded by its edge pixels (AVX2 build).
    #[cfg(target_arch = "x86_64")]
    padrow: Vec<f32>,
    /// An axis tap's fractional position per pixel, and the same repeated over the channels.
    frac: [f32; CHUNK],
    frac3: [f32; FLOATS],
    /// An axis tap's first texel minus the pixel's own offset, + 2²³, as bits.
    key: [u32; CHUNK],
    /// An axis tap's choice between two offsets (1: the larger) per pixel, and the same
    /// repeated over the channels.
    hi: [f32; CHUNK],
    hi3: [f32; FLOATS],
    /// Per rotated tap inside the image: each pixel's first texel, bilinear fractions, and
    /// the tap's index (grown to the most such taps seen).
    rj: Slots<u32>,
    rfx: Slots<f32>,
    rfy: Slots<f32>,
    rtap: [usize; ROTATED],
    /// The folded rotated sums, RGB per pixel (and one float written past the last pixel).
    rot3: [f32; FLOATS + 1],
    /// A rotated tap's cell (floored position) per pixel.
    cx: [f32; CHUNK],
    cy: [f32; CHUNK],
    /// Rotated axis direction.
    rdx: [f32; CHUNK],
    rdy: [f32; CHUNK],
    /// The four texel indices of a rotated tap near the border.
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
/// [`super::groups::chunk`] (multiply-adds fused, so its results differ from the baseline
/// build's by rounding: a few units in the last place of each sum), the rest as in the
/// baseline build.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn row_avx2<const VERTICAL: bool, const JITTER: bool>(
    pass: &Pass,
    ctx: &Ctx,
    lanes: &mut Lanes,
    y: usize,
    out: RowOut,
) -> usize {
    row_any::<VERTICAL, JITTER, true>(pass, ctx, lanes, y, out)
}

/// `a · b + c` as a multiply and an add (the portable loops' rounding; a fused multiply-add
/// would be a library call in the baseline build).
#[inline(always)]
fn mul_add(a: f32, b: f32, c: f32) -> f32 {
    a * b + c
}

#[inline(always)]
fn row_any<const VERTICAL: bool, const JITTER: bool, const AVX2: bool>(
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
struct PadRow {
    row: Vec<f32>,
    pad: Option<usize>,
}

/// (No padded row outside x86-64.)
#[cfg(not(target_arch = "x86_64"))]
struct PadRow;

/// Sums the chunk of `n` pixels of row `y` from `x0` through the fast path if it passes the
/// test ([`eligible`]). A function rather than a closure of [`row_any`] so that it is
/// inlined there and compiled with its target features (a closure is compiled without).
#[inline(always)]
fn fast_chunk<const VERTICAL: bool, const JITTER: bool, const AVX2: bool>(
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
                super::groups::pad_row(pass.src.as_flattened(), w, y, pad, &mut padrow.row);
                pad
            })
        };
        let srcs = super::groups::Sources {
            src: pass.src.as_flattened(),
            row: &padrow.row,
            pad,
        };
        // SAFETY: `AVX2` is only true in `row_avx2`, which is only called after checking
        // that the CPU has AVX2 and FMA.
        unsafe {
            if ctx.avx512 {
                // (And `avx512` is only set where the CPU has AVX-512F.)
                super::groups16::chunk::<VERTICAL, JITTER>(pass, ctx, &srcs, x0, y, n, out)
            } else {
                super::groups::chunk::<VERTICAL, JITTER>(pass, ctx, &srcs, x0, y, n, out)
            }
        };
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
fn row_reach(ctx: &Ctx, y: usize) -> usize {
    let inv_max = ctx.summary.row_inv_max(y);
    let reach = (ctx.taps.axis_mm * inv_max).ceil() + 4.0;
    if reach < 4096.0 { reach as usize } else { 4096 }
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
        let s: [f32; 8] = s.try_into().expect("8 values");
        let d: &mut [f32; 24] = d.try_into().expect("24 values");
        *d = [
            s[0], s[0], s[0], s[1], s[1], s[1], s[2], s[2], s[2], s[3], s[3], s[3], s[4], s[4],
            s[4], s[5], s[5], s[5], s[6], s[6], s[6], s[7], s[7], s[7],
        ];
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

/// Floats `i..i + 8` of a flat image (zeros past its end).
#[inline(always)]
fn load8(src: &[f32], i: usize) -> [f32; 8] {
    match src.get(i..).and_then(|s| s.first_chunk::<8>()) {
        Some(v) => *v,
        None => std::array::from_fn(|k| src.get(i + k).copied().unwrap_or(0.0)),
    }
}

/// Whether the `n` pixels of row `y` from column `x0` can take the fast path: all blurred,
/// one object, and every texel their taps can reach kept (the silhouette test, hoisted into
/// the [`Summary`]).
#[inline(always)]
fn eligible<const VERTICAL: bool, const JITTER: bool>(
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

/// The taps of a chunk that passed [`eligible`], summed into `lanes.acc` (the portable
/// form).
#[inline(always)]
fn sum_chunk<const VERTICAL: bool, const JITTER: bool>(
    pass: &Pass,
    ctx: &Ctx,
    lanes: &mut Lanes,
    x0: usize,
    y: usize,
    n: usize,
) {
    let inp = pass.input;
    let (w, h) = (inp.width, inp.height);
    let i0 = y * w + x0;
    let taps = ctx.taps;
    for (v, &mm) in lanes.inv[..n].iter_mut().zip(&inp.mm_per_pixel[i0..i0 + n]) {
        *v = pass.rules.inverse_scale_lane(mm).0;
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
        // The pass's rotated axis (c, s), or (−s, c) for the vertical pass (whose −s is
        // applied as an added product: x − o·(−s) = x + o·s, the same bits).
        let rot = &ctx.table.rotation[i0..i0 + n];
        for l in 0..n {
            let [c, s] = pass.rotations[rot[l] as usize];
            (lanes.rdx[l], lanes.rdy[l]) = if VERTICAL { (s, c) } else { (c, s) };
        }
    }
    lanes.acc[..m].fill(0.0);
    let yf = y as f32;
    let step = usize::from(!VERTICAL);
    let lim = if VERTICAL { hmax } else { wmax };
    let t = pass.taps;
    // Rotated taps whose cells are all inside the image: their positions are kept (in
    // `lanes.rj`, `rfx`, `rfy`, `rtap`) and summed after the other taps, per pixel.
    let mut inside = 0;
    for (k, (&o_mm, wt)) in t.offset.iter().zip(&t.weight).enumerate() {
        let pattern = &taps.pattern[k][..m];
        if o_mm == 0.0 {
            // The centre tap reads the pixel itself.
            let s = &src[3 * i0..3 * i0 + m];
            for i in 0..m {
                lanes.acc[i] = mul_add(pattern[i], s[i], lanes.acc[i]);
            }
        } else if JITTER && pass.rotates(o_mm) {
            // Rotated tap: a bilinear read at p − o·dir. Positions and cells for all pixels,
            // then per pixel the reads and the blend.
            if inside == ROTATED {
                rotated_sums(lanes, taps, src, w, n, inside);
                inside = 0;
            }
            let (wf, hf) = (wmax as f32, hmax as f32);
            let edge = rotated_cells::<VERTICAL>(
                (o_mm, yf, w, wf, hf),
                &lanes.inv[..n],
                (&lanes.px[..n], &lanes.rdx[..n], &lanes.rdy[..n]),
                &mut lanes.rj[inside][..n],
                (&mut lanes.rfx[inside][..n], &mut lanes.rfy[inside][..n]),
                (&mut lanes.cx[..n], &mut lanes.cy[..n]),
            );
            if !edge {
                lanes.rtap[inside] = k;
                inside += 1;
            } else {
                // Near the border: the four clamped texels of each pixel, as the per-pixel
                // form reads them.
                for l in 0..n {
                    let (cx, cy) = (lanes.cx[l], lanes.cy[l]);
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
                for l in 0..n {
                    let a0 = texel4(src, lanes.j[0][l]);
                    let a1 = texel4(src, lanes.j[1][l]);
                    let b0 = texel4(src, lanes.j[2][l]);
                    let b1 = texel4(src, lanes.j[3][l]);
                    let (fx, fy) = (lanes.rfx[inside][l], lanes.rfy[inside][l]);
                    for c in 0..3 {
                        let top = mul_add(fx, a1[c] - a0[c], a0[c]);
                        let bottom = mul_add(fx, b1[c] - b0[c], b0[c]);
                        let a = &mut lanes.acc[3 * l + c];
                        *a = mul_add(wt[c], mul_add(fy, bottom - top, top), *a);
                    }
                }
            }
        } else {
            // Axis-aligned tap: a linear read at p − o along the axis. Positions per pixel
            // (the per-pixel form's f32 operations, so the same values), then the fractions
            // repeated over the channels.
            for l in 0..n {
                let o = o_mm * lanes.inv[l];
                let p = if VERTICAL { yf } else { lanes.px[l] } - o;
                let p0 = floor_small(p);
                lanes.frac[l] = p - p0;
                // The first texel's coordinate minus the pixel's own offset in the chunk (one
                // value for the whole chunk unless the footprint changes across it), as the
                // bits of cell + 2²³: monotonic for |cell| < 2²², so its range is an integer
                // fold, which vectorises where a float comparison fold does not.
                lanes.key[l] = (p0 - lanes.lane[l] * step as f32 + 8_388_608.0).to_bits();
            }
            spread3(&lanes.frac[..n], &mut lanes.frac3[..m]);
            let (kmin, kmax) = lanes.key[..n]
                .iter()
                .fold((u32::MAX, 0u32), |(lo, hi), &k| (lo.min(k), hi.max(k)));
            let c0 = (f32::from_bits(kmin) - 8_388_608.0) as i32;
            let spread = kmax - kmin;
            let last = c0 + spread as i32 + (n - 1) as i32 * step as i32 + 1;
            let frac = &lanes.frac3[..m];
            let first = if VERTICAL {
                c0.max(0) as usize * w + x0
            } else {
                y * w + c0.max(0) as usize
            };
            let next = if VERTICAL { w } else { 1 };
            if spread == 0 && c0 >= 0 && last <= lim {
                // One offset: two contiguous runs of the source.
                let s0 = &src[3 * first..3 * first + m];
                let s1 = &src[3 * (first + next)..3 * (first + next) + m];
                for i in 0..m {
                    let v = mul_add(frac[i], s1[i] - s0[i], s0[i]);
                    lanes.acc[i] = mul_add(pattern[i], v, lanes.acc[i]);
                }
            } else if spread == 1 && c0 >= 0 && last <= lim {
                // Two offsets (the footprint changes across the chunk): three contiguous runs,
                // each pixel blending the first two or the last two.
                for l in 0..n {
                    lanes.hi[l] = f32::from(u8::from(lanes.key[l] != kmin));
                }
                spread3(&lanes.hi[..n], &mut lanes.hi3[..m]);
                let hi = &lanes.hi3[..m];
                let s0 = &src[3 * first..3 * first + m];
                let s1 = &src[3 * (first + next)..3 * (first + next) + m];
                let s2 = &src[3 * (first + 2 * next)..3 * (first + 2 * next) + m];
                for i in 0..m {
                    let up = hi[i] != 0.0;
                    let (a, b) = if up { (s1[i], s2[i]) } else { (s0[i], s1[i]) };
                    let v = mul_add(frac[i], b - a, a);
                    lanes.acc[i] = mul_add(pattern[i], v, lanes.acc[i]);
                }
            } else {
                for l in 0..n {
                    let cell = f32::from_bits(lanes.key[l]) - 8_388_608.0;
                    let p0 = cell as i32 + (l * step) as i32;
                    let (q0, q1) = (p0.clamp(0, lim) as usize, (p0 + 1).clamp(0, lim) as usize);
                    let (j0, j1) = if VERTICAL {
                        (q0 * w + x0 + l, q1 * w + x0 + l)
                    } else {
                        (y * w + q0, y * w + q1)
                    };
                    for c in 0..3 {
                        let (s0, s1) = (src[3 * j0 + c], src[3 * j1 + c]);
                        let v = mul_add(frac[3 * l], s1 - s0, s0);
                        lanes.acc[3 * l + c] = mul_add(wt[c], v, lanes.acc[3 * l + c]);
                    }
                }
            }
        }
    }
    if inside > 0 {
        rotated_sums(lanes, taps, src, w, n, inside);
    }
}

/// Adds the first `inside` rotated taps held in `lanes` (cells inside the image) to the
/// chunk's sums, per pixel: each cell's two texels of a row are six contiguous floats, read
/// as one 8-float load per row. The row pair is blended along y first, then weighted by
/// [(1 − fx)·wt, fx·wt, 0, 0] (as 8 lanes) and summed over the taps in registers; the halves
/// are folded and written as 4 floats that overlap the next pixel's (in order, so each keeps
/// its 3), then added.
#[inline(always)]
fn rotated_sums(
    lanes: &mut Lanes,
    taps: &ChunkTaps,
    src: &[f32],
    w: usize,
    n: usize,
    inside: usize,
) {
    let down = 3 * w;
    let n = n.min(CHUNK);
    let inside = inside.min(ROTATED);
    let (rj, rfx, rfy) = (
        &lanes.rj[..inside],
        &lanes.rfx[..inside],
        &lanes.rfy[..inside],
    );
    let rtap = &lanes.rtap[..inside];
    let rot3 = &mut lanes.rot3;
    for l in 0..n {
        let mut r = [0.0f32; 8];
        for q in 0..inside {
            let j = 3 * rj[q][l] as usize;
            let (a, b) = (load8(src, j), load8(src, j + down));
            let (fx, fy) = (rfx[q][l], rfy[q][l]);
            let k = rtap[q];
            let (wlo, wd) = (&taps.rot_lo[k], &taps.rot_d[k]);
            let v: [f32; 8] = std::array::from_fn(|i| mul_add(fy, b[i] - a[i], a[i]));
            let x: [f32; 8] = std::array::from_fn(|i| mul_add(fx, wd[i], wlo[i]));
            r = std::array::from_fn(|i| mul_add(x[i], v[i], r[i]));
        }
        // (The fourth float, overwritten by the next pixel's, folds the two spare lanes: it
        // keeps all eight lanes live, so the compiler reads them as one vector.)
        let v = [r[0] + r[3], r[1] + r[4], r[2] + r[5], r[6] + r[7]];
        rot3[3 * l..3 * l + 4].copy_from_slice(&v);
    }
    for i in 0..3 * n {
        lanes.acc[i] += lanes.rot3[i];
    }
}

/// A rotated tap's cells for the chunk's pixels (`rdx` holds −(the x direction) in the
/// vertical pass): `rj` the first texel (unclamped),
/// `f` the bilinear fractions, `c` the floored positions; returns whether a cell reaches past
/// the border (then `rj` is not valid). Separate arguments, so the compiler knows the arrays
/// do not overlap and vectorises the loop.
#[inline(always)]
fn rotated_cells<const VERTICAL: bool>(
    (o_mm, yf, w, wf, hf): (f32, f32, usize, f32, f32),
    inv: &[f32],
    (px, rdx, rdy): (&[f32], &[f32], &[f32]),
    rj: &mut [u32],
    (rfx, rfy): (&mut [f32], &mut [f32]),
    (cxs, cys): (&mut [f32], &mut [f32]),
) -> bool {
    let n = inv.len();
    let (px, rdx, rdy) = (&px[..n], &rdx[..n], &rdy[..n]);
    let (rj, rfx, rfy, cxs, cys) = (
        &mut rj[..n],
        &mut rfx[..n],
        &mut rfy[..n],
        &mut cxs[..n],
        &mut cys[..n],
    );
    let mut edge = 0u32;
    for l in 0..n {
        let o = o_mm * inv[l];
        let sx = if VERTICAL {
            px[l] + o * rdx[l]
        } else {
            px[l] - o * rdx[l]
        };
        let sy = yf - o * rdy[l];
        let (cx, cy) = (floor_small(sx), floor_small(sy));
        rfx[l] = sx - cx;
        rfy[l] = sy - cy;
        edge |= u32::from(cx < 0.0) | u32::from(cx >= wf);
        edge |= u32::from(cy < 0.0) | u32::from(cy >= hf);
        cxs[l] = cx;
        cys[l] = cy;
        // Through the bits of c + 2²³ (wrapping where c < 0: then `edge` is set).
        let bits = |c: f32| (c + 8_388_608.0).to_bits().wrapping_sub(0x4B00_0000);
        rj[l] = bits(cx).wrapping_add(bits(cy).wrapping_mul(w as u32));
    }
    edge != 0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The AVX2 summary cell is the scalar one, bit for bit, on cells that mix every kind of
    /// value the rules treat apart: other ids, background, non-finite and negative depths,
    /// −0, zero, negative, non-finite, subnormal and sub-pixel footprints.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn avx2_summary_cells_match_the_scalar_ones() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("skipped: this CPU has no AVX2");
            return;
        }
        let rules = Rules {
            support_mm: 14.0,
            depth_mm: 14.0,
            min_footprint_px: 1.0,
        };
        let depths = [
            600.0,
            601.5,
            -3.0,
            -0.0,
            0.0,
            1e30,
            f32::NAN,
            f32::INFINITY,
            -f32::INFINITY,
        ];
        let footprints = [
            0.5,
            0.3,
            27.9,
            28.1,
            0.0,
            -0.5,
            f32::NAN,
            f32::INFINITY,
            1e-40,
            1e-30,
        ];
        let key = |c: &Cell| {
            (
                c.id,
                c.uniform,
                c.dmin.to_bits(),
                c.dmax.to_bits(),
                c.blurred,
                c.inv_max.to_bits(),
            )
        };
        let (mut uniform, mut blurred) = (0, 0);
        for t in 0..4000u64 {
            let r = |k: u64, n: usize| (sss_util::splitmix64(t * 64 + k) % n as u64) as usize;
            // Most cells clean (one id, finite depths, valid footprints), with a few odd
            // pixels sprinkled in, so both outcomes of every test are reached.
            let odd = r(99, 4);
            let mask: [u32; CELL] = std::array::from_fn(|i| match (odd, r(i as u64, 16)) {
                (0, 0) => 7,
                (0, 1) => NO_OBJECT,
                _ => {
                    if t % 50 == 0 {
                        NO_OBJECT
                    } else {
                        3
                    }
                }
            });
            let depth: [f32; CELL] = std::array::from_fn(|i| {
                if odd == 1 {
                    depths[r(20 + i as u64, depths.len())]
                } else {
                    600.0 + r(20 + i as u64, 1000) as f32 * 0.01
                }
            });
            let mm: [f32; CELL] = std::array::from_fn(|i| {
                if odd == 2 {
                    footprints[r(40 + i as u64, footprints.len())]
                } else {
                    footprints[r(40 + i as u64, 3)]
                }
            });
            let scalar = summary_cell(&mask, &depth, &mm, &rules);
            // SAFETY: the CPU was checked to support AVX2.
            let vector = unsafe { summary_cell_avx2(&mask, &depth, &mm, &rules) };
            assert_eq!(
                key(&vector),
                key(&scalar),
                "cell {t}: {mask:?} {depth:?} {mm:?}"
            );
            uniform += usize::from(scalar.uniform);
            blurred += usize::from(scalar.blurred);
        }
        // Both outcomes of each test were compared.
        assert!((500..3500).contains(&uniform), "{uniform} uniform cells");
        assert!((500..3500).contains(&blurred), "{blurred} blurred cells");
    }

    /// The hoisted silhouette test is the per-pixel one over whole cells: on a frame with
    /// another object, a background strip, a raised patch and a non-finite depth,
    /// [`Summary::clean`] says a rectangle's cells show only `id` with finite depths in
    /// [lo, hi] exactly when every pixel of them does, for rectangles of 1 to 40 rows, both
    /// where the blocks pass and where only the cells do.
    #[test]
    fn clean_is_the_per_pixel_test() {
        let (w, h) = (203, 70);
        let n = w * h;
        let mut mask = vec![1u32; n];
        let mut depth: Vec<f32> = (0..n)
            .map(|i| 600.0 + 0.02 * (i % w) as f32 + 0.03 * (i / w) as f32)
            .collect();
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let (dx, dy) = (x as f32 - 120.0, y as f32 - 30.0);
                if dx * dx + dy * dy < 90.0 {
                    mask[i] = 2;
                }
                if (10..13).contains(&y) && x < 70 {
                    mask[i] = NO_OBJECT;
                }
                if (40..47).contains(&x) && (50..58).contains(&y) {
                    depth[i] += 25.0;
                }
            }
        }
        depth[66 * w + 180] = f32::NAN;
        let mm = vec![0.5f32; n];
        let irradiance = vec![[0.0f32; 3]; n];
        let input = ScreenInput {
            width: w,
            height: h,
            irradiance: &irradiance,
            depth: &depth,
            mask: &mask,
            mm_per_pixel: &mm,
        };
        let rules = Rules {
            support_mm: 14.0,
            depth_mm: 14.0,
            min_footprint_px: 1.0,
        };
        let s = Summary::new(&input, &rules, Default::default(), true);
        let (mut kept, mut by_cells) = (0, 0);
        for t in 0..20_000u64 {
            let r = |k: u64, m: usize| (sss_util::splitmix64(t * 16 + k) % m as u64) as usize;
            let id = if r(0, 4) == 0 { 2 } else { 1 };
            let rows = 1 + r(1, 40);
            let y0 = r(2, h - rows + 1);
            let x0 = r(3, w);
            let x1 = (x0 + r(4, 120)).min(w - 1);
            let (ys, xs) = ((y0, y0 + rows - 1), (x0, x1));
            let lo = 600.0 + r(5, 6) as f32;
            let hi = lo + [3.0, 10.0, 30.0][r(6, 3)];
            // Every pixel of the cells holding columns x0..=x1.
            let expected = (ys.0..=ys.1).all(|y| {
                (x0 / CELL * CELL..((x1 / CELL + 1) * CELL).min(w)).all(|x| {
                    let (m, d) = (mask[y * w + x], depth[y * w + x]);
                    m == id && d.is_finite() && d >= lo && d <= hi
                })
            });
            let got = s.clean(id, ys, xs, lo, hi);
            assert_eq!(
                got, expected,
                "id {id}, rows {ys:?}, columns {xs:?}, [{lo}, {hi}]"
            );
            kept += usize::from(got);
            if got && rows >= BAND && !s.banded::<true>(id, ys, xs, lo, hi) {
                by_cells += 1;
            }
        }
        // Both outcomes, and rectangles that only the cells' test keeps.
        assert!((2_000..18_000).contains(&kept), "{kept} rectangles kept");
        assert!(by_cells >= 200, "{by_cells} kept by the cells only");
    }

    /// The AVX2 rotation table is the scalar hash, pixel for pixel: row lengths around the
    /// 4-pixel step, rows far down (y enters the hash's high half), seeds that wrap.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn avx2_rotation_rows_match_the_scalar_hash() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("skipped: this CPU has no AVX2");
            return;
        }
        let mut checked = 0;
        for seed in [0, 1, 0x9e37_79b9_7f4a_7c15, u64::MAX - 2] {
            for y in [0, 1, 7, 1079, 65_537, (1 << 31) - 1] {
                for w in [0, 1, 3, 4, 5, 8, 13, 1921] {
                    let (mut a, mut b) = (vec![0u8; w], vec![0u8; w]);
                    rotation_row(y, seed, &mut a);
                    // SAFETY: the CPU was checked to support AVX2.
                    unsafe { rotation_row_avx2(y, seed, &mut b) };
                    assert_eq!(a, b, "seed {seed}, row {y}, width {w}");
                    checked += w;
                }
            }
        }
        // The table is not constant (a broken hash could still agree with itself).
        let mut row = vec![0u8; 1024];
        rotation_row(5, 0, &mut row);
        let distinct = (0..256).filter(|v| row.contains(&(*v as u8))).count();
        assert!(
            distinct > 200,
            "{distinct} distinct rotations in 1024 pixels"
        );
        assert_eq!(checked, 24 * 1955);
    }
}
