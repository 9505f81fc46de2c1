//! The rendering experiment: every registered method (`sss_render::integrators::METHODS`) over
//! its compare sweep on the
//! default scenes (and any named ones), against a cached `exact` reference per scene.
//! Files: [`load`] (scenes), [`cache`] (references), [`runs`] (timed runs, `results.csv`),
//! [`images`] (pictures); this one runs the sweep and writes the report section.
//!
//! Writes `results.csv` (one row per run and thread count; columns documented in README.md),
//! `error_vs_time_<scene>.png` (log-log RMSE against total seconds), and under
//! `scenes/<scene>/` the reference, each method's most expensive render and its false-colour
//! error map.

mod cache;
mod images;
mod load;
mod runs;

pub(super) use cache::{reference, reference_method};
pub use load::default_mesh_dirs;
pub(super) use load::load_scenes;

use super::output::{md_num, md_pct, md_table, write_atomic};
use super::{Context, Error, Experiment, Section};
use images::write_images;
use runs::{Outcome, Run, csv_rows, run_timed};
use sss_plot::{PALETTE, Series, SeriesStyle, line_plot};
use sss_render::image::{auto_exposure, write_png};
use sss_render::integrators::exact::reference_spacing;
use sss_render::integrators::{METHODS, MethodOptions};
use sss_render::metrics::{error_figures, frac_within_se, mean_ratio};
use sss_render::render::RenderSettings;
use std::fmt::Write as _;

/// Relative-error threshold of `frac_within_eps`.
pub const EPS: f64 = 0.05;

/// The rendering experiment.
pub struct SceneComparison;

impl Experiment for SceneComparison {
    fn name(&self) -> &'static str {
        "scenes"
    }

    fn run(&self, ctx: &Context<'_>) -> Result<Section, Error> {
        let cfg = ctx.config;
        let (scenes, skipped) = load_scenes(ctx, &cfg.scenes)?;
        let all_threads = rayon::current_num_threads();
        let mut thread_counts = vec![all_threads];
        if all_threads > 1 {
            thread_counts.push(1);
        }
        let settings = RenderSettings {
            seed: cfg.seed,
            ..RenderSettings::default()
        };
        let mut runs: Vec<Run> = Vec::new();
        let mut body = String::new();
        let mut summary_rows = Vec::new();
        let mut unsupported: Vec<String> = Vec::new();
        for (scene, text) in &scenes {
            let reference = reference(ctx, scene, text)?;
            let pixels: Vec<usize> = (0..reference.coverage.len())
                .filter(|&i| reference.coverage[i] > 0.0)
                .collect();
            let dir = cfg.out.join("scenes").join(&scene.name);
            std::fs::create_dir_all(&dir)
                .map_err(|e| Error(format!("cannot create {}: {e}", dir.display())))?;
            let exposure = auto_exposure(&reference.subsurface);
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
                auto_exposure(&reference.total),
            )
            .map_err(e)?;
            let mut series = Vec::new();
            'methods: for (mi, m) in METHODS.iter().enumerate() {
                let values = (m.sweep.values)(cfg.quick);
                let mut points = Vec::new();
                for (vi, &v) in values.iter().enumerate() {
                    // One thread too only at the middle of the sweep: the speed-up and the
                    // same-bits check need one point per method, and one-thread runs of every
                    // point would double the main job's time.
                    let counts = if vi == values.len() / 2 {
                        &thread_counts[..]
                    } else {
                        &thread_counts[..1]
                    };
                    for &threads in counts {
                        let label = format!("{} {}={v}", m.name, m.sweep.label);
                        (ctx.log)(&format!(
                            "scene {}: {label} ({threads} thread(s))",
                            scene.name
                        ));
                        // Point-based methods sweeping another option sum over the
                        // reference's own irradiance samples, so their error is their
                        // approximation's alone.
                        let mut options = MethodOptions::new().with(m.sweep.option, v);
                        if m.sweep.option != "spacing"
                            && m.options.iter().any(|o| o.name == "spacing")
                        {
                            options = options.with("spacing", reference_spacing(cfg.quick));
                        }
                        let method =
                            (m.build)(&options).map_err(|e| Error(format!("{label}: {e}")))?;
                        let out =
                            match run_timed(method.as_ref(), scene, &settings, threads, &label)? {
                                Outcome::Done(out) => out,
                                Outcome::Unsupported(why) => {
                                    (ctx.log)(&format!(
                                        "scene {}: {} skipped: {why}",
                                        scene.name, m.name
                                    ));
                                    unsupported
                                        .push(format!("`{}` on `{}`: {why}", m.name, scene.name));
                                    continue 'methods;
                                }
                            };
                        for w in &out.warnings {
                            (ctx.log)(&format!("scene {}: {label}: warning: {w}", scene.name));
                        }
                        let f = error_figures(&out.subsurface, &reference.subsurface, &pixels, EPS);
                        let run = Run {
                            scene: scene.name.clone(),
                            method: m.name,
                            param: m.sweep.label,
                            value: v,
                            threads,
                            stages: out.stages.clone(),
                            rmse: f.rmse,
                            rel_rmse: f.rel_rmse,
                            frac_within_eps: f.frac_within_eps,
                            within_3se: out.std_error.as_ref().and_then(|se| {
                                frac_within_se(
                                    &out.subsurface,
                                    se,
                                    &reference.subsurface,
                                    &pixels,
                                    3.0,
                                )
                            }),
                            mean_ratio: mean_ratio(&out.subsurface, &reference.subsurface, &pixels),
                            warnings: out.warnings.clone(),
                        };
                        if threads == all_threads {
                            points.push((run.seconds_total(), run.rmse));
                            if vi + 1 == values.len() {
                                write_images(
                                    &dir,
                                    &format!("{}_{}", m.name, v),
                                    &out,
                                    &reference.subsurface,
                                    &pixels,
                                    exposure,
                                )?;
                            }
                        }
                        runs.push(run);
                    }
                }
                series.push(
                    Series::line(m.name, points)
                        .with_style(SeriesStyle::LineMarkers)
                        .with_color(PALETTE[(mi + 1) % 8]),
                );
            }
            let plot = cfg.out.join(format!("error_vs_time_{}.png", scene.name));
            line_plot(
                &plot,
                &format!(
                    "{}: RMSE against exact vs. time ({} threads)",
                    scene.name, all_threads
                ),
                "seconds (total)",
                "RMSE",
                &series,
                true,
                true,
            )
            .map_err(|e| Error(e.to_string()))?;
            // Per-scene table.
            let _ = writeln!(
                body,
                "### {}\n\n{}x{} pixels, {} translucent; reference `exact` with {} irradiance samples took {} s ({} threads). \
                 Images in `scenes/{}/`, curve in `error_vs_time_{}.png`.\n",
                scene.name,
                scene.camera.width,
                scene.camera.height,
                pixels.len(),
                reference.samples,
                md_num(Some(reference.seconds), 3),
                all_threads,
                scene.name,
                scene.name
            );
            let rows: Vec<Vec<String>> = runs
                .iter()
                .filter(|r| r.scene == scene.name)
                .map(|r| {
                    vec![
                        r.method.to_string(),
                        // A run whose caps bound (or whose units look wrong) is marked.
                        if r.warnings.is_empty() {
                            format!("{}={}", r.param, r.value)
                        } else {
                            format!("{}={} ⚠", r.param, r.value)
                        },
                        r.threads.to_string(),
                        md_num(Some(r.seconds_total()), 3),
                        md_num(r.stage("shading"), 3),
                        md_num(Some(r.rmse), 3),
                        md_pct(Some(r.rel_rmse)),
                        md_pct(Some(r.frac_within_eps)),
                        md_pct(r.within_3se),
                        md_num(Some(r.mean_ratio), 4),
                    ]
                })
                .collect();
            body.push_str(&md_table(
                &[
                    "method",
                    "param",
                    "threads",
                    "total s",
                    "shading s",
                    "RMSE",
                    "rel. RMSE",
                    &format!("within {} %", EPS * 100.0),
                    "within 3 SE",
                    "mean / ref. mean",
                ],
                &rows,
            ));
            body.push('\n');
            let best_pt = runs.iter().rev().find(|r| {
                r.scene == scene.name && r.method == "pathtrace" && r.threads == all_threads
            });
            summary_rows.push(vec![
                scene.name.clone(),
                pixels.len().to_string(),
                reference.samples.to_string(),
                md_num(Some(reference.seconds), 3),
                best_pt.map_or("–".into(), |r| {
                    format!("{} spp: {} s", r.value, md_num(Some(r.seconds_total()), 3))
                }),
                best_pt.map_or("–".into(), |r| md_pct(Some(r.rel_rmse))),
                best_pt.map_or("–".into(), |r| md_num(Some(r.mean_ratio), 4)),
            ]);
        }
        write_atomic(&cfg.out.join("results.csv"), csv_rows(&runs).as_bytes())?;
        let mut summary = md_table(
            &[
                "scene",
                "translucent pixels",
                "irradiance samples",
                "exact s",
                "pathtrace",
                "pathtrace rel. RMSE vs exact",
                "pathtrace mean / exact mean",
            ],
            &summary_rows,
        );
        for s in &skipped {
            let _ = writeln!(summary, "\nSkipped {s}");
        }
        if !unsupported.is_empty() {
            let _ = writeln!(
                summary,
                "\nMethods that cannot render a scene (not run there):\n"
            );
            for u in &unsupported {
                let _ = writeln!(summary, "- {u}");
            }
        }
        let mut warned: Vec<String> = Vec::new();
        for r in runs.iter().filter(|r| !r.warnings.is_empty()) {
            for w in &r.warnings {
                let line = format!("`{}` {} {}={}: {w}", r.scene, r.method, r.param, r.value);
                if !warned.contains(&line) {
                    warned.push(line);
                }
            }
        }
        if !warned.is_empty() {
            let _ = writeln!(
                summary,
                "\nRuns marked ⚠ gave warnings (a cap bound, or implausible units; count in the \
                 `warnings` column of `results.csv`):\n"
            );
            for w in &warned {
                let _ = writeln!(summary, "- {w}");
            }
        }
        let _ = writeln!(
            summary,
            "\nEvery run's figures (all threads, and one thread at the middle of each sweep) are in \
             `results.csv`; error is over \
             pixels covered by translucent objects, against the cached `exact` reference. The \
             path tracer converges to the surface integral that `exact` approximates with discrete \
             irradiance samples, so its mean ratio measures the point sum's discretisation plus \
             noise; per-pixel agreement within 3 standard errors is only meaningful at high spp \
             (with few samples, shadowed pixels often get all-zero estimates and a zero error bar)."
        );
        Ok(Section {
            title: "Scenes: references and error against run time".into(),
            summary,
            body,
        })
    }
}
