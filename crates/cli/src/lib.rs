//! # sss-cli: the `sss` command-line tool
//!
//! The argument definitions (clap derive) and [`main`], which the `sss` binary calls; one
//! module per subcommand under [`commands`]. Every failure ends in a single `error: …` line
//! on stderr and a non-zero exit code (2 for bad input, 1 for failures while running); nothing
//! is written to stdout then. Each command is a thin layer over the library that owns its idea
//! (`sss_bssrdf::profile_rows` for `sss profile`, `sss_render::kernel_export` for `sss
//! kernel`, `sss_scene::load_named` and `sss_render::render` for `sss render`), so a program
//! that wants what a command does depends on that library, never on this crate; only `xtask`
//! uses its clap definitions (the generated reference, the argument fuzzer).
//!
//! ```
//! use clap::Parser;
//! use sss_cli::{Cli, run};
//!
//! let cli = Cli::try_parse_from(["sss", "presets", "--csv"]).unwrap();
//! let mut out = Vec::new();
//! run(&cli, &mut out).unwrap();
//! assert!(String::from_utf8(out).unwrap().lines().any(|l| l.starts_with("skin1,")));
//! ```
//!
//! ## Papers
//! None of its own: it drives the models of `sss-bssrdf` (Jensen et al. 2001, d'Eon 2012,
//! Frisvad et al. 2014, Habel et al. 2013), their Monte Carlo reference (MCML, Wang et al.
//! 1995), the renderer `sss-render` and the separable kernels of Jimenez et al. 2015.

#![forbid(unsafe_code)]

pub mod args;
pub mod commands;
pub mod method_flags;
pub mod presets_table;
pub mod progress;
pub mod reference;

use crate::commands::diff::DiffArgs;
use crate::commands::filter::FilterArgs;
use crate::commands::kernel::KernelArgs;
use crate::commands::presets::PresetsArgs;
use crate::commands::profile::ProfileArgs;
use crate::commands::render::RenderArgs;
use clap::{Parser, Subcommand};
pub use sss_render::Error;
use std::ffi::OsString;
use std::io::Write;
use std::process::ExitCode;

/// A plot error as the tool's error: a bad extension is bad input (exit 2), anything else a
/// failure while writing (exit 1).
pub fn plot_error(e: sss_plot::PlotError) -> Error {
    use sss_plot::PlotError;
    match e {
        PlotError::UnsupportedFormat(_) => Error::Input(e.to_string()),
        PlotError::Draw { path, message } => Error::Io {
            what: format!("cannot write plot '{}'", path.display()),
            source: std::io::Error::other(message),
        },
        PlotError::Font => Error::Io {
            what: "cannot register the embedded plot font".into(),
            source: std::io::Error::other("font"),
        },
    }
}

/// A panic's message and location on one line (`message at file:line`), as `sss` reports a
/// bug and `cargo xtask fuzz` records a crash.
pub fn panic_message(info: &std::panic::PanicHookInfo<'_>) -> String {
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
    format!("{}{at}", payload.replace('\n', " "))
}

/// The exit status after Ctrl-C or SIGTERM (128 + SIGINT, the shell convention).
pub const INTERRUPTED_STATUS: i32 = 130;

/// The line printed on stderr when an interrupt removed `n` temporary files.
pub fn interrupted_message(n: usize) -> String {
    format!(
        "interrupted: removed {n} temporary file{}",
        if n == 1 { "" } else { "s" }
    )
}

/// Installs the Ctrl-C / SIGTERM / SIGHUP handler of a binary (`sss`, `xtask`): it deletes
/// the temporary files of writes in flight ([`sss_util::remove_temporaries`]), prints
/// [`interrupted_message`] and exits with [`INTERRUPTED_STATUS`]. Every output is written
/// through a temporary file and a rename, so an interrupted run leaves neither a partial
/// output nor a stray temporary file. Only binaries call this, once, before any work; a
/// second call (or a handler already installed by someone else) is a no-op.
pub fn install_interrupt_handler() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // Without a handler (setting it failed) the default action, termination, remains.
        let _ = ctrlc::set_handler(|| {
            let n = sss_util::remove_temporaries();
            // Start on a fresh line when a progress bar occupies the current one.
            let fresh = if std::io::IsTerminal::is_terminal(&std::io::stderr()) {
                "\n"
            } else {
                ""
            };
            eprintln!("{fresh}{}", interrupted_message(n));
            std::process::exit(INTERRUPTED_STATUS);
        });
    });
}

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
    /// Render a scene with any registered method (EXR and/or PNG out, timings on stdout).
    Render(RenderArgs),
    /// Compare two renders: error figures and a false-colour error map.
    Diff(DiffArgs),
    /// Export a separable screen-space kernel (JSON, CSV, GLSL, HLSL or WGSL).
    Kernel(KernelArgs),
    /// Run the screen-space separable pass on inputs read from an EXR file.
    Filter(FilterArgs),
}

/// Runs a parsed command, writing its normal output to `out`. Output is produced only once
/// everything (including a requested plot) has succeeded.
pub fn run(cli: &Cli, out: &mut dyn Write) -> Result<(), Error> {
    let text = match &cli.command {
        Command::Presets(args) => commands::presets::run(args).into_bytes(),
        Command::Render(args) => commands::render::run(args)?.into_bytes(),
        Command::Diff(args) => commands::diff::run(args)?.into_bytes(),
        Command::Kernel(args) => commands::kernel::run(args)?.into_bytes(),
        Command::Filter(args) => commands::filter::run(args)?.into_bytes(),
        Command::Profile(args) => commands::profile::run(args)?,
    };
    out.write_all(&text)
        .and_then(|()| out.flush())
        .map_err(|source| Error::Io {
            what: "writing to stdout".into(),
            source,
        })
}

/// Joins a multi-line clap message into one line, dropping the usage and help hints (also
/// used by `xtask`).
pub fn one_line(message: &str) -> String {
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
        eprintln!("error: internal error (a bug): {}", panic_message(info));
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
