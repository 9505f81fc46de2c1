//! `sss presets`: the measured materials of Jensen et al. 2001 (Table 2).

use clap::Args;

/// Arguments of `sss presets`.
#[derive(Debug, Args)]
pub struct PresetsArgs {
    /// Print CSV instead of an aligned table.
    #[arg(long)]
    pub csv: bool,
}

/// Runs `sss presets`: the table for stdout.
pub fn run(args: &PresetsArgs) -> String {
    crate::presets_table::presets_table(args.csv)
}
