//! The default experiments split over many machines: `--prepare` fills the reference cache,
//! `--shard I/N` runs the I-th of N balanced shares of the work into its own directory, and
//! `--merge DIR...` joins the shards into the `results.csv`, `report.md` and plots an unsharded
//! run gives.
//!
//! **The work.** One item for the profile comparison (every model against the Monte Carlo
//! reference of every preset), one for the kernel comparison, and one per unit of the scenes
//! sweep ([`SweepUnit`]: a method at one value of its sweep on one scene, with its one-thread
//! run where it has one, so the speed-up and the same-bits check stay within one shard).
//! [`assign`] deals the items to the shards by estimated cost, largest first, each to the
//! least-loaded shard (ties to the lower shard): deterministic, so every shard computes the
//! same assignment on its own.
//!
//! **The references** (Monte Carlo profiles, each scene's `exact` render) are computed once,
//! by a first job (`--prepare`) into a cache every shard reads (`--cache DIR` on a shared
//! filesystem). A shard that finds a reference missing computes it itself, which is correct
//! but repeats work.
//!
//! **A shard's directory** holds the pictures of its items, each item's report section
//! (`section_<name>.md`), its sweep units' results (`runs.tsv`, lossless: numbers in
//! round-trip notation), the scene facts the report needs (`scenes.tsv`), and last, when all
//! of that is written, `shard.txt`: the settings, the version, the plan and the host. A
//! merge refuses shards whose settings, version or plan differ, naming the difference, and a
//! set of shards that is not exactly 1..N.

use super::host::Host;
use super::output::write_atomic;
use super::scenes::{
    self, PlanOutline, SceneInfo, SweepUnit, UnitResult, escape, run_units, unescape,
};
use super::{Config, Context, Error, Experiment, Section, kernels, profiles, reference};
use sss_render::integrators::METHODS;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Instant;

/// Version of the shard files' layout; bump when it changes.
const FORMAT: u32 = 1;

/// The manifest's file name.
const MANIFEST: &str = "shard.txt";
/// The sweep units' results.
const RUNS: &str = "runs.tsv";
/// The scene facts.
const SCENES: &str = "scenes.tsv";

/// What a merge leaves out of a shard's directory besides its records: the shard's cache,
/// and a report or results.csv of an earlier unsharded run there (the merge writes its own).
const NOT_COPIED: [&str; 3] = ["cache", "report.md", "results.csv"];

/// Files of a shard's directory that a merge reads instead of copying.
const RECORDS: [&str; 5] = [
    MANIFEST,
    RUNS,
    SCENES,
    "section_profiles.md",
    "section_kernels.md",
];

/// Estimated seconds of the profile comparison (the references cached): about 2 s with
/// `--quick` on the 2-core machine, 10 s without.
fn profiles_cost(quick: bool) -> f64 {
    if quick { 2.0 } else { 10.0 }
}

/// Estimated seconds of the kernel comparison: 45 s with `--quick` on the 2-core machine (a
/// 480×270 frame per kernel); the full run filters 1920×1080 frames.
fn kernels_cost(quick: bool) -> f64 {
    if quick { 45.0 } else { 180.0 }
}

/// Seconds of one all-threads run at the middle of a method's `--quick` sweep on a scene of
/// 4 800 pixels, measured on the 2-core machine (`results.csv` of `compare --quick`, mean over
/// the built-in scenes); 1 for a method not listed.
fn method_seconds(name: &str) -> f64 {
    match name {
        "exact" => 2.0,
        "pathtrace" => 0.04,
        "separable" => 0.015,
        "single-tree" => 0.5,
        "dual-tree" => 0.7,
        "dual-tree-fmm" => 0.3,
        "manylight" => 1.2,
        "mdlc" => 0.5,
        "eelc" => 1.4,
        _ => 1.0,
    }
}

/// Estimated seconds of a sweep unit on a scene of `pixels` pixels: the method's
/// [`method_seconds`] in proportion to the pixels, doubled per step along the sweep from its
/// middle (the sweeps double their work per step), times 2.5 with a one-thread run.
fn unit_cost(unit: &SweepUnit, pixels: usize, quick: bool) -> f64 {
    let m = &METHODS[unit.method];
    let mid = (m.sweep.values)(quick).len() / 2;
    let step = 2f64.powi(unit.value as i32 - mid as i32);
    let one = if unit.with_one_thread(quick) {
        2.5
    } else {
        1.0
    };
    method_seconds(m.name) * (pixels.max(1) as f64 / 4800.0) * step * one
}

/// The I-th of N shares (I from 1 to N).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// Which share, from 1.
    pub index: usize,
    /// How many shares.
    pub count: usize,
}

impl FromStr for Shard {
    type Err = String;

    /// Parses `I/N` with 1 ≤ I ≤ N.
    fn from_str(s: &str) -> Result<Shard, String> {
        let bad = |why: &str| format!("--shard {s}: {why} (expected I/N with 1 <= I <= N)");
        let (i, n) = s.split_once('/').ok_or_else(|| bad("no `/`"))?;
        let index: usize = i.trim().parse().map_err(|_| bad("I is not a number"))?;
        let count: usize = n.trim().parse().map_err(|_| bad("N is not a number"))?;
        if count == 0 {
            return Err(bad("N must be at least 1"));
        }
        if index == 0 || index > count {
            return Err(bad("I must lie in 1..=N"));
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// One item of the default job's work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Work {
    /// Every model's profile against the Monte Carlo references.
    Profiles,
    /// The separable-kernel comparison.
    Kernels,
    /// A unit of the scenes sweep (index into the plan's units).
    Sweep(usize),
}

/// The shard (0-based) of each item of `costs`: largest cost first, each to the least-loaded
/// shard, ties to the lower shard and, among equal costs, the earlier item first.
pub fn assign(costs: &[f64], shards: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..costs.len()).collect();
    order.sort_by(|&a, &b| costs[b].total_cmp(&costs[a]).then(a.cmp(&b)));
    let mut load = vec![0.0f64; shards.max(1)];
    let mut out = vec![0; costs.len()];
    for i in order {
        let (s, _) = load
            .iter()
            .enumerate()
            .fold(
                (0, f64::INFINITY),
                |best, (s, &l)| {
                    if l < best.1 { (s, l) } else { best }
                },
            );
        out[i] = s;
        load[s] += costs[i].max(0.0);
    }
    out
}

/// Every item of the default job with its estimated cost, in report order.
fn work(plan: &scenes::ScenePlan, quick: bool) -> Vec<(Work, f64)> {
    let mut v = vec![(Work::Profiles, profiles_cost(quick))];
    for (i, u) in plan.units.iter().enumerate() {
        let cam = &plan.scenes[u.scene].0.camera;
        let pixels = cam.width as usize * cam.height as usize;
        v.push((Work::Sweep(i), unit_cost(u, pixels, quick)));
    }
    v.push((Work::Kernels, kernels_cost(quick)));
    v
}

/// The version of the code: the package version and the git commit of the workspace (with
/// `+dirty` when tracked files differ from it), or `unknown` without git.
fn version() -> String {
    let root = crate::workspace_root();
    let root = root.as_path();
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .arg("-C")
            .arg(root)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let commit = git(&["rev-parse", "HEAD"]).unwrap_or_else(|| "unknown".into());
    let dirty =
        git(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
    format!(
        "{} {commit}{}",
        env!("CARGO_PKG_VERSION"),
        if dirty { "+dirty" } else { "" }
    )
}

/// The settings that decide a run's results, as `key=value` lines in a fixed order: shards
/// of one run agree on all of them.
fn settings(config: &Config, outline: &PlanOutline) -> Vec<(&'static str, String)> {
    vec![
        ("format", FORMAT.to_string()),
        ("version", version()),
        ("quick", config.quick.to_string()),
        ("seed", config.seed.to_string()),
        ("photons", config.photons.to_string()),
        ("bins", config.bins.to_string()),
        ("presets", escape(&config.presets.join(","))),
        ("scenes", escape(&config.scenes.join(","))),
        ("loaded", escape(&outline.scenes.join(","))),
        (
            "skipped",
            outline
                .skipped
                .iter()
                .map(|s| escape(s))
                .collect::<Vec<_>>()
                .join("\t"),
        ),
        ("units", outline.units.len().to_string()),
    ]
}

/// A report section as a file: the title, then the summary and the body after marker lines.
fn section_text(s: &Section) -> String {
    format!(
        "{}\n<!-- sss-shard summary -->\n{}<!-- sss-shard body -->\n{}",
        s.title, s.summary, s.body
    )
}

fn parse_section(text: &str, path: &Path) -> Result<Section, Error> {
    let bad = || {
        Error(format!(
            "{}: not a section written by a shard",
            path.display()
        ))
    };
    let (title, rest) = text
        .split_once("\n<!-- sss-shard summary -->\n")
        .ok_or_else(bad)?;
    let (summary, body) = rest
        .split_once("<!-- sss-shard body -->\n")
        .ok_or_else(bad)?;
    Ok(Section {
        title: title.to_string(),
        summary: summary.to_string(),
        body: body.to_string(),
    })
}

/// `--prepare`: computes every reference the default experiments use (the Monte Carlo profile
/// of every preset and channel, and every scene's `exact` render) into the cache, and nothing
/// else.
pub fn prepare(config: &Config, ctx_log: &dyn Fn(&str)) -> Result<(), Error> {
    let presets = super::check(config)?;
    let bar = sss_cli::progress::bar(presets.len() as u64 * 3 * config.photons, "photons");
    reference::load_or_compute(config, &presets, ctx_log, &bar)?;
    bar.finish_and_clear();
    let ctx = Context {
        config,
        references: &[],
        log: ctx_log,
    };
    let plan = scenes::plan(&ctx)?;
    for (scene, text) in &plan.scenes {
        scenes::reference(&ctx, scene, text)?;
    }
    // The kernel comparison reads the references of `sphere` and `slab` when the run has them;
    // they are among the plan's scenes then.
    ctx_log(&format!(
        "prepare: references of {} preset(s) and {} scene(s) in {}",
        presets.len(),
        plan.scenes.len(),
        config.cache_dir().display()
    ));
    Ok(())
}

/// `--shard I/N`: runs this shard's items and writes its directory.
pub fn run_shard(config: &Config, shard: Shard, log: &dyn Fn(&str)) -> Result<(), Error> {
    let started = Instant::now();
    let presets = super::check(config)?;
    for name in RECORDS {
        let p = config.out.join(name);
        if p.exists() {
            std::fs::remove_file(&p)
                .map_err(|e| Error(format!("cannot remove the old {}: {e}", p.display())))?;
        }
    }
    let plain = Context {
        config,
        references: &[],
        log,
    };
    let plan = scenes::plan(&plain)?;
    let items = work(&plan, config.quick);
    let costs: Vec<f64> = items.iter().map(|(_, c)| *c).collect();
    let owner = assign(&costs, shard.count);
    let (mine, load): (Vec<Work>, f64) = items
        .iter()
        .zip(&owner)
        .filter(|(_, s)| **s + 1 == shard.index)
        .fold((Vec::new(), 0.0), |(mut v, l), ((w, c), _)| {
            v.push(*w);
            (v, l + c)
        });
    log(&format!(
        "shard {shard}: {} of {} items (estimated {:.0} % of the work) -> {}",
        mine.len(),
        items.len(),
        100.0 * load / costs.iter().sum::<f64>().max(f64::MIN_POSITIVE),
        config.out.display()
    ));
    if mine.contains(&Work::Profiles) {
        let bar = sss_cli::progress::bar(presets.len() as u64 * 3 * config.photons, "photons");
        let references = reference::load_or_compute(config, &presets, log, &bar)?;
        bar.finish_and_clear();
        let ctx = Context {
            config,
            references: &references,
            log,
        };
        let section = profiles::ProfileComparison.run(&ctx)?;
        write_atomic(
            &config.out.join("section_profiles.md"),
            section_text(&section).as_bytes(),
        )?;
    }
    let units: Vec<usize> = mine
        .iter()
        .filter_map(|w| match w {
            Work::Sweep(i) => Some(*i),
            _ => None,
        })
        .collect();
    let (infos, results) = run_units(&plain, &plan, &units)?;
    let mut text = String::new();
    for (ui, result) in &results {
        match result {
            UnitResult::Runs(runs) => {
                let _ = writeln!(text, "unit\t{ui}\truns\t{}", runs.len());
                for r in runs {
                    let _ = writeln!(text, "{}", r.record());
                }
            }
            UnitResult::Unsupported(why) => {
                let _ = writeln!(text, "unit\t{ui}\tunsupported\t{}", escape(why));
            }
        }
    }
    write_atomic(&config.out.join(RUNS), text.as_bytes())?;
    let mut text = String::new();
    for (si, info) in &infos {
        let _ = writeln!(text, "scene\t{si}\t{}", info.record());
    }
    write_atomic(&config.out.join(SCENES), text.as_bytes())?;
    if mine.contains(&Work::Kernels) {
        let section = kernels::KernelComparison.run(&plain)?;
        write_atomic(
            &config.out.join("section_kernels.md"),
            section_text(&section).as_bytes(),
        )?;
    }
    let mut manifest = String::new();
    for (k, v) in settings(config, &plan.outline()) {
        let _ = writeln!(manifest, "{k}={v}");
    }
    let host = Host::this();
    let _ = writeln!(manifest, "shard={shard}");
    let _ = writeln!(manifest, "host={}", escape(&host.cpu));
    let _ = writeln!(manifest, "host_cores={}", host.cores);
    let _ = writeln!(manifest, "seconds={:e}", started.elapsed().as_secs_f64());
    write_atomic(&config.out.join(MANIFEST), manifest.as_bytes())?;
    log(&format!(
        "shard {shard}: done in {:.1} s; merge with `cargo xtask compare --merge DIR...`",
        started.elapsed().as_secs_f64()
    ));
    Ok(())
}

/// A shard's manifest, read back.
struct Manifest {
    dir: PathBuf,
    shard: Shard,
    /// The settings, in [`settings`]'s order.
    settings: Vec<(String, String)>,
    seconds: f64,
}

impl Manifest {
    /// The value of setting `k` (empty when absent).
    fn setting(&self, k: &str) -> String {
        self.settings
            .iter()
            .find(|(key, _)| key == k)
            .map(|(_, v)| v.clone())
            .unwrap_or_default()
    }
}

fn read_manifest(dir: &Path) -> Result<Manifest, Error> {
    let path = dir.join(MANIFEST);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        Error(format!(
            "{}: cannot read ({e}); is it the directory of a finished `--shard` run?",
            path.display()
        ))
    })?;
    let mut map: Vec<(String, String)> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let (k, v) = line
            .split_once('=')
            .ok_or_else(|| Error(format!("{}:{}: not key=value", path.display(), n + 1)))?;
        map.push((k.to_string(), v.to_string()));
    }
    let get = |k: &str| {
        map.iter()
            .find(|(key, _)| key == k)
            .map(|(_, v)| v.clone())
            .ok_or_else(|| Error(format!("{}: no `{k}`", path.display())))
    };
    let format = get("format")?;
    if format != FORMAT.to_string() {
        return Err(Error(format!(
            "{}: shard format {format}, this version reads {FORMAT}",
            path.display()
        )));
    }
    let shard: Shard = get("shard")?
        .parse()
        .map_err(|e| Error(format!("{}: {e}", path.display())))?;
    let seconds = get("seconds")?.parse().unwrap_or(f64::NAN);
    let keys = [
        "format", "version", "quick", "seed", "photons", "bins", "presets", "scenes", "loaded",
        "skipped", "units",
    ];
    let settings = keys
        .iter()
        .map(|k| Ok((k.to_string(), get(k)?)))
        .collect::<Result<_, Error>>()?;
    Ok(Manifest {
        dir: dir.to_path_buf(),
        shard,
        settings,
        seconds,
    })
}

/// Checks that `manifests` are the shards 1..N of one run; the error names the difference.
fn check_shards(manifests: &[Manifest]) -> Result<(), Error> {
    let first = &manifests[0];
    for m in &manifests[1..] {
        for ((k, a), (_, b)) in first.settings.iter().zip(&m.settings) {
            if a != b {
                return Err(Error(format!(
                    "cannot merge: shard {} ({}) has {k}={b} but shard {} ({}) has {k}={a}",
                    m.shard,
                    m.dir.display(),
                    first.shard,
                    first.dir.display()
                )));
            }
        }
        if m.shard.count != first.shard.count {
            return Err(Error(format!(
                "cannot merge: {} is shard {} but {} is shard {}",
                m.dir.display(),
                m.shard,
                first.dir.display(),
                first.shard
            )));
        }
    }
    let n = first.shard.count;
    for i in 1..=n {
        let with: Vec<&Manifest> = manifests.iter().filter(|m| m.shard.index == i).collect();
        match with.len() {
            1 => {}
            0 => {
                return Err(Error(format!(
                    "cannot merge: shard {i}/{n} is missing (got {})",
                    manifests
                        .iter()
                        .map(|m| format!("{} from {}", m.shard, m.dir.display()))
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
            _ => {
                return Err(Error(format!(
                    "cannot merge: shard {i}/{n} is given twice ({})",
                    with.iter()
                        .map(|m| m.dir.display().to_string())
                        .collect::<Vec<_>>()
                        .join(" and ")
                )));
            }
        }
    }
    Ok(())
}

/// The settings of the run the shards made, as a config writing into `out`.
fn merged_config(m: &Manifest, out: &Path) -> Result<Config, Error> {
    let get = |k: &str| m.setting(k);
    let bad = |k: &str| Error(format!("{}: bad `{k}`", m.dir.join(MANIFEST).display()));
    let list = |k: &str| -> Result<Vec<String>, Error> {
        let text = unescape(&get(k)).ok_or_else(|| bad(k))?;
        Ok(text
            .split(',')
            .filter(|s| !s.is_empty())
            .map(String::from)
            .collect())
    };
    Ok(Config {
        photons: get("photons").parse().map_err(|_| bad("photons"))?,
        seed: get("seed").parse().map_err(|_| bad("seed"))?,
        bins: get("bins").parse().map_err(|_| bad("bins"))?,
        quick: get("quick").parse().map_err(|_| bad("quick"))?,
        ..Config::new(list("presets")?, list("scenes")?, out.to_path_buf())
    })
}

/// Copies every file under `from` into `to` (same relative paths), but the shard's records
/// and its cache.
fn copy_outputs(from: &Path, to: &Path, top: bool) -> Result<(), Error> {
    let entries = std::fs::read_dir(from)
        .map_err(|e| Error(format!("cannot read {}: {e}", from.display())))?;
    for entry in entries {
        let entry = entry.map_err(|e| Error(format!("cannot read {}: {e}", from.display())))?;
        let name = entry.file_name();
        let name_str = name.to_string_lossy();
        let path = entry.path();
        if top && (RECORDS.contains(&name_str.as_ref()) || NOT_COPIED.contains(&name_str.as_ref()))
        {
            continue;
        }
        let target = to.join(&name);
        if path.is_dir() {
            std::fs::create_dir_all(&target)
                .map_err(|e| Error(format!("cannot create {}: {e}", target.display())))?;
            copy_outputs(&path, &target, false)?;
        } else if path.is_file() {
            let bytes = std::fs::read(&path)
                .map_err(|e| Error(format!("cannot read {}: {e}", path.display())))?;
            write_atomic(&target, &bytes)?;
        }
    }
    Ok(())
}

/// Reads a shard's `runs.tsv` into `results` (by unit index); a unit given twice is an error.
fn read_runs(dir: &Path, results: &mut [Option<UnitResult>]) -> Result<(), Error> {
    let path = dir.join(RUNS);
    let text = std::fs::read_to_string(&path)
        .map_err(|e| Error(format!("{}: cannot read ({e})", path.display())))?;
    let bad = |n: usize, why: String| Error(format!("{}:{}: {why}", path.display(), n + 1));
    let mut lines = text.lines().enumerate();
    while let Some((n, line)) = lines.next() {
        let f: Vec<&str> = line.splitn(4, '\t').collect();
        if f.len() != 4 || f[0] != "unit" {
            return Err(bad(n, "expected `unit` INDEX runs|unsupported ...".into()));
        }
        let ui: usize = f[1].parse().map_err(|_| bad(n, "bad unit index".into()))?;
        let result = match f[2] {
            "runs" => {
                let k: usize = f[3].parse().map_err(|_| bad(n, "bad run count".into()))?;
                let mut runs = Vec::with_capacity(k);
                for _ in 0..k {
                    let (n, line) = lines
                        .next()
                        .ok_or_else(|| bad(n, format!("{k} runs announced, file ends")))?;
                    runs.push(scenes::Run::from_record(line).map_err(|e| bad(n, e))?);
                }
                UnitResult::Runs(runs)
            }
            "unsupported" => {
                UnitResult::Unsupported(unescape(f[3]).ok_or_else(|| bad(n, "bad escape".into()))?)
            }
            other => return Err(bad(n, format!("unknown result `{other}`"))),
        };
        let slot = results
            .get_mut(ui)
            .ok_or_else(|| bad(n, format!("unit {ui} is not in the plan")))?;
        if slot.is_some() {
            return Err(bad(
                n,
                format!("unit {ui} was already given by another shard"),
            ));
        }
        *slot = Some(result);
    }
    Ok(())
}

/// `--merge DIR...`: joins shard directories into `config.out`.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<(), Error> {
    let manifests = dirs
        .iter()
        .map(|d| read_manifest(d))
        .collect::<Result<Vec<_>, _>>()?;
    if manifests.is_empty() {
        return Err(Error("--merge needs at least one shard directory".into()));
    }
    check_shards(&manifests)?;
    let out_real = out.canonicalize().ok();
    let same = |a: &Path| out_real.is_some() && a.canonicalize().ok() == out_real;
    if let Some(m) = manifests.iter().find(|m| same(&m.dir)) {
        return Err(Error(format!(
            "cannot merge into {}: it is shard {}'s own directory; give --out another one",
            out.display(),
            m.shard
        )));
    }
    let config = merged_config(&manifests[0], out)?;
    let presets = super::check(&config)?;
    std::fs::create_dir_all(out)
        .map_err(|e| Error(format!("cannot create {}: {e}", out.display())))?;
    let setting = |k: &str| manifests[0].setting(k);
    let scene_names: Vec<String> = unescape(&setting("loaded"))
        .unwrap_or_default()
        .split(',')
        .filter(|s| !s.is_empty())
        .map(String::from)
        .collect();
    let skipped: Vec<String> = setting("skipped")
        .split('\t')
        .filter(|s| !s.is_empty())
        .map(|s| unescape(s).unwrap_or_default())
        .collect();
    let units = SweepUnit::all(scene_names.len(), config.quick);
    if units.len().to_string() != setting("units") {
        return Err(Error(format!(
            "cannot merge: the shards planned {} units, this version plans {}",
            setting("units"),
            units.len()
        )));
    }
    let mut results: Vec<Option<UnitResult>> = vec![None; units.len()];
    let mut info: Vec<Option<SceneInfo>> = vec![None; scene_names.len()];
    let mut sections: BTreeMap<&str, Section> = BTreeMap::new();
    for m in &manifests {
        read_runs(&m.dir, &mut results)?;
        let path = m.dir.join(SCENES);
        let text = std::fs::read_to_string(&path)
            .map_err(|e| Error(format!("{}: cannot read ({e})", path.display())))?;
        for (n, line) in text.lines().enumerate() {
            let bad = |why: String| Error(format!("{}:{}: {why}", path.display(), n + 1));
            let (head, rest) = line
                .strip_prefix("scene\t")
                .and_then(|l| l.split_once('\t'))
                .ok_or_else(|| bad("expected `scene` INDEX ...".into()))?;
            let si: usize = head.parse().map_err(|_| bad("bad scene index".into()))?;
            let parsed = SceneInfo::from_record(rest).map_err(bad)?;
            let slot = info
                .get_mut(si)
                .ok_or_else(|| bad(format!("scene {si} is not in the plan")))?;
            slot.get_or_insert(parsed);
        }
        for name in ["profiles", "kernels"] {
            let path = m.dir.join(format!("section_{name}.md"));
            if path.exists() {
                let text = std::fs::read_to_string(&path)
                    .map_err(|e| Error(format!("{}: cannot read ({e})", path.display())))?;
                if sections
                    .insert(name, parse_section(&text, &path)?)
                    .is_some()
                {
                    return Err(Error(format!(
                        "cannot merge: two shards ran the {name} comparison"
                    )));
                }
            }
        }
        copy_outputs(&m.dir, out, true)?;
    }
    let missing: Vec<usize> = (0..units.len()).filter(|&i| results[i].is_none()).collect();
    if let Some(&first) = missing.first() {
        return Err(Error(format!(
            "cannot merge: {} sweep unit(s) missing from every shard (first: unit {first})",
            missing.len()
        )));
    }
    let results: Vec<UnitResult> = results.into_iter().flatten().collect();
    let outline = PlanOutline {
        scenes: scene_names,
        skipped,
        units,
    };
    let log = |msg: &str| eprintln!("{msg}");
    let ctx = Context {
        config: &config,
        references: &[],
        log: &log,
    };
    let scenes_section = scenes::assemble(&ctx, &outline, &info, &results)?;
    let mut all = Vec::new();
    for (name, section) in [
        ("profiles", sections.remove("profiles")),
        ("scenes", Some(scenes_section)),
        ("kernels", sections.remove("kernels")),
    ] {
        all.push(section.ok_or_else(|| {
            Error(format!(
                "cannot merge: no shard holds the {name} comparison"
            ))
        })?);
    }
    let seconds: Vec<f64> = manifests.iter().map(|m| m.seconds).collect();
    let report = super::assemble_report(
        &config,
        &presets,
        &all,
        seconds.iter().sum(),
        Some(&format!(
            "Merged from {} shards (`--shard I/{}`), {} s in all; per shard: {} s.",
            manifests.len(),
            manifests.len(),
            super::output::md_num(Some(seconds.iter().sum()), 3),
            seconds
                .iter()
                .map(|s| super::output::md_num(Some(*s), 3))
                .collect::<Vec<_>>()
                .join(", ")
        )),
    );
    let path = out.join("report.md");
    write_atomic(&path, report.as_bytes())?;
    eprintln!("merge: {} shards -> {}", manifests.len(), path.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_parses_and_refuses() {
        assert_eq!("2/3".parse::<Shard>(), Ok(Shard { index: 2, count: 3 }));
        assert_eq!("1/1".parse::<Shard>(), Ok(Shard { index: 1, count: 1 }));
        for (text, why) in [
            ("0/0", "N must be at least 1"),
            ("3/2", "I must lie in 1..=N"),
            ("0/2", "I must lie in 1..=N"),
            ("a/2", "I is not a number"),
            ("1/b", "N is not a number"),
            ("12", "no `/`"),
            ("-1/2", "I is not a number"),
        ] {
            let e = text.parse::<Shard>().unwrap_err();
            assert!(e.contains(why) && e.contains(text), "{text}: {e}");
            assert!(!e.contains('\n'));
        }
    }

    /// Every item goes to exactly one shard, the largest first to the emptiest, so no shard
    /// carries more than the ideal share plus the largest item (the LPT bound).
    #[test]
    fn assignment_is_balanced_and_complete() {
        let costs: Vec<f64> = (0..40).map(|i| ((i * 37) % 11 + 1) as f64).collect();
        for n in 1..6 {
            let a = assign(&costs, n);
            assert_eq!(a.len(), costs.len());
            assert!(a.iter().all(|&s| s < n));
            let mut load = vec![0.0; n];
            for (i, &s) in a.iter().enumerate() {
                load[s] += costs[i];
            }
            let total: f64 = costs.iter().sum();
            let max = costs.iter().cloned().fold(0.0, f64::max);
            for l in &load {
                assert!(*l <= total / n as f64 + max, "{load:?}");
            }
            assert_eq!(a, assign(&costs, n), "deterministic");
        }
        // Ties go to the lower shard, in item order.
        assert_eq!(assign(&[1.0, 1.0, 1.0, 1.0], 2), [0, 1, 0, 1]);
        assert_eq!(assign(&[1.0, 5.0, 1.0], 2), [1, 0, 1]);
    }

    #[test]
    fn sections_round_trip() {
        let s = Section {
            title: "Profiles".into(),
            summary: "a | b\n|---|\n".into(),
            body: "## x\n\ntext\n".into(),
        };
        let back = parse_section(&section_text(&s), Path::new("x")).unwrap();
        assert_eq!(
            (back.title, back.summary, back.body),
            (s.title, s.summary, s.body)
        );
        assert!(parse_section("just text", Path::new("x")).is_err());
    }

    /// Relative paths of the files under `dir`, but the cache, the report, results.csv and a
    /// shard's records.
    fn outputs(dir: &Path, prefix: &Path, into: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let e = e.unwrap();
            let name = e.file_name().to_string_lossy().to_string();
            let rel = prefix.join(&name);
            if prefix.as_os_str().is_empty()
                && (NOT_COPIED.contains(&name.as_str()) || RECORDS.contains(&name.as_str()))
            {
                continue;
            }
            if e.path().is_dir() {
                outputs(&e.path(), &rel, into);
            } else {
                into.push(rel);
            }
        }
        into.sort();
    }

    /// Three shards (reading references a `--prepare` job computed) and their merge give the
    /// rows, error figures, pictures and report sections of one unsharded run; merges of
    /// incomplete, repeated or mismatched shards are refused with the difference named.
    #[test]
    fn shards_merge_to_the_unsharded_run() {
        let root = std::env::temp_dir().join(format!("xtask-shards-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(&root).unwrap();
        // The built-in sphere, small: what is tested is the bookkeeping of shards and merges,
        // which every method's rows, pictures and report sections go through at any size (the
        // built-in scene took most of this crate's test time in CI).
        let scene = root.join("small.toml");
        let text = sss_render::scene::BUILTIN_SCENES
            .iter()
            .find(|(n, _)| *n == "sphere")
            .expect("the built-in sphere")
            .1
            .replace("resolution = [160, 120]", "resolution = [48, 36]")
            .replace("units_per_mm = 0.05", "units_per_mm = 0.15");
        assert!(text.contains("[48, 36]") && text.contains("0.15"), "{text}");
        std::fs::write(&scene, text).unwrap();
        let base = Config {
            photons: 2000,
            bins: 20,
            quick: true,
            ..Config::new(
                vec!["skin1".into()],
                vec![scene.to_string_lossy().into_owned()],
                root.join("whole"),
            )
        };
        super::super::run(&base).unwrap();
        let shared = Config {
            cache: Some(root.join("shared-cache")),
            out: root.join("prepare"),
            ..base.clone()
        };
        super::super::run(&Config {
            prepare: true,
            ..shared.clone()
        })
        .unwrap();
        let dirs: Vec<PathBuf> = (1..=3).map(|i| root.join(format!("s{i}"))).collect();
        for (i, dir) in dirs.iter().enumerate() {
            super::super::run(&Config {
                shard: Some(Shard {
                    index: i + 1,
                    count: 3,
                }),
                out: dir.clone(),
                ..shared.clone()
            })
            .unwrap();
        }
        let merged = root.join("merged");
        super::super::run(&Config {
            merge: dirs.clone(),
            out: merged.clone(),
            ..base.clone()
        })
        .unwrap();

        // results.csv: the same rows; every column but the times equal.
        let whole = std::fs::read_to_string(base.out.join("results.csv")).unwrap();
        let joined = std::fs::read_to_string(merged.join("results.csv")).unwrap();
        let (wl, jl): (Vec<&str>, Vec<&str>) = (whole.lines().collect(), joined.lines().collect());
        assert_eq!(wl.len(), jl.len());
        assert!(wl.len() > 10, "{whole}");
        assert_eq!(wl[0], jl[0], "the same columns");
        let header: Vec<&str> = wl[0].split(',').collect();
        for (a, b) in wl[1..].iter().zip(&jl[1..]) {
            let (a, b): (Vec<&str>, Vec<&str>) = (a.split(',').collect(), b.split(',').collect());
            for (k, col) in header.iter().enumerate() {
                if !col.starts_with("seconds_") {
                    assert_eq!(a[k], b[k], "column {col}");
                }
            }
        }
        // The same pictures and tables.
        let (mut a, mut b) = (Vec::new(), Vec::new());
        outputs(&base.out, Path::new(""), &mut a);
        outputs(&merged, Path::new(""), &mut b);
        assert_eq!(a, b);
        assert!(
            a.iter().any(|p| p.ends_with("pathtrace_16_error.png")),
            "{a:?}"
        );
        for csv in ["profiles.csv", "kernels.csv"] {
            let cols = |text: &str| -> Vec<String> {
                // The error columns: those not named for seconds, times or ns.
                let mut lines = text.lines();
                let h: Vec<&str> = lines.next().unwrap().split(',').collect();
                lines
                    .flat_map(|l| {
                        l.split(',')
                            .zip(&h)
                            .filter(|(_, c)| {
                                !(c.contains("seconds") || c.contains("ns_") || c.contains("_ns"))
                            })
                            .map(|(v, _)| v.to_string())
                            .collect::<Vec<_>>()
                    })
                    .collect()
            };
            let x = std::fs::read_to_string(base.out.join(csv)).unwrap();
            let y = std::fs::read_to_string(merged.join(csv)).unwrap();
            assert_eq!(cols(&x), cols(&y), "{csv}");
        }
        let report = std::fs::read_to_string(merged.join("report.md")).unwrap();
        let headings = |t: &str| -> Vec<String> {
            t.lines()
                .filter(|l| l.starts_with('#'))
                .map(String::from)
                .collect()
        };
        let whole_report = std::fs::read_to_string(base.out.join("report.md")).unwrap();
        assert_eq!(headings(&report), headings(&whole_report));
        assert!(report.contains("Merged from 3 shards"), "{report}");

        // Refusals.
        let merge = |dirs: Vec<PathBuf>| {
            super::super::run(&Config {
                merge: dirs,
                out: root.join("refused"),
                ..base.clone()
            })
            .unwrap_err()
            .to_string()
        };
        let e = merge(dirs[..2].to_vec());
        assert!(e.contains("shard 3/3 is missing"), "{e}");
        let e = merge(vec![dirs[0].clone(), dirs[1].clone(), dirs[1].clone()]);
        assert!(e.contains("shard 2/3 is given twice"), "{e}");
        let e = super::super::run(&Config {
            merge: dirs.clone(),
            out: dirs[2].clone(),
            ..base.clone()
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("shard 3/3's own directory"), "{e}");
        let e = merge(vec![root.join("prepare")]);
        assert!(e.contains("shard.txt") && e.contains("cannot read"), "{e}");
        let manifest = dirs[1].join(MANIFEST);
        let text = std::fs::read_to_string(&manifest).unwrap();
        for (from, to, named) in [
            ("seed=1\n", "seed=2\n", "seed=2"),
            ("version=", "version=0.0.0 other", "version=0.0.0 other"),
            ("quick=true", "quick=false", "quick=false"),
        ] {
            assert!(text.contains(from), "{from}");
            std::fs::write(&manifest, text.replacen(from, to, 1)).unwrap();
            let e = merge(dirs.clone());
            assert!(e.contains(named) && e.contains("cannot merge"), "{e}");
            assert!(!e.contains('\n'), "{e}");
        }
        std::fs::write(&manifest, &text).unwrap();
        std::fs::remove_dir_all(&root).unwrap();
    }
}
