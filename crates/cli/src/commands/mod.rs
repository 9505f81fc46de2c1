//! One module per `sss` subcommand: its arguments and what it runs.

pub mod diff;
pub mod filter;
pub mod kernel;
pub mod presets;
pub mod profile;
pub mod render;
