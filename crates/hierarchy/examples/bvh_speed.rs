//! Measures TriangleBvh build time and single-thread ray throughput.
//!
//! `cargo run --release -p sss-hierarchy --example bvh_speed [mesh.obj]`
//!
//! Without an argument a 327,680-triangle icosphere is used. Times are wall-clock on one
//! thread, best of 3, so they are pessimistic on a loaded machine.

use std::time::Instant;

use glam::DVec3;
use rand::RngExt;
use sss_hierarchy::{TriangleBvh, blue_noise_on_mesh};

#[path = "../tests/integration/common/mod.rs"]
mod common;

fn best_of<T>(mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..3 {
        let t = Instant::now();
        let r = f();
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(r);
    }
    (best, out.unwrap())
}

fn main() {
    let tris = match std::env::args().nth(1) {
        Some(path) => common::load_obj(&path),
        None => common::icosphere(7, DVec3::ZERO, 1.0),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        let (dt, bvh) = best_of(|| TriangleBvh::new(&tris));
        let (lo, hi) = bvh.bounds().unwrap();
        let size = (hi - lo).length();
        println!("{} triangles, build {:.1} ms", tris.len(), dt * 1e3);

        let mut g = common::rng(1);
        let n = 200_000;
        // Surface points with normals (for rays leaving the surface).
        let (pts, _) = blue_noise_on_mesh(&tris, 0.0, 20_000, 1);
        let surf: Vec<(DVec3, DVec3)> = pts
            .iter()
            .map(|s| {
                let t = tris[s.triangle as usize];
                (s.position, (t[1] - t[0]).cross(t[2] - t[0]).normalize())
            })
            .collect();
        let centre = (lo + hi) / 2.0;
        let outside: Vec<(DVec3, DVec3)> = (0..n)
            .map(|_| {
                let o = centre + common::random_dir(&mut g) * size;
                let target = centre + common::random_in_cube(&mut g, 0.3 * size);
                (o, target - o)
            })
            .collect();
        let from_surface: Vec<(DVec3, DVec3)> = (0..n)
            .map(|_| {
                let (p, nrm) = surf[g.random_range(0..surf.len())];
                let mut d = common::random_dir(&mut g);
                if d.dot(nrm) < 0.0 {
                    d = -d;
                }
                (p, d)
            })
            .collect();
        let eps = 1e-7 * size;
        let run = |name: &str, rays: &[(DVec3, DVec3)], t_max: f64, occl: bool| {
            let (dt, hits) = best_of(|| {
                rays.iter()
                    .filter(|(o, d)| {
                        if occl {
                            bvh.occluded(*o, *d, eps, t_max)
                        } else {
                            bvh.closest_hit(*o, *d, eps, t_max).is_some()
                        }
                    })
                    .count()
            });
            println!(
                "{name:>40}: {:.2} Mrays/s ({:.0}% hit)",
                rays.len() as f64 / dt / 1e6,
                100.0 * hits as f64 / rays.len() as f64
            );
        };
        run("from outside, closest hit", &outside, f64::INFINITY, false);
        run("from outside, occluded", &outside, f64::INFINITY, true);
        run(
            "from surface, outward, closest hit",
            &from_surface,
            f64::INFINITY,
            false,
        );
        run(
            "from surface, outward, occluded",
            &from_surface,
            f64::INFINITY,
            true,
        );
        run(
            "from surface, short (0.05 size), closest",
            &from_surface,
            0.05 * size,
            false,
        );
    });
}
