//! Workspace automation, run as `cargo xtask <task>` (alias in `.cargo/config.toml`).
//!
//! - `cargo xtask compare`: measures every BSSRDF model against the Monte Carlo reference for
//!   the measured materials and writes `target/compare/report.md`, `results.csv` and plots
//!   (see [`compare`]).

mod compare;

use clap::{Parser, Subcommand};
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
}

fn workspace_root() -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().map(PathBuf::from).unwrap_or(manifest)
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() {
                ExitCode::from(2)
            } else {
                ExitCode::SUCCESS
            };
        }
    };
    let result = match cli.task {
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
