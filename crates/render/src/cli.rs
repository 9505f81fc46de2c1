//! The `sss` command line: argument definitions (clap derive) and [`main`], which the binary
//! calls. Every failure ends in a single `error: …` line on stderr and a non-zero exit code
//! (2 for bad input, 1 for failures while running); nothing is written to stdout then.

use crate::Error;
use crate::filter_cli::{FilterArgs, run_filter};
use crate::kernel_cli::{KernelArgs, run_kernel};
use crate::presets_table::presets_table;
use crate::profile::{MediumSpec, ProfileModel, ProfileRequest, compute};
use crate::render_cli::{DiffArgs, RenderArgs, run_diff, run_render};
use clap::{ArgGroup, Args, Parser, Subcommand};
use sss_bssrdf::Rgb;
use std::ffi::OsString;
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

/// Subsurface-scattering toolkit: BSSRDF profiles and measured materials.
#[derive(Debug, Parser)]
#[command(name = "sss", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Print the radial profile Rd(r) of a model (or the Monte Carlo reference) as CSV.
    Profile(ProfileArgs),
    /// List the measured materials of Jensen et al. 2001 (Table 2).
    Presets(PresetsArgs),
    /// Render a scene's subsurface term with a reference integrator (EXR and/or PNG out).
    Render(RenderArgs),
    /// Compare two renders: error figures and a false-colour error map.
    Diff(DiffArgs),
    /// Export a separable screen-space kernel (JSON, CSV, GLSL or HLSL).
    Kernel(KernelArgs),
    /// Run the screen-space separable pass on inputs read from an EXR file.
    Filter(FilterArgs),
}

/// The medium of `sss profile` and `sss kernel`: a preset, or coefficients.
#[derive(Debug, Args)]
#[command(group(ArgGroup::new("medium").required(true).args(["preset", "sigma_a"])))]
pub struct MediumArgs {
    /// A measured material (see `sss presets`); g = 0 and sigma_s = sigma_s'.
    #[arg(long, conflicts_with_all = ["sigma_a", "sigma_s", "g"])]
    pub preset: Option<String>,
    /// Absorption coefficients R,G,B in 1/mm.
    #[arg(long, value_name = "R,G,B", value_parser = parse_rgb, allow_hyphen_values = true, requires = "sigma_s")]
    pub sigma_a: Option<Rgb>,
    /// Scattering coefficients R,G,B in 1/mm.
    #[arg(long, value_name = "R,G,B", value_parser = parse_rgb, allow_hyphen_values = true, requires = "sigma_a")]
    pub sigma_s: Option<Rgb>,
    /// Henyey-Greenstein anisotropy (with --sigma-a/--sigma-s) [default: 0].
    #[arg(long, allow_hyphen_values = true)]
    pub g: Option<f64>,
    /// Relative index of refraction [default: 1.3].
    #[arg(long, allow_hyphen_values = true)]
    pub eta: Option<f64>,
}

impl MediumArgs {
    /// The medium these arguments name (without η, which callers pass on separately).
    pub fn spec(&self) -> Result<MediumSpec, Error> {
        match (&self.preset, self.sigma_a, self.sigma_s) {
            (Some(name), None, None) => Ok(MediumSpec::Preset(name.clone())),
            (None, Some(sigma_a), Some(sigma_s)) => Ok(MediumSpec::Coefficients {
                sigma_a,
                sigma_s,
                g: self.g.unwrap_or(0.0),
            }),
            _ => Err(Error::Input(
                "give either --preset NAME or both --sigma-a R,G,B and --sigma-s R,G,B".into(),
            )),
        }
    }
}

/// Arguments of `sss profile`.
#[derive(Debug, Args)]
pub struct ProfileArgs {
    /// The model, or the Monte Carlo reference.
    #[arg(long, value_enum)]
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
    /// Monte Carlo photons per channel.
    #[arg(long, default_value_t = 1_000_000)]
    pub photons: u64,
    /// Monte Carlo seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// Arguments of `sss presets`.
#[derive(Debug, Args)]
pub struct PresetsArgs {
    /// Print CSV instead of an aligned table.
    #[arg(long)]
    pub csv: bool,
}

/// Parses `R,G,B` (three numbers separated by commas; spaces allowed).
pub fn parse_rgb(s: &str) -> Result<Rgb, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!(
            "expected three comma-separated numbers R,G,B, got {} value(s)",
            parts.len()
        ));
    }
    let mut v = [0.0; 3];
    for (slot, p) in v.iter_mut().zip(&parts) {
        *slot = p
            .parse::<f64>()
            .map_err(|_| format!("'{p}' is not a number (expected R,G,B)"))?;
    }
    Ok(v)
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

/// Runs a parsed command, writing its normal output to `out`. Output is produced only once
/// everything (including a requested plot) has succeeded.
pub fn run(cli: &Cli, out: &mut dyn Write) -> Result<(), Error> {
    let text = match &cli.command {
        Command::Presets(args) => presets_table(args.csv).into_bytes(),
        Command::Render(args) => run_render(args)?.into_bytes(),
        Command::Diff(args) => run_diff(args)?.into_bytes(),
        Command::Kernel(args) => run_kernel(args)?.into_bytes(),
        Command::Filter(args) => run_filter(args)?.into_bytes(),
        Command::Profile(args) => {
            let req = args.request()?;
            if let Some(path) = &args.plot {
                // Fail on a bad extension or directory before a long computation.
                crate::plot::check_writable(path)?;
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
                table.plot(path, req.log)?;
            }
            let mut buf = Vec::new();
            table.write_csv(&mut buf).map_err(|source| Error::Io {
                what: "formatting the CSV".into(),
                source,
            })?;
            buf
        }
    };
    out.write_all(&text)
        .and_then(|()| out.flush())
        .map_err(|source| Error::Io {
            what: "writing to stdout".into(),
            source,
        })
}

/// Joins a multi-line clap message into one line, dropping the usage and help hints.
fn one_line(message: &str) -> String {
    let parts: Vec<&str> = message
        .lines()
        .map(str::trim)
        .filter(|l| {
            !l.is_empty() && !l.starts_with("Usage:") && !l.starts_with("For more information")
        })
        .collect();
    let joined = parts.join(" ");
    let body = joined.strip_prefix("error:").unwrap_or(&joined).trim();
    format!("error: {body}")
}

/// The whole program: parses `args` (program name first), runs, reports. Returns the exit code.
pub fn main(args: impl IntoIterator<Item = OsString>) -> ExitCode {
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            match e.kind() {
                ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
                    let _ = e.print();
                    return ExitCode::SUCCESS;
                }
                ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
                    eprintln!(
                        "error: a subcommand is required (profile, presets, render, diff, kernel or filter); see `sss --help`"
                    );
                    return ExitCode::from(2);
                }
                _ => {}
            }
            eprintln!("{}", one_line(&e.to_string()));
            return ExitCode::from(2);
        }
    };
    // A panic is a bug; report it on one line like every other error.
    std::panic::set_hook(Box::new(|info| {
        let payload = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "panic".into());
        let at = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        eprintln!(
            "error: internal error (a bug): {}{at}",
            payload.replace('\n', " ")
        );
    }));
    let stdout = std::io::stdout();
    let mut lock = stdout.lock();
    match run(&cli, &mut lock) {
        Ok(()) => ExitCode::SUCCESS,
        Err(Error::Io { source, .. }) if source.kind() == std::io::ErrorKind::BrokenPipe => {
            // The reader went away (`sss profile … | head`): nothing left to report.
            ExitCode::SUCCESS
        }
        Err(e) => {
            let msg = e.to_string().replace('\n', " ");
            eprintln!("error: {msg}");
            ExitCode::from(e.exit_code())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgb_parsing() {
        assert_eq!(parse_rgb("1,2.5, 3e-1").unwrap(), [1.0, 2.5, 0.3]);
        assert!(parse_rgb("1,2").is_err());
        assert!(parse_rgb("1,2,3,4").is_err());
        assert!(parse_rgb("1,x,3").is_err());
        assert!(parse_rgb("-1,2,3").is_ok(), "range is checked by Medium");
    }

    #[test]
    fn clap_messages_become_one_line() {
        let e = Cli::try_parse_from(["sss", "profile", "--model", "nope"]).unwrap_err();
        let line = one_line(&e.to_string());
        assert!(!line.contains('\n'));
        assert!(
            line.starts_with("error: ") && line.contains("nope"),
            "{line}"
        );
        assert!(line.contains("standard-dipole"), "{line}");
    }

    #[test]
    fn command_definition_is_valid() {
        use clap::CommandFactory;
        Cli::command().debug_assert();
    }
}
