//! `volpath` against MCML (Wang, Jacques & Zheng 1995), an independent Monte Carlo code: the
//! total diffuse reflectance of a slab far thicker than its transport mean free path under a
//! normally incident beam.
//!
//! By reciprocity, the radiance a surface sends back along its normal under a uniform
//! environment of radiance 1 is its directional–hemispherical reflectance for light arriving
//! along the normal: the fraction of a normal beam's photons that come back out, counted per
//! incident photon. That is MCML's total diffuse reflectance, whose photons start with weight
//! 1 − R_sp (the specular reflection is excluded but its loss counted) — and `volpath`'s value
//! at a camera ray along the normal, which excludes the reflection at the camera point and
//! refracts in with weight 1 − F. The slab (2 m wide, 0.5 m thick, as thick as MCML's) is a
//! box, so the walk meets real triangles; the one pixel looks straight down at its centre.
//! Reads `../shared/reference/mcml/cases.csv` (or `SSS_MCML_DIR`); skips, saying so, when it
//! is absent.

use sss_render::integrators::{self, MethodOptions};
use sss_render::progress::NoProgress;
use sss_render::scene::{LoadOptions, load_str};
use sss_render::{RenderSettings, render};
use std::path::PathBuf;

fn mcml_dir() -> PathBuf {
    match std::env::var_os("SSS_MCML_DIR") {
        Some(d) => PathBuf::from(d),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/reference/mcml"),
    }
}

/// One case of `cases.csv`: the medium (1/mm) and MCML's total diffuse reflectance.
struct Case {
    name: String,
    sigma_a: f64,
    sigma_s: f64,
    g: f64,
    eta: f64,
    total: f64,
    total_se: f64,
}

/// The cases of `cases.csv`, or None (the reason printed) without the folder.
fn cases() -> Option<Vec<Case>> {
    let dir = mcml_dir();
    let Ok(text) = std::fs::read_to_string(dir.join("cases.csv")) else {
        eprintln!(
            "skipped: no MCML reference at {} (set SSS_MCML_DIR)",
            dir.display()
        );
        return None;
    };
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next()?.split(',').map(str::trim).collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("cases.csv: no column {name}"))
    };
    let cols = [
        col("sigma_a_per_mm"),
        col("sigma_s_per_mm"),
        col("g"),
        col("eta"),
        col("total_diffuse_reflectance"),
        col("total_se"),
    ];
    let (c_name, c_above) = (col("case"), col("eta_above"));
    Some(
        lines
            .filter(|l| !l.trim().is_empty())
            .map(|l| {
                let f: Vec<&str> = l.split(',').map(str::trim).collect();
                let v = cols.map(|c| f[c].parse::<f64>().unwrap());
                assert_eq!(f[c_above].parse::<f64>().unwrap(), 1.0, "{l}");
                Case {
                    name: f[c_name].to_string(),
                    sigma_a: v[0],
                    sigma_s: v[1],
                    g: v[2],
                    eta: v[3],
                    total: v[4],
                    total_se: v[5],
                }
            })
            .collect(),
    )
}

/// The slab of a case (coefficients in every channel), 1 unit = 1 mm, seen by one pixel
/// straight down under a uniform environment of radiance 1.
fn slab(sigma_a: f64, sigma_s: f64, g: f64, eta: f64) -> String {
    format!(
        r#"
[camera]
position = [0.0, 1000.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov = 0.001
resolution = [1, 1]

[[lights]]
type = "environment"
radiance = 1.0

[materials.slab]
type = "translucent"
sigma_a = {sigma_a}
sigma_s = {sigma_s}
g = {g}
eta = {eta}
units_per_mm = 1.0

[[objects]]
name = "slab"
material = "slab"
shape = "box"
size = [2000.0, 500.0, 2000.0]
"#
    )
}

/// Every MCML case within 1 % (η = 1 and 1.3, g = 0 and 0.9, albedo 0.33 to 0.9999); our
/// standard error is held near 0.3 %, so the 1 % criterion is resolved. Measured at 0.2 %:
/// every case within 0.5 % (the largest +0.50 % ± 0.20 %, apple G).
#[test]
fn volpath_total_reflectance_matches_mcml() {
    let Some(cases) = cases() else { return };
    assert!(cases.len() >= 10, "{} cases", cases.len());
    for Case {
        name,
        sigma_a,
        sigma_s,
        g,
        eta,
        total,
        total_se,
    } in cases
    {
        let text = slab(sigma_a, sigma_s, g, eta);
        let scene = load_str(&text, "slab.toml", None, &LoadOptions::default()).unwrap();
        let run = |spp: u64| {
            let method =
                integrators::build("volpath", &MethodOptions::new().with("spp", spp)).unwrap();
            let out = render(
                &scene,
                method.as_ref(),
                &RenderSettings::default(),
                &NoProgress,
            )
            .unwrap();
            let se = out.std_error.as_ref().unwrap()[0][0];
            (out, se)
        };
        let t = std::time::Instant::now();
        // A pilot sets the paths for a standard error of 0.3 % (fewer for bright media).
        let pilot = 20_000;
        let (_, se) = run(pilot);
        let paths = (pilot as f64 * (se / (0.003 * total)).powi(2)).ceil() as u64;
        let (out, se) = run(paths.clamp(pilot, 2_000_000));
        let r = out.subsurface[0][0];
        // Identical coefficients in every channel give identical estimates.
        assert_eq!(out.subsurface[0][1], r);
        let err = r / total - 1.0;
        eprintln!(
            "{name}: volpath {r:.5} ± {se:.5}, MCML {total:.5} ± {total_se:.5}: {:+.2} % ({:.1} s)",
            100.0 * err,
            t.elapsed().as_secs_f64()
        );
        assert!(se < 0.0035 * total, "{name}: standard error {se}");
        assert!(err.abs() < 0.01, "{name}: {r} against MCML {total}");
    }
}
