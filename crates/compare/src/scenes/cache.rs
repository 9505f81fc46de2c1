//! The cached `exact` reference of each scene (`target/compare/cache/scene_<name>_<key>.exr`
//! plus a `.txt` with its seconds and sample count), keyed by the scene text, resolution,
//! seed, the reference method's settings and [`REFERENCE_VERSION`]. Both files carry a
//! length-and-checksum sidecar ([`checked`]); a damaged entry is reported and re-rendered.

use super::super::checked::{self, Entry, fnv1a64};
use super::super::{Context, Error};
use sss_bssrdf::Rgb;
use sss_render::image::{read_exr, write_exr};
use sss_render::integrators::exact::{Exact, reference_spacing};
use sss_render::irradiance::IrradianceSettings;
use sss_render::progress::NoProgress;
use sss_render::scene::Scene;
use sss_render::{RenderSettings, render};
use std::path::Path;

/// Bumped whenever the reference renderer's output (or the cache layout) changes, to
/// invalidate cached references. 3: checksum sidecars. 4: disk-averaged R_d near x_o.
const REFERENCE_VERSION: u32 = 4;

/// The reference method: `exact` at [`reference_spacing`].
pub fn reference_method(quick: bool) -> Exact {
    Exact {
        irradiance: IrradianceSettings {
            spacing_mfp: reference_spacing(quick),
            ..IrradianceSettings::default()
        },
    }
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
    // FNV-1a 64 of everything that determines the reference: a stable cache key.
    let key = fnv1a64(
        format!(
            "v{REFERENCE_VERSION}|{text}|{}x{}|{}|{:?}",
            scene.camera.width,
            scene.camera.height,
            cfg.seed,
            reference_method(cfg.quick)
        )
        .as_bytes(),
    );
    let dir = cfg.cache_dir();
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error(format!("cannot create {}: {e}", dir.display())))?;
    let path = dir.join(format!("scene_{}_{key:016x}.exr", scene.name));
    let meta = path.with_extension("txt");
    if !cfg.fresh {
        let subject = format!("scene {}", scene.name);
        let read = load(&path, &meta, scene.camera.width, scene.camera.height);
        if let Some(r) = checked::usable(read, &subject, "reference", ctx.log) {
            (ctx.log)(&format!("{subject}: reference from cache"));
            return Ok(r);
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
    let r = Reference {
        seconds: out.seconds_total(),
        samples: out.irradiance_samples,
        subsurface: out.subsurface,
        total: out.total,
        coverage: out.coverage,
    };
    store(&path, &meta, out.width, out.height, &r)?;
    // The reference as the cache holds it (f32 in the EXR), not the render's f64: a run that
    // renders the reference and one that reads it from the cache (a later run, or a shard)
    // then score every method against the same numbers, bit for bit.
    match load(&path, &meta, out.width, out.height) {
        Ok(Some(stored)) => Ok(stored),
        Ok(None) => Err(Error(format!(
            "scene {}: the reference just written to {} is missing",
            scene.name,
            path.display()
        ))),
        Err(reason) => Err(Error(format!(
            "scene {}: the reference just written does not read back ({reason})",
            scene.name
        ))),
    }
}

/// Writes a reference: the EXR and its sidecar, then the `.txt` and its sidecar. An
/// interrupt anywhere in between leaves an entry that [`load`] rejects.
fn store(path: &Path, meta: &Path, width: u32, height: u32, r: &Reference) -> Result<(), Error> {
    let cov: Vec<Rgb> = r.coverage.iter().map(|&c| [c as f64; 3]).collect();
    write_exr(
        path,
        width,
        height,
        &[
            ("subsurface", &r.subsurface),
            ("total", &r.total),
            ("coverage", &cov),
        ],
    )
    .map_err(|e| Error(e.to_string()))?;
    checked::seal(path)?;
    checked::write_entry(meta, format!("{} {}\n", r.seconds, r.samples).as_bytes())
}

/// A cached reference of a `width`×`height` scene: `Ok(None)` when there is none,
/// `Err(reason)` when it must not be trusted (a file fails its checksum, the EXR does not
/// decode, has another size or lacks a layer, or the `.txt` does not parse).
fn load(path: &Path, meta: &Path, width: u32, height: u32) -> Result<Option<Reference>, String> {
    match checked::check(path) {
        Entry::Missing => return Ok(None),
        Entry::Corrupt(reason) => return Err(format!("{}: {reason}", file_name(path))),
        Entry::Good(_) => {}
    }
    let m = match checked::check(meta) {
        Entry::Missing => return Err(format!("{}: missing", file_name(meta))),
        Entry::Corrupt(reason) => return Err(format!("{}: {reason}", file_name(meta))),
        Entry::Good(bytes) => String::from_utf8(bytes).unwrap_or_default(),
    };
    let mut it = m.split_whitespace();
    let seconds = it.next().and_then(|v| v.parse::<f64>().ok());
    let samples = it.next().and_then(|v| v.parse::<usize>().ok());
    let (Some(seconds), Some(samples)) = (seconds, samples) else {
        return Err(format!("{}: malformed", file_name(meta)));
    };
    let (w, h, layers) = read_exr(path).map_err(|e| format!("{}: {e}", file_name(path)))?;
    if (w, h) != (width, height) {
        return Err(format!(
            "{}: {w}x{h}, {width}x{height} expected",
            file_name(path)
        ));
    }
    let get = |n: &str| {
        layers
            .iter()
            .find(|(name, _)| name == n)
            .map(|(_, d)| d.clone())
            .ok_or_else(|| format!("{}: no layer {n}", file_name(path)))
    };
    Ok(Some(Reference {
        subsurface: get("subsurface")?,
        total: get("total")?,
        coverage: get("coverage")?.iter().map(|c| c[0] as f32).collect(),
        seconds,
        samples,
    }))
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checked::{sum_path, tests as t};

    /// A 3×2 reference with distinct values in every pixel (all exact in f32, as the EXR
    /// stores them).
    fn sample() -> Reference {
        let px = |k: usize, s: f64| [s * k as f64, s * k as f64 + 0.5, 0.25];
        Reference {
            subsurface: (0..6).map(|k| px(k, 0.125)).collect(),
            total: (0..6).map(|k| px(k, 1.0)).collect(),
            coverage: vec![0.0, 0.25, 0.5, 0.75, 1.0, 1.0],
            seconds: 1.5,
            samples: 42,
        }
    }

    fn same(a: &Reference, b: &Reference) -> bool {
        a.subsurface == b.subsurface
            && a.total == b.total
            && a.coverage == b.coverage
            && a.seconds == b.seconds
            && a.samples == b.samples
    }

    fn err(r: Result<Option<Reference>, String>) -> String {
        match r {
            Err(e) => e,
            Ok(Some(_)) => panic!("a damaged entry was trusted"),
            Ok(None) => panic!("a damaged entry was taken as missing"),
        }
    }

    #[test]
    fn stored_reference_round_trips_and_damage_is_detected() {
        let d = t::scratch("scene");
        let exr = d.join("scene_x_0.exr");
        let txt = exr.with_extension("txt");
        assert!(matches!(load(&exr, &txt, 3, 2), Ok(None)));
        let r = sample();
        store(&exr, &txt, 3, 2, &r).unwrap();
        let back = load(&exr, &txt, 3, 2).unwrap().unwrap();
        assert!(same(&back, &r));
        // Another resolution is not this entry.
        assert!(err(load(&exr, &txt, 2, 3)).contains("3x2, 2x3 expected"));

        let len = std::fs::metadata(&exr).unwrap().len();
        t::truncate(&exr, len / 2);
        assert_eq!(
            err(load(&exr, &txt, 3, 2)),
            format!("scene_x_0.exr: {} bytes, {len} expected", len / 2)
        );

        store(&exr, &txt, 3, 2, &r).unwrap();
        t::flip_byte(&exr, len as usize - 3);
        assert_eq!(
            err(load(&exr, &txt, 3, 2)),
            "scene_x_0.exr: checksum mismatch"
        );

        store(&exr, &txt, 3, 2, &r).unwrap();
        std::fs::remove_file(sum_path(&exr)).unwrap();
        assert_eq!(
            err(load(&exr, &txt, 3, 2)),
            "scene_x_0.exr: no checksum file"
        );

        // The timing file is checked as well: "1.5 42" -> "1.5 43" parses but is caught.
        store(&exr, &txt, 3, 2, &r).unwrap();
        t::flip_byte(&txt, 5);
        assert_eq!(std::fs::read_to_string(&txt).unwrap(), "1.5 43\n");
        assert_eq!(
            err(load(&exr, &txt, 3, 2)),
            "scene_x_0.txt: checksum mismatch"
        );
        store(&exr, &txt, 3, 2, &r).unwrap();
        std::fs::remove_file(&txt).unwrap();
        assert_eq!(err(load(&exr, &txt, 3, 2)), "scene_x_0.txt: missing");

        // Rewritten and sealed again, the entry is trusted again.
        store(&exr, &txt, 3, 2, &r).unwrap();
        assert!(same(&load(&exr, &txt, 3, 2).unwrap().unwrap(), &r));
        std::fs::remove_dir_all(&d).unwrap();
    }
}
