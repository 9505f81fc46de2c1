//! `cargo xtask tables`: regenerates the tabulated Monte Carlo profile of the `mc-table` model
//! (`crates/bssrdf/data/mc_table.bin`, see `sss_bssrdf::mc_table`).
//!
//! Every walk has a fixed seed and stream and the Monte Carlo is bit-identical for any number
//! of threads, so the file is the same bytes on every run. `--check` regenerates it and
//! compares it with the file in the repository instead of writing it; `--scale` multiplies
//! every photon count (for trial runs; the repository's table is `--scale 1`); `--reuse FILE`
//! copies the tables FILE holds with the same walks instead of running them again.

use sss_bssrdf::mc_table::McTableData;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of `cargo xtask tables`.
#[derive(Debug)]
pub struct Config {
    /// Where the table goes.
    pub out: PathBuf,
    /// Photon multiplier (1 for the repository's table).
    pub scale: f64,
    /// Compare with `out` instead of writing it.
    pub check: bool,
    /// A table file (version 1 or 2) whose unchanged tables are copied instead of re-run.
    pub reuse: Option<PathBuf>,
}

/// The repository's table file.
pub fn default_path(root: &Path) -> PathBuf {
    root.join("crates")
        .join("bssrdf")
        .join("data")
        .join("mc_table.bin")
}

/// Runs the walks and writes (or checks) the table.
pub fn run(config: &Config) -> Result<(), String> {
    let start = Instant::now();
    eprintln!(
        "tables: mc-table Monte Carlo on {} threads, photon scale {}",
        rayon::current_num_threads(),
        config.scale
    );
    let reuse = match &config.reuse {
        Some(path) => {
            let bytes =
                std::fs::read(path).map_err(|e| format!("reading {}: {e}", path.display()))?;
            let data = McTableData::from_bytes(&bytes)
                .or_else(|_| McTableData::from_bytes_v1(&bytes))
                .map_err(|e| format!("{}: {e}", path.display()))?;
            Some(data)
        }
        None => None,
    };
    let data = McTableData::generate_reusing(config.scale, reuse.as_ref(), &|line| {
        eprintln!("  [{:7.1} s] {line}", start.elapsed().as_secs_f64())
    })
    .map_err(|e| e.to_string())?;
    let bytes = data.to_bytes();
    let seconds = start.elapsed().as_secs_f64();
    if config.check {
        let old = std::fs::read(&config.out)
            .map_err(|e| format!("reading {}: {e}", config.out.display()))?;
        if old != bytes {
            return Err(format!(
                "{} differs from the regenerated table ({} vs {} bytes); run `cargo xtask \
                 tables` to rewrite it",
                config.out.display(),
                old.len(),
                bytes.len()
            ));
        }
        println!(
            "tables: {} is bit-identical to the regenerated table ({} bytes, {seconds:.0} s)",
            config.out.display(),
            bytes.len()
        );
        return Ok(());
    }
    sss_util::write_atomic(&config.out, &bytes)
        .map_err(|e| format!("writing {}: {e}", config.out.display()))?;
    println!(
        "tables: wrote {} ({} bytes) in {seconds:.0} s",
        config.out.display(),
        bytes.len()
    );
    Ok(())
}
