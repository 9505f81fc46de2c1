//! HDR-FLIP (`sss_render::flip::hdr_flip`) of a render against a noisier one: the built-in
//! `sphere` scene, `exact` against `pathtrace` at 4 samples, at 80 × 60 (the size of
//! `cargo xtask compare --quick`'s scenes), 320 × 240 and 640 × 480, on all threads. Pixels
//! per second; the cost grows with the exposures the reference's range asks for (printed).
//! `cargo bench -p sss-bench --bench flip -- --noplot`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use sss_render::flip::{FlipParams, hdr_flip};
use sss_render::integrators::{self, MethodOptions};
use sss_render::progress::NoProgress;
use sss_render::scene::{LoadOptions, builtin};
use sss_render::{RenderSettings, render};
use std::hint::black_box;
use std::time::Duration;

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("flip");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5));
    for (w, h) in [(80u32, 60u32), (320, 240), (640, 480)] {
        let mut scene = builtin("sphere", &LoadOptions::default()).unwrap();
        scene.camera.width = w;
        scene.camera.height = h;
        let draw = |name: &str, options: MethodOptions| {
            let m = integrators::build(name, &options).unwrap();
            render(&scene, m.as_ref(), &RenderSettings::default(), &NoProgress)
                .unwrap()
                .subsurface
        };
        let reference = draw("exact", MethodOptions::new());
        let test = draw("pathtrace", MethodOptions::new().with("spp", 4));
        let (w, h) = (w as usize, h as usize);
        let once = hdr_flip(&reference, &test, w, h, &FlipParams::default());
        println!(
            "flip {w}x{h}: mean {:.4}, {} exposures from {:.2} to {:.2} stops",
            once.mean, once.count, once.exposures.0, once.exposures.1
        );
        group.throughput(Throughput::Elements((w * h) as u64));
        group.bench_function(format!("hdr_{w}x{h}"), |b| {
            b.iter(|| black_box(hdr_flip(&reference, &test, w, h, &FlipParams::default())))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
