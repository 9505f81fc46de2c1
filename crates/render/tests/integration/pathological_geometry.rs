//! Pathological geometry: meshes with only degenerate triangles, a single triangle,
//! NaN normals, a camera inside a translucent object, a light inside one, zero-area and
//! zero-power lights. Each case either renders finite values with every registered method or
//! fails with an error naming the problem and where it is. The rule decided per case is stated
//! at each test.
//!
//! Finiteness is checked twice: on the integrator's own per-sample values (`integrate`), because
//! `render`'s assembly counts non-finite values as 0 and would hide a NaN, and on every layer of
//! the render output.

use crate::common::cheap;
use glam::DVec3;
use sss_render::frame::Frame;
use sss_render::integrators::{self, METHODS};
use sss_render::progress::NoProgress;
use sss_render::scene::{LoadOptions, Scene, SceneError, SceneErrorKind, load_str};
use sss_render::{RenderOutput, RenderSettings, render};
use std::path::{Path, PathBuf};

/// A fresh, empty directory under the system temporary directory.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "sss-render-pathological-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// A scene of a 24×18 camera at `camera`, looking at the origin, the given light and object
/// tables, and one translucent material `wax` (skin1, better dipole, 0.1 units per mm).
fn scene_text(camera: [f64; 3], lights: &str, objects: &str) -> String {
    format!(
        r#"
[camera]
position = {camera:?}
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov = 40.0
resolution = [24, 18]

{lights}

[materials.wax]
type = "translucent"
model = "better-dipole"
preset = "skin1"
units_per_mm = 0.1

{objects}
"#
    )
}

fn load(text: &str) -> Result<Scene, SceneError> {
    load_str(text, "patho.toml", None, &LoadOptions::default())
}

/// An object table using `wax` with a mesh from `file` (an absolute path).
fn mesh_object(file: &Path) -> String {
    format!(
        "[[objects]]\nname = \"thing\"\nmaterial = \"wax\"\nshape = \"mesh\"\nfile = {:?}\n",
        file.display().to_string()
    )
}

const SPHERE: &str = r#"
[[objects]]
name = "ball"
material = "wax"
shape = "sphere"
radius = 1.0
subdivisions = 3
"#;

const FRONT_LIGHT: &str = r#"
[[lights]]
type = "directional"
direction = [0.0, 0.0, -1.0]
irradiance = 1.0
"#;

/// Renders `scene` with every registered method; checks the integrator's per-sample values and
/// every layer of the output are finite and non-negative; returns the outputs by method.
fn render_all(scene: &Scene) -> Vec<RenderOutput> {
    let settings = RenderSettings::default();
    let mut outs = Vec::new();
    for m in METHODS {
        let method = integrators::build(m.name, &cheap(m.name)).unwrap();
        let frame = Frame::prepare(scene, settings.seed);
        let shaded = method
            .integrate(&frame, &NoProgress)
            .unwrap_or_else(|e| panic!("{}: {e}", m.name));
        for v in &shaded.values {
            assert!(
                v.iter().all(|x| x.is_finite() && *x >= 0.0),
                "{}: per-sample value {v:?}",
                m.name
            );
        }
        let out = render(scene, method.as_ref(), &settings, &NoProgress)
            .unwrap_or_else(|e| panic!("{}: {e}", m.name));
        let n = (out.width * out.height) as usize;
        let mut layers: Vec<(&str, &[[f64; 3]])> =
            vec![("subsurface", &out.subsurface), ("total", &out.total)];
        if let Some(se) = &out.std_error {
            layers.push(("std_error", se));
        }
        for l in &out.layers {
            layers.push((l.name, &l.pixels));
        }
        for (name, px) in layers {
            assert_eq!(px.len(), n, "{}: layer {name}", m.name);
            for p in px {
                assert!(
                    p.iter().all(|x| x.is_finite() && *x >= 0.0),
                    "{}: layer {name} has {p:?}",
                    m.name
                );
            }
        }
        assert!(
            out.coverage
                .iter()
                .all(|c| c.is_finite() && (0.0..=1.0).contains(c)),
            "{}: coverage",
            m.name
        );
        outs.push(out);
    }
    outs
}

fn max_value(px: &[[f64; 3]]) -> f64 {
    px.iter().flatten().cloned().fold(0.0, f64::max)
}

fn assert_invalid(e: &SceneError, file: &str, line: Option<usize>, words: &[&str]) {
    let msg = e.to_string();
    assert_eq!(e.kind, SceneErrorKind::Invalid, "{msg}");
    assert_eq!(e.file, file, "{msg}");
    assert_eq!(e.line, line, "{msg}");
    for w in words {
        assert!(msg.contains(w), "`{w}` missing from: {msg}");
    }
}

/// Case 1. An OBJ whose every triangle has zero area (a repeated vertex, three collinear
/// points, three coincident points) would leave an object with nothing to hit or sample: a load
/// error naming the OBJ file, the object and how many triangles were dropped. One good
/// triangle among them is enough to load, with a warning counting the dropped ones.
#[test]
fn a_mesh_of_only_degenerate_triangles_is_a_load_error() {
    let dir = temp_dir("degenerate");
    let cases = [
        // Repeated vertex index.
        (
            "repeated.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 1 2\nf 2 3 3\n",
            2,
        ),
        // Collinear (distinct indices, zero area).
        (
            "collinear.obj",
            "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3\nf 1 2 4\n",
            2,
        ),
        // Coincident positions: the bounding box itself has no extent.
        ("point.obj", "v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n", 1),
    ];
    for (name, obj, n) in cases {
        let path = dir.join(name);
        std::fs::write(&path, obj).unwrap();
        let e = load(&scene_text(
            [0.0, 0.0, 4.0],
            FRONT_LIGHT,
            &mesh_object(&path),
        ))
        .expect_err("a mesh of degenerate triangles must not load");
        let plural = if n == 1 { "" } else { "s" };
        assert_invalid(
            &e,
            &path.display().to_string(),
            None,
            &[
                "`thing`",
                &format!("no triangles left after dropping {n} degenerate one{plural}"),
            ],
        );
    }
    // One good triangle among the degenerate ones: loads, warns, keeps exactly that one.
    let path = dir.join("one_good.obj");
    std::fs::write(
        &path,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 1 2\nf 1 2 4\nf 1 2 3\n",
    )
    .unwrap();
    let s = load(&scene_text(
        [0.0, 0.0, 4.0],
        FRONT_LIGHT,
        &mesh_object(&path),
    ))
    .unwrap();
    assert_eq!(s.objects[0].mesh.triangles.len(), 1);
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert!(
        s.warnings[0].contains("dropped 2 degenerate triangles")
            && s.warnings[0].contains("kept 1"),
        "{:?}",
        s.warnings
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Case 2. A single triangle (an open surface, no volume) as a translucent object: the
/// irradiance samples lie on one triangle, the separable pass sees a small patch, path tracing
/// probes a surface with no far side. It must render finite, non-negative values with every
/// method, and the lit, facing triangle must receive some light.
#[test]
fn a_single_triangle_renders_finite_values_with_every_method() {
    let dir = temp_dir("single");
    for (name, obj) in [
        // Facing the camera and the light (+z, counter-clockwise seen from +z).
        ("front.obj", "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n"),
        // The same triangle wound the other way: the normal points away from camera and light.
        ("back.obj", "v -1 -1 0\nv 0 1 0\nv 1 -1 0\nf 1 2 3\n"),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, obj).unwrap();
        let s = load(&scene_text(
            [0.0, 0.0, 4.0],
            FRONT_LIGHT,
            &mesh_object(&path),
        ))
        .unwrap();
        assert_eq!(s.objects[0].mesh.triangles.len(), 1);
        for out in render_all(&s) {
            let covered: f64 = out.coverage.iter().map(|&c| c as f64).sum();
            // Closed form: at distance 4 a 40° field of view spans 2·4·tan 20° = 2.912 units
            // over 18 rows (and 24/18 of that across), so the triangle's area of 2 units²
            // covers 2 / (2.912² · 24/18) · 24 · 18 = 76.4 pixels. Its perimeter of 6.47 units
            // crosses about 40 pixels, each half covered on average: ±20 pixels for the
            // one-sample-per-pixel coverage.
            let th = 4.0 * (20.0f64).to_radians().tan() * 2.0;
            let expected = 2.0 / (th * th * 24.0 / 18.0) * 24.0 * 18.0;
            assert!(
                (covered - expected).abs() < 20.0,
                "{name} {}: {covered} pixels, expected {expected:.1}",
                out.method
            );
            if name == "front.obj" {
                assert!(
                    max_value(&out.subsurface) > 0.0,
                    "{name} {}: the lit triangle is black",
                    out.method
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Case 3. NaN in an OBJ: a `vn` or `v` line with `nan` is refused at load with the OBJ file and
/// line (normals are not silently recomputed: a NaN is a broken file). A finite but zero `vn`
/// has no direction; such normals are replaced by the smooth normals of the geometry, and the
/// scene renders finite values with every method.
#[test]
fn nan_normals_and_positions_are_load_errors_and_zero_normals_are_recomputed() {
    let dir = temp_dir("nan");
    let quad = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n";
    for (name, obj, line, words) in [
        (
            "nan_normal.obj",
            format!("{quad}vn 0 0 1\nvn nan 0 1\nf 1//1 2//1 3//2\nf 1//1 3//2 4//1\n"),
            6,
            ["normal coordinate `nan`", "not finite"],
        ),
        (
            "nan_position.obj",
            "v -1 -1 0\nv 1 NaN 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n".to_string(),
            2,
            ["vertex coordinate `NaN`", "not finite"],
        ),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, obj).unwrap();
        let e = load(&scene_text(
            [0.0, 0.0, 4.0],
            FRONT_LIGHT,
            &mesh_object(&path),
        ))
        .expect_err("NaN in an OBJ must not load");
        let mut expected = words.to_vec();
        expected.push("`thing`");
        assert_invalid(&e, &path.display().to_string(), Some(line), &expected);
    }
    // Zero normals: recomputed from the (flat, +z-facing) geometry.
    let path = dir.join("zero_normal.obj");
    std::fs::write(
        &path,
        format!("{quad}vn 0 0 0\nf 1//1 2//1 3//1\nf 1//1 3//1 4//1\n"),
    )
    .unwrap();
    let s = load(&scene_text(
        [0.0, 0.0, 4.0],
        FRONT_LIGHT,
        &mesh_object(&path),
    ))
    .unwrap();
    for n in &s.objects[0].mesh.normals {
        assert!((*n - DVec3::Z).length() < 1e-12, "{n}");
    }
    for out in render_all(&s) {
        assert!(max_value(&out.subsurface) > 0.0, "{}", out.method);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Case 3, for scenes built in code: a mesh whose normals are NaN, zero or not unit, or whose
/// positions are not finite, or whose triangles index past the vertices, breaks the invariants
/// of `Mesh`. `render` refuses it with an input error naming the object and the problem
/// instead of rendering NaN (or panicking).
#[test]
fn a_scene_built_in_code_with_broken_meshes_is_refused_by_render() {
    let good = load(&scene_text([0.0, 0.0, 4.0], FRONT_LIGHT, SPHERE)).unwrap();
    type Break = fn(&mut sss_render::scene::Mesh);
    let breaks: [(Break, &str); 5] = [
        (|m| m.normals[3] = DVec3::NAN, "normal"),
        (|m| m.normals[0] = DVec3::ZERO, "normal"),
        (|m| m.positions[2].y = f64::INFINITY, "position"),
        (|m| m.triangles[1][2] = u32::MAX, "vertex"),
        (|m| _ = m.normals.pop(), "normals"),
    ];
    let exact = integrators::build("exact", &cheap("exact")).unwrap();
    for (k, (brk, word)) in breaks.into_iter().enumerate() {
        let mut s = good.clone();
        brk(&mut s.objects[0].mesh);
        let e = render(&s, exact.as_ref(), &RenderSettings::default(), &NoProgress)
            .expect_err("a broken mesh must be refused");
        let msg = e.to_string();
        assert!(matches!(e, sss_render::Error::Input(_)), "{k}: {e:?}");
        assert!(msg.contains("`ball`") && msg.contains(word), "{k}: {msg}");
    }
    // Degenerate triangles built in code: among good ones they are tolerated (nothing to hit or
    // sample; the rest of the sphere still renders, finite and lit with every method); a mesh
    // of nothing else is refused like the loader refuses it.
    let mut some = good.clone();
    for t in some.objects[0].mesh.triangles.iter_mut().step_by(3) {
        t[2] = t[1];
    }
    for out in render_all(&some) {
        assert!(max_value(&out.subsurface) > 0.0, "{}", out.method);
    }
    let mut all = good.clone();
    let m = &mut all.objects[0].mesh;
    let collinear = [m.positions[0], 2.0 * m.positions[0], 3.0 * m.positions[0]];
    m.positions[..3].copy_from_slice(&collinear);
    for (k, t) in m.triangles.iter_mut().enumerate() {
        *t = if k % 2 == 0 { [0, 1, 2] } else { [5, 5, 7] };
    }
    let e = render(
        &all,
        exact.as_ref(),
        &RenderSettings::default(),
        &NoProgress,
    )
    .expect_err("a mesh of degenerate triangles must be refused");
    assert!(
        e.to_string().contains("`ball`")
            && e.to_string().contains("no triangle with non-zero area"),
        "{e}"
    );
    // Lights built in code without area, direction or finite power.
    use sss_render::scene::Light;
    for (k, light) in [
        Light::Directional {
            direction: DVec3::ZERO,
            irradiance: [1.0; 3],
        },
        Light::Point {
            position: DVec3::new(0.0, f64::NAN, 3.0),
            intensity: [1.0; 3],
        },
        Light::Point {
            position: DVec3::Z * 3.0,
            intensity: [1.0, -1.0, 1.0],
        },
        Light::Quad {
            corner: DVec3::Z * 3.0,
            edge_u: DVec3::X,
            edge_v: DVec3::X * 2.0,
            radiance: [1.0; 3],
        },
        Light::Environment {
            radiance: [f64::INFINITY; 3],
        },
    ]
    .into_iter()
    .enumerate()
    {
        let mut s = good.clone();
        s.lights.push(light);
        let e = render(&s, exact.as_ref(), &RenderSettings::default(), &NoProgress)
            .expect_err("a broken light must be refused");
        assert!(matches!(e, sss_render::Error::Input(_)), "{k}: {e:?}");
        assert!(e.to_string().contains("light 1"), "{k}: {e}");
    }
    // The unbroken scene renders.
    render(
        &good,
        exact.as_ref(),
        &RenderSettings::default(),
        &NoProgress,
    )
    .unwrap();
}

/// Case 4. The camera inside a closed translucent sphere: every camera ray leaves through the
/// inside of the sphere, i.e. sees back faces. Our surface models describe light entering from
/// outside and leaving towards the outside, so there is no defensible positive value for a
/// viewer inside the medium; what is required is finite, non-negative output from every method,
/// with the sphere covering the whole frame.
#[test]
fn a_camera_inside_a_translucent_sphere_renders_finite_values() {
    let s = load(&scene_text([0.0, 0.0, 0.3], FRONT_LIGHT, SPHERE)).unwrap();
    for out in render_all(&s) {
        assert!(
            out.coverage.iter().all(|c| *c == 1.0),
            "{}: every camera ray hits the sphere from inside",
            out.method
        );
    }
}

/// Case 5. A point light inside a closed translucent sphere (nothing else in the scene): light
/// reaches the surface only from inside, travelling outwards. The models take irradiance on the
/// outside of the surface (E = I cos θ / d² for cos θ > 0, with the surface normal pointing
/// out), and here cos θ < 0 everywhere, so no light enters: every method must give exactly 0
/// (finite, and black rather than a light leak). The same holds with the light on the surface.
/// The same light moved outside must light it.
#[test]
fn a_light_inside_a_translucent_sphere_is_occluded() {
    let inside = "[[lights]]\ntype = \"point\"\nposition = [0.1, 0.2, 0.0]\nintensity = 10.0\n";
    let s = load(&scene_text([0.0, 0.0, 4.0], inside, SPHERE)).unwrap();
    for out in render_all(&s) {
        assert_eq!(max_value(&out.subsurface), 0.0, "{}", out.method);
        assert_eq!(max_value(&out.total), 0.0, "{}", out.method);
    }
    // On the surface (a vertex of the sphere, and 10⁻⁹ inside it): the segment from any other
    // surface point to the light is a chord, inside the convex sphere, so cos θ ≤ 0 everywhere
    // and the closed form is again exactly 0 (and no 1/d² at d = 0 may leak a NaN or Inf).
    for p in [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0 - 1e-9]] {
        let l = format!("[[lights]]\ntype = \"point\"\nposition = {p:?}\nintensity = 10.0\n");
        let s = load(&scene_text([0.0, 0.0, 4.0], &l, SPHERE)).unwrap();
        assert!(
            s.objects[0].mesh.positions.contains(&DVec3::Z),
            "the sphere has a vertex at its pole"
        );
        for out in render_all(&s) {
            assert_eq!(max_value(&out.subsurface), 0.0, "{p:?} {}", out.method);
        }
    }
    let outside = "[[lights]]\ntype = \"point\"\nposition = [0.0, 0.0, 3.0]\nintensity = 10.0\n";
    let s = load(&scene_text([0.0, 0.0, 4.0], outside, SPHERE)).unwrap();
    for out in render_all(&s) {
        assert!(max_value(&out.subsurface) > 0.0, "{}", out.method);
    }
}

/// Case 6. Lights without area or power. The format's area light is the quad: a zero edge or
/// parallel edges (no area) is a load error naming the key; a directional light with a zero
/// direction is a load error. Zero power is allowed and renders exactly black (a closed form).
#[test]
fn zero_area_lights_are_load_errors_and_zero_power_renders_black() {
    for (light, key, words) in [
        (
            "type = \"quad\"\ncorner = [0.0, 0.0, 3.0]\nedge_u = [0.0, 0.0, 0.0]\nedge_v = [0.0, 1.0, 0.0]\nradiance = 1.0",
            "lights[0].edge_u",
            "non-zero",
        ),
        (
            "type = \"quad\"\ncorner = [0.0, 0.0, 3.0]\nedge_u = [1.0, 1.0, 0.0]\nedge_v = [-2.0, -2.0, 0.0]\nradiance = 1.0",
            "lights[0].edge_v",
            "no area",
        ),
        (
            "type = \"directional\"\ndirection = [0.0, 0.0, 0.0]\nirradiance = 1.0",
            "lights[0].direction",
            "non-zero",
        ),
    ] {
        let text = scene_text([0.0, 0.0, 4.0], &format!("[[lights]]\n{light}\n"), SPHERE);
        let e = load(&text).expect_err("a light without area or direction must not load");
        let msg = e.to_string();
        assert_eq!(e.kind, SceneErrorKind::Invalid, "{msg}");
        assert_eq!(e.key.as_deref(), Some(key), "{msg}");
        assert!(msg.contains(words), "{msg}");
        assert!(e.line.is_some(), "{msg}");
    }
    for light in [
        "type = \"point\"\nposition = [0.0, 0.0, 3.0]\nintensity = 0.0",
        "type = \"directional\"\ndirection = [0.0, 0.0, -1.0]\nirradiance = 0.0",
        "type = \"quad\"\ncorner = [-0.5, -0.5, 3.0]\nedge_u = [1.0, 0.0, 0.0]\nedge_v = [0.0, -1.0, 0.0]\nradiance = 0.0",
        "type = \"environment\"\nradiance = 0.0",
    ] {
        let text = scene_text([0.0, 0.0, 4.0], &format!("[[lights]]\n{light}\n"), SPHERE);
        let s = load(&text).unwrap();
        for out in render_all(&s) {
            assert_eq!(max_value(&out.total), 0.0, "{light} {}", out.method);
        }
    }
}
