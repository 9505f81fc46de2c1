//! `sss render`: a scene with any registered integrator (EXR and/or PNG out, a timing table
//! on stdout). The method list and each method's flags come from the registry
//! (`sss_render::integrators::METHODS`).

use crate::method_flags::{AllMethods, MethodFlags, method_parser};
use clap::Args;
use sss_bssrdf::Rgb;
use sss_render::Error;
use sss_render::image::{exposure_or_auto, write_exr, write_exr_with, write_png};
use sss_render::integrators::{self, Integrator, MethodOptions};
use sss_render::scene::{self, Scene};
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
    /// Linear OpenEXR output, one part: layer `total` as the channels R,G,B with the alpha A
    /// (the fraction of each pixel's camera samples that hit an object: the silhouette), then
    /// `subsurface.R,G,B`, for stochastic methods `std_error.R,G,B`, and the method's own
    /// layers (`dual-tree`: `sampling_rate`, `pixel_clusters`; `manylight`: `triplets`; ...).
    #[arg(long, value_name = "FILE.exr")]
    pub out: Option<PathBuf>,
    /// Tone-mapped sRGB PNG of the total.
    #[arg(long, value_name = "FILE.png")]
    pub png: Option<PathBuf>,
    /// The PNG's exposure: linear values are multiplied by this scale before the sRGB curve
    /// (values above 1 clip). Default: automatic, the 99th percentile of the non-zero
    /// luminances to 0.9. Give the same value to compare PNGs of several renders.
    #[arg(long, value_name = "SCALE", value_parser = sss_render::image::parse_exposure)]
    pub exposure: Option<f64>,
    /// Also write the method's screen-space inputs (separable: layer `irradiance` as R,G,B,
    /// and `surface.R,G,B` = depth, footprint in scene units and object id + 1, 0 for none)
    /// for `sss filter`.
    #[arg(long, value_name = "FILE.exr")]
    pub gbuffer: Option<PathBuf>,
    /// The image size, overriding the scene's `camera.resolution` (the field of view stays
    /// vertical: a wider image sees more on the sides).
    #[arg(long, value_name = "WIDTHxHEIGHT", value_parser = parse_resolution)]
    pub resolution: Option<(u32, u32)>,
    /// Camera samples per pixel, overriding the scene's `camera.pixel_samples`.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub pixel_samples: Option<u32>,
}

/// `640x480` (or `640X480`): both at least 1.
pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("`{s}` is not WIDTHxHEIGHT with both at least 1 (640x480, say)");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    if w == 0 || h == 0 {
        return Err(bad());
    }
    Ok((w, h))
}

/// The integrator `--method` and its flags describe. Flags of other methods are ignored with a
/// warning on stderr.
pub fn integrator(method: &str, given: &MethodOptions) -> Result<Box<dyn Integrator>, Error> {
    let (options, others) = given.partition(integrators::method(method)?);
    for name in others {
        eprintln!("warning: --{name} is not an option of method {method}; ignored");
    }
    integrators::build(method, &options)
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
    let mut scene = scene::load_named(&args.scene, &args.mesh_dir, "--mesh-dir DIR")?;
    if let Some((w, h)) = args.resolution {
        scene.camera.width = w;
        scene.camera.height = h;
    }
    if let Some(n) = args.pixel_samples {
        scene.camera.pixel_samples = n;
    }
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    if args.out.is_none() && args.png.is_none() && args.gbuffer.is_none() {
        eprintln!(
            "warning: no --out FILE.exr or --png FILE.png given: the image is not kept, only \
             the summary is printed"
        );
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
        // Then the method's own layers (dual-tree's sampling rate and pixel clusters,
        // manylight's triplets, ...), as the help of `--out` promises.
        layers.extend(out.layers.iter().map(|l| (l.name, l.pixels.as_slice())));
        let made = provenance(&args.scene, &scene, method.as_ref(), &settings, &out);
        write_exr_with(p, out.width, out.height, &layers, Some(&out.alpha), &made)?;
    }
    if let Some(p) = &args.png {
        write_png(
            p,
            out.width,
            out.height,
            &out.total,
            exposure_or_auto(args.exposure, &out.total),
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

/// How an image was made, for the header of `--out`: the toolkit's version, the scene as
/// given, the method with its settings, the models of the translucent materials, the seed,
/// the camera samples per pixel, and the render's seconds and statistics.
fn provenance(
    given: &str,
    scene: &Scene,
    method: &dyn Integrator,
    s: &RenderSettings,
    out: &RenderOutput,
) -> Vec<(&'static str, String)> {
    let models: Vec<String> = scene
        .materials
        .iter()
        .filter_map(|m| match &m.kind {
            scene::MaterialKind::Translucent(t) => Some(format!("{}: {}", m.name, t.model)),
            scene::MaterialKind::Diffuse { .. } => None,
        })
        .collect();
    let stats: Vec<String> = out
        .stats
        .iter()
        .map(|st| format!("{} {}", st.name, st.value))
        .collect();
    vec![
        ("sss/version", env!("CARGO_PKG_VERSION").to_string()),
        ("sss/scene", given.to_string()),
        ("sss/method", method.name().to_string()),
        ("sss/settings", method.describe()),
        ("sss/models", models.join("; ")),
        ("sss/seed", s.seed.to_string()),
        ("sss/pixel_samples", scene.camera.pixel_samples.to_string()),
        ("sss/seconds", format!("{:.3}", out.seconds_total())),
        ("sss/stats", stats.join("; ")),
    ]
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
        let _ = write!(text, "irradiance samples: {}", out.irradiance_samples);
        if out.irradiance_left_out > 0 {
            let _ = write!(
                text,
                " (about {} more left out: beyond the profile's reach of every visible point)",
                out.irradiance_left_out
            );
        }
        let _ = writeln!(text);
    }
    for st in &out.stats {
        let _ = writeln!(
            text,
            "{}: {}",
            st.name.replace('_', " "),
            significant(st.value)
        );
    }
    let _ = writeln!(
        text,
        "translucent pixels: {}",
        out.translucent_pixels().len()
    );
    // The stage names' column as wide as the longest (`irradiance_tree`, say).
    let w = out
        .stages
        .iter()
        .map(|st| st.name.len())
        .chain(["stage".len(), "write".len()])
        .max()
        .unwrap_or(5);
    let _ = writeln!(text, "{:<w$} seconds", "stage");
    for st in &out.stages {
        let _ = writeln!(text, "{:<w$} {:.4}", st.name, st.seconds);
    }
    let _ = writeln!(text, "{:<w$} {:.4}", "write", write_seconds);
    let _ = writeln!(
        text,
        "{:<w$} {:.4}",
        "total",
        out.seconds_total() + write_seconds
    );
    text
}

/// A statistic as read: a whole number as it is, anything else to 4 significant digits
/// (`0.0001` rather than `0.00009999999999998899`), in scientific notation outside
/// 10⁻⁴ ..= 10⁹.
pub fn significant(v: f64) -> String {
    if !v.is_finite() {
        return v.to_string();
    }
    if v.fract() == 0.0 && v.abs() < 1e15 {
        return format!("{v:.0}");
    }
    let rounded: f64 = format!("{v:.3e}").parse().unwrap_or(v);
    let mag = rounded.abs().log10().floor();
    if (-4.0..=9.0).contains(&mag) {
        let decimals = (3.0 - mag).max(0.0) as usize;
        let fixed = format!("{rounded:.decimals$}");
        if fixed.contains('.') {
            fixed
                .trim_end_matches('0')
                .trim_end_matches('.')
                .to_string()
        } else {
            fixed
        }
    } else {
        format!("{rounded:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::{parse_resolution, significant};

    #[test]
    fn statistics_read_as_figures() {
        for (v, want) in [
            (0.000_099_999_999_999_988_99, "0.0001"),
            (271.502_788_104_089_23, "271.5"),
            (12.0, "12"),
            (1_234_567.0, "1234567"),
            (0.5, "0.5"),
            (-4.56789, "-4.568"),
            (123_456.7, "123500"),
            (1.5e-7, "1.500e-7"),
            (2.5e-12, "2.500e-12"),
            (1e16, "1.000e16"),
            (0.0, "0"),
            (f64::NAN, "NaN"),
        ] {
            assert_eq!(significant(v), want, "{v}");
        }
    }

    #[test]
    fn resolutions_parse_as_width_by_height() {
        assert_eq!(parse_resolution("640x480"), Ok((640, 480)));
        assert_eq!(parse_resolution("8X6"), Ok((8, 6)));
        for bad in ["640", "0x4", "4x0", "ax4", "4x-1", "x", ""] {
            assert!(parse_resolution(bad).is_err(), "{bad}");
        }
    }
}
