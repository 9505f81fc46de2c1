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

    /// One row: `out[x] = Σ_t w_t · row(x + o_t)`, where `row(k)` is
    /// `src[base + k·stride .. +3]` (clamped to the line's `len` pixels).
    fn line(&self, src: &[f32], out: &mut [f32], base: usize, stride: usize, len: usize) {
        let w = out.len() / 3;
        let reach = self
            .offsets
            .iter()
            .map(|o| o.unsigned_abs())
            .max()
            .unwrap_or(0);
        let at = |x: isize, c: usize| {
            let k = x.clamp(0, len as isize - 1) as usize;
            src[base + k * stride + c]
        };
        let px = |x: usize, out: &mut [f32]| {
            for c in 0..3 {
                out[3 * x + c] = self
                    .offsets
                    .iter()
                    .zip(&self.weights)
                    .map(|(&o, wt)| wt[c] * at(x as isize + o, c))
                    .sum();
            }
        };
        // Borders pixel by pixel with the clamp; the interior in vectorisable blocks.
        let (lo, hi) = (reach.min(w), w.saturating_sub(reach).max(reach.min(w)));
        for x in (0..lo).chain(hi..w) {
            px(x, out);
        }
        let mut x = lo;
        while x + BLOCK <= hi {
            let o = &mut out[3 * x..3 * (x + BLOCK)];
            o.fill(0.0);
            for (&off, lanes) in self.offsets.iter().zip(&self.lanes) {
                let s0 = base + ((x as isize + off) as usize) * stride;
                let s = &src[s0..s0 + 3 * BLOCK];
                for i in 0..3 * BLOCK {
                    o[i] += lanes[i] * s[i];
                }
            }
            x += BLOCK;
        }
        for x in x..hi {
            px(x, out);
        }
    }

    /// Horizontal pass into `tmp`, vertical pass into `out` (both row-major RGB).
    fn run(&self, f: &Frame, tmp: &mut [[f32; 3]], out: &mut [[f32; 3]]) {
        let (w, h) = (f.width, f.height);
        let src = f.irradiance.as_flattened();
        tmp.as_flattened_mut()
            .par_chunks_mut(3 * w)
            .enumerate()
            .for_each(|(y, row)| self.line(src, row, 3 * w * y, 3, w));
        let tmp = tmp.as_flattened();
        // The vertical pass: the same blocks over the rows above and below (stride = a row).
        let reach = self
            .offsets
            .iter()
            .map(|o| o.unsigned_abs())
            .max()
            .unwrap_or(0);
        out.as_flattened_mut()
            .par_chunks_mut(3 * w)
            .enumerate()
            .for_each(|(y, row)| {
                if y < reach || y + reach >= h {
                    for x in 0..w {
                        for c in 0..3 {
                            row[3 * x + c] = self
                                .offsets
                                .iter()
                                .zip(&self.weights)
                                .map(|(&o, wt)| {
                                    let yy = (y as isize + o).clamp(0, h as isize - 1) as usize;
                                    wt[c] * tmp[3 * (yy * w + x) + c]
                                })
                                .sum();
                        }
                    }
                    return;
                }
                row.fill(0.0);
                for ((&off, wt), lanes) in self.offsets.iter().zip(&self.weights).zip(&self.lanes) {
                    let r0 = 3 * w * (y as isize + off) as usize;
                    let s = &tmp[r0..r0 + 3 * w];
                    let mut blocks = row.chunks_exact_mut(3 * BLOCK);
                    let mut sources = s.chunks_exact(3 * BLOCK);
                    for (o, s) in (&mut blocks).zip(&mut sources) {
                        for i in 0..3 * BLOCK {
                            o[i] += lanes[i] * s[i];
                        }
                    }
                    let rest = blocks.into_remainder();
                    for (i, (o, s)) in rest.iter_mut().zip(sources.remainder()).enumerate() {
                        *o += wt[i % 3] * s;
                    }
                }
            });
    }
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
