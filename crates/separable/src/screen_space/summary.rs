//! The per-frame summary the row-chunked form tests its chunks against: per row and per cell
//! of [`CELL`] pixels, whether the cell shows one object, its depth range and footprint
//! bound ([`Cell`]), joined into bands of 8 rows and blocks of 64 pixels ([`CellSummary`]), so a
//! chunk checks a few cells instead of every texel its taps reach. The portable form; the
//! AVX2 one is in [`super::avx2`] and gives the same bits.

use super::{NO_OBJECT, Rules, ScreenInput};
use rayon::prelude::*;

/// Pixels per summary cell.
pub(super) const CELL: usize = 16;

/// One summary cell: a run of up to [`CELL`] pixels of one row.
#[derive(Clone, Copy, Debug)]
pub(super) struct Cell {
    /// The object id of the cell's first pixel.
    pub(super) id: u32,
    /// Every pixel has that id (not [`NO_OBJECT`]) and a finite depth.
    pub(super) uniform: bool,
    /// Smallest depth in the cell.
    pub(super) dmin: f32,
    /// Largest depth in the cell.
    pub(super) dmax: f32,
    /// Every pixel is blurred (a valid footprint over the sub-pixel limit, [`Rules`]).
    pub(super) blurred: bool,
    /// The largest 1 / mm_per_pixel of the cell's blurred pixels (0 if none).
    pub(super) inv_max: f32,
}

/// Per-row cells of object id and depth range, built once per frame (the silhouette test of a
/// chunk, hoisted).
pub(super) struct CellSummary {
    pub(super) cols: usize,
    pub(super) cells: Vec<Cell>,
    /// `bands[y * cols + c]` combines cells (y..y + BAND, c), for y + BAND ≤ height.
    pub(super) bands: Vec<Cell>,
    /// Working rows of the bands (combinations of 4 rows), kept for the next frame.
    pub(super) quads: Vec<Cell>,
    /// `blocks[y * ⌈cols / BLOCK⌉ + b]` combines bands (y, BLOCK·b..BLOCK·(b + 1)): 8 rows
    /// by 64 pixels, tested before the bands so a chunk far from any silhouette checks a few
    /// blocks instead of every cell its taps reach.
    pub(super) blocks: Vec<Cell>,
}

/// Cells per block of the summary.
pub(super) const BLOCK: usize = 4;

/// `dst` row y = `src` rows y and y + `step` joined, for `rows` rows of `cols` cells.
pub(super) fn join_rows(
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
pub(super) const BAND: usize = 8;

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
pub(super) fn order_key(bits: u32) -> u32 {
    let neg = 0u32.wrapping_sub(bits >> 31);
    bits ^ (neg | 0x8000_0000)
}

/// The f32 bits of an [`order_key`].
#[inline(always)]
pub(super) fn order_bits(key: u32) -> u32 {
    let pos = 0u32.wrapping_sub(key >> 31);
    key ^ (!pos | 0x8000_0000)
}

/// The cells of row `y`.
#[inline(always)]
pub(super) fn summary_row(input: &ScreenInput, rules: &Rules, y: usize, row: &mut [Cell]) {
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
pub(super) fn summary_cell(mask: &[u32], depth: &[f32], mm: &[f32], rules: &Rules) -> Cell {
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

/// Builds one row of cells: the portable [`summary_row`] or its AVX2 form (the same cells).
pub(super) type RowFill = dyn Fn(&ScreenInput, &Rules, usize, &mut [Cell]) + Sync;

impl CellSummary {
    /// Scans `input`'s mask, depth and footprint once (`rules`: which pixels are blurred).
    /// The summary of `input`, in `buffers` (cells, bands and the bands' working rows, from
    /// an earlier frame: every element used is written).
    ///
    /// `fill` builds one row of cells (the portable [`summary_row`] or its AVX2 form, which
    /// give the same cells).
    pub fn new(
        input: &ScreenInput,
        rules: &Rules,
        buffers: [Vec<Cell>; 4],
        fill: &RowFill,
    ) -> CellSummary {
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
            .for_each(|(y, row)| fill(input, rules, y, row));
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
        CellSummary {
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
    pub(super) fn range(&self, id: u32, y: usize, xs: (usize, usize)) -> Option<(f32, f32, f32)> {
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
    pub(super) fn row_inv_max(&self, y: usize) -> f32 {
        let r = y * self.cols;
        self.cells[r..r + self.cols]
            .iter()
            .fold(0.0f32, |a, c| a.max(c.inv_max))
    }

    /// Whether every pixel of rows `ys.0..=ys.1`, columns `xs.0..=xs.1` (and the rest of
    /// their cells) shows object `id` with a depth in [lo, hi].
    #[inline]
    pub(super) fn clean(
        &self,
        id: u32,
        ys: (usize, usize),
        xs: (usize, usize),
        lo: f32,
        hi: f32,
    ) -> bool {
        if ys.1 + 1 - ys.0 < BAND {
            return (ys.0..=ys.1).all(|y| Cell::all_within(self.cells(y, xs), id, lo, hi));
        }
        // Whole blocks first: they cover the rectangle and more, so if they pass, so would
        // its cells; if not (another object or a depth step within a block), its cells.
        self.banded::<true>(id, ys, xs, lo, hi) || self.banded::<false>(id, ys, xs, lo, hi)
    }

    /// [`CellSummary::clean`] of `ys.1 + 1 − ys.0 ≥ BAND` rows through bands of BAND rows from
    /// ys.0, the last one ending at ys.1 (overlaps are harmless), of cells or of whole
    /// `BLOCKS` (a stricter test: blocks cover whole 64-pixel runs).
    #[inline]
    pub(super) fn banded<const BLOCKS: bool>(
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
