//! Bounded resources: a frame over the memory budget is refused before anything is allocated,
//! and caps that bind and implausible units are reported as warnings in the render output (the
//! CLI prints them as `warning:` lines, `compare` marks the runs), with the requested and the
//! effective value and how to lift the cap.

use sss_render::budget::{BYTES_PER_PIXEL, BYTES_PER_SAMPLE};
use sss_render::integrators::exact::Exact;
use sss_render::irradiance::IrradianceSettings;
use sss_render::progress::NoProgress;
use sss_render::scene::{LoadOptions, builtin, load_str};
use sss_render::{RenderSettings, render};

fn sphere_scene(units_per_mm: f64) -> sss_render::scene::Scene {
    let text = format!(
        r#"
[camera]
position = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov = 30.0
resolution = [24, 18]

[[lights]]
type = "directional"
direction = [0.0, 0.0, -1.0]
irradiance = 1.0

[materials.wax]
type = "translucent"
model = "better-dipole"
preset = "skin1"
units_per_mm = {units_per_mm}

[[objects]]
name = "ball"
material = "wax"
shape = "sphere"
radius = 1.0
"#
    );
    load_str(&text, "ball.toml", None, &LoadOptions::default()).unwrap()
}

/// skin1's reduced extinction per channel (1/mm), from Jensen et al. 2001 Table 2
/// (σ'_s = 0.74, 0.88, 1.01; σ_a = 0.032, 0.17, 0.48).
const SIGMA_T_REDUCED: [f64; 3] = [0.74 + 0.032, 0.88 + 0.17, 1.01 + 0.48];

#[test]
fn a_binding_sample_cap_warns_with_requested_and_effective_spacing() {
    let scene = sphere_scene(0.1);
    let exact = Exact {
        irradiance: IrradianceSettings {
            spacing_mfp: 0.25,
            max_samples: 500,
            ..IrradianceSettings::default()
        },
    };
    let out = render(&scene, &exact, &RenderSettings::default(), &NoProgress).unwrap();
    assert_eq!(out.warnings.len(), 1, "{:?}", out.warnings);
    let w = &out.warnings[0];
    assert!(w.contains("`ball`") && w.contains("`wax`"), "{w}");
    assert!(
        w.contains("cap of 500") && w.contains("requested 0.25"),
        "{w}"
    );
    assert!(w.contains("--max-samples"), "{w}");
    // The effective spacing in mean free paths, computed here from the spacing reported: the
    // smallest reduced mean free path is 1/max σ'_t mm = 0.1/1.49 scene units.
    let (_, spacing) = &out.spacing[0];
    let mfp = 0.1 / SIGMA_T_REDUCED.iter().cloned().fold(0.0, f64::max);
    let used = spacing / mfp;
    assert!(
        used > 0.25 * 1.5,
        "the cap must have coarsened the samples: {used}"
    );
    assert!(
        w.contains(&format!("{used:.3} mean free paths apart")),
        "{w} vs {used}"
    );
    // A unit sphere has area 4π; 500 samples spaced `spacing` apart cover about that much, so
    // lifting the cap needs about 500·(used/0.25)² samples (the message's estimate).
    let needed = (out.irradiance_samples as f64 * (used / 0.25).powi(2)).ceil();
    assert!(w.contains(&format!("about {needed:.0}")), "{w} vs {needed}");
}

#[test]
fn no_warning_when_nothing_binds() {
    let scene = sphere_scene(0.1);
    let out = render(
        &scene,
        &Exact::default(),
        &RenderSettings::default(),
        &NoProgress,
    )
    .unwrap();
    assert!(out.warnings.is_empty(), "{:?}", out.warnings);
    for name in ["sphere", "toad", "slab", "backlit"] {
        let mut s = builtin(name, &LoadOptions::default()).unwrap();
        s.camera.width /= 8;
        s.camera.height /= 8;
        let coarse = Exact {
            irradiance: IrradianceSettings {
                spacing_mfp: 2.0,
                ..IrradianceSettings::default()
            },
        };
        let out = render(&s, &coarse, &RenderSettings::default(), &NoProgress).unwrap();
        assert!(out.warnings.is_empty(), "{name}: {:?}", out.warnings);
    }
}

#[test]
fn implausible_units_warn_naming_object_material_and_units() {
    // 2 scene units across at 1e-7 units per mm: 2e7 mm, far over 10⁴ mean free paths.
    let huge = sphere_scene(1e-7);
    let exact = Exact {
        irradiance: IrradianceSettings {
            max_samples: 200,
            ..IrradianceSettings::default()
        },
    };
    let out = render(&huge, &exact, &RenderSettings::default(), &NoProgress).unwrap();
    let units: Vec<&String> = out
        .warnings
        .iter()
        .filter(|w| w.contains("check units_per_mm"))
        .collect();
    assert_eq!(units.len(), 1, "{:?}", out.warnings);
    let w = units[0];
    assert!(w.contains("`ball`") && w.contains("`wax`"), "{w}");
    assert!(w.contains("units_per_mm = 0.0000001"), "{w}");
    assert!(w.contains("larger than 10⁴"), "{w}");
    // The cap binds too and says so.
    assert!(
        out.warnings.iter().any(|w| w.contains("cap of 200")),
        "{:?}",
        out.warnings
    );

    // 2 scene units at 1e4 units per mm: 0.2 µm, under one mean free path (≥ 0.67 mm).
    let tiny = sphere_scene(1e4);
    let out = render(&tiny, &exact, &RenderSettings::default(), &NoProgress).unwrap();
    assert!(
        out.warnings
            .iter()
            .any(|w| w.contains("smaller than one") && w.contains("units_per_mm = 10000")),
        "{:?}",
        out.warnings
    );

    // Just inside both bounds: 2 scene units at 1 unit per mm is 2 mm, between 1 and 10⁴
    // mean free paths in every channel.
    let fine = sphere_scene(1.0);
    let out = render(&fine, &exact, &RenderSettings::default(), &NoProgress).unwrap();
    assert!(
        !out.warnings
            .iter()
            .any(|w| w.contains("check units_per_mm")),
        "{:?}",
        out.warnings
    );
}

/// The example — 100000² pixels — and a budget one byte short of a small frame are
/// refused with one error naming the input, the bytes and the budget; a budget that fits
/// renders.
#[test]
fn frames_over_the_memory_budget_are_refused_before_allocation() {
    let mut scene = sphere_scene(0.1);
    let (w, h) = (scene.camera.width as u64, scene.camera.height as u64);
    let needed = w * h * (BYTES_PER_SAMPLE + BYTES_PER_PIXEL);
    let tight = RenderSettings {
        max_memory: needed - 1,
        ..RenderSettings::default()
    };
    let e = render(&scene, &Exact::default(), &tight, &NoProgress)
        .expect_err("over budget")
        .to_string();
    assert!(
        e.contains("resolution 24x18") && e.contains("--max-memory"),
        "{e}"
    );
    assert!(e.contains(&format!("{needed} bytes")), "{e}");
    assert!(
        e.contains(&format!("budget of {} bytes", needed - 1)),
        "{e}"
    );
    // `exact` also places irradiance samples: the budget must hold them on top of the frame.
    let samples =
        sss_render::budget::irradiance_estimate(&scene, &IrradianceSettings::default())[0].2;
    let short = RenderSettings {
        max_memory: needed + samples - 1,
        ..RenderSettings::default()
    };
    let e = render(&scene, &Exact::default(), &short, &NoProgress)
        .expect_err("samples over budget")
        .to_string();
    assert!(
        e.contains("irradiance samples") && e.contains("--max-samples"),
        "{e}"
    );
    let enough = RenderSettings {
        max_memory: needed + samples,
        ..RenderSettings::default()
    };
    assert!(render(&scene, &Exact::default(), &enough, &NoProgress).is_ok());

    scene.camera.width = 100_000;
    scene.camera.height = 100_000;
    let e = render(
        &scene,
        &Exact::default(),
        &RenderSettings::default(),
        &NoProgress,
    )
    .expect_err("10¹⁰ camera samples cannot be held")
    .to_string();
    assert!(e.contains("resolution 100000x100000"), "{e}");
    scene.camera.width = 40_000;
    scene.camera.height = 40_000;
    let e = render(&scene, &Exact::default(), &tight, &NoProgress)
        .expect_err("over budget")
        .to_string();
    assert!(e.contains("over the memory budget"), "{e}");
}

#[test]
fn absurd_irradiance_sample_counts_are_refused_before_placement() {
    let scene = sphere_scene(0.1);
    // 10^15 samples at a spacing of 10⁻⁹ mean free paths: petabytes, would abort if placed.
    let exact = Exact {
        irradiance: IrradianceSettings {
            spacing_mfp: 1e-9,
            max_samples: 1_000_000_000_000_000,
            ..IrradianceSettings::default()
        },
    };
    let settings = RenderSettings {
        max_memory: 1 << 40,
        ..RenderSettings::default()
    };
    let e = render(&scene, &exact, &settings, &NoProgress)
        .unwrap_err()
        .to_string();
    assert!(e.contains("--max-samples 1000000000000000"), "{e}");
    assert!(e.contains("up to 1000000000000000 on object `ball`"), "{e}");
    assert!(
        e.contains(&format!("budget of {} bytes", 1u64 << 40)),
        "{e}"
    );
    // At least 10^15 samples × one 100-byte IrradianceSample.
    let bytes: u64 = e
        .split("need about ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|t| t.parse().ok())
        .expect("bytes in the message");
    assert!(bytes >= 100_000_000_000_000_000, "{e}");
}

#[test]
fn irradiance_estimate_bounds_the_samples_placed() {
    use sss_render::budget::{BYTES_PER_IRRADIANCE_SAMPLE, check_irradiance, irradiance_estimate};
    let scene = sphere_scene(0.1);
    let irr = IrradianceSettings {
        spacing_mfp: 0.5,
        max_samples: 1_000_000,
        ..IrradianceSettings::default()
    };
    // Hexagonal packing bound on a unit sphere (area ≤ 4π for an inscribed mesh, ≥ 0.97·4π
    // for this tessellation): 2·4π / (√3 s²), s = 0.5 · 0.1 mm / max σ'_t.
    let s = 0.5 * 0.1 / SIGMA_T_REDUCED.iter().cloned().fold(0.0, f64::max);
    let bound = 2.0 * 4.0 * std::f64::consts::PI / (3f64.sqrt() * s * s);
    let est = irradiance_estimate(&scene, &irr);
    assert_eq!(est.len(), 1);
    let (_, count, bytes) = est[0];
    assert!(
        (count as f64) <= bound + 2.0 && (count as f64) >= 0.97 * bound,
        "{count} vs {bound}"
    );
    assert_eq!(bytes, count * BYTES_PER_IRRADIANCE_SAMPLE);
    // The blue-noise placement puts no more samples than the bound.
    let exact = Exact { irradiance: irr };
    let out = render(&scene, &exact, &RenderSettings::default(), &NoProgress).unwrap();
    assert!(
        out.irradiance_samples as u64 <= count,
        "{} > {count}",
        out.irradiance_samples
    );
    assert!(
        out.irradiance_samples as u64 > count / 4,
        "{}",
        out.irradiance_samples
    );
    // The cap wins when it is lower; the budget boundary is exact.
    let capped = IrradianceSettings {
        max_samples: 500,
        ..irr
    };
    assert_eq!(irradiance_estimate(&scene, &capped)[0].1, 500);
    let cam = &scene.camera;
    let frame = sss_render::budget::frame_bytes(cam.width, cam.height, cam.pixel_samples);
    let need = frame + 500 * BYTES_PER_IRRADIANCE_SAMPLE;
    assert!(check_irradiance(&scene, &capped, need).is_ok());
    let e = check_irradiance(&scene, &capped, need - 1)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&format!("{} bytes", 500 * BYTES_PER_IRRADIANCE_SAMPLE)),
        "{e}"
    );
}
