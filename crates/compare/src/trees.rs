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
//! irradiance samples) on a seeded uniform random subset of [`super::subset::SUBSET_PIXELS`] translucent pixels:
//! the subset's mean squared error is an unbiased estimate of the whole image's, reported with
//! its standard error (finite-population corrected). The subset reference is cached like the
//! scene references.
//!
//! Writes `trees.csv`, `trees_error_vs_time.png`, `trees_scaling.png` and `trees/*.png`
//! under the output directory.

use super::output::{csv_num, md_num, md_table, write_atomic};
use super::subset::{SubsetReference, subset_reference};
use super::{Context, Error, Experiment, Section};
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

/// The paper-scale bunny: the full-resolution scan (35 947 vertices, in metres) scaled ×64 to
/// the built-in bunny's size (about 10 units wide) on its ground, in skin1 with photon beam
/// diffusion, under the built-in bunny's point light and camera.
pub const BUNNY: &str = include_str!("../../../scenes/experiments/trees-bunny.toml");

/// The trees experiment.
pub struct TreeExperiment;

/// What one configuration runs.
struct Plan {
    /// Resolutions (square) of the scaling runs.
    resolutions: Vec<u32>,
    /// Resolution of the ε and ρ sweeps and the stage table.
    sweep_resolution: u32,
    /// ε values of the sweep, cheapest first.
    eps: Vec<f64>,
    /// ε values of `dual-tree-fmm`'s sweep, cheapest first.
    fmm_eps: Vec<f64>,
    /// ρ values of the dual tree's ρ sweep (at [`FIXED_EPS`]; 0.75 is in the ε sweep).
    rhos: Vec<f64>,
    /// ε values of the one-thread stage table.
    table_eps: Vec<f64>,
}

/// ε of the scaling runs and the ρ sweep.
const FIXED_EPS: f64 = 0.05;

/// ρ everywhere but the ρ sweep (the paper's value).
const RHO: f64 = 0.75;

fn plan(quick: bool) -> Plan {
    if quick {
        Plan {
            resolutions: vec![128, 256],
            sweep_resolution: 256,
            eps: vec![0.2, 0.05, 0.01],
            fmm_eps: vec![0.2, 0.05, 0.01],
            rhos: vec![0.25, 1.5],
            table_eps: vec![0.2, 0.05],
        }
    } else {
        Plan {
            resolutions: vec![256, 512, 1024, 2048],
            sweep_resolution: 1024,
            eps: vec![0.2, 0.1, 0.05, 0.01],
            fmm_eps: vec![0.2, 0.1, 0.05, 0.02, 0.01, 0.005],
            rhos: vec![0.25, 0.5, 1.5],
            table_eps: vec![0.2, 0.1, 0.05],
        }
    }
}

/// An image's error on the subset: RMSE (over pixels and channels) with its standard error,
/// and the RMSE relative to the reference's root mean square over the subset.
#[derive(Clone, Copy, Debug)]
struct Score {
    rmse: f64,
    rmse_se: f64,
    rel_rmse: f64,
}

fn score(image: &[Rgb], r: &SubsetReference) -> Result<Score, Error> {
    let e = r.error(image)?;
    let n = r.values.len().max(1) as f64;
    let ref_ms = r
        .values
        .iter()
        .map(|v| (0..3).map(|c| v[c] * v[c]).sum::<f64>() / 3.0)
        .sum::<f64>()
        / n;
    Ok(Score {
        rmse: e.rmse,
        rmse_se: e.rmse_se,
        rel_rmse: if ref_ms > 0.0 {
            e.rmse / ref_ms.sqrt()
        } else {
            0.0
        },
    })
}

/// One timed run.
struct TreeRun {
    experiment: &'static str,
    resolution: u32,
    method: &'static str,
    eps: f64,
    rho: Option<f64>,
    threads: usize,
    out: RenderOutput,
    score: Score,
}

impl TreeRun {
    fn total(&self) -> f64 {
        self.out.stages.iter().map(|s| s.seconds).sum()
    }
    /// Seconds of stage `name`, or "–" when the method has no such stage.
    fn stage_cell(&self, name: &str) -> String {
        if self.out.stages.iter().any(|s| s.name == name) {
            md_num(Some(self.stage(name)), 3)
        } else {
            "–".into()
        }
    }
    fn stage(&self, name: &str) -> f64 {
        self.out
            .stages
            .iter()
            .filter(|s| s.name == name)
            .map(|s| s.seconds)
            .sum()
    }
}

fn run_on(
    scene: &Scene,
    method: &dyn Integrator,
    seed: u64,
    threads: usize,
) -> Result<RenderOutput, Error> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error(format!("cannot start {threads} threads: {e}")))?;
    let settings = RenderSettings {
        seed,
        ..RenderSettings::default()
    };
    pool.install(|| render(scene, method, &settings, &NoProgress))
        .map_err(|e| Error(format!("scene {}: {}: {e}", scene.name, method.name())))
}

fn at_resolution(scene: &Scene, res: u32) -> Scene {
    let mut s = scene.clone();
    s.camera.width = res;
    s.camera.height = res;
    s
}

const STAGES: [&str; 6] = [
    "samples",
    "illumination_tree",
    "fourier",
    "shading_tree",
    "shading",
    "gbuffer",
];

fn csv(runs: &[TreeRun]) -> String {
    let mut s = String::from(
        "experiment,resolution,method,eps,rho,threads,total_s,samples_s,illumination_tree_s,\
         fourier_s,shading_tree_s,shading_s,gbuffer_s,rmse,rmse_se,rel_rmse\n",
    );
    for r in runs {
        let _ = write!(
            s,
            "{},{},{},{},{},{},{}",
            r.experiment,
            r.resolution,
            r.method,
            r.eps,
            r.rho.map_or(String::new(), |x| x.to_string()),
            r.threads,
            csv_num(Some(r.total()))
        );
        for st in STAGES {
            let present = r.out.stages.iter().any(|x| x.name == st);
            let _ = write!(s, ",{}", csv_num(present.then(|| r.stage(st))));
        }
        let _ = writeln!(
            s,
            ",{},{},{}",
            csv_num(Some(r.score.rmse)),
            csv_num(Some(r.score.rmse_se)),
            csv_num(Some(r.score.rel_rmse))
        );
    }
    s
}

/// The dual tree's total time at the single tree's RMSE `target`, interpolated log-log along
/// the dual tree's (time, RMSE) points; `None` outside their range.
fn time_at_rmse(points: &[(f64, f64)], target: f64) -> Option<f64> {
    let mut pts: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|p| p.0 > 0.0 && p.1 > 0.0)
        .collect();
    pts.sort_by(|a, b| a.1.total_cmp(&b.1));
    if let Some(p) = pts.iter().find(|p| p.1 == target) {
        return Some(p.0);
    }
    pts.windows(2).find_map(|w| {
        let (a, b) = (w[0], w[1]);
        if a.1 < target && target < b.1 {
            let f = (target.ln() - a.1.ln()) / (b.1.ln() - a.1.ln());
            Some((a.0.ln() + f * (b.0.ln() - a.0.ln())).exp())
        } else {
            None
        }
    })
}

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
        write_atomic(&cfg.out.join("trees.csv"), csv(&runs).as_bytes())?;
        pictures(ctx, &runs, sr)?;
        plots(ctx, &runs, &p)?;
        Ok(report(&runs, &p, &refs, threads))
    }
}

/// A run of the scaling series: the scaling runs, and the sweep's runs at [`FIXED_EPS`] and
/// ρ = [`RHO`] (the series' point at the sweep resolution).
fn is_scaling(r: &TreeRun, p: &Plan) -> bool {
    r.experiment == "scaling"
        || (r.experiment == "eps"
            && r.resolution == p.sweep_resolution
            && r.eps == FIXED_EPS
            && r.rho.is_none_or(|x| x == RHO))
}

fn pictures(ctx: &Context<'_>, runs: &[TreeRun], res: u32) -> Result<(), Error> {
    let dir = ctx.config.out.join("trees");
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error(format!("cannot create {}: {e}", dir.display())))?;
    let e = |e: sss_render::Error| Error(e.to_string());
    let sweep: Vec<&TreeRun> = runs
        .iter()
        .filter(|r| r.experiment == "eps" && r.resolution == res)
        .collect();
    // The finest single-tree image stands in for the full reference of the difference images.
    let Some(finest) = sweep
        .iter()
        .filter(|r| r.method == "single-tree")
        .min_by(|a, b| a.eps.total_cmp(&b.eps))
    else {
        return Ok(());
    };
    let exposure = sss_render::image::auto_exposure(&finest.out.subsurface);
    let covered: Vec<bool> = finest.out.coverage.iter().map(|&c| c > 0.0).collect();
    let difference = |r: &TreeRun| -> Vec<Option<f64>> {
        r.out
            .subsurface
            .iter()
            .zip(&finest.out.subsurface)
            .zip(&covered)
            .map(|((a, b), &c)| {
                let m = (b[0] + b[1] + b[2]) / 3.0;
                (c && m > 0.0).then(|| ((a[0] + a[1] + a[2]) / 3.0 - m).abs() / m)
            })
            .collect()
    };
    if let Some((d, f)) = equal_time_pair(&sweep) {
        // Side by side, one colour scale (0 to 1 %), each against the finest single-tree
        // image: the paper's dual tree on the left, the local expansions given no more time
        // on the right, a 16-pixel gap between.
        let gap = 16usize;
        let n = res as usize;
        let (a, b) = (difference(d), difference(f));
        let mut values = Vec::with_capacity(n * (2 * n + gap));
        for y in 0..n {
            values.extend_from_slice(&a[y * n..(y + 1) * n]);
            values.extend(std::iter::repeat_n(None, gap));
            values.extend_from_slice(&b[y * n..(y + 1) * n]);
        }
        write_error_map(
            &dir.join("equal_time_difference.png"),
            2 * res + gap as u32,
            res,
            &values,
            0.01,
            &format!(
                "left: dual-tree eps={} rho={RHO}, {:.2} s | right: dual-tree-fmm eps={}, {:.2} s",
                d.eps,
                d.total(),
                f.eps,
                f.total(),
            ),
            "|a-b|/b",
        )
        .map_err(|e| Error(e.to_string()))?;
    }
    for r in &sweep {
        let name = format!("{}_eps{}", r.method, r.eps);
        sss_render::image::write_png(
            &dir.join(format!("{name}.png")),
            res,
            res,
            &r.out.subsurface,
            exposure,
        )
        .map_err(e)?;
        if std::ptr::eq(*r, *finest) {
            continue;
        }
        let values = difference(r);
        write_error_map(
            &dir.join(format!("{name}_difference.png")),
            res,
            res,
            &values,
            0.05,
            &format!(
                "{name}: relative difference from single-tree ε={}",
                finest.eps
            ),
            "|a-b|/b",
        )
        .map_err(|e| Error(e.to_string()))?;
    }
    if let Some(d) = sweep
        .iter()
        .find(|r| r.method == "dual-tree" && r.rho == Some(RHO))
    {
        for l in &d.out.layers {
            match l.name {
                "sampling_rate" => {
                    let values: Vec<Option<f64>> = l
                        .pixels
                        .iter()
                        .zip(&covered)
                        .map(|(p, &c)| c.then_some(p[0]))
                        .collect();
                    // Scaled to the 99th percentile: grazing pixels at the silhouettes reach
                    // s_p in the thousands (1/cos θ_o, clamped at 10⁻³) and would flatten the
                    // rest.
                    let mut sorted: Vec<f64> = values.iter().flatten().copied().collect();
                    sorted.sort_by(f64::total_cmp);
                    let p99 = sorted
                        .get((sorted.len() * 99 / 100).min(sorted.len().saturating_sub(1)))
                        .copied()
                        .unwrap_or(1.0);
                    write_error_map(
                        &dir.join("sampling_rate.png"),
                        res,
                        res,
                        &values,
                        p99.max(1e-12),
                        "s_p (samples per pixel, Eq. 5; scale to the 99th percentile)",
                        "s_p",
                    )
                    .map_err(|e| Error(e.to_string()))?;
                }
                "pixel_clusters" => {
                    sss_render::image::write_png(
                        &dir.join("pixel_clusters.png"),
                        res,
                        res,
                        &l.pixels,
                        1.0,
                    )
                    .map_err(e)?;
                }
                _ => {}
            }
        }
    }
    Ok(())
}

/// The equal-time pair of the pictures: the paper's dual tree at [`FIXED_EPS`] and ρ = [`RHO`],
/// and the most accurate `dual-tree-fmm` run of the sweep that took no more total time (the
/// fastest one if none did).
fn equal_time_pair<'r>(sweep: &[&'r TreeRun]) -> Option<(&'r TreeRun, &'r TreeRun)> {
    let d = *sweep
        .iter()
        .find(|r| r.method == "dual-tree" && r.rho == Some(RHO) && r.eps == FIXED_EPS)?;
    let fmm: Vec<&TreeRun> = sweep
        .iter()
        .copied()
        .filter(|r| r.method == "dual-tree-fmm")
        .collect();
    let within = fmm
        .iter()
        .copied()
        .filter(|r| r.total() <= d.total())
        .min_by(|a, b| a.score.rmse.total_cmp(&b.score.rmse));
    let f = within.or_else(|| {
        fmm.iter()
            .copied()
            .min_by(|a, b| a.total().total_cmp(&b.total()))
    })?;
    Some((d, f))
}

fn plots(ctx: &Context<'_>, runs: &[TreeRun], p: &Plan) -> Result<(), Error> {
    let out = &ctx.config.out;
    let pe = |e: sss_plot::PlotError| Error(e.to_string());
    let curve = |exp: &str, method: &str| -> Vec<(f64, f64)> {
        runs.iter()
            .filter(|r| r.experiment == exp && r.method == method)
            .map(|r| (r.total(), r.score.rmse))
            .collect()
    };
    let series = vec![
        Series::line("single-tree (ε sweep)", curve("eps", "single-tree"))
            .with_style(SeriesStyle::LineMarkers)
            .with_color(PALETTE[1]),
        Series::line("dual-tree ρ=0.75 (ε sweep)", curve("eps", "dual-tree"))
            .with_style(SeriesStyle::LineMarkers)
            .with_color(PALETTE[2]),
        Series::line(
            format!("dual-tree ε={FIXED_EPS} (ρ sweep)"),
            curve("rho", "dual-tree"),
        )
        .with_style(SeriesStyle::LineMarkers)
        .with_color(PALETTE[3]),
        Series::line("dual-tree-fmm (ε sweep)", curve("eps", "dual-tree-fmm"))
            .with_style(SeriesStyle::LineMarkers)
            .with_color(PALETTE[4]),
    ];
    line_plot(
        &out.join("trees_error_vs_time.png"),
        &format!(
            "bunny {0}x{0}: RMSE against exact (subset) vs. total time",
            p.sweep_resolution
        ),
        "seconds (total)",
        "RMSE",
        &series,
        true,
        true,
    )
    .map_err(pe)?;
    let scaling = |method: &str| -> Vec<(f64, f64)> {
        let mut v: Vec<(f64, f64)> = runs
            .iter()
            .filter(|r| is_scaling(r, p) && r.method == method)
            .map(|r| (f64::from(r.resolution).powi(2), r.stage("shading")))
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        v
    };
    line_plot(
        &out.join("trees_scaling.png"),
        &format!("bunny: final shading time vs. pixels (ε = {FIXED_EPS})"),
        "pixels",
        "shading seconds",
        &[
            Series::line("single-tree", scaling("single-tree"))
                .with_style(SeriesStyle::LineMarkers)
                .with_color(PALETTE[1]),
            Series::line("dual-tree", scaling("dual-tree"))
                .with_style(SeriesStyle::LineMarkers)
                .with_color(PALETTE[2]),
            Series::line("dual-tree-fmm", scaling("dual-tree-fmm"))
                .with_style(SeriesStyle::LineMarkers)
                .with_color(PALETTE[4]),
        ],
        true,
        true,
    )
    .map_err(pe)
}

fn report(runs: &[TreeRun], p: &Plan, refs: &[(u32, SubsetReference)], threads: usize) -> Section {
    let mut body = String::new();
    let mut summary = String::new();
    let sr = p.sweep_resolution;
    let fmt_rmse = |r: &TreeRun| {
        format!(
            "{} ± {}",
            md_num(Some(r.score.rmse), 3),
            md_num(Some(r.score.rmse_se), 2)
        )
    };
    let _ = writeln!(
        body,
        "Scene: the full-resolution Stanford bunny (69 451 triangles) in skin1 (photon beam \
         diffusion), one pixel sample, irradiance samples at 0.5 mean free paths. Error: RMSE \
         (± its standard error) against `exact` over the same irradiance samples on a uniform \
         random subset of translucent pixels:\n"
    );
    let rows: Vec<Vec<String>> = refs
        .iter()
        .map(|(res, r)| {
            vec![
                format!("{res}²"),
                r.population.to_string(),
                r.pixels.len().to_string(),
                if r.seconds > 0.0 {
                    md_num(Some(r.seconds), 3)
                } else {
                    "cached".into()
                },
            ]
        })
        .collect();
    body.push_str(&md_table(
        &["resolution", "translucent pixels", "subset", "reference s"],
        &rows,
    ));
    // 1. ε and ρ sweeps.
    let _ = writeln!(
        body,
        "\n#### RMSE against total time at {sr}² ({threads} threads)\n"
    );
    let rows: Vec<Vec<String>> = runs
        .iter()
        .filter(|r| (r.experiment == "eps" || r.experiment == "rho") && r.resolution == sr)
        .map(|r| {
            vec![
                r.method.to_string(),
                r.eps.to_string(),
                r.rho.map_or("–".into(), |x| x.to_string()),
                md_num(Some(r.total()), 3),
                md_num(Some(r.stage("shading")), 3),
                fmt_rmse(r),
                format!("{:.3} %", 100.0 * r.score.rel_rmse),
            ]
        })
        .collect();
    body.push_str(&md_table(
        &[
            "method",
            "ε",
            "ρ",
            "total s",
            "shading s",
            "RMSE",
            "rel. RMSE",
        ],
        &rows,
    ));
    for (method, goal) in [("dual-tree", "1/3"), ("dual-tree-fmm", "1/5")] {
        let pts: Vec<(f64, f64)> = runs
            .iter()
            .filter(|r| r.experiment == "eps" && r.method == method)
            .map(|r| (r.total(), r.score.rmse))
            .collect();
        let mut ratios = Vec::new();
        for r in runs
            .iter()
            .filter(|r| r.experiment == "eps" && r.method == "single-tree")
        {
            if let Some(t) = time_at_rmse(&pts, r.score.rmse) {
                ratios.push(format!(
                    "ε = {}: single {} s, {method} {} s at the same RMSE ({:.2}×)",
                    r.eps,
                    md_num(Some(r.total()), 3),
                    md_num(Some(t), 3),
                    t / r.total()
                ));
            } else if let Some(&(t, e)) = pts
                .iter()
                .filter(|p| p.1 <= r.score.rmse)
                .min_by(|a, b| a.0.total_cmp(&b.0))
            {
                // Every run of the method is below the target: its cheapest one bounds the time.
                ratios.push(format!(
                    "ε = {}: single {} s at RMSE {}; {method} reaches it in at most {} s (its \
                     cheapest run, RMSE {}: ≤ {:.2}×)",
                    r.eps,
                    md_num(Some(r.total()), 3),
                    md_num(Some(r.score.rmse), 3),
                    md_num(Some(t), 3),
                    md_num(Some(e), 3),
                    t / r.total()
                ));
            } else {
                ratios.push(format!(
                    "ε = {}: the single tree's RMSE {} is outside {method}'s range",
                    r.eps,
                    md_num(Some(r.score.rmse), 3)
                ));
            }
        }
        let _ = writeln!(
            summary,
            "{method}'s total time at the single tree's RMSE (bunny {sr}², {threads} threads; \
             goal ≤ {goal}):\n"
        );
        for l in &ratios {
            let _ = writeln!(summary, "- {l}");
        }
        let _ = writeln!(summary);
    }
    // 2. Table 1.
    let _ = writeln!(
        body,
        "\n#### Stage breakdown on one thread at {sr}² (Milaenen et al. Table 1)\n"
    );
    let rows: Vec<Vec<String>> = runs
        .iter()
        .filter(|r| r.experiment == "table1")
        .map(|r| {
            vec![
                r.method.to_string(),
                r.eps.to_string(),
                r.stage_cell("samples"),
                r.stage_cell("illumination_tree"),
                r.stage_cell("fourier"),
                r.stage_cell("shading_tree"),
                md_num(Some(r.stage("shading")), 3),
                md_num(Some(r.total()), 3),
            ]
        })
        .collect();
    body.push_str(&md_table(
        &[
            "method",
            "ε",
            "irradiance samples s",
            "illumination tree s",
            "Fourier s",
            "shading tree s",
            "final shading s",
            "total s",
        ],
        &rows,
    ));
    let _ = writeln!(
        body,
        "\nThe paper (one core of an i3-7100, 3.9 GHz): illumination tree 1.74 s, Fourier \
         0.09–0.11 s, shading tree 5.1–5.6 s, final shading 6.8 / 11.7 / 21.2 s at ε = 0.2 / \
         0.1 / 0.05."
    );
    // 3. Scaling.
    let _ = writeln!(
        body,
        "\n#### Scaling with the pixel count (ε = {FIXED_EPS}, ρ = {RHO}, {threads} threads)\n"
    );
    let mut scaling_runs: Vec<&TreeRun> = runs.iter().filter(|r| is_scaling(r, p)).collect();
    scaling_runs.sort_by_key(|r| (r.resolution, r.method));
    let rows: Vec<Vec<String>> = scaling_runs
        .iter()
        .map(|r| {
            vec![
                format!("{}²", r.resolution),
                r.method.to_string(),
                r.stage_cell("shading_tree"),
                md_num(Some(r.stage("shading")), 3),
                md_num(Some(r.total()), 3),
                fmt_rmse(r),
            ]
        })
        .collect();
    body.push_str(&md_table(
        &[
            "resolution",
            "method",
            "shading tree s",
            "final shading s",
            "total s",
            "RMSE",
        ],
        &rows,
    ));
    let growth = |method: &str, stage: Option<&str>| {
        let t = |res: u32| {
            runs.iter()
                .find(|r| is_scaling(r, p) && r.method == method && r.resolution == res)
                .map(|r| stage.map_or_else(|| r.total(), |s| r.stage(s)))
        };
        let (lo, hi) = (p.resolutions.first()?, p.resolutions.last()?);
        let lo = if p.resolutions.contains(&512) {
            &512
        } else {
            lo
        };
        Some((*lo, *hi, t(*hi)? / t(*lo)?.max(1e-9)))
    };
    for m in ["single-tree", "dual-tree", "dual-tree-fmm"] {
        if let (Some((lo, hi, g)), Some((_, _, gs))) = (growth(m, None), growth(m, Some("shading")))
        {
            let _ = writeln!(
                summary,
                "- {m}: total time grows {g:.2}× (final shading {gs:.2}×) from {lo}² to {hi}² \
                 ({:.0}× the pixels; goal for the dual trees ≤ 5× over 16×)",
                (f64::from(hi) / f64::from(lo)).powi(2)
            );
        }
    }
    let sweep: Vec<&TreeRun> = runs
        .iter()
        .filter(|r| r.experiment == "eps" && r.resolution == sr)
        .collect();
    if let Some((d, f)) = equal_time_pair(&sweep) {
        let _ = writeln!(
            summary,
            "\nAt equal time (`trees/equal_time_difference.png`): the paper's dual tree (ε = {}, \
             ρ = {RHO}) {} s at RMSE {}; dual-tree-fmm (ε = {}) {} s at RMSE {} ({:.1}× lower).",
            d.eps,
            md_num(Some(d.total()), 3),
            md_num(Some(d.score.rmse), 3),
            f.eps,
            md_num(Some(f.total()), 3),
            md_num(Some(f.score.rmse), 3),
            d.score.rmse / f.score.rmse.max(1e-300)
        );
    }
    let _ = writeln!(
        body,
        "\nFiles: `trees.csv` (every run), `trees_error_vs_time.png`, `trees_scaling.png`, \
         `trees/` (images per ε, relative differences from the finest single-tree image, \
         `equal_time_difference.png`, `sampling_rate.png`, `pixel_clusters.png`)."
    );
    Section {
        title: "Trees: single (Jensen & Buhler) against dual (Milaenen et al.; local expansions) \
                at paper scale"
            .into(),
        summary,
        body,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn score_of_a_known_error() {
        // Errors of 0.1 in every channel of every pixel: RMSE 0.1, no spread, so SE 0; the
        // reference's RMS is 1, so the relative RMSE is 0.1 too.
        let r = SubsetReference {
            pixels: (0..10).collect(),
            values: vec![[1.0; 3]; 10],
            population: 100,
            seconds: 0.0,
            samples: 0,
        };
        let s = score(&vec![[1.1; 3]; 10], &r).unwrap();
        assert!((s.rmse - 0.1).abs() < 1e-12);
        assert!(s.rmse_se.abs() < 1e-12);
        assert!((s.rel_rmse - 0.1).abs() < 1e-12);
    }

    #[test]
    fn equal_rmse_time_interpolates_log_log() {
        let pts = [(10.0, 1e-2), (100.0, 1e-3)];
        let t = time_at_rmse(&pts, 10f64.powf(-2.5)).unwrap();
        assert!((t - 10f64.powf(1.5)).abs() < 1e-9);
        assert_eq!(time_at_rmse(&pts, 1e-4), None);
        assert_eq!(time_at_rmse(&pts, 1e-3), Some(100.0));
    }
}
