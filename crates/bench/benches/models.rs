//! Throughput of every BSSRDF model: profile evaluations (one channel and RGB) and radius
//! samples per second, for two measured materials (skin1 and marble).
//!
//! Groups are named `<preset>/<operation>` and benchmarks by model, e.g.
//! `skin1/rd/pbd`; criterion reports elements (calls) per second. Settings are short
//! (10 samples, 1 s) so the whole run takes about a minute:
//! `cargo bench -p sss-bench -- --noplot`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use sss_bssrdf::{Medium, ModelKind, make_model};
use std::hint::black_box;
use std::time::Duration;

/// Inputs per iteration.
const N: usize = 256;

fn models(c: &mut Criterion) {
    let radii = sss_bench::radii(N);
    let us = sss_bench::uniforms(N, 7);
    for preset in ["skin1", "marble"] {
        let medium = Medium::preset(preset).expect("preset");
        let built: Vec<_> = ModelKind::ALL
            .into_iter()
            .map(|k| (k, make_model(k, &medium)))
            .collect();

        let mut g = c.benchmark_group(format!("{preset}/rd"));
        g.throughput(Throughput::Elements(N as u64));
        for (kind, model) in &built {
            g.bench_function(kind.name(), |b| {
                b.iter(|| {
                    let mut acc = 0.0;
                    for &r in &radii {
                        acc += model.rd(0, black_box(r));
                    }
                    acc
                })
            });
        }
        g.finish();

        let mut g = c.benchmark_group(format!("{preset}/rd_rgb"));
        g.throughput(Throughput::Elements(N as u64));
        for (kind, model) in &built {
            g.bench_function(kind.name(), |b| {
                b.iter(|| {
                    let mut acc = 0.0;
                    for &r in &radii {
                        let v = model.rd_rgb(black_box(r));
                        acc += v[0] + v[1] + v[2];
                    }
                    acc
                })
            });
        }
        g.finish();

        let mut g = c.benchmark_group(format!("{preset}/sample_sr"));
        g.throughput(Throughput::Elements(N as u64));
        for (kind, model) in &built {
            g.bench_function(kind.name(), |b| {
                b.iter(|| {
                    let mut acc = 0.0;
                    for &u in &us {
                        acc += model.sample_sr(0, black_box(u));
                    }
                    acc
                })
            });
        }
        g.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1))
        .nresamples(2000);
    targets = models
}
criterion_main!(benches);
