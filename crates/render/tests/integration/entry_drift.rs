//! `drift = true` (the random walk's drift of obliquely entering light, `EntryDrift`) against
//! real transport: `volpath`, which shares no code with the model, on a sphere lit from one
//! side, where a radial profile sends light back towards the lamp that real light carries
//! on; and between the two methods that take it (`exact`, `pathtrace`), and the refusal of
//! those that sum one irradiance per point.

use sss_render::integrators::{self, MethodOptions};
use sss_render::progress::NoProgress;
use sss_render::scene::{Scene, load_str};
use sss_render::{RenderSettings, render};

/// A 10 mm skin1 sphere seen from 60 mm at `n` × `n` pixels, lit by a 10 mm square quad
/// 60 mm away on the camera's side (`front`) or behind the sphere; `mc-table` with the given
/// extra keys.
fn lit_sphere(extra: &str, front: bool, n: u32) -> Scene {
    let z = if front { 60.0 } else { -60.0 };
    let (eu, ev) = if front {
        ("[0.0, 10.0, 0.0]", "[10.0, 0.0, 0.0]")
    } else {
        ("[10.0, 0.0, 0.0]", "[0.0, 10.0, 0.0]")
    };
    let text = format!(
        "[camera]\nposition = [0.0, 0.0, 60.0]\ntarget = [0.0, 0.0, 0.0]\nfov = 24.0\n\
         resolution = [{n}, {n}]\n\n[[lights]]\ntype = \"quad\"\ncorner = [-5.0, -5.0, {z:?}]\n\
         edge_u = {eu}\nedge_v = {ev}\nradiance = 100.0\n\n\
         [materials.skin]\ntype = \"translucent\"\nmodel = \"mc-table\"\npreset = \"skin1\"\n\
         units_per_mm = 1.0\n{extra}\n\n\
         [[objects]]\nname = \"ball\"\nmaterial = \"skin\"\nshape = \"sphere\"\nradius = 10.0\n\
         subdivisions = 5\n"
    );
    load_str(&text, "sphere.toml", None, &Default::default()).unwrap()
}

/// The image's mean per channel (the whole image: under light from behind most of the light
/// is at the silhouette).
fn mean(scene: &Scene, method: &str, options: MethodOptions, seed: u64) -> [f64; 3] {
    let m = integrators::build(method, &options).unwrap();
    let settings = RenderSettings {
        seed,
        ..Default::default()
    };
    let out = render(scene, m.as_ref(), &settings, &NoProgress).unwrap();
    let n = out.subsurface.len() as f64;
    let mut s = [0.0; 3];
    for v in &out.subsurface {
        for c in 0..3 {
            s[c] += v[c] / n;
        }
    }
    s
}

const BALL: &str = "angular = \"albedo\"\nsphere_radius = \"auto\"";

/// Lit from the camera's side, the ball's radial profile is too bright (measured 1.14 / 1.10 /
/// 1.05 of `volpath` here): light entering near the lit cap's edge is sent back towards the
/// camera. With the drift every channel comes within 4 % (measured 0.98 / 1.00 / 1.00). Lit
/// from behind the profile is far too dark (0.80 / 0.30 / 0.10) and the drift brings it nearer
/// (1.08 / 0.51 / 0.14; the rest is light seen at grazing angles at the silhouette, which one
/// harmonic does not hold): red within 10 %, red and green at least 0.1 nearer than without.
/// Blue from behind reaches the camera through a thin ring at the silhouette, too rarely for
/// a test of this size to pin it.
#[test]
fn drift_brings_one_sided_light_to_real_transport() {
    let spp = |n: u32| MethodOptions::new().with("spp", n);
    let drift = format!("{BALL}\ndrift = true");
    for front in [true, false] {
        // Light from behind reaches few paths: more of them.
        let paths = if front { 512 } else { 2048 };
        let truth = mean(&lit_sphere("", front, 48), "volpath", spp(paths), 5);
        let ball = mean(&lit_sphere(BALL, front, 48), "pathtrace", spp(128), 6);
        let moved = mean(&lit_sphere(&drift, front, 48), "pathtrace", spp(128), 6);
        for c in 0..3 {
            let (rb, rd) = (ball[c] / truth[c], moved[c] / truth[c]);
            eprintln!("front {front}, channel {c}: ball {rb:.4}, with drift {rd:.4}");
            if front {
                assert!(rb > 1.05, "front, channel {c}: ball alone {rb:.4}");
                assert!((rd - 1.0).abs() < 0.04, "front, channel {c}: drift {rd:.4}");
            } else if c < 2 {
                assert!(
                    (rd - 1.0).abs() + 0.1 < (rb - 1.0).abs(),
                    "behind, channel {c}: ball {rb:.4}, drift {rd:.4}"
                );
            }
        }
        if !front {
            let rd = moved[0] / truth[0];
            assert!((rd - 1.0).abs() < 0.1, "behind, red: drift {rd:.4}");
        }
    }
}

/// `exact` (each irradiance sample keeps its light's directions) and `pathtrace` (the light at
/// each probe point) apply the same drift: within 2 % per channel on the sphere lit from the
/// camera's side, where the drift moves 7–16 % of the light.
#[test]
fn exact_and_pathtrace_drift_alike() {
    let scene = lit_sphere(&format!("{BALL}\ndrift = true"), true, 24);
    let pt = mean(
        &scene,
        "pathtrace",
        MethodOptions::new().with("spp", 256),
        8,
    );
    let ex = mean(&scene, "exact", MethodOptions::new(), 8);
    for c in 0..3 {
        let r = ex[c] / pt[c];
        eprintln!("channel {c}: exact {r:.4} of pathtrace");
        assert!(
            (r - 1.0).abs() < 0.02,
            "channel {c}: exact {r:.4} of pathtrace"
        );
    }
}

/// The methods that sum one irradiance per point cannot apply a factor that depends on each
/// light's direction: they refuse, naming the material and the methods that can.
#[test]
fn methods_without_directions_refuse_drift() {
    let scene = lit_sphere("drift = true", true, 8);
    for method in [
        "single-tree",
        "dual-tree",
        "dual-tree-fmm",
        "separable",
        "manylight",
        "mdlc",
    ] {
        let m = integrators::build(method, &MethodOptions::new()).unwrap();
        let e = render(&scene, m.as_ref(), &RenderSettings::default(), &NoProgress)
            .err()
            .unwrap_or_else(|| panic!("{method} rendered a drifting material"))
            .to_string();
        assert!(
            e.contains("skin") && e.contains("drift") && e.contains("exact or pathtrace"),
            "{method}: {e}"
        );
    }
}
