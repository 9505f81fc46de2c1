//! `write_exr()` and `write_png()`: arrays to the files `sss render` writes, through the same
//! writers (so `sss diff`, `read_exr` and other renderers' readers read them).

use crate::arrays::{Axis, read};
use crate::errors::{guard, to_py, value_error};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sss_bssrdf::Rgb;
use sss_render::image::{exposure_or_auto, write_exr_with, write_png as write_png_file};
use std::path::PathBuf;

/// An image argument: a float64 or float32 array (H, W, 3) (another dtype or shape gets
/// float32's message), its pixels and (width, height).
pub fn image_arg(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<(Vec<Rgb>, usize, usize)> {
    let axes = [Axis::Any("H"), Axis::Any("W"), Axis::Fixed(3)];
    let (v, shape) = match read::<f64>(obj, name, "float64", &axes) {
        Ok(got) => got,
        Err(_) => {
            let (v, shape) = read::<f32>(obj, name, "float32", &axes)?;
            (v.into_iter().map(f64::from).collect(), shape)
        }
    };
    let pixels = v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    Ok((pixels, shape[1], shape[0]))
}

/// write_exr(path, layers, *, alpha=None, attributes=None)
///
/// Writes a linear OpenEXR file as `sss render --out` does: `layers` is an image (float32 or
/// float64 (H, W, 3), written as the plain channels R, G, B of a part named `beauty`) or a
/// dict of them by name (the first is the plain R, G, B and names the part, the others are
/// `NAME.R`, `NAME.G`, `NAME.B`); `alpha` an optional (H, W) array written as channel A;
/// `attributes` optional {name: text} header attributes. Negative and non-finite values are
/// written as 0. The file is written under a temporary name and renamed into place, so an
/// error leaves no partial file. `read_exr` gives the layers back.
#[pyfunction]
#[pyo3(signature = (path, layers, *, alpha=None, attributes=None))]
pub fn write_exr(
    py: Python<'_>,
    path: PathBuf,
    layers: &Bound<'_, PyAny>,
    alpha: Option<&Bound<'_, PyAny>>,
    attributes: Option<&Bound<'_, PyDict>>,
) -> PyResult<()> {
    let mut named: Vec<(String, Vec<Rgb>)> = Vec::new();
    let mut size: Option<(usize, usize, String)> = None;
    let mut add = |name: String, obj: &Bound<'_, PyAny>| -> PyResult<()> {
        let what = format!("layers[{name:?}]");
        let (px, w, h) = image_arg(obj, &what)?;
        if let Some((w0, h0, first)) = &size {
            if (w, h) != (*w0, *h0) {
                return Err(value_error(format!(
                    "{what} has shape ({h}, {w}, 3) but {first} has ({h0}, {w0}, 3); every layer \
                     must have one shape"
                )));
            }
        } else {
            size = Some((w, h, what));
        }
        named.push((name, px));
        Ok(())
    };
    if let Ok(d) = layers.cast::<PyDict>() {
        for (k, v) in d.iter() {
            let name: String = k
                .extract()
                .map_err(|_| PyTypeError::new_err("layers' names must be str"))?;
            add(name, &v)?;
        }
    } else {
        add("beauty".to_string(), layers)?;
    }
    let Some((w, h, _)) = size else {
        return Err(value_error("layers must hold at least one image"));
    };
    let alpha = match alpha {
        None => None,
        Some(a) => {
            let (v, _) = read::<f32>(a, "alpha", "float32", &[Axis::Fixed(h), Axis::Fixed(w)])?;
            Some(v)
        }
    };
    let mut attrs: Vec<(String, String)> = Vec::new();
    if let Some(d) = attributes {
        for (k, v) in d.iter() {
            let name: String = k
                .extract()
                .map_err(|_| PyTypeError::new_err("attributes' names must be str"))?;
            attrs.push((name, v.str()?.to_cow()?.into_owned()));
        }
    }
    py.detach(|| {
        guard(|| {
            let layers: Vec<(&str, &[Rgb])> = named
                .iter()
                .map(|(n, p)| (n.as_str(), p.as_slice()))
                .collect();
            let attrs: Vec<(&str, String)> =
                attrs.iter().map(|(n, v)| (n.as_str(), v.clone())).collect();
            write_exr_with(&path, w as u32, h as u32, &layers, alpha.as_deref(), &attrs)
                .map_err(to_py)
        })
    })
}

/// write_png(path, image, *, exposure=None)
///
/// Writes an image (float32 or float64 (H, W, 3), linear) as an 8-bit sRGB PNG, as `sss
/// render --png` does: scaled by `exposure`, or by the automatic exposure `sss render` uses
/// (the 95th percentile of luminance mapped near white) when None.
#[pyfunction]
#[pyo3(signature = (path, image, *, exposure=None))]
pub fn write_png(
    py: Python<'_>,
    path: PathBuf,
    image: &Bound<'_, PyAny>,
    exposure: Option<f64>,
) -> PyResult<()> {
    let (px, w, h) = image_arg(image, "image")?;
    if let Some(e) = exposure
        && !(e.is_finite() && e > 0.0)
    {
        return Err(value_error(format!(
            "exposure must be a finite number > 0, got {e}"
        )));
    }
    py.detach(|| {
        guard(|| {
            let e = exposure_or_auto(exposure, &px);
            write_png_file(&path, w as u32, h as u32, &px, e).map_err(to_py)
        })
    })
}
