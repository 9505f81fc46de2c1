//! Workspace automation, run as `cargo xtask <task>` (alias in `.cargo/config.toml`).
//!
//! - `cargo xtask compare`: measures every BSSRDF model against the Monte Carlo reference for
//!   the measured materials and writes `target/compare/report.md`, `results.csv` and plots
//!   (see [`compare`]).
//! - `cargo xtask check-results DIR`: checks the values of a compare run's `results.csv`
//!   (see [`check_results`]).
//! - `cargo xtask fuzz`: seeded fuzzing of the scene, OBJ and EXR readers and the `sss`
//!   command line on stable Rust (see [`fuzz`]).
//! - `cargo xtask docs`: regenerates `docs/cli.md`, the command-line reference, and
//!   `docs/test-index.md`, where each source file's tests are (see [`docs`]).
//! - `cargo xtask tables`: regenerates the `mc-table` model's Monte Carlo table
//!   (`crates/bssrdf/data/mc_table.bin`, see [`tables`]).

#![forbid(unsafe_code)]

mod check_results;
mod docs;
mod fuzz;
mod tables;
mod test_index;

use clap::{Parser, Subcommand};
use sss_compare as compare;
use std::path::PathBuf;
use std::process::ExitCode;

/// Workspace automation for the subsurface-scattering toolkit.
#[derive(Debug, Parser)]
#[command(name = "cargo xtask", about)]
struct Cli {
    #[command(subcommand)]
    task: Task,
}

#[derive(Debug, Subcommand)]
enum Task {
    /// Compare every model with the Monte Carlo reference (errors, totals, cost).
    Compare(CompareArgs),
    /// Fuzz the scene, OBJ and EXR readers and the `sss` command line with a seeded mutator.
    Fuzz(FuzzArgs),
    /// Check the values in a compare run's results.csv (ranges, thread-count agreement,
    /// unbiasedness, convergence).
    CheckResults {
        /// The compare output directory (holding results.csv).
        dir: PathBuf,
    },
    /// Regenerate docs/cli.md, the command-line reference, from the clap definitions and the
    /// method registry, and docs/test-index.md, where each source file's tests are.
    Docs {
        /// Compare with the committed files instead of writing them (fails if they differ).
        #[arg(long)]
        check: bool,
    },
    /// Regenerate the Monte Carlo table of the `mc-table` model (bit-identical on every run;
    /// about 700 CPU-seconds, 6 minutes on 2 idle cores).
    Tables(TablesArgs),
}

/// Arguments of `cargo xtask tables`.
#[derive(Debug, clap::Args)]
struct TablesArgs {
    /// Output file [default: WORKSPACE/crates/bssrdf/data/mc_table.bin].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Multiply every photon count by this (trial runs; the repository's table uses 1).
    #[arg(long, default_value_t = 1.0)]
    scale: f64,
    /// Regenerate and compare with the output file instead of writing it (fails if they
    /// differ).
    #[arg(long)]
    check: bool,
    /// Worker threads [default: all cores]; the table is the same for any number.
    #[arg(long)]
    threads: Option<usize>,
    /// Take every table whose g, η and walks this file (version 1 or 2) holds unchanged from
    /// it instead of running its walks again: the same bytes as a full run, since every walk
    /// is seeded. Not with --check.
    #[arg(long, conflicts_with = "check")]
    reuse: Option<PathBuf>,
}

/// Arguments of `cargo xtask fuzz`.
#[derive(Debug, clap::Args)]
struct FuzzArgs {
    /// Seed of every mutation (same seed, same inputs).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Most iterations per target [default: 1000 when --seconds is not given].
    #[arg(long)]
    iterations: Option<u64>,
    /// Wall-clock budget over all targets, split evenly between them.
    #[arg(long)]
    seconds: Option<f64>,
    /// Which target: scene, obj, exr, cli or all.
    #[arg(long, default_value = "all", value_parser = ["scene", "obj", "exr", "cli", "all"])]
    target: String,
    /// Time limit of one input in milliseconds; longer is reported as a hang.
    #[arg(long, default_value_t = 10_000)]
    per_input_ms: u64,
    /// Output directory: work files, crashes/ and the in-flight input [default:
    /// WORKSPACE/target/fuzz].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Run one saved input (e.g. target/fuzz/crashes/scene-….bin) on --target.
    #[arg(long, value_name = "FILE")]
    replay: Option<PathBuf>,
    /// Internal: run the fuzzing in this process (the supervising parent passes it).
    #[arg(long, hide = true)]
    worker: bool,
}

/// Arguments of `cargo xtask compare`.
#[derive(Debug, clap::Args)]
struct CompareArgs {
    /// A fast run: few photons and a subset of presets (skin1, marble, ketchup), unless
    /// --photons / --presets say otherwise.
    #[arg(long)]
    quick: bool,
    /// Comma-separated preset names (default: every measured material).
    #[arg(long, value_delimiter = ',')]
    presets: Option<Vec<String>>,
    /// Monte Carlo photons per channel [default: 100000, or 50000 with --quick].
    #[arg(long)]
    photons: Option<u64>,
    /// Monte Carlo seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Radial bins per channel, over [0, r_max] with r_max holding 99 % of the standard
    /// dipole's reflectance.
    #[arg(long, default_value_t = 100)]
    bins: usize,
    /// Output directory [default: WORKSPACE/target/compare].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Recompute the Monte Carlo and scene references even if cached.
    #[arg(long)]
    fresh: bool,
    /// Comma-separated scenes: built-in names (sphere, toad, picnic, backlit, slab, bunny) or
    /// scene-file paths [default: every built-in scene].
    #[arg(long, value_delimiter = ',')]
    scenes: Option<Vec<String>>,
    /// Directory to search for meshes (repeatable) [default: SSS_MESH_DIR, ../shared/meshes].
    #[arg(long, value_name = "DIR")]
    mesh_dir: Vec<PathBuf>,
    /// Run only the paper-scale tree experiments (Milaenen et al. 2019 on the full-resolution
    /// bunny from the shared meshes, 256² to 2048²; about 50 minutes on 2 cores, a few
    /// with --quick) instead of the default experiments.
    #[arg(long)]
    trees: bool,
    /// Run only the paper-scale many-light experiments (Nabata & Iwasaki 2021 on a Buddha, two
    /// Buddhas and a head from the shared meshes: estimation accuracy against ε, BSSRDF-aware
    /// against Max-Extent, VPL count and mesh refinement) instead of the default experiments
    /// (with --trees, both).
    #[arg(long)]
    manylight: bool,
    /// Run only the sparse many-light experiment: sparse-manylight against manylight on whole
    /// frames of the many-light scenes and on windows of 1080p frames of the Buddha and the
    /// head, scored against a path-traced reference (about an hour on 2 cores, minutes with
    /// --quick).
    #[arg(long)]
    sparse: bool,
    /// Run only the truth experiment: every BSSRDF model, the fast methods and volpath itself
    /// against volumetric light transport (volpath's reference) on spheres, the bunny, the
    /// head and the dragon (meshes from the shared meshes) in four media under a quad or an
    /// environment light; about an hour on 2 cores, a minute with --quick.
    #[arg(long)]
    truth: bool,
    /// Run only the deficit experiment: where the BSSRDF models' error against volumetric
    /// light transport comes from (incidence and exit angles on a half-space, slabs lit from
    /// behind and from the front, spheres of 2-160 mm, the bunny and the dragon scaled 1-16
    /// times, single scattering's share), each image mean to 0.5 % (about 20 minutes on 2
    /// cores; under a minute with --quick).
    #[arg(long)]
    deficit: bool,
    /// With --truth: render every case with Mitsuba 3 and Blender Cycles too (their Python
    /// packages, found through SSS_PEERS_PYTHON or python3), on the same axes; a peer whose
    /// package is missing is skipped with a sentence saying how to install it.
    #[arg(long, requires = "truth")]
    peers: bool,
    /// Run only the I-th of N balanced shares of the default experiments (e.g. 2/8) into
    /// --out, for a cluster's array job; join the shares with --merge. Shards share the
    /// references through --cache (fill it first with --prepare).
    #[arg(long, value_name = "I/N")]
    shard: Option<compare::Shard>,
    /// Join the directories of finished --shard runs into --out: the results.csv, plots and
    /// report.md of an unsharded run (refused if the shards' settings or versions differ).
    #[arg(long, value_name = "DIR", num_args = 1.., conflicts_with_all = ["shard", "prepare"])]
    merge: Vec<PathBuf>,
    /// Only compute every reference (Monte Carlo profiles, each scene's exact render) into the
    /// cache: the first job of a sharded run.
    #[arg(long, conflicts_with = "shard")]
    prepare: bool,
    /// The reference cache [default: OUT/cache]; give shards one on a shared filesystem.
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
    /// One exposure for every picture: linear values are multiplied by this scale before the
    /// sRGB curve [default: per scene, its reference's automatic one, shared by every method].
    #[arg(long, value_name = "SCALE", value_parser = sss_render::image::parse_exposure)]
    exposure: Option<f64>,
}

fn workspace_root() -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().map(PathBuf::from).unwrap_or(manifest)
}

/// `cargo xtask --help` and each task's `--help`, as clap renders them (for `docs/cli.md`).
fn xtask_help() -> Vec<(String, String)> {
    use clap::CommandFactory;
    let mut cmd = Cli::command();
    cmd.build();
    let mut out = vec![(
        "cargo xtask".to_string(),
        cmd.render_long_help().to_string(),
    )];
    for sub in cmd.get_subcommands() {
        if sub.get_name() == "help" {
            continue;
        }
        let mut sub = sub.clone();
        out.push((
            format!("cargo xtask {}", sub.get_name()),
            sub.render_long_help().to_string(),
        ));
    }
    out
}

fn fuzz_main(args: FuzzArgs) -> ExitCode {
    if args.seconds.is_some_and(|s| !(s.is_finite() && s >= 0.0)) {
        eprintln!("error: --seconds must be a non-negative number of seconds");
        return ExitCode::from(2);
    }
    if args.per_input_ms == 0 {
        eprintln!("error: --per-input-ms must be at least 1");
        return ExitCode::from(2);
    }
    let targets = match args.target.as_str() {
        "all" => fuzz::targets::Target::ALL.to_vec(),
        name => fuzz::targets::Target::ALL
            .into_iter()
            .filter(|t| t.name() == name)
            .collect(),
    };
    let root = workspace_root();
    let config = fuzz::Config {
        seed: args.seed,
        iterations: args.iterations,
        seconds: args.seconds,
        targets,
        per_input: std::time::Duration::from_millis(args.per_input_ms),
        out: args.out.unwrap_or_else(|| root.join("target").join("fuzz")),
        shared_meshes: root.join("..").join("shared").join("meshes"),
        replay: args.replay,
    };
    let result = if args.worker {
        fuzz::run_worker(&config)
    } else {
        let forwarded: Vec<String> = std::env::args().skip(1).collect();
        fuzz::run_supervised(&config, &forwarded)
    };
    match result {
        Ok(false) => ExitCode::SUCCESS,
        // Exit at once: a hung input's thread may still be running.
        Ok(true) => std::process::exit(fuzz::CRASH_STATUS),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

fn main() -> ExitCode {
    // Ctrl-C / SIGTERM: delete the temporaries of writes in flight, exit 130.
    sss_cli::install_interrupt_handler();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // Help and version go to stdout as clap writes them; a usage error is one line.
            return if e.use_stderr() {
                eprintln!("{}", sss_cli::one_line(&e.to_string()));
                ExitCode::from(2)
            } else {
                let _ = e.print();
                ExitCode::SUCCESS
            };
        }
    };
    let result = match cli.task {
        Task::Fuzz(args) => return fuzz_main(args),
        Task::Docs { check } => {
            let root = workspace_root();
            return match docs::run(&root, &docs::reference(&xtask_help()), check) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::FAILURE
                }
            };
        }
        Task::Tables(args) => {
            let config = tables::Config {
                out: args
                    .out
                    .unwrap_or_else(|| tables::default_path(&workspace_root())),
                scale: args.scale,
                check: args.check,
                reuse: args.reuse,
            };
            let result = match args.threads {
                Some(0) => Err("--threads must be at least 1".to_string()),
                Some(n) => rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .map_err(|e| e.to_string())
                    .and_then(|pool| pool.install(|| tables::run(&config))),
                None => tables::run(&config),
            };
            return match result {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::FAILURE
                }
            };
        }
        Task::CheckResults { dir } => {
            return match check_results::run(&dir) {
                Ok(n) => {
                    println!("check-results: {n} rows of results.csv pass every check");
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::FAILURE
                }
            };
        }
        Task::Compare(args) => {
            let presets = match args.presets {
                Some(p) => p,
                None if args.quick => compare::QUICK_PRESETS
                    .iter()
                    .map(|s| s.to_string())
                    .collect(),
                None => sss_bssrdf::presets::PRESETS
                    .iter()
                    .map(|p| p.name.to_string())
                    .collect(),
            };
            let config = compare::Config {
                presets,
                photons: args.photons.unwrap_or(if args.quick {
                    compare::QUICK_PHOTONS
                } else {
                    compare::DEFAULT_PHOTONS
                }),
                seed: args.seed,
                bins: args.bins,
                out: args
                    .out
                    .unwrap_or_else(|| workspace_root().join("target").join("compare")),
                fresh: args.fresh,
                scenes: args.scenes.unwrap_or_else(|| {
                    sss_render::scene::BUILTIN_SCENES
                        .iter()
                        .map(|(n, _)| n.to_string())
                        .collect()
                }),
                mesh_dirs: if args.mesh_dir.is_empty() {
                    compare::default_mesh_dirs(&workspace_root())
                } else {
                    args.mesh_dir
                },
                quick: args.quick,
                trees: args.trees,
                manylight: args.manylight,
                sparse: args.sparse,
                truth: args.truth,
                deficit: args.deficit,
                peers: args.peers,
                shard: args.shard,
                merge: args.merge,
                prepare: args.prepare,
                cache: args.cache,
                exposure: args.exposure,
            };
            compare::run(&config)
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The committed command-line reference is what `cargo xtask docs` generates now: a flag,
    /// default or help text changed without regenerating it fails here.
    #[test]
    fn the_committed_cli_reference_is_current() {
        let root = workspace_root();
        let text = docs::reference(&xtask_help());
        if let Err(e) = docs::run(&root, &text, true) {
            panic!("{e}");
        }
        // The generator sees every task, hidden flags excepted.
        for task in ["compare", "fuzz", "check-results", "docs", "tables"] {
            assert!(text.contains(&format!("## `cargo xtask {task}`")), "{task}");
        }
        assert!(!text.contains("--worker"), "a hidden flag is documented");
        for e in sss_compare::EXPERIMENTS {
            assert!(text.contains(&format!("| `{}` |", e.name)), "{}", e.name);
        }
    }

    /// A bad `--shard` is one line naming the value and the rule; `--merge` and `--shard`
    /// do not go together.
    #[test]
    fn bad_shard_is_one_line() {
        for (value, why) in [
            ("0/0", "N must be at least 1"),
            ("3/2", "I must lie in 1..=N"),
            ("two/3", "I is not a number"),
        ] {
            let e = Cli::try_parse_from(["cargo xtask", "compare", "--shard", value]).unwrap_err();
            assert!(e.use_stderr());
            let line = sss_cli::one_line(&e.to_string());
            assert!(!line.contains('\n'), "{line}");
            assert!(line.starts_with("error: "), "{line}");
            assert!(line.contains(value) && line.contains(why), "{line}");
        }
        let ok = Cli::try_parse_from(["cargo xtask", "compare", "--shard", "2/3"]).unwrap();
        let Task::Compare(args) = ok.task else {
            panic!("not compare");
        };
        assert_eq!(args.shard, Some(compare::Shard { index: 2, count: 3 }));
        assert!(
            Cli::try_parse_from(["cargo xtask", "compare", "--shard", "1/2", "--merge", "a"])
                .is_err()
        );
    }
}
