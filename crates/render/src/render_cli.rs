//! `sss render` and `sss diff`: argument structures and what they run.

use crate::image::{auto_exposure, read_exr, write_error_map, write_exr, write_png};
use crate::integrators::separable::{KernelMethod, SeparableSettings};
use crate::irradiance::IrradianceSettings;
use crate::render::{Method, RenderOutput, RenderSettings, render};
use sss_scene::{self as scene, LoadOptions, Scene};
use crate::{Error, progress};
use clap::{Args, ValueEnum};
use sss_bssrdf::Rgb;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Integrators selectable on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// Brute-force sum over all irradiance samples.
    Exact,
    /// BSSRDF importance-sampled path tracing (pbrt §15.4).
    Pathtrace,
    /// Screen-space separable blur (Jimenez et al. 2015).
    Separable,
}

/// Arguments of `sss render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// A scene file (TOML), or the name of a built-in scene (sphere, toad, picnic, backlit,
    /// slab, bunny).
    pub scene: String,
    /// The integrator.
    #[arg(long, value_enum, default_value_t = MethodArg::Exact)]
    pub method: MethodArg,
    /// Path tracer: BSSRDF samples per pixel sample.
    #[arg(long, default_value_t = 16)]
    pub spp: u32,
    /// The separable integrator's kernel and filter.
    #[command(flatten)]
    pub separable: SeparableArgs,
    /// Seed of every random choice (same seed, same image).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Irradiance sample spacing in units of the smallest reduced mean free path.
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    pub spacing: f64,
    /// At most this many irradiance samples per object.
    #[arg(long, default_value_t = 100_000)]
    pub max_samples: usize,
    /// Directory to search for meshes (repeatable; SSS_MESH_DIR is searched too).
    #[arg(long, value_name = "DIR")]
    pub mesh_dir: Vec<PathBuf>,
    /// Linear OpenEXR output (layers `total`, `subsurface`, and `std_error` for pathtrace).
    #[arg(long, value_name = "FILE.exr")]
    pub out: Option<PathBuf>,
    /// Tone-mapped sRGB PNG of the total.
    #[arg(long, value_name = "FILE.png")]
    pub png: Option<PathBuf>,
    /// Separable: also write the screen-space inputs (layers `irradiance`, and `surface` =
    /// depth, footprint in scene units and object id + 1, 0 for none) for `sss filter`.
    #[arg(long, value_name = "FILE.exr")]
    pub gbuffer: Option<PathBuf>,
}

/// Arguments of `sss diff`.
#[derive(Debug, Args)]
pub struct DiffArgs {
    /// The render to judge (OpenEXR from `sss render`).
    pub image: PathBuf,
    /// The reference (OpenEXR from `sss render`).
    pub reference: PathBuf,
    /// Which layer to compare.
    #[arg(long, default_value = "subsurface")]
    pub layer: String,
    /// False-colour error map (PNG) of the relative error per pixel.
    #[arg(long, value_name = "FILE.png")]
    pub png: Option<PathBuf>,
    /// Relative-error threshold for the fraction of pixels within it.
    #[arg(long, default_value_t = 0.05)]
    pub eps: f64,
}

/// The separable kernel and filter options of `sss render` and `sss filter`.
#[derive(Debug, Args)]
pub struct SeparableArgs {
    /// Separable: the kernel (preintegrated, svd1, svd3, svd6, artist, guided, gaussians1,
    /// gaussians6, or exact2d for the brute-force 2D screen-space convolution).
    #[arg(long, default_value = "preintegrated")]
    pub kernel: KernelMethod,
    /// Separable: taps per 1D pass.
    #[arg(long, default_value_t = 7)]
    pub taps: usize,
    /// Separable: place taps uniformly instead of by importance.
    #[arg(long)]
    pub uniform_taps: bool,
    /// Separable: guided-optimisation exponent k in [0, 4].
    #[arg(long, default_value_t = 2.0, allow_hyphen_values = true)]
    pub k: f64,
    /// Separable: fraction of the kernel support within which the filter axes are rotated per
    /// pixel (0 turns the jitter off).
    #[arg(long, default_value_t = 0.1, allow_hyphen_values = true)]
    pub jitter: f32,
}

impl SeparableArgs {
    /// The checked settings these options describe.
    pub fn settings(&self) -> Result<SeparableSettings, Error> {
        check_separable_args(self.taps, self.k, self.jitter)?;
        Ok(SeparableSettings {
            kernel: self.kernel,
            taps: self.taps,
            importance: !self.uniform_taps,
            k: self.k,
            jitter: self.jitter,
        })
    }
}

/// Checks the separable options shared by `sss render`, `sss filter` and `sss kernel`.
pub fn check_separable_args(taps: usize, k: f64, jitter: f32) -> Result<(), Error> {
    if taps == 0 || taps > 1025 {
        return Err(Error::Input(format!(
            "--taps must lie in 1..=1025, got {taps}"
        )));
    }
    if !(0.0..=4.0).contains(&k) {
        return Err(Error::Input(format!("--k must lie in [0, 4], got {k}")));
    }
    if !(0.0..=1.0).contains(&jitter) {
        return Err(Error::Input(format!(
            "--jitter must lie in [0, 1], got {jitter}"
        )));
    }
    Ok(())
}

/// Loads a scene file, or a built-in scene when `name` is not a file but names one.
pub fn load_scene(name: &str, mesh_dirs: &[PathBuf]) -> Result<Scene, Error> {
    let mut opts = LoadOptions::from_env();
    let mut dirs = mesh_dirs.to_vec();
    dirs.append(&mut opts.mesh_dirs);
    opts.mesh_dirs = dirs;
    let path = Path::new(name);
    if !path.exists() && scene::BUILTIN_SCENES.iter().any(|(n, _)| *n == name) {
        return Ok(scene::builtin(name, &opts)?);
    }
    Ok(scene::load(path, &opts)?)
}

/// Checks that `path` ends in `.ext` and that its directory is writable.
pub fn check_output(path: &Path, ext: &str) -> Result<(), Error> {
    let ok = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case(ext));
    if !ok {
        return Err(Error::Input(format!(
            "{}: the output file must end in .{ext}",
            path.display()
        )));
    }
    let tmp = path.with_extension(format!("{ext}.{}.probe", std::process::id()));
    std::fs::File::create(&tmp).map_err(|source| Error::Io {
        what: format!("cannot write {}", path.display()),
        source,
    })?;
    let _ = std::fs::remove_file(&tmp);
    Ok(())
}

/// Runs `sss render`: returns the text for stdout (a summary and the timing breakdown).
pub fn run_render(args: &RenderArgs) -> Result<String, Error> {
    if !(args.spacing.is_finite() && args.spacing > 0.0) {
        return Err(Error::Input(format!(
            "--spacing must be positive, got {}",
            args.spacing
        )));
    }
    if args.spp == 0 {
        return Err(Error::Input("--spp must be at least 1".into()));
    }
    let separable = args.separable.settings()?;
    if args.threads == Some(0) {
        return Err(Error::Input("--threads must be at least 1".into()));
    }
    if let Some(p) = &args.out {
        check_output(p, "exr")?;
    }
    if let Some(p) = &args.png {
        check_output(p, "png")?;
    }
    if let Some(p) = &args.gbuffer {
        if args.method != MethodArg::Separable {
            return Err(Error::Input("--gbuffer needs --method separable".into()));
        }
        check_output(p, "exr")?;
    }
    let scene = load_scene(&args.scene, &args.mesh_dir)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let settings = RenderSettings {
        method: match args.method {
            MethodArg::Exact => Method::Exact,
            MethodArg::Pathtrace => Method::PathTrace,
            MethodArg::Separable => Method::Separable,
        },
        separable,
        spp: args.spp,
        seed: args.seed,
        irradiance: IrradianceSettings {
            spacing_mfp: args.spacing,
            max_samples: args.max_samples,
            ..IrradianceSettings::default()
        },
        ..RenderSettings::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .map_err(|e| {
            Error::Input(format!(
                "cannot start {} threads: {e}",
                args.threads.unwrap_or(0)
            ))
        })?;
    let bar = progress::bar(0, "pixel samples");
    let out = pool.install(|| render(&scene, &settings, Some(&bar)));
    bar.finish_and_clear();
    let out = out?;
    let write_t = std::time::Instant::now();
    if let Some(p) = &args.out {
        let mut layers: Vec<(&str, &[Rgb])> =
            vec![("total", &out.total), ("subsurface", &out.subsurface)];
        if let Some(se) = &out.std_error {
            layers.push(("std_error", se));
        }
        write_exr(p, out.width, out.height, &layers)?;
    }
    if let Some(p) = &args.png {
        write_png(
            p,
            out.width,
            out.height,
            &out.total,
            auto_exposure(&out.total),
        )?;
    }
    if let (Some(p), Some(b)) = (&args.gbuffer, &out.screen) {
        let surface: Vec<Rgb> = (0..b.depth.len())
            .map(|i| {
                // Object id + 1 (0: no translucent object); EXR values are kept non-negative.
                let id = if b.object[i] == u32::MAX {
                    0.0
                } else {
                    b.object[i] as f64 + 1.0
                };
                [b.depth[i], b.footprint[i], id]
            })
            .collect();
        write_exr(
            p,
            out.width,
            out.height,
            &[("irradiance", &b.irradiance), ("surface", &surface)],
        )?;
    }
    Ok(summary(
        &scene,
        &settings,
        &out,
        write_t.elapsed().as_secs_f64(),
    ))
}

fn summary(scene: &Scene, s: &RenderSettings, out: &RenderOutput, write_seconds: f64) -> String {
    let mut text = String::new();
    let _ = writeln!(
        text,
        "scene {} ({}x{}, {} pixel sample(s)), method {}, seed {}",
        scene.name,
        out.width,
        out.height,
        scene.camera.pixel_samples,
        s.method.name(),
        s.seed
    );
    if s.method == Method::PathTrace {
        let _ = writeln!(text, "bssrdf samples per pixel sample: {}", s.spp);
    } else if s.method == Method::Separable {
        let _ = writeln!(
            text,
            "kernel {}, {} {} taps per pass, jitter {}",
            s.separable.kernel,
            s.separable.taps,
            if s.separable.importance {
                "importance-sampled"
            } else {
                "uniform"
            },
            s.separable.jitter
        );
    } else {
        let _ = writeln!(text, "irradiance samples: {}", out.irradiance_samples);
    }
    let _ = writeln!(
        text,
        "translucent pixels: {}",
        out.translucent_pixels().len()
    );
    let _ = writeln!(text, "stage        seconds");
    for st in &out.stages {
        let _ = writeln!(text, "{:<12} {:.4}", st.name, st.seconds);
    }
    let _ = writeln!(text, "{:<12} {:.4}", "write", write_seconds);
    let _ = writeln!(
        text,
        "{:<12} {:.4}",
        "total",
        out.seconds_total() + write_seconds
    );
    text
}

/// Error figures of an image against a reference over a set of pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorFigures {
    /// Root mean square error over pixels and channels.
    pub rmse: f64,
    /// RMSE divided by the reference's mean over the same pixels and channels.
    pub rel_rmse: f64,
    /// Fraction of pixels whose relative error (per-pixel luminance-free: max over channels of
    /// |a − b| / max(b, floor)) is below `eps`.
    pub frac_within_eps: f64,
}

/// Per-pixel relative error: max over channels of |a − b| / max(b, floor), where `floor` is 1 %
/// of the reference's mean (so nearly black pixels do not dominate).
pub fn relative_errors(image: &[Rgb], reference: &[Rgb], pixels: &[usize]) -> Vec<f64> {
    let mean = reference_mean(reference, pixels);
    let floor = (mean * 0.01).max(1e-300);
    pixels
        .iter()
        .map(|&i| {
            (0..3)
                .map(|c| (image[i][c] - reference[i][c]).abs() / reference[i][c].max(floor))
                .fold(0.0, f64::max)
        })
        .collect()
}

fn reference_mean(reference: &[Rgb], pixels: &[usize]) -> f64 {
    if pixels.is_empty() {
        return 0.0;
    }
    pixels
        .iter()
        .map(|&i| reference[i].iter().sum::<f64>() / 3.0)
        .sum::<f64>()
        / pixels.len() as f64
}

/// RMSE, relative RMSE and the fraction of pixels within `eps` relative error, over `pixels`.
pub fn error_figures(image: &[Rgb], reference: &[Rgb], pixels: &[usize], eps: f64) -> ErrorFigures {
    if pixels.is_empty() {
        return ErrorFigures {
            rmse: 0.0,
            rel_rmse: 0.0,
            frac_within_eps: 1.0,
        };
    }
    let mut se = 0.0;
    for &i in pixels {
        for c in 0..3 {
            let d = image[i][c] - reference[i][c];
            se += d * d;
        }
    }
    let rmse = (se / (3 * pixels.len()) as f64).sqrt();
    let mean = reference_mean(reference, pixels);
    let rel = relative_errors(image, reference, pixels);
    let within = rel.iter().filter(|e| **e < eps).count();
    ErrorFigures {
        rmse,
        rel_rmse: if mean > 0.0 { rmse / mean } else { 0.0 },
        frac_within_eps: within as f64 / pixels.len() as f64,
    }
}

/// Runs `sss diff`.
pub fn run_diff(args: &DiffArgs) -> Result<String, Error> {
    if let Some(p) = &args.png {
        check_output(p, "png")?;
    }
    let (w, h, a) = read_exr(&args.image)?;
    let (wr, hr, b) = read_exr(&args.reference)?;
    if (w, h) != (wr, hr) {
        return Err(Error::Input(format!(
            "{} is {w}x{h} but {} is {wr}x{hr}",
            args.image.display(),
            args.reference.display()
        )));
    }
    let pick = |layers: &[(String, Vec<Rgb>)], path: &Path| -> Result<Vec<Rgb>, Error> {
        layers
            .iter()
            .find(|(n, _)| *n == args.layer)
            .map(|(_, d)| d.clone())
            .ok_or_else(|| {
                let names: Vec<&str> = layers.iter().map(|(n, _)| n.as_str()).collect();
                Error::Input(format!(
                    "{}: no layer `{}` (it has: {})",
                    path.display(),
                    args.layer,
                    names.join(", ")
                ))
            })
    };
    let img = pick(&a, &args.image)?;
    let reference = pick(&b, &args.reference)?;
    let pixels: Vec<usize> = (0..img.len())
        .filter(|&i| reference[i].iter().chain(img[i].iter()).any(|v| *v > 0.0))
        .collect();
    let f = error_figures(&img, &reference, &pixels, args.eps);
    if let Some(p) = &args.png {
        let rel = relative_errors(&img, &reference, &pixels);
        let mut values = vec![None; img.len()];
        for (k, &i) in pixels.iter().enumerate() {
            values[i] = Some(rel[k]);
        }
        let max = 4.0 * args.eps;
        write_error_map(
            p,
            w,
            h,
            &values,
            max,
            &format!("relative error, layer {}", args.layer),
            "|a-b|/b",
        )?;
    }
    let mean = |img: &[Rgb]| -> Rgb {
        let mut m = [0.0; 3];
        for &i in &pixels {
            for c in 0..3 {
                m[c] += img[i][c] / pixels.len().max(1) as f64;
            }
        }
        m
    };
    let (ma, mb) = (mean(&img), mean(&reference));
    let ratio = [0, 1, 2].map(|c| if mb[c] > 0.0 { ma[c] / mb[c] } else { 0.0 });
    Ok(format!(
        "pixels {}\nrmse {:.6e}\nrel_rmse {:.6e}\nfrac_within_{} {:.4}\nmean_ratio {:.5} {:.5} {:.5}\n",
        pixels.len(),
        f.rmse,
        f.rel_rmse,
        args.eps,
        f.frac_within_eps,
        ratio[0],
        ratio[1],
        ratio[2]
    ))
}
