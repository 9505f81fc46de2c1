//! The toolkit's errors as Python exceptions, with the message the `sss` binary prints after
//! `error: ` (one line).

use pyo3::PyErr;
use pyo3::exceptions::{
    PyFileNotFoundError, PyOSError, PyPermissionError, PyRuntimeError, PyValueError,
};
use sss_render::Error;
use sss_render::scene::SceneErrorKind;

/// Maps an error of the Rust side to its Python exception: `ValueError` for bad input (a bad
/// argument, medium, scene text or unsupported method), `OSError` (or its subclasses
/// `FileNotFoundError`, `PermissionError`) for files that cannot be read or written,
/// `RuntimeError` for a non-finite value (a bug in a model, reported instead of returned).
pub fn to_py(e: Error) -> PyErr {
    let msg = python_terms(&e.to_string().replace('\n', " "));
    match &e {
        Error::Io { source, .. } => os_error(source.kind(), msg),
        Error::Scene(s) if s.kind == SceneErrorKind::Io => PyOSError::new_err(msg),
        Error::NonFinite(_) => PyRuntimeError::new_err(msg),
        Error::Input(_) | Error::Bssrdf(_) | Error::Scene(_) | Error::Unsupported(_) => {
            PyValueError::new_err(msg)
        }
    }
}

/// A message of the Rust side in a Python caller's terms: the command line's `--max-samples`
/// is the keyword `max_samples`, and `--boundary lambertian`, where `lambertian` is one of the
/// values the option lists, is `boundary="lambertian"` (every method's options and their
/// values come from the one registry the command line uses).
pub fn python_terms(msg: &str) -> String {
    let mut out = String::with_capacity(msg.len());
    let mut rest = msg;
    while let Some(at) = rest.find("--") {
        out.push_str(&rest[..at]);
        let after = &rest[at + 2..];
        let len = after
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
            .unwrap_or(after.len());
        let name = after[..len].trim_end_matches('-');
        if !name.starts_with(|c: char| c.is_ascii_lowercase()) {
            // Not a flag (a rule `---`, a negative number, a lone `--`).
            out.push_str("--");
            rest = after;
            continue;
        }
        let keyword = name.replace('-', "_");
        rest = &after[name.len()..];
        // `--name VALUE` with VALUE one of the option's listed values: a keyword argument.
        let value = rest.strip_prefix(' ').and_then(|r| {
            let v_len = r
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '-' || c == '_'))
                .unwrap_or(r.len());
            let v = &r[..v_len];
            let listed = sss_render::integrators::METHODS.iter().any(|m| {
                m.options
                    .iter()
                    .any(|o| o.name == name && o.values.contains(&v))
            });
            (listed && !v.is_empty()).then_some(v)
        });
        match value {
            Some(v) => {
                if v.parse::<f64>().is_ok() {
                    out.push_str(&format!("{keyword}={v}"));
                } else {
                    out.push_str(&format!("{keyword}=\"{v}\""));
                }
                rest = &rest[1 + v.len()..];
            }
            None => out.push_str(&keyword),
        }
    }
    out.push_str(rest);
    out
}

/// The `OSError` subclass Python itself raises for an I/O error of this kind.
fn os_error(kind: std::io::ErrorKind, msg: String) -> PyErr {
    match kind {
        std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(msg),
        std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(msg),
        _ => PyOSError::new_err(msg),
    }
}

/// A `ValueError` with `msg`.
pub fn value_error(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}

/// A panic's payload as text, for the `RuntimeError` that reports it.
pub fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "panic".into())
        .replace('\n', " ")
}

/// Runs `f`, turning a panic (a bug) into a `RuntimeError` instead of letting PyO3 raise its
/// `PanicException`.
pub fn guard<T>(f: impl FnOnce() -> pyo3::PyResult<T>) -> pyo3::PyResult<T> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => Err(PyRuntimeError::new_err(format!(
            "internal error (a bug): {}",
            panic_text(payload.as_ref())
        ))),
    }
}
