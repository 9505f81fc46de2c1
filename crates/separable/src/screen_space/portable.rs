//! The portable chunk loops of the row-chunked form: the sums of a chunk's taps with the
//! pixels as the inner loop, in memory, for CPUs without AVX2 and FMA (and
//! `Evaluation::RowsBaseline`). [`super::avx2`] sums the same taps in registers.

use super::chunk::{CHUNK, ChunkTaps, Ctx, Lanes, ROTATED};
use super::pixel::Pass;

/// `a · b + c` as a multiply and an add (the portable loops' rounding; a fused multiply-add
/// would be a library call in the baseline build).
#[inline(always)]
pub(super) fn mul_add(a: f32, b: f32, c: f32) -> f32 {
    a * b + c
}

/// Image coordinates (and tap positions, which stay within w + h of the image) below this
/// keep [`floor_small`] and [`small_u32`] exact.
pub(super) const SMALL: usize = 1 << 20;

/// ⌊x⌋ for |x| < 2²², in float arithmetic that vectorises (a saturating `as i32` cast does
/// not): adding and subtracting 1.5 · 2²³ rounds to the nearest integer exactly in that
/// range, and one is taken off where that rounded up. Equals `floor_i32(x) as f32` there.
#[inline(always)]
pub(super) fn floor_small(x: f32) -> f32 {
    const ROUND: f32 = 12_582_912.0;
    let r = (x + ROUND) - ROUND;
    r - if r > x { 1.0 } else { 0.0 }
}

/// `v as u32` for an integer-valued 0 ≤ v < 2²³, through its bits (vectorises): v + 2²³ has
/// v in its mantissa.
#[inline(always)]
pub(super) fn small_u32(v: f32) -> u32 {
    (v + 8_388_608.0).to_bits() - 0x4B00_0000
}

/// `dst[3 l + c] = src[l]`: per-pixel values repeated over the three channels, eight pixels
/// at a time as one fixed shuffle (which compiles to a few vector permutes).
#[inline(always)]
pub(super) fn spread3(src: &[f32], dst: &mut [f32]) {
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
pub(super) fn texel4(src: &[f32], j: u32) -> [f32; 4] {
    let i = 3 * j as usize;
    match src.get(i..i + 4).and_then(|s| <[f32; 4]>::try_from(s).ok()) {
        Some(v) => v,
        None => [src[i], src[i + 1], src[i + 2], 0.0],
    }
}

/// Floats `i..i + 8` of a flat image (zeros past its end).
#[inline(always)]
pub(super) fn load8(src: &[f32], i: usize) -> [f32; 8] {
    match src.get(i..).and_then(|s| s.first_chunk::<8>()) {
        Some(v) => *v,
        None => std::array::from_fn(|k| src.get(i + k).copied().unwrap_or(0.0)),
    }
}

/// The taps of a chunk that passed [`eligible`], summed into `lanes.acc` (the portable
/// form).
#[inline(always)]
pub(super) fn sum_chunk<const VERTICAL: bool, const JITTER: bool>(
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
pub(super) fn rotated_sums(
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
pub(super) fn rotated_cells<const VERTICAL: bool>(
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
