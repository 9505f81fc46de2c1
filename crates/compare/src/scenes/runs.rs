//! One timed run of a method, `results.csv` (one row per run and thread count; columns
//! documented in `docs/compare.md`), and the lossless text records a shard writes of its runs
//! ([`Run::record`]). The stage columns follow the stages the runs report, in pipeline
//! order, so a new method's stages get their own columns.

use super::super::Error;
use super::super::host::Host;
use super::super::output::{Csv, csv_num, csv_text};
use sss_render::integrators::Integrator;
use sss_render::integrators::METHODS;
use sss_render::progress::NoProgress;
use sss_render::scene::Scene;
use sss_render::{RenderOutput, RenderSettings, Stage, render};

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
    /// The machine the run was timed on.
    pub host: Host,
    pub stages: Vec<Stage>,
    pub rmse: f64,
    pub rel_rmse: f64,
    pub frac_within_eps: f64,
    /// Path tracer only: fraction of pixels within 3 standard errors of the reference.
    pub within_3se: Option<f64>,
    /// Mean over translucent pixels and channels of the render divided by the reference's
    /// (1 for an unbiased method, up to noise).
    pub mean_ratio: f64,
    /// HDR-FLIP of the subsurface image against the reference's, the mean over the whole
    /// frame (`sss_render::flip`; the background agrees, so it counts as 0).
    pub flip: f64,
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

/// The columns of `results.csv` (documented in `docs/compare.md`).
pub fn csv_columns(stages: &[&str]) -> Vec<String> {
    let mut cols: Vec<String> = [
        "scene",
        "method",
        "param",
        "value",
        "threads",
        "host",
        "host_cores",
        "seconds_total",
    ]
    .map(String::from)
    .to_vec();
    cols.extend(stages.iter().map(|s| format!("seconds_{s}")));
    cols.extend(
        [
            "rmse",
            "rel_rmse",
            "frac_within_eps",
            "frac_within_3se",
            "mean_ratio",
            "flip",
            "warnings",
        ]
        .map(String::from),
    );
    cols
}

/// `results.csv`: one row per run.
pub fn results_csv(runs: &[Run]) -> Csv {
    let stages = stage_columns(runs);
    let mut csv = Csv::new(csv_columns(&stages));
    for r in runs {
        let mut row = vec![
            csv_text(&r.scene),
            csv_text(r.method),
            csv_text(r.param),
            csv_num(Some(r.value)),
            csv_text(r.threads),
            csv_text(&r.host.cpu),
            csv_text(r.host.cores),
            csv_num(Some(r.seconds_total())),
        ];
        row.extend(stages.iter().map(|st| csv_num(r.stage(st))));
        row.extend([
            csv_num(Some(r.rmse)),
            csv_num(Some(r.rel_rmse)),
            csv_num(Some(r.frac_within_eps)),
            csv_num(r.within_3se),
            csv_num(Some(r.mean_ratio)),
            csv_num(Some(r.flip)),
            csv_text(r.warnings.len()),
        ]);
        csv.row(row);
    }
    csv
}

/// What one unit of the sweep gave: its runs (all threads first, then one thread where the
/// unit has a one-thread run), or the reason the method cannot render the scene.
#[derive(Clone, Debug)]
pub enum UnitResult {
    /// The unit's runs.
    Runs(Vec<Run>),
    /// The method cannot render the scene (why); the rest of its sweep there is not run.
    Unsupported(String),
}

/// Escapes `text` as one field of a tab-separated record: `\\`, `\t`, `\n`, `\r`.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '\\' => out.push_str("\\\\"),
            '\t' => out.push_str("\\t"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            c => out.push(c),
        }
    }
    out
}

/// The inverse of [`escape`]; `None` for a dangling or unknown escape.
pub fn unescape(field: &str) -> Option<String> {
    let mut out = String::with_capacity(field.len());
    let mut chars = field.chars();
    while let Some(c) = chars.next() {
        if c != '\\' {
            out.push(c);
            continue;
        }
        out.push(match chars.next()? {
            '\\' => '\\',
            't' => '\t',
            'n' => '\n',
            'r' => '\r',
            _ => return None,
        });
    }
    Some(out)
}

/// A number as a record field: shortest round-trip notation (`NaN` and `inf` too), so a
/// parsed record holds the same bits.
fn num(v: f64) -> String {
    format!("{v:e}")
}

/// An optional number: empty for none.
fn opt_num(v: Option<f64>) -> String {
    v.map(num).unwrap_or_default()
}

/// A stage name as `'static` (the render's stages are named by string literals): the name of a
/// known stage where it is one, else the text kept for the rest of the process.
fn stage_name(name: &str) -> &'static str {
    const KNOWN: [&str; 5] = ["bvh", "gbuffer", "models", "shading", "opaque"];
    KNOWN
        .iter()
        .find(|k| **k == name)
        .copied()
        .unwrap_or_else(|| Box::leak(name.to_string().into_boxed_str()))
}

impl Run {
    /// The run as one line of tab-separated fields (no line break): scene, method, param,
    /// value, threads, host, host cores, stages (`name=seconds` joined by `;`), rmse, relative
    /// RMSE, fraction within ε, fraction within 3 SE (empty for none), mean ratio, FLIP, then
    /// one field per warning. Numbers in round-trip notation: [`Run::from_record`] gives the run
    /// back bit for bit.
    pub fn record(&self) -> String {
        let stages: Vec<String> = self
            .stages
            .iter()
            .map(|s| format!("{}={}", escape(s.name), num(s.seconds)))
            .collect();
        let mut fields = vec![
            escape(&self.scene),
            escape(self.method),
            escape(self.param),
            num(self.value),
            self.threads.to_string(),
            escape(&self.host.cpu),
            self.host.cores.to_string(),
            stages.join(";"),
            num(self.rmse),
            num(self.rel_rmse),
            num(self.frac_within_eps),
            opt_num(self.within_3se),
            num(self.mean_ratio),
            num(self.flip),
        ];
        fields.extend(self.warnings.iter().map(|w| escape(w)));
        fields.join("\t")
    }

    /// Parses a line written by [`Run::record`]. The method must be a registered one (its
    /// name and sweep label are taken from `METHODS`).
    pub fn from_record(line: &str) -> Result<Run, String> {
        let f: Vec<&str> = line.split('\t').collect();
        if f.len() < 14 {
            return Err(format!("{} fields, at least 14 expected", f.len()));
        }
        let text = |i: usize| unescape(f[i]).ok_or_else(|| format!("field {}: bad escape", i + 1));
        let number = |i: usize| {
            f[i].parse::<f64>()
                .map_err(|_| format!("field {}: `{}` is not a number", i + 1, f[i]))
        };
        let count = |i: usize| {
            f[i].parse::<usize>()
                .map_err(|_| format!("field {}: `{}` is not a count", i + 1, f[i]))
        };
        let method_name = text(1)?;
        let method = METHODS
            .iter()
            .find(|m| m.name == method_name)
            .ok_or_else(|| format!("unknown method `{method_name}`"))?;
        let param = text(2)?;
        if param != method.sweep.label {
            return Err(format!(
                "method `{method_name}` sweeps `{}`, not `{param}`",
                method.sweep.label
            ));
        }
        let mut stages = Vec::new();
        for part in f[7].split(';').filter(|p| !p.is_empty()) {
            let (name, secs) = part
                .split_once('=')
                .ok_or_else(|| format!("stage `{part}` is not name=seconds"))?;
            let name = unescape(name).ok_or("stage name: bad escape")?;
            let seconds = secs
                .parse::<f64>()
                .map_err(|_| format!("stage `{part}`: bad seconds"))?;
            stages.push(Stage {
                name: stage_name(&name),
                seconds,
            });
        }
        Ok(Run {
            scene: text(0)?,
            method: method.name,
            param: method.sweep.label,
            value: number(3)?,
            threads: count(4)?,
            host: Host {
                cpu: text(5)?,
                cores: count(6)?,
            },
            stages,
            rmse: number(8)?,
            rel_rmse: number(9)?,
            frac_within_eps: number(10)?,
            within_3se: if f[11].is_empty() {
                None
            } else {
                Some(number(11)?)
            },
            mean_ratio: number(12)?,
            flip: number(13)?,
            warnings: (14..f.len()).map(text).collect::<Result<_, _>>()?,
        })
    }
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
            host: Host {
                cpu: "test cpu".into(),
                cores: 2,
            },
            stages: stages
                .iter()
                .map(|&name| Stage { name, seconds: 1.0 })
                .collect(),
            rmse: 0.0,
            rel_rmse: 0.0,
            frac_within_eps: 1.0,
            within_3se: None,
            mean_ratio: 1.0,
            flip: 0.0,
            warnings: Vec::new(),
        }
    }

    /// The columns of today's three methods keep the order `docs/compare.md` documents, and a new
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
        let csv = String::from(results_csv(&more));
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
        let h = csv_columns(&stage_columns(&[]));
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
            assert!(h.iter().any(|c| c == col), "{col} missing from {h:?}");
        }
    }

    /// A run written as a record and read back is the same run, bit for bit, whatever its
    /// text holds; records that are not runs are refused with the reason.
    #[test]
    fn records_round_trip() {
        let mut r = run(&["bvh", "gbuffer", "irradiance_tree", "shading"]);
        r.method = METHODS[1].name;
        r.param = METHODS[1].sweep.label;
        r.scene = "a\tscene\\with\nbreaks".into();
        r.value = 0.1 + 0.2;
        r.rmse = 1.0 / 3.0;
        r.rel_rmse = f64::MIN_POSITIVE;
        r.within_3se = Some(0.7);
        r.mean_ratio = 1.0 + f64::EPSILON;
        r.flip = 0.1 + 0.7;
        r.stages[2].seconds = 1e-300;
        r.host.cpu = "cpu, with comma\tand tab".into();
        r.warnings = vec!["cap bound\t(spacing 2)".into(), String::new(), "\\n".into()];
        let line = r.record();
        assert!(!line.contains('\n'));
        let back = Run::from_record(&line).unwrap();
        assert_eq!(back.record(), line);
        assert_eq!(back.scene, r.scene);
        assert_eq!(back.method, r.method);
        assert_eq!(back.value.to_bits(), r.value.to_bits());
        assert_eq!(back.rmse.to_bits(), r.rmse.to_bits());
        assert_eq!(back.rel_rmse.to_bits(), r.rel_rmse.to_bits());
        assert_eq!(back.mean_ratio.to_bits(), r.mean_ratio.to_bits());
        assert_eq!(back.flip.to_bits(), r.flip.to_bits());
        assert_eq!(back.within_3se, r.within_3se);
        assert_eq!(back.host, r.host);
        assert_eq!(back.warnings, r.warnings);
        let names: Vec<&str> = back.stages.iter().map(|s| s.name).collect();
        assert_eq!(names, ["bvh", "gbuffer", "irradiance_tree", "shading"]);
        assert_eq!(back.stages[2].seconds, 1e-300);
        r.within_3se = None;
        assert_eq!(Run::from_record(&r.record()).unwrap().within_3se, None);

        let fields: Vec<String> = line.split('\t').map(String::from).collect();
        let with = |i: usize, v: &str| {
            let mut f = fields.clone();
            f[i] = v.into();
            Run::from_record(&f.join("\t")).unwrap_err()
        };
        assert!(with(1, "nope").contains("unknown method `nope`"));
        assert!(with(2, "taps").contains("sweeps"));
        assert!(with(3, "x").contains("field 4"));
        assert!(with(4, "-1").contains("not a count"));
        assert!(with(7, "bvh").contains("name=seconds"));
        assert!(with(13, "flip").contains("field 14"));
        assert!(with(0, "bad\\q").contains("bad escape"));
        assert!(
            Run::from_record("a\tb")
                .unwrap_err()
                .contains("at least 14")
        );
        for text in ["", "plain", "\\", "\t\n\r\\\\t"] {
            assert_eq!(unescape(&escape(text)).as_deref(), Some(text));
        }
        assert_eq!(unescape("dangling\\"), None);
    }
}
