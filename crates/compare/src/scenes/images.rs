//! The pictures of a run: a method's subsurface image and its false-colour error map.

use super::super::Error;
use super::EPS;
use sss_bssrdf::Rgb;
use sss_plot::write_error_map;
use sss_render::RenderOutput;
use sss_render::image::write_png;
use sss_render::metrics::relative_errors;
use std::path::Path;

/// Writes `<name>.png` (the subsurface image) and `<name>_error.png` (its relative error
/// against the reference, false colour) into `dir`.
pub fn write_images(
    dir: &Path,
    name: &str,
    out: &RenderOutput,
    reference: &[Rgb],
    pixels: &[usize],
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
    .map_err(|e| Error(e.to_string()))
}
