//! Scenes as Python objects, as Mitsuba 3's `load_dict` and `load_file` give them: a scene
//! described by a dict with the scene file's structure (`camera`, `lights`, `materials`,
//! `objects`, the same keys and values as the TOML), loaded and checked once, rendered any
//! number of times, and its description given back as a dict to edit and load again.

use crate::errors::{guard, to_py};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use sss_render::Error;
use sss_render::scene::{BUILTIN_SCENES, LoadOptions, Scene as RustScene, load_named, load_str};
use std::path::{Path, PathBuf};

/// How a Python caller adds a mesh directory, for the error of a missing mesh.
pub const MESH_DIR_HINT: &str = "render(..., mesh_dirs=[...])";

/// A loaded, checked scene: `sss.load_dict(d)` or `sss.load_file(path)`; pass it to
/// `render`. `to_dict()` gives its description back (a new dict, to edit and load again).
#[pyclass(name = "Scene", module = "sss", frozen)]
pub struct Scene {
    /// The scene as the renderer takes it.
    pub scene: RustScene,
    /// Its description (TOML's data model).
    description: toml::Table,
}

/// A Python value as TOML: dict → table, list/tuple (or anything with `tolist()`, a numpy
/// array) → array, bool, int, float, str. Anything else is a `TypeError` naming the key.
fn to_toml(v: &Bound<'_, PyAny>, at: &str) -> PyResult<toml::Value> {
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(toml::Value::Integer(v.extract().map_err(|_| {
            PyTypeError::new_err(format!("scene `{at}`: integer out of range"))
        })?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(toml::Value::String(s.to_cow()?.into_owned()));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        return Ok(toml::Value::Table(to_table(d, at)?));
    }
    let items: Option<Bound<'_, PyAny>> =
        if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
            Some(v.clone())
        } else if v.hasattr("tolist")? {
            Some(v.call_method0("tolist")?)
        } else {
            None
        };
    if let Some(items) = items {
        if !(items.is_instance_of::<PyList>() || items.is_instance_of::<PyTuple>()) {
            return to_toml(&items, at);
        }
        let mut out = Vec::new();
        for (i, item) in items.try_iter()?.enumerate() {
            out.push(to_toml(&item?, &format!("{at}[{i}]"))?);
        }
        return Ok(toml::Value::Array(out));
    }
    let ty = v
        .get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into());
    Err(PyTypeError::new_err(format!(
        "scene `{at}`: a {ty} has no place in a scene (numbers, strings, booleans, lists and dicts do)"
    )))
}

fn to_table(d: &Bound<'_, PyDict>, at: &str) -> PyResult<toml::Table> {
    let mut t = toml::Table::new();
    for (k, v) in d.iter() {
        let key: String = k
            .extract()
            .map_err(|_| PyTypeError::new_err(format!("scene `{at}`: keys must be str")))?;
        let path = if at.is_empty() {
            key.clone()
        } else {
            format!("{at}.{key}")
        };
        if v.is_none() {
            // None leaves the key out (its default), as a missing key.
            continue;
        }
        t.insert(key, to_toml(&v, &path)?);
    }
    Ok(t)
}

/// A TOML value as Python.
fn to_python<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        toml::Value::String(s) => PyString::new(py, s).into_any(),
        toml::Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        toml::Value::Float(f) => PyFloat::new(py, *f).into_any(),
        toml::Value::Boolean(b) => PyBool::new(py, *b).to_owned().into_any(),
        toml::Value::Datetime(d) => PyString::new(py, &d.to_string()).into_any(),
        toml::Value::Array(a) => {
            let items = a
                .iter()
                .map(|x| to_python(py, x))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        toml::Value::Table(t) => {
            let d = PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, to_python(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// The scene `description` describes, loaded as the scene file `file` in `base_dir`.
fn load(
    description: toml::Table,
    file: &str,
    base_dir: Option<&Path>,
    mesh_dirs: &[PathBuf],
) -> PyResult<Scene> {
    let text = toml::to_string(&description)
        .map_err(|e| PyTypeError::new_err(format!("scene: cannot describe it as TOML: {e}")))?;
    let opts = LoadOptions::with_dirs(mesh_dirs);
    let scene = guard(|| {
        load_str(&text, file, base_dir, &opts)
            .map_err(|e| to_py(Error::Scene(e.with_mesh_hint(MESH_DIR_HINT))))
    })?;
    Ok(Scene { scene, description })
}

/// load_dict(description, *, mesh_dirs=None) -> Scene
///
/// Loads a scene described by a dict with the scene file's structure, e.g.
/// `{"camera": {"position": [0, 0, 4], "target": [0, 0, 0], "fov": 30, "resolution": [320,
/// 240]}, "lights": [{"type": "point", "position": [3, 4, 4], "intensity": 100}],
/// "materials": {"skin": {"type": "translucent", "model": "better-dipole", "preset":
/// "skin1", "units_per_mm": 0.05}}, "objects": [{"material": "skin", "shape": "sphere",
/// "radius": 1}]}` (see docs/scene-format.md; numpy arrays are taken as lists, None as a
/// missing key). The same checks as a scene file, with the same messages naming the key
/// (`objects[0].radius`); relative mesh paths are looked up in the working directory, then
/// `mesh_dirs`, then `SSS_MESH_DIR`.
#[pyfunction]
#[pyo3(signature = (description, *, mesh_dirs=None))]
pub fn load_dict(
    description: &Bound<'_, PyDict>,
    mesh_dirs: Option<Vec<PathBuf>>,
) -> PyResult<Scene> {
    let table = to_table(description, "")?;
    let cwd = std::env::current_dir().ok();
    load(
        table,
        "scene dict",
        cwd.as_deref(),
        &mesh_dirs.unwrap_or_default(),
    )
}

/// load_file(path, *, mesh_dirs=None) -> Scene
///
/// Loads a scene file (TOML), or a built-in scene by name (`BUILTIN_SCENES`), as `sss
/// render SCENE` does.
#[pyfunction]
#[pyo3(signature = (path, *, mesh_dirs=None))]
pub fn load_file(path: PathBuf, mesh_dirs: Option<Vec<PathBuf>>) -> PyResult<Scene> {
    let mesh_dirs = mesh_dirs.unwrap_or_default();
    let name = path.to_string_lossy().into_owned();
    let scene =
        guard(|| load_named(&name, &mesh_dirs, MESH_DIR_HINT).map_err(|e| to_py(Error::Scene(e))))?;
    let text = match BUILTIN_SCENES.iter().find(|(n, _)| *n == name) {
        Some((_, text)) if !path.exists() => text.to_string(),
        _ => std::fs::read_to_string(&path).map_err(|e| {
            to_py(Error::Io {
                what: format!("reading {}", path.display()),
                source: e,
            })
        })?,
    };
    let mut description: toml::Table = text
        .parse()
        .map_err(|e| PyTypeError::new_err(format!("{}: {e}", path.display())))?;
    // Mesh files relative to the scene file's directory, made absolute, so the description
    // loads the same meshes from anywhere.
    if let Some(dir) = path.parent().filter(|_| path.exists())
        && let Some(toml::Value::Array(objects)) = description.get_mut("objects")
    {
        for o in objects.iter_mut() {
            if let Some(toml::Value::String(f)) = o.get_mut("file")
                && Path::new(f.as_str()).is_relative()
                && dir.join(&*f).exists()
                && let Ok(abs) = std::path::absolute(dir.join(&*f))
            {
                *f = abs.to_string_lossy().into_owned();
            }
        }
    }
    Ok(Scene { scene, description })
}

#[pymethods]
impl Scene {
    /// The scene's description as a new dict (the scene file's structure; mesh paths of a
    /// scene file made absolute): edit it and `load_dict` it again.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &toml::Value::Table(self.description.clone()))
    }

    /// The camera's (width, height) in pixels.
    #[getter]
    fn resolution(&self) -> (u32, u32) {
        (self.scene.camera.width, self.scene.camera.height)
    }

    /// The objects' names, in order.
    #[getter]
    fn objects(&self) -> Vec<String> {
        self.scene.objects.iter().map(|o| o.name.clone()).collect()
    }

    /// The materials' names, in order.
    #[getter]
    fn materials(&self) -> Vec<String> {
        self.scene
            .materials
            .iter()
            .map(|m| m.name.clone())
            .collect()
    }

    /// The loader's warnings (e.g. degenerate triangles dropped).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.scene.warnings.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({:?}, {}x{}, {} object(s), {} light(s))",
            self.scene.name,
            self.scene.camera.width,
            self.scene.camera.height,
            self.scene.objects.len(),
            self.scene.lights.len()
        )
    }
}
