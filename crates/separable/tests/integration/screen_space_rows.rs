//! The row-chunked pass (`filter_into`) against the per-pixel form it reorganises
//! (`Evaluation::PerPixel`, every tap fetched and silhouette-tested on its own), on frames
//! built to hit every branch of the chunked form — silhouettes, depth jumps, footprints that
//! change across a chunk, image borders, background, sub-pixel skips, bad pixels,
//! chunk-unaligned widths, every jitter setting and multi-term kernels.
//!
//! The two forms agree within [`REL`] relative per pixel and channel, with an absolute floor
//! of [`ABS`] times the channel's largest magnitude in the image (see [`assert_close`]); the
//! chunked form gives the same bits for any thread count, and its 16-pixel AVX-512 groups
//! the same bits as its 8-pixel AVX2 ones.

use crate::common;

use crate::common::{BACKGROUND, Frame, hash01};
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
pub(crate) fn run_with(
    f: &Frame,
    kernel: &SeparableKernel,
    opts: &FilterOptions,
    e: Evaluation,
) -> (Vec<[f32; 3]>, f64) {
    let mut out = vec![[0.0; 3]; f.width * f.height];
    let fast = screen_space::filter_into_with(
        &f.input(),
        kernel,
        opts,
        &mut Default::default(),
        &mut out,
        e,
    )
    .unwrap();
    (out, fast)
}

fn run(f: &Frame, kernel: &SeparableKernel, opts: &FilterOptions, e: Evaluation) -> Vec<[f32; 3]> {
    run_with(f, kernel, opts, e).0
}

/// Relative tolerance per pixel and channel (the required bound).
const REL: f64 = 1e-5;
/// Absolute floor, as a fraction of the channel's largest |value| in the reference image.
const ABS: f64 = 1e-6;

/// Asserts `got` within tolerance of the per-pixel `reference`, naming the first pixel off:
/// |got − ref| ≤ [`REL`]·|ref| + [`ABS`]·M, M the channel's largest |ref| over the image, and
/// identical bits where the reference is not finite.
///
/// The chunked form differs from the per-pixel one by rounding only: fused multiply-adds
/// (AVX2 build), rotated taps blended along y first and summed after the axis taps, lerps
/// written as fused operations. Each of a pixel's few dozen roundings is at most 2⁻²⁴ of the
/// terms it combines, so for the one-signed kernels the difference stays near 10⁻⁶ relative.
/// Signed kernels (SVD terms of rank ≥ 2) cancel, so a near-zero pixel can carry the rounding
/// of terms as large as the image's values: hence the floor, 10⁻⁶ of the channel's largest
/// value (≈ 16 roundings of that size). A weight off by 10⁻⁴ shifts a pixel by ≈ 10⁻⁴ of
/// that tap's share of it, far beyond both.
fn assert_close(f: &Frame, got: &[[f32; 3]], reference: &[[f32; 3]], what: &str) {
    if let Some(off) = first_off(f, got, reference) {
        panic!("{what}: {off}");
    }
    let scale = channel_scale(reference);
    let mut worst = 0.0f64;
    for (a, b) in got.iter().zip(reference) {
        for c in 0..3 {
            let (x, r) = (a[c] as f64, b[c] as f64);
            if r.is_finite() {
                let err = (x - r).abs();
                worst = worst.max(err / (r.abs() + ABS / REL * scale[c]).max(f64::MIN_POSITIVE));
            }
        }
    }
    eprintln!("{what}: largest error {worst:.2e} of the tolerance's scale");
}

/// Each channel's largest finite |value| in `reference` (the scale of [`ABS`]).
fn channel_scale(reference: &[[f32; 3]]) -> [f64; 3] {
    std::array::from_fn(|c| {
        reference
            .iter()
            .map(|p| p[c].abs() as f64)
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max)
    })
}

/// The first pixel and channel where `got` is off the per-pixel `reference` by more than the
/// tolerance, if any.
pub(crate) fn first_off(f: &Frame, got: &[[f32; 3]], reference: &[[f32; 3]]) -> Option<String> {
    let scale = channel_scale(reference);
    for (i, (a, b)) in got.iter().zip(reference).enumerate() {
        for c in 0..3 {
            let (x, r) = (a[c] as f64, b[c] as f64);
            let ok = if r.is_finite() {
                (x - r).abs() <= REL * r.abs() + ABS * scale[c]
            } else {
                a[c].to_bits() == b[c].to_bits()
            };
            if !ok {
                return Some(format!(
                    "pixel ({}, {}) channel {c}: {a:?} vs per-pixel {b:?}",
                    i % f.width,
                    i / f.width
                ));
            }
        }
    }
    None
}

/// Asserts the chunked form (both builds) within tolerance of the per-pixel form; returns the
/// fast-path fraction.
fn assert_same(f: &Frame, kernel: &SeparableKernel, opts: &FilterOptions, what: &str) -> f64 {
    let (rows, fast) = run_with(f, kernel, opts, Evaluation::Rows);
    let (reference, none) = run_with(f, kernel, opts, Evaluation::PerPixel);
    assert_eq!(none, 0.0, "the per-pixel form takes no chunk");
    // The x86-64 baseline build of the chunked form (AVX2 + FMA machines run the other one).
    let (baseline, fast_baseline) = run_with(f, kernel, opts, Evaluation::RowsBaseline);
    assert_eq!(fast_baseline, fast);
    assert_close(
        f,
        &baseline,
        &reference,
        &format!("{what} (baseline build)"),
    );
    assert_close(f, &rows, &reference, what);
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
fn chunked_pass_matches_the_per_pixel_pass() {
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
    // Two footprints that vary along the row, over a texture:
    // - changing by a fraction of a pixel per chunk (the tap offsets differ across a chunk,
    //   so taps switch between the contiguous and the per-lane reads);
    // - alternating every 5 pixels between 0.25 and 0.6 mm: an axis tap's integer offsets
    //   span several values within a group of 8 or 16 pixels, so the groups go pixel by
    //   pixel inside chunks that pass the test (every tap must still be summed).
    type Footprint = fn(usize) -> f32;
    let footprints: [(&str, usize, Footprint); 2] = [
        ("sliding footprint", 64, |x| 0.3 + 0.0007 * x as f32),
        ("alternating footprint", 48, |x| {
            if (x / 5) % 2 == 0 { 0.25 } else { 0.6 }
        }),
    ];
    for (label, height, mm) in footprints {
        let mut f = Frame::flat(257, height, 0.5);
        f.set_irradiance(hash01);
        for (i, m) in f.mm_per_pixel.iter_mut().enumerate() {
            *m = mm(i % 257);
        }
        for jitter in [0.0, 0.1] {
            let opts = FilterOptions {
                jitter_radius: jitter,
                ..Default::default()
            };
            for (name, kernel) in kernels() {
                let what = format!("{label}, {name}, jitter {jitter}");
                assert_eq!(assert_same(&f, &kernel, &opts, &what), 1.0, "{what}");
            }
        }
    }
}

#[test]
fn horizontal_edges_within_the_vertical_reach_are_seen() {
    // A horizontal strip of another object, of a raised surface and of a sunken one across
    // the frame: the vertical pass's silhouette test reads the summary's 8-row bands, which
    // must carry the strip's id and depths to the chunks above and below it (a band that
    // lost either would let those chunks read across the edge, which the per-pixel form
    // rejects). The texture makes any such read visible.
    let (w, h) = (200, 96);
    let strip = |y: usize| (40..56).contains(&y);
    let mut frames = Vec::new();
    let mut f = Frame::flat(w, h, 0.5);
    f.set_irradiance(hash01);
    for y in 0..h {
        if strip(y) {
            f.mask[y * w..(y + 1) * w].fill(1);
        }
    }
    frames.push(("object strip", f));
    for dz in [60.0, -60.0] {
        let mut f = Frame::flat(w, h, 0.5);
        f.set_irradiance(hash01);
        for y in 0..h {
            if strip(y) {
                f.depth[y * w..(y + 1) * w].fill(1000.0 + dz);
            }
        }
        frames.push((
            if dz > 0.0 {
                "deeper strip"
            } else {
                "nearer strip"
            },
            f,
        ));
    }
    let (_, kernel) = kernels().remove(0);
    for (name, f) in &frames {
        for jitter in [0.0, 0.1] {
            let opts = FilterOptions {
                jitter_radius: jitter,
                ..Default::default()
            };
            let fast = assert_same(f, &kernel, &opts, &format!("{name}, jitter {jitter}"));
            // Rows far from the strip (and from the frame's ends) still take chunks.
            assert!(
                fast > 0.3 && fast < 1.0,
                "{name}: fast path fraction {fast}"
            );
        }
    }
}

#[test]
fn taps_reaching_past_the_padded_row_fall_back_per_pixel() {
    // A frame 4200 pixels wide whose footprint is so small that the widest axis tap reaches
    // 4150 pixels: the chunks still qualify (the reach is under width + height), but the
    // horizontal pass pads its row by at most 4096 pixels, so the groups whose taps read past
    // the padding (within 55 pixels of either end) must go pixel by pixel, and the rotated
    // taps (over 1200 pixels long) reach past the frame's two rows and read clamped texels.
    let (_, kernel) = kernels().remove(0);
    let reach = kernel.terms[0]
        .horizontal
        .taps
        .iter()
        .map(|t| t.offset_mm.abs())
        .fold(0.0, f64::max);
    let mut f = Frame::flat(4200, 2, (reach / 4150.0) as f32);
    f.set_irradiance(hash01);
    for jitter in [0.0, 0.1] {
        let opts = FilterOptions {
            jitter_radius: jitter,
            ..Default::default()
        };
        let fast = assert_same(
            &f,
            &kernel,
            &opts,
            &format!("reach 4150 px, jitter {jitter}"),
        );
        assert_eq!(fast, 1.0, "jitter {jitter}: every chunk qualifies");
    }
}

#[test]
fn the_benchmark_frames_filter_alike() {
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
    // The second bench frame: the footprint grows from 0.3 to 0.7 mm per pixel across the
    // frame, so tap offsets change within chunks (the two-offset reads).
    tilt(&mut f);
    let fast = assert_same(&f, &kernel, &FilterOptions::default(), "tilted bench frame");
    assert!(fast > 0.9, "tilted: fast path fraction {fast}");
}

/// The footprint and depth of the tilted bench frame (`crates/bench/benches/separable.rs`).
fn tilt(f: &mut Frame) {
    let (wf, hf) = (f.width.max(2) as f32 - 1.0, f.height.max(2) as f32 - 1.0);
    for (i, (d, m)) in f.depth.iter_mut().zip(&mut f.mm_per_pixel).enumerate() {
        let (x, y) = ((i % f.width) as f32, (i / f.width) as f32);
        *m = 0.3 + 0.4 * x / wf + 0.05 * y / hf;
        *d = 600.0 + 0.1 * x + 0.05 * y;
    }
}

#[test]
fn the_chunked_pass_gives_the_same_bits_for_any_thread_count() {
    let mut tilted = Frame::flat(203, 71, 0.5);
    tilted.set_irradiance(hash01);
    tilt(&mut tilted);
    for f in [hard_frame(203, 71), tilted] {
        for jitter in [0.0, 0.1, 1.0] {
            let opts = FilterOptions {
                jitter_radius: jitter,
                seed: 5,
                ..Default::default()
            };
            for (name, kernel) in kernels() {
                let run = |threads| {
                    rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .unwrap()
                        .install(|| run(&f, &kernel, &opts, Evaluation::Rows))
                };
                let (one, two) = (run(1), run(2));
                assert!(
                    one.iter()
                        .zip(&two)
                        .all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits)),
                    "{name} jitter {jitter}: 1 and 2 threads differ"
                );
            }
        }
    }
}

/// A [`screen_space::FilterScratch`] kept across frames gives the bits of a fresh one, frame
/// after frame, as the size, the seed, the jitter and the content change (its rotation table
/// is reused only for the same size and seed; its summary buffers are rewritten). Every
/// frame here differs from the one before in exactly one of those, so a table or a summary
/// kept when it should not be shows as a mismatch.
#[test]
fn a_scratch_kept_across_frames_gives_the_bits_of_a_fresh_one() {
    let kernel = &kernels()[0].1;
    let mut moved = hard_frame(203, 71);
    moved.set_irradiance(|x, y| hash01(x + 7, y));
    moved.mm_per_pixel.iter_mut().for_each(|m| *m *= 1.5);
    moved.mask[50 * 203..52 * 203].fill(BACKGROUND);
    let frames = [
        hard_frame(203, 71),
        hard_frame(203, 71),
        moved,
        hard_frame(71, 203),
        hard_frame(203, 71),
    ];
    let opts = |seed, jitter_radius| FilterOptions {
        jitter_radius,
        seed,
        ..Default::default()
    };
    // (frame, seed, jitter): same twice, new content, new size (same pixel count), back, new
    // seed, no jitter, jitter again.
    let sequence = [
        (0, 5, 0.3),
        (1, 5, 0.3),
        (2, 5, 0.3),
        (3, 5, 0.3),
        (4, 5, 0.3),
        (4, 6, 0.3),
        (4, 6, 0.0),
        (4, 6, 0.3),
        (0, 5, 1.0),
    ];
    let mut kept = screen_space::FilterScratch::default();
    for (step, &(i, seed, jitter)) in sequence.iter().enumerate() {
        let f = &frames[i];
        let o = opts(seed, jitter);
        let mut got = vec![[0.0; 3]; f.width * f.height];
        screen_space::filter_into(&f.input(), kernel, &o, &mut kept, &mut got).unwrap();
        let fresh = run(f, kernel, &o, Evaluation::Rows);
        let off = got
            .iter()
            .zip(&fresh)
            .filter(|(a, b)| a.map(f32::to_bits) != b.map(f32::to_bits))
            .count();
        assert_eq!(
            off, 0,
            "step {step} (frame {i}, seed {seed}, jitter {jitter})"
        );
    }
    // The steps differ from each other (so each one checks something).
    let a = run(&frames[4], kernel, &opts(5, 0.3), Evaluation::Rows);
    let b = run(&frames[4], kernel, &opts(6, 0.3), Evaluation::Rows);
    let c = run(&frames[2], kernel, &opts(5, 0.3), Evaluation::Rows);
    let d = run(&frames[0], kernel, &opts(5, 0.3), Evaluation::Rows);
    assert!(a.iter().zip(&b).filter(|(x, y)| x != y).count() > 1000);
    assert!(c.iter().zip(&d).filter(|(x, y)| x != y).count() > 1000);
}
