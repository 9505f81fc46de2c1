//! Model throughput per CPU second: the `models` bench's inputs and loops, timed with the
//! thread's own CPU time (`/proc/thread-self/schedstat`, Linux) instead of wall time, so the
//! figures stay meaningful on a machine shared with other jobs (wall time on a loaded machine
//! counts the time the thread waited for a core). Falls back to wall time elsewhere.
//!
//! `cargo run --release -p sss-bench --example models_per_core`

use sss_bssrdf::{Medium, ModelKind, make_model};
use std::hint::black_box;
use std::time::Instant;

/// Nanoseconds this thread has run on a CPU, if the kernel reports it.
fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

/// Calls of `f` (each doing `per_call` operations) per second of CPU time, over ≈ 0.3 s.
fn rate(per_call: usize, mut f: impl FnMut() -> f64) -> f64 {
    let mut calls = 0u64;
    let wall = Instant::now();
    let cpu0 = thread_cpu_ns();
    let mut acc = 0.0;
    loop {
        for _ in 0..64 {
            acc += f();
        }
        calls += 64;
        let elapsed = match (cpu0, thread_cpu_ns()) {
            (Some(a), Some(b)) => (b - a) as f64 * 1e-9,
            _ => wall.elapsed().as_secs_f64(),
        };
        if elapsed > 0.3 {
            black_box(acc);
            return calls as f64 * per_call as f64 / elapsed;
        }
    }
}

fn main() {
    let n = 256;
    let radii = sss_bench::radii(n);
    let us = sss_bench::uniforms(n, 7);
    println!("M calls per CPU second (one thread); rd and sample_sr of channel 0");
    println!(
        "{:<8} {:<20} {:>8} {:>10}",
        "preset", "model", "rd", "sample_sr"
    );
    for preset in ["skin1", "marble"] {
        let medium = Medium::preset(preset).expect("preset");
        for kind in ModelKind::ALL {
            let model = make_model(kind, &medium);
            // Models built per CPU second, after the first build (PBD's shared table of the
            // medium's (g, η) is cached by then).
            let builds = rate(1, || make_model(kind, black_box(&medium)).rd(0, 1.0));
            let rd = rate(n, || radii.iter().map(|&r| model.rd(0, black_box(r))).sum());
            let sample = rate(n, || {
                us.iter().map(|&u| model.sample_sr(0, black_box(u))).sum()
            });
            println!(
                "{:<8} {:<20} {:>8.1} {:>10.1} {:>10.1}",
                preset,
                kind.name(),
                rd * 1e-6,
                sample * 1e-6,
                1e6 / builds
            );
        }
    }
}
