//! Scene loading: the built-in scenes (they load, and their cameras frame them), procedural
//! shapes against closed forms, transforms, OBJ meshes, every validation error, and textures.

use glam::DVec3;
use sss_render::scene::{
    BUILTIN_SCENES, Camera, Light, LoadOptions, MaterialKind, Mesh, Scene, SceneError,
    SceneErrorKind, Texture, builtin, load, load_str,
};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

// ---------------------------------------------------------------------------------------------
// Helpers

fn no_dirs() -> LoadOptions {
    LoadOptions::default()
}

/// Where the shared test meshes live when the workspace sits next to `shared/`.
fn shared_meshes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/meshes")
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

/// A camera, a light and a diffuse material `m`; objects are appended.
const HEAD: &str = r#"[camera]
position = [0.0, 0.0, 10.0]
target = [0.0, 0.0, 0.0]
fov = 40.0
resolution = [16, 12]

[[lights]]
type = "point"
position = [0.0, 5.0, 5.0]
intensity = 1.0

[materials.m]
type = "diffuse"
albedo = 0.5
"#;

/// The world-space mesh of a scene made of [`HEAD`] and one object with `body` (the lines
/// after `[[objects]]`, without `material`).
fn mesh_of(body: &str) -> Mesh {
    let text = format!("{HEAD}\n[[objects]]\nmaterial = \"m\"\n{body}\n");
    let scene = load_str(&text, "shape.toml", None, &no_dirs())
        .unwrap_or_else(|e| panic!("{e}\n--- scene ---\n{text}"));
    assert!(
        scene.warnings.is_empty(),
        "unexpected warnings: {:?}",
        scene.warnings
    );
    assert_eq!(scene.objects.len(), 1);
    let mesh = scene.objects[0].mesh.clone();
    check_mesh(&mesh);
    mesh
}

/// The invariants every loaded mesh must satisfy.
fn check_mesh(m: &Mesh) {
    assert!(!m.triangles.is_empty());
    assert_eq!(m.positions.len(), m.normals.len());
    let mut used = vec![false; m.positions.len()];
    for t in &m.triangles {
        for &i in t {
            assert!((i as usize) < m.positions.len());
            used[i as usize] = true;
        }
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        assert!(
            (b - a).cross(c - a).length() > 0.0,
            "degenerate triangle {t:?}"
        );
    }
    assert!(used.iter().all(|&u| u), "unused vertices");
    for (p, n) in m.positions.iter().zip(&m.normals) {
        assert!(p.is_finite());
        assert!((n.length() - 1.0).abs() < 1e-9, "normal {n} is not unit");
    }
}

fn area(m: &Mesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// Enclosed volume by the divergence theorem: Σ a·(b × c) / 6.
fn volume(m: &Mesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            a.dot(b.cross(c))
        })
        .sum::<f64>()
        / 6.0
}

/// Area-weighted centroid of the surface.
fn centroid(m: &Mesh) -> DVec3 {
    let mut sum = DVec3::ZERO;
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        sum += (a + b + c) / 3.0 * 0.5 * (b - a).cross(c - a).length();
    }
    sum / area(m)
}

fn max_edge(m: &Mesh) -> f64 {
    m.triangles
        .iter()
        .flat_map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            [a.distance(b), b.distance(c), c.distance(a)]
        })
        .fold(0.0, f64::max)
}

fn bbox(m: &Mesh) -> (DVec3, DVec3) {
    m.positions
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        })
}

/// The 1-based line of the first line of `text` containing `needle`; `needle#n` means the
/// n-th such line.
fn line_of(text: &str, needle: &str) -> usize {
    let (needle, nth) = match needle.rsplit_once('#') {
        Some((n, k)) if k.parse::<usize>().is_ok() => (n, k.parse::<usize>().unwrap()),
        _ => (needle, 1),
    };
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.contains(needle))
        .nth(nth - 1)
        .unwrap_or_else(|| panic!("`{needle}` #{nth} not in the text"))
        .0
        + 1
}

fn load_err(text: &str) -> SceneError {
    match load_str(text, "bad.toml", None, &no_dirs()) {
        Ok(_) => panic!("expected an error for\n{text}"),
        Err(e) => e,
    }
}

/// Asserts an `Invalid` error in `bad.toml` at the line containing `line_needle` (if given),
/// whose key contains `key` (if given) and whose message contains every `words` item.
fn assert_err(text: &str, line_needle: Option<&str>, key: Option<&str>, words: &[&str]) {
    let e = load_err(text);
    println!("{e}");
    assert_eq!(e.kind, SceneErrorKind::Invalid, "{e}");
    assert_eq!(e.file, "bad.toml", "{e}");
    if let Some(n) = line_needle {
        assert_eq!(e.line, Some(line_of(text, n)), "wrong line in: {e}");
    }
    if let Some(k) = key {
        let got = e.key.as_deref().unwrap_or_else(|| panic!("no key in: {e}"));
        assert!(got.contains(k), "key `{got}` does not contain `{k}`: {e}");
    }
    let shown = e.to_string();
    for w in words {
        assert!(
            shown.to_lowercase().contains(&w.to_lowercase()),
            "`{w}` not in: {shown}"
        );
    }
}

/// A fresh, empty directory under the system temporary directory.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sss-scene-tests-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// A scene (in `dir`) with one mesh object naming `file`.
fn mesh_scene(file: &str) -> String {
    format!("{HEAD}\n[[objects]]\nmaterial = \"m\"\nshape = \"mesh\"\nfile = \"{file}\"\n")
}

/// Loads `scene.toml` written to `dir` with `text`.
fn load_in(dir: &Path, text: &str, opts: &LoadOptions) -> Result<Scene, SceneError> {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).expect("write scene");
    load(&path, opts)
}

const TETRA: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

// ---------------------------------------------------------------------------------------------
// Built-in scenes

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

// ---------------------------------------------------------------------------------------------
// Camera framing: a z-buffer rasteriser over the meshes (pixel centres, like the renderer's
// one sample per pixel).

struct Frame {
    /// Object index seen at each pixel (row-major), if any.
    ids: Vec<Option<usize>>,
    /// Face normal seen at each pixel.
    normals: Vec<DVec3>,
}

/// Projects `p` to continuous pixel coordinates (x right, y down) and its depth along the
/// view direction.
fn project(cam: &Camera, p: DVec3) -> (f64, f64, f64) {
    let f = (cam.target - cam.position).normalize();
    let r = f.cross(cam.up).normalize();
    let u = r.cross(f);
    let d = p - cam.position;
    let z = d.dot(f);
    let th = (cam.vfov_deg.to_radians() / 2.0).tan();
    let aspect = cam.width as f64 / cam.height as f64;
    let nx = d.dot(r) / (z * th * aspect);
    let ny = d.dot(u) / (z * th);
    (
        (nx + 1.0) / 2.0 * cam.width as f64,
        (1.0 - ny) / 2.0 * cam.height as f64,
        z,
    )
}

fn rasterize(s: &Scene) -> Frame {
    let cam = &s.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let mut inv_depth = vec![0.0f64; w * h];
    let mut ids = vec![None; w * h];
    let mut normals = vec![DVec3::ZERO; w * h];
    for (oi, o) in s.objects.iter().enumerate() {
        let proj: Vec<(f64, f64, f64)> =
            o.mesh.positions.iter().map(|&p| project(cam, p)).collect();
        for t in &o.mesh.triangles {
            let [a, b, c] = t.map(|i| proj[i as usize]);
            if a.2 <= 1e-6 || b.2 <= 1e-6 || c.2 <= 1e-6 {
                continue;
            }
            let [pa, pb, pc] = t.map(|i| o.mesh.positions[i as usize]);
            let n = (pb - pa).cross(pc - pa).normalize();
            let area = (b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1);
            if area.abs() < 1e-12 {
                continue;
            }
            let x0 = a.0.min(b.0).min(c.0).floor().max(0.0) as usize;
            let x1 = (a.0.max(b.0).max(c.0).ceil().max(0.0) as usize).min(w);
            let y0 = a.1.min(b.1).min(c.1).floor().max(0.0) as usize;
            let y1 = (a.1.max(b.1).max(c.1).ceil().max(0.0) as usize).min(h);
            for y in y0..y1 {
                for x in x0..x1 {
                    let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                    let e = |p: (f64, f64, f64), q: (f64, f64, f64)| {
                        ((q.0 - p.0) * (py - p.1) - (px - p.0) * (q.1 - p.1)) / area
                    };
                    let (wa, wb, wc) = (e(b, c), e(c, a), e(a, b));
                    if wa < 0.0 || wb < 0.0 || wc < 0.0 {
                        continue;
                    }
                    let iz = wa / a.2 + wb / b.2 + wc / c.2;
                    let k = y * w + x;
                    if iz > inv_depth[k] {
                        inv_depth[k] = iz;
                        ids[k] = Some(oi);
                        normals[k] = n;
                    }
                }
            }
        }
    }
    Frame { ids, normals }
}

/// Writes a flat-shaded preview PNG of the frame (for looking at the framing by eye).
fn write_preview(s: &Scene, frame: &Frame, dir: &Path) {
    let (w, h) = (s.camera.width, s.camera.height);
    let towards_light = match s.lights.first() {
        Some(Light::Directional { direction, .. }) => -*direction,
        Some(Light::Point { position, .. }) => (*position - s.camera.target).normalize(),
        Some(Light::Quad {
            corner,
            edge_u,
            edge_v,
            ..
        }) => (*corner + 0.5 * (*edge_u + *edge_v) - s.camera.target).normalize(),
        _ => DVec3::Y,
    };
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    for (id, n) in frame.ids.iter().zip(&frame.normals) {
        let c = match id {
            None => [0u8; 3],
            Some(i) => {
                let base = if s.translucent(*i).is_some() {
                    [230.0, 170.0, 140.0]
                } else {
                    [150.0, 150.0, 170.0]
                };
                let k = 0.25 + 0.75 * n.dot(towards_light).max(0.0);
                base.map(|v: f64| (v * k) as u8)
            }
        };
        rgb.extend_from_slice(&c);
    }
    let file = std::fs::File::create(dir.join(format!("{}.png", s.name))).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header().unwrap().write_image_data(&rgb).unwrap();
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

// ---------------------------------------------------------------------------------------------
// Shapes

#[test]
fn sphere_area_volume_and_normals() {
    let r = 1.7;
    let mut last_err = f64::INFINITY;
    for n in 1..=5 {
        let m = mesh_of(&format!(
            "shape = \"sphere\"\nradius = {r}\nsubdivisions = {n}"
        ));
        assert_eq!(m.triangles.len(), 20 * 4usize.pow(n));
        // An inscribed polyhedron whose triangles have sides ≤ h stays outside the ball of
        // radius √(r² − h²/3) (the farthest a triangle's nearest point can be from its
        // vertices), so its area and volume are bracketed.
        let h = max_edge(&m);
        let k = 1.0 - h * h / (3.0 * r * r);
        let (a, v) = (area(&m), volume(&m));
        let (a_exact, v_exact) = (4.0 * PI * r * r, 4.0 / 3.0 * PI * r.powi(3));
        assert!(
            a <= a_exact && a >= a_exact * k,
            "n={n}: area {a} vs {a_exact}"
        );
        assert!(
            v <= v_exact && v >= v_exact * k.powf(1.5),
            "n={n}: volume {v} vs {v_exact}"
        );
        let err = (a_exact - a) / a_exact;
        assert!(err < last_err, "area error must fall with subdivision");
        last_err = err;
        for (p, nrm) in m.positions.iter().zip(&m.normals) {
            assert!((p.length() - r).abs() < 1e-12);
            assert!(nrm.dot(*p) > 0.0);
            assert!((*nrm - *p / r).length() < 1e-12, "exact radial normals");
        }
    }
    assert!(last_err < 2e-3, "{last_err}");
}

#[test]
fn box_plane_torus_closed_forms() {
    let m = mesh_of("shape = \"box\"\nsize = [1.0, 2.0, 3.0]");
    assert_eq!(m.triangles.len(), 12);
    assert_eq!(m.positions.len(), 24);
    assert!((area(&m) - 2.0 * (2.0 + 6.0 + 3.0)).abs() < 1e-12);
    assert!((volume(&m) - 6.0).abs() < 1e-12);
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let face = (b - a).cross(c - a).normalize();
        for &i in t {
            assert!(
                (m.normals[i as usize] - face).length() < 1e-12,
                "flat normals"
            );
        }
        assert!(face.dot((a + b + c) / 3.0) > 0.0, "outward");
    }

    let m = mesh_of("shape = \"plane\"\nsize = [4.0, 2.5]");
    assert_eq!(m.triangles.len(), 2);
    assert!((area(&m) - 10.0).abs() < 1e-12);
    let m = mesh_of("shape = \"plane\"\nsize = [4.0, 2.5]\nsubdivisions = 3");
    assert_eq!(m.triangles.len(), 18);
    assert!((area(&m) - 10.0).abs() < 1e-12);
    let (lo, hi) = bbox(&m);
    assert!((lo - DVec3::new(-2.0, 0.0, -1.25)).length() < 1e-12);
    assert!((hi - DVec3::new(2.0, 0.0, 1.25)).length() < 1e-12);
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        assert!((b - a).cross(c - a).normalize().dot(DVec3::Y) > 1.0 - 1e-12);
    }
    assert!(m.normals.iter().all(|n| *n == DVec3::Y));

    let (big_r, small_r) = (1.0, 0.3);
    let mut last = f64::INFINITY;
    for seg in [16, 32, 64, 128] {
        let m = mesh_of(&format!(
            "shape = \"torus\"\nmajor = {big_r}\nminor = {small_r}\nsegments = [{seg}, {}]",
            seg / 2
        ));
        let a_exact = 4.0 * PI * PI * big_r * small_r;
        let v_exact = 2.0 * PI * PI * big_r * small_r * small_r;
        let (ea, ev) = (
            (area(&m) - a_exact).abs() / a_exact,
            (volume(&m) - v_exact).abs() / v_exact,
        );
        assert!(ea < last, "torus area error must fall");
        last = ea;
        if seg >= 64 {
            assert!(ea < 0.01 && ev < 0.01, "seg {seg}: {ea} {ev}");
        }
        assert!(volume(&m) > 0.0);
        for (p, n) in m.positions.iter().zip(&m.normals) {
            let ring = DVec3::new(p.x, 0.0, p.z).normalize() * big_r;
            assert!(n.dot(*p - ring) > 0.0, "outward torus normal");
        }
    }
    // Default segments and a single number.
    mesh_of("shape = \"torus\"\nmajor = 1.0\nminor = 0.3");
    let m = mesh_of("shape = \"torus\"\nmajor = 1.0\nminor = 0.3\nsegments = 12");
    assert_eq!(m.triangles.len(), 2 * 12 * 12);
}

#[test]
fn bumpy_sphere_is_displaced_smoothly_and_deterministically() {
    let body = |seed: u64| {
        format!(
            "shape = \"bumpy-sphere\"\nradius = 2.0\namplitude = 0.2\nfrequency = 3.0\n\
             seed = {seed}\nsubdivisions = 4"
        )
    };
    let m = mesh_of(&body(7));
    assert_eq!(m.triangles.len(), 20 * 256);
    let radii: Vec<f64> = m.positions.iter().map(|p| p.length()).collect();
    assert!(radii.iter().all(|&r| (1.8..=2.2).contains(&r)));
    let spread = radii.iter().cloned().fold(0.0, f64::max)
        - radii.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(spread > 0.1, "the surface is displaced ({spread})");
    assert!(volume(&m) > 0.0);
    for (p, n) in m.positions.iter().zip(&m.normals) {
        assert!(n.dot(*p) > 0.0, "outward");
    }
    // Normals come from the displaced geometry, not the sphere.
    let tilted = m
        .positions
        .iter()
        .zip(&m.normals)
        .filter(|(p, n)| n.dot(p.normalize()) < 0.99)
        .count();
    assert!(tilted > 100, "{tilted}");
    // Smooth (Lipschitz): each partial derivative of the value noise is at most
    // max fade' = 15/8 per lattice unit, so along an edge whose unit directions are a chord c
    // apart the radius changes by at most 2·amplitude·(15/8)·√3·frequency·c.
    let lipschitz = 2.0 * 0.2 * 1.875 * 3f64.sqrt() * 3.0;
    let mut steepest: f64 = 0.0;
    for t in &m.triangles {
        for k in 0..3 {
            let (i, j) = (t[k] as usize, t[(k + 1) % 3] as usize);
            let chord = (m.positions[i] / radii[i]).distance(m.positions[j] / radii[j]);
            let slope = (radii[i] - radii[j]).abs() / chord;
            assert!(slope <= lipschitz + 1e-9, "slope {slope}");
            steepest = steepest.max(slope);
        }
    }
    assert!(steepest > 0.05 * lipschitz, "{steepest}");
    assert_eq!(m, mesh_of(&body(7)));
    assert_ne!(m.positions, mesh_of(&body(8)).positions);
}

#[test]
fn transforms() {
    let base = mesh_of("shape = \"sphere\"\nradius = 1.0\nsubdivisions = 3");
    let scaled =
        mesh_of("shape = \"sphere\"\nradius = 1.0\nsubdivisions = 3\ntransform = { scale = 2.5 }");
    assert!((area(&scaled) / area(&base) - 6.25).abs() < 1e-12);
    assert!((volume(&scaled) / volume(&base) - 2.5f64.powi(3)).abs() < 1e-12);

    let moved = mesh_of(
        "shape = \"box\"\nsize = [1.0, 2.0, 3.0]\ntransform = { translate = [1.0, -2.0, 3.5] }",
    );
    assert!((centroid(&moved) - DVec3::new(1.0, -2.0, 3.5)).length() < 1e-12);
    assert!((area(&moved) - 22.0).abs() < 1e-12);

    // Non-uniform scale of a box: closed-form area.
    let m =
        mesh_of("shape = \"box\"\nsize = [1.0, 1.0, 1.0]\ntransform = { scale = [1.0, 2.0, 3.0] }");
    assert!((area(&m) - 22.0).abs() < 1e-12);

    // Rotation order: X first, then Y, then Z. A 1×2×3 box turned 90° about X becomes
    // 1×3×2, then 90° about Y becomes 2×3×1 (Y first would give 3×1×2).
    let m = mesh_of(
        "shape = \"box\"\nsize = [1.0, 2.0, 3.0]\ntransform = { rotate = [90.0, 90.0, 0.0] }",
    );
    let (lo, hi) = bbox(&m);
    assert!(
        (hi - lo - DVec3::new(2.0, 3.0, 1.0)).length() < 1e-9,
        "{}",
        hi - lo
    );
    let m = mesh_of(
        "shape = \"box\"\nsize = [1.0, 2.0, 3.0]\ntransform = { rotate = [0.0, 0.0, 90.0] }",
    );
    let (lo, hi) = bbox(&m);
    assert!((hi - lo - DVec3::new(2.0, 1.0, 3.0)).length() < 1e-9);
    // Scale before rotation: scale x by 3, then turn about Z: the long side ends up along y.
    let m = mesh_of(
        "shape = \"box\"\nsize = [1.0, 1.0, 1.0]\n\
         transform = { scale = [3.0, 1.0, 1.0], rotate = [0.0, 0.0, 90.0], translate = [0.0, 5.0, 0.0] }",
    );
    let (lo, hi) = bbox(&m);
    assert!((hi - lo - DVec3::new(1.0, 3.0, 1.0)).length() < 1e-9);
    assert!((centroid(&m) - DVec3::new(0.0, 5.0, 0.0)).length() < 1e-9);

    // Normals under a non-uniform scale: the ellipsoid's gradient direction (x/a², y/b², z/c²).
    let (a, b, c) = (1.0, 1.3, 0.06);
    let m = mesh_of(&format!(
        "shape = \"sphere\"\nradius = 1.0\nsubdivisions = 3\ntransform = {{ scale = [{a}, {b}, {c}] }}"
    ));
    for (p, n) in m.positions.iter().zip(&m.normals) {
        let g = DVec3::new(p.x / (a * a), p.y / (b * b), p.z / (c * c)).normalize();
        assert!((*n - g).length() < 1e-9, "{n} vs {g}");
    }

    // A mirroring scale keeps the surface facing outwards.
    let m = mesh_of(
        "shape = \"sphere\"\nradius = 1.0\nsubdivisions = 2\ntransform = { scale = [-1.0, 1.0, 1.0] }",
    );
    assert!(volume(&m) > 0.0);
    for (p, n) in m.positions.iter().zip(&m.normals) {
        assert!(n.dot(*p) > 0.0);
    }
}

// ---------------------------------------------------------------------------------------------
// OBJ meshes

#[test]
fn obj_meshes_load() {
    let dir = temp_dir("obj-load");
    std::fs::write(dir.join("tetra.obj"), TETRA).unwrap();
    let s = load_in(&dir, &mesh_scene("tetra.obj"), &no_dirs()).unwrap();
    let m = &s.objects[0].mesh;
    check_mesh(m);
    assert_eq!(m.triangles.len(), 4);
    assert!((volume(m) - 1.0 / 6.0).abs() < 1e-7);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // Area-weighted smooth normals: the origin vertex's normal is -(1,1,1)/√3 by symmetry.
    let origin = m.positions.iter().position(|p| *p == DVec3::ZERO).unwrap();
    assert!((m.normals[origin] + DVec3::ONE.normalize()).length() < 1e-7);

    // A unit cube of quads is fanned into 12 triangles.
    let cube = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
                f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    std::fs::write(dir.join("cube.obj"), cube).unwrap();
    let s = load_in(&dir, &mesh_scene("cube.obj"), &no_dirs()).unwrap();
    let m = &s.objects[0].mesh;
    check_mesh(m);
    assert_eq!(m.triangles.len(), 12);
    assert!((volume(m) - 1.0).abs() < 1e-7);
    assert!((area(m) - 6.0).abs() < 1e-7);

    // Normals from `vn` are used as given (normalised).
    let with_vn = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 2\nf 1//1 2//1 3//1\n";
    std::fs::write(dir.join("vn.obj"), with_vn).unwrap();
    let s = load_in(&dir, &mesh_scene("vn.obj"), &no_dirs()).unwrap();
    assert!(s.objects[0].mesh.normals.iter().all(|n| *n == DVec3::Z));

    // Faces without normals among ones with: the `vn` are ignored, normals computed.
    let mixed = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 1 0 0\nf 1//1 2//1 3//1\nf 2 4 3\n";
    std::fs::write(dir.join("mixed.obj"), mixed).unwrap();
    let s = load_in(&dir, &mesh_scene("mixed.obj"), &no_dirs()).unwrap();
    assert_eq!(s.objects[0].mesh.positions.len(), 4);
    assert!(
        s.objects[0]
            .mesh
            .normals
            .iter()
            .all(|n| (*n - DVec3::Z).length() < 1e-12)
    );

    // Found in the second mesh directory when not next to the scene.
    let other = temp_dir("obj-load-dirs");
    std::fs::write(other.join("elsewhere.obj"), TETRA).unwrap();
    let opts = LoadOptions {
        mesh_dirs: vec![dir.join("missing-subdir"), other.clone()],
    };
    let s = load_in(&dir, &mesh_scene("elsewhere.obj"), &opts).unwrap();
    assert_eq!(s.objects[0].mesh.triangles.len(), 4);
    // An inside-out closed mesh is turned around, with a warning.
    let inverted = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 4 2\nf 1 3 4\nf 2 4 3\n";
    std::fs::write(dir.join("inverted.obj"), inverted).unwrap();
    let s = load_in(&dir, &mesh_scene("inverted.obj"), &no_dirs()).unwrap();
    assert!(volume(&s.objects[0].mesh) > 0.0);
    assert_eq!(s.warnings.len(), 1);
    assert!(s.warnings[0].contains("inverted.obj") && s.warnings[0].contains("reversed"));
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&other);
}

#[test]
fn obj_degenerate_triangles_are_dropped_and_counted() {
    let dir = temp_dir("obj-degenerate");
    // The tetrahedron, a triangle repeating a vertex, and a collinear (zero-area) one.
    let text = format!("{TETRA}v 2 0 0\nf 1 1 2\nf 1 2 5\n");
    std::fs::write(dir.join("degen.obj"), text).unwrap();
    let s = load_in(&dir, &mesh_scene("degen.obj"), &no_dirs()).unwrap();
    let m = &s.objects[0].mesh;
    check_mesh(m);
    assert_eq!(m.triangles.len(), 4);
    assert_eq!(m.positions.len(), 4, "the unused vertex is removed");
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert!(s.warnings[0].contains("degen.obj"), "{}", s.warnings[0]);
    assert!(
        s.warnings[0].contains("dropped 2 degenerate"),
        "{}",
        s.warnings[0]
    );

    // Nothing left: an error naming the mesh file.
    std::fs::write(dir.join("flat.obj"), "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap();
    let e = load_in(&dir, &mesh_scene("flat.obj"), &no_dirs()).unwrap_err();
    assert_eq!(e.kind, SceneErrorKind::Invalid);
    assert!(e.file.ends_with("flat.obj"), "{e}");
    assert!(
        e.message.contains("no triangles left after dropping 1"),
        "{e}"
    );
    std::fs::write(dir.join("points.obj"), "v 0 0 0\nv 1 0 0\n").unwrap();
    let e = load_in(&dir, &mesh_scene("points.obj"), &no_dirs()).unwrap_err();
    assert!(
        e.file.ends_with("points.obj") && e.message.contains("no triangles"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn obj_errors_name_the_file_and_line() {
    let dir = temp_dir("obj-errors");
    let cases: [(&str, &str, usize, &[&str]); 6] = [
        (
            "nan.obj",
            "v 0 0 0\nv 1 0 0\n# c\nv 0 nan 0\nf 1 2 3\n",
            4,
            &["nan", "not finite"],
        ),
        (
            "inf.obj",
            "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n",
            2,
            &["inf", "not finite"],
        ),
        (
            "huge.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1e40 0\nf 1 2 3\n",
            3,
            &["1e40", "not finite"],
        ),
        (
            "face.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n",
            4,
            &["malformed face index", "x"],
        ),
        (
            "range.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n",
            5,
            &["out of range", "9"],
        ),
        (
            "short.obj",
            "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n",
            2,
            &["2 coordinates"],
        ),
    ];
    for (file, text, line, words) in cases {
        std::fs::write(dir.join(file), text).unwrap();
        let e = load_in(&dir, &mesh_scene(file), &no_dirs()).unwrap_err();
        assert_eq!(e.kind, SceneErrorKind::Invalid, "{e}");
        assert!(e.file.ends_with(file), "{e}");
        assert_eq!(e.line, Some(line), "{e}");
        for w in words {
            assert!(e.to_string().contains(w), "`{w}` not in {e}");
        }
    }
    // An error only tobj finds (a malformed texture coordinate) still names the file.
    std::fs::write(
        dir.join("vt.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt a b\nf 1 2 3\n",
    )
    .unwrap();
    let e = load_in(&dir, &mesh_scene("vt.obj"), &no_dirs()).unwrap_err();
    assert!(
        e.file.ends_with("vt.obj") && e.message.contains("malformed OBJ"),
        "{e}"
    );

    // Missing: kind MeshNotFound, the scene's line and key, every directory searched.
    let opts = LoadOptions {
        mesh_dirs: vec![
            PathBuf::from("/nonexistent/a"),
            PathBuf::from("/nonexistent/b"),
        ],
    };
    let text = mesh_scene("nowhere.obj");
    let e = load_in(&dir, &text, &opts).unwrap_err();
    assert_eq!(e.kind, SceneErrorKind::MeshNotFound, "{e}");
    assert!(e.file.ends_with("scene.toml"));
    assert_eq!(e.line, Some(line_of(&text, "nowhere.obj")));
    assert_eq!(e.key.as_deref(), Some("objects[0].file"));
    for w in [
        "nowhere.obj",
        &dir.display().to_string(),
        "/nonexistent/a",
        "/nonexistent/b",
    ] {
        assert!(e.message.contains(w), "`{w}` not in {e}");
    }
    // Unreadable (a directory): kind Io, naming the path.
    std::fs::create_dir_all(dir.join("folder.obj")).unwrap();
    let e = load_in(&dir, &mesh_scene("folder.obj"), &no_dirs()).unwrap_err();
    assert_eq!(e.kind, SceneErrorKind::Io, "{e}");
    assert!(e.file.ends_with("folder.obj"), "{e}");
    // A missing scene file: kind Io.
    let e = load(&dir.join("no-such-scene.toml"), &no_dirs()).unwrap_err();
    assert_eq!(e.kind, SceneErrorKind::Io, "{e}");
    assert!(e.file.ends_with("no-such-scene.toml"));
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------------
// Validation errors

/// A complete valid scene with a translucent and a diffuse material, a textured one, and
/// objects; the error tests below each break one thing in it.
const GOOD: &str = r#"[camera]
position = [0.0, 1.0, 5.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov = 30.0
resolution = [160, 120]
pixel_samples = 1

[[lights]]
type = "point"
position = [3.0, 4.0, 4.0]
intensity = [10.0, 10.0, 10.0]

[[lights]]
type = "directional"
direction = [0.0, -1.0, 0.0]
irradiance = 1.0

[[lights]]
type = "quad"
corner = [-1.0, 3.0, -1.0]
edge_u = [0.0, 0.0, 2.0]
edge_v = [2.0, 0.0, 0.0]
radiance = 5.0

[[lights]]
type = "environment"
radiance = 0.1

[materials.skin]
type = "translucent"
model = "directional-dipole"
preset = "skin1"
units_per_mm = 0.05
texture = { type = "checker", scale = 0.1, a = 1.0, b = [0.5, 0.4, 0.3] }

[materials.jelly]
type = "translucent"
sigma_a = [0.01, 0.02, 0.03]
sigma_s = 2.0
g = 0.5
eta = 1.4
units_per_mm = 0.1

[materials.floor]
type = "diffuse"
albedo = [0.5, 0.5, 0.5]
texture = { type = "stripes", axis = [1.0, 0.0, 0.0], period = 0.5, a = 0.2, b = 0.9 }

[materials.spare]
type = "diffuse"
albedo = 0.3
texture = { type = "noise", scale = 0.2, seed = 4, a = 0.0, b = 1.0 }

[[objects]]
name = "ball"
material = "skin"
shape = "sphere"
radius = 1.0
transform = { translate = [0.0, 1.0, 0.0] }

[[objects]]
material = "jelly"
shape = "torus"
major = 1.0
minor = 0.25
transform = { scale = 0.5, rotate = [90.0, 0.0, 0.0], translate = [2.0, 1.0, 0.0] }

[[objects]]
name = "floor"
material = "floor"
shape = "plane"
size = [10.0, 10.0]

[[objects]]
name = "blob"
material = "skin"
shape = "bumpy-sphere"
radius = 0.5
amplitude = 0.05
frequency = 4.0
seed = 2
subdivisions = 3

[[objects]]
name = "crate"
material = "floor"
shape = "box"
size = [1.0, 0.5, 1.0]
"#;

/// `GOOD` with the first occurrence of `from` replaced by `to`.
fn with(from: &str, to: &str) -> String {
    assert!(GOOD.contains(from), "`{from}` not in GOOD");
    GOOD.replacen(from, to, 1)
}

#[test]
fn good_scene_loads() {
    let s = load_str(GOOD, "good.toml", None, &no_dirs()).unwrap();
    assert_eq!(s.name, "good");
    assert_eq!(s.lights.len(), 4);
    assert_eq!(s.objects.len(), 5);
    assert_eq!(s.objects[1].name, "object1");
    // Materials in order of first use; the unused one dropped with a warning.
    let names: Vec<&str> = s.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["skin", "jelly", "floor"]);
    assert_eq!(s.objects[3].material, 0);
    assert_eq!(s.objects[4].material, 2);
    assert_eq!(s.warnings.len(), 1);
    assert!(s.warnings[0].contains("good.toml") && s.warnings[0].contains("`spare`"));
    let MaterialKind::Translucent(t) = &s.materials[1].kind else {
        panic!("jelly is translucent")
    };
    assert_eq!(t.model.name(), "better-dipole", "the default model");
    assert_eq!(t.medium.sigma_a(), [0.01, 0.02, 0.03]);
    assert_eq!(t.medium.sigma_s(), [2.0; 3]);
    assert_eq!(
        (t.medium.g(), t.medium.eta(), t.units_per_mm),
        (0.5, 1.4, 0.1)
    );
    let MaterialKind::Translucent(t) = &s.materials[0].kind else {
        panic!("skin is translucent")
    };
    assert_eq!(t.medium.sigma_s(), [0.74, 0.88, 1.01]);
    assert_eq!(t.medium.eta(), 1.3);
    assert_eq!(
        t.texture,
        Some(Texture::Checker {
            scale: 0.1,
            a: [1.0; 3],
            b: [0.5, 0.4, 0.3]
        })
    );
    assert_eq!(
        s.lights[1],
        Light::Directional {
            direction: DVec3::NEG_Y,
            irradiance: [1.0; 3]
        }
    );
    assert_eq!(s.camera.vfov_deg, 30.0);
    // A preset with g keeps the measured reduced scattering.
    let s = load_str(
        &with("preset = \"skin1\"", "preset = \"skin1\"\ng = 0.8"),
        "good.toml",
        None,
        &no_dirs(),
    )
    .unwrap();
    let MaterialKind::Translucent(t) = &s.materials[0].kind else {
        panic!()
    };
    assert!((t.medium.sigma_s_reduced(0) - 0.74).abs() < 1e-12);
}

#[test]
fn toml_syntax_and_structure_errors() {
    // Syntax: the line from toml's span.
    assert_err(
        &with("[materials.jelly]", "[materials.jelly"),
        Some("[materials.jelly"),
        None,
        &[],
    );
    assert_err(
        &with("fov = 30.0", "fov = 30.0.0"),
        Some("fov = "),
        None,
        &[],
    );
    // Unknown keys, at their line.
    assert_err(
        &with("fov = 30.0", "fov = 30.0\nfocus = 2.0"),
        Some("focus"),
        Some("focus"),
        &["unknown field", "focus"],
    );
    assert_err(
        &with("irradiance = 1.0", "irradiance = 1.0\ncolour = 1.0"),
        Some("colour"),
        Some("colour"),
        &["unknown field"],
    );
    assert_err(
        &with(
            "translate = [0.0, 1.0, 0.0]",
            "translate = [0.0, 1.0, 0.0], spin = 2.0",
        ),
        Some("spin"),
        Some("spin"),
        &["unknown field", "spin"],
    );
    assert_err(
        &with("[camera]", "[camra]\nx = 1\n[camera]"),
        Some("[camra]"),
        Some("camra"),
        &["unknown field"],
    );
    // Wrong types and lengths: the key and its line.
    assert_err(
        &with("fov = 30.0", "fov = \"wide\""),
        Some("fov"),
        Some("camera.fov"),
        &["invalid type"],
    );
    assert_err(
        &with("position = [3.0, 4.0, 4.0]", "position = [3.0, 4.0]"),
        Some("position = [3.0, 4.0]"),
        Some("lights[0].position"),
        &["length 2"],
    );
    assert_err(
        &with("sigma_s = 2.0", "sigma_s = [1.0, 2.0]"),
        Some("sigma_s"),
        Some("materials.jelly.sigma_s"),
        &["3 numbers"],
    );
    assert_err(
        &with("resolution = [160, 120]", "resolution = [160, -120]"),
        Some("resolution"),
        Some("camera.resolution"),
        &["-120"],
    );
    // A missing table or key.
    assert_err(
        &GOOD.replacen("[camera]", "[lens]", 1),
        None,
        None,
        &["lens"],
    );
    assert_err(
        &with("fov = 30.0\n", ""),
        Some("[camera]"),
        Some("camera.fov"),
        &["missing field `fov`"],
    );
    assert_err(
        &with("shape = \"torus\"\n", ""),
        Some("[[objects]]#2"),
        Some("objects[1].shape"),
        &["missing field `shape`"],
    );
}

#[test]
fn camera_errors() {
    let fov_words = ["(0, 180)"];
    for bad in ["0.0", "180.0", "-5.0", "nan", "inf"] {
        assert_err(
            &with("fov = 30.0", &format!("fov = {bad}")),
            Some("fov"),
            Some("camera.fov"),
            &fov_words,
        );
    }
    assert_err(
        &with("resolution = [160, 120]", "resolution = [0, 120]"),
        Some("resolution"),
        Some("camera.resolution"),
        &["at least 1"],
    );
    assert_err(
        &with("pixel_samples = 1", "pixel_samples = 0"),
        Some("pixel_samples"),
        Some("camera.pixel_samples"),
        &["at least 1"],
    );
    assert_err(
        &with("target = [0.0, 0.0, 0.0]", "target = [0.0, 1.0, 5.0]"),
        Some("target"),
        Some("camera.target"),
        &["equals camera.position"],
    );
    assert_err(
        &with("up = [0.0, 1.0, 0.0]", "up = [0.0, -2.0, -10.0]"),
        Some("up ="),
        Some("camera.up"),
        &["parallel"],
    );
    assert_err(
        &with("up = [0.0, 1.0, 0.0]", "up = [0.0, 0.0, 0.0]"),
        Some("up ="),
        Some("camera.up"),
        &["non-zero"],
    );
    assert_err(
        &with("position = [0.0, 1.0, 5.0]", "position = [0.0, nan, 5.0]"),
        Some("position = [0.0, nan"),
        Some("camera.position"),
        &["finite"],
    );
}

#[test]
fn light_errors() {
    let no_lights = GOOD
        .split("\n\n")
        .filter(|block| !block.starts_with("[[lights]]"))
        .collect::<Vec<_>>()
        .join("\n\n");
    assert_err(&no_lights, None, None, &["no lights"]);
    assert_err(
        &with("type = \"point\"", "type = \"spot\""),
        Some("spot"),
        Some("lights[0].type"),
        &["unknown light type", "spot", "point", "environment"],
    );
    assert_err(
        &with(
            "intensity = [10.0, 10.0, 10.0]",
            "intensity = [10.0, -1.0, 10.0]",
        ),
        Some("intensity"),
        Some("lights[0].intensity"),
        &["non-negative", "-1"],
    );
    assert_err(
        &with("intensity = [10.0, 10.0, 10.0]", "intensity = nan"),
        Some("intensity"),
        Some("lights[0].intensity"),
        &["NaN"],
    );
    assert_err(
        &with("intensity = [10.0, 10.0, 10.0]", "radiance = 1.0"),
        Some("radiance = 1.0"),
        Some("lights[0].radiance"),
        &["does not apply to a point light"],
    );
    assert_err(
        &with("intensity = [10.0, 10.0, 10.0]\n", ""),
        Some("[[lights]]"),
        Some("lights[0].intensity"),
        &["needs `intensity`"],
    );
    assert_err(
        &with(
            "direction = [0.0, -1.0, 0.0]",
            "direction = [0.0, 0.0, 0.0]",
        ),
        Some("direction ="),
        Some("lights[1].direction"),
        &["non-zero"],
    );
    assert_err(
        &with("edge_v = [2.0, 0.0, 0.0]", "edge_v = [0.0, 0.0, -1.0]"),
        Some("edge_v"),
        Some("lights[2].edge_v"),
        &["parallel"],
    );
}

#[test]
fn material_errors() {
    assert_err(
        &with("model = \"directional-dipole\"", "model = \"quadpole\""),
        Some("quadpole"),
        Some("materials.skin.model"),
        &[
            "unknown model",
            "quadpole",
            "standard-dipole",
            "better-dipole",
            "directional-dipole",
            "pbd",
        ],
    );
    assert_err(
        &with("preset = \"skin1\"", "preset = \"skin3\""),
        Some("skin3"),
        Some("materials.skin.preset"),
        &["unknown preset", "skin3", "skin1", "marble", "ketchup"],
    );
    for (bad, word) in [("-0.5", "-0.5"), ("nan", "NaN"), ("inf", "inf")] {
        assert_err(
            &with(
                "sigma_a = [0.01, 0.02, 0.03]",
                &format!("sigma_a = [0.01, {bad}, 0.03]"),
            ),
            Some("sigma_a"),
            Some("materials.jelly.sigma_a"),
            &["non-negative", word, "channel 1"],
        );
    }
    assert_err(
        &with("sigma_s = 2.0", "sigma_s = -inf"),
        Some("sigma_s"),
        Some("materials.jelly.sigma_s"),
        &["non-negative"],
    );
    for bad in ["0.0", "-0.05", "nan"] {
        assert_err(
            &with("units_per_mm = 0.05", &format!("units_per_mm = {bad}")),
            Some("units_per_mm = "),
            Some("materials.skin.units_per_mm"),
            &["units per millimetre", "> 0"],
        );
    }
    assert_err(
        &with("units_per_mm = 0.05\n", ""),
        Some("[materials.skin]"),
        Some("materials.skin.units_per_mm"),
        &["needs `units_per_mm`"],
    );
    assert_err(
        &with("preset = \"skin1\"", "preset = \"skin1\"\nsigma_a = 1.0"),
        Some("sigma_a = 1.0"),
        Some("materials.skin.sigma_a"),
        &["either `preset`"],
    );
    assert_err(
        &with("sigma_s = 2.0\n", ""),
        Some("[materials.jelly]"),
        Some("materials.jelly.sigma_s"),
        &["needs `preset` or"],
    );
    assert_err(
        &with("g = 0.5", "g = 1.0"),
        Some("g = 1.0"),
        Some("materials.jelly.g"),
        &["(-1, 1)"],
    );
    assert_err(
        &with("eta = 1.4", "eta = 0.0"),
        Some("eta"),
        Some("materials.jelly.eta"),
        &["> 0"],
    );
    assert_err(
        &with(
            "sigma_a = [0.01, 0.02, 0.03]",
            "sigma_a = [0.0, 0.02, 0.03]",
        )
        .replacen("sigma_s = 2.0", "sigma_s = [0.0, 1.0, 1.0]", 1),
        Some("[materials.jelly]"),
        Some("materials.jelly"),
        &["invalid medium"],
    );
    assert_err(
        &with("type = \"translucent\"", "type = \"glass\""),
        Some("glass"),
        Some("materials.skin.type"),
        &["unknown material type", "glass"],
    );
    assert_err(
        &with("albedo = [0.5, 0.5, 0.5]", "albedo = [0.5, 1.5, 0.5]"),
        Some("albedo = [0.5, 1.5"),
        Some("materials.floor.albedo"),
        &["[0, 1]", "1.5"],
    );
    assert_err(
        &with(
            "albedo = [0.5, 0.5, 0.5]",
            "albedo = 0.5\npreset = \"skin2\"",
        ),
        Some("skin2"),
        Some("materials.floor.preset"),
        &["does not apply to a diffuse material"],
    );
    // Textures.
    assert_err(
        &with("type = \"checker\"", "type = \"marble\""),
        Some("type = \"marble\""),
        Some("materials.skin.texture.type"),
        &["unknown texture type", "checker", "stripes", "noise"],
    );
    assert_err(
        &with("scale = 0.1, a = 1.0", "scale = 0.0, a = 1.0"),
        Some("scale = 0.0"),
        Some("materials.skin.texture.scale"),
        &["> 0"],
    );
    assert_err(
        &with("b = [0.5, 0.4, 0.3]", "b = [0.5, 0.4, 1.3]"),
        Some("1.3]"),
        Some("materials.skin.texture.b"),
        &["[0, 1]"],
    );
    assert_err(
        &with("period = 0.5, a = 0.2", "period = 0.5, seed = 3, a = 0.2"),
        Some("period = 0.5, seed"),
        Some("materials.floor.texture.seed"),
        &["does not apply to a stripes texture"],
    );
    assert_err(
        &with("axis = [1.0, 0.0, 0.0]", "axis = [0.0, 0.0, 0.0]"),
        Some("axis"),
        Some("materials.floor.texture.axis"),
        &["non-zero"],
    );
}

#[test]
fn object_errors() {
    let no_objects = GOOD.split("[[objects]]").next().unwrap().to_string();
    assert_err(&no_objects, None, None, &["no objects"]);
    assert_err(
        &with("material = \"jelly\"", "material = \"jam\""),
        Some("jam"),
        Some("objects[1].material"),
        &["unknown material `jam`", "`skin`", "`floor`"],
    );
    assert_err(
        &with("shape = \"torus\"", "shape = \"teapot\""),
        Some("teapot"),
        Some("objects[1].shape"),
        &["unknown shape", "teapot", "bumpy-sphere"],
    );
    for bad in ["0.0", "-1.0", "nan"] {
        assert_err(
            &with("radius = 1.0", &format!("radius = {bad}")),
            Some("radius = "),
            Some("objects[0].radius"),
            &["> 0"],
        );
    }
    assert_err(
        &with("size = [10.0, 10.0]", "size = [10.0, 0.0]"),
        Some("size = [10.0, 0.0]"),
        Some("objects[2].size"),
        &["> 0"],
    );
    assert_err(
        &with("size = [10.0, 10.0]", "size = [10.0, 10.0, 1.0]"),
        Some("size = [10.0, 10.0, 1.0]"),
        Some("objects[2].size"),
        &["2 numbers"],
    );
    assert_err(
        &with("size = [1.0, 0.5, 1.0]", "size = [1.0, -0.5, 1.0]"),
        Some("size = [1.0, -0.5"),
        Some("objects[4].size"),
        &["> 0", "-0.5"],
    );
    assert_err(
        &with(
            "size = [1.0, 0.5, 1.0]",
            "size = [1.0, 0.5, 1.0]\nradius = 2.0",
        ),
        Some("radius = 2.0"),
        Some("objects[4].radius"),
        &["does not apply to shape `box`", "size"],
    );
    assert_err(
        &with("minor = 0.25", "minor = 1.5"),
        Some("minor"),
        Some("objects[1].minor"),
        &["smaller than the major radius"],
    );
    assert_err(
        &with(
            "major = 1.0\nminor = 0.25",
            "major = 1.0\nminor = 0.25\nsegments = 2",
        ),
        Some("segments"),
        Some("objects[1].segments"),
        &["[3, "],
    );
    assert_err(
        &with("amplitude = 0.05", "amplitude = 0.5"),
        Some("amplitude"),
        Some("objects[3].amplitude"),
        &["smaller than the radius"],
    );
    assert_err(
        &with("frequency = 4.0", "frequency = 0.0"),
        Some("frequency"),
        Some("objects[3].frequency"),
        &["> 0"],
    );
    assert_err(
        &with("subdivisions = 3", "subdivisions = 30"),
        Some("subdivisions = 30"),
        Some("objects[3].subdivisions"),
        &["at most"],
    );
    assert_err(
        &with("scale = 0.5, rotate", "scale = [0.5, 0.0, 1.0], rotate"),
        Some("scale = [0.5, 0.0"),
        Some("objects[1].transform.scale"),
        &["non-zero"],
    );
    assert_err(
        &with("rotate = [90.0, 0.0, 0.0]", "rotate = [90.0, inf, 0.0]"),
        Some("rotate = [90.0, inf"),
        Some("objects[1].transform.rotate"),
        &["finite"],
    );
    assert_err(
        &with("shape = \"sphere\"", "shape = \"mesh\""),
        Some("radius = 1.0"),
        Some("objects[0].radius"),
        &["does not apply to shape `mesh`"],
    );
    assert_err(
        &with("radius = 1.0\n", "").replacen("shape = \"sphere\"", "shape = \"mesh\"", 1),
        Some("[[objects]]"),
        Some("objects[0].file"),
        &["needs `file`"],
    );
}

// ---------------------------------------------------------------------------------------------
// Textures

#[test]
fn checker_and_stripes() {
    let (a, b) = ([0.9, 0.1, 0.2], [0.2, 0.3, 0.8]);
    let t = Texture::Checker { scale: 0.5, a, b };
    let e = 1e-9;
    assert_eq!(t.eval(DVec3::new(0.25, 0.25, 0.25)), a);
    assert_eq!(t.eval(DVec3::new(0.5 - e, 0.1, 0.1)), a);
    assert_eq!(
        t.eval(DVec3::new(0.5 + e, 0.1, 0.1)),
        b,
        "alternates across x = s"
    );
    assert_eq!(t.eval(DVec3::new(0.1, 0.5 + e, 0.1)), b, "and across y = s");
    assert_eq!(t.eval(DVec3::new(0.1, 0.1, -e)), b, "and across z = 0");
    assert_eq!(
        t.eval(DVec3::new(0.5 + e, 0.5 + e, 0.1)),
        a,
        "two steps: back to a"
    );
    assert_eq!(t.eval(DVec3::new(-0.25, -0.25, 0.25)), a);
    for i in 0..1000 {
        let p = DVec3::new(
            i as f64 * 0.137 - 50.0,
            i as f64 * 0.071,
            -(i as f64) * 0.093,
        );
        let v = t.eval(p);
        assert!(v == a || v == b);
    }
    let t = Texture::Stripes {
        axis: DVec3::X,
        period: 2.0,
        a,
        b,
    };
    assert_eq!(t.eval(DVec3::new(0.5, 7.0, -3.0)), a);
    assert_eq!(t.eval(DVec3::new(1.5, 7.0, -3.0)), b);
    assert_eq!(t.eval(DVec3::new(-0.5, 0.0, 0.0)), b);
    assert_eq!(t.eval(DVec3::new(2.5, 0.0, 0.0)), a);
}

#[test]
fn noise_is_smooth_bounded_and_deterministic() {
    let (a, b) = ([0.9, 0.1, 0.5], [0.2, 0.6, 0.5]);
    let t = Texture::Noise {
        scale: 0.3,
        seed: 42,
        a,
        b,
    };
    let other = Texture::Noise {
        scale: 0.3,
        seed: 43,
        a,
        b,
    };
    let mut values = Vec::new();
    let mut differs = 0;
    for i in 0..20_000 {
        let k = i as f64;
        let p = DVec3::new(
            (k * 0.618).sin() * 37.0,
            (k * 0.377).cos() * 1e4,
            k * 0.0131 - 100.0,
        );
        let v = t.eval(p);
        assert_eq!(v, t.eval(p), "deterministic");
        for ch in 0..3 {
            assert!(
                v[ch] >= a[ch].min(b[ch]) && v[ch] <= a[ch].max(b[ch]),
                "{v:?}"
            );
        }
        assert_eq!(v[2], 0.5, "a = b gives a constant channel");
        if other.eval(p) != v {
            differs += 1;
        }
        values.push(v[0]);
    }
    assert!(differs > 19_000, "the seed changes the noise ({differs})");
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    assert!(
        lo < 0.35 && hi > 0.75,
        "varies over its range: [{lo}, {hi}]"
    );
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    assert!((mean - 0.55).abs() < 0.05, "mean {mean}");
    // Smooth: a step of 1e-4 feature sizes changes the value by little (Lipschitz), and
    // values along a line change continuously.
    let mut max_jump: f64 = 0.0;
    let step = 1e-4 * 0.3;
    for i in 0..10_000 {
        let p = DVec3::new(i as f64 * step, 0.37, -1.21);
        let q = p + DVec3::new(step, 0.0, 0.0);
        max_jump = max_jump.max((t.eval(p)[0] - t.eval(q)[0]).abs());
    }
    assert!(max_jump < 0.7 * 3.0 * 1e-4, "max jump {max_jump}");
    // Varies with position on the scale of the feature size.
    let far = (0..100)
        .filter(|&i| {
            let p = DVec3::splat(i as f64 * 0.77);
            (t.eval(p)[0] - t.eval(p + DVec3::splat(0.3))[0]).abs() > 1e-3
        })
        .count();
    assert!(far > 80, "{far}");
}
