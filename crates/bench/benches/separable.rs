//! Cost of the screen-space separable subsurface-scattering pass (Jimenez et al. 2015) on a
//! 1920 × 1080 RGB f32 frame, against the memory-bound limit (copying the same buffers), the
//! 6-Gaussian baseline (d'Eon et al. 2007, 12 passes) and the exact 2D convolution.
//!
//! Frame: one skin1 object (better dipole) filling the screen, 0.5 mm per pixel (a head and
//! shoulders shot: the 99 % kernel radius, 14 mm, spans 28 pixels), a pore-like irradiance
//! texture, a gentle depth ramp, default filter options (jitter within 10 % of the kernel).
//! Kernels: the pre-integrated kernel with 7 importance-sampled taps per pass; six Gaussians
//! with 7 importance-sampled taps per pass each. The exact 2D convolution is far too slow at
//! 1080p (N² taps per pixel), so it runs on a 256 × 256 crop with a 31 × 31 kernel grid, next
//! to the 7-tap pass on the same crop for the ratio.
//!
//! Groups report pixels per second: `cargo bench -p sss-bench --bench separable -- --noplot`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rayon::prelude::*;
use sss_bssrdf::{Medium, ModelKind, make_model};
use sss_separable::screen_space::{self, FilterOptions};
use sss_separable::{
    Kernel2d, Kernel2dSpec, ScreenInput, SeparableKernel, TapPlacement, convolve2d, gaussians,
    preintegrated,
};
use std::hint::black_box;
use std::time::Duration;

struct Frame {
    width: usize,
    height: usize,
    irradiance: Vec<[f32; 3]>,
    depth: Vec<f32>,
    mask: Vec<u32>,
    mm_per_pixel: Vec<f32>,
}

impl Frame {
    fn new(width: usize, height: usize) -> Frame {
        let n = width * height;
        let u = sss_bench::uniforms(n, 11);
        Frame {
            width,
            height,
            irradiance: u
                .iter()
                .map(|v| if *v < 0.1 { [0.1; 3] } else { [1.0, 0.9, 0.8] })
                .collect(),
            depth: (0..n).map(|i| 600.0 + (i % width) as f32 * 0.05).collect(),
            mask: vec![0; n],
            mm_per_pixel: vec![0.5; n],
        }
    }

    fn input(&self) -> ScreenInput<'_> {
        ScreenInput {
            width: self.width,
            height: self.height,
            irradiance: &self.irradiance,
            depth: &self.depth,
            mask: &self.mask,
            mm_per_pixel: &self.mm_per_pixel,
        }
    }
}

/// The memory-bound limit: read every input buffer once and write the output image.
fn copy(f: &Frame, out: &mut [[f32; 3]], aux: &mut [(f32, u32, f32)]) {
    out.copy_from_slice(&f.irradiance);
    for (i, a) in aux.iter_mut().enumerate() {
        *a = (f.depth[i], f.mask[i], f.mm_per_pixel[i]);
    }
}

/// The floor for a 7-tap pass: a plain two-pass blur of the same frame with fixed integer
/// offsets and per-channel weights (no footprint, jitter or silhouettes), written so the
/// compiler vectorises it: rows as flat f32 slices in blocks of 16 pixels with the weights
/// laid out per lane, borders clamped outside the tap loop, rows in parallel.
struct PlainBlur {
    offsets: Vec<isize>,
    /// Per tap, its RGB weights repeated over a block of [`BLOCK`] pixels.
    lanes: Vec<[f32; 3 * BLOCK]>,
    weights: Vec<[f32; 3]>,
}

const BLOCK: usize = 16;

impl PlainBlur {
    fn new(kernel: &SeparableKernel, mm_per_pixel: f64) -> PlainBlur {
        let taps = &kernel.terms[0].horizontal.taps;
        PlainBlur {
            offsets: taps
                .iter()
                .map(|t| (t.offset_mm / mm_per_pixel).round() as isize)
                .collect(),
            lanes: taps
                .iter()
                .map(|t| std::array::from_fn(|i| t.weight[i % 3] as f32))
                .collect(),
            weights: taps.iter().map(|t| t.weight.map(|w| w as f32)).collect(),
        }
    }

    /// The clamped sum at pixel `x` of a line: `Σ_t w_t · line(x + o_t)`, where `line(k)` is
    /// `src[base + k·stride .. +3]` (k clamped to the line's `len` pixels).
    #[inline(always)]
    fn clamped(&self, src: &[f32], x: isize, base: usize, stride: usize, len: usize) -> [f32; 3] {
        let mut v = [0.0f32; 3];
        for (&o, wt) in self.offsets.iter().zip(&self.weights) {
            let k = (x + o).clamp(0, len as isize - 1) as usize;
            for c in 0..3 {
                v[c] += wt[c] * src[base + k * stride + c];
            }
        }
        v
    }

    /// `acc[i] = Σ_t lanes_t[i] · src[start_t + i]` over one block of [`BLOCK`] pixels, with the
    /// sums in registers.
    #[inline(always)]
    fn block(&self, src: &[f32], starts: impl Iterator<Item = usize>, out: &mut [f32]) {
        let mut acc = [0.0f32; 3 * BLOCK];
        for (s0, lanes) in starts.zip(&self.lanes) {
            let s = &src[s0..s0 + 3 * BLOCK];
            for i in 0..3 * BLOCK {
                acc[i] += lanes[i] * s[i];
            }
        }
        out.copy_from_slice(&acc);
    }

    fn reach(&self) -> usize {
        self.offsets
            .iter()
            .map(|o| o.unsigned_abs())
            .max()
            .unwrap_or(0)
    }

    /// Row `y` of the horizontal pass.
    #[inline(always)]
    fn row_h(&self, src: &[f32], out: &mut [f32], y: usize, w: usize) {
        let base = 3 * w * y;
        let reach = self.reach();
        let (lo, hi) = (reach.min(w), w.saturating_sub(reach).max(reach.min(w)));
        // Borders pixel by pixel with the clamp; the interior in vectorisable blocks.
        for x in (0..lo).chain(hi..w) {
            let v = self.clamped(src, x as isize, base, 3, w);
            out[3 * x..3 * x + 3].copy_from_slice(&v);
        }
        let mut x = lo;
        while x + BLOCK <= hi {
            let starts = self
                .offsets
                .iter()
                .map(|&o| base + 3 * (x as isize + o) as usize);
            self.block(src, starts, &mut out[3 * x..3 * (x + BLOCK)]);
            x += BLOCK;
        }
        for x in x..hi {
            let v = self.clamped(src, x as isize, base, 3, w);
            out[3 * x..3 * x + 3].copy_from_slice(&v);
        }
    }

    /// Row `y` of the vertical pass.
    #[inline(always)]
    fn row_v(&self, tmp: &[f32], out: &mut [f32], y: usize, w: usize, h: usize) {
        let reach = self.reach();
        if y < reach || y + reach >= h {
            for x in 0..w {
                let v = self.clamped(tmp, y as isize, 3 * x, 3 * w, h);
                out[3 * x..3 * x + 3].copy_from_slice(&v);
            }
            return;
        }
        let mut x = 0;
        while x + BLOCK <= w {
            let starts = self
                .offsets
                .iter()
                .map(|&o| 3 * w * (y as isize + o) as usize + 3 * x);
            self.block(tmp, starts, &mut out[3 * x..3 * (x + BLOCK)]);
            x += BLOCK;
        }
        for x in x..w {
            let v = self.clamped(tmp, y as isize, 3 * x, 3 * w, h);
            out[3 * x..3 * x + 3].copy_from_slice(&v);
        }
    }

    /// Horizontal pass into `tmp`, vertical pass into `out` (both row-major RGB), in the AVX2
    /// build where the CPU has it (as the separable pass does).
    fn run(&self, f: &Frame, tmp: &mut [[f32; 3]], out: &mut [[f32; 3]]) {
        let (w, h) = (f.width, f.height);
        let src = f.irradiance.as_flattened();
        tmp.as_flattened_mut()
            .par_chunks_mut(3 * w)
            .enumerate()
            .for_each(|(y, row)| self.dispatch(|| self.row_h(src, row, y, w)));
        let tmp = tmp.as_flattened();
        out.as_flattened_mut()
            .par_chunks_mut(3 * w)
            .enumerate()
            .for_each(|(y, row)| self.dispatch(|| self.row_v(tmp, row, y, w, h)));
    }

    #[inline(always)]
    fn dispatch(&self, f: impl FnOnce()) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2, checked just above.
            return unsafe { avx2(f) };
        }
        f()
    }
}

/// Runs `f` (inlined) compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn avx2(f: impl FnOnce()) {
    f()
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
}

fn separable(c: &mut Criterion) {
    let model = make_model(
        ModelKind::BetterDipole,
        &Medium::preset("skin1").expect("skin1"),
    );
    let k2 = Kernel2d::from_model(model.as_ref(), &Kernel2dSpec::default()).expect("kernel");
    let pre7 = preintegrated::kernel(&k2, TapPlacement::Importance(7)).expect("pre-integrated");
    let fits = gaussians::fit_model(model.as_ref(), 6).expect("gaussians");
    let gauss6: SeparableKernel = fits[5]
        .kernel(k2.total, TapPlacement::Importance(7))
        .expect("6 gaussians");
    let opts = FilterOptions::default();

    let frame = Frame::new(1920, 1080);
    let n = frame.width * frame.height;
    let mut out = vec![[0.0f32; 3]; n];
    let mut scratch = Vec::new();
    let mut aux = vec![(0.0f32, 0u32, 0.0f32); n];
    let (one, two) = (pool(1), pool(2));

    let mut g = c.benchmark_group("separable/1080p");
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("copy", |b| {
        b.iter(|| copy(black_box(&frame), &mut out, &mut aux))
    });
    let plain = PlainBlur::new(&pre7, 0.5);
    let mut tmp = vec![[0.0f32; 3]; n];
    // The floor computes what it claims: a few pixels against the clamped sums written out.
    plain.run(&frame, &mut tmp, &mut out);
    let (w, h) = (frame.width, frame.height);
    let first = frame.irradiance.as_flattened();
    for (x, y) in [(0, 0), (5, 700), (960, 540), (1919, 1079), (1000, 3)] {
        let mut want = [0.0f64; 3];
        for (&oy, wy) in plain.offsets.iter().zip(&plain.weights) {
            let yy = (y as isize + oy).clamp(0, h as isize - 1) as usize;
            let row = plain.clamped(first, x as isize, 3 * w * yy, 3, w);
            for c in 0..3 {
                want[c] += wy[c] as f64 * row[c] as f64;
            }
        }
        for c in 0..3 {
            let got = out[y * w + x][c] as f64;
            assert!(
                (got - want[c]).abs() <= 1e-5 * want[c].abs().max(1e-3),
                "plain blur ({x},{y})"
            );
        }
    }
    for (name, threads) in [
        ("plain-blur-7taps/1-thread", &one),
        ("plain-blur-7taps/2-threads", &two),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| threads.install(|| plain.run(black_box(&frame), &mut tmp, &mut out)))
        });
    }
    g.bench_function("pre-integrated-7taps-per-pixel/2-threads", |b| {
        b.iter(|| {
            two.install(|| {
                screen_space::filter_into_with(
                    black_box(&frame.input()),
                    &pre7,
                    &opts,
                    &mut scratch,
                    &mut out,
                    screen_space::Evaluation::PerPixel,
                )
                .expect("filter")
            })
        })
    });
    for (name, kernel, threads) in [
        ("pre-integrated-7taps/1-thread", &pre7, &one),
        ("pre-integrated-7taps/2-threads", &pre7, &two),
        ("6-gaussians-7taps/1-thread", &gauss6, &one),
        ("6-gaussians-7taps/2-threads", &gauss6, &two),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                threads.install(|| {
                    screen_space::filter_into(
                        black_box(&frame.input()),
                        kernel,
                        &opts,
                        &mut scratch,
                        &mut out,
                    )
                    .expect("filter")
                })
            })
        });
    }
    g.finish();

    // The exact 2D convolution on a crop, with a coarse kernel grid.
    let crop = Frame::new(256, 256);
    let k31 = Kernel2d::from_model(
        model.as_ref(),
        &Kernel2dSpec {
            cells: 31,
            ..Default::default()
        },
    )
    .expect("kernel 31");
    let m = crop.width * crop.height;
    let mut out_crop = vec![[0.0f32; 3]; m];
    let mut g = c.benchmark_group("separable/256x256");
    g.throughput(Throughput::Elements(m as u64));
    g.bench_function("pre-integrated-7taps/2-threads", |b| {
        b.iter(|| {
            two.install(|| {
                screen_space::filter_into(&crop.input(), &pre7, &opts, &mut scratch, &mut out_crop)
                    .expect("filter")
            })
        })
    });
    g.bench_function("exact-2d-31x31/2-threads", |b| {
        b.iter(|| two.install(|| convolve2d::exact(&crop.input(), &k31, &opts).expect("exact")))
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .nresamples(2000);
    targets = separable
}
criterion_main!(benches);
