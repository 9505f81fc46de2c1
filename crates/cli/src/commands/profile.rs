//! `sss profile`: the radial profile R_d(r) of a model (or the Monte Carlo reference) as CSV,
//! optionally plotted.

use crate::args::{MediumArgs, names_parser};
use crate::plot_error;
use clap::Args;
use sss_bssrdf::profile_rows::{ProfileModel, ProfileRequest, ProfileRows, check_budget, compute};
use sss_plot::{CHANNEL_COLORS, ErrorStyle, PlotError, Series, line_plot};
use sss_render::Error;
use std::path::{Path, PathBuf};

/// Arguments of `sss profile`.
#[derive(Debug, Args)]
pub struct ProfileArgs {
    /// The model, or the Monte Carlo reference.
    #[arg(long, value_parser = names_parser::<ProfileModel>(ProfileModel::ALL.map(|m| m.name())))]
    pub model: ProfileModel,
    /// The medium.
    #[command(flatten)]
    pub medium: MediumArgs,
    /// Largest radius in mm.
    #[arg(long, allow_hyphen_values = true)]
    pub r_max: f64,
    /// Number of radii (or Monte Carlo bins).
    #[arg(long)]
    pub steps: usize,
    /// Log-spaced radii from r_max·1e-4 to r_max (models only).
    #[arg(long)]
    pub log: bool,
    /// Also draw the profile to this file (.png or .svg).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Monte Carlo photons per channel. They cost time only, not memory: photons are traced
    /// and tallied in batches, never stored.
    #[arg(long, default_value_t = 1_000_000)]
    pub photons: u64,
    /// Monte Carlo seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Memory budget (bytes, or with a suffix: 512M, 8G); a profile whose rows (or Monte Carlo
    /// bins) are estimated to need more is refused before anything is allocated. Default: half
    /// the physical memory.
    #[arg(long, value_name = "BYTES", value_parser = sss_render::budget::parse_bytes)]
    pub max_memory: Option<u64>,
}

impl ProfileArgs {
    /// The library request these arguments describe.
    pub fn request(&self) -> Result<ProfileRequest, Error> {
        let medium = self.medium.spec()?;
        Ok(ProfileRequest {
            model: self.model,
            medium,
            eta: self.medium.eta,
            r_max: self.r_max,
            steps: self.steps,
            log: self.log,
            photons: self.photons,
            seed: self.seed,
        })
    }
}

/// Runs `sss profile`: the CSV bytes for stdout (after the plot, if any, is written).
pub fn run(args: &ProfileArgs) -> Result<Vec<u8>, Error> {
    let req = args.request()?;
    check_budget(
        &req,
        args.max_memory
            .unwrap_or_else(sss_render::budget::default_budget),
    )?;
    if let Some(path) = &args.plot {
        // Fail on a bad extension or directory before a long computation.
        sss_plot::check_writable(path).map_err(plot_error)?;
    }
    let bar = (req.model == ProfileModel::MonteCarlo)
        .then(|| crate::progress::bar(3 * req.photons, "photons"));
    let table = compute(&req, &|n| {
        if let Some(b) = &bar {
            b.set_position(n);
        }
    });
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let table = table?;
    if let Some(path) = &args.plot {
        plot(&table, path, req.log).map_err(plot_error)?;
    }
    let mut buf = Vec::new();
    table.write_csv(&mut buf).map_err(|source| Error::Io {
        what: "formatting the CSV".into(),
        source,
    })?;
    Ok(buf)
}

/// Draws the three channels of `rows` on a log y axis (log x too when `log_x`), Monte Carlo
/// with its standard errors as a band, to `path` (`.png` or `.svg`).
pub fn plot(rows: &ProfileRows, path: &Path, log_x: bool) -> Result<(), PlotError> {
    let names = ["red", "green", "blue"];
    let series: Vec<Series> = (0..3)
        .map(|ch| {
            let points = rows.rows.iter().map(|r| (r.r, r.rd[ch])).collect();
            let s = Series::line(names[ch], points).with_color(CHANNEL_COLORS[ch]);
            if rows.has_se() {
                let err = rows
                    .rows
                    .iter()
                    .map(|r| r.se.map_or(0.0, |se| se[ch]))
                    .collect();
                s.with_errors(err, ErrorStyle::Band)
            } else {
                s
            }
        })
        .collect();
    let title = format!("Rd(r), {}: {}", rows.model.name(), rows.medium_label);
    line_plot(path, &title, "r (mm)", "Rd (1/mm²)", &series, log_x, true)
}
