//! [`super::groups`] in AVX-512F, picked at run time where the CPU has it: a chunk summed in
//! groups of 16 pixels, each group's sums held as three 16-lane vectors (its 48 floats of
//! RGB), so each instruction of the tap loop serves twice the pixels of the 8-lane groups.
//! The rotated taps' positions, cells and fractions are found for 16 pixels at once; their
//! reads (a cell's two rows per pixel) go two pixels per 16-lane register; the packing of
//! the pixels' sums into RGB order is a few two-register permutes.
//!
//! Why: the same frame in one process, 16-pixel groups against 8-pixel ones, was 1.2× as
//! fast on 2 threads of an AVX-512 Xeon, with and without jitter (`docs/benchmarks.md`).
//!
//! Per group and axis tap, the same steps and f32 operations as the 8-lane loop (so the
//! same positions, fractions and sums, bit for bit): the pixels' positions, floors and
//! fractions in one register, spread over the channels with three permutes; when all the
//! chunk's pixels share their integer offset, each group blends its part of two runs found
//! once for the chunk, otherwise each group reads three runs from its own smallest offset
//! and each pixel blends the first two or the last two (a masked select). A group whose
//! offsets span more than two values (or whose runs leave the padded row) is summed as two
//! 8-pixel groups instead, which go pixel by pixel only where they would in the 8-lane loop:
//! so the two loops give the same sums, bit for bit (`tests/screen_space_rows.rs` checks it).

use super::groups::{GROUPS, Sources};
use super::pixel::Pass;
use super::rows::{Ctx, RowOut};
use std::arch::x86_64::*;

/// Pixels per group.
const W: usize = 16;
/// Floats per group (RGB).
const F: usize = 3 * W;
/// Groups in a chunk, at most.
const WIDE_GROUPS: usize = GROUPS / 2;

/// 16 floats of `s` from `i` (bounds-checked).
#[target_feature(enable = "avx512f,avx2,fma")]
#[inline]
fn load(s: &[f32], i: usize) -> __m512 {
    let v: &[f32; 16] = s[i..i + 16].try_into().expect("16 floats");
    // SAFETY: `v` holds 16 floats.
    unsafe { _mm512_loadu_ps(v.as_ptr()) }
}

/// The 48 floats of `s` from `i` as three registers (one bounds check).
#[target_feature(enable = "avx512f,avx2,fma")]
#[inline]
fn load48(s: &[f32], i: usize) -> [__m512; 3] {
    let v: &[f32; F] = s[i..i + F].try_into().expect("48 floats");
    // SAFETY: `v` holds 48 floats.
    unsafe {
        [
            _mm512_loadu_ps(v.as_ptr()),
            _mm512_loadu_ps(v.as_ptr().add(16)),
            _mm512_loadu_ps(v.as_ptr().add(32)),
        ]
    }
}

/// The lane of each of a group's 48 floats: pixel `j / 3` for float `j`, per register.
const SPREAD: [[i32; 16]; 3] = {
    let mut s = [[0i32; 16]; 3];
    let mut j = 0;
    while j < F {
        s[j / 16][j % 16] = (j / 3) as i32;
        j += 1;
    }
    s
};

/// Per-pixel lanes repeated over the three channels: 16 pixels → 48 floats.
#[target_feature(enable = "avx512f,avx2,fma")]
#[inline]
fn spread(v: __m512) -> [__m512; 3] {
    let idx = |k: usize| {
        // SAFETY: `SPREAD[k]` holds 16 i32s.
        unsafe { _mm512_loadu_si512(SPREAD[k].as_ptr().cast()) }
    };
    [
        _mm512_permutexvar_ps(idx(0), v),
        _mm512_permutexvar_ps(idx(1), v),
        _mm512_permutexvar_ps(idx(2), v),
    ]
}

/// A per-pixel mask spread like [`spread`]: one mask per register of a group's floats.
#[target_feature(enable = "avx512f,avx2,fma")]
#[inline]
fn spread_mask(m: __mmask16) -> [__mmask16; 3] {
    let v = _mm512_castsi512_ps(_mm512_maskz_set1_epi32(m, -1));
    let s = spread(v);
    let bits = |r: __m512| {
        let r = _mm512_castps_si512(r);
        _mm512_test_epi32_mask(r, r)
    };
    [bits(s[0]), bits(s[1]), bits(s[2])]
}

/// The upper 8 lanes of `v`.
#[target_feature(enable = "avx512f,avx2,fma")]
#[inline]
fn upper(v: __m512) -> __m256 {
    _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(v)))
}

/// [`super::groups::chunk`] with groups of 16 pixels: sums the `n` pixels of row `y` from
/// column `x0` (a chunk that passed the silhouette test) into `out`; pixels past the last
/// whole group of 16 go to the 8-pixel groups.
#[target_feature(enable = "avx512f,avx2,fma")]
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
    let groups = (n / W).min(WIDE_GROUPS);
    let gt = ctx.groups;
    let (w, h) = (pass.input.width, pass.input.height);
    let src = srcs.src;
    let iota = _mm512_setr_ps(
        0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0, 14.0, 15.0,
    );
    let yv = _mm512_set1_ps(y as f32);
    let mm = &pass.input.mm_per_pixel[y * w + x0..y * w + x0 + W * groups];
    let mut inv = [_mm512_setzero_ps(); WIDE_GROUPS];
    let mut along = [yv; WIDE_GROUPS];
    for g in 0..groups {
        // 1 / mm_per_pixel, as `Rules::inverse_scale_lane` computes it.
        inv[g] = _mm512_div_ps(_mm512_set1_ps(1.0), load(mm, W * g));
        if !VERTICAL {
            along[g] = _mm512_add_ps(_mm512_set1_ps((x0 + W * g) as f32), iota);
        }
    }
    let mut acc = [[_mm512_setzero_ps(); 3]; WIDE_GROUPS];
    // Groups that go to the 8-pixel groups (one bit each).
    let mut failed = 0u32;
    // As in the 8-lane loop: the horizontal pass reads its padded row, the vertical one the
    // image (its row index clamped once per tap).
    let from = if VERTICAL { src } else { srcs.row };
    let last_row = h as i32 - 1;
    let row_run = |k: i32, x: usize| 3 * ((y as i32 + k).clamp(0, last_row) as usize * w + x);
    let padded_start = |k: i32, x: usize| srcs.pad as isize + x as isize + k as isize;

    for wt in &gt.centre {
        let wv = load48(wt, 0);
        let start = if VERTICAL {
            3 * (y * w + x0)
        } else {
            3 * (srcs.pad + x0)
        };
        for (g, run) in from[start..start + F * groups].chunks_exact(F).enumerate() {
            let s = load48(run, 0);
            for i in 0..3 {
                acc[g][i] = _mm512_fmadd_ps(wv[i], s[i], acc[g][i]);
            }
        }
    }

    for (o_mm, wt) in &gt.axis {
        // Per pixel: p = x − o (or y − o), its floor p0 and fraction, as the per-pixel form
        // computes them, and the offset p0 − x of the pixel from its own column (or row).
        let o = _mm512_set1_ps(*o_mm);
        let mut frac = [_mm512_setzero_ps(); WIDE_GROUPS];
        let mut key = [_mm512_setzero_si512(); WIDE_GROUPS];
        let (mut lo, mut hi) = (_mm512_set1_epi32(i32::MAX), _mm512_set1_epi32(i32::MIN));
        for g in 0..groups {
            let p = _mm512_sub_ps(along[g], _mm512_mul_ps(o, inv[g]));
            // Round down (0b01), exceptions suppressed (0b1000): `floor`.
            let p0 = _mm512_roundscale_ps::<0b1001>(p);
            frac[g] = _mm512_sub_ps(p, p0);
            key[g] = _mm512_cvttps_epi32(_mm512_sub_ps(p0, along[g]));
            lo = _mm512_min_epi32(lo, key[g]);
            hi = _mm512_max_epi32(hi, key[g]);
        }
        let wv = load48(wt, 0);
        let (c, top) = (_mm512_reduce_min_epi32(lo), _mm512_reduce_max_epi32(hi));
        // One offset over the chunk: two runs, each read once per group.
        let runs = if c != top {
            None
        } else if VERTICAL {
            Some((row_run(c, x0), row_run(c + 1, x0)))
        } else {
            let start = padded_start(c, x0);
            (start >= 0 && start as usize + W * groups < srcs.row.len() / 3)
                .then(|| (3 * start as usize, 3 * start as usize + 3))
        };
        if let Some((r0, r1)) = runs {
            let (a0, a1) = (
                from[r0..r0 + F * groups].chunks_exact(F),
                from[r1..r1 + F * groups].chunks_exact(F),
            );
            for (g, (a, b)) in a0.zip(a1).enumerate() {
                let (a, b) = (load48(a, 0), load48(b, 0));
                let f = spread(frac[g]);
                for i in 0..3 {
                    let v = _mm512_fmadd_ps(f[i], _mm512_sub_ps(b[i], a[i]), a[i]);
                    acc[g][i] = _mm512_fmadd_ps(wv[i], v, acc[g][i]);
                }
            }
            continue;
        }
        // The offset changes across the chunk: each group on its own, with the runs at
        // offsets lo and lo + 1 (and lo + 2), each pixel blending the first two or the last
        // two; a group whose offsets span more than two values goes to the 8-pixel groups.
        for g in 0..groups {
            let (lo, hi) = (
                _mm512_reduce_min_epi32(key[g]),
                _mm512_reduce_max_epi32(key[g]),
            );
            if hi - lo > 1 {
                failed |= 1 << g;
                continue;
            }
            let xg = x0 + W * g;
            let r: [usize; 3] = if VERTICAL {
                [row_run(lo, xg), row_run(lo + 1, xg), row_run(lo + 2, xg)]
            } else {
                let start = padded_start(lo, xg);
                if start < 0 || start as usize + W + 2 > srcs.row.len() / 3 {
                    failed |= 1 << g;
                    continue;
                }
                let s = 3 * start as usize;
                [s, s + 3, s + 6]
            };
            let (a, b, c) = (load48(from, r[0]), load48(from, r[1]), load48(from, r[2]));
            let m = spread_mask(_mm512_cmpgt_epi32_mask(key[g], _mm512_set1_epi32(lo)));
            let f = spread(frac[g]);
            for i in 0..3 {
                let (a, b) = (
                    _mm512_mask_blend_ps(m[i], a[i], b[i]),
                    _mm512_mask_blend_ps(m[i], b[i], c[i]),
                );
                let v = _mm512_fmadd_ps(f[i], _mm512_sub_ps(b, a), a);
                acc[g][i] = _mm512_fmadd_ps(wv[i], v, acc[g][i]);
            }
        }
    }

    if JITTER && !gt.rotated.is_empty() {
        for g in 0..groups {
            if failed & (1 << g) != 0 {
                continue;
            }
            let r = rotated::<VERTICAL>(pass, ctx, inv[g], src, x0 + W * g, y);
            for i in 0..3 {
                acc[g][i] = _mm512_add_ps(acc[g][i], r[i]);
            }
        }
    }

    for (g, acc) in acc.iter().enumerate().take(groups) {
        let xg = x0 + W * g;
        if failed & (1 << g) != 0 {
            // Its two halves as 8-pixel groups: each goes pixel by pixel only if it would in
            // the 8-lane loop, so the sums are that loop's, bit for bit.
            super::groups::chunk::<VERTICAL, JITTER>(pass, ctx, srcs, xg, y, W, out);
            continue;
        }
        let dst: &mut [f32; F] = (&mut out.row[3 * xg..3 * xg + F])
            .try_into()
            .expect("48 floats");
        let p = dst.as_mut_ptr();
        // SAFETY: `dst` holds 48 floats.
        unsafe {
            for (i, a) in acc.iter().enumerate() {
                let v = if out.accumulate {
                    _mm512_add_ps(_mm512_loadu_ps(p.add(16 * i)), *a)
                } else {
                    *a
                };
                _mm512_storeu_ps(p.add(16 * i), v);
            }
        }
    }
    let done = W * groups;
    if done < n {
        super::groups::chunk::<VERTICAL, JITTER>(pass, ctx, srcs, x0 + done, y, n - done, out);
    }
}

/// Rotated taps whose positions a 16-pixel group holds at once (more are summed in batches).
const HELD16: usize = 2;

/// [`super::groups::rotated`] for 16 pixels: the positions, cells and fractions of a tap
/// are computed for the 16 pixels in one register each, and the per-pixel reads go two
/// pixels at a time, one per half of a 16-lane register (each half as the 8-lane loop's
/// register: RGB of the left texel, of the right one, two spare floats). Each pixel's sum
/// takes the same operations in the same order as in the 8-lane loop.
#[target_feature(enable = "avx512f,avx2,fma")]
#[inline]
fn rotated<const VERTICAL: bool>(
    pass: &Pass,
    ctx: &Ctx,
    inv: __m512,
    src: &[f32],
    xg: usize,
    y: usize,
) -> [__m512; 3] {
    let (w, h) = (pass.input.width, pass.input.height);
    let iota = _mm512_setr_ps(
        0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0, 14.0, 15.0,
    );
    // The pixels' rotated axis (cos, sin).
    let i0 = y * w + xg;
    let r: &[u8; W] = ctx.table.rotation[i0..i0 + W]
        .try_into()
        .expect("16 rotations");
    // SAFETY: `r` holds 16 bytes.
    let k = _mm512_cvtepu8_epi32(unsafe { _mm_loadu_si128(r.as_ptr().cast()) });
    let table = pass.rotations.as_flattened();
    assert_eq!(table.len(), 2 * super::ROTATION_STEPS);
    let k2 = _mm512_slli_epi32::<1>(k);
    // SAFETY: every index is 2·k or 2·k + 1 with k < 256 = ROTATION_STEPS (a u8), into the
    // table of ROTATION_STEPS (cos, sin) pairs.
    let (cs, sn) = unsafe {
        (
            _mm512_i32gather_ps::<4>(k2, table.as_ptr()),
            _mm512_i32gather_ps::<4>(k2, table.as_ptr().add(1)),
        )
    };
    assert!(src.len() >= 3 * w * h);
    let geo = Geometry16 {
        xv: _mm512_add_ps(_mm512_set1_ps(xg as f32), iota),
        yv: _mm512_set1_ps(y as f32),
        cs,
        sn,
        inv,
        w,
        h,
    };
    // Pixels 2p and 2p + 1 in the halves of register p.
    let mut rsum = [_mm512_setzero_ps(); W / 2];
    for batch in ctx.groups.rotated.chunks(HELD16) {
        match batch {
            [a] => batch16::<VERTICAL, 1>(&geo, [a], src, &mut rsum),
            [a, b] => batch16::<VERTICAL, 2>(&geo, [a, b], src, &mut rsum),
            _ => unreachable!("batches of 1 to {HELD16} taps"),
        }
    }
    interleave(&rsum)
}

/// A 16-pixel group's coordinates, rotated axes and inverse footprints, and the image size.
struct Geometry16 {
    xv: __m512,
    yv: __m512,
    cs: __m512,
    sn: __m512,
    inv: __m512,
    w: usize,
    h: usize,
}

/// Per pixel pair p: lanes 0..8 take lane 2p of a 16-lane register, lanes 8..16 lane 2p + 1.
const PAIR: [[i32; 16]; W / 2] = {
    let mut s = [[0i32; 16]; W / 2];
    let mut p = 0;
    while p < W / 2 {
        let mut l = 0;
        while l < 16 {
            s[p][l] = (2 * p + l / 8) as i32;
            l += 1;
        }
        p += 1;
    }
    s
};

/// 16 i32s as a register.
#[target_feature(enable = "avx512f,avx2,fma")]
#[inline]
fn index(v: &[i32; 16]) -> __m512i {
    // SAFETY: `v` holds 16 i32s.
    unsafe { _mm512_loadu_si512(v.as_ptr().cast()) }
}

/// 8 floats of `v` in both halves of a 16-lane register.
#[target_feature(enable = "avx512f,avx2,fma")]
#[inline]
fn twice(v: &[f32; 8]) -> __m512 {
    // SAFETY: `v` holds 8 floats.
    let h = unsafe { _mm256_loadu_ps(v.as_ptr()) };
    cat(h, h)
}

/// Adds `NQ` rotated taps to the pixel pairs' sums in `rsum` (see [`rotated`]).
#[target_feature(enable = "avx512f,avx2,fma")]
#[inline]
fn batch16<const VERTICAL: bool, const NQ: usize>(
    geo: &Geometry16,
    taps: [&(f32, [f32; 8], [f32; 8]); NQ],
    src: &[f32],
    rsum: &mut [__m512; W / 2],
) {
    let (w, h) = (geo.w, geo.h);
    let zero = _mm512_setzero_ps();
    let (xmax, ymax) = (
        _mm512_set1_ps(w as f32 - 3.0),
        _mm512_set1_ps(h as f32 - 2.0),
    );
    let wi = _mm512_set1_epi32(w as i32);
    // Per tap and pixel: the cell's first float (for cells inside the image) or its column
    // and row (for a tap whose cells reach past the border); the fractions in registers.
    let mut cell = [[0u32; W]; NQ];
    let mut col = [[0i32; W]; NQ];
    let mut row = [[0i32; W]; NQ];
    let mut fx = [zero; NQ];
    let mut fy = [zero; NQ];
    let mut edge = 0u16;
    // The largest first float of a cell (as u32: a negative one is larger than any image).
    let mut top = _mm512_setzero_si512();
    for q in 0..NQ {
        let o = _mm512_mul_ps(_mm512_set1_ps(taps[q].0), geo.inv);
        // x − o·c, y − o·s (horizontal); x + o·s, y − o·c (vertical), as the 8-lane loop.
        let (sx, sy) = if VERTICAL {
            (
                _mm512_add_ps(geo.xv, _mm512_mul_ps(o, geo.sn)),
                _mm512_sub_ps(geo.yv, _mm512_mul_ps(o, geo.cs)),
            )
        } else {
            (
                _mm512_sub_ps(geo.xv, _mm512_mul_ps(o, geo.cs)),
                _mm512_sub_ps(geo.yv, _mm512_mul_ps(o, geo.sn)),
            )
        };
        let (cx, cy) = (
            _mm512_roundscale_ps::<0b1001>(sx),
            _mm512_roundscale_ps::<0b1001>(sy),
        );
        // Inside: 0 ≤ cx ≤ w − 3 and 0 ≤ cy ≤ h − 2 (see the 8-lane loop).
        edge |= _mm512_cmp_ps_mask::<_CMP_LT_OQ>(cx, zero)
            | _mm512_cmp_ps_mask::<_CMP_GT_OQ>(cx, xmax)
            | _mm512_cmp_ps_mask::<_CMP_LT_OQ>(cy, zero)
            | _mm512_cmp_ps_mask::<_CMP_GT_OQ>(cy, ymax);
        let (cxi, cyi) = (_mm512_cvttps_epi32(cx), _mm512_cvttps_epi32(cy));
        let j = _mm512_add_epi32(cxi, _mm512_mullo_epi32(cyi, wi));
        fx[q] = _mm512_sub_ps(sx, cx);
        fy[q] = _mm512_sub_ps(sy, cy);
        let j3 = _mm512_add_epi32(j, _mm512_add_epi32(j, j));
        top = _mm512_max_epu32(top, j3);
        // SAFETY: each destination holds 16 lanes.
        unsafe {
            _mm512_storeu_si512(cell[q].as_mut_ptr().cast(), j3);
            _mm512_storeu_si512(col[q].as_mut_ptr().cast(), cxi);
            _mm512_storeu_si512(row[q].as_mut_ptr().cast(), cyi);
        }
    }
    let lo: [__m512; NQ] = std::array::from_fn(|q| twice(&taps[q].1));
    let d: [__m512; NQ] = std::array::from_fn(|q| twice(&taps[q].2));
    if edge != 0 {
        border16(&col, &row, &fx, &fy, &lo, &d, src, (w, h), rsum);
        return;
    }
    let base = src.as_ptr();
    let down = 3 * w;
    // The loads below rely on the border test above; this check backs it, so a wrong test
    // panics instead of reading past the image.
    assert!(
        _mm512_reduce_max_epu32(top) as usize + down + 8 <= src.len(),
        "rotated tap cell outside the image"
    );
    for (p, r) in rsum.iter_mut().enumerate() {
        let pair = index(&PAIR[p]);
        for q in 0..NQ {
            let (j0, j1) = (cell[q][2 * p] as usize, cell[q][2 * p + 1] as usize);
            // SAFETY: no cell of the batch reaches the border: each was checked inside the
            // image with 0 ≤ cx ≤ w − 3 and 0 ≤ cy ≤ h − 2, so j = 3·(cy·w + cx) and the 8
            // floats from j + 3w end at 3·((cy + 1)·w + cx) + 8 ≤ 3·w·h − 1 < src.len()
            // (and the assertion above checked j + 3w + 8 ≤ src.len() for every j).
            let (a, b) = unsafe {
                (
                    cat(_mm256_loadu_ps(base.add(j0)), _mm256_loadu_ps(base.add(j1))),
                    cat(
                        _mm256_loadu_ps(base.add(j0 + down)),
                        _mm256_loadu_ps(base.add(j1 + down)),
                    ),
                )
            };
            let fyp = _mm512_permutexvar_ps(pair, fy[q]);
            let fxp = _mm512_permutexvar_ps(pair, fx[q]);
            let v = _mm512_fmadd_ps(fyp, _mm512_sub_ps(b, a), a);
            let x = _mm512_fmadd_ps(fxp, d[q], lo[q]);
            *r = _mm512_fmadd_ps(x, v, *r);
        }
    }
}

/// Two 8-lane registers as the halves of one 16-lane register.
#[target_feature(enable = "avx512f,avx2,fma")]
#[inline]
fn cat(lo: __m256, hi: __m256) -> __m512 {
    _mm512_castpd_ps(_mm512_insertf64x4::<1>(
        _mm512_castpd256_pd512(_mm256_castps_pd(lo)),
        _mm256_castps_pd(hi),
    ))
}

/// [`batch16`] for a batch with a cell at the image border: each pixel's four texels clamped
/// to the image, as the per-pixel form reads them ([`super::groups::clamped_pair`]).
#[target_feature(enable = "avx512f,avx2,fma")]
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn border16<const NQ: usize>(
    col: &[[i32; W]; NQ],
    row: &[[i32; W]; NQ],
    fx: &[__m512; NQ],
    fy: &[__m512; NQ],
    lo: &[__m512; NQ],
    d: &[__m512; NQ],
    src: &[f32],
    (w, h): (usize, usize),
    rsum: &mut [__m512; W / 2],
) {
    let row_of = |c: i32| c.clamp(0, h as i32 - 1) as usize * w;
    let mut fxs = [[0f32; W]; NQ];
    let mut fys = [[0f32; W]; NQ];
    for q in 0..NQ {
        // SAFETY: each destination holds 16 floats.
        unsafe {
            _mm512_storeu_ps(fxs[q].as_mut_ptr(), fx[q]);
            _mm512_storeu_ps(fys[q].as_mut_ptr(), fy[q]);
        }
    }
    let (lo8, d8): ([__m256; NQ], [__m256; NQ]) = (
        std::array::from_fn(|q| _mm512_castps512_ps256(lo[q])),
        std::array::from_fn(|q| _mm512_castps512_ps256(d[q])),
    );
    for (p, r) in rsum.iter_mut().enumerate() {
        let mut half = [_mm512_castps512_ps256(*r), upper(*r)];
        for (s, sum) in half.iter_mut().enumerate() {
            let l = 2 * p + s;
            for q in 0..NQ {
                let (cx, cy) = (col[q][l], row[q][l]);
                let (a, b) = (
                    super::groups::clamped_pair(src, w, row_of(cy), cx),
                    super::groups::clamped_pair(src, w, row_of(cy + 1), cx),
                );
                let v = _mm256_fmadd_ps(_mm256_set1_ps(fys[q][l]), _mm256_sub_ps(b, a), a);
                let x = _mm256_fmadd_ps(_mm256_set1_ps(fxs[q][l]), d8[q], lo8[q]);
                *sum = _mm256_fmadd_ps(x, v, *sum);
            }
        }
        *r = cat(half[0], half[1]);
    }
}

/// How each register of a group's 48 floats is gathered from the pairs' folded sums (pixel
/// 2p's RGB in lanes 0..3 of register p, pixel 2p + 1's in lanes 8..11): the first pair a,
/// and for each step the indices of a two-register permute (0..16 the first operand, 16..32
/// the second): step 0 takes pairs a and a + 1, each later step s keeps what it has and
/// takes pair a + 1 + s. A register spans up to four pairs (floats 16..32 are pixels 5..10).
const PACK: [(usize, [[i32; 16]; 3]); 3] = {
    let mut s = [(0usize, [[0i32; 16]; 3]); 3];
    let mut k = 0;
    while k < 3 {
        let a = (16 * k / 3) / 2;
        let mut idx = [[0i32; 16]; 3];
        let mut i = 0;
        while i < 16 {
            let j = 16 * k + i;
            let (m, c) = (j / 3, j % 3);
            let lane = (8 * (m % 2) + c) as i32;
            let pair = m / 2;
            let mut step = 0;
            while step < 3 {
                idx[step][i] = if step == 0 {
                    if pair == a {
                        lane
                    } else if pair == a + 1 {
                        16 + lane
                    } else {
                        0
                    }
                } else if pair == a + 1 + step {
                    16 + lane
                } else {
                    i as i32
                };
                step += 1;
            }
            i += 1;
        }
        s[k] = (a, idx);
        k += 1;
    }
    s
};

/// Whether step s of register k's gather ([`PACK`]) takes any lane.
const STEP_USED: [[bool; 3]; 3] = {
    let mut u = [[false; 3]; 3];
    let mut k = 0;
    while k < 3 {
        let mut step = 0;
        while step < 3 {
            let mut i = 0;
            while i < 16 {
                if PACK[k].1[step][i] >= 16 {
                    u[k][step] = true;
                }
                i += 1;
            }
            step += 1;
        }
        k += 1;
    }
    u
};

/// The 16 pixels' rotated sums as the group's 48 floats of RGB: each pixel's left texel plus
/// its right one, then the pixels' triples packed in order, in registers.
#[target_feature(enable = "avx512f,avx2,fma")]
#[inline]
fn interleave(rsum: &[__m512; W / 2]) -> [__m512; 3] {
    // Lanes 3..6 onto 0..3 and 11..14 onto 8..11 (the rest is not read).
    let fold = index(&[3, 4, 5, 6, 7, 7, 7, 7, 11, 12, 13, 14, 15, 15, 15, 15]);
    let mut s = [_mm512_setzero_ps(); W / 2];
    for (p, r) in rsum.iter().enumerate() {
        s[p] = _mm512_add_ps(*r, _mm512_permutexvar_ps(fold, *r));
    }
    let mut out = [_mm512_setzero_ps(); 3];
    for (k, (a, idx)) in PACK.iter().enumerate() {
        let mut t = _mm512_permutex2var_ps(s[*a], index(&idx[0]), s[*a + 1]);
        for (step, ix) in idx.iter().enumerate().skip(1) {
            // A step that takes nothing (every index its own lane) is skipped: the last
            // register's third step would name a pair past the group.
            if STEP_USED[k][step] {
                t = _mm512_permutex2var_ps(t, index(ix), s[*a + 1 + step]);
            }
        }
        out[k] = t;
    }
    out
}
