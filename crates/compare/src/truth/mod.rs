//! `cargo xtask compare --truth`: every BSSRDF model scored against real light transport.
//!
//! The reference of each case is `volpath` (volumetric path tracing of the medium in the mesh,
//! checked against Mitsuba 3 and MCML in the render crate's tests), rendered until its own
//! relative noise is below the plan's target and cached ([`reference`]). Against it, on the
//! same pixels ([`runs`]):
//! - every model under `exact` (its sum) and under `pathtrace` (the integral that sum
//!   discretises, its own noise removed: the model's floor against the truth);
//! - the fast methods (`dual-tree-fmm`, `manylight`, `separable`) over their sweeps, with
//!   `mc-table`, and `dual-tree-fmm` with each point's own ball too
//!   (`mc-table+albedo+local`), and with one bounce of the light the surfaces trade and the
//!   light refracted through the objects without a collision
//!   (`mc-table+albedo+local+bounce+unscattered`);
//! - `volpath` at increasing paths per pixel, with another seed, on the same axes, so the
//!   report reads off for each method and model the time at which brute force reaches the same
//!   error ([`Crossover`]).
//!
//! Scores ([`scoring`]): the image mean per channel over the reference's, and the relative
//! RMSE over the translucent pixels with the reference's own noise removed. Cases
//! ([`plan`](mod@plan)): a 10 mm sphere in skin1, marble, ketchup and an absorbing medium, a
//! 3 mm sphere, the bunny, the head and the dragon (the meshes from the shared meshes, each
//! skipped with a message when absent), under a quad light or a uniform environment; `--quick`
//! runs the 10 mm skin1 sphere alone at half resolution.
//!
//! With `--peers`, Mitsuba 3 and Blender Cycles render every case too ([`peers`]), scored the
//! same way.
//!
//! Writes `truth.csv` (columns in `docs/compare.md`), `truth_error_vs_time_<case>.png` and
//! under `truth/<case>/` the pictures ([`images`]).
//!
//! `--deficit` ([`deficit`]) uses the same media and scenes to measure where the models'
//! error against this truth comes from.

pub(crate) mod deficit;
mod images;
mod peers;
mod plan;
mod report;
mod runs;
mod scoring;
#[cfg(test)]
mod tests;
mod volpath_reference;

use super::checked::{self, Entry, fnv1a64};
use super::output::{Csv, csv_num, csv_text, md_num, md_pct, md_table};
use super::{Context, Error, Experiment, Section};
use images::{SIGNED_RANGE, write_pictures, write_plot};
use peers::{Peers, run_peers};
use plan::{
    Case, Plan, plan, with_albedo_weights, with_ball_profile, with_drift, with_local_balls,
    with_unscattered,
};
use report::{CaseResult, section, truth_csv};
use runs::{
    BOUNCE_FAST_MODEL, EXACT_SAMPLES, FAST, FAST_MODEL, LOCAL_FAST, LOCAL_FAST_MODEL,
    PATHTRACE_SPP, TruthRun, run_case,
};
use scoring::{Crossover, Score, score, score_without_noise};
use sss_bssrdf::{Medium, ModelKind, Rgb};
use sss_plot::{PALETTE, Series, SeriesStyle, write_signed_map};
use sss_render::image::{auto_exposure, write_png};
use sss_render::integrators::exact::{Exact, reference_spacing};
use sss_render::integrators::pathtrace::PathTrace;
use sss_render::integrators::volpath::VolPath;
use sss_render::integrators::{self, MethodOptions};
use sss_render::irradiance::IrradianceSettings;
use sss_render::progress::NoProgress;
use sss_render::scene::{
    self, Angular, Light, LoadOptions, MaterialKind, Scene, SceneError, SceneErrorKind,
};
use sss_render::{RenderOutput, RenderSettings, render};
use sss_util::luminance;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;
use volpath_reference::{Truth, reference};

/// The truth experiment.
pub struct TruthExperiment;

impl Experiment for TruthExperiment {
    fn name(&self) -> &'static str {
        "truth"
    }

    fn run(&self, ctx: &Context<'_>) -> Result<Section, Error> {
        let cfg = ctx.config;
        let plan = plan(cfg.quick);
        let mut results = Vec::new();
        let mut skipped = Vec::new();
        let peers = cfg.peers.then(Peers::find);
        if let Some(p) = &peers {
            for n in p.notes() {
                (ctx.log)(&format!("truth: peers: {n}"));
            }
        }
        for case in &plan.cases {
            let name = case.name();
            let scene = match case.scene(FAST_MODEL, plan.shrink, &cfg.mesh_dirs) {
                Ok(s) => s,
                Err(e) if e.kind == SceneErrorKind::MeshNotFound => {
                    (ctx.log)(&format!("truth {name}: skipped ({e})"));
                    skipped.push(format!(
                        "`{name}`: {e} (set SSS_MESH_DIR to the shared meshes)"
                    ));
                    continue;
                }
                Err(e) => return Err(Error(format!("truth {name}: {e}"))),
            };
            let truth = reference(ctx, case, &scene, &plan)?;
            let mut runs = run_case(ctx, case, &plan, &truth)?;
            if let Some(p) = &peers {
                let dir = cfg.out.join("truth").join(&name).join("peers");
                runs.runs
                    .extend(run_peers(ctx, p, case, &scene, &plan, &truth, &dir)?);
            }
            let sweep: Vec<(u32, f64, f64, f64)> = runs
                .runs
                .iter()
                .filter(|r| r.method == "volpath" && r.renderer == "sss")
                .map(|r| (r.value as u32, r.seconds, r.shading, r.score.rel_rmse))
                .collect();
            let crossover = Crossover::fit(&sweep);
            write_pictures(
                &cfg.out.join("truth").join(&name),
                &name,
                &truth,
                &runs.model_images,
                cfg.exposure,
            )?;
            write_plot(
                &cfg.out.join(format!("truth_error_vs_time_{name}.png")),
                &name,
                &runs.runs,
            )?;
            results.push(CaseResult {
                case: name,
                truth,
                runs: runs.runs,
                crossover,
                unsupported: runs.unsupported,
            });
        }
        truth_csv(&results).write(&cfg.out.join("truth.csv"))?;
        let notes = peers.map(|p| p.notes()).unwrap_or_default();
        Ok(section(
            &results,
            &skipped,
            &notes,
            rayon::current_num_threads(),
        ))
    }
}
