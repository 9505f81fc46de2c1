//! The per-pixel rotation table of the jittered passes ([`PixelTable`]): each pixel's index
//! into the rotation steps, hashed from its position and the seed once per frame size and
//! seed, and kept in the caller's scratch. The portable form; the AVX2 one is in
//! [`super::avx2`] and gives the same bytes.

use super::{ScreenInput, rotation_index};
use rayon::prelude::*;

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
    /// `fill` computes one row (the portable [`rotation_row`] or its AVX2 form, which give the
    /// same bytes).
    pub fn new(
        input: &ScreenInput,
        seed: u64,
        jitter: bool,
        mut rotation: Vec<u8>,
        key: &mut Option<(usize, usize, u64)>,
        fill: &(dyn Fn(usize, u64, &mut [u8]) + Sync),
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
            .for_each(|(y, row)| fill(y, seed, row));
        *key = Some(now);
        PixelTable { rotation }
    }
}

/// The rotation steps of the pixels of row `y` ([`rotation_index`]).
pub(super) fn rotation_row(y: usize, seed: u64, row: &mut [u8]) {
    for (x, r) in row.iter_mut().enumerate() {
        *r = rotation_index(x, y, seed) as u8;
    }
}
