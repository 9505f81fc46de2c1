//! Unit tests of the row-chunked form's pieces: the AVX2 summary and rotation table against
//! the portable ones bit for bit, and the summary's cells against brute force.

#[cfg(target_arch = "x86_64")]
use super::avx2::{rotation_row_avx2, summary_cell_avx2};
use super::rotation::rotation_row;
use super::summary::{BAND, CELL, summary_cell};
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
        // Around the widest kernel: 2 · 14 mm / 2²⁴ ≈ 1.669e-6 mm per pixel.
        1.6e-6,
        1.7e-6,
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
    // Under Miri, which checks the loads of every cell, a tenth of the cells.
    let cells = if cfg!(miri) { 400 } else { 4000 };
    for t in 0..cells as u64 {
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
    let both = cells / 8..cells * 7 / 8;
    assert!(both.contains(&uniform), "{uniform} uniform cells");
    assert!(both.contains(&blurred), "{blurred} blurred cells");
}

/// The hoisted silhouette test is the per-pixel one over whole cells: on a frame with
/// another object, a background strip, a raised patch and a non-finite depth,
/// [`CellSummary::clean`] says a rectangle's cells show only `id` with finite depths in
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
    let s = CellSummary::new(&input, &rules, Default::default(), &summary_rows(Isa::Best));
    let (mut kept, mut by_cells) = (0, 0);
    // Under Miri, a tenth of the rectangles.
    let tries = if cfg!(miri) { 300 } else { 20_000 };
    for t in 0..tries as u64 {
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
    assert!(
        (tries / 10..tries * 9 / 10).contains(&kept),
        "{kept} rectangles kept"
    );
    assert!(by_cells >= tries / 100, "{by_cells} kept by the cells only");
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
            for w in [0, 1, 3, 4, 5, 8, 13, if cfg!(miri) { 21 } else { 1921 }] {
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
    assert_eq!(checked, 24 * if cfg!(miri) { 55 } else { 1955 });
}

/// A kernel built from taps alone (no model or fit: cheap enough for Miri): 7 taps over
/// ±3 mm, one positive term plus, with `signed`, a second whose vertical taps change sign.
fn small_kernel(signed: bool) -> SeparableKernel {
    use crate::kernel::{Kernel1d, SeparableTerm, Tap};
    let taps = |scale: f64, alt: bool| Kernel1d {
        taps: (0..7)
            .map(|i| {
                let x = i as f64 - 3.0;
                let w = scale * (-(x * x) / 4.0).exp();
                let s = if alt && i % 2 == 1 { -0.5 } else { 1.0 };
                Tap {
                    offset_mm: x,
                    weight: [w * s, 0.8 * w * s, 0.6 * w],
                }
            })
            .collect(),
    };
    let mut terms = vec![SeparableTerm {
        horizontal: taps(0.3, false),
        vertical: taps(0.3, false),
    }];
    if signed {
        terms.push(SeparableTerm {
            horizontal: taps(0.05, false),
            vertical: taps(0.05, true),
        });
    }
    SeparableKernel {
        terms,
        support_mm: 3.0,
    }
}

/// The row-chunked form (with AVX2 and FMA where the CPU has them: under Miri, where the build
/// enables them, see `docs/testing.md`), its baseline build and the per-pixel form agree on
/// small frames that reach the fast path, the group loops' rotated-tap loads, the border
/// path and the per-pixel fallback (another object, a depth step, a broken footprint). Sized
/// for Miri, which checks every `unsafe` access of the AVX2 loops it executes for bounds,
/// alignment and initialisation.
#[test]
fn the_forms_agree_on_small_frames() {
    // Under Miri (about a million times slower): three rows, jitter on (the gathers and the
    // rotated taps' loads), both kernels.
    let (w, h) = if cfg!(miri) { (70, 3) } else { (70, 5) };
    #[cfg(target_arch = "x86_64")]
    eprintln!(
        "AVX2 and FMA {}",
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            "detected: the chunks run the AVX2 loops"
        } else {
            "not detected: the chunks run the portable loops"
        }
    );
    let n = w * h;
    let irradiance: Vec<[f32; 3]> = (0..n)
        .map(|i| {
            let u = (sss_util::splitmix64(i as u64) >> 40) as f32 / (1u64 << 24) as f32;
            [u, 0.5 * u + 0.1, 1.0 - u]
        })
        .collect();
    let mut mask = vec![1u32; n];
    let mut depth: Vec<f32> = (0..n).map(|i| 800.0 + 0.05 * (i % w) as f32).collect();
    let mut mm: Vec<f32> = (0..n).map(|i| 0.2 + 0.001 * (i % w) as f32).collect();
    mask[2 * w + 50] = 2;
    depth[(h - 1) * w + 60] += 40.0;
    mm[w + 10] = f32::NAN;
    mm[(h - 1) * w + 30] = 1e-30;
    let input = ScreenInput {
        width: w,
        height: h,
        irradiance: &irradiance,
        depth: &depth,
        mask: &mask,
        mm_per_pixel: &mm,
    };
    let mut fast_seen = 0.0f64;
    for signed in [false, true] {
        let kernel = small_kernel(signed);
        let jitters: &[f32] = if cfg!(miri) { &[0.5] } else { &[0.0, 0.5] };
        for &jitter in jitters {
            let opts = FilterOptions {
                jitter_radius: jitter,
                seed: 3,
                ..Default::default()
            };
            let run = |e| {
                let mut out = vec![[0.0f32; 3]; n];
                let fast =
                    filter_into_with(&input, &kernel, &opts, &mut Default::default(), &mut out, e)
                        .unwrap();
                (out, fast)
            };
            let (reference, _) = run(Evaluation::PerPixel);
            let scale: [f32; 3] =
                std::array::from_fn(|c| reference.iter().map(|p| p[c].abs()).fold(0.0, f32::max));
            let forms: &[Evaluation] = if cfg!(miri) {
                &[Evaluation::Rows]
            } else {
                &[Evaluation::Rows, Evaluation::RowsBaseline]
            };
            for &e in forms {
                let (out, fast) = run(e);
                fast_seen = fast_seen.max(fast);
                for (i, (a, b)) in out.iter().zip(&reference).enumerate() {
                    for c in 0..3 {
                        assert!(
                            a[c].is_finite()
                                && (a[c] - b[c]).abs() <= 1e-5 * b[c].abs() + 1e-6 * scale[c],
                            "signed {signed}, jitter {jitter}, {e:?}: pixel {i} channel {c}: \
                             {a:?} vs {b:?}"
                        );
                    }
                }
            }
        }
    }
    assert!(fast_seen > 0.3, "fast path fraction {fast_seen}");
}
