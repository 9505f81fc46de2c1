//! The fast path of the row-chunked pass in AVX2 + FMA intrinsics: a chunk that passed the
//! silhouette test of [`super::rows`] is summed in groups of 8 pixels, each group's sums
//! held as three 8-lane vectors (the group's 24 floats of RGB). The taps are the outer loop
//! and the chunk's groups the inner one, so that what a tap needs once per chunk is found
//! once.
//!
//! Per group and tap, as [`super::pixel::Pass::pixel`] computes them, with the same f32
//! operations (so the same positions and fractions, bit for bit):
//! - an axis-aligned tap computes the 8 pixels' positions in one register, then their
//!   fractions are spread over the channels with three permutes. When all the chunk's pixels
//!   share their integer offset (the footprint changes slowly), each group blends its part of
//!   two unaligned runs of the source found once for the chunk; otherwise each group reads
//!   three runs from its own smallest offset, each pixel blending the first two or the last
//!   two (a per-lane select), or goes pixel by pixel if its offsets span more than two
//!   values. The horizontal pass reads a copy of the source row
//!   padded on both sides by its edge pixels (the clamp to the edge, done once per row), the
//!   vertical pass reads whole source rows whose index is clamped once per tap;
//! - the centre tap reads the group's own 24 floats;
//! - a rotated (jittered) tap is a bilinear read at each pixel's own angle: the positions
//!   and cells of the 8 pixels are computed in registers, then each pixel reads its cell's
//!   two rows as two 8-float loads (the cell's two texels are six contiguous floats), blends
//!   them along y, weights them by [(1 − fx)·w, fx·w] and adds them up over the rotated taps;
//!   the sums are added after the other taps. A batch of taps with a cell at the image
//!   border reads each pixel's four texels clamped to the image instead (masked 3-float
//!   loads, no round trip through memory).
//!
//! The rounding differs from the per-pixel form's (fused multiply-adds, rotated taps summed
//! last), within the tolerance stated in [`super`].
//!
//! The AVX2 forms of the per-frame summary's cells ([`summary_row_avx2`]) and of the rotation
//! table ([`rotation_row_avx2`]) live here too, beside the group loops: every AVX2 + FMA path
//! of the pass is in this file, each tested against its portable form bit for bit.

use super::chunk::{CHUNK, ChunkTaps, Ctx, RowOut, store};
use super::pixel::Pass;
use super::summary::{CELL, Cell, order_bits, summary_cell};
use super::{NO_OBJECT, Rules, ScreenInput, rotation_index};
use std::arch::x86_64::*;

/// Pixels per group (one 8-lane register per channel triple of floats).
const G: usize = 8;
/// Rotated taps whose positions a group holds at once (more are summed in batches).
const HELD: usize = 4;

/// The pass's taps as the group loop uses them, by kind (the centre tap, the axis-aligned
/// ones, the rotated ones), each with its weights laid out for the group's registers.
pub(super) struct GroupTaps {
    /// Offset-0 taps: their weights over 48 floats (RGB repeated; an 8-pixel group reads the
    /// first 24).
    pub(super) centre: Vec<[f32; 6 * G]>,
    /// Axis-aligned taps: offset (mm) and weights over the 48 floats.
    pub(super) axis: Vec<(f32, [f32; 6 * G])>,
    /// Rotated taps: offset (mm) and their row-pair weights at fx = 0 and their change per
    /// unit of fx (see [`ChunkTaps`]).
    pub(super) rotated: Vec<(f32, [f32; 8], [f32; 8])>,
}

impl GroupTaps {
    /// The layout of `pass`'s taps (`taps` is the same pass's chunk layout).
    pub fn new(pass: &Pass, taps: &ChunkTaps) -> GroupTaps {
        let t = pass.taps;
        let mut g = GroupTaps {
            centre: Vec::new(),
            axis: Vec::new(),
            rotated: Vec::new(),
        };
        for (k, &o) in t.offset.iter().enumerate() {
            let w24: [f32; 6 * G] = taps.pattern[k][..6 * G].try_into().expect("48 floats");
            if o == 0.0 {
                g.centre.push(w24);
            } else if pass.rotates(o) {
                g.rotated.push((o, taps.rot_lo[k], taps.rot_d[k]));
            } else {
                g.axis.push((o, w24));
            }
        }
        g
    }
}

/// The horizontal pass's source row `y`, padded on each side by `pad` copies of its edge
/// pixel (so reads up to `pad` pixels past either end are the clamped ones), RGB.
pub(super) fn pad_row(src: &[f32], w: usize, y: usize, pad: usize, row: &mut Vec<f32>) {
    let s = &src[3 * y * w..3 * (y + 1) * w];
    row.resize(3 * (w + 2 * pad), 0.0);
    let (left, rest) = row.split_at_mut(3 * pad);
    let (middle, right) = rest.split_at_mut(3 * w);
    middle.copy_from_slice(s);
    for p in left.chunks_exact_mut(3) {
        p.copy_from_slice(&s[..3]);
    }
    for p in right.chunks_exact_mut(3) {
        p.copy_from_slice(&s[3 * w - 3..]);
    }
}

/// 8 floats of `s` from `i` (bounds-checked).
#[target_feature(enable = "avx2,fma")]
#[inline]
fn load(s: &[f32], i: usize) -> __m256 {
    let v: &[f32; 8] = s[i..i + 8].try_into().expect("8 floats");
    // SAFETY: `v` holds 8 floats.
    unsafe { _mm256_loadu_ps(v.as_ptr()) }
}

/// The 24 floats of `s` from `i` as three registers (one bounds check).
#[target_feature(enable = "avx2,fma")]
#[inline]
fn load24(s: &[f32], i: usize) -> [__m256; 3] {
    let v: &[f32; 24] = s[i..i + 24].try_into().expect("24 floats");
    // SAFETY: `v` holds 24 floats.
    unsafe {
        [
            _mm256_loadu_ps(v.as_ptr()),
            _mm256_loadu_ps(v.as_ptr().add(8)),
            _mm256_loadu_ps(v.as_ptr().add(16)),
        ]
    }
}

/// Per-pixel lanes repeated over the three channels: 8 pixels → 24 floats.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn spread(v: __m256) -> [__m256; 3] {
    [
        perm(v, [0, 0, 0, 1, 1, 1, 2, 2]),
        perm(v, [2, 3, 3, 3, 4, 4, 4, 5]),
        perm(v, [5, 5, 6, 6, 6, 7, 7, 7]),
    ]
}

/// The smallest and largest of 8 integer lanes.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn min_max(v: __m256i) -> (i32, i32) {
    let swap = _mm256_permute2x128_si256::<1>(v, v);
    let (mut lo, mut hi) = (_mm256_min_epi32(v, swap), _mm256_max_epi32(v, swap));
    lo = _mm256_min_epi32(lo, _mm256_shuffle_epi32::<0b01_00_11_10>(lo));
    hi = _mm256_max_epi32(hi, _mm256_shuffle_epi32::<0b01_00_11_10>(hi));
    lo = _mm256_min_epi32(lo, _mm256_shuffle_epi32::<0b10_11_00_01>(lo));
    hi = _mm256_max_epi32(hi, _mm256_shuffle_epi32::<0b10_11_00_01>(hi));
    (_mm256_cvtsi256_si32(lo), _mm256_cvtsi256_si32(hi))
}

/// The largest of 8 u32 lanes.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn max_u32(v: __m256i) -> u32 {
    let mut m = _mm256_max_epu32(v, _mm256_permute2x128_si256::<1>(v, v));
    m = _mm256_max_epu32(m, _mm256_shuffle_epi32::<0b01_00_11_10>(m));
    m = _mm256_max_epu32(m, _mm256_shuffle_epi32::<0b10_11_00_01>(m));
    _mm256_cvtsi256_si32(m) as u32
}

/// Where a group's rows come from.
pub(super) struct Sources<'a> {
    /// The pass's source image (RGB, row-major).
    pub src: &'a [f32],
    /// The horizontal pass's padded source row ([`pad_row`]) and its padding (pixels).
    pub row: &'a [f32],
    pub pad: usize,
}

/// Groups in a chunk, at most.
pub(super) const GROUPS: usize = CHUNK / G;

/// Sums the `n` pixels of row `y` from column `x0` (a chunk that passed the silhouette test)
/// into `out`: whole groups of 8 here, the rest (and any group the registers cannot take)
/// pixel by pixel.
///
/// The taps are the outer loop and the groups the inner one, so that what a tap needs once
/// per chunk (its integer offset when the chunk's pixels share it, and where its runs start)
/// is found once: the centre tap, then each axis tap, then the rotated taps.
#[target_feature(enable = "avx2,fma")]
#[allow(clippy::too_many_arguments)]
pub(super) fn chunk<const VERTICAL: bool, const JITTER: bool>(
    pass: &Pass,
    ctx: &Ctx,
    srcs: &Sources,
    x0: usize,
    y: usize,
    n: usize,
    out: &mut RowOut,
) {
    let groups = (n / G).min(GROUPS);
    let gt = ctx.groups;
    let (w, h) = (pass.input.width, pass.input.height);
    let src = srcs.src;
    let iota = _mm256_setr_ps(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0);
    let yv = _mm256_set1_ps(y as f32);
    let mm = &pass.input.mm_per_pixel[y * w + x0..y * w + x0 + G * groups];
    let mut inv = [_mm256_setzero_ps(); GROUPS];
    let mut along = [yv; GROUPS];
    for g in 0..groups {
        // 1 / mm_per_pixel, as `Rules::inverse_scale_lane` computes it.
        inv[g] = _mm256_div_ps(_mm256_set1_ps(1.0), load(mm, G * g));
        if !VERTICAL {
            along[g] = _mm256_add_ps(_mm256_set1_ps((x0 + G * g) as f32), iota);
        }
    }
    let mut acc = [[_mm256_setzero_ps(); 3]; GROUPS];
    // Groups that go pixel by pixel (one bit each).
    let mut failed = 0u32;
    // The horizontal pass reads its padded row, the vertical one the image: the first float
    // of the run at integer offset `k` from the pixels at column `x` (the vertical pass's row
    // index clamped to the image), or for the horizontal pass the run's first pixel in the
    // padded row, which may fall outside it.
    let from = if VERTICAL { src } else { srcs.row };
    let last_row = h as i32 - 1;
    let row_run = |k: i32, x: usize| 3 * ((y as i32 + k).clamp(0, last_row) as usize * w + x);
    let padded_start = |k: i32, x: usize| srcs.pad as isize + x as isize + k as isize;

    for wt in &gt.centre {
        let wv = [load(wt, 0), load(wt, 8), load(wt, 16)];
        let start = if VERTICAL {
            3 * (y * w + x0)
        } else {
            3 * (srcs.pad + x0)
        };
        for (g, run) in from[start..start + 3 * G * groups]
            .chunks_exact(3 * G)
            .enumerate()
        {
            let s = load24(run, 0);
            for i in 0..3 {
                acc[g][i] = _mm256_fmadd_ps(wv[i], s[i], acc[g][i]);
            }
        }
    }

    for (o_mm, wt) in &gt.axis {
        // Per pixel: p = x − o (or y − o), its floor p0 and fraction, as the per-pixel form
        // computes them, and the offset p0 − x of the pixel from its own column (or row).
        let o = _mm256_set1_ps(*o_mm);
        let mut frac = [_mm256_setzero_ps(); GROUPS];
        let mut key = [_mm256_setzero_si256(); GROUPS];
        let (mut lo, mut hi) = (_mm256_set1_epi32(i32::MAX), _mm256_set1_epi32(i32::MIN));
        for g in 0..groups {
            let p = _mm256_sub_ps(along[g], _mm256_mul_ps(o, inv[g]));
            let p0 = _mm256_floor_ps(p);
            frac[g] = _mm256_sub_ps(p, p0);
            key[g] = _mm256_cvttps_epi32(_mm256_sub_ps(p0, along[g]));
            lo = _mm256_min_epi32(lo, key[g]);
            hi = _mm256_max_epi32(hi, key[g]);
        }
        let wv = [load(wt, 0), load(wt, 8), load(wt, 16)];
        let (c, _) = min_max(lo);
        let (_, top) = min_max(hi);
        // One offset over the chunk: two runs, each read once per group.
        let runs = if c != top {
            None
        } else if VERTICAL {
            Some((row_run(c, x0), row_run(c + 1, x0)))
        } else {
            let start = padded_start(c, x0);
            (start >= 0 && start as usize + G * groups < srcs.row.len() / 3)
                .then(|| (3 * start as usize, 3 * start as usize + 3))
        };
        if let Some((r0, r1)) = runs {
            let (a0, a1) = (
                from[r0..r0 + 3 * G * groups].chunks_exact(3 * G),
                from[r1..r1 + 3 * G * groups].chunks_exact(3 * G),
            );
            for (g, (a, b)) in a0.zip(a1).enumerate() {
                let (a, b) = (load24(a, 0), load24(b, 0));
                let f = spread(frac[g]);
                for i in 0..3 {
                    let v = _mm256_fmadd_ps(f[i], _mm256_sub_ps(b[i], a[i]), a[i]);
                    acc[g][i] = _mm256_fmadd_ps(wv[i], v, acc[g][i]);
                }
            }
            continue;
        }
        // The offset changes across the chunk: each group on its own, with the runs at
        // offsets lo and lo + 1 (and lo + 2), each pixel blending the first two or the last
        // two; a group whose offsets span more than two values goes pixel by pixel.
        for g in 0..groups {
            let (lo, hi) = min_max(key[g]);
            if hi - lo > 1 {
                failed |= 1 << g;
                continue;
            }
            let xg = x0 + G * g;
            let r: [usize; 3] = if VERTICAL {
                [row_run(lo, xg), row_run(lo + 1, xg), row_run(lo + 2, xg)]
            } else {
                let start = padded_start(lo, xg);
                if start < 0 || start as usize + G + 2 > srcs.row.len() / 3 {
                    failed |= 1 << g;
                    continue;
                }
                let s = 3 * start as usize;
                [s, s + 3, s + 6]
            };
            let (a, b, c) = (load24(from, r[0]), load24(from, r[1]), load24(from, r[2]));
            let up = _mm256_castsi256_ps(_mm256_cmpgt_epi32(key[g], _mm256_set1_epi32(lo)));
            let m = spread(up);
            let f = spread(frac[g]);
            for i in 0..3 {
                let (a, b) = (
                    _mm256_blendv_ps(a[i], b[i], m[i]),
                    _mm256_blendv_ps(b[i], c[i], m[i]),
                );
                let v = _mm256_fmadd_ps(f[i], _mm256_sub_ps(b, a), a);
                acc[g][i] = _mm256_fmadd_ps(wv[i], v, acc[g][i]);
            }
        }
    }

    if JITTER && !gt.rotated.is_empty() {
        for g in 0..groups {
            if failed & (1 << g) != 0 {
                continue;
            }
            let r = rotated::<VERTICAL>(pass, ctx, inv[g], src, x0 + G * g, y);
            for i in 0..3 {
                acc[g][i] = _mm256_add_ps(acc[g][i], r[i]);
            }
        }
    }

    for (g, acc) in acc.iter().enumerate().take(groups) {
        let xg = x0 + G * g;
        if failed & (1 << g) != 0 {
            pixels::<VERTICAL, JITTER>(pass, xg, xg + G, y, out);
            continue;
        }
        let dst: &mut [f32; 24] = (&mut out.row[3 * xg..3 * xg + 3 * G])
            .try_into()
            .expect("24 floats");
        let p = dst.as_mut_ptr();
        // SAFETY: `dst` holds 24 floats.
        unsafe {
            for (i, a) in acc.iter().enumerate() {
                let v = if out.accumulate {
                    _mm256_add_ps(_mm256_loadu_ps(p.add(8 * i)), *a)
                } else {
                    *a
                };
                _mm256_storeu_ps(p.add(8 * i), v);
            }
        }
    }
    pixels::<VERTICAL, JITTER>(pass, x0 + G * groups, x0 + n, y, out);
}

/// Pixels `a..b` of row `y` through the per-pixel form.
#[inline(never)]
fn pixels<const VERTICAL: bool, const JITTER: bool>(
    pass: &Pass,
    a: usize,
    b: usize,
    y: usize,
    out: &mut RowOut,
) {
    for x in a..b {
        store(out, &pass.pixel::<VERTICAL, JITTER>(x, y), x);
    }
}

/// The rotated taps of the group at `xg`: each pixel's bilinear reads along its own rotated
/// axis, summed per pixel (the cell's two rows as 8-float loads: RGB of the left texel, of
/// the right one, two spare floats; blended along y, weighted by [(1 − fx)·w, fx·w, 0, 0]).
/// A batch of taps with a cell at the image border reads each pixel's four clamped texels.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn rotated<const VERTICAL: bool>(
    pass: &Pass,
    ctx: &Ctx,
    inv: __m256,
    src: &[f32],
    xg: usize,
    y: usize,
) -> [__m256; 3] {
    let (w, h) = (pass.input.width, pass.input.height);
    let iota = _mm256_setr_ps(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0);
    let xv = _mm256_add_ps(_mm256_set1_ps(xg as f32), iota);
    let yv = _mm256_set1_ps(y as f32);
    // The pixels' rotated axis (cos, sin).
    let i0 = y * w + xg;
    let r: &[u8; 8] = ctx.table.rotation[i0..i0 + G]
        .try_into()
        .expect("8 rotations");
    let k = _mm256_cvtepu8_epi32(_mm_set_epi64x(0, i64::from_le_bytes(*r)));
    let table = pass.rotations.as_flattened();
    assert_eq!(table.len(), 2 * super::ROTATION_STEPS);
    let k2 = _mm256_slli_epi32::<1>(k);
    // SAFETY: every index is 2·k or 2·k + 1 with k < 256 = ROTATION_STEPS (a u8), into the
    // table of ROTATION_STEPS (cos, sin) pairs.
    let (cs, sn) = unsafe {
        (
            _mm256_i32gather_ps::<4>(table.as_ptr(), k2),
            _mm256_i32gather_ps::<4>(table.as_ptr().add(1), k2),
        )
    };
    assert!(src.len() >= 3 * w * h);
    let geo = Geometry {
        xv,
        yv,
        cs,
        sn,
        inv,
        w,
        h,
    };
    let mut rsum = [_mm256_setzero_ps(); G];
    for batch in ctx.groups.rotated.chunks(HELD) {
        match batch {
            [a] => rotated_batch::<VERTICAL, 1>(&geo, [a], src, &mut rsum),
            [a, b] => rotated_batch::<VERTICAL, 2>(&geo, [a, b], src, &mut rsum),
            [a, b, c] => rotated_batch::<VERTICAL, 3>(&geo, [a, b, c], src, &mut rsum),
            [a, b, c, d] => rotated_batch::<VERTICAL, 4>(&geo, [a, b, c, d], src, &mut rsum),
            _ => unreachable!("batches of 1 to {HELD} taps"),
        }
    }
    interleave(&rsum)
}

/// A group's coordinates, rotated axes and inverse footprints, and the image size.
struct Geometry {
    xv: __m256,
    yv: __m256,
    cs: __m256,
    sn: __m256,
    inv: __m256,
    w: usize,
    h: usize,
}

/// Adds `NQ` rotated taps to each pixel's 8-lane sum in `rsum` (see [`rotated`]).
///
/// Each tap's cells and fractions are computed for the 8 pixels in registers and stored
/// once; the per-pixel loop then reads them back as a scalar index and two broadcast loads
/// (load-port work, where taking a lane out of a register is a shuffle, and the shuffle
/// port is the one the rest of the group loop needs).
#[target_feature(enable = "avx2,fma")]
#[inline]
fn rotated_batch<const VERTICAL: bool, const NQ: usize>(
    geo: &Geometry,
    taps: [&(f32, [f32; 8], [f32; 8]); NQ],
    src: &[f32],
    rsum: &mut [__m256; G],
) {
    let (w, h) = (geo.w, geo.h);
    let zero = _mm256_setzero_ps();
    let (xmax, ymax) = (
        _mm256_set1_ps(w as f32 - 3.0),
        _mm256_set1_ps(h as f32 - 2.0),
    );
    let wi = _mm256_set1_epi32(w as i32);
    // Per tap and pixel: the cell's first float (for cells inside the image) or its column
    // and row (for a tap whose cells reach past the border), and the bilinear fractions.
    let mut cell = [[0i32; G]; NQ];
    let mut col = [[0i32; G]; NQ];
    let mut row = [[0i32; G]; NQ];
    let mut fx = [[0f32; G]; NQ];
    let mut fy = [[0f32; G]; NQ];
    let mut edge = false;
    // The largest first float of a cell (as u32: a negative one is larger than any image).
    let mut top = _mm256_setzero_si256();
    for q in 0..NQ {
        let o = _mm256_mul_ps(_mm256_set1_ps(taps[q].0), geo.inv);
        // x − o·c, y − o·s (horizontal); x + o·s, y − o·c (vertical: the axis is (−s, c)),
        // with the per-pixel form's roundings.
        let (sx, sy) = if VERTICAL {
            (
                _mm256_add_ps(geo.xv, _mm256_mul_ps(o, geo.sn)),
                _mm256_sub_ps(geo.yv, _mm256_mul_ps(o, geo.cs)),
            )
        } else {
            (
                _mm256_sub_ps(geo.xv, _mm256_mul_ps(o, geo.cs)),
                _mm256_sub_ps(geo.yv, _mm256_mul_ps(o, geo.sn)),
            )
        };
        let (cx, cy) = (_mm256_floor_ps(sx), _mm256_floor_ps(sy));
        // Inside: 0 ≤ cx ≤ w − 3 (the 8-float loads read one pixel past the cell) and
        // 0 ≤ cy ≤ h − 2 (positions are finite: inv and the offsets are).
        let outside = _mm256_or_ps(
            _mm256_or_ps(
                _mm256_cmp_ps::<_CMP_LT_OQ>(cx, zero),
                _mm256_cmp_ps::<_CMP_GT_OQ>(cx, xmax),
            ),
            _mm256_or_ps(
                _mm256_cmp_ps::<_CMP_LT_OQ>(cy, zero),
                _mm256_cmp_ps::<_CMP_GT_OQ>(cy, ymax),
            ),
        );
        edge |= _mm256_movemask_ps(outside) != 0;
        let (cxi, cyi) = (_mm256_cvttps_epi32(cx), _mm256_cvttps_epi32(cy));
        let j = _mm256_add_epi32(cxi, _mm256_mullo_epi32(cyi, wi));
        let j3 = _mm256_add_epi32(j, _mm256_add_epi32(j, j));
        top = _mm256_max_epu32(top, j3);
        // SAFETY: each destination holds 8 lanes.
        unsafe {
            _mm256_storeu_ps(fx[q].as_mut_ptr(), _mm256_sub_ps(sx, cx));
            _mm256_storeu_ps(fy[q].as_mut_ptr(), _mm256_sub_ps(sy, cy));
            _mm256_storeu_si256(cell[q].as_mut_ptr().cast(), j3);
            _mm256_storeu_si256(col[q].as_mut_ptr().cast(), cxi);
            _mm256_storeu_si256(row[q].as_mut_ptr().cast(), cyi);
        }
    }
    let mut lo = [_mm256_setzero_ps(); NQ];
    let mut d = [_mm256_setzero_ps(); NQ];
    for q in 0..NQ {
        lo[q] = load(&taps[q].1, 0);
        d[q] = load(&taps[q].2, 0);
    }
    if edge {
        border_batch(&col, &row, &fx, &fy, &lo, &d, src, (w, h), rsum);
        return;
    }
    let base = src.as_ptr();
    let down = 3 * w;
    // The loads below rely on the border test above; this check backs it (a few
    // instructions per batch), so a wrong test panics instead of reading past the image.
    assert!(
        max_u32(top) as usize + down + 8 <= src.len(),
        "rotated tap cell outside the image"
    );
    for (l, r) in rsum.iter_mut().enumerate() {
        for q in 0..NQ {
            let j = cell[q][l] as u32 as usize;
            // SAFETY: no cell of the batch reaches the border: each was checked inside the
            // image with 0 ≤ cx ≤ w − 3 and 0 ≤ cy ≤ h − 2, so j = 3·(cy·w + cx) and the 8
            // floats from j + 3w end at 3·((cy + 1)·w + cx) + 8 ≤ 3·w·h − 1 < src.len()
            // (and the assertion above checked j + 3w + 8 ≤ src.len() for every j).
            let (a, b) = unsafe {
                (
                    _mm256_loadu_ps(base.add(j)),
                    _mm256_loadu_ps(base.add(j + down)),
                )
            };
            let v = _mm256_fmadd_ps(_mm256_set1_ps(fy[q][l]), _mm256_sub_ps(b, a), a);
            let x = _mm256_fmadd_ps(_mm256_set1_ps(fx[q][l]), d[q], lo[q]);
            *r = _mm256_fmadd_ps(x, v, *r);
        }
    }
}

/// [`rotated_batch`] for a batch with a cell at the image border: each pixel's four texels
/// clamped to the image, as the per-pixel form reads them, for every tap of the batch.
#[target_feature(enable = "avx2,fma")]
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn border_batch<const NQ: usize>(
    col: &[[i32; G]; NQ],
    row: &[[i32; G]; NQ],
    fx: &[[f32; G]; NQ],
    fy: &[[f32; G]; NQ],
    lo: &[__m256; NQ],
    d: &[__m256; NQ],
    src: &[f32],
    (w, h): (usize, usize),
    rsum: &mut [__m256; G],
) {
    let row_of = |c: i32| c.clamp(0, h as i32 - 1) as usize * w;
    for (l, r) in rsum.iter_mut().enumerate() {
        for q in 0..NQ {
            let (cx, cy) = (col[q][l], row[q][l]);
            let (a, b) = (
                clamped_pair(src, w, row_of(cy), cx),
                clamped_pair(src, w, row_of(cy + 1), cx),
            );
            let v = _mm256_fmadd_ps(_mm256_set1_ps(fy[q][l]), _mm256_sub_ps(b, a), a);
            let x = _mm256_fmadd_ps(_mm256_set1_ps(fx[q][l]), d[q], lo[q]);
            *r = _mm256_fmadd_ps(x, v, *r);
        }
    }
}

/// The texels at columns `cx` and `cx + 1` (clamped to the image) of the row starting at
/// pixel `r`, as [L.rgb, R.rgb, 0, 0].
#[target_feature(enable = "avx2,fma")]
#[inline]
pub(super) fn clamped_pair(src: &[f32], w: usize, r: usize, cx: i32) -> __m256 {
    let col = |c: i32| 3 * (r + c.clamp(0, w as i32 - 1) as usize);
    let (a, b) = (
        &src[col(cx)..col(cx) + 3],
        &src[col(cx + 1)..col(cx + 1) + 3],
    );
    // The first three lanes of a 4-lane load: a texel's RGB, without reading past it.
    let rgb = _mm_setr_epi32(-1, -1, -1, 0);
    // SAFETY: `a` and `b` hold three floats each, the masked loads read those only.
    let (a, b) = unsafe {
        (
            _mm_maskload_ps(a.as_ptr(), rgb),
            _mm_maskload_ps(b.as_ptr(), rgb),
        )
    };
    // [L.rgb, 0, R.rgb, 0] → [L.rgb, R.rgb, 0, 0] (lane 3 is a zero).
    _mm256_permutevar8x32_ps(
        _mm256_set_m128(b, a),
        _mm256_setr_epi32(0, 1, 2, 4, 5, 6, 3, 3),
    )
}

/// The 8 pixels' rotated sums as the group's 24 floats of RGB: each pixel's left texel
/// (lanes 0..3) plus its right one (lanes 3..6), then the pixels' triples packed in order,
/// in registers.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn interleave(rsum: &[__m256; G]) -> [__m256; 3] {
    let fold = _mm256_setr_epi32(3, 4, 5, 6, 7, 7, 7, 7);
    let mut s = [_mm256_setzero_ps(); G];
    for l in 0..G {
        s[l] = _mm256_add_ps(rsum[l], _mm256_permutevar8x32_ps(rsum[l], fold));
    }
    // Pairs of pixels: [R G B · R' G' B' ·].
    let (t01, t23, t45, t67) = (
        pair(s[0], s[1]),
        pair(s[2], s[3]),
        pair(s[4], s[5]),
        pair(s[6], s[7]),
    );
    [
        // R0 G0 B0 R1 G1 B1 R2 G2
        _mm256_blend_ps::<0b1100_0000>(
            perm(t01, [0, 1, 2, 4, 5, 6, 0, 0]),
            perm(t23, [0, 0, 0, 0, 0, 0, 0, 1]),
        ),
        // B2 R3 G3 B3 R4 G4 B4 R5
        _mm256_blend_ps::<0b1111_0000>(
            perm(t23, [2, 4, 5, 6, 0, 0, 0, 0]),
            perm(t45, [0, 0, 0, 0, 0, 1, 2, 4]),
        ),
        // G5 B5 R6 G6 B6 R7 G7 B7
        _mm256_blend_ps::<0b1111_1100>(
            perm(t45, [5, 6, 0, 0, 0, 0, 0, 0]),
            perm(t67, [0, 0, 0, 1, 2, 4, 5, 6]),
        ),
    ]
}

/// [a₀..a₄, b₀..b₄].
#[target_feature(enable = "avx2,fma")]
#[inline]
fn pair(a: __m256, b: __m256) -> __m256 {
    _mm256_insertf128_ps::<1>(a, _mm256_castps256_ps128(b))
}

/// The lanes of `v` picked by `i`.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn perm(v: __m256, i: [i32; 8]) -> __m256 {
    _mm256_permutevar8x32_ps(
        v,
        _mm256_setr_epi32(i[0], i[1], i[2], i[3], i[4], i[5], i[6], i[7]),
    )
}

/// [`summary_row`] in AVX2: each whole cell of [`CELL`] pixels as two 8-lane halves
/// ([`summary_cell_avx2`]), a partial last cell as the scalar form.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(super) fn summary_row_avx2(input: &ScreenInput, rules: &Rules, y: usize, row: &mut [Cell]) {
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
pub(super) fn summary_cell_avx2(
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
    let (twice_support, min_fp, max_span) = (
        _mm256_set1_ps(2.0 * rules.support_mm),
        _mm256_set1_ps(rules.min_footprint_px),
        _mm256_set1_ps(super::MAX_SPAN_PX),
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
        // inverse_scale_lane: (mm > 0) & mm finite & min ≤ 2·support·inv ≤ MAX_SPAN_PX &
        // inv finite.
        let inv = _mm256_div_ps(one, f);
        let span = _mm256_mul_ps(twice_support, inv);
        let ok = _mm256_and_ps(
            _mm256_and_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(f, zero), finite_lanes(f)),
            _mm256_and_ps(
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_GE_OQ>(span, min_fp),
                    _mm256_cmp_ps::<_CMP_LE_OQ>(span, max_span),
                ),
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
pub(super) fn fold_u32<const MAX: bool>(v: std::arch::x86_64::__m256i) -> u32 {
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
pub(super) fn finite_lanes(v: std::arch::x86_64::__m256) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    let exp = _mm256_set1_epi32(0x7F80_0000);
    let e = _mm256_and_si256(_mm256_castps_si256(v), exp);
    _mm256_castsi256_ps(_mm256_xor_si256(
        _mm256_cmpeq_epi32(e, exp),
        _mm256_set1_epi32(-1),
    ))
}

/// [`rotation_row`] four pixels at a time in AVX2's 64-bit lanes: the SplitMix64 finaliser
/// with each 64-bit product built from three 32-bit ones (AVX2 has no 64-bit multiply), so
/// every index is the scalar one, bit for bit (integer arithmetic).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(super) fn rotation_row_avx2(y: usize, seed: u64, row: &mut [u8]) {
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
