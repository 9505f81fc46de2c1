//! The row-chunked pass (`filter_into`) against the per-pixel form it reorganises
//! (`Evaluation::PerPixel`, every tap fetched and silhouette-tested on its own): identical
//! bits on frames built to hit every branch of the chunked form — silhouettes, depth jumps,
//! footprints that change across a chunk, image borders, background, sub-pixel skips, bad
//! pixels, chunk-unaligned widths, every jitter setting and multi-term kernels.

mod common;

use common::{BACKGROUND, Frame, hash01};
use sss_separable::screen_space::{self, Evaluation, FilterOptions};
use sss_separable::{SeparableKernel, TapPlacement, preintegrated};

/// The shared screen-space kernels and a uniform 15-tap one (taps that reach far).
fn kernels() -> Vec<(&'static str, SeparableKernel)> {
    let m = common::model("skin1");
    let k = common::kernel2d(m.as_ref(), 31);
    let mut all = common::screen_kernels();
    all.insert(
        1,
        (
            "pre-integrated 15 uniform",
            preintegrated::kernel(&k, TapPlacement::Uniform(15)).unwrap(),
        ),
    );
    all
}

/// The filtered image and the fraction of pixel passes on the fast path.
fn run_with(
    f: &Frame,
    kernel: &SeparableKernel,
    opts: &FilterOptions,
    e: Evaluation,
) -> (Vec<[f32; 3]>, f64) {
    let mut out = vec![[0.0; 3]; f.width * f.height];
    let fast =
        screen_space::filter_into_with(&f.input(), kernel, opts, &mut Vec::new(), &mut out, e)
            .unwrap();
    (out, fast)
}

fn run(f: &Frame, kernel: &SeparableKernel, opts: &FilterOptions, e: Evaluation) -> Vec<[f32; 3]> {
    run_with(f, kernel, opts, e).0
}

/// Asserts identical bits, naming the first differing pixel; returns the fast-path fraction.
fn assert_same(f: &Frame, kernel: &SeparableKernel, opts: &FilterOptions, what: &str) -> f64 {
    let (rows, fast) = run_with(f, kernel, opts, Evaluation::Rows);
    let (reference, none) = run_with(f, kernel, opts, Evaluation::PerPixel);
    assert_eq!(none, 0.0, "the per-pixel form takes no chunk");
    // The x86-64 baseline build of the chunked form (AVX2 machines run the other one).
    let (baseline, fast_baseline) = run_with(f, kernel, opts, Evaluation::RowsBaseline);
    assert_eq!(fast_baseline, fast);
    assert!(
        rows.iter()
            .zip(&baseline)
            .all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits)),
        "{what}: baseline and AVX2 builds differ"
    );
    for (i, (a, b)) in rows.iter().zip(&reference).enumerate() {
        assert!(
            a.map(f32::to_bits) == b.map(f32::to_bits),
            "{what}: pixel ({}, {}) chunked {a:?} vs per-pixel {b:?}",
            i % f.width,
            i / f.width
        );
    }
    fast
}

/// A frame with everything the chunked form must get right.
fn hard_frame(width: usize, height: usize) -> Frame {
    let mut f = Frame::flat(width, height, 0.25);
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            let u = hash01(x, y);
            f.irradiance[i] = [u, 0.5 * u + 0.1, (1.0 - u) * 0.3];
            // Footprint varying smoothly (a tilted surface) and stepping in the lower half.
            f.mm_per_pixel[i] = 0.2 + 0.002 * x as f32 + if y > height / 2 { 0.1 } else { 0.0 };
            f.depth[i] = 800.0 + 0.3 * x as f32 + 0.1 * y as f32;
            // Two objects, background in a disc, a depth cliff on a diagonal.
            f.mask[i] = if x > width * 2 / 3 { 2 } else { 1 };
            let (dx, dy) = (
                x as f32 - width as f32 * 0.3,
                y as f32 - height as f32 * 0.35,
            );
            if dx * dx + dy * dy < 60.0 {
                f.mask[i] = BACKGROUND;
            }
            if x + y > width {
                f.depth[i] += 50.0;
            }
        }
    }
    // Bad pixels: the per-pixel rules give them defined values; the chunks must defer.
    let n = width * height;
    for (i, v) in [
        (n / 3, 0.0),
        (n / 3 + 7, f32::NAN),
        (n / 2 + 3, f32::INFINITY),
    ] {
        if let Some(m) = f.mm_per_pixel.get_mut(i) {
            *m = v;
        }
    }
    for (i, v) in [(n / 2 + 40, f32::NAN), (2 * n / 3, f32::INFINITY)] {
        if let Some(d) = f.depth.get_mut(i) {
            *d = v;
        }
    }
    // Sub-pixel footprint (skip) on row 5.
    if height > 5 {
        f.mm_per_pixel[5 * width..6 * width].fill(100.0);
    }
    f
}

#[test]
fn chunked_pass_equals_the_per_pixel_pass_bit_for_bit() {
    // 203 = three full chunks and a partial one; 150 = two and a partial one.
    let mut fast_seen = 0.0f64;
    for (w, h) in [(203, 71), (150, 40), (7, 5), (1, 9), (64, 1)] {
        let f = hard_frame(w, h);
        for jitter in [0.0, 0.1, 0.3, 1.0] {
            for seed in [0, 3] {
                let opts = FilterOptions {
                    jitter_radius: jitter,
                    seed,
                    ..Default::default()
                };
                for (name, kernel) in kernels() {
                    let what = format!("{w}×{h} {name} jitter {jitter}");
                    let fast = assert_same(&f, &kernel, &opts, &what);
                    if w == 203 {
                        fast_seen = fast_seen.max(fast);
                    }
                }
            }
        }
    }
    // Both paths were compared: the large frame's clean regions took chunks.
    assert!(fast_seen > 0.1, "fast path fraction {fast_seen}");
}

#[test]
fn the_fast_path_is_taken_on_clean_frames() {
    // A clean, uniform frame: both forms agree, and agree with a closed form (a constant
    // irradiance is reproduced × the kernel's total weight in the interior, and at the
    // borders, where reads clamp to the edge).
    let mut f = Frame::flat(300, 120, 0.5);
    f.set_irradiance(|_, _| 0.75);
    for (name, kernel) in kernels() {
        let opts = FilterOptions::default();
        let fast = assert_same(&f, &kernel, &opts, name);
        // Every chunk of a clean frame is fast, borders included (they clamp per lane).
        assert_eq!(fast, 1.0, "{name}");
        let total = kernel.total_weight();
        let out = run(&f, &kernel, &opts, Evaluation::Rows);
        for p in &out {
            for c in 0..3 {
                let want = 0.75 * total[c];
                assert!(((p[c] as f64 - want) / want).abs() < 1e-5, "{name}: {p:?}");
            }
        }
    }
    // A texture over a footprint that changes by a fraction of a pixel per chunk (the tap
    // offsets differ across a chunk, so taps switch between the contiguous and the per-lane
    // reads).
    let mut f = Frame::flat(257, 64, 0.5);
    f.set_irradiance(hash01);
    for (i, m) in f.mm_per_pixel.iter_mut().enumerate() {
        *m = 0.3 + 0.0007 * (i % 257) as f32;
    }
    for jitter in [0.0, 0.1] {
        let opts = FilterOptions {
            jitter_radius: jitter,
            ..Default::default()
        };
        for (name, kernel) in kernels() {
            assert_eq!(assert_same(&f, &kernel, &opts, name), 1.0, "{name}");
        }
    }
}

#[test]
fn the_benchmark_frame_filters_identically() {
    // The frame of `crates/bench/benches/separable.rs`: 1080p, one object, 0.5 mm per pixel, a
    // pore-like texture, a gentle depth ramp, default options, the 7-tap pre-integrated kernel
    // (here from a 31² kernel grid).
    let (w, h) = (1920, 1080);
    let mut f = Frame::flat(w, h, 0.5);
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            f.irradiance[i] = if hash01(x, y) < 0.1 {
                [0.1; 3]
            } else {
                [1.0, 0.9, 0.8]
            };
            f.depth[i] = 600.0 + x as f32 * 0.05;
        }
    }
    let (_, kernel) = kernels().remove(0);
    let fast = assert_same(&f, &kernel, &FilterOptions::default(), "bench frame");
    assert_eq!(fast, 1.0);
}
