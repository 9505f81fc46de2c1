//! `cargo xtask compare --trees`: the paper-scale experiments of Milaenen et al. 2019 on our
//! machine — the single tree (Jensen & Buhler 2002) against the paper's dual tree and the
//! dual tree with local expansions (`dual-tree-fmm`) on the full-resolution Stanford bunny
//! (`stanford-bunny.obj` from the shared meshes; skipped with a message when absent):
//!
//! 1. RMSE against total time over ε ∈ [0.01, 0.2] for the single tree and the paper's dual
//!    tree at ρ = 0.75, a ρ sweep of the latter, and `dual-tree-fmm` over ε ∈ [0.005, 0.2],
//!    at 1024² (Fig. 6);
//! 2. the stage breakdown per ε on one thread at 1024² (Table 1);
//! 3. scaling with the pixel count, 256² to 2048², at ε = 0.05 (all three);
//! 4. pictures: s_p, the pixel clusters (Fig. 5), each method's relative difference from
//!    the finest single-tree image, and the paper's dual tree's beside `dual-tree-fmm`'s at
//!    equal time.
//!
//! Error is measured against `exact` (the point sum both trees approximate, over the same
//! irradiance samples) on a seeded uniform random subset of
//! [`super::subset::SUBSET_PIXELS`] translucent pixels: the subset's mean squared error is an
//! unbiased estimate of the whole image's, reported with its standard error
//! (finite-population corrected). The subset reference is cached like the
//! scene references.
//!
//! Writes `trees.csv`, `trees_error_vs_time.png`, `trees_scaling.png` and `trees/*.png`
//! under the output directory.

mod plan;
mod plots;
mod report;
mod runs;
mod scoring;
#[cfg(test)]
mod tests;

use super::output::{Csv, csv_num, csv_text, md_num, md_table};
use super::subset::{SubsetReference, subset_reference};
use super::{Context, Error, Experiment, Section};
use plan::*;
use plots::*;
use report::*;
use runs::*;
use scoring::*;
use sss_bssrdf::Rgb;
use sss_plot::{PALETTE, Series, SeriesStyle, line_plot, write_error_map};
use sss_render::integrators::Integrator;
use sss_render::integrators::dual_tree::DualTree;
use sss_render::integrators::dual_tree_fmm::DualTreeFmm;
use sss_render::integrators::exact::reference_spacing;
use sss_render::integrators::single_tree::SingleTree;
use sss_render::irradiance::IrradianceSettings;
use sss_render::progress::NoProgress;
use sss_render::scene::{self, LoadOptions, Scene, SceneErrorKind};
use sss_render::{RenderOutput, RenderSettings, render};
use std::fmt::Write as _;

/// The trees experiment.
pub struct TreeExperiment;

impl Experiment for TreeExperiment {
    fn name(&self) -> &'static str {
        "trees"
    }

    fn run(&self, ctx: &Context<'_>) -> Result<Section, Error> {
        let cfg = ctx.config;
        let title = "Trees: single (Jensen & Buhler) against dual (Milaenen et al.; local \
                     expansions) at paper scale";
        let opts = LoadOptions {
            mesh_dirs: cfg.mesh_dirs.clone(),
        };
        let base = match scene::load_str(BUNNY, "bunny-paper.toml", None, &opts) {
            Ok(s) => s,
            Err(e) if e.kind == SceneErrorKind::MeshNotFound => {
                (ctx.log)(&format!("trees: skipped ({e})"));
                return Ok(Section {
                    title: title.into(),
                    summary: format!("Skipped: {e} (set SSS_MESH_DIR to the shared meshes).\n"),
                    body: String::new(),
                });
            }
            Err(e) => return Err(Error(e.to_string())),
        };
        let p = plan(cfg.quick);
        // The trees sum over the reference's own irradiance samples.
        let irr = IrradianceSettings {
            spacing_mfp: reference_spacing(cfg.quick),
            ..IrradianceSettings::default()
        };
        let threads = rayon::current_num_threads();
        let mut runs: Vec<TreeRun> = Vec::new();
        let mut refs: Vec<(u32, SubsetReference)> = Vec::new();
        let mut resolutions = p.resolutions.clone();
        if !resolutions.contains(&p.sweep_resolution) {
            resolutions.push(p.sweep_resolution);
        }
        for &res in &resolutions {
            let s = at_resolution(&base, res);
            refs.push((res, subset_reference(ctx, &s, BUNNY)?));
        }
        let reference = |res: u32| &refs.iter().find(|r| r.0 == res).expect("computed").1;
        let mut go = |experiment: &'static str,
                      res: u32,
                      m: &dyn Integrator,
                      eps: f64,
                      rho: Option<f64>,
                      threads: usize|
         -> Result<(), Error> {
            (ctx.log)(&format!(
                "trees: {experiment} {}² {} ε={eps}{} ({threads} thread(s))",
                res,
                m.name(),
                rho.map_or(String::new(), |r| format!(" ρ={r}"))
            ));
            let s = at_resolution(&base, res);
            let out = run_on(&s, m, cfg.seed, threads)?;
            let score = score(&out.subsurface, reference(res))?;
            runs.push(TreeRun {
                experiment,
                resolution: res,
                method: m.name(),
                eps,
                rho,
                threads,
                out,
                score,
            });
            Ok(())
        };
        let single = |eps| SingleTree {
            irradiance: irr,
            eps,
        };
        let dual = |eps, rho| DualTree {
            irradiance: irr,
            eps,
            rho,
        };
        let fmm = |eps| DualTreeFmm {
            irradiance: irr,
            eps,
            ..DualTreeFmm::default()
        };
        let sr = p.sweep_resolution;
        // 1. ε sweeps (all three) and ρ sweep (the paper's dual tree).
        for &eps in &p.eps {
            go("eps", sr, &single(eps), eps, None, threads)?;
            go("eps", sr, &dual(eps, RHO), eps, Some(RHO), threads)?;
        }
        for &eps in &p.fmm_eps {
            go("eps", sr, &fmm(eps), eps, None, threads)?;
        }
        for &rho in &p.rhos {
            go(
                "rho",
                sr,
                &dual(FIXED_EPS, rho),
                FIXED_EPS,
                Some(rho),
                threads,
            )?;
        }
        // 2. Table 1 on one thread: the dual tree at each ε (as the paper), the single tree at
        // the middle one for comparison.
        for &eps in &p.table_eps {
            go("table1", sr, &dual(eps, RHO), eps, Some(RHO), 1)?;
        }
        go("table1", sr, &single(FIXED_EPS), FIXED_EPS, None, 1)?;
        go("table1", sr, &fmm(FIXED_EPS), FIXED_EPS, None, 1)?;
        // 3. Scaling (the sweep resolution's runs at FIXED_EPS are the sweep's own).
        for &res in p.resolutions.iter().filter(|&&r| r != sr) {
            go("scaling", res, &single(FIXED_EPS), FIXED_EPS, None, threads)?;
            go(
                "scaling",
                res,
                &dual(FIXED_EPS, RHO),
                FIXED_EPS,
                Some(RHO),
                threads,
            )?;
            go("scaling", res, &fmm(FIXED_EPS), FIXED_EPS, None, threads)?;
        }
        csv(&runs).write(&cfg.out.join("trees.csv"))?;
        pictures(ctx, &runs, sr)?;
        plots(ctx, &runs, &p)?;
        Ok(report(&runs, &p, &refs, threads))
    }
}
