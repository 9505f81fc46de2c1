//! `cargo xtask compare --manylight`: the claims of Nabata & Iwasaki 2021 measured on our
//! machine against an independent reference, on scenes after the paper's built from the shared
//! meshes (each skipped with a message when its mesh is absent): a Buddha in skin, two Buddhas
//! in skim milk and marble, and a head, each under a quad light of [`VPLS`] VPLs with 16
//! shading points per pixel (4 with `--quick`); a variant of each lit by one point light at
//! the quad's centre with 4 shading points per pixel ([`Lighting::Point`]); and, lit that way,
//! a scanned dragon in skin1 with the standard dipole (thin claws, deep folds: [`DRAGON`]).
//!
//! 1. **Bias**: each method's image mean (the summed luminance over the scored subset) over
//!    the reference's, with its standard error ([`Score::bias`]); for manylight also with the
//!    paper's final estimate (`manylight-paper`: the samples the stopping test saw, at
//!    ε ≥ 5 %, where its sequential-stopping bias shows) beside ours (new samples of the final
//!    triplets, `sss_manylight::Settings::fresh_final`).
//! 2. **Estimation accuracy** (Table 1, Fig. 10): the fraction of pixels whose relative error
//!    (of the luminance) is below ε, at ε ∈ {10, 5, 2, 1} % and α = 95 %, over a seeded
//!    uniform subset of translucent pixels and several estimator streams.
//! 3. **BSSRDF-aware against Max-Extent selection** (Table 3): triplets and time at ε = 2 %.
//! 4. **VPL count** (Fig. 9): time and triplets at ×½ … ×8 the VPLs, and **mesh refinement**:
//!    the same at 4× and 16× the triangles (midpoint subdivision), on the first scene.
//! 5. **Pictures** (Fig. 7): the first scene, and its triplets per pixel with each selection.
//! 6. **Against the baselines** (Table 1, Fig. 6): MDLC and EELC on the same VPLs, subset and
//!    reference, each with BSSRDF importance-sampled irradiance points (probe rays, "IS") and
//!    with uniform ones, over a sweep of the points per shading point N at ε = 2 %
//!    ([`Plan::points_is`], [`Plan::points_uniform`]) on the paper's scenes and at
//!    [`Plan::eelc_points`] elsewhere: RMSE against time per scene, and Table 1's equal
//!    quality (the time each needs to reach ours' RMSE at ε = 2 %, log-log interpolated along
//!    its sweep, [`equal::time_to_reach`]) and equal time (its RMSE at ours' time,
//!    [`equal::error_at_time`]); and EELC's estimation accuracy at the ε of item 2 with
//!    [`Plan::eelc_points`] points (Fig. 10). With N points per shading point the baselines
//!    converge, as ε → 0, to their point set's value, whose error is the N-point Monte Carlo
//!    noise (∝ N^−½): N bounds the error they can reach at any ε; at a fixed ε their own
//!    estimate's error (EELC's about ours' at the same ε) bounds it at any N.
//!
//! **The reference** ([`reference()`]) is the path tracer on the subset pixels, with the paths
//! each pixel needs for a relative standard error of [`Budget::target_rel_se`] (and the finer
//! [`Budget::fine_rel_se`] on the first [`Budget::fine_pixels`] of the seeded subset): no VPLs,
//! clusters, bounds or stopping rule, so it can show a bias of the many-light estimator, which a
//! reference rendered by the method itself (the paper's, at ε = 0.1 %) cannot. A pixel is
//! scored at ε only where the reference's own standard error is at most ε/4. Against a quad
//! light the reference also counts the VPLs' discretisation of the light as error.
//!
//! **One integral.** The camera samples (hence the shading points) and the VPLs are drawn from
//! the run's seed for the reference and for every run alike; runs differ only in the
//! estimator's random stream (`ManyLight::stream`, the `seed` column of the CSV). Without
//! that, two renders estimate different pixel values (a pixel's 16 jittered camera samples and
//! the jittered VPL grid move with the seed), and the measured "accuracy" falls to 50–70 %
//! whatever the estimator does.
//!
//! Every run is timed with its frame set-up (G-buffer, VPLs, triangle BVHs) included.
//!
//! Writes `manylight.csv` (one row per run, column `method`: `manylight`, `mdlc-is`,
//! `mdlc-uniform`, `eelc-is`, `eelc-uniform`), `manylight_accuracy.png`,
//! `manylight_vpls.png`, `manylight_rmse_<scene>.png` and `manylight/*.png` under the output
//! directory.

mod equal;
mod pathtraced;
mod plan;
mod plots;
mod report;
mod runs;
mod scoring;
pub(super) mod sparse;
#[cfg(test)]
mod tests;

use super::output::{Csv, csv_num, csv_text, md_num, md_table};
use super::{Context, Error, Experiment, Section};
use equal::{Reach, error_at_time, extrapolated_time, time_to_reach};
use pathtraced::{Budget, Reference, path_reference};
use plan::*;
use plots::*;
use report::*;
use runs::*;
use scoring::*;
use sss_manylight::Selection;
use sss_plot::{PALETTE, Series, SeriesStyle, line_plot, write_error_map};
use sss_render::frame::Frame;
use sss_render::integrators::eelc::Eelc;
use sss_render::integrators::exact::translucent_pixels;
use sss_render::integrators::manylight::{ManyLight, PixelResult};
use sss_render::integrators::mdlc::Mdlc;
use sss_render::integrators::vpl::gather_points::PointOptions;
use sss_render::metrics::subset_pixels;
use sss_render::progress::NoProgress;
use sss_render::scene::{self, Light, LoadOptions, Scene, SceneErrorKind};
use sss_render::{RenderSettings, render};
use sss_separable::erf;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::time::Instant;

/// One row of `manylight.csv`: a method's estimates of one scene's subset.
#[derive(Clone, Debug)]
pub(super) struct Row {
    pub(super) scene: &'static str,
    pub(super) experiment: &'static str,
    /// [`Variant::label`].
    pub(super) method: &'static str,
    pub(super) selection: &'static str,
    pub(super) eps: f64,
    /// Irradiance points per shading point (0 for ours).
    pub(super) points: u32,
    pub(super) vpls: u32,
    pub(super) triangles: usize,
    pub(super) seed: u64,
    pub(super) seconds: f64,
    /// Pixels scored at this row's ε ([`Score::scored`]).
    pub(super) pixels: usize,
    pub(super) mean_triplets: f64,
    /// [`Score::accuracy`].
    pub(super) accuracy: f64,
    /// RMSE over the subset (pixels and channels).
    pub(super) rmse: f64,
    /// [`Score::bias`].
    pub(super) bias: f64,
    /// [`Score::bias_se`].
    pub(super) bias_se: f64,
    /// Pixels that stopped at a cap.
    pub(super) capped: u64,
    /// Pixel estimates that stopped at the dark-pixel floor.
    pub(super) floored: u64,
}

pub(super) fn selection_name(s: Selection) -> &'static str {
    match s {
        Selection::BssrdfAware => "bssrdf",
        Selection::MaxExtent => "max-extent",
    }
}

/// The manylight experiment.
pub struct ManyLightExperiment;

impl Experiment for ManyLightExperiment {
    fn name(&self) -> &'static str {
        "manylight"
    }

    fn run(&self, ctx: &Context<'_>) -> Result<Section, Error> {
        let cfg = ctx.config;
        let p = plan(cfg.quick);
        let mut rows: Vec<Row> = Vec::new();
        let mut refs: Vec<(&'static str, Reference, usize)> = Vec::new();
        let mut skipped: Vec<String> = Vec::new();
        let dir = cfg.out.join("manylight");
        std::fs::create_dir_all(&dir)
            .map_err(|e| Error(format!("cannot create {}: {e}", dir.display())))?;
        for spec in &p.scenes {
            let name = spec.name;
            let Some(scene) = load(ctx, spec, &p)? else {
                skipped.push(name.into());
                continue;
            };
            let r = reference(ctx, &scene, &p)?;
            let tri = triangles(&scene);
            let run = |m: &Variant,
                       sc: &Scene,
                       experiment: &'static str,
                       seed: u64,
                       rows: &mut Vec<Row>|
             -> Result<(), Error> {
                (ctx.log)(&format!(
                    "manylight: {name} {experiment} {} ε={} N={} {} VPLs {} seed {seed}",
                    m.label(),
                    m.eps(),
                    m.points(),
                    m.vpls(),
                    m.selection()
                ));
                let (out, seconds) = shade(ctx, sc, m, &r.pixels, seed)?;
                let got = score(&out, &r, m.eps());
                let n = out.len().max(1) as f64;
                rows.push(Row {
                    scene: name,
                    experiment,
                    method: m.label(),
                    selection: m.selection(),
                    eps: m.eps(),
                    points: m.points(),
                    vpls: m.vpls(),
                    triangles: triangles(sc),
                    seed,
                    seconds,
                    pixels: got.scored,
                    mean_triplets: out.iter().map(|o| o.triplets).sum::<f64>() / n,
                    accuracy: got.accuracy,
                    rmse: got.rmse,
                    bias: got.bias,
                    bias_se: got.bias_se,
                    capped: out
                        .iter()
                        .map(|o| o.summary.triplet_cap + o.summary.split_cap)
                        .sum(),
                    floored: out.iter().map(|o| o.summary.floor).sum(),
                });
                Ok(())
            };
            let ours = |eps: f64| {
                Variant::Ours(ManyLight {
                    eps,
                    ..base(ctx, VPLS)
                })
            };
            // 1. Accuracy against ε.
            for &eps in &p.eps {
                for k in 0..p.seeds {
                    run(&ours(eps), &scene, "accuracy", cfg.seed + 1 + k, &mut rows)?;
                }
            }
            // 1b. The paper's final estimate (the samples the stopping test saw) at the loose
            // ε, where its sequential-stopping bias shows, on the same streams.
            for &eps in p.eps.iter().filter(|&&e| e >= 0.05) {
                for k in 0..p.seeds {
                    let m = Variant::Ours(ManyLight {
                        eps,
                        fresh_final: false,
                        ..base(ctx, VPLS)
                    });
                    run(&m, &scene, "paper-estimate", cfg.seed + 1 + k, &mut rows)?;
                }
            }
            // 2. Max-Extent at the fixed ε (BSSRDF-aware's rows are the sweep's at that ε).
            let max_extent = Variant::Ours(ManyLight {
                selection: Selection::MaxExtent,
                eps: p.fixed_eps,
                ..base(ctx, VPLS)
            });
            run(&max_extent, &scene, "selection", cfg.seed + 1, &mut rows)?;
            if !p.eps.contains(&p.fixed_eps) {
                run(
                    &ours(p.fixed_eps),
                    &scene,
                    "selection",
                    cfg.seed + 1,
                    &mut rows,
                )?;
            }
            // 3. VPLs and mesh refinement, on the first scene only.
            if refs.is_empty() {
                for &f in &p.vpl_factors {
                    let m = Variant::Ours(ManyLight {
                        eps: p.fixed_eps,
                        ..base(ctx, ((VPLS as f64 * f).round() as u32).max(1))
                    });
                    run(&m, &scene, "vpls", cfg.seed + 1, &mut rows)?;
                }
                for &l in &p.subdivisions {
                    let fine = subdivide(&scene, l);
                    run(&ours(p.fixed_eps), &fine, "mesh", cfg.seed + 1, &mut rows)?;
                }
                pictures(ctx, &scene, &p, &dir)?;
            }
            // 5. The baselines: RMSE against time over N at the fixed ε (Table 1, Fig. 6),
            // importance-sampled and uniform points; one stream each (their cost is the
            // points, and their error the points' noise).
            let stream = cfg.seed + 1;
            let one = [p.eelc_points];
            let sweeps: [(bool, &[u32]); 2] = if spec.sweep_baselines {
                [(false, &p.points_is), (true, &p.points_uniform)]
            } else {
                [(false, &one), (true, &[])]
            };
            for (uniform, ns) in sweeps {
                for &n in ns {
                    let pts = points(ctx, n, uniform);
                    run(
                        &mdlc(p.fixed_eps, pts),
                        &scene,
                        "quality",
                        stream,
                        &mut rows,
                    )?;
                    run(
                        &eelc(p.fixed_eps, pts),
                        &scene,
                        "quality",
                        stream,
                        &mut rows,
                    )?;
                }
            }
            // EELC's estimation accuracy against ε (Fig. 10) at a fixed N: the run at the fixed
            // ε is the quality sweep's when that has the same N (same stream, same points).
            let pts = points(ctx, p.eelc_points, false);
            let eelc_eps: &[f64] = if spec.sweep_baselines {
                &p.eps
            } else {
                &[p.fixed_eps]
            };
            for &eps in eelc_eps {
                let same = rows.iter().rposition(|x| {
                    x.scene == name
                        && x.experiment == "quality"
                        && x.method == "eelc-is"
                        && x.points == p.eelc_points
                        && x.eps == eps
                });
                match same {
                    Some(k) => {
                        let row = Row {
                            experiment: "accuracy",
                            ..rows[k].clone()
                        };
                        rows.push(row);
                    }
                    None => run(&eelc(eps, pts), &scene, "accuracy", stream, &mut rows)?,
                }
            }
            refs.push((name, r, tri));
        }
        csv(&rows).write(&cfg.out.join("manylight.csv"))?;
        plots(ctx, &rows, &p)?;
        Ok(report(&rows, &refs, &skipped, &p))
    }
}
