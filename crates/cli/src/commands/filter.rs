//! `sss filter`: the screen-space separable pass on inputs read from an OpenEXR file (as
//! written by `sss render --method separable --gbuffer`): layer `irradiance` (RGB) and layer
//! `surface` (R = depth, G = world size of a pixel, both in scene units; B = object id + 1, 0
//! where no translucent object is seen). Outputs the diffuse exitance E ∗ R_d per pixel (same
//! unit as the irradiance; multiply by F_t(η, cos θ_o)/(cπ) for radiance).
//!
//! `--gpu` runs the same pass on a GPU through wgpu (`sss-gpu`: the WGSL shader that
//! `sss kernel --format wgsl` pastes into, as two compute passes per term). It has no jitter,
//! so it needs `--jitter 0`, and a build with the `gpu` feature; it gives the CPU's picture
//! within f32 rounding. Without an adapter it stops with a one-line error.

use crate::args::MediumArgs;
use crate::commands::render::check_output;
use crate::method_flags::{MethodFlags, SeparableOnly};

use clap::Args;
use sss_bssrdf::{ModelKind, Rgb, make_model};
use sss_render::Error;
use sss_render::image::{exposure_or_auto, read_exr_within, write_exr, write_png};
use sss_render::integrators::separable::kernel_settings;
use sss_render::kernel_choice::{MaterialKernel, build_kernel, filter_options};
use sss_separable::{NO_OBJECT, ScreenInput, convolve2d, screen_space};
use std::path::PathBuf;

/// Arguments of `sss filter`.
#[derive(Debug, Args)]
pub struct FilterArgs {
    /// The input EXR (layers `irradiance` and `surface`).
    pub input: PathBuf,
    /// The medium.
    #[command(flatten)]
    pub medium: MediumArgs,
    /// Scene units per millimetre of the input's depth and footprint.
    #[arg(long)]
    pub units_per_mm: f64,
    /// The BSSRDF model whose R_d the kernel approximates (the help lists `ModelKind::ALL`).
    #[arg(long, default_value = "better-dipole", help = crate::args::model_help("The BSSRDF model whose R_d the kernel approximates"))]
    pub model: ModelKind,
    /// The kernel and filter options.
    #[command(flatten)]
    pub separable: MethodFlags<SeparableOnly>,
    /// Seed of the per-pixel rotations.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output EXR (layer `exitance`).
    #[arg(long, value_name = "FILE.exr")]
    pub out: PathBuf,
    /// Tone-mapped PNG of the exitance.
    #[arg(long, value_name = "FILE.png")]
    pub png: Option<PathBuf>,
    /// The PNG's exposure: linear values are multiplied by this scale before the sRGB curve
    /// (values above 1 clip). Default: automatic, the 99th percentile of the non-zero
    /// luminances to 0.9. Give the same value to compare PNGs of several renders.
    #[arg(long, value_name = "SCALE", value_parser = sss_render::image::parse_exposure)]
    pub exposure: Option<f64>,
    /// Run the pass on a GPU through wgpu (the exported WGSL compute shader). It has no
    /// jitter: needs `--jitter 0`. Needs an `sss` built with the `gpu` feature.
    #[arg(long)]
    pub gpu: bool,
    /// Memory budget (bytes, or with a suffix: 512M, 8G); an input EXR whose header says it
    /// needs more to read is refused before any pixel is read. Default: half the physical
    /// memory.
    #[arg(long, value_name = "BYTES", value_parser = sss_render::budget::parse_bytes)]
    pub max_memory: Option<u64>,
}

/// Runs `sss filter`; returns a one-line summary.
pub fn run(args: &FilterArgs) -> Result<String, Error> {
    let settings = kernel_settings(&args.separable.options)?;
    if !(args.units_per_mm.is_finite() && args.units_per_mm > 0.0) {
        return Err(Error::Input(format!(
            "--units-per-mm must be positive, got {}",
            args.units_per_mm
        )));
    }
    if args.gpu {
        if !cfg!(feature = "gpu") {
            return Err(no_gpu_feature());
        }
        if !settings.kernel.is_separable() {
            return Err(Error::Input(format!(
                "--gpu runs separable kernels only, not `{}`",
                settings.kernel
            )));
        }
        if settings.jitter != 0.0 {
            return Err(Error::Input(format!(
                "--gpu has no jitter: add --jitter 0 (got --jitter {})",
                settings.jitter
            )));
        }
    }
    check_output(&args.out, "exr")?;
    if let Some(p) = &args.png {
        check_output(p, "png")?;
    }
    let medium = args.medium.spec()?.medium(args.medium.eta)?;
    let model = make_model(args.model, &medium);
    let budget = args
        .max_memory
        .unwrap_or_else(sss_render::budget::default_budget);
    let (w, h, layers) = read_exr_within(&args.input, budget)?;
    let layer = |name: &str| -> Result<&Vec<Rgb>, Error> {
        layers.iter().find(|(n, _)| n == name).map(|(_, d)| d).ok_or_else(|| {
            Error::Input(format!("{}: no layer `{name}` (write it with `sss render --method separable --gbuffer`)", args.input.display()))
        })
    };
    let (irr, surface) = (layer("irradiance")?, layer("surface")?);
    let u = args.units_per_mm;
    let n = (w as usize) * (h as usize);
    let mut e = vec![[0.0f32; 3]; n];
    let mut depth = vec![0.0f32; n];
    let mut mm = vec![0.0f32; n];
    let mut mask = vec![NO_OBJECT; n];
    for i in 0..n {
        let id = surface[i][2].round();
        if id >= 1.0 {
            mask[i] = (id - 1.0) as u32;
            depth[i] = (surface[i][0] / u) as f32;
            mm[i] = (surface[i][1] / u) as f32;
            e[i] = irr[i].map(|v| v as f32);
        }
    }
    let kernel = build_kernel(model.as_ref(), &settings)
        .map_err(|e| Error::Input(format!("cannot build the {} kernel: {e}", settings.kernel)))?;
    let input = ScreenInput {
        width: w as usize,
        height: h as usize,
        irradiance: &e,
        depth: &depth,
        mask: &mask,
        mm_per_pixel: &mm,
    };
    let opts = filter_options(&settings, args.seed);
    let mut on = String::new();
    let t = std::time::Instant::now();
    let out = match &kernel {
        MaterialKernel::Separable(k) if args.gpu => {
            let (out, adapter) = gpu_filter(&input, k, &opts)?;
            on = format!(" on {adapter}");
            Ok(out)
        }
        MaterialKernel::Separable(k) => screen_space::filter(&input, k, &opts),
        MaterialKernel::Full(k2) => convolve2d::exact(&input, k2, &opts),
    }
    .map_err(|e| Error::Input(format!("{}: {e}", args.input.display())))?;
    let seconds = t.elapsed().as_secs_f64();
    let out: Vec<Rgb> = out.iter().map(|p| p.map(|v| v as f64)).collect();
    write_exr(&args.out, w, h, &[("exitance", &out)])?;
    if let Some(p) = &args.png {
        write_png(p, w, h, &out, exposure_or_auto(args.exposure, &out))?;
    }
    let covered = mask.iter().filter(|m| **m != NO_OBJECT).count();
    Ok(format!(
        "filtered {w}x{h} ({covered} translucent pixels) with the {} kernel in {seconds:.4} s{on}\n",
        settings.kernel
    ))
}

/// The pass on the GPU: the output and the adapter's name. No adapter, or a GPU failure, is
/// a one-line [`Error::Unsupported`].
#[cfg(feature = "gpu")]
fn gpu_filter(
    input: &ScreenInput,
    kernel: &sss_separable::SeparableKernel,
    opts: &sss_separable::FilterOptions,
) -> Result<(Vec<[f32; 3]>, String), Error> {
    use sss_gpu::GpuError;
    let fail = |e: GpuError| match e {
        GpuError::Input(m) => Error::Input(format!("--gpu: {m}")),
        e => Error::Unsupported(format!("--gpu: {e}")),
    };
    let gpu = sss_gpu::Gpu::new().map_err(fail)?;
    let filter = sss_gpu::GpuFilter::new(&gpu, kernel, opts).map_err(fail)?;
    let out = filter.filter(input).map_err(fail)?;
    Ok((out, gpu.adapter_name()))
}

/// Without the `gpu` feature, `--gpu` is refused ([`run`] does so before reading the input).
#[cfg(not(feature = "gpu"))]
fn gpu_filter(
    _: &ScreenInput,
    _: &sss_separable::SeparableKernel,
    _: &sss_separable::FilterOptions,
) -> Result<(Vec<[f32; 3]>, String), Error> {
    Err(no_gpu_feature())
}

/// The error of `--gpu` in a build without the `gpu` feature.
fn no_gpu_feature() -> Error {
    Error::Unsupported(
        "--gpu: this sss was built without the `gpu` feature \
         (build it with `cargo build --release -p sss-cli --features gpu`)"
            .into(),
    )
}
