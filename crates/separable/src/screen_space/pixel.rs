//! The per-pixel form of one separable pass: every tap of every pixel fetched and tested on its
//! own. It is the reference the row-chunked form ([`super::rows`]) reproduces bit for bit, and
//! what that form falls back to for chunks near silhouettes.

use super::{NO_OBJECT, Rules, ScreenInput, bilinear_cell, floor_i32, rotation_index};
use crate::kernel::Kernel1d;

/// One pass's taps in f32.
pub(super) struct PassTaps {
    /// Tap offsets (mm).
    pub offset: Vec<f32>,
    /// Tap weights per channel.
    pub weight: Vec<[f32; 3]>,
    /// Sum of the weights per channel.
    pub sum: [f32; 3],
    /// Whether a channel's weights all have one sign (renormalisation is valid).
    pub one_signed: [bool; 3],
}

impl PassTaps {
    pub fn new(k: &Kernel1d) -> PassTaps {
        let sum = k.sum();
        let one_signed = std::array::from_fn(|c| {
            k.taps.iter().all(|t| t.weight[c] >= 0.0) || k.taps.iter().all(|t| t.weight[c] <= 0.0)
        });
        PassTaps {
            offset: k.taps.iter().map(|t| t.offset_mm as f32).collect(),
            weight: k.taps.iter().map(|t| t.weight.map(|w| w as f32)).collect(),
            sum: sum.map(|s| s as f32),
            one_signed,
        }
    }
}

/// Final value of a pixel from the kept accumulation and the dropped weight.
#[inline(always)]
fn finish(
    acc: [f32; 3],
    dropped: [f32; 3],
    sum: [f32; 3],
    one_signed: [bool; 3],
    centre: [f32; 3],
) -> [f32; 3] {
    std::array::from_fn(|c| {
        let kept = sum[c] - dropped[c];
        if one_signed[c] && kept * sum[c] > 0.0 && kept.abs() > 1e-6 * sum[c].abs() {
            acc[c] * (sum[c] / kept)
        } else {
            acc[c] + dropped[c] * centre[c]
        }
    })
}

/// One 1D pass (horizontal or vertical) of one kernel term over a source image.
pub(super) struct Pass<'a> {
    pub input: &'a ScreenInput<'a>,
    /// The image filtered (the irradiance, or the horizontal pass's output).
    pub src: &'a [[f32; 3]],
    pub taps: &'a PassTaps,
    pub vertical: bool,
    pub rules: Rules,
    pub jitter: bool,
    /// Taps with |offset| ≤ this (mm) are rotated by the pixel's angle.
    pub rotate_limit_mm: f32,
    pub seed: u64,
    /// (cos, sin) of every rotation step.
    pub rotations: &'a [[f32; 2]],
}

/// Running sums of one pixel.
struct Acc {
    acc: [f32; 3],
    dropped: [f32; 3],
    any_drop: bool,
}

impl Pass<'_> {
    /// Whether a tap at `o_mm` is read along the pixel's rotated axis (jitter on, and the
    /// tap within the rotation radius).
    #[inline(always)]
    pub fn rotates(&self, o_mm: f32) -> bool {
        self.jitter && o_mm.abs() <= self.rotate_limit_mm
    }

    /// Whether texel `j` is dropped (another object, or a depth jump).
    #[inline(always)]
    fn dropped(&self, j: usize, id: u32, d0: f32) -> bool {
        let inp = self.input;
        inp.mask[j] != id || (inp.depth[j] - d0).abs() > self.rules.depth_mm
    }

    /// Adds texel `j` with weight `bw · wt`, or drops it (zero weights are skipped).
    #[inline(always)]
    fn texel(&self, j: usize, bw: f32, wt: &[f32; 3], id: u32, d0: f32, a: &mut Acc) {
        if bw == 0.0 {
            return;
        }
        let ww = [bw * wt[0], bw * wt[1], bw * wt[2]];
        if self.dropped(j, id, d0) {
            a.any_drop = true;
            for c in 0..3 {
                a.dropped[c] += ww[c];
            }
        } else {
            let s = self.src[j];
            for c in 0..3 {
                a.acc[c] += ww[c] * s[c];
            }
        }
    }

    /// The general per-pixel filter: every texel tested and dropped individually, the kept
    /// ones renormalised ([`finish`]). Used near silhouettes.
    #[inline(never)]
    fn pixel_slow(&self, x: usize, y: usize, id: u32, inv: f32) -> [f32; 3] {
        let inp = self.input;
        let w = inp.width;
        let i = y * w + x;
        let centre = self.src[i];
        let t = self.taps;
        let d0 = inp.depth[i];
        let (wmax, hmax) = (w as i32 - 1, inp.height as i32 - 1);
        let mut a = Acc {
            acc: [0.0; 3],
            dropped: [0.0; 3],
            any_drop: false,
        };
        let (rdx, rdy) = if self.jitter {
            let [c, s] = self.rotations[rotation_index(x, y, self.seed)];
            if self.vertical { (-s, c) } else { (c, s) }
        } else {
            (0.0, 0.0)
        };
        for (&o_mm, wt) in t.offset.iter().zip(&t.weight) {
            let o = o_mm * inv;
            if self.rotates(o_mm) {
                // Rotated axis: bilinear fetch at p − o·dir.
                let (sx, sy) = (x as f32 - o * rdx, y as f32 - o * rdy);
                let ([j00, j01, j10, j11], fx, fy) = bilinear_cell(sx, sy, w, wmax, hmax);
                self.texel(j00, (1.0 - fx) * (1.0 - fy), wt, id, d0, &mut a);
                self.texel(j01, fx * (1.0 - fy), wt, id, d0, &mut a);
                self.texel(j10, (1.0 - fx) * fy, wt, id, d0, &mut a);
                self.texel(j11, fx * fy, wt, id, d0, &mut a);
            } else {
                // Axis-aligned: linear fetch along the pass's axis.
                let (p, stride, lim, base) = if self.vertical {
                    (y as f32 - o, w, hmax, x)
                } else {
                    (x as f32 - o, 1, wmax, y * w)
                };
                let p0 = floor_i32(p);
                let f = p - p0 as f32;
                let j0 = base + p0.clamp(0, lim) as usize * stride;
                let j1 = base + (p0 + 1).clamp(0, lim) as usize * stride;
                self.texel(j0, 1.0 - f, wt, id, d0, &mut a);
                self.texel(j1, f, wt, id, d0, &mut a);
            }
        }
        if !a.any_drop {
            a.acc
        } else {
            finish(a.acc, a.dropped, t.sum, t.one_signed, centre)
        }
    }

    /// The common case: every texel the taps read is kept (same object, no depth jump). Sums
    /// the taps with two linear (or bilinear) fetches each and returns None as soon as a texel
    /// would be dropped, leaving the pixel to [`Pass::pixel_slow`].
    #[inline(always)]
    fn pixel_fast<const VERTICAL: bool, const JITTER: bool>(
        &self,
        x: usize,
        y: usize,
        id: u32,
        inv: f32,
    ) -> Option<[f32; 3]> {
        let inp = self.input;
        let (mask, depth, src) = (inp.mask, inp.depth, self.src);
        let w = inp.width;
        let d0 = depth[y * w + x];
        let thr = self.rules.depth_mm;
        let (wmax, hmax) = (w as i32 - 1, inp.height as i32 - 1);
        let t = self.taps;
        let (rdx, rdy) = if JITTER {
            let [c, s] = self.rotations[rotation_index(x, y, self.seed)];
            if VERTICAL { (-s, c) } else { (c, s) }
        } else {
            (0.0, 0.0)
        };
        let kept = |j: usize| mask[j] == id && (depth[j] - d0).abs() <= thr;
        let (mut r, mut g, mut b) = (0.0f32, 0.0f32, 0.0f32);
        let centre = src[y * w + x];
        for (&o_mm, wt) in t.offset.iter().zip(&t.weight) {
            let o = o_mm * inv;
            let v = if o_mm == 0.0 {
                // The centre tap reads the pixel itself, whatever the rotation.
                centre
            } else if JITTER && self.rotates(o_mm) {
                let (sx, sy) = (x as f32 - o * rdx, y as f32 - o * rdy);
                let ([j00, j01, j10, j11], fx, fy) = bilinear_cell(sx, sy, w, wmax, hmax);
                if !(kept(j00) && kept(j01) && kept(j10) && kept(j11)) {
                    return None;
                }
                let (a0, a1, b0, b1) = (src[j00], src[j01], src[j10], src[j11]);
                let lerp2 = |c: usize| {
                    let top = a0[c] + fx * (a1[c] - a0[c]);
                    let bottom = b0[c] + fx * (b1[c] - b0[c]);
                    top + fy * (bottom - top)
                };
                [lerp2(0), lerp2(1), lerp2(2)]
            } else {
                let (p, stride, lim) = if VERTICAL {
                    (y as f32 - o, w, hmax)
                } else {
                    (x as f32 - o, 1, wmax)
                };
                let base = if VERTICAL { x } else { y * w };
                let p0 = floor_i32(p);
                let f = p - p0 as f32;
                let j0 = base + p0.clamp(0, lim) as usize * stride;
                let j1 = base + (p0 + 1).clamp(0, lim) as usize * stride;
                if !(kept(j0) && kept(j1)) {
                    return None;
                }
                let (s0, s1) = (src[j0], src[j1]);
                [
                    s0[0] + f * (s1[0] - s0[0]),
                    s0[1] + f * (s1[1] - s0[1]),
                    s0[2] + f * (s1[2] - s0[2]),
                ]
            };
            r += wt[0] * v[0];
            g += wt[1] * v[1];
            b += wt[2] * v[2];
        }
        Some([r, g, b])
    }

    /// The filtered value of pixel (x, y): 0 for background, the skip rule, else every tap.
    #[inline(always)]
    pub fn pixel<const VERTICAL: bool, const JITTER: bool>(&self, x: usize, y: usize) -> [f32; 3] {
        let inp = self.input;
        let i = y * inp.width + x;
        let id = inp.mask[i];
        if id == NO_OBJECT {
            return [0.0; 3];
        }
        let Some(inv) = self.rules.inverse_scale(inp.mm_per_pixel[i]) else {
            let (centre, sum) = (self.src[i], self.taps.sum);
            return [centre[0] * sum[0], centre[1] * sum[1], centre[2] * sum[2]];
        };
        match self.pixel_fast::<VERTICAL, JITTER>(x, y, id, inv) {
            Some(v) => v,
            None => self.pixel_slow(x, y, id, inv),
        }
    }
}
