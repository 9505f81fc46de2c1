//! The fuzz targets: what runs one input, and the guards that keep `cli` inputs bounded.

use super::corpus::{self, CliFiles};
use clap::Parser;
use sss_cli::{Cli, Command};
use std::path::{Component, Path, PathBuf};

/// A fuzz target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// `sss_scene::load_str` and `load` on mutated scene TOML.
    Scene,
    /// A scene naming a mutated OBJ file.
    Obj,
    /// `read_exr` and `sss filter` on mutated EXR bytes.
    Exr,
    /// `sss` on mutated argument lists, in-process.
    Cli,
}

impl Target {
    /// Every target, in the order `--target all` runs them.
    pub const ALL: [Target; 4] = [Target::Scene, Target::Obj, Target::Exr, Target::Cli];

    /// The name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Target::Scene => "scene",
            Target::Obj => "obj",
            Target::Exr => "exr",
            Target::Cli => "cli",
        }
    }

    /// The target's index (a stream of the mutator's generator).
    pub fn id(self) -> u64 {
        self as u64
    }
}

/// Most bytes of a mutated file input.
pub const MAX_FILE_LEN: usize = 1 << 16;
/// Most bytes of one mutated argument.
pub const MAX_ARG_LEN: usize = 4096;

/// Limits of the `cli` guard: inputs asking for more are skipped, not run.
pub mod limits {
    /// `--max-memory` must be given and at most this (64 MiB).
    pub const MAX_MEMORY: u64 = 64 << 20;
    /// At most this many worker threads.
    pub const THREADS: usize = 4;
    /// At most this many path-traced samples per pixel.
    pub const SPP: u64 = 64;
    /// At most this many exact-method irradiance samples per object.
    pub const MAX_SAMPLES: u64 = 100_000;
    /// At most this many Monte Carlo photons per channel (`sss profile --model monte-carlo`).
    pub const PHOTONS: u64 = 20_000;
    /// A mutated tiny scene may have at most this many pixel samples (pixels × samples per
    /// pixel) ...
    pub const PIXEL_SAMPLES: u64 = 1024;
    /// ... and at most this many triangles.
    pub const TRIANGLES: usize = 100_000;
}

/// A target with its corpus and work directory.
pub struct Harness {
    /// Which target.
    pub target: Target,
    /// The seed inputs (file bytes, or arguments joined by NUL for `cli`).
    pub corpus: Vec<Vec<u8>>,
    /// Whether token-level (text) mutations apply.
    pub text: bool,
    /// Where inputs are written and outputs go.
    pub dir: PathBuf,
    /// Arguments the `cli` mutator inserts.
    pub pool: Vec<String>,
}

impl Harness {
    /// Prepares `target` in the work directory `dir` (emptied first); `shared_meshes` is
    /// searched for OBJ files to take the head of (skipped when absent).
    pub fn new(target: Target, dir: &Path, shared_meshes: &Path) -> Result<Harness, String> {
        let _ = std::fs::remove_dir_all(dir);
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let write = |name: &str, text: &str| {
            std::fs::write(dir.join(name), text).map_err(|e| format!("{name}: {e}"))
        };
        let mut pool = Vec::new();
        let (corpus, text) = match target {
            Target::Scene => {
                for (name, text) in corpus::TINY_OBJS {
                    write(name, text)?;
                }
                (corpus::scenes(), true)
            }
            Target::Obj => {
                write("scene.toml", &corpus::mesh_scene("mesh.obj"))?;
                (corpus::objs(shared_meshes), true)
            }
            Target::Exr => (corpus::exrs(dir)?, false),
            Target::Cli => {
                let files = CliFiles::write(dir)?;
                pool = files.pool();
                let lists = files
                    .arg_lists()
                    .iter()
                    .map(|l| join_args(l))
                    .collect::<Vec<_>>();
                (lists, false)
            }
        };
        Ok(Harness {
            target,
            corpus,
            text,
            dir: dir.to_path_buf(),
            pool,
        })
    }
}

/// Separates the arguments of a stored `cli` input from the text of its tiny scene.
const SCENE_MARK: &str = "\0\u{1}SCENE\u{1}\0";

/// An argument list as bytes (NUL-separated), the form `cli` inputs are stored in.
pub fn join_args(args: &[String]) -> Vec<u8> {
    args.join("\0").into_bytes()
}

/// A `cli` input whose tiny scene file holds `scene` instead of the unmutated tiny scene.
pub fn join_args_scene(args: &[String], scene: &[u8]) -> Vec<u8> {
    let mut out = join_args(args);
    out.extend_from_slice(SCENE_MARK.as_bytes());
    out.extend_from_slice(scene);
    out
}

/// The arguments of a stored `cli` input.
pub fn split_args(bytes: &[u8]) -> Vec<String> {
    split_input(bytes).0
}

/// The arguments of a stored `cli` input and the text of its tiny scene, if mutated.
pub fn split_input(bytes: &[u8]) -> (Vec<String>, Option<Vec<u8>>) {
    let mark = SCENE_MARK.as_bytes();
    let (args, scene) = match bytes.windows(mark.len()).position(|w| w == mark) {
        Some(at) => (&bytes[..at], Some(bytes[at + mark.len()..].to_vec())),
        None => (bytes, None),
    };
    let args = String::from_utf8_lossy(args)
        .split('\0')
        .map(str::to_string)
        .collect();
    (args, scene)
}

/// What one run of a target gave: per execution, `Ok` or the error's text; or `Skipped`
/// (the guard refused a `cli` input).
pub enum Ran {
    /// The library's results, one per call.
    Done(Vec<Result<(), String>>),
    /// The input was not run; the reason.
    Skipped(&'static str),
}

/// Runs `input` on `target` with files in `dir`.
pub fn run(target: Target, dir: &Path, input: &[u8]) -> Ran {
    match target {
        Target::Scene => Ran::Done(run_scene(dir, input)),
        Target::Obj => Ran::Done(vec![run_obj(dir, input)]),
        Target::Exr => Ran::Done(run_exr(dir, input)),
        Target::Cli => {
            let (args, scene) = split_input(input);
            run_cli(dir, &args, scene.as_deref())
        }
    }
}

fn no_dirs() -> sss_render::scene::LoadOptions {
    sss_render::scene::LoadOptions::default()
}

fn run_scene(dir: &Path, input: &[u8]) -> Vec<Result<(), String>> {
    let mut results = Vec::new();
    if let Ok(text) = std::str::from_utf8(input) {
        results.push(
            sss_render::scene::load_str(text, "fuzz.toml", Some(dir), &no_dirs())
                .map(drop)
                .map_err(|e| e.to_string()),
        );
    }
    let path = dir.join("fuzz.toml");
    results.push(match std::fs::write(&path, input) {
        Ok(()) => sss_render::scene::load(&path, &no_dirs())
            .map(drop)
            .map_err(|e| e.to_string()),
        Err(e) => Err(format!("fuzz driver: cannot write {}: {e}", path.display())),
    });
    results
}

fn run_obj(dir: &Path, input: &[u8]) -> Result<(), String> {
    let mesh = dir.join("mesh.obj");
    std::fs::write(&mesh, input)
        .map_err(|e| format!("fuzz driver: cannot write {}: {e}", mesh.display()))?;
    sss_render::scene::load(&dir.join("scene.toml"), &no_dirs())
        .map(drop)
        .map_err(|e| e.to_string())
}

fn run_exr(dir: &Path, input: &[u8]) -> Vec<Result<(), String>> {
    let path = dir.join("in.exr");
    if let Err(e) = std::fs::write(&path, input) {
        return vec![Err(format!(
            "fuzz driver: cannot write {}: {e}",
            path.display()
        ))];
    }
    let read = sss_render::image::read_exr(&path)
        .map(drop)
        .map_err(|e| e.to_string());
    let args = [
        "sss".to_string(),
        "filter".into(),
        path.display().to_string(),
        "--preset".into(),
        "skin1".into(),
        "--units-per-mm".into(),
        "0.05".into(),
        "--taps".into(),
        "5".into(),
        "--out".into(),
        dir.join("out.exr").display().to_string(),
    ];
    let filter = match Cli::try_parse_from(&args) {
        Ok(cli) => sss_cli::run(&cli, &mut Vec::new()).map_err(|e| e.to_string()),
        Err(e) => Err(format!("fuzz driver: bad filter arguments: {e}")),
    };
    vec![read, filter]
}

/// True when `p` is inside `dir` with no `..` (outputs of fuzzed commands stay in the work
/// directory).
fn inside(dir: &Path, p: &Path) -> bool {
    p.starts_with(dir) && !p.components().any(|c| matches!(c, Component::ParentDir))
}

/// The guard of the `cli` target: the reason to skip a parsed command, if any.
///
/// - every output (`--out`, `--png`, `--gbuffer`, `--plot`) must lie inside the work
///   directory, so a mutated path never writes elsewhere;
/// - `render` only on the tiny 16x12 scene file written into the work directory, with
///   `--max-memory` at most 64 MiB, at most 4 threads, `--spp` ≤ 64 and `--max-samples` ≤
///   100000 (unparsable values are run: the library must reject them);
/// - `profile --model monte-carlo` with at most 20000 photons;
/// - and (checked when run) a mutated tiny scene must, if it loads, have at most 1024 pixel
///   samples (width × height × pixel_samples) and 100000 triangles.
pub fn guard(dir: &Path, cli: &Cli) -> Option<&'static str> {
    let outputs_ok = |paths: &[Option<&PathBuf>]| paths.iter().flatten().all(|p| inside(dir, p));
    let number = |v: Option<&str>| v.and_then(|v| v.trim().parse::<f64>().ok());
    match &cli.command {
        Command::Render(a) => {
            if !outputs_ok(&[a.out.as_ref(), a.png.as_ref(), a.gbuffer.as_ref()]) {
                return Some("output outside the work directory");
            }
            if Path::new(&a.scene) != dir.join("tiny.toml") {
                return Some("render of a scene other than the tiny one");
            }
            if a.max_memory.is_none_or(|m| m > limits::MAX_MEMORY) {
                return Some("render without --max-memory <= 64M");
            }
            if a.threads.is_some_and(|t| t > limits::THREADS) {
                return Some("render with more than 4 threads");
            }
            let o = &a.options.options;
            if number(o.value("spp")).is_some_and(|v| v > limits::SPP as f64) {
                return Some("render with --spp > 64");
            }
            if number(o.value("max-samples")).is_some_and(|v| v > limits::MAX_SAMPLES as f64) {
                return Some("render with --max-samples > 100000");
            }
            None
        }
        Command::Profile(a) => {
            if !outputs_ok(&[a.plot.as_ref()]) {
                return Some("output outside the work directory");
            }
            if a.model == sss_bssrdf::profile_rows::ProfileModel::MonteCarlo
                && a.photons > limits::PHOTONS
            {
                return Some("monte-carlo profile with more than 20000 photons");
            }
            None
        }
        Command::Filter(a) => (!outputs_ok(&[Some(&a.out), a.png.as_ref()]))
            .then_some("output outside the work directory"),
        Command::Diff(a) => {
            (!outputs_ok(&[a.png.as_ref()])).then_some("output outside the work directory")
        }
        Command::Kernel(_) | Command::Presets(_) => None,
    }
}

/// The guard's check of a mutated tiny scene (render only): the reason to skip it, if any.
/// A scene that does not load is run (the error is the point); one that loads must be small.
fn scene_guard(path: &Path) -> Option<&'static str> {
    let scene = sss_render::scene::load(path, &no_dirs()).ok()?;
    let c = &scene.camera;
    let samples = c.width as u64 * c.height as u64 * c.pixel_samples as u64;
    let triangles: usize = scene.objects.iter().map(|o| o.mesh.triangles.len()).sum();
    if samples > limits::PIXEL_SAMPLES {
        return Some("mutated scene with more than 1024 pixel samples");
    }
    (triangles > limits::TRIANGLES).then_some("mutated scene with more than 100000 triangles")
}

fn run_cli(dir: &Path, args: &[String], scene: Option<&[u8]>) -> Ran {
    let tiny = dir.join("tiny.toml");
    let written = match scene {
        Some(text) => std::fs::write(&tiny, text),
        None => std::fs::write(&tiny, corpus::tiny_sphere_scene()),
    };
    if let Err(e) = written {
        return Ran::Done(vec![Err(format!(
            "fuzz driver: cannot write {}: {e}",
            tiny.display()
        ))]);
    }
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            let text = e.to_string();
            return Ran::Done(vec![Err(text)]);
        }
    };
    if let Some(why) = guard(dir, &cli) {
        return Ran::Skipped(why);
    }
    if scene.is_some()
        && matches!(cli.command, Command::Render(_))
        && let Some(why) = scene_guard(&tiny)
    {
        return Ran::Skipped(why);
    }
    Ran::Done(vec![
        sss_cli::run(&cli, &mut Vec::new()).map_err(|e| e.to_string()),
    ])
}
