//! The pictures of a run: a method's subsurface image, its false-colour error map and its
//! HDR-FLIP map.

use super::super::Error;
use super::EPS;
use sss_bssrdf::Rgb;
use sss_plot::{write_error_map, write_flip_map, write_signed_map};
use sss_render::RenderOutput;
use sss_render::image::write_png;
use sss_render::metrics::{relative_errors, signed_relative_errors};
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
    // Per-pixel values of the scored pixels, the others empty (drawn grey).
    let on_pixels = |values: Vec<f64>| {
        let mut all = vec![None; out.subsurface.len()];
        for (&i, v) in pixels.iter().zip(values) {
            all[i] = Some(v);
        }
        all
    };
    let values = on_pixels(relative_errors(&out.subsurface, reference, pixels));
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
    let signed = on_pixels(signed_relative_errors(&out.subsurface, reference, pixels));
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
    write_flip_map(
        &dir.join(format!("{name}_flip.png")),
        out.width,
        out.height,
        flip,
        &format!("{name}: HDR-FLIP against exact"),
    )
    .map_err(|e| Error(e.to_string()))
}
