//! Camera rays of the 1080p G-buffer: the Stanford bunny scene (`bunny`, 3674 triangles on
//! a two-triangle ground, about half the pixels sky) at 1920 × 1080, one sample per pixel.
//!
//! - `gbuffer/build`: [`GBuffer::new`] on all threads (ray casting plus the flat sample
//!   array), pixels per second.
//! - `gbuffer/closest_hit`: the same camera rays through [`SceneGeometry::closest_hit`] on one
//!   thread, nothing stored: rays per second per core.
//!
//! The mesh is not in the repository: it is looked up in `SSS_MESH_DIR`, then in `shared/meshes`
//! next to the workspace; without it the benchmark prints a message and measures nothing.
//! `cargo bench -p sss-bench --bench gbuffer -- --noplot`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use sss_render::camera::CameraFrame;
use sss_render::gbuffer::GBuffer;
use sss_render::geometry::SceneGeometry;
use sss_render::scene::{LoadOptions, Scene, SceneErrorKind, builtin};
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The bunny scene at 1920 × 1080, or `None` (with a message) when its mesh is missing.
fn bunny_1080p() -> Option<Scene> {
    let mut mesh_dirs: Vec<PathBuf> = std::env::var_os("SSS_MESH_DIR")
        .map(|d| std::env::split_paths(&d).collect())
        .unwrap_or_default();
    mesh_dirs.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/meshes"));
    match builtin("bunny", &LoadOptions { mesh_dirs }) {
        Ok(mut s) => {
            s.camera.width = 1920;
            s.camera.height = 1080;
            Some(s)
        }
        Err(e) if e.kind == SceneErrorKind::MeshNotFound => {
            println!("skipping the gbuffer benchmark: {e}");
            None
        }
        Err(e) => panic!("{e}"),
    }
}

fn gbuffer(c: &mut Criterion) {
    let Some(scene) = bunny_1080p() else {
        return;
    };
    let geom = SceneGeometry::new(&scene);
    let cam = &scene.camera;
    let pixels = cam.width as u64 * cam.height as u64;

    let mut g = c.benchmark_group("gbuffer");
    g.throughput(Throughput::Elements(pixels));
    g.bench_function("build", |b| {
        b.iter(|| GBuffer::new(black_box(&scene), &geom, 1))
    });

    let frame = CameraFrame::new(cam);
    let dirs: Vec<_> = (0..cam.height)
        .flat_map(|y| (0..cam.width).map(move |x| (x, y)))
        .map(|(x, y)| frame.direction(x as f64 + 0.5, y as f64 + 0.5))
        .collect();
    g.bench_function("closest_hit", |b| {
        b.iter(|| {
            let mut hits = 0u32;
            for &d in &dirs {
                hits += u32::from(
                    geom.closest_hit(frame.origin(), black_box(d), 0.0, f64::INFINITY)
                        .is_some(),
                );
            }
            hits
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(4))
        .nresamples(2000);
    targets = gbuffer
}
criterion_main!(benches);
