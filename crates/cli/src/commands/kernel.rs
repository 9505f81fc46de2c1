//! `sss kernel`: exports a separable subsurface-scattering kernel (Jimenez et al. 2015) for a
//! material; the text and its layout are `sss_render::kernel_export`'s (see there).

use crate::args::{MediumArgs, model_help, names_parser};
use clap::Args;
use sss_bssrdf::{MediumSpec, ModelKind};
use sss_render::Error;
use sss_render::kernel_choice::KernelMethod;
use sss_render::kernel_export::{KernelFormat, KernelRequest, export};
use sss_separable::artist;

/// Arguments of `sss kernel`.
#[derive(Debug, Args)]
pub struct KernelArgs {
    /// The medium.
    #[command(flatten)]
    pub medium: MediumArgs,
    /// The BSSRDF model whose R_d is approximated (the help lists `ModelKind::ALL`).
    #[arg(long, default_value_t = defaults().model, help = model_help("The BSSRDF model whose R_d is approximated"))]
    pub model: ModelKind,
    /// The kernel (the help lists the separable ones of `KernelMethod::ALL`; `artist` is
    /// fitted to the material).
    #[arg(long, default_value_t = defaults().method, help = format!(
        "The kernel (one of: {}; artist is fitted to the material)",
        KernelMethod::separable_names().join(", ")
    ))]
    pub method: KernelMethod,
    /// With `--method artist`: use a Table 2 parameter set (the help lists
    /// `sss_separable::artist::PRESETS`) instead of fitting the material.
    #[arg(long, help = format!(
        "With --method artist: use a Table 2 parameter set (one of: {}) instead of fitting the material",
        artist::PRESETS.iter().map(|p| p.name).collect::<Vec<_>>().join(", ")
    ))]
    pub artist_preset: Option<String>,
    /// Guided-optimisation exponent k in [0, 4].
    #[arg(long, default_value_t = defaults().k, allow_hyphen_values = true)]
    pub k: f64,
    /// Taps per 1D pass.
    #[arg(long, default_value_t = defaults().taps)]
    pub taps: usize,
    /// Place taps uniformly instead of by importance (SVD terms always are).
    #[arg(long)]
    pub uniform: bool,
    /// Output format; shader constants are in the float4(r, g, b, offset_mm) layout, centre
    /// tap first.
    #[arg(long, default_value_t = defaults().format, value_parser = names_parser::<KernelFormat>(KernelFormat::ALL.map(|f| f.name())))]
    pub format: KernelFormat,
    /// Scale the weights to sum to 1 instead of the total diffuse reflectance.
    #[arg(long)]
    pub normalize: bool,
}

/// The library's defaults ([`KernelRequest::new`]), the flags' only source of them.
fn defaults() -> KernelRequest {
    KernelRequest::new(MediumSpec::Preset(String::new()))
}

impl KernelArgs {
    /// The library request these arguments describe.
    pub fn request(&self) -> Result<KernelRequest, Error> {
        Ok(KernelRequest {
            medium: self.medium.spec()?,
            eta: self.medium.eta,
            model: self.model,
            method: self.method,
            artist_preset: self.artist_preset.clone(),
            k: self.k,
            taps: self.taps,
            uniform: self.uniform,
            format: self.format,
            normalize: self.normalize,
        })
    }
}

/// Runs `sss kernel`: the kernel text for stdout.
pub fn run(args: &KernelArgs) -> Result<String, Error> {
    export(&args.request()?)
}
