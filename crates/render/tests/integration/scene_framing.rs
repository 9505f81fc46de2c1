//! Camera framing of the built-in scenes, checked with the test rasteriser: every translucent
//! object is whole and inside the image over a few thousand pixels, the toad's board stays out
//! of view and the backlit scene's quad light hides behind its disc.

use crate::common::rasterizer::{project, rasterize, write_preview};
use sss_render::scene::{BUILTIN_SCENES, Light, LoadOptions, SceneErrorKind, builtin};
use std::path::{Path, PathBuf};

/// Where the shared test meshes live when the workspace sits next to `shared/`.
fn shared_meshes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/meshes")
}

/// Every built-in scene shows its translucent objects whole, inside the image, over a few
/// thousand pixels (affordable for a brute-force reference). Set `SSS_SCENE_PREVIEW_DIR` to
/// also write flat-shaded previews.
#[test]
fn builtin_scene_framing() {
    let opts = LoadOptions {
        mesh_dirs: vec![shared_meshes()],
    };
    let preview = std::env::var_os("SSS_SCENE_PREVIEW_DIR").map(PathBuf::from);
    for (name, _) in BUILTIN_SCENES {
        let s = match builtin(name, &opts) {
            Ok(s) => s,
            Err(e) if e.kind == SceneErrorKind::MeshNotFound => {
                println!("skipping the framing of {name}: {e}");
                continue;
            }
            Err(e) => panic!("{e}"),
        };
        let frame = rasterize(&s);
        let translucent_px = frame
            .ids
            .iter()
            .filter(|id| id.is_some_and(|i| s.translucent(i).is_some()))
            .count();
        println!("{name}: {translucent_px} translucent pixels");
        assert!(
            (1500..=12000).contains(&translucent_px),
            "{name}: {translucent_px} translucent pixels"
        );
        for (i, o) in s.objects.iter().enumerate() {
            if s.translucent(i).is_none() {
                continue;
            }
            for &p in &o.mesh.positions {
                let (x, y, z) = project(&s.camera, p);
                assert!(z > 0.0, "{name}/{}: behind the camera", o.name);
                assert!(
                    (0.0..=s.camera.width as f64).contains(&x)
                        && (0.0..=s.camera.height as f64).contains(&y),
                    "{name}/{}: {p} projects outside the image at ({x:.1}, {y:.1})",
                    o.name
                );
            }
            let visible = frame.ids.iter().filter(|id| **id == Some(i)).count();
            assert!(visible >= 100, "{name}/{}: {visible} pixels", o.name);
        }
        if let Some(dir) = &preview {
            write_preview(&s, &frame, dir);
        }
        match *name {
            // The thin occluder stays above the image.
            "toad" => {
                let board = s.objects.iter().position(|o| o.name == "board").unwrap();
                assert!(!frame.ids.contains(&Some(board)), "the board is visible");
            }
            // The quad light hides behind the disc: every pixel whose ray passes the quad
            // sees the disc first.
            "backlit" => {
                let Light::Quad {
                    corner,
                    edge_u,
                    edge_v,
                    ..
                } = s.lights[0]
                else {
                    panic!("backlit: not a quad light");
                };
                let w = s.camera.width as usize;
                let quad = [
                    corner,
                    corner + edge_u,
                    corner + edge_u + edge_v,
                    corner + edge_v,
                ]
                .map(|p| project(&s.camera, p));
                let (xs, ys): (Vec<f64>, Vec<f64>) = quad.iter().map(|q| (q.0, q.1)).unzip();
                let x0 = xs.iter().cloned().fold(f64::INFINITY, f64::min) as usize;
                let x1 = xs.iter().cloned().fold(0.0, f64::max).ceil() as usize;
                let y0 = ys.iter().cloned().fold(f64::INFINITY, f64::min) as usize;
                let y1 = ys.iter().cloned().fold(0.0, f64::max).ceil() as usize;
                for y in y0..y1 {
                    for x in x0..x1 {
                        assert_eq!(frame.ids[y * w + x], Some(0), "light visible at ({x}, {y})");
                    }
                }
            }
            _ => {}
        }
    }
}
