//! Helpers shared by the render crate's integration tests.

// Each test file uses some of these.
#![allow(dead_code)]

pub mod rasterizer;

use glam::DVec3;
use sss_bssrdf::fresnel::ft_dielectric;
use sss_bssrdf::{Medium, ModelKind, fresnel_normalization, make_model};
use sss_render::frame::Frame;
use sss_render::integrators::{Integrator, MethodOptions, Shaded};
use sss_render::irradiance::IrradianceSettings;
use sss_render::progress::NoProgress;
use sss_render::scene::{
    Camera, Light, LoadOptions, Material, MaterialKind, Mesh, Object, Scene, Translucent, builtin,
};
use std::f64::consts::PI;

/// Cheap options per registered method, for tests that run every method on a small frame and
/// check properties that do not depend on accuracy (finite values, exact zeros, coverage,
/// determinism): the point-based methods on coarse irradiance samples, 2 paths per pixel
/// (`volpath` with its Lambertian boundary), and 32 irradiance points per shading point for the MDLC / EELC baselines (their default,
/// 4096, takes about 12 s a render even on a 24×18 frame).
pub fn cheap(name: &str) -> MethodOptions {
    match name {
        "exact" | "single-tree" | "dual-tree" | "dual-tree-fmm" => {
            MethodOptions::new().with("spacing", 2.0)
        }
        "pathtrace" => MethodOptions::new().with("spp", 2),
        "mdlc" | "eelc" => MethodOptions::new().with("irradiance-points", 32),
        // The Lambertian boundary reaches every light kind, so the shared scenes (point and
        // directional lights) render; the dielectric boundary is tested on its own.
        "volpath" => MethodOptions::new()
            .with("spp", 2)
            .with("boundary", "lambertian"),
        _ => MethodOptions::new(),
    }
}

/// Built-in scene `name` at `w` × `h` pixels.
pub fn scene(name: &str, w: u32, h: u32) -> Scene {
    let mut s = builtin(name, &LoadOptions::default()).unwrap();
    s.camera.width = w;
    s.camera.height = h;
    s
}

/// The default irradiance-sample settings at `spacing` mean free paths.
pub fn irradiance(spacing: f64) -> IrradianceSettings {
    IrradianceSettings {
        spacing_mfp: spacing,
        ..IrradianceSettings::default()
    }
}

/// `m` on `frame`, without progress.
pub fn run(frame: &Frame<'_>, m: &dyn Integrator) -> Shaded {
    m.integrate(frame, &NoProgress).unwrap()
}

/// A UV sphere about `centre` of `rings` × `segments` quads, outward normals.
pub fn uv_sphere(centre: DVec3, radius: f64, rings: u32, segments: u32) -> Mesh {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for i in 0..=rings {
        let theta = PI * i as f64 / rings as f64;
        for j in 0..segments {
            let phi = 2.0 * PI * j as f64 / segments as f64;
            let n = DVec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            positions.push(centre + n * radius);
            normals.push(n);
        }
    }
    let mut triangles = Vec::new();
    let idx = |i: u32, j: u32| i * segments + (j % segments);
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (idx(i, j), idx(i, j + 1), idx(i + 1, j), idx(i + 1, j + 1));
            // Counter-clockwise seen from outside.
            if i != 0 {
                triangles.push([a, b, c]);
            }
            if i + 1 != rings {
                triangles.push([b, d, c]);
            }
        }
    }
    Mesh {
        positions,
        normals,
        triangles,
    }
}

/// A square in the plane y = 0 of side `size`, facing +y, split into n × n cells.
pub fn square(size: f64, n: u32) -> Mesh {
    let mut positions = Vec::new();
    for i in 0..=n {
        for j in 0..=n {
            let x = -size / 2.0 + size * j as f64 / n as f64;
            let z = -size / 2.0 + size * i as f64 / n as f64;
            positions.push(DVec3::new(x, 0.0, z));
        }
    }
    let normals = vec![DVec3::Y; positions.len()];
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let a = i * (n + 1) + j;
            let (b, c, d) = (a + 1, a + n + 1, a + n + 2);
            // (b - a) × (c - a) = x × z = -y, so order a, c, b for +y.
            triangles.push([a, c, b]);
            triangles.push([b, c, d]);
        }
    }
    Mesh {
        positions,
        normals,
        triangles,
    }
}

/// A translucent material of `preset` with `model`, at `units_per_mm` scene units per mm.
pub fn translucent(model: ModelKind, preset: &str, units_per_mm: f64) -> Material {
    Material {
        name: preset.into(),
        kind: MaterialKind::Translucent(Translucent {
            model,
            medium: Medium::preset(preset).unwrap(),
            units_per_mm,
            texture: None,
            angular: Default::default(),
            sphere_radius: None,
            local_radius: false,
            drift: false,
            unscattered: false,
        }),
    }
}

/// A scene of one object, `mesh` in `material`, under `lights`, seen by `camera`.
pub fn scene_with(mesh: Mesh, material: Material, lights: Vec<Light>, camera: Camera) -> Scene {
    scene_of(vec![mesh], material, lights, camera)
}

/// A scene of one object per mesh, all in `material`, under `lights`, seen by `camera`.
pub fn scene_of(
    meshes: Vec<Mesh>,
    material: Material,
    lights: Vec<Light>,
    camera: Camera,
) -> Scene {
    Scene {
        name: "test".into(),
        path: None,
        camera,
        lights,
        materials: vec![material],
        objects: meshes
            .into_iter()
            .enumerate()
            .map(|(i, mesh)| Object {
                name: format!("object{i}"),
                material: 0,
                mesh,
                curvature: None,
            })
            .collect(),
        warnings: Vec::new(),
    }
}

/// A grey diffuse material (albedo 0.5).
pub fn diffuse() -> Material {
    Material {
        name: "grey".into(),
        kind: MaterialKind::Diffuse {
            albedo: [0.5; 3],
            texture: None,
        },
    }
}

/// A Python that imports `modules` (`SSS_PEERS_PYTHON`, else `python3`), or None with the
/// reason printed (the test skips) — unless `SSS_REQUIRE_PEERS` is set, as in CI, where a
/// missing package fails the test.
pub fn peers_python(modules: &[&str]) -> Option<std::path::PathBuf> {
    match sss_peers::find_python(modules) {
        Ok(p) => Some(p),
        Err(why) => {
            assert!(
                std::env::var_os("SSS_REQUIRE_PEERS").is_none(),
                "SSS_REQUIRE_PEERS is set but {why}"
            );
            eprintln!("skipped: {why}");
            None
        }
    }
}

/// Brute force of the sphere scene's subsurface image, written independently of the
/// integrator: per G-buffer sample x_o, F_t(η, n·ω_o)/(cπ) Σ over the mesh triangles of
/// R_d(‖x − x_o‖) I cos θ_i/d² F_t(η, cos θ_i) dA by the centroid rule on each triangle cut
/// into 4^L parts (L = 4 within 0.15 units of x_o, 3 within 0.5, 1 beyond), with no shadow
/// rays: the sphere is convex and alone, so a face is lit iff it faces the light. cos θ_i is
/// taken against the shading normal, which on this icosphere (vertex normals radial) is the
/// point's own direction from the centre; the face must face the light too.
pub fn brute_force_sphere(scene: &Scene, frame: &Frame<'_>) -> Vec<[f64; 3]> {
    let t = scene.translucent(0).unwrap();
    let model = make_model(t.model, &t.medium);
    let u = t.units_per_mm;
    let eta = t.medium.eta();
    let norm = 1.0 / (fresnel_normalization(eta) * PI);
    let Light::Point {
        position: light,
        intensity,
    } = scene.lights[0]
    else {
        panic!("sphere has one point light")
    };
    let mesh = &scene.objects[0].mesh;
    let tris: Vec<[DVec3; 3]> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize]))
        .collect();
    // E(x) F_t at the centroid of each part, for parts at every level, computed once.
    let gb = &frame.gbuffer;
    let spp = gb.samples_per_pixel as f64;
    let mut out = vec![[0.0; 3]; gb.pixels()];
    for g in &gb.samples {
        let exit = ft_dielectric(g.n.dot(g.wo), eta) * norm / spp;
        let mut sum = [0.0; 3];
        for tri in &tris {
            let c = (tri[0] + tri[1] + tri[2]) / 3.0;
            let dist = c.distance(g.p);
            let level = if dist < 0.15 {
                4
            } else if dist < 0.5 {
                3
            } else {
                1
            };
            let nrm = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
            let area = 0.5 * nrm.length();
            let n = nrm / (2.0 * area);
            let mut stack = vec![(*tri, 0)];
            while let Some((t, l)) = stack.pop() {
                if l < level {
                    let m = [
                        0.5 * (t[0] + t[1]),
                        0.5 * (t[1] + t[2]),
                        0.5 * (t[2] + t[0]),
                    ];
                    stack.push(([t[0], m[0], m[2]], l + 1));
                    stack.push(([m[0], t[1], m[1]], l + 1));
                    stack.push(([m[2], m[1], t[2]], l + 1));
                    stack.push(([m[0], m[1], m[2]], l + 1));
                    continue;
                }
                let x = (t[0] + t[1] + t[2]) / 3.0;
                let a = area / 4f64.powi(level);
                let to = light - x;
                let d2 = to.length_squared();
                let cos = x.normalize().dot(to) / d2.sqrt();
                if cos <= 0.0 || n.dot(to) <= 0.0 {
                    continue;
                }
                let e = cos / d2 * ft_dielectric(cos, eta) * a;
                let rd = model.rd_rgb(x.distance(g.p) / u);
                for c in 0..3 {
                    sum[c] += rd[c] / (u * u) * intensity[c] * e;
                }
            }
        }
        for c in 0..3 {
            out[g.pixel as usize][c] += exit * sum[c];
        }
    }
    out
}

/// Renders `scene` with `method` and returns the mean per channel over the pixels an object
/// covers fully (alpha 1), and the mean's standard error where the method reports one;
/// asserts more than `min_pixels` such pixels.
pub fn covered_mean(
    scene: &Scene,
    method: &str,
    options: MethodOptions,
    seed: u64,
    min_pixels: usize,
) -> ([f64; 3], [f64; 3]) {
    let m = sss_render::integrators::build(method, &options).unwrap();
    let settings = sss_render::RenderSettings {
        seed,
        ..Default::default()
    };
    let out = sss_render::render(scene, m.as_ref(), &settings, &NoProgress).unwrap();
    let se = out.std_error.clone().unwrap_or_default();
    let inside: Vec<usize> = (0..out.subsurface.len())
        .filter(|&i| out.alpha[i] > 0.999)
        .collect();
    assert!(inside.len() > min_pixels, "{} pixels covered", inside.len());
    let n = inside.len() as f64;
    let (mut m, mut v) = ([0.0; 3], [0.0; 3]);
    for &i in &inside {
        for c in 0..3 {
            m[c] += out.subsurface[i][c] / n;
            if let Some(s) = se.get(i) {
                v[c] += s[c] * s[c] / (n * n);
            }
        }
    }
    (m, v.map(f64::sqrt))
}
