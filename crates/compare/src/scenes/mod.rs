//! The rendering experiment: every registered method (`sss_render::integrators::METHODS`) over
//! its compare sweep on the
//! default scenes (and any named ones), against a cached `exact` reference per scene.
//! Files: [`load`] (scenes), [`cache`] (references), [`runs`] (timed runs, `results.csv`,
//! records), [`images`] (pictures); this one plans the sweep as units ([`plan`]), runs a list of
//! them ([`run_units`]) and writes `results.csv`, the plots and the report section from their
//! results ([`assemble`]). An unsharded run does all three in one process; `--shard` runs a
//! share of the units and `--merge` assembles the shards' results (see `super::shard`).
//!
//! Writes `results.csv` (one row per run and thread count; columns documented in `docs/compare.md`),
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
pub(super) use runs::{Run, UnitResult, escape, unescape};

use super::host::Host;
use super::output::{md_num, md_pct, md_table, write_atomic};
use super::{Context, Error, Experiment, Section};
use cache::Reference;
use images::write_images;
use runs::{Outcome, csv_rows, run_timed};
use sss_plot::{PALETTE, Series, SeriesStyle, line_plot};
use sss_render::RenderSettings;
use sss_render::image::{auto_exposure, write_png};
use sss_render::integrators::exact::reference_spacing;
use sss_render::integrators::{METHODS, MethodOptions};
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

/// One unit of the sweep: a method (index into `METHODS`) at one value of its sweep (index)
/// on one scene (index into the plan's scenes), with all threads, and with one thread too at
/// the middle of the sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct SweepUnit {
    pub scene: usize,
    pub method: usize,
    pub value: usize,
}

impl SweepUnit {
    /// Every unit of `scenes` scenes, in report order: scene, then method, then sweep value.
    pub fn all(scenes: usize, quick: bool) -> Vec<SweepUnit> {
        let mut units = Vec::new();
        for scene in 0..scenes {
            for (method, m) in METHODS.iter().enumerate() {
                for value in 0..(m.sweep.values)(quick).len() {
                    units.push(SweepUnit {
                        scene,
                        method,
                        value,
                    });
                }
            }
        }
        units
    }

    /// Whether the unit has a one-thread run too: only the middle of each sweep, since the
    /// speed-up and the same-bits check need one point per method, and one-thread runs of
    /// every point would double the main job's time.
    pub fn with_one_thread(&self, quick: bool) -> bool {
        self.value == (METHODS[self.method].sweep.values)(quick).len() / 2
    }
}

/// The sweep: the scenes loaded (in order, with their TOML text), the ones skipped (a missing
/// mesh), and every unit.
pub(super) struct ScenePlan {
    pub scenes: Vec<(Scene, String)>,
    pub skipped: Vec<String>,
    pub units: Vec<SweepUnit>,
}

/// What the report needs of a plan, without the scenes themselves: what a shard records and a
/// merge reads back.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct PlanOutline {
    /// Scene names, in order.
    pub scenes: Vec<String>,
    /// Skip messages of scenes that were not loaded.
    pub skipped: Vec<String>,
    /// Every unit.
    pub units: Vec<SweepUnit>,
}

impl ScenePlan {
    /// The plan without its scenes.
    pub fn outline(&self) -> PlanOutline {
        PlanOutline {
            scenes: self.scenes.iter().map(|(s, _)| s.name.clone()).collect(),
            skipped: self.skipped.clone(),
            units: self.units.clone(),
        }
    }
}

/// Loads the run's scenes and lists the units of the sweep.
pub(super) fn plan(ctx: &Context<'_>) -> Result<ScenePlan, Error> {
    let (scenes, skipped) = load_scenes(ctx, &ctx.config.scenes)?;
    let units = SweepUnit::all(scenes.len(), ctx.config.quick);
    Ok(ScenePlan {
        scenes,
        skipped,
        units,
    })
}

/// What the report says of a scene: its size, the reference's pixels, samples and time.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct SceneInfo {
    pub width: u32,
    pub height: u32,
    /// Pixels covered by translucent objects (where errors are measured).
    pub pixels: usize,
    /// Irradiance samples of the reference.
    pub samples: usize,
    /// Seconds the reference took (when it was rendered, maybe in an earlier run).
    pub seconds: f64,
    /// Threads of the run that reports it.
    pub threads: usize,
}

impl SceneInfo {
    /// The info as one tab-separated line (see [`SceneInfo::from_record`]).
    pub fn record(&self) -> String {
        format!(
            "{}\t{}\t{}\t{}\t{:e}\t{}",
            self.width, self.height, self.pixels, self.samples, self.seconds, self.threads
        )
    }

    /// Parses a line of [`SceneInfo::record`].
    pub fn from_record(line: &str) -> Result<SceneInfo, String> {
        let f: Vec<&str> = line.split('\t').collect();
        if f.len() != 6 {
            return Err(format!("{} fields, 6 expected", f.len()));
        }
        let bad = |i: usize| format!("field {}: `{}` is not a number", i + 1, f[i]);
        Ok(SceneInfo {
            width: f[0].parse().map_err(|_| bad(0))?,
            height: f[1].parse().map_err(|_| bad(1))?,
            pixels: f[2].parse().map_err(|_| bad(2))?,
            samples: f[3].parse().map_err(|_| bad(3))?,
            seconds: f[4].parse().map_err(|_| bad(4))?,
            threads: f[5].parse().map_err(|_| bad(5))?,
        })
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
        let mut runs = Vec::new();
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
            if threads == all_threads && unit.value + 1 == values.len() {
                write_images(
                    &prepared.dir,
                    &format!("{}_{}", m.name, v),
                    &out,
                    reference,
                    pixels,
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

/// Writes `results.csv` and the error-against-time plots from the results of every unit of
/// `plan` (`results[i]` of `plan.units[i]`), and returns the report section. `info[s]` is scene
/// `s`'s info (`None` only for a scene without units). A method's units after its first
/// unsupported one on a scene are left out, as an unsharded run never runs them.
pub(super) fn assemble(
    ctx: &Context<'_>,
    plan: &PlanOutline,
    info: &[Option<SceneInfo>],
    results: &[UnitResult],
) -> Result<Section, Error> {
    let cfg = ctx.config;
    // What each (scene, method) gave, in unit order, up to its first unsupported unit.
    let mut runs: Vec<Run> = Vec::new();
    // (scene, method) → the runs' start in `runs` of each of its units.
    let mut unit_runs: Vec<Vec<Vec<usize>>> =
        vec![vec![Vec::new(); METHODS.len()]; plan.scenes.len()];
    let mut unsupported: Vec<(usize, usize, String)> = Vec::new();
    for (unit, result) in plan.units.iter().zip(results) {
        if unsupported
            .iter()
            .any(|(s, m, _)| (*s, *m) == (unit.scene, unit.method))
        {
            continue;
        }
        match result {
            UnitResult::Runs(r) => {
                if !r.is_empty() {
                    unit_runs[unit.scene][unit.method].push(runs.len());
                }
                runs.extend(r.iter().cloned());
            }
            UnitResult::Unsupported(why) => {
                unsupported.push((unit.scene, unit.method, why.clone()));
            }
        }
    }
    let hosts: Vec<&Host> = runs.iter().fold(Vec::new(), |mut v, r| {
        if !v.contains(&&r.host) {
            v.push(&r.host);
        }
        v
    });
    let mixed = hosts.len() > 1;
    let mut body = String::new();
    let mut summary_rows = Vec::new();
    for (si, name) in plan.scenes.iter().enumerate() {
        let Some(info) = &info[si] else {
            continue;
        };
        // The first run of each unit is its all-threads run.
        let firsts =
            |mi: usize| -> Vec<&Run> { unit_runs[si][mi].iter().map(|&k| &runs[k]).collect() };
        let mut series = Vec::new();
        for (mi, m) in METHODS.iter().enumerate() {
            let points: Vec<(f64, f64)> = firsts(mi)
                .iter()
                .map(|r| (r.seconds_total(), r.rmse))
                .collect();
            series.push(
                Series::line(m.name, points)
                    .with_style(SeriesStyle::LineMarkers)
                    .with_color(PALETTE[(mi + 1) % 8]),
            );
        }
        let plot = cfg.out.join(format!("error_vs_time_{name}.png"));
        line_plot(
            &plot,
            &format!(
                "{name}: RMSE against exact vs. time ({} threads)",
                info.threads
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
            "### {name}\n\n{}x{} pixels, {} translucent; reference `exact` with {} irradiance samples took {} s ({} threads). \
             Images in `scenes/{name}/`, curve in `error_vs_time_{name}.png`.\n",
            info.width,
            info.height,
            info.pixels,
            info.samples,
            md_num(Some(info.seconds), 3),
            info.threads,
        );
        let rows: Vec<Vec<String>> = runs
            .iter()
            .filter(|r| r.scene == *name)
            .map(|r| {
                let mut row = vec![
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
                ];
                if mixed {
                    let h = hosts.iter().position(|h| **h == r.host).unwrap_or(0);
                    row.push(format!("H{}", h + 1));
                }
                row
            })
            .collect();
        let within = format!("within {} %", EPS * 100.0);
        let mut header = vec![
            "method",
            "param",
            "threads",
            "total s",
            "shading s",
            "RMSE",
            "rel. RMSE",
            &within,
            "within 3 SE",
            "mean / ref. mean",
        ];
        if mixed {
            header.push("host");
        }
        body.push_str(&md_table(&header, &rows));
        body.push('\n');
        let pt = METHODS.iter().position(|m| m.name == "pathtrace");
        let best_pt = pt.and_then(|mi| firsts(mi).last().copied());
        summary_rows.push(vec![
            name.clone(),
            info.pixels.to_string(),
            info.samples.to_string(),
            md_num(Some(info.seconds), 3),
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
    for s in &plan.skipped {
        let _ = writeln!(summary, "\nSkipped {s}");
    }
    if !unsupported.is_empty() {
        let _ = writeln!(
            summary,
            "\nMethods that cannot render a scene (not run there):\n"
        );
        for (s, m, why) in &unsupported {
            let _ = writeln!(
                summary,
                "- `{}` on `{}`: {why}",
                METHODS[*m].name, plan.scenes[*s]
            );
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
    if mixed {
        let _ = writeln!(
            summary,
            "\n**Times come from {} different hosts** (a merged sharded run); compare times only \
             between rows of the same host (column `host` of the tables, `host` and \
             `host_cores` in `results.csv`):\n",
            hosts.len()
        );
        for (i, h) in hosts.iter().enumerate() {
            let _ = writeln!(summary, "- H{}: {}", i + 1, h.label());
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

#[cfg(test)]
mod tests {
    use super::super::Config;
    use super::*;
    use sss_render::Stage;

    fn config(out: PathBuf) -> Config {
        Config {
            photons: 1,
            bins: 1,
            quick: true,
            ..Config::new(vec!["skin1".into()], vec!["s".into()], out)
        }
    }

    fn results(units: &[SweepUnit], hosts: &[Host]) -> Vec<UnitResult> {
        units
            .iter()
            .enumerate()
            .map(|(i, u)| {
                let m = &METHODS[u.method];
                let host = hosts[i % hosts.len()].clone();
                let run = Run {
                    scene: "s".into(),
                    method: m.name,
                    param: m.sweep.label,
                    value: (m.sweep.values)(true)[u.value],
                    threads: host.cores,
                    host,
                    stages: vec![Stage {
                        name: "shading",
                        seconds: 1.0 + i as f64,
                    }],
                    rmse: 0.1,
                    rel_rmse: 0.1,
                    frac_within_eps: 0.5,
                    within_3se: None,
                    mean_ratio: 1.0,
                    warnings: Vec::new(),
                };
                if m.name == "eelc" {
                    UnitResult::Unsupported("needs a radial model".into())
                } else {
                    UnitResult::Runs(vec![run])
                }
            })
            .collect()
    }

    /// Rows timed on different hosts are flagged in the report (a host column and the list of
    /// hosts) and named in `results.csv`; rows of one host are not flagged. Units after a
    /// method's unsupported one are left out, and the method is listed as unsupported.
    #[test]
    fn mixed_hosts_are_flagged() {
        let dir = std::env::temp_dir().join(format!("xtask-hosts-{}", std::process::id()));
        let cfg = config(dir.clone());
        std::fs::create_dir_all(&dir).unwrap();
        let log = |_: &str| {};
        let ctx = Context {
            config: &cfg,
            references: &[],
            log: &log,
        };
        let units = SweepUnit::all(1, true);
        let outline = PlanOutline {
            scenes: vec!["s".into()],
            skipped: vec!["`bunny`: no mesh".into()],
            units: units.clone(),
        };
        let info = vec![Some(SceneInfo {
            width: 8,
            height: 6,
            pixels: 40,
            samples: 100,
            seconds: 1.5,
            threads: 2,
        })];
        let a = Host {
            cpu: "cpu A".into(),
            cores: 2,
        };
        let b = Host {
            cpu: "cpu B".into(),
            cores: 64,
        };
        let one = assemble(
            &ctx,
            &outline,
            &info,
            &results(&units, std::slice::from_ref(&a)),
        )
        .unwrap();
        assert!(!one.summary.contains("different hosts"), "{}", one.summary);
        assert!(one.summary.contains("`eelc` on `s`: needs a radial model"));
        assert!(one.summary.contains("Skipped `bunny`: no mesh"));
        let mixed = assemble(&ctx, &outline, &info, &results(&units, &[a, b])).unwrap();
        assert!(
            mixed.summary.contains("from 2 different hosts")
                && mixed.summary.contains("H1: cpu A (2 cores)")
                && mixed.summary.contains("H2: cpu B (64 cores)"),
            "{}",
            mixed.summary
        );
        assert!(mixed.body.contains("| host |"), "{}", mixed.body);
        let csv = std::fs::read_to_string(dir.join("results.csv")).unwrap();
        assert!(csv.lines().next().unwrap().contains(",host,host_cores,"));
        assert!(
            csv.contains(",cpu A,2,") && csv.contains(",cpu B,64,"),
            "{csv}"
        );
        assert!(!csv.contains("eelc"), "{csv}");
        let rows = csv.lines().count() - 1;
        let eelc = units
            .iter()
            .filter(|u| METHODS[u.method].name == "eelc")
            .count();
        assert_eq!(rows, units.len() - eelc);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
