//! The cached `exact` reference of each scene (`target/compare/cache/scene_<name>_<key>.exr`
//! plus a `.txt` with its seconds and sample count), keyed by the scene text, resolution,
//! seed, the reference method's settings and [`REFERENCE_VERSION`].

use super::super::output::write_atomic;
use super::super::{Context, Error};
use sss_bssrdf::Rgb;
use sss_render::image::{read_exr, write_exr};
use sss_render::integrators::exact::{Exact, reference_spacing};
use sss_render::irradiance::IrradianceSettings;
use sss_render::progress::NoProgress;
use sss_render::render::{RenderSettings, render};
use sss_render::scene::Scene;

/// Bumped whenever the reference renderer's output changes, to invalidate cached references.
const REFERENCE_VERSION: u32 = 2;

/// The reference method: `exact` at [`reference_spacing`].
pub fn reference_method(quick: bool) -> Exact {
    Exact {
        irradiance: IrradianceSettings {
            spacing_mfp: reference_spacing(quick),
            ..IrradianceSettings::default()
        },
    }
}

/// FNV-1a over bytes: a stable cache key.
fn fnv(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= *b as u64;
        h = h.wrapping_mul(0x100_0000_01b3);
    }
    h
}

/// The cached reference of a scene: its subsurface image, coverage and timing.
pub(in super::super) struct Reference {
    pub(in super::super) subsurface: Vec<Rgb>,
    pub(super) total: Vec<Rgb>,
    pub(in super::super) coverage: Vec<f32>,
    pub(super) seconds: f64,
    pub(super) samples: usize,
}

pub(in super::super) fn reference(
    ctx: &Context<'_>,
    scene: &Scene,
    text: &str,
) -> Result<Reference, Error> {
    let cfg = ctx.config;
    let key = fnv(format!(
        "v{REFERENCE_VERSION}|{text}|{}x{}|{}|{:?}",
        scene.camera.width,
        scene.camera.height,
        cfg.seed,
        reference_method(cfg.quick)
    )
    .as_bytes());
    let dir = cfg.out.join("cache");
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error(format!("cannot create {}: {e}", dir.display())))?;
    let path = dir.join(format!("scene_{}_{key:016x}.exr", scene.name));
    let meta = path.with_extension("txt");
    if !cfg.fresh
        && let (Ok((w, h, layers)), Ok(m)) = (read_exr(&path), std::fs::read_to_string(&meta))
        && (w, h) == (scene.camera.width, scene.camera.height)
    {
        let get = |n: &str| {
            layers
                .iter()
                .find(|(name, _)| name == n)
                .map(|(_, d)| d.clone())
        };
        let mut it = m.split_whitespace();
        let seconds = it.next().and_then(|v| v.parse().ok());
        let samples = it.next().and_then(|v| v.parse().ok());
        if let (Some(sub), Some(tot), Some(cov), Some(seconds), Some(samples)) = (
            get("subsurface"),
            get("total"),
            get("coverage"),
            seconds,
            samples,
        ) {
            (ctx.log)(&format!("scene {}: reference from cache", scene.name));
            return Ok(Reference {
                subsurface: sub,
                total: tot,
                coverage: cov.iter().map(|c| c[0] as f32).collect(),
                seconds,
                samples,
            });
        }
    }
    (ctx.log)(&format!(
        "scene {}: rendering the exact reference",
        scene.name
    ));
    let settings = RenderSettings {
        seed: cfg.seed,
        ..RenderSettings::default()
    };
    let out = render(scene, &reference_method(cfg.quick), &settings, &NoProgress)
        .map_err(|e| Error(format!("scene {}: reference: {e}", scene.name)))?;
    for w in &out.warnings {
        (ctx.log)(&format!("scene {}: reference: warning: {w}", scene.name));
    }
    let cov: Vec<Rgb> = out.coverage.iter().map(|&c| [c as f64; 3]).collect();
    write_exr(
        &path,
        out.width,
        out.height,
        &[
            ("subsurface", &out.subsurface),
            ("total", &out.total),
            ("coverage", &cov),
        ],
    )
    .map_err(|e| Error(e.to_string()))?;
    write_atomic(
        &meta,
        format!("{} {}\n", out.seconds_total(), out.irradiance_samples).as_bytes(),
    )?;
    let seconds = out.seconds_total();
    Ok(Reference {
        subsurface: out.subsurface,
        total: out.total,
        coverage: out.coverage,
        seconds,
        samples: out.irradiance_samples,
    })
}
