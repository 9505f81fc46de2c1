//! `sss_render::flip` against code we did not write: NVIDIA's `flip-evaluator` (the PyPI
//! package of the FLIP authors' C++ implementation), on pairs of our own renders. The test
//! skips with the reason when the package cannot be imported, unless `SSS_REQUIRE_PEERS` is
//! set (CI installs it beside Mitsuba and sets it, so CI cannot skip it).
//!
//! The images go to Python as raw little-endian f32 (no image format in between), linear
//! RGB (`inputsRGB=False`: the package otherwise decodes HDR input as sRGB).

use super::common::peers_python;
use sss_render::flip::{FlipParams, hdr_flip, ldr_flip};
use sss_render::integrators::{self, MethodOptions};
use sss_render::progress::NoProgress;
use sss_render::scene::{LoadOptions, load_str};
use sss_render::{RenderOutput, RenderSettings, render};
use std::path::Path;
use std::process::Command;

/// A skin sphere on a marble slab under a quad light and an environment: the environment
/// fills the background, so the median luminance is not 0 and the package's exposure range
/// is defined.
const SCENE: &str = r#"
[camera]
position = [0.0, 1.2, 5.0]
target = [0.0, 0.0, 0.0]
fov = 35.0
resolution = [96, 72]

[[lights]]
type = "quad"
corner = [-1.0, 3.0, -1.0]
edge_u = [2.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 2.0]
radiance = 6.0

[[lights]]
type = "environment"
radiance = 0.3

[materials.skin]
type = "translucent"
preset = "skin1"
units_per_mm = 0.1

[materials.stone]
type = "translucent"
preset = "marble"
units_per_mm = 0.1

[[objects]]
material = "skin"
shape = "sphere"
radius = 1.0
subdivisions = 4

[[objects]]
material = "stone"
shape = "box"
size = [5.0, 0.3, 5.0]
transform = { translate = [0.0, -1.15, 0.0] }
"#;

fn render_with(method: &str, options: MethodOptions) -> RenderOutput {
    let scene = load_str(SCENE, "flip-pair.toml", None, &LoadOptions::default()).unwrap();
    let m = integrators::build(method, &options).unwrap();
    render(&scene, m.as_ref(), &RenderSettings::default(), &NoProgress).unwrap()
}

fn write_f32(path: &Path, values: impl Iterator<Item = f32>) {
    let bytes: Vec<u8> = values.flat_map(f32::to_le_bytes).collect();
    std::fs::write(path, bytes).unwrap();
}

/// The package's (mean, map) for two linear images of `w` × `h`, in `mode` ("HDR" or
/// "LDR"), with `params` as a Python dict literal.
fn theirs(
    python: &Path,
    dir: &Path,
    a: &[[f32; 3]],
    b: &[[f32; 3]],
    (w, h): (usize, usize),
    mode: &str,
    params: &str,
) -> (f64, Vec<f32>) {
    std::fs::create_dir_all(dir).unwrap();
    let (ra, rb, out) = (dir.join("a.f32"), dir.join("b.f32"), dir.join("map.f32"));
    write_f32(&ra, a.iter().flatten().copied());
    write_f32(&rb, b.iter().flatten().copied());
    let script = format!(
        "import numpy as np, flip_evaluator as flip\n\
         a = np.fromfile({ra:?}, dtype='<f4').reshape({h}, {w}, 3)\n\
         b = np.fromfile({rb:?}, dtype='<f4').reshape({h}, {w}, 3)\n\
         m, mean, p = flip.evaluate(a, b, '{mode}', inputsRGB=False, applyMagma=False, \
         parameters={params})\n\
         np.asarray(m, dtype='<f4').reshape(-1).tofile({out:?})\n\
         print(repr(float(mean)))\n",
    );
    let run = Command::new(python).args(["-c", &script]).output().unwrap();
    assert!(
        run.status.success(),
        "flip-evaluator failed: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let mean: f64 = String::from_utf8_lossy(&run.stdout).trim().parse().unwrap();
    let map: Vec<f32> = std::fs::read(&out)
        .unwrap()
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    (mean, map)
}

fn to_f32(img: &[[f64; 3]]) -> Vec<[f32; 3]> {
    img.iter().map(|p| p.map(|v| v as f32)).collect()
}

/// Means within 1 % of each other and the maps equal pixel by pixel to 10⁻³ (errors are in
/// [0, 1]; both compute in f32, and agreed to 6·10⁻⁵ at the last run).
fn assert_agree(what: &str, ours_mean: f64, ours_map: &[f32], their_mean: f64, their_map: &[f32]) {
    assert_eq!(ours_map.len(), their_map.len(), "{what}: map sizes");
    let mut d: Vec<f32> = ours_map
        .iter()
        .zip(their_map)
        .map(|(a, b)| (a - b).abs())
        .collect();
    d.sort_by(f32::total_cmp);
    let rel = (ours_mean - their_mean).abs() / their_mean;
    eprintln!(
        "{what}: ours {ours_mean:.6}, flip-evaluator {their_mean:.6} ({:+.4} %), per pixel up to {:.2e}",
        100.0 * (ours_mean / their_mean - 1.0),
        d[d.len() - 1]
    );
    assert!(their_mean > 0.005, "{what}: a pair that differs");
    assert!(rel < 0.01, "{what}: means {ours_mean} vs {their_mean}");
    assert!(
        d[d.len() - 1] < 1e-3,
        "{what}: per-pixel difference up to {}",
        d[d.len() - 1]
    );
}

#[test]
fn hdr_flip_equals_nvidias_flip_evaluator_on_our_renders() {
    let Some(python) = peers_python(&["flip_evaluator", "numpy"]) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("sss-flip-evaluator-{}", std::process::id()));
    // A reference and two test renders that differ from it as our methods do: path-tracing
    // noise, and a model's bias with a screen-space blur.
    let reference = render_with("exact", MethodOptions::new().with("spacing", 1.0));
    let noisy = render_with("pathtrace", MethodOptions::new().with("spp", 2));
    let separable = render_with("separable", MethodOptions::new());
    let (w, h) = (reference.width as usize, reference.height as usize);
    for (name, test) in [("pathtrace 2 spp", &noisy), ("separable", &separable)] {
        let ours = hdr_flip(&reference.total, &test.total, w, h, &FlipParams::default());
        let (mean, map) = theirs(
            &python,
            &dir,
            &to_f32(&reference.total),
            &to_f32(&test.total),
            (w, h),
            "HDR",
            "{}",
        );
        assert_agree(&format!("HDR {name}"), ours.mean, &ours.map, mean, &map);
    }

    // The subsurface layer alone: a black background, where the package's automatic exposure
    // range is undefined, so both are given ours.
    let ours = hdr_flip(
        &reference.subsurface,
        &noisy.subsurface,
        w,
        h,
        &FlipParams::default(),
    );
    let (start, stop) = ours.exposures;
    assert!(start.is_finite() && stop.is_finite() && start < stop);
    let params = format!(
        "{{'startExposure': {start}, 'stopExposure': {stop}, 'numExposures': {}}}",
        ours.count
    );
    let (mean, map) = theirs(
        &python,
        &dir,
        &to_f32(&reference.subsurface),
        &to_f32(&noisy.subsurface),
        (w, h),
        "HDR",
        &params,
    );
    assert_agree("HDR subsurface", ours.mean, &ours.map, mean, &map);

    // LDR-FLIP on the renders scaled into [0, 1].
    let scale = |img: &[[f64; 3]]| -> Vec<[f32; 3]> {
        img.iter()
            .map(|p| p.map(|v| (v * 0.8).clamp(0.0, 1.0) as f32))
            .collect()
    };
    let (a, b) = (scale(&reference.total), scale(&noisy.total));
    let ours = ldr_flip(&a, &b, w, h, sss_render::flip::DEFAULT_PPD);
    let ours_mean = ours.iter().map(|&v| f64::from(v)).sum::<f64>() / ours.len() as f64;
    let (mean, map) = theirs(&python, &dir, &a, &b, (w, h), "LDR", "{}");
    assert_agree("LDR", ours_mean, &ours, mean, &map);
    std::fs::remove_dir_all(&dir).ok();
}
