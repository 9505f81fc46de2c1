//! The pictures of a run: a method's subsurface image, its false-colour error map and its
//! HDR-FLIP map.

use super::super::Error;
use super::EPS;
use sss_bssrdf::Rgb;
use sss_plot::{ColourMap, MapScale, write_error_map, write_error_map_with, write_signed_map};
use sss_render::RenderOutput;
use sss_render::image::write_png;
use sss_render::metrics::relative_errors;
use std::path::Path;

/// Writes `<name>.png` (the subsurface image), `<name>_error.png` (its relative error against
/// the `reference` over its scored `pixels`, false colour), `<name>_signed.png` (its signed
/// relative error in the pixels' mean over channels: blue too dark, red too bright) and
/// `<name>_flip.png` (its HDR-FLIP map `flip`, magma) into `dir`.
pub fn write_images(
    dir: &Path,
    name: &str,
    out: &RenderOutput,
    (reference, pixels): (&[Rgb], &[usize]),
    flip: &[f32],
    exposure: f64,
) -> Result<(), Error> {
    let e = |e: sss_render::Error| Error(e.to_string());
    write_png(
        &dir.join(format!("{name}.png")),
        out.width,
        out.height,
        &out.subsurface,
        exposure,
    )
    .map_err(e)?;
    let rel = relative_errors(&out.subsurface, reference, pixels);
    let mut values = vec![None; out.subsurface.len()];
    for (k, &i) in pixels.iter().enumerate() {
        values[i] = Some(rel[k]);
    }
    write_error_map(
        &dir.join(format!("{name}_error.png")),
        out.width,
        out.height,
        &values,
        4.0 * EPS,
        &format!("{name}: relative error against exact"),
        "|a-ref|/ref",
    )
    .map_err(|e| Error(e.to_string()))?;
    // Signed: (mean_c a − mean_c b) / max(mean_c b, 1 % of the reference's mean), the floor of
    // `relative_errors`, so that nearly black pixels do not dominate.
    let mean = |p: &Rgb| (p[0] + p[1] + p[2]) / 3.0;
    let floor = if pixels.is_empty() {
        0.0
    } else {
        pixels.iter().map(|&i| mean(&reference[i])).sum::<f64>() / pixels.len() as f64 * 0.01
    };
    let mut signed = vec![None; out.subsurface.len()];
    for &i in pixels {
        let b = mean(&reference[i]);
        let d = b.max(floor).max(1e-300);
        signed[i] = Some((mean(&out.subsurface[i]) - b) / d);
    }
    write_signed_map(
        &dir.join(format!("{name}_signed.png")),
        out.width,
        out.height,
        &signed,
        4.0 * EPS,
        &format!("{name}: signed relative error against exact"),
        "(a-ref)/ref",
    )
    .map_err(|e| Error(e.to_string()))?;
    let values: Vec<Option<f64>> = flip.iter().map(|&v| Some(f64::from(v))).collect();
    let scale = MapScale {
        max: 1.0,
        log: false,
        colours: ColourMap::Magma,
    };
    write_error_map_with(
        &dir.join(format!("{name}_flip.png")),
        out.width,
        out.height,
        &values,
        &scale,
        &format!("{name}: HDR-FLIP against exact"),
        "FLIP",
    )
    .map_err(|e| Error(e.to_string()))
}
