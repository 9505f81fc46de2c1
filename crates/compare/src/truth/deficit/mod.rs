//! `cargo xtask compare --deficit`: where a BSSRDF model's error against real light transport
//! comes from, measured on controlled set-ups.
//!
//! Every row renders one set-up ([`setups`]) four times (five on the meshes) and takes image
//! means over the scored pixels ([`measure`]): `volpath` (the truth: light transport in the
//! medium itself, checked against Mitsuba 3 and MCML), `volpath --scattering single` (the
//! truth's single scattering alone), on the meshes `volpath --reentry no` (the truth without
//! the light their parts trade, which a BSSRDF under direct light cannot carry), `mc-table`
//! under `pathtrace` (the model's integral, which discretises nothing) and the same with
//! `angular = "albedo"` (the half-space's directional albedo for its angular factors,
//! `sss_bssrdf::DirectionalAlbedo`). Each is rendered until the relative standard error of
//! its mean is about the target. The model over the truth, per channel, is the row's figure;
//! the sweeps separate the effects the planar, normal-incidence, separable model leaves out:
//!
//! - `incidence`: a half-space lit by a small sun (±10°) at an angle, seen head-on;
//! - `exit-sun`, `exit-environment`: the half-space lit head-on or by a uniform environment,
//!   seen at an angle (the exit direction's lobe);
//! - `slab-behind`, `slab-front`: slabs of finite thickness lit from behind (transmission)
//!   or from the front (thin parts);
//! - `sphere-environment`, `sphere-quad`: the 10 mm sphere of `--truth` scaled to radii of
//!   2–160 mm (curvature, against the mean free path);
//! - `bunny-quad`, `dragon-quad`: the truth's bunny and dragon scaled 1, 4, 16 and 64 times.
//!
//! The report apportions each scaled scene's deficit into four factors whose product is the
//! model's image mean over the truth's: interreflection (the truth without the light the
//! object's parts trade, over the truth; 1 on the convex set-ups, which trade none), and,
//! against the truth without it, the size (scale 1 against the largest scale, where the
//! surface is flat over a mean free path: curvature and thin parts), the angles (the largest
//! scale against the half-space lit and seen head-on: the incidence and exit directions of
//! that scene's light and view, single scattering's lobe among them) and the profile with
//! its boundary terms (the half-space head-on, what is left when geometry and angles match
//! the table's own set-up). `--quick` runs a few rows at low precision.
//!
//! Writes `deficit.csv` (columns in `docs/compare.md`), `deficit_<group>.png`/`.svg` (the
//! ratio against the swept quantity, per channel) and `deficit/<row>.toml`, each flat set-up's
//! scene file, so a row can be rendered again with `sss render`.

mod measure;
mod report;
mod setups;
#[cfg(test)]
mod tests;

use super::plan::with_albedo_weights;
use super::volpath_reference::interior;
use super::{Context, Error, Experiment, Section};
use measure::{Mean, measure};
use report::{DeficitRow, deficit_csv, section, write_plots};
use setups::{Kind, Setup, setups};
use sss_bssrdf::{ModelKind, Rgb};
use sss_render::integrators::Integrator;
use sss_render::integrators::pathtrace::PathTrace;
use sss_render::integrators::volpath::{Scattering, VolPath};
use sss_render::progress::NoProgress;
use sss_render::scene::{self, LoadOptions, MaterialKind, Scene, SceneError, SceneErrorKind};
use sss_render::{RenderSettings, render};
use std::path::PathBuf;
use std::time::Instant;

/// The model the deficit is measured for: the crate's own random walk, tabulated (it matches
/// MCML within 1 % on the half-space, so what it misses is the set-up, not the profile's
/// numbers).
pub const MODEL: ModelKind = ModelKind::McTable;

/// What one run measures.
#[derive(Clone, Debug)]
pub(crate) struct DeficitPlan {
    /// The rows.
    pub setups: Vec<Setup>,
    /// Relative standard error each image mean aims for.
    pub target: f64,
    /// `volpath`'s pilot and most paths per pixel.
    pub volpath_spp: (u32, u32),
    /// `pathtrace`'s pilot and most BSSRDF samples per pixel.
    pub pathtrace_spp: (u32, u32),
    /// The truth scenes' resolution is divided by this.
    pub shrink: u32,
    /// The flat set-ups' image side, pixels.
    pub flat_pixels: u32,
}

/// The plan of a full run (about 20 minutes on 2 cores) or of `--quick` (a few rows at 3 %).
pub(crate) fn plan(quick: bool) -> DeficitPlan {
    if quick {
        DeficitPlan {
            setups: setups(true),
            target: 0.03,
            volpath_spp: (4, 256),
            pathtrace_spp: (4, 256),
            shrink: 4,
            flat_pixels: 16,
        }
    } else {
        DeficitPlan {
            setups: setups(false),
            target: 0.003,
            volpath_spp: (16, 16384),
            pathtrace_spp: (16, 4096),
            shrink: 2,
            flat_pixels: 32,
        }
    }
}

/// The deficit experiment.
pub struct DeficitExperiment;

impl Experiment for DeficitExperiment {
    fn name(&self) -> &'static str {
        "deficit"
    }

    fn run(&self, ctx: &Context<'_>) -> Result<Section, Error> {
        let cfg = ctx.config;
        let plan = plan(cfg.quick);
        let dir = cfg.out.join("deficit");
        std::fs::create_dir_all(&dir)
            .map_err(|e| Error(format!("cannot create {}: {e}", dir.display())))?;
        let mut rows = Vec::new();
        let mut skipped = Vec::new();
        let total = plan.setups.len();
        for (i, setup) in plan.setups.iter().enumerate() {
            let name = setup.name();
            let scene = match setup.scene(MODEL, plan.shrink, plan.flat_pixels, &cfg.mesh_dirs) {
                Ok(s) => s,
                Err(e) if e.kind == SceneErrorKind::MeshNotFound => {
                    (ctx.log)(&format!("deficit {name}: skipped ({e})"));
                    if !skipped
                        .iter()
                        .any(|s: &String| s.starts_with(&format!("`{}`", setup.group)))
                    {
                        skipped.push(format!(
                            "`{}`: {e} (set SSS_MESH_DIR to the shared meshes)",
                            setup.group
                        ));
                    }
                    continue;
                }
                Err(e) => return Err(Error(format!("deficit {name}: {e}"))),
            };
            if let Some(text) = setup.text(plan.flat_pixels) {
                sss_util::write_atomic(&dir.join(format!("{name}.toml")), text.as_bytes())
                    .map_err(|e| Error(format!("deficit {name}: {e}")))?;
            }
            let volpath = |scattering: Scattering| {
                move |spp: u32| -> Box<dyn Integrator> {
                    Box::new(VolPath {
                        spp,
                        scattering,
                        ..VolPath::default()
                    })
                }
            };
            let all = volpath(Scattering::All);
            let single = volpath(Scattering::Single);
            let pathtrace = |spp: u32| -> Box<dyn Integrator> {
                Box::new(PathTrace {
                    spp,
                    ..PathTrace::default()
                })
            };
            let (truth, _) = measure(&scene, &all, plan.volpath_spp, plan.target, cfg.seed)?;
            // The truth without the light traded between the object's parts, where it has
            // parts that see each other.
            let direct = if setup.trades_light() {
                let without = |spp: u32| -> Box<dyn Integrator> {
                    Box::new(VolPath {
                        spp,
                        reentry: false,
                        ..VolPath::default()
                    })
                };
                Some(
                    measure(
                        &scene,
                        &without,
                        plan.volpath_spp,
                        plan.target,
                        cfg.seed + 3,
                    )?
                    .0,
                )
            } else {
                None
            };
            let (single, _) =
                measure(&scene, &single, plan.volpath_spp, plan.target, cfg.seed + 2)?;
            let (model, pixels) = measure(
                &scene,
                &pathtrace,
                plan.pathtrace_spp,
                plan.target,
                cfg.seed + 1,
            )?;
            // The same model with the half-space's directional albedo for its angular factors.
            let mut weighted = scene.clone();
            with_albedo_weights(&mut weighted);
            let (albedo, _) = measure(
                &weighted,
                &pathtrace,
                plan.pathtrace_spp,
                plan.target,
                cfg.seed + 1,
            )?;
            let row = DeficitRow {
                setup: setup.clone(),
                truth,
                single,
                direct,
                model,
                albedo,
                pixels: pixels.len(),
            };
            let three = |q: [Option<(f64, f64)>; 3]| {
                q.map(|v| v.map_or("-".to_string(), |(x, _)| format!("{x:.3}")))
                    .join(" / ")
            };
            (ctx.log)(&format!(
                "deficit [{}/{total}] {name}: {} / truth = {}, with angular = albedo {} \
                 (volpath {} paths, {:.1} s; pathtrace {} samples, {:.1} s)",
                i + 1,
                MODEL.name(),
                three(row.ratio()),
                three(row.albedo_ratio()),
                truth.spp,
                truth.seconds,
                model.spp,
                model.seconds,
            ));
            rows.push(row);
        }
        deficit_csv(&rows).write(&cfg.out.join("deficit.csv"))?;
        write_plots(&cfg.out, &rows)?;
        Ok(section(&rows, &skipped, &plan))
    }
}
