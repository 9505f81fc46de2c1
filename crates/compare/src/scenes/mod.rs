//! The rendering experiment: every registered method (`sss_render::integrators::METHODS`) over
//! its compare sweep on the default scenes (and any named ones), against a cached `exact`
//! reference per scene.
//!
//! Files: [`plan`](mod@plan) (the sweep as units), [`load`] (scenes), [`cache`] (references),
//! [`runs`] (timed runs, `results.csv`, records), [`images`] (pictures), [`report`]
//! (`results.csv`, the plots and the report section from the units' results, [`assemble`]);
//! this one runs a list of units ([`run_units`]). An unsharded run plans, runs and assembles
//! in one process; `--shard` runs a share of the units and `--merge` assembles the shards'
//! results (see `super::shard`).
//!
//! Writes `results.csv` (one row per run and thread count; columns documented in
//! `docs/compare.md`), `error_vs_time_<scene>.png` (log-log RMSE against total seconds), and
//! under `scenes/<scene>/` the reference, each method's most expensive render, its
//! false-colour error map and its HDR-FLIP map.

mod cache;
mod images;
mod load;
mod plan;
mod report;
mod runs;
#[cfg(test)]
mod tests;

pub(super) use cache::{reference, reference_method};
pub use load::default_mesh_dirs;
pub(super) use load::load_scenes;
pub(super) use plan::{PlanOutline, SceneInfo, ScenePlan, SweepUnit, plan, swept};
pub(super) use report::assemble;
pub(super) use runs::{Run, UnitResult, escape, unescape};

use super::host::Host;
use super::output::{md_num, md_pct, md_table};
use super::{Context, Error, Experiment, Section};
use cache::Reference;
use images::write_images;
use runs::{Outcome, results_csv, run_timed};
use sss_plot::{PALETTE, Series, SeriesStyle, line_plot};
use sss_render::RenderSettings;
use sss_render::flip::{FlipParams, hdr_flip};
use sss_render::image::{exposure_or_auto, write_png};
use sss_render::integrators::exact::reference_spacing;
use sss_render::integrators::{Converges, METHODS, Method, MethodOptions};
use sss_render::metrics::{error_figures, frac_within_se, mean_ratio};
use sss_render::scene::Scene;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Relative-error threshold of `frac_within_eps`.
pub const EPS: f64 = 0.05;

/// The rendering experiment.
pub struct SceneComparison;

impl Experiment for SceneComparison {
    fn name(&self) -> &'static str {
        "scenes"
    }

    fn run(&self, ctx: &Context<'_>) -> Result<Section, Error> {
        let plan = plan(ctx)?;
        let all: Vec<usize> = (0..plan.units.len()).collect();
        let (infos, results) = run_units(ctx, &plan, &all)?;
        let mut info: Vec<Option<SceneInfo>> = vec![None; plan.scenes.len()];
        for (i, s) in infos {
            info[i] = Some(s);
        }
        let results: Vec<UnitResult> = results.into_iter().map(|(_, r)| r).collect();
        assemble(ctx, &plan.outline(), &info, &results)
    }
}

/// A scene made ready for its units: the reference, the pixels scored, the exposure of its
/// pictures and their directory.
struct Prepared {
    info: SceneInfo,
    reference: Reference,
    pixels: Vec<usize>,
    exposure: f64,
    dir: PathBuf,
}

/// Loads (or renders) the reference of `scene` and writes its pictures.
fn prepare(ctx: &Context<'_>, scene: &Scene, text: &str) -> Result<Prepared, Error> {
    let reference = reference(ctx, scene, text)?;
    let pixels: Vec<usize> = (0..reference.coverage.len())
        .filter(|&i| reference.coverage[i] > 0.0)
        .collect();
    let dir = ctx.config.out.join("scenes").join(&scene.name);
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error(format!("cannot create {}: {e}", dir.display())))?;
    let exposure = exposure_or_auto(ctx.config.exposure, &reference.subsurface);
    let e = |e: sss_render::Error| Error(e.to_string());
    write_png(
        &dir.join("reference.png"),
        scene.camera.width,
        scene.camera.height,
        &reference.subsurface,
        exposure,
    )
    .map_err(e)?;
    write_png(
        &dir.join("reference_total.png"),
        scene.camera.width,
        scene.camera.height,
        &reference.total,
        exposure_or_auto(ctx.config.exposure, &reference.total),
    )
    .map_err(e)?;
    Ok(Prepared {
        info: SceneInfo {
            width: scene.camera.width,
            height: scene.camera.height,
            pixels: pixels.len(),
            samples: reference.samples,
            seconds: reference.seconds,
            threads: rayon::current_num_threads(),
        },
        reference,
        pixels,
        exposure,
        dir,
    })
}

/// Scene infos (by scene index) and unit results (by unit index) of a list of units.
pub(super) type UnitsDone = (Vec<(usize, SceneInfo)>, Vec<(usize, UnitResult)>);

/// Runs the units `which` (indices into `plan.units`, in increasing order) and returns the
/// info of every scene they touched and each unit's result. A scene's reference is loaded (or
/// rendered) when its first unit runs. Once a method is unsupported on a scene, its later units
/// there are not run and give the same reason.
pub(super) fn run_units(
    ctx: &Context<'_>,
    plan: &ScenePlan,
    which: &[usize],
) -> Result<UnitsDone, Error> {
    let cfg = ctx.config;
    let all_threads = rayon::current_num_threads();
    let host = Host::this();
    let settings = RenderSettings {
        seed: cfg.seed,
        ..RenderSettings::default()
    };
    let mut infos: Vec<(usize, SceneInfo)> = Vec::new();
    let mut results: Vec<(usize, UnitResult)> = Vec::new();
    let mut current: Option<(usize, Prepared)> = None;
    let mut unsupported: Vec<((usize, usize), String)> = Vec::new();
    for &ui in which {
        let unit = plan.units[ui];
        let (scene, text) = &plan.scenes[unit.scene];
        if current.as_ref().is_none_or(|(i, _)| *i != unit.scene) {
            let p = prepare(ctx, scene, text)?;
            infos.push((unit.scene, p.info.clone()));
            current = Some((unit.scene, p));
        }
        let Some((_, prepared)) = current.as_ref() else {
            unreachable!("prepared above");
        };
        if let Some((_, why)) = unsupported
            .iter()
            .find(|(k, _)| *k == (unit.scene, unit.method))
        {
            results.push((ui, UnitResult::Unsupported(why.clone())));
            continue;
        }
        let m = &METHODS[unit.method];
        let values = (m.sweep.values)(cfg.quick);
        let v = values[unit.value];
        let counts: &[usize] = if unit.with_one_thread(cfg.quick) && all_threads > 1 {
            &[all_threads, 1]
        } else {
            &[all_threads]
        };
        let mut runs: Vec<Run> = Vec::new();
        let mut why_not = None;
        for &threads in counts {
            let label = format!("{} {}={v}", m.name, m.sweep.label);
            (ctx.log)(&format!(
                "scene {}: {label} ({threads} thread(s))",
                scene.name
            ));
            // Point-based methods sweeping another option sum over the reference's own
            // irradiance samples, so their error is their approximation's alone.
            let mut options = MethodOptions::new().with(m.sweep.option, v);
            if m.sweep.option != "spacing" && m.options.iter().any(|o| o.name == "spacing") {
                options = options.with("spacing", reference_spacing(cfg.quick));
            }
            let method = (m.build)(&options).map_err(|e| Error(format!("{label}: {e}")))?;
            let out = match run_timed(method.as_ref(), scene, &settings, threads, &label)? {
                Outcome::Done(out) => out,
                Outcome::Unsupported(why) => {
                    (ctx.log)(&format!("scene {}: {} skipped: {why}", scene.name, m.name));
                    why_not = Some(why);
                    break;
                }
            };
            for w in &out.warnings {
                (ctx.log)(&format!("scene {}: {label}: warning: {w}", scene.name));
            }
            let reference = &prepared.reference.subsurface;
            let pixels = &prepared.pixels;
            let f = error_figures(&out.subsurface, reference, pixels, EPS);
            // A unit's runs give the same image whatever their threads: FLIP on the first,
            // the others take its mean.
            let map = runs.is_empty().then(|| {
                hdr_flip(
                    &out.subsurface,
                    reference,
                    out.width as usize,
                    out.height as usize,
                    &FlipParams::default(),
                )
            });
            let flip = map.as_ref().map_or_else(|| runs[0].flip, |m| m.mean);
            if threads == all_threads
                && unit.value + 1 == values.len()
                && let Some(map) = &map
            {
                write_images(
                    &prepared.dir,
                    &format!("{}_{}", m.name, v),
                    &out,
                    (reference, pixels),
                    &map.map,
                    prepared.exposure,
                )?;
            }
            runs.push(Run {
                scene: scene.name.clone(),
                method: m.name,
                param: m.sweep.label,
                value: v,
                threads,
                host: host.clone(),
                stages: out.stages.clone(),
                rmse: f.rmse,
                rel_rmse: f.rel_rmse,
                frac_within_eps: f.frac_within_eps,
                within_3se: out
                    .std_error
                    .as_ref()
                    .and_then(|se| frac_within_se(&out.subsurface, se, reference, pixels, 3.0)),
                mean_ratio: mean_ratio(&out.subsurface, reference, pixels),
                flip,
                warnings: out.warnings.clone(),
            });
        }
        match why_not {
            Some(why) => {
                unsupported.push(((unit.scene, unit.method), why.clone()));
                results.push((ui, UnitResult::Unsupported(why)));
            }
            None => results.push((ui, UnitResult::Runs(runs))),
        }
    }
    Ok((infos, results))
}
