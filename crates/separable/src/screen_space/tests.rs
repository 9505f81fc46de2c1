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
