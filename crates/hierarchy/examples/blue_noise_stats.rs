//! Prints blue-noise statistics (count relative to A/r², area spread, time) for a sphere
//! and a plane, and optionally for an OBJ mesh given as the first argument.
//!
//! `cargo run --release -p sss-hierarchy --example blue_noise_stats [mesh.obj]`

use std::time::Instant;

use glam::DVec3;
use sss_hierarchy::blue_noise_on_mesh;

#[path = "../tests/integration/common/mod.rs"]
mod common;

fn report(name: &str, tris: &[[DVec3; 3]], radius: f64, max_count: usize) {
    let start = Instant::now();
    let (s, st) = blue_noise_on_mesh(tris, radius, max_count, 1);
    let dt = start.elapsed().as_secs_f64();
    let n = s.len() as f64;
    let mean = st.surface_area / n;
    let var = s.iter().map(|x| (x.area - mean).powi(2)).sum::<f64>() / n;
    let (mn, mx) = s.iter().fold((f64::INFINITY, 0f64), |(a, b), x| {
        (a.min(x.area), b.max(x.area))
    });
    println!(
        "{name:>10}: r={:.5} (asked {radius}) N={} N*r^2/A={:.4} cv={:.4} min/mean={:.3} max/mean={:.3} candidates/N={:.1} {:.3}s",
        st.radius,
        s.len(),
        n * st.radius * st.radius / st.surface_area,
        var.sqrt() / mean,
        mn / mean,
        mx / mean,
        st.candidates as f64 / n,
        dt
    );
}

fn main() {
    let sphere = common::icosphere(5, DVec3::ZERO, 1.0);
    for r in [0.2, 0.1, 0.05, 0.02] {
        report("sphere", &sphere, r, usize::MAX);
    }
    report("sphere cap", &sphere, 0.0, 2000);
    report("sphere cap", &sphere, 0.001, 20000);
    let plane = common::plane(2, 1.0, 0.0);
    for r in [0.1, 0.05, 0.02, 0.01] {
        report("plane", &plane, r, usize::MAX);
    }
    report("plane cap", &plane, 0.0, 2000);
    if let Some(path) = std::env::args().nth(1) {
        let tris = common::load_obj(&path);
        let (lo, hi) = tris.iter().flatten().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(a, b), p| (a.min(*p), b.max(*p)),
        );
        println!("mesh: {} triangles, bounds {lo} {hi}", tris.len());
        for n in [1000, 10_000, 100_000] {
            report("mesh cap", &tris, 0.0, n);
        }
    }
}
