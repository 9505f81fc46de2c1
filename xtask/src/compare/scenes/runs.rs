//! One timed run of a method, and `results.csv` (one row per run and thread count; columns
//! documented in README.md). The stage columns follow the stages the runs report, in pipeline
//! order, so a new method's stages get their own columns.

use super::super::Error;
use super::super::output::csv_num;
use sss_render::integrators::Integrator;
use sss_render::progress::NoProgress;
use sss_render::render::{RenderOutput, RenderSettings, Stage, render};
use sss_render::scene::Scene;
use std::fmt::Write as _;

/// Stages every render reports first, in order.
const LEADING: [&str; 3] = ["bvh", "gbuffer", "models"];
/// Stages every render reports last, in order.
const TRAILING: [&str; 2] = ["shading", "opaque"];

/// The stage columns of `results.csv` for `runs`: [`LEADING`], then each other stage in the
/// order it first appears, then [`TRAILING`].
pub fn stage_columns(runs: &[Run]) -> Vec<&'static str> {
    let mut cols: Vec<&'static str> = LEADING.to_vec();
    for r in runs {
        for s in &r.stages {
            if !cols.contains(&s.name) && !TRAILING.contains(&s.name) {
                cols.push(s.name);
            }
        }
    }
    cols.extend(TRAILING);
    cols
}

/// One run: a method at one parameter value with one thread count.
#[derive(Clone, Debug)]
pub struct Run {
    pub scene: String,
    pub method: &'static str,
    pub param: &'static str,
    pub value: f64,
    pub threads: usize,
    pub stages: Vec<Stage>,
    pub rmse: f64,
    pub rel_rmse: f64,
    pub frac_within_eps: f64,
    /// Path tracer only: fraction of pixels within 3 standard errors of the reference.
    pub within_3se: Option<f64>,
    /// Mean over translucent pixels and channels of the render divided by the reference's
    /// (1 for an unbiased method, up to noise).
    pub mean_ratio: f64,
    /// Warnings the render gave (a cap that bound, implausible units).
    pub warnings: Vec<String>,
}

impl Run {
    /// Seconds over all stages.
    pub fn seconds_total(&self) -> f64 {
        self.stages.iter().map(|s| s.seconds).sum()
    }
    /// Seconds of the stages named `name` (summed), if any ran.
    pub fn stage(&self, name: &str) -> Option<f64> {
        let v: Vec<f64> = self
            .stages
            .iter()
            .filter(|s| s.name == name)
            .map(|s| s.seconds)
            .collect();
        (!v.is_empty()).then(|| v.iter().sum())
    }
}

/// The header of `results.csv` (documented in README.md).
pub fn csv_header(stages: &[&str]) -> String {
    let mut h = String::from("scene,method,param,value,threads,seconds_total");
    for s in stages {
        let _ = write!(h, ",seconds_{s}");
    }
    h.push_str(",rmse,rel_rmse,frac_within_eps,frac_within_3se,mean_ratio,warnings\n");
    h
}

pub fn csv_rows(runs: &[Run]) -> String {
    let stages = stage_columns(runs);
    let mut s = csv_header(&stages);
    for r in runs {
        let _ = write!(
            s,
            "{},{},{},{},{},{}",
            r.scene,
            r.method,
            r.param,
            csv_num(Some(r.value)),
            r.threads,
            csv_num(Some(r.seconds_total()))
        );
        for st in &stages {
            let _ = write!(s, ",{}", csv_num(r.stage(st)));
        }
        let _ = writeln!(
            s,
            ",{},{},{},{},{},{}",
            csv_num(Some(r.rmse)),
            csv_num(Some(r.rel_rmse)),
            csv_num(Some(r.frac_within_eps)),
            csv_num(r.within_3se),
            csv_num(Some(r.mean_ratio)),
            r.warnings.len()
        );
    }
    s
}

/// What one run gave.
pub enum Outcome {
    /// The render.
    Done(Box<RenderOutput>),
    /// The method cannot render this scene (why): the run is skipped and listed.
    Unsupported(String),
}

/// Renders `scene` with `method` on a pool of `threads` threads; errors name the scene and the
/// run (`label`).
pub fn run_timed(
    method: &dyn Integrator,
    scene: &Scene,
    settings: &RenderSettings,
    threads: usize,
    label: &str,
) -> Result<Outcome, Error> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error(format!("cannot start {threads} threads: {e}")))?;
    match pool.install(|| render(scene, method, settings, &NoProgress)) {
        Ok(out) => Ok(Outcome::Done(Box::new(out))),
        Err(sss_render::Error::Unsupported(why)) => Ok(Outcome::Unsupported(why)),
        Err(e) => Err(Error(format!("scene {}: {label}: {e}", scene.name))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(stages: &[&'static str]) -> Run {
        Run {
            scene: "s".into(),
            method: "m",
            param: "p",
            value: 1.0,
            threads: 1,
            stages: stages
                .iter()
                .map(|&name| Stage { name, seconds: 1.0 })
                .collect(),
            rmse: 0.0,
            rel_rmse: 0.0,
            frac_within_eps: 1.0,
            within_3se: None,
            mean_ratio: 1.0,
            warnings: Vec::new(),
        }
    }

    /// The columns of today's three methods keep the order README documents, and a new
    /// method's stage gets a column before `shading`.
    #[test]
    fn stage_columns_follow_the_pipeline() {
        let runs = [
            run(&["bvh", "gbuffer", "models", "samples", "shading", "opaque"]),
            run(&["bvh", "gbuffer", "models", "shading", "opaque"]),
            run(&[
                "bvh",
                "gbuffer",
                "models",
                "irradiance",
                "kernels",
                "shading",
                "opaque",
            ]),
        ];
        assert_eq!(
            stage_columns(&runs),
            [
                "bvh",
                "gbuffer",
                "models",
                "samples",
                "irradiance",
                "kernels",
                "shading",
                "opaque"
            ]
        );
        let more = [runs[0].clone(), run(&["bvh", "trees", "shading"])];
        assert_eq!(
            stage_columns(&more),
            [
                "bvh", "gbuffer", "models", "samples", "trees", "shading", "opaque"
            ]
        );
        let csv = csv_rows(&more);
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let row: Vec<&str> = csv.lines().nth(2).unwrap().split(',').collect();
        assert_eq!(header.len(), row.len());
        let trees = header.iter().position(|c| *c == "seconds_trees").unwrap();
        assert_eq!(row[trees], "1e0");
        let samples = header.iter().position(|c| *c == "seconds_samples").unwrap();
        assert_eq!(row[samples], "", "a stage a run lacks stays empty");
    }

    #[test]
    fn csv_header_has_the_documented_columns() {
        let h = csv_header(&stage_columns(&[]));
        for col in [
            "scene",
            "method",
            "param",
            "value",
            "threads",
            "seconds_total",
            "seconds_shading",
            "rmse",
            "rel_rmse",
            "frac_within_eps",
            "warnings",
        ] {
            assert!(
                h.split(',').any(|c| c.trim() == col),
                "{col} missing from {h}"
            );
        }
    }
}
