//! Cost of the separable subsurface-scattering pass (Jimenez et al. 2015) on a GPU: the
//! exported WGSL shader run through wgpu (`sss-gpu`) on a 1920 × 1080 frame, to set beside
//! the paper's 0.489 ms per 1080p frame. The adapter's name is printed with every time (on a
//! machine without a GPU, wgpu finds Mesa's software rasteriser, llvmpipe, whose time says
//! nothing about a GPU); without an adapter the benchmark prints why and measures nothing.
//!
//! Frames: the two frames of `benches/separable.rs` (one skin1 object filling the screen, a
//! pore-like irradiance texture; `1080p` at a constant 0.5 mm per pixel with a gentle depth
//! ramp, `1080p-tilted` with a footprint growing from 0.3 to 0.75 mm per pixel across it), no
//! jitter (the GPU pass has none). Kernels: pre-integrated with 7 importance-sampled taps per
//! pass (the paper's), and six Gaussians with 7 taps per pass each (12 passes). Timed: one
//! submission of every pass and the wait for it (`GpuFilter::run`), the inputs already on the
//! GPU, so the time includes the submission's overhead (tens of µs) but no upload or readback.
//! The CPU filter with the same options runs next to it for the ratio; before timing, the
//! GPU's output is checked against it.
//!
//! `cargo bench -p sss-bench --bench gpu -- --noplot`; `WGPU_BACKEND=vulkan|gl` picks a backend.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use sss_bench::Frame;
use sss_bssrdf::{Medium, ModelKind, make_model};
use sss_gpu::{Gpu, GpuFilter};
use sss_separable::screen_space::{self, FilterOptions};
use sss_separable::{
    Kernel2d, Kernel2dSpec, SeparableKernel, TapPlacement, gaussians, preintegrated,
};
use std::time::{Duration, Instant};

/// The largest |gpu − cpu| relative to the frame's largest value.
fn largest_difference(cpu: &[[f32; 3]], gpu: &[[f32; 3]]) -> f32 {
    let peak = cpu.iter().flatten().fold(0.0f32, |m, v| m.max(v.abs()));
    let diff = cpu
        .iter()
        .flatten()
        .zip(gpu.iter().flatten())
        .fold(0.0f32, |m, (a, b)| m.max((a - b).abs()));
    diff / peak
}

fn gpu(c: &mut Criterion) {
    let gpu = match Gpu::new() {
        Ok(g) => g,
        Err(e) => {
            eprintln!("gpu benchmark skipped: {e}");
            return;
        }
    };
    let adapter = gpu.adapter_name();
    eprintln!("adapter: {adapter}");
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
    let opts = FilterOptions {
        jitter_radius: 0.0,
        ..FilterOptions::default()
    };
    let frames = [
        ("1080p", Frame::new(1920, 1080)),
        ("1080p-tilted", Frame::tilted(1920, 1080)),
    ];
    let kernels = [("preintegrated-7", &pre7), ("gaussians6-7", &gauss6)];
    let mut summary = Vec::new();
    for (frame_name, frame) in &frames {
        let input = frame.input();
        let n = frame.width * frame.height;
        let mut g = c.benchmark_group(format!("gpu/{frame_name}"));
        g.throughput(Throughput::Elements(n as u64));
        for (kernel_name, kernel) in kernels {
            let filter = GpuFilter::new(&gpu, kernel, &opts).expect("compile the pass");
            let uploaded = filter.upload(&input).expect("upload");
            filter.run(&uploaded).expect("run");
            // The GPU computes what the CPU filter does (rounding apart).
            let cpu = screen_space::filter(&input, kernel, &opts).expect("cpu filter");
            let diff = largest_difference(&cpu, &filter.read(&uploaded).expect("read"));
            assert!(
                diff < 1e-4,
                "{frame_name} {kernel_name}: GPU differs by {diff}"
            );
            g.bench_function(format!("{kernel_name} [{adapter}]"), |b| {
                b.iter(|| filter.run(&uploaded).expect("run"))
            });
            g.bench_function(format!("{kernel_name} [cpu, no jitter]"), |b| {
                let mut out = vec![[0.0f32; 3]; n];
                let mut scratch = screen_space::FilterScratch::default();
                b.iter(|| screen_space::filter_into(&input, kernel, &opts, &mut scratch, &mut out))
            });
            // The fastest of 20 runs (or of those that fit in 3 s, at least 3), for the
            // summary line.
            let start = Instant::now();
            let mut runs = Vec::new();
            while runs.len() < 20 && (runs.len() < 3 || start.elapsed().as_secs_f64() < 3.0) {
                let t = Instant::now();
                filter.run(&uploaded).expect("run");
                runs.push(t.elapsed());
            }
            let best = runs.iter().min().copied().unwrap_or_default();
            summary.push(format!(
                "{frame_name} {kernel_name}: {:.3} ms per frame (fastest of {}), \
                 largest difference from the CPU {diff:.1e}",
                best.as_secs_f64() * 1e3,
                runs.len()
            ));
        }
        g.finish();
    }
    eprintln!("GPU pass on {adapter} (Jimenez et al. 2015 report 0.489 ms per 1080p frame):");
    for line in summary {
        eprintln!("  {line}");
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .nresamples(2000);
    targets = gpu
}
criterion_main!(benches);
