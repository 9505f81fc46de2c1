//! `sss render`: a scene with any registered integrator (EXR and/or PNG out, a timing table
//! on stdout). The method list and each method's flags come from the registry
//! (`sss_render::integrators::METHODS`).

use crate::method_flags::{AllMethods, MethodFlags, method_parser};
use clap::Args;
use sss_bssrdf::Rgb;
use sss_render::Error;
use sss_render::image::{auto_exposure, write_exr, write_png};
use sss_render::integrators::{self, Integrator, MethodOptions};
use sss_render::scene::{self, LoadOptions, Scene};
use sss_render::{RenderOutput, RenderSettings, render};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Arguments of `sss render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// A scene file (TOML), or the name of a built-in scene (the help lists
    /// `sss_render::scene::BUILTIN_SCENES`).
    #[arg(help = format!(
        "A scene file (TOML), or the name of a built-in scene ({})",
        scene::BUILTIN_SCENES.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
    ))]
    pub scene: String,
    /// The integrator.
    #[arg(long, default_value = "exact", value_parser = method_parser())]
    pub method: String,
    /// The method's options (every registered method's flags; each applies to the methods
    /// named in its help).
    #[command(flatten)]
    pub options: MethodFlags<AllMethods>,
    /// Seed of every random choice (same seed, same image).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Memory budget (bytes, or with a suffix: 512M, 8G); a frame estimated to need more is
    /// refused before anything is allocated [default: half the physical memory].
    #[arg(long, value_name = "BYTES", value_parser = sss_render::budget::parse_bytes)]
    pub max_memory: Option<u64>,
    /// Directory to search for meshes (repeatable; SSS_MESH_DIR is searched too).
    #[arg(long, value_name = "DIR")]
    pub mesh_dir: Vec<PathBuf>,
    /// Linear OpenEXR output, one part: layer `total` as the channels R,G,B, then
    /// `subsurface.R,G,B` and, for stochastic methods, `std_error.R,G,B`.
    #[arg(long, value_name = "FILE.exr")]
    pub out: Option<PathBuf>,
    /// Tone-mapped sRGB PNG of the total.
    #[arg(long, value_name = "FILE.png")]
    pub png: Option<PathBuf>,
    /// Also write the method's screen-space inputs (separable: layer `irradiance` as R,G,B,
    /// and `surface.R,G,B` = depth, footprint in scene units and object id + 1, 0 for none)
    /// for `sss filter`.
    #[arg(long, value_name = "FILE.exr")]
    pub gbuffer: Option<PathBuf>,
}

/// The integrator `--method` and its flags describe. Flags of other methods are ignored with a
/// warning on stderr.
pub fn integrator(method: &str, given: &MethodOptions) -> Result<Box<dyn Integrator>, Error> {
    let m = integrators::method(method)?;
    let mut options = MethodOptions::new();
    for name in given.names() {
        if m.options.iter().any(|o| o.name == name) {
            options = options.with(name, given.value(name).unwrap_or_default());
        } else {
            eprintln!("warning: --{name} is not an option of method {method}; ignored");
        }
    }
    integrators::build(method, &options)
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
    // A registered temporary name, so an interrupt right here leaves nothing behind either.
    let tmp = sss_util::Temporary::register(sss_util::temp_path(path));
    std::fs::File::create(tmp.path()).map_err(|source| Error::Io {
        what: format!("cannot write {}", path.display()),
        source,
    })?;
    let _ = std::fs::remove_file(tmp.path());
    Ok(())
}

/// Runs `sss render`: returns the text for stdout (a summary and the timing breakdown).
pub fn run(args: &RenderArgs) -> Result<String, Error> {
    let method = integrator(&args.method, &args.options.options)?;
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
        if method.layer_names().is_empty() {
            let with: Vec<&str> = integrators::METHODS
                .iter()
                .filter(|m| {
                    (m.build)(&MethodOptions::new()).is_ok_and(|i| !i.layer_names().is_empty())
                })
                .map(|m| m.name)
                .collect();
            return Err(Error::Input(format!(
                "--gbuffer needs a method that produces screen-space inputs (--method {})",
                with.join(" or --method ")
            )));
        }
        check_output(p, "exr")?;
    }
    let scene = load_scene(&args.scene, &args.mesh_dir)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let settings = RenderSettings {
        seed: args.seed,
        max_memory: args
            .max_memory
            .unwrap_or_else(sss_render::budget::default_budget),
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
    let bar = crate::progress::Bar(crate::progress::bar(0, "pixel samples"));
    let out = pool.install(|| render(&scene, method.as_ref(), &settings, &bar));
    bar.0.finish_and_clear();
    let out = out?;
    for w in &out.warnings {
        eprintln!("warning: {w}");
    }
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
    if let Some(p) = &args.gbuffer {
        let layers: Vec<(&str, &[Rgb])> = out
            .layers
            .iter()
            .map(|l| (l.name, l.pixels.as_slice()))
            .collect();
        write_exr(p, out.width, out.height, &layers)?;
    }
    Ok(summary(
        &scene,
        method.as_ref(),
        &settings,
        &out,
        write_t.elapsed().as_secs_f64(),
    ))
}

fn summary(
    scene: &Scene,
    method: &dyn Integrator,
    s: &RenderSettings,
    out: &RenderOutput,
    write_seconds: f64,
) -> String {
    let mut text = String::new();
    let _ = writeln!(
        text,
        "scene {} ({}x{}, {} pixel sample(s)), method {}, seed {}",
        scene.name,
        out.width,
        out.height,
        scene.camera.pixel_samples,
        method.name(),
        s.seed
    );
    let _ = writeln!(text, "{}", method.describe());
    if out.irradiance_samples > 0 {
        let _ = writeln!(text, "irradiance samples: {}", out.irradiance_samples);
    }
    for st in &out.stats {
        let _ = writeln!(text, "{}: {}", st.name.replace('_', " "), st.value);
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
