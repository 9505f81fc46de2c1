//! `sss diff`: error figures of one render against another (RMSE, relative RMSE, fraction of
//! pixels within a relative error, mean ratio per channel; [`sss_render::metrics`]), HDR-FLIP
//! ([`sss_render::flip`]), a false-colour error map and a FLIP map.

use crate::commands::render::check_output;
use crate::plot_error;
use clap::Args;
use sss_bssrdf::Rgb;
use sss_plot::{ColourMap, MapScale, write_error_map_with, write_flip_map};
use sss_render::Error;
use sss_render::flip::{FlipParams, hdr_flip};
use sss_render::image::{check_exr_budget, read_exr_within};
use sss_render::metrics::{error_figures, mean_ratio_rgb, relative_errors};
use std::path::{Path, PathBuf};

/// Arguments of `sss diff`.
#[derive(Debug, Args)]
pub struct DiffArgs {
    /// The render to judge (OpenEXR from `sss render`).
    pub image: PathBuf,
    /// The reference (OpenEXR from `sss render`).
    pub reference: PathBuf,
    /// Which layer to compare (of both files, unless `--reference-layer` names the
    /// reference's).
    #[arg(long, default_value = "subsurface")]
    pub layer: String,
    /// The reference's layer, when it differs from `--layer`: `beauty` for the plain R,G,B of
    /// another renderer's EXR, say.
    #[arg(long, value_name = "NAME")]
    pub reference_layer: Option<String>,
    /// False-colour error map (PNG) of the relative error per pixel; pixels beyond the range
    /// are drawn green and counted beside the colour bar.
    #[arg(long, value_name = "FILE.png")]
    pub png: Option<PathBuf>,
    /// The top of the error map's colour bar (a relative error). Default: 4 × --eps.
    #[arg(long, value_name = "MAX")]
    pub range: Option<f64>,
    /// The error map on a log scale: three decades below --range.
    #[arg(long)]
    pub log: bool,
    /// HDR-FLIP's per-pixel error (Andersson et al. 2021; magma, 0 to 1) of the whole layer as
    /// a PNG; its mean is the `flip` line either way.
    #[arg(long, value_name = "FILE.png")]
    pub flip_map: Option<PathBuf>,
    /// Relative-error threshold for the fraction of pixels within it.
    #[arg(long, default_value_t = 0.05)]
    pub eps: f64,
    /// Memory budget (bytes, or with a suffix: 512M, 8G); two EXRs whose headers say they need
    /// more together are refused before any pixel is read. Default: half the physical memory.
    #[arg(long, value_name = "BYTES", value_parser = sss_render::budget::parse_bytes)]
    pub max_memory: Option<u64>,
}

/// Runs `sss diff`.
pub fn run(args: &DiffArgs) -> Result<String, Error> {
    for p in args.png.iter().chain(&args.flip_map) {
        check_output(p, "png")?;
    }
    if let Some(r) = args.range
        && !(r.is_finite() && r > 0.0)
    {
        return Err(Error::Input(format!(
            "--range must be a finite relative error > 0, got {r}"
        )));
    }
    let budget = args
        .max_memory
        .unwrap_or_else(sss_render::budget::default_budget);
    check_exr_budget(&[&args.image, &args.reference], budget)?;
    let (w, h, a) = read_exr_within(&args.image, budget)?;
    let (wr, hr, b) = read_exr_within(&args.reference, budget)?;
    if (w, h) != (wr, hr) {
        return Err(Error::Input(format!(
            "{} is {w}x{h} but {} is {wr}x{hr}",
            args.image.display(),
            args.reference.display()
        )));
    }
    let pick = |layers: &[(String, Vec<Rgb>)],
                path: &Path,
                layer: &str,
                flag: &str|
     -> Result<Vec<Rgb>, Error> {
        layers
            .iter()
            .find(|(n, _)| n == layer)
            .map(|(_, d)| d.clone())
            .ok_or_else(|| {
                let names: Vec<&str> = layers.iter().map(|(n, _)| n.as_str()).collect();
                Error::Input(format!(
                    "{}: no layer `{layer}` (it has: {}; choose with {flag})",
                    path.display(),
                    names.join(", ")
                ))
            })
    };
    let img = pick(&a, &args.image, &args.layer, "--layer")?;
    let reference = match &args.reference_layer {
        Some(l) => pick(&b, &args.reference, l, "--reference-layer")?,
        None => pick(&b, &args.reference, &args.layer, "--reference-layer")?,
    };
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
        let scale = MapScale {
            max: args.range.unwrap_or(4.0 * args.eps),
            log: args.log,
            colours: ColourMap::Inferno,
        };
        write_error_map_with(
            p,
            w,
            h,
            &values,
            &scale,
            &format!(
                "relative error, layer {}{}",
                args.layer,
                if args.log { " (log scale)" } else { "" }
            ),
            "|a-b|/b",
        )
        .map_err(plot_error)?;
    }
    // FLIP sees the whole picture, background included.
    let flip = hdr_flip(
        &img,
        &reference,
        w as usize,
        h as usize,
        &FlipParams::default(),
    );
    if let Some(p) = &args.flip_map {
        write_flip_map(
            p,
            w,
            h,
            &flip.map,
            &format!("HDR-FLIP, layer {} (mean {:.4})", args.layer, flip.mean),
        )
        .map_err(plot_error)?;
    }
    let ratio = mean_ratio_rgb(&img, &reference, &pixels);
    Ok(format!(
        "pixels {}\nrmse {:.6e}\nrel_rmse {:.6e}\nfrac_within_{} {:.4}\nmean_ratio {:.5} {:.5} {:.5}\nflip {:.6}\n",
        pixels.len(),
        f.rmse,
        f.rel_rmse,
        args.eps,
        f.frac_within_eps,
        ratio[0],
        ratio[1],
        ratio[2],
        flip.mean
    ))
}
