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

mod balance;
mod manifest;
mod merge;
#[cfg(test)]
mod tests;

use super::host::Host;
use super::output::write_atomic;
use super::scenes::{
    self, PlanOutline, SceneInfo, SweepUnit, UnitResult, escape, run_units, unescape,
};
use super::{Config, Context, Error, Experiment, Section, kernels, profiles, walk_reference};
use balance::*;
use manifest::*;
pub use merge::merge;
use sss_render::integrators::METHODS;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Instant;

/// Version of the shard files' layout; bump when it changes.
const FORMAT: u32 = 2;

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

/// `--prepare`: computes every reference the default experiments use (the Monte Carlo profile
/// of every preset and channel, and every scene's `exact` render) into the cache, and nothing
/// else.
pub fn prepare(config: &Config, ctx_log: &dyn Fn(&str)) -> Result<(), Error> {
    let presets = super::check(config)?;
    let bar = sss_util::progress::bar(presets.len() as u64 * 3 * config.photons, "photons");
    walk_reference::load_or_compute(config, &presets, ctx_log, &bar)?;
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
        let bar = sss_util::progress::bar(presets.len() as u64 * 3 * config.photons, "photons");
        let references = walk_reference::load_or_compute(config, &presets, log, &bar)?;
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
