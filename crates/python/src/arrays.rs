//! numpy arrays in and out: inputs are checked (an ndarray, the dtype, the shape) with a
//! one-line message naming the argument, and copied in C order whatever their strides;
//! outputs are new C-contiguous arrays.

use numpy::{Element, PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use sss_bssrdf::Rgb;

/// One axis of an expected shape: a fixed length, or any length (named in messages).
#[derive(Clone, Copy, Debug)]
pub enum Axis {
    /// Exactly this length.
    Fixed(usize),
    /// Any length; the name shown in messages (`N`, `H`, `W`).
    Any(&'static str),
}

fn pattern(axes: &[Axis]) -> String {
    let parts: Vec<String> = axes
        .iter()
        .map(|a| match a {
            Axis::Fixed(n) => n.to_string(),
            Axis::Any(name) => (*name).to_string(),
        })
        .collect();
    if parts.len() == 1 {
        format!("({},)", parts[0])
    } else {
        format!("({})", parts.join(", "))
    }
}

fn shape_text(shape: &[usize]) -> String {
    let parts: Vec<String> = shape.iter().map(|n| n.to_string()).collect();
    if parts.len() == 1 {
        format!("({},)", parts[0])
    } else {
        format!("({})", parts.join(", "))
    }
}

/// Reads argument `name` as an ndarray of element type `T` (numpy dtype `dtype`) and shape
/// `axes`: its values in C order and its shape. A non-array or another dtype is a `TypeError`,
/// another shape a `ValueError`; both name the argument, what was expected and what was given.
pub fn read<T: Element + Copy>(
    obj: &Bound<'_, PyAny>,
    name: &str,
    dtype: &str,
    axes: &[Axis],
) -> PyResult<(Vec<T>, Vec<usize>)> {
    let expected = pattern(axes);
    let Ok(untyped) = obj.cast::<PyUntypedArray>() else {
        let ty = obj
            .get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_else(|_| "?".into());
        return Err(PyTypeError::new_err(format!(
            "{name} must be a numpy array of dtype {dtype} and shape {expected}, got {ty}; \
             convert with np.asarray({name}, dtype=np.{dtype})"
        )));
    };
    let shape = untyped.shape().to_vec();
    let Ok(typed) = obj.cast::<PyArrayDyn<T>>() else {
        return Err(PyTypeError::new_err(format!(
            "{name} must have dtype {dtype}, got {}; convert with {name}.astype(np.{dtype})",
            untyped.dtype()
        )));
    };
    let fits = shape.len() == axes.len()
        && shape.iter().zip(axes).all(|(n, a)| match a {
            Axis::Fixed(m) => n == m,
            Axis::Any(_) => true,
        });
    if !fits {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape {expected}, got {}",
            shape_text(&shape)
        )));
    }
    let ro = typed
        .try_readonly()
        .map_err(|e| PyValueError::new_err(format!("{name} cannot be read: {e}")))?;
    let values: Vec<T> = ro.as_array().iter().copied().collect();
    Ok((values, shape))
}

/// A float64 argument that is a Python number, a sequence of numbers (a list, a tuple, a
/// range) or a 1-D float64 array: its values, and whether it was a scalar (so results can be
/// returned as scalars too), as numpy functions take whatever `np.asarray` takes.
pub fn read_f64s(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<(Vec<f64>, bool)> {
    if obj.cast::<PyUntypedArray>().is_err() {
        if let Ok(v) = obj.extract::<f64>() {
            return Ok((vec![v], true));
        }
        if !obj.is_instance_of::<pyo3::types::PyString>()
            && let Ok(v) = obj.extract::<Vec<f64>>()
        {
            return Ok((v, false));
        }
    }
    let (v, _) = read::<f64>(obj, name, "float64", &[Axis::Any("N")])?;
    Ok((v, false))
}

/// Checks that every value is finite and within `[lo, hi)` (`hi` exclusive when `open_hi`),
/// naming the first that is not.
pub fn check_range(name: &str, values: &[f64], lo: f64, hi: f64, open_hi: bool) -> PyResult<()> {
    for (i, &v) in values.iter().enumerate() {
        let ok = v.is_finite() && v >= lo && if open_hi { v < hi } else { v <= hi };
        if !ok {
            let interval = match (hi.is_finite(), open_hi) {
                (false, _) => format!("[{lo}, inf)"),
                (true, true) => format!("[{lo}, {hi})"),
                (true, false) => format!("[{lo}, {hi}]"),
            };
            let at = if values.len() == 1 {
                String::new()
            } else {
                format!("[{i}]")
            };
            return Err(PyValueError::new_err(format!(
                "{name}{at} is {v}; it must be a finite number in {interval}"
            )));
        }
    }
    Ok(())
}

/// A C-contiguous array of `shape` holding `values` (in C order).
pub fn new_array<'py, T: Element>(
    py: Python<'py>,
    values: Vec<T>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    let flat = PyArray1::from_vec(py, values);
    Ok(flat.reshape(shape.to_vec())?.into_any())
}

/// An image of RGB pixels (row-major from the top-left) as a float32 array `(H, W, 3)`;
/// non-finite values become 0.
pub fn image<'py>(
    py: Python<'py>,
    pixels: &[Rgb],
    width: u32,
    height: u32,
) -> PyResult<Bound<'py, PyAny>> {
    let values: Vec<f32> = pixels.iter().flat_map(|p| p.map(finite_f32)).collect();
    new_array(py, values, &[height as usize, width as usize, 3])
}

/// `v` as f32, 0 where it is not finite (or not finite as f32).
pub fn finite_f32(v: f64) -> f32 {
    let f = v as f32;
    if f.is_finite() { f } else { 0.0 }
}

/// Rows of RGB values as a float64 array `(N, 3)`.
pub fn rgb_rows<'py>(py: Python<'py>, rows: &[Rgb]) -> PyResult<Bound<'py, PyAny>> {
    let values: Vec<f64> = rows.iter().flatten().copied().collect();
    new_array(py, values, &[rows.len(), 3])
}

/// An RGB triple as a float64 array `(3,)`.
pub fn rgb<'py>(py: Python<'py>, v: Rgb) -> PyResult<Bound<'py, PyAny>> {
    new_array(py, v.to_vec(), &[3])
}

/// Argument `name` as an RGB triple: any sequence of three numbers (a list, a tuple, an
/// array), or one number for all three channels (as a scene file's coefficients).
pub fn extract_rgb(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Rgb> {
    if obj.cast::<PyUntypedArray>().is_err()
        && let Ok(v) = obj.extract::<f64>()
    {
        return Ok([v; 3]);
    }
    let values: Vec<f64> = obj.extract().map_err(|_| {
        PyTypeError::new_err(format!(
            "{name} must be a number or a sequence of three numbers (R, G, B)"
        ))
    })?;
    <[f64; 3]>::try_from(values.as_slice()).map_err(|_| {
        PyValueError::new_err(format!(
            "{name} must hold three numbers (R, G, B), got {}",
            values.len()
        ))
    })
}
