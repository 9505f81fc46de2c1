//! Validation: a complete valid scene loads as described, and every way of breaking it (toml
//! syntax and structure, camera, lights, materials, textures, objects) is an `Invalid` error
//! naming the file, line and key.

use crate::common::{line_of, no_dirs};
use glam::DVec3;
use sss_scene::{Light, MaterialKind, SceneError, SceneErrorKind, Texture, load_str};

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
    // A quad is degenerate when its edges are parallel relative to their lengths, at any
    // scale: sin θ = 10⁻¹⁴ is refused and 10⁻⁹ accepted, for edges of 10⁻⁶ to 10⁶.
    for s in [1e-6, 1.0, 1e6] {
        for (sin, ok) in [(1e-14, false), (1e-9, true)] {
            let text = with(
                "edge_v = [2.0, 0.0, 0.0]",
                &format!("edge_v = [{:e}, {:e}, 0.0]", 1000.0 * s, 1000.0 * sin * s),
            )
            .replace(
                "edge_u = [0.0, 0.0, 2.0]",
                &format!("edge_u = [{s:e}, 0.0, 0.0]"),
            );
            let got = load_str(&text, "good.toml", None, &no_dirs());
            match (ok, got) {
                (true, Ok(_)) => {}
                (false, Err(e)) => assert!(e.to_string().contains("parallel"), "{e}"),
                (_, got) => panic!("scale {s}, sin {sin}: {:?}", got.map(|_| "loaded")),
            }
        }
    }
    // A light may be dark in some channels (≥ 0, not > 0): a red point light.
    let s = load_str(
        &with(
            "intensity = [10.0, 10.0, 10.0]",
            "intensity = [10.0, 0.0, 0.0]",
        ),
        "good.toml",
        None,
        &no_dirs(),
    )
    .unwrap();
    assert!(
        matches!(s.lights[0], Light::Point { intensity, .. } if intensity == [10.0, 0.0, 0.0]),
        "{:?}",
        s.lights[0]
    );
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

/// A sun: the directional light with a disc of finite angular diameter (degrees in the file,
/// half the angle in radians in the scene; 0.53°, the sun's, by default).
#[test]
fn sun_lights() {
    let sun = |extra: &str| {
        with(
            "type = \"directional\"\ndirection = [0.0, -1.0, 0.0]\nirradiance = 1.0",
            &format!("type = \"sun\"\ndirection = [0.0, -2.0, 0.0]\nirradiance = 3.0{extra}"),
        )
    };
    let half = |text: &str| match load_str(text, "sun.toml", None, &no_dirs()).unwrap().lights[1] {
        Light::Sun {
            direction,
            irradiance,
            half_angle,
        } => {
            assert_eq!(direction, DVec3::new(0.0, -1.0, 0.0));
            assert_eq!(irradiance, [3.0; 3]);
            half_angle
        }
        ref other => panic!("not a sun: {other:?}"),
    };
    assert!((half(&sun("")) - 0.265f64.to_radians()).abs() < 1e-15);
    assert!((half(&sun("\nangular_diameter = 10.0")) - 5f64.to_radians()).abs() < 1e-15);
    for bad in ["0.0", "-1.0", "180.0", "nan"] {
        assert_err(
            &sun(&format!("\nangular_diameter = {bad}")),
            Some("angular_diameter"),
            Some("lights[1].angular_diameter"),
            &["degrees above 0 and below 180"],
        );
    }
    // Only a sun takes an angular diameter.
    assert_err(
        &with(
            "intensity = [10.0, 10.0, 10.0]",
            "intensity = 1.0\nangular_diameter = 1.0",
        ),
        Some("angular_diameter"),
        Some("lights[0].angular_diameter"),
        &["does not apply to a point light"],
    );
    assert_err(
        &with("type = \"point\"", "type = \"spot\""),
        None,
        None,
        &["sun"],
    );
}

/// `angular` is `fresnel` by default, `albedo` on request, refused with the directional
/// dipole (which has its own S) and for any other word.
#[test]
fn angular_factors() {
    let jelly = |s: &sss_scene::Scene| match &s.materials[1].kind {
        MaterialKind::Translucent(t) => t.angular,
        _ => panic!("jelly is translucent"),
    };
    let s = load_str(GOOD, "good.toml", None, &no_dirs()).unwrap();
    assert_eq!(jelly(&s), sss_scene::Angular::Fresnel);
    let text = with("eta = 1.4", "eta = 1.4\nangular = \"albedo\"");
    let s = load_str(&text, "good.toml", None, &no_dirs()).unwrap();
    assert_eq!(jelly(&s), sss_scene::Angular::Albedo);
    let text = with("eta = 1.4", "eta = 1.4\nangular = \"fresnel\"");
    let s = load_str(&text, "good.toml", None, &no_dirs()).unwrap();
    assert_eq!(jelly(&s), sss_scene::Angular::Fresnel);
    assert_err(
        &with("eta = 1.4", "eta = 1.4\nangular = \"lambert\""),
        Some("lambert"),
        Some("materials.jelly.angular"),
        &["unknown angular factors", "lambert", "fresnel", "albedo"],
    );
    assert_err(
        &with(
            "model = \"directional-dipole\"",
            "model = \"directional-dipole\"\nangular = \"albedo\"",
        ),
        Some("angular = \"albedo\""),
        Some("materials.skin.angular"),
        &["directional dipole", "radial model"],
    );
}

/// `sphere_radius`: a length in scene units, or `"auto"`, 3 V/A of the material's objects (a
/// torus' is 3/2 of its tube radius: V = 2π²Rr², A = 4π²Rr); refused on the directional
/// dipole, for non-positive lengths, unknown words, and for objects that enclose no volume.
#[test]
fn sphere_radius() {
    let jelly = |s: &sss_scene::Scene| match &s.materials[1].kind {
        MaterialKind::Translucent(t) => t.sphere_radius,
        _ => panic!("jelly is translucent"),
    };
    let s = load_str(GOOD, "good.toml", None, &no_dirs()).unwrap();
    assert_eq!(jelly(&s), None);
    let text = with("eta = 1.4", "eta = 1.4\nsphere_radius = 2.5");
    let s = load_str(&text, "good.toml", None, &no_dirs()).unwrap();
    assert_eq!(jelly(&s), Some(2.5));
    let text = with("eta = 1.4", "eta = 1.4\nsphere_radius = 3");
    let s = load_str(&text, "good.toml", None, &no_dirs()).unwrap();
    assert_eq!(jelly(&s), Some(3.0));
    // The torus of tube radius 0.25, scaled by 0.5; its tessellation is a little inside.
    let text = with("eta = 1.4", "eta = 1.4\nsphere_radius = \"auto\"");
    let s = load_str(&text, "good.toml", None, &no_dirs()).unwrap();
    let r = jelly(&s).unwrap();
    assert!((r / 0.1875 - 1.0).abs() < 0.02, "auto radius {r}");
    for bad in ["0.0", "-1.0", "nan", "inf"] {
        assert_err(
            &with("eta = 1.4", &format!("eta = 1.4\nsphere_radius = {bad}")),
            Some("sphere_radius"),
            Some("materials.jelly.sphere_radius"),
            &["finite and > 0"],
        );
    }
    assert_err(
        &with("eta = 1.4", "eta = 1.4\nsphere_radius = \"big\""),
        Some("sphere_radius"),
        Some("materials.jelly.sphere_radius"),
        &["unknown sphere radius", "big", "auto", "local"],
    );
    // `"local"`: no one radius, each point's own; with or without drift; only that material.
    let local = |s: &sss_scene::Scene, k: usize| match &s.materials[k].kind {
        MaterialKind::Translucent(t) => (t.sphere_radius, t.local_radius),
        _ => panic!("translucent"),
    };
    assert_eq!(
        local(&load_str(GOOD, "good.toml", None, &no_dirs()).unwrap(), 1),
        (None, false)
    );
    for extra in ["", "\ndrift = true"] {
        let text = with(
            "eta = 1.4",
            &format!("eta = 1.4\nsphere_radius = \"local\"{extra}"),
        );
        let s = load_str(&text, "good.toml", None, &no_dirs()).unwrap();
        assert_eq!(local(&s, 1), (None, true), "{extra}");
        assert_eq!(local(&s, 0), (None, false));
    }
    for v in ["\"auto\"", "2.5"] {
        let text = with("eta = 1.4", &format!("eta = 1.4\nsphere_radius = {v}"));
        let s = load_str(&text, "good.toml", None, &no_dirs()).unwrap();
        assert!(!local(&s, 1).1, "{v}");
    }
    assert_err(
        &with(
            "model = \"directional-dipole\"",
            "model = \"directional-dipole\"\nsphere_radius = \"local\"",
        ),
        Some("sphere_radius = \"local\""),
        Some("materials.skin.sphere_radius"),
        &["directional dipole", "radial"],
    );
    assert_err(
        &with(
            "model = \"directional-dipole\"",
            "model = \"directional-dipole\"\nsphere_radius = 1.0",
        ),
        Some("sphere_radius = 1.0"),
        Some("materials.skin.sphere_radius"),
        &["directional dipole", "radial"],
    );
    // Jelly on the open floor plane only: no volume.
    let text = with("eta = 1.4", "eta = 1.4\nsphere_radius = \"auto\"")
        .replacen("material = \"jelly\"", "material = \"floor\"", 1)
        .replacen(
            "material = \"floor\"\nshape = \"plane\"",
            "material = \"jelly\"\nshape = \"plane\"",
            1,
        );
    let e = load_err(&text);
    assert_eq!(
        e.key.as_deref(),
        Some("materials.jelly.sphere_radius"),
        "{e}"
    );
    assert!(e.to_string().contains("enclose no volume"), "{e}");
}

/// `drift`: off by default, `true` or `false`, refused on the directional dipole (its S has
/// its own) and for anything but a boolean.
#[test]
fn drift() {
    let jelly = |s: &sss_scene::Scene| match &s.materials[1].kind {
        MaterialKind::Translucent(t) => t.drift,
        _ => panic!("jelly is translucent"),
    };
    let s = load_str(GOOD, "good.toml", None, &no_dirs()).unwrap();
    assert!(!jelly(&s));
    for (v, want) in [("true", true), ("false", false)] {
        let text = with("eta = 1.4", &format!("eta = 1.4\ndrift = {v}"));
        let s = load_str(&text, "good.toml", None, &no_dirs()).unwrap();
        assert_eq!(jelly(&s), want, "drift = {v}");
    }
    assert_err(
        &with(
            "model = \"directional-dipole\"",
            "model = \"directional-dipole\"\ndrift = true",
        ),
        Some("drift = true"),
        Some("materials.skin.drift"),
        &["directional dipole", "radial model"],
    );
    assert_err(
        &with("eta = 1.4", "eta = 1.4\ndrift = \"yes\""),
        Some("drift = \"yes\""),
        Some("materials.jelly.drift"),
        &["expected a boolean"],
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
    // mc-table has tables for η from 1 to 1.5 only; inside that range the material loads.
    assert_err(
        &with("eta = 1.4", "model = \"mc-table\"\neta = 1.6"),
        Some("eta = 1.6"),
        Some("materials.jelly.eta"),
        &["mc-table", "from 1 to 1.5", "1.6"],
    );
    let ok = with("eta = 1.4", "model = \"mc-table\"\neta = 1.45");
    assert!(load_str(&ok, "ok.toml", None, &no_dirs()).is_ok());
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

/// `unscattered`: off by default, `true` or `false` on every model (the directional dipole
/// too: the light refracted straight through is no model's), and nothing but a boolean.
#[test]
fn unscattered() {
    let flag = |s: &sss_scene::Scene, i: usize| match &s.materials[i].kind {
        MaterialKind::Translucent(t) => t.unscattered,
        _ => panic!("material {i} is translucent"),
    };
    let s = load_str(GOOD, "good.toml", None, &no_dirs()).unwrap();
    assert!(!flag(&s, 0) && !flag(&s, 1));
    for (v, want) in [("true", true), ("false", false)] {
        let text = with("eta = 1.4", &format!("eta = 1.4\nunscattered = {v}"));
        let s = load_str(&text, "good.toml", None, &no_dirs()).unwrap();
        assert_eq!(flag(&s, 1), want, "unscattered = {v}");
        assert!(!flag(&s, 0), "only the material that names it");
    }
    let text = with(
        "model = \"directional-dipole\"",
        "model = \"directional-dipole\"\nunscattered = true",
    );
    let s = load_str(&text, "good.toml", None, &no_dirs()).unwrap();
    assert!(flag(&s, 0));
    assert_err(
        &with("eta = 1.4", "eta = 1.4\nunscattered = 1"),
        Some("unscattered = 1"),
        Some("materials.jelly.unscattered"),
        &["expected a boolean"],
    );
}
