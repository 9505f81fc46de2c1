//! # sss-compare: the comparison experiments behind `cargo xtask compare`
//!
//! The project's main measurement, as a library: every BSSRDF model against the Monte Carlo
//! reference, every rendering method against an independent reference, error against run
//! time, written as `report.md`, `results.csv`, `profiles.csv`, images and plots. `cargo
//! xtask compare` parses its flags into a [`Config`] and calls [`run`]; use the library to run
//! the experiments from your own driver or a cluster job.
//!
//! 1. For every selected preset and channel, the Monte Carlo reference is loaded from the
//!    cache or simulated (module `reference`).
//! 2. Each selected [`Experiment`] of the registry [`EXPERIMENTS`] uses the references and
//!    contributes a report [`Section`] plus its own files: `profiles` (every model's radial
//!    profile against Monte Carlo), `scenes` (every rendering method over its sweep) and
//!    `kernels` (the separable kernels) by default; `trees` and `manylight`, the paper-scale
//!    experiments, and `truth` (every model against volumetric light transport), by their
//!    flags.
//! 3. `report.md` is assembled from the sections, and `report.html` from it and the pictures
//!    (module `html`: one self-contained page with image comparisons, FLIP maps and charts).
//!
//! Each experiment is a module of its own, split by concern (its plan, runs, scoring, plots
//! or images, and report), and every CSV it writes goes through one writer (module `output`),
//! so every file formats its numbers, cleans its text fields and ends its lines the same way.
//!
//! Everything random is seeded ([`Config::seed`]), so error figures are reproducible; only
//! the timings vary from run to run.
//!
//! The default experiments can be split over many machines (module `shard`): `--prepare` fills the
//! reference cache, `--shard I/N` runs a share of the work, `--merge` joins the shares into
//! the same `results.csv`, plots and report.
//!
//! ```no_run
//! use sss_compare::{Config, run};
//!
//! // Profiles of one preset and the sphere scene's renders, into target/compare-sphere.
//! let mut config = Config::new(
//!     vec!["skin1".into()],
//!     vec!["sphere".into()],
//!     "target/compare-sphere".into(),
//! );
//! config.quick = true;
//! run(&config)?;
//! # Ok::<(), sss_compare::Error>(())
//! ```
//!
//! ## Papers
//! What it measures is the other crates' (their docs cite the papers); the experiments test
//! the claims of Jensen et al. 2001 and d'Eon 2012 (profiles against MCML-style Monte Carlo,
//! Wang et al. 1995), Jimenez et al. 2015 (kernels), Milaenen et al. 2019 (`trees`) and Nabata
//! & Iwasaki 2021 (`manylight`, with Walter et al. 2006 and Sakai et al. 2019 as baselines);
//! `truth` scores every model against volumetric path tracing (pbrt 3rd ed. §15.3).

#![forbid(unsafe_code)]

mod checked;
mod host;
mod html;
mod kernels;
mod manylight;
mod output;
mod profiles;
mod scenes;
mod shard;
mod subset;
mod trees;
mod truth;
mod walk_reference;

pub use scenes::default_mesh_dirs;
pub use shard::Shard;

use output::write_atomic;
use sss_bssrdf::presets::{self, Preset};
use std::fmt;
use std::path::PathBuf;
use std::time::Instant;
use walk_reference::PresetReference;

/// Presets of `--quick`: a typical translucent material (skin1), a nearly non-absorbing one
/// (marble) and a strongly absorbing one (ketchup, whose blue channel reflects almost
/// nothing).
pub const QUICK_PRESETS: [&str; 3] = ["skin1", "marble", "ketchup"];

/// Photons per channel of `--quick`.
pub const QUICK_PHOTONS: u64 = 50_000;

/// Photons per channel of a full run (about 4 minutes of simulation on 2 cores, most of it
/// spectralon, whose albedo-1 walks are long; cached afterwards).
pub const DEFAULT_PHOTONS: u64 = 100_000;

/// What `compare` does.
#[derive(Clone, Debug)]
pub struct Config {
    /// Preset names.
    pub presets: Vec<String>,
    /// Monte Carlo photons per channel.
    pub photons: u64,
    /// Monte Carlo seed.
    pub seed: u64,
    /// Radial bins per channel.
    pub bins: usize,
    /// Output directory.
    pub out: PathBuf,
    /// Ignore cached references.
    pub fresh: bool,
    /// Scenes to render: built-in names or scene-file paths.
    pub scenes: Vec<String>,
    /// Directories searched for meshes the scenes name.
    pub mesh_dirs: Vec<PathBuf>,
    /// The fast variant (smaller images, shorter sweeps).
    pub quick: bool,
    /// Run only the paper-scale tree experiments (module `trees`).
    pub trees: bool,
    /// Run only the paper-scale many-light experiments (module `manylight`).
    pub manylight: bool,
    /// Run only the sparse many-light experiment: `sparse-manylight` against `manylight` on
    /// whole frames and on windows of 1080p frames, against a path-traced reference (module
    /// `manylight::sparse`).
    pub sparse: bool,
    /// Run only the truth experiment: every model against volumetric light transport (module
    /// `truth`).
    pub truth: bool,
    /// Run only the deficit experiment: where the models' error against volumetric light
    /// transport comes from, on controlled set-ups (module `truth::deficit`).
    pub deficit: bool,
    /// With `truth`: render its cases with the peers too (Mitsuba 3), when installed.
    pub peers: bool,
    /// Run only this share of the default experiments (module `shard`).
    pub shard: Option<Shard>,
    /// Join these shard directories into `out` instead of running anything (module `shard`).
    pub merge: Vec<PathBuf>,
    /// Only compute the references into the cache (the first job of a sharded run).
    pub prepare: bool,
    /// The cache directory [default: `out/cache`].
    pub cache: Option<PathBuf>,
    /// The exposure of every picture (`sss_render::image::write_png`'s scale), or `None` for
    /// each scene's automatic one (its reference's); every method of a scene is drawn at its
    /// reference's exposure either way.
    pub exposure: Option<f64>,
}

impl Config {
    /// The default experiments of `presets` and `scenes` into `out`, with the defaults of
    /// `cargo xtask compare` for the rest (full run, seed 1, no cache elsewhere, no sharding).
    pub fn new(presets: Vec<String>, scenes: Vec<String>, out: PathBuf) -> Config {
        Config {
            presets,
            photons: DEFAULT_PHOTONS,
            seed: 1,
            bins: 100,
            out,
            fresh: false,
            scenes,
            mesh_dirs: Vec::new(),
            quick: false,
            trees: false,
            manylight: false,
            sparse: false,
            truth: false,
            deficit: false,
            peers: false,
            shard: None,
            merge: Vec::new(),
            prepare: false,
            cache: None,
            exposure: None,
        }
    }

    /// True when only flagged experiments run (they use no Monte Carlo reference).
    pub fn paper_only(&self) -> bool {
        self.trees || self.manylight || self.sparse || self.truth || self.deficit
    }

    /// Where references are cached: `--cache`, or `cache/` in the output directory.
    pub fn cache_dir(&self) -> PathBuf {
        self.cache.clone().unwrap_or_else(|| self.out.join("cache"))
    }
}

/// The workspace root (this crate lives in `crates/compare`): where the shared data next to
/// the repository (`../shared`) and git are looked up.
pub fn workspace_root() -> PathBuf {
    let manifest = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest
        .ancestors()
        .nth(2)
        .unwrap_or(manifest)
        .to_path_buf()
}

/// A failure, with a message for a person.
#[derive(Debug)]
pub struct Error(pub String);

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

/// What an experiment sees.
pub struct Context<'a> {
    /// The run's configuration (output directory, seed, …).
    pub config: &'a Config,
    /// The Monte Carlo reference of every selected preset, in the order given.
    pub references: &'a [PresetReference],
    /// Prints a progress line (above the progress bars, or plainly when stderr is not a
    /// terminal).
    pub log: &'a dyn Fn(&str),
}

/// An experiment's part of the report.
pub struct Section {
    /// Heading.
    pub title: String,
    /// Markdown for the summary at the top of the report.
    pub summary: String,
    /// Markdown with the details.
    pub body: String,
}

/// One part of the comparison.
pub trait Experiment {
    /// Short name, for progress messages.
    fn name(&self) -> &'static str;
    /// Runs the experiment, writing its files under `ctx.config.out`.
    fn run(&self, ctx: &Context<'_>) -> Result<Section, Error>;
}

/// When an experiment runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Selection {
    /// In every default run (and in its shards and merges).
    Default,
    /// Only when asked for by its own flag (`--trees`, `--manylight`, `--sparse`, `--truth`,
    /// `--deficit`): a
    /// paper-scale or long experiment, which needs no Monte Carlo reference and runs instead of
    /// the default ones.
    Flag(&'static str),
}

/// A registry entry: what the command line and the run loop need to know of an experiment.
#[derive(Clone, Copy, Debug)]
pub struct ExperimentEntry {
    /// Its name, as [`Experiment::name`] gives it.
    pub name: &'static str,
    /// One line for documentation.
    pub about: &'static str,
    /// When it runs.
    pub selection: Selection,
    /// Builds it.
    pub build: fn() -> Box<dyn Experiment>,
}

/// Every experiment, in report order.
pub const EXPERIMENTS: &[ExperimentEntry] = &[
    ExperimentEntry {
        name: "profiles",
        about: "every model's radial profile against the Monte Carlo reference (and MCML's)",
        selection: Selection::Default,
        build: || Box::new(profiles::ProfileComparison),
    },
    ExperimentEntry {
        name: "scenes",
        about: "every rendering method over its sweep on every scene, against the exact reference",
        selection: Selection::Default,
        build: || Box::new(scenes::SceneComparison),
    },
    ExperimentEntry {
        name: "kernels",
        about: "every separable kernel per material on synthetic frames: cost and error",
        selection: Selection::Default,
        build: || Box::new(kernels::KernelComparison),
    },
    ExperimentEntry {
        name: "trees",
        about: "Milaenen et al.'s claims at paper scale: the tree methods' error against time",
        selection: Selection::Flag("trees"),
        build: || Box::new(trees::TreeExperiment),
    },
    ExperimentEntry {
        name: "manylight",
        about: "Nabata & Iwasaki's claims at paper scale against a path-traced reference",
        selection: Selection::Flag("manylight"),
        build: || Box::new(manylight::ManyLightExperiment),
    },
    ExperimentEntry {
        name: "sparse",
        about: "sparse-manylight (estimates where s_p asks, the rest reconstructed with an \
                interval) against manylight on whole frames and 1080p windows, against a \
                path-traced reference",
        selection: Selection::Flag("sparse"),
        build: || Box::new(manylight::sparse::SparseExperiment),
    },
    ExperimentEntry {
        name: "truth",
        about: "every model, the fast methods and volpath itself against volumetric light \
                transport (volpath's reference)",
        selection: Selection::Flag("truth"),
        build: || Box::new(truth::TruthExperiment),
    },
    ExperimentEntry {
        name: "deficit",
        about: "where the models' error against volumetric light transport comes from: \
                incidence and exit angles, thin slabs, curvature and object size, single \
                scattering, on controlled set-ups",
        selection: Selection::Flag("deficit"),
        build: || Box::new(truth::deficit::DeficitExperiment),
    },
];

/// The experiments `config` selects, in report order: those whose flag it sets, or the
/// default ones when it sets none.
fn experiments(config: &Config) -> Vec<Box<dyn Experiment>> {
    let flagged = |f: &str| match f {
        "trees" => config.trees,
        "manylight" => config.manylight,
        "sparse" => config.sparse,
        "truth" => config.truth,
        "deficit" => config.deficit,
        _ => false,
    };
    EXPERIMENTS
        .iter()
        .filter(|e| match e.selection {
            Selection::Default => !config.paper_only(),
            Selection::Flag(f) => flagged(f),
        })
        .map(|e| (e.build)())
        .collect()
}

fn check(config: &Config) -> Result<Vec<&'static Preset>, Error> {
    if config.presets.is_empty() {
        return Err(Error("no presets selected".into()));
    }
    if config.photons == 0 {
        return Err(Error("--photons must be at least 1".into()));
    }
    if config.bins == 0 || config.bins > 100_000 {
        return Err(Error(format!(
            "--bins {} must lie in 1..=100000",
            config.bins
        )));
    }
    let mut out: Vec<&'static Preset> = Vec::new();
    for name in &config.presets {
        let p = presets::find(name).map_err(|e| {
            let all: Vec<&str> = presets::PRESETS.iter().map(|p| p.name).collect();
            Error(format!("{e}; known presets: {}", all.join(", ")))
        })?;
        if !out.iter().any(|q| q.name == p.name) {
            out.push(p);
        }
    }
    Ok(out)
}

/// Runs the whole comparison (or, with [`Config::merge`], [`Config::shard`] or
/// [`Config::prepare`], that part of it).
pub fn run(config: &Config) -> Result<(), Error> {
    let started = Instant::now();
    let sharding = config.shard.is_some() || config.prepare || !config.merge.is_empty();
    if sharding && config.paper_only() {
        return Err(Error(
            "--shard, --prepare and --merge split the default experiments; they do not go \
             with --trees, --manylight, --sparse, --truth or --deficit"
                .into(),
        ));
    }
    if config.shard.is_some() && config.fresh {
        return Err(Error(
            "--fresh with --shard would recompute the references in every shard; run \
             `--prepare --fresh` once first"
                .into(),
        ));
    }
    if !config.merge.is_empty() {
        return shard::merge(&config.merge, &config.out);
    }
    let presets = check(config)?;
    std::fs::create_dir_all(&config.out).map_err(|e| {
        Error(format!(
            "cannot create output directory '{}': {e}",
            config.out.display()
        ))
    })?;
    let log_line = |msg: &str| eprintln!("{msg}");
    if config.prepare {
        return shard::prepare(config, &log_line);
    }
    if let Some(s) = config.shard {
        return shard::run_shard(config, s, &log_line);
    }
    let bar = sss_util::progress::bar(presets.len() as u64 * 3 * config.photons, "photons");
    let log = |msg: &str| {
        if bar.is_hidden() {
            eprintln!("{msg}");
        } else {
            bar.println(msg);
        }
    };
    if !config.paper_only() {
        log(&format!(
            "compare: {} preset(s), {} photons per channel, seed {}, {} bins -> {}",
            presets.len(),
            config.photons,
            config.seed,
            config.bins,
            config.out.display()
        ));
    }
    // The paper-scale experiments use no Monte Carlo reference.
    let references = if config.paper_only() {
        Vec::new()
    } else {
        walk_reference::load_or_compute(config, &presets, &log, &bar)?
    };
    bar.finish_and_clear();
    let ctx = Context {
        config,
        references: &references,
        log: &|msg| eprintln!("{msg}"),
    };
    let mut sections = Vec::new();
    for exp in experiments(config) {
        eprintln!("experiment {}", exp.name());
        sections.push(exp.run(&ctx)?);
    }
    let report = assemble_report(
        config,
        &presets,
        &sections,
        started.elapsed().as_secs_f64(),
        None,
    );
    let path = config.out.join("report.md");
    write_atomic(&path, report.as_bytes())?;
    html::write(&config.out, &report)?;
    eprintln!(
        "compare: done in {:.1} s; wrote {}",
        started.elapsed().as_secs_f64(),
        path.display()
    );
    Ok(())
}

/// `report.md` from the sections, with `note` (if any) after the opening paragraph.
fn assemble_report(
    config: &Config,
    presets: &[&Preset],
    sections: &[Section],
    seconds: f64,
    note: Option<&str>,
) -> String {
    let names: Vec<&str> = presets.iter().map(|p| p.name).collect();
    let mut s = String::new();
    s.push_str("# Subsurface-scattering models: comparison report\n\n");
    s.push_str(&format!(
        "Generated by `cargo xtask compare`. Presets: {}. Monte Carlo: {} photons per channel, \
         seed {}, {} linear bins per channel over [0, r_max], r_max holding {:.0} % of the \
         standard dipole's reflectance. Media: Jensen et al. 2001 Table 2 (g = 0, η = 1.3). \
         Run time {seconds:.1} s.\n\n",
        names.join(", "),
        config.photons,
        config.seed,
        config.bins,
        100.0 * walk_reference::R_MAX_ENERGY,
    ));
    if let Some(note) = note {
        s.push_str(note);
        s.push_str("\n\n");
    }
    s.push_str("## Summary\n\n");
    for sec in sections {
        s.push_str(&format!("### {}\n\n{}\n", sec.title, sec.summary));
    }
    for sec in sections {
        s.push_str(&format!("## {}\n\n{}\n", sec.title, sec.body));
    }
    s
}

#[cfg(test)]
mod registry_tests {
    use super::*;

    /// Each entry builds the experiment it names; a default run selects the three default
    /// experiments in report order, a flag selects its experiment alone, and both flags both.
    #[test]
    fn the_registry_selects_by_flag() {
        for e in EXPERIMENTS {
            assert_eq!((e.build)().name(), e.name);
        }
        let names =
            |c: &Config| -> Vec<&'static str> { experiments(c).iter().map(|e| e.name()).collect() };
        let mut c = Config::new(vec!["skin1".into()], Vec::new(), PathBuf::from("x"));
        assert_eq!(names(&c), ["profiles", "scenes", "kernels"]);
        c.trees = true;
        assert_eq!(names(&c), ["trees"]);
        c.manylight = true;
        assert_eq!(names(&c), ["trees", "manylight"]);
        c.trees = false;
        assert_eq!(names(&c), ["manylight"]);
        c.manylight = false;
        c.sparse = true;
        assert_eq!(names(&c), ["sparse"]);
        c.sparse = false;
        c.truth = true;
        assert_eq!(names(&c), ["truth"]);
        c.deficit = true;
        assert_eq!(names(&c), ["truth", "deficit"]);
        c.truth = false;
        assert_eq!(names(&c), ["deficit"]);
    }
}
