//! The built-in scenes: they load, match the files in `scenes/`, use the documented materials,
//! lights and scales, have the documented shadow edges, and the bunny scene either loads from
//! `../shared/meshes` or reports its missing mesh.

use crate::common::{bbox, check_mesh, no_dirs, volume};
use glam::DVec3;
use sss_scene::{
    BUILTIN_SCENES, Light, LoadOptions, Scene, SceneErrorKind, Texture, builtin, load,
};
use std::path::{Path, PathBuf};

/// Where the shared test meshes live when the workspace sits next to `shared/`.
fn shared_meshes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/meshes")
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

#[test]
fn builtin_scenes_load() {
    let names: Vec<&str> = BUILTIN_SCENES.iter().map(|(n, _)| *n).collect();
    assert_eq!(
        names,
        ["sphere", "toad", "picnic", "backlit", "slab", "bunny"]
    );
    for name in names.iter().filter(|n| **n != "bunny") {
        let s = builtin(name, &no_dirs()).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(s.name, *name);
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
        assert!(!s.lights.is_empty() && !s.objects.is_empty());
        for o in &s.objects {
            check_mesh(&o.mesh);
        }
        let translucent = (0..s.objects.len())
            .filter(|&i| s.translucent(i).is_some())
            .count();
        assert!(translucent >= 1, "{name} has no translucent object");
        assert_eq!((s.camera.width, s.camera.height), (160, 120), "{name}");
        assert_eq!(s.camera.pixel_samples, 1, "{name}");
        // Every material kept is used.
        for (mi, _) in s.materials.iter().enumerate() {
            assert!(s.objects.iter().any(|o| o.material == mi), "{name}");
        }
    }
    let e = builtin("teapot", &no_dirs()).unwrap_err();
    for n in names {
        assert!(e.message.contains(n), "{e}");
    }
    assert!(e.message.contains("teapot"));
}

#[test]
fn builtin_scenes_match_the_files() {
    for (name, text) in BUILTIN_SCENES {
        let path = scenes_dir().join(format!("{name}.toml"));
        let on_disk = std::fs::read_to_string(&path).expect("scene file");
        assert_eq!(on_disk, *text, "{name}");
    }
    let s = load(&scenes_dir().join("sphere.toml"), &no_dirs()).unwrap();
    assert_eq!(s.name, "sphere");
    assert!(
        s.path
            .as_deref()
            .is_some_and(|p| p.ends_with("sphere.toml"))
    );
}

#[test]
fn builtin_scene_materials() {
    let model = |s: &Scene, obj: &str| {
        let i = s.objects.iter().position(|o| o.name == obj).unwrap();
        let t = s.translucent(i).unwrap();
        (t.model.name(), t.units_per_mm)
    };
    let s = builtin("sphere", &no_dirs()).unwrap();
    assert_eq!(model(&s, "sphere"), ("better-dipole", 0.05));
    assert!(matches!(s.lights.as_slice(), [Light::Point { .. }]));
    let s = builtin("toad", &no_dirs()).unwrap();
    assert_eq!(model(&s, "toad").0, "directional-dipole");
    let i = s.objects.iter().position(|o| o.name == "toad").unwrap();
    assert!(matches!(
        s.translucent(i).unwrap().texture,
        Some(Texture::Noise { .. })
    ));
    assert!(matches!(s.lights.as_slice(), [Light::Directional { .. }]));
    let s = builtin("picnic", &no_dirs()).unwrap();
    let models: std::collections::HashSet<&str> = (0..s.objects.len())
        .filter_map(|i| s.translucent(i).map(|t| t.model.name()))
        .collect();
    assert_eq!(models.len(), 4, "picnic uses all four models");
    assert_eq!(
        (0..s.objects.len())
            .filter(|&i| s.translucent(i).is_some())
            .count(),
        5
    );
    assert!(s.lights.iter().any(|l| matches!(l, Light::Point { .. })));
    assert!(
        s.lights
            .iter()
            .any(|l| matches!(l, Light::Environment { .. }))
    );
    let s = builtin("backlit", &no_dirs()).unwrap();
    assert!(matches!(s.lights.as_slice(), [Light::Quad { .. }]));
}

/// Each translucent material's reduced mean free path, in scene units, is 1–5 % of its
/// object's size (bounding-box diagonal over √3, roughly its width).
#[test]
fn builtin_scene_scales() {
    for (name, _) in BUILTIN_SCENES.iter().filter(|(n, _)| *n != "bunny") {
        let s = builtin(name, &no_dirs()).unwrap();
        for (i, o) in s.objects.iter().enumerate() {
            let Some(t) = s.translucent(i) else { continue };
            let mfp = (0..3)
                .map(|ch| t.medium.reduced_mean_free_path(ch))
                .fold(0.0, f64::max)
                * t.units_per_mm;
            let (lo, hi) = bbox(&o.mesh);
            let size = (hi - lo).max_element();
            let ratio = mfp / size;
            println!(
                "{name}/{}: mean free path {mfp:.4} units, {:.1} % of {size:.3}",
                o.name,
                100.0 * ratio
            );
            assert!(
                (0.01..=0.05).contains(&ratio),
                "{name}/{}: mean free path {mfp:.4} is {:.1} % of size {size:.3}",
                o.name,
                100.0 * ratio
            );
        }
    }
}

#[test]
fn bunny_scene_loads_or_reports_missing_mesh() {
    // Without mesh directories the mesh cannot be found, whatever the machine.
    let e = builtin("bunny", &no_dirs()).unwrap_err();
    assert_eq!(e.kind, SceneErrorKind::MeshNotFound, "{e}");
    assert!(e.message.contains("stanford-bunny-small.obj"), "{e}");
    assert_eq!(e.key.as_deref(), Some("objects[1].file"));
    assert_eq!(e.file, "scenes/bunny.toml");

    let dir = shared_meshes();
    let opts = LoadOptions {
        mesh_dirs: vec![PathBuf::from("/nonexistent/sss-meshes"), dir.clone()],
    };
    if !dir.join("stanford-bunny-small.obj").exists() {
        println!(
            "skipping the bunny mesh checks: {} not found",
            dir.join("stanford-bunny-small.obj").display()
        );
        let e = builtin("bunny", &opts).unwrap_err();
        assert_eq!(e.kind, SceneErrorKind::MeshNotFound, "{e}");
        assert!(e.message.contains("/nonexistent/sss-meshes"), "{e}");
        return;
    }
    let s = builtin("bunny", &opts).unwrap_or_else(|e| panic!("{e}"));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let bunny = s.objects.iter().find(|o| o.name == "bunny").unwrap();
    check_mesh(&bunny.mesh);
    assert_eq!(bunny.mesh.triangles.len(), 3674);
    assert_eq!(bunny.mesh.positions.len(), 1839);
    let (lo, hi) = bbox(&bunny.mesh);
    assert!((hi.y - lo.y - 9.658).abs() < 0.01, "height {}", hi.y - lo.y);
    assert!(lo.y >= 0.0 && lo.y < 1e-3, "bunny base at {}", lo.y);
    // Closed and outward: positive volume, normals pointing away from the interior on
    // average.
    assert!(volume(&bunny.mesh) > 0.0);
    let t = s.translucent(s.objects.iter().position(|o| o.name == "bunny").unwrap());
    assert_eq!(t.unwrap().model.name(), "pbd");
    let mfp = 1.0 / t.unwrap().medium.sigma_t_reduced(0) * t.unwrap().units_per_mm;
    let ratio = mfp / (hi - lo).max_element();
    assert!((0.01..=0.05).contains(&ratio), "{ratio}");
}

/// Whether the ray `o + t·d`, t > 0, hits the axis-aligned box [lo, hi] (slab test).
fn ray_hits_box(o: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> bool {
    let (mut t0, mut t1) = (1e-9f64, f64::INFINITY);
    for k in 0..3 {
        if d[k].abs() < 1e-15 {
            if o[k] < lo[k] || o[k] > hi[k] {
                return false;
            }
            continue;
        }
        let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    t0 <= t1
}

/// The documented shadow edges: in `toad`, the board shadows the blob's lit side exactly for
/// x < 0.15; in `slab`, the wall shadows the slab's top exactly for x < 0.1.
#[test]
fn builtin_shadow_edges() {
    let s = builtin("toad", &no_dirs()).unwrap();
    let Light::Directional { direction, .. } = s.lights[0] else {
        panic!("toad: not a directional light")
    };
    let board = &s.objects.iter().find(|o| o.name == "board").unwrap().mesh;
    let (lo, hi) = bbox(board);
    let toad = &s.objects.iter().find(|o| o.name == "toad").unwrap().mesh;
    let (mut shadowed, mut lit) = (0, 0);
    for (p, n) in toad.positions.iter().zip(&toad.normals) {
        if n.dot(-direction) <= 0.0 || (p.x - 0.15).abs() < 1e-3 {
            continue;
        }
        let blocked = ray_hits_box(*p, -direction, lo, hi);
        assert_eq!(blocked, p.x < 0.15, "toad vertex {p}");
        if blocked {
            shadowed += 1;
        } else {
            lit += 1;
        }
    }
    assert!(
        shadowed > 1000 && lit > 1000,
        "{shadowed} shadowed, {lit} lit"
    );

    let s = builtin("slab", &no_dirs()).unwrap();
    let Light::Directional { direction, .. } = s.lights[0] else {
        panic!("slab: not a directional light")
    };
    let wall = &s.objects.iter().find(|o| o.name == "wall").unwrap().mesh;
    let (lo, hi) = bbox(wall);
    let slab = &s.objects.iter().find(|o| o.name == "slab").unwrap().mesh;
    let (slo, shi) = bbox(slab);
    for i in 0..=40 {
        for j in 0..=20 {
            let x = slo.x + (shi.x - slo.x) * (i as f64 + 0.5) / 41.0;
            let z = slo.z + (shi.z - slo.z) * (j as f64 + 0.5) / 21.0;
            if (x - 0.1).abs() < 1e-6 {
                continue;
            }
            let p = DVec3::new(x, shi.y, z);
            assert_eq!(ray_hits_box(p, -direction, lo, hi), x < 0.1, "slab top {p}");
        }
    }
}

/// `load_named`, as `sss render SCENE` and Python's `load_file` take a scene: a built-in name
/// when no such file exists, else the file; a name that is neither lists the built-in scenes;
/// a missing mesh names the caller's hint and `SSS_MESH_DIR`.
#[test]
fn scenes_by_name_or_file_with_the_callers_hint() {
    let s = sss_scene::load_named("slab", &[], "HINT").unwrap();
    assert_eq!(s.name, "slab");
    let file = scenes_dir().join("slab.toml");
    let from_file = sss_scene::load_named(file.to_str().unwrap(), &[], "HINT").unwrap();
    assert_eq!(from_file.path.as_deref(), Some(file.as_path()));
    assert!(s.path.is_none());

    let e = sss_scene::load_named("no-such-scene", &[], "HINT").unwrap_err();
    assert_eq!(e.kind, SceneErrorKind::Io);
    let names: Vec<&str> = BUILTIN_SCENES.iter().map(|(n, _)| *n).collect();
    assert!(
        e.message.ends_with(&format!(
            "nor is it a built-in scene ({})",
            names.join(", ")
        )),
        "{e}"
    );
    assert!(!e.message.contains("HINT"), "{e}");

    let dir = std::env::temp_dir().join(format!("sss-load-named-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A path that exists but cannot be read as a file (a directory): an I/O error that names
    // the file, with no list of built-in scenes (the user named a file, not a scene).
    let e = sss_scene::load_named(dir.to_str().unwrap(), &[], "HINT").unwrap_err();
    assert_eq!(e.kind, SceneErrorKind::Io, "{e}");
    assert!(!e.message.contains("built-in scene"), "{e}");
    let scene = dir.join("s.toml");
    std::fs::write(
        &scene,
        "[camera]\nposition = [0, 0, 4]\ntarget = [0, 0, 0]\nfov = 30\nresolution = [8, 8]\n\
         [[lights]]\ntype = \"point\"\nposition = [0, 4, 4]\nintensity = 1\n\
         [materials.m]\ntype = \"diffuse\"\nalbedo = [0.5, 0.5, 0.5]\n\
         [[objects]]\nmaterial = \"m\"\nshape = \"mesh\"\nfile = \"missing.obj\"\n",
    )
    .unwrap();
    let e =
        sss_scene::load_named(scene.to_str().unwrap(), &[dir.join("extra")], "HINT").unwrap_err();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(e.kind, SceneErrorKind::MeshNotFound, "{e}");
    assert!(
        e.message
            .ends_with("; add a mesh directory with HINT or the SSS_MESH_DIR environment variable"),
        "{e}"
    );
    // The caller's directories come before the environment's.
    let opts = LoadOptions::with_dirs(&[PathBuf::from("first")]);
    assert_eq!(opts.mesh_dirs[0], PathBuf::from("first"));
}
