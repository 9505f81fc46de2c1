//! Differential test of the screen-space pass on random frames: the AVX2 + FMA build of the
//! row-chunked form (`Evaluation::Rows` on a CPU that has both), its x86-64 baseline build
//! (`Evaluation::RowsBaseline`, the portable loops) and the per-pixel form they reorganise
//! (`Evaluation::PerPixel`) on frames drawn from a seeded generator: sizes from one pixel to a
//! few chunks (chunk-unaligned widths), footprints constant, tilted, stepped, noisy, sub-pixel
//! or broken (0, negative, NaN, ∞), depths smooth, cliffed or broken, object ids in
//! rectangles, discs and single pixels (background among them), features touching the
//! borders, every jitter setting, rotation seeds and kernels with one and several terms,
//! signed ones among them.
//!
//! Required: each pair agrees within the tolerance the module documentation of
//! `sss_separable::screen_space` states (10⁻⁵ relative per pixel and channel, with an absolute
//! floor of 10⁻⁶ of the channel's largest value; identical bits where the per-pixel value is
//! not finite), the same as the hand-built frames of `screen_space_rows`. The AVX2 loops'
//! `unsafe` reads (the rotated taps' loads from cells checked inside the image once per group,
//! the gathers of the rotation table) sit on the fast path, which these frames reach: the test
//! also requires that a good share of the frames took it.
//!
//! Under Miri (`docs/testing.md`) the same test runs on a few small frames.

use crate::common::{self, BACKGROUND, Frame};
use crate::screen_space_rows::{first_off, run_with};
use sss_separable::screen_space::{Evaluation, FilterOptions};
use sss_separable::{SeparableKernel, TapPlacement, preintegrated};
use sss_util::splitmix64;

/// A seeded stream of random numbers for one frame.
struct Draw {
    state: u64,
}

impl Draw {
    fn new(seed: u64) -> Draw {
        Draw {
            state: splitmix64(seed ^ 0x5eed_f00d),
        }
    }
    fn u64(&mut self) -> u64 {
        self.state = splitmix64(self.state);
        self.state
    }
    /// Uniform in 0..n (n > 0).
    fn below(&mut self, n: usize) -> usize {
        (self.u64() % n as u64) as usize
    }
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn pick<T: Copy>(&mut self, xs: &[T]) -> T {
        xs[self.below(xs.len())]
    }
}

/// A random frame: see the module documentation for what varies.
fn random_frame(d: &mut Draw, max_w: usize, max_h: usize) -> Frame {
    let w = match d.below(4) {
        0 => 1 + d.below(8),
        1 => d.pick(&[63, 64, 65, 127, 128, 129, 191, 203]).min(max_w),
        _ => 1 + d.below(max_w),
    };
    let h = 1 + d.below(max_h);
    // Footprint (mm per pixel) at the frame's centre: the 7-tap kernel reaches ≈ 3 mm, so
    // 0.05 gives ≈ 60-pixel taps, 0.5 a few pixels, 20 a sub-pixel kernel (skipped).
    let base = d.pick(&[0.05f32, 0.1, 0.25, 0.5, 1.0, 20.0]);
    let footprint = d.below(5);
    let (tx, ty) = (d.unit() * 0.02, d.unit() * 0.02);
    let depth_mode = d.below(3);
    let mut f = Frame::flat(w, h, base);
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let u = d.unit();
            f.irradiance[i] = match d.below(8) {
                0 => [0.0; 3],
                1 => [u * 1e3, u, 1e-3],
                _ => [u, 0.5 * u + 0.1, (1.0 - u) * 0.3],
            };
            f.mm_per_pixel[i] = match footprint {
                0 => base,
                1 => base * (1.0 + tx * x as f32 + ty * y as f32),
                2 => base * if x > w / 2 { 1.7 } else { 1.0 },
                3 => base * (0.8 + 0.4 * d.unit()),
                _ => base * if (x / 16 + y / 8) % 2 == 0 { 1.0 } else { 40.0 },
            };
            f.depth[i] = 800.0
                + match depth_mode {
                    0 => 0.0,
                    1 => 0.3 * x as f32 + 0.1 * y as f32,
                    _ => 25.0 * (d.unit() < 0.01) as u32 as f32 + 0.05 * x as f32,
                };
        }
    }
    // Objects: a few rectangles and discs of other ids or of background, some reaching past
    // the borders.
    for _ in 0..d.below(5) {
        let id = d.pick(&[1u32, 2, 7, BACKGROUND]);
        let (cx, cy) = (d.below(w + 8) as isize - 4, d.below(h + 8) as isize - 4);
        let (rx, ry) = (
            1 + d.below(w.max(2)) as isize / 2,
            1 + d.below(h.max(2)) as isize / 2,
        );
        let disc = d.below(2) == 0;
        let raise = d.pick(&[0.0f32, 0.0, 3.0, 60.0]);
        for y in 0..h as isize {
            for x in 0..w as isize {
                let (dx, dy) = (x - cx, y - cy);
                let inside = if disc {
                    (dx * dx) as f32 / (rx * rx) as f32 + (dy * dy) as f32 / (ry * ry) as f32 <= 1.0
                } else {
                    dx.abs() <= rx && dy.abs() <= ry
                };
                if inside {
                    let i = y as usize * w + x as usize;
                    f.mask[i] = id;
                    f.depth[i] += raise;
                }
            }
        }
    }
    // Broken pixels: the per-pixel rules give them defined values, the chunks must defer.
    for _ in 0..d.below(4) {
        let i = d.below(w * h);
        match d.below(5) {
            0 => f.mm_per_pixel[i] = d.pick(&[0.0, -0.5, f32::NAN, f32::INFINITY, 1e-30]),
            1 => f.depth[i] = d.pick(&[f32::NAN, f32::INFINITY, -3.0, -0.0]),
            2 => f.mask[i] = d.pick(&[3, BACKGROUND]),
            3 => f.irradiance[i] = [0.0, 1e30, 0.0],
            _ => f.mm_per_pixel[i] = 1e30,
        }
    }
    f
}

/// The kernels drawn from: pre-integrated with 7 importance and 15 uniform taps (reaching far),
/// SVD rank 3 (signed terms), 3 Gaussians (several terms).
fn kernels() -> Vec<(&'static str, SeparableKernel)> {
    let m = common::model("skin1");
    let k = common::kernel2d(m.as_ref(), 31);
    let mut all = common::screen_kernels();
    all.push((
        "pre-integrated 15 uniform",
        preintegrated::kernel(&k, TapPlacement::Uniform(15)).unwrap(),
    ));
    all
}

/// Frames per run, and their largest size: fewer and smaller under Miri.
fn plan() -> (u64, usize, usize) {
    if cfg!(miri) {
        (6, 70, 6)
    } else {
        (400, 203, 40)
    }
}

#[test]
fn avx2_portable_and_per_pixel_agree_on_random_frames() {
    let kernels = kernels();
    let (frames, max_w, max_h) = plan();
    let (mut fast_frames, mut pixels) = (0, 0);
    for seed in 0..frames {
        let mut d = Draw::new(seed);
        let f = random_frame(&mut d, max_w, max_h);
        let (name, kernel) = &kernels[d.below(kernels.len())];
        let opts = FilterOptions {
            jitter_radius: d.pick(&[0.0, 0.0, 0.1, 0.3, 1.0]),
            seed: d.u64(),
            ..Default::default()
        };
        let what = format!(
            "frame {seed} ({}×{}, {name}, jitter {})",
            f.width, f.height, opts.jitter_radius
        );
        let (reference, _) = run_with(&f, kernel, &opts, Evaluation::PerPixel);
        let (avx2, fast) = run_with(&f, kernel, &opts, Evaluation::Rows);
        let (portable, fast_portable) = run_with(&f, kernel, &opts, Evaluation::RowsBaseline);
        // The two builds choose the same chunks: only the arithmetic differs.
        assert_eq!(fast, fast_portable, "{what}: fast-path fractions differ");
        if let Some(off) = first_off(&f, &avx2, &reference) {
            panic!("{what}: AVX2 build: {off}");
        }
        if let Some(off) = first_off(&f, &portable, &reference) {
            panic!("{what}: portable build: {off}");
        }
        fast_frames += usize::from(fast > 0.0);
        pixels += f.width * f.height;
    }
    // The fast path (and with it the `unsafe` loads) was reached on many frames, and the
    // frames were not all tiny.
    eprintln!("{fast_frames} of {frames} frames took the fast path; {pixels} pixels");
    assert!(
        fast_frames as u64 * 5 >= frames,
        "only {fast_frames} of {frames} frames took the fast path"
    );
    assert!(
        pixels as u64 >= frames * 8,
        "{pixels} pixels in {frames} frames"
    );
}

/// The test can fail: a tap weight changed by 10⁻⁴ of itself in one build only (the kind of
/// slip a SIMD loop makes) is caught on the frames above.
#[test]
fn a_perturbed_kernel_is_caught() {
    let kernels = kernels();
    let (_, kernel) = &kernels[0];
    let mut wrong = kernel.clone();
    wrong.terms[0].horizontal.taps[1].weight[0] *= 1.0 + 1e-4;
    let mut caught = 0;
    for seed in 0..20 {
        let mut d = Draw::new(1000 + seed);
        let f = random_frame(&mut d, 128, 16);
        let opts = FilterOptions::default();
        let (reference, _) = run_with(&f, kernel, &opts, Evaluation::PerPixel);
        let (off, _) = run_with(&f, &wrong, &opts, Evaluation::Rows);
        caught += usize::from(first_off(&f, &off, &reference).is_some());
    }
    assert!(
        caught >= 10,
        "a perturbed weight was caught on {caught} of 20 frames"
    );
}

/// Found by the random frames: a footprint of 10⁻³⁰ mm per pixel (a kernel 10³¹ pixels wide)
/// put taps where f32 positions lose their fractions and the integer part saturates, and the
/// filter wrote ±∞ and NaN around it. Such a pixel now skips the blur (irradiance × the
/// kernel's total weight), in every form, and its neighbours stay finite.
#[test]
fn a_vanishing_footprint_skips_the_blur_and_stays_finite() {
    let kernels = kernels();
    for (name, kernel) in &kernels {
        for footprint in [1e-30f32, 1e-12, 1e-7] {
            let mut f = Frame::flat(40, 9, 0.5);
            f.set_irradiance(crate::common::hash01);
            let centre = 4 * 40 + 20;
            f.mm_per_pixel[centre] = footprint;
            for jitter in [0.0, 0.3] {
                let opts = FilterOptions {
                    jitter_radius: jitter,
                    ..Default::default()
                };
                for e in [
                    Evaluation::Rows,
                    Evaluation::RowsBaseline,
                    Evaluation::PerPixel,
                ] {
                    let (out, _) = run_with(&f, kernel, &opts, e);
                    assert!(
                        out.iter().flatten().all(|v| v.is_finite()),
                        "{name}, footprint {footprint}, jitter {jitter}, {e:?}: non-finite output"
                    );
                    // One term: the skipped pixel is E × the kernel's total weight (the
                    // horizontal and vertical sums' product).
                    if kernel.terms.len() == 1 {
                        let t = &kernel.terms[0];
                        for c in 0..3 {
                            let sum = |k: &sss_separable::Kernel1d| {
                                k.taps.iter().map(|t| t.weight[c]).sum::<f64>()
                            };
                            let want = f.irradiance[centre][c] as f64
                                * sum(&t.horizontal)
                                * sum(&t.vertical);
                            let got = out[centre][c] as f64;
                            assert!(
                                (got - want).abs() <= 1e-5 * want.abs() + 1e-12,
                                "{name}, footprint {footprint}, {e:?}, channel {c}: {got} vs {want}"
                            );
                        }
                    }
                }
            }
        }
    }
}
