//! `render()` (as `sss render`, into arrays), `diff()` (the figures of `sss diff`) and
//! `read_exr()` (the EXR reader `sss diff` and `sss filter` use).

use crate::arrays::{image, new_array};
use crate::errors::{guard, python_terms, to_py, value_error};
use crate::progress::run_cancellable;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use sss_bssrdf::Rgb;
use sss_render::Error;
use sss_render::image::{read_exr, read_exr_alpha};
use sss_render::integrators::{self, MethodOptions};
use sss_render::metrics::{error_figures, mean_ratio_rgb};
use sss_render::scene::{LoadOptions, Scene, load_named, load_str};
use sss_render::{RenderSettings, render as render_scene};
use std::path::PathBuf;

use crate::scene::MESH_DIR_HINT;

/// Loads `scene`: a `Scene` (`load_dict`, `load_file`), a dict (as `load_dict` takes), TOML
/// text (a str holding a line break), a path (str or os.PathLike) or the name of a built-in
/// scene, as `sss render SCENE` resolves it.
fn scene_from(scene: &Bound<'_, PyAny>, mesh_dirs: &[PathBuf]) -> PyResult<Scene> {
    if let Ok(s) = scene.cast::<crate::scene::Scene>() {
        return Ok(s.get().scene.clone());
    }
    if let Ok(d) = scene.cast::<PyDict>() {
        return Ok(crate::scene::load_dict(d, Some(mesh_dirs.to_vec()))?.scene);
    }
    if let Ok(s) = scene.cast::<PyString>() {
        let text = s.to_cow()?;
        if text.contains('\n') {
            let opts = LoadOptions::with_dirs(mesh_dirs);
            let cwd = std::env::current_dir().ok();
            return guard(|| {
                load_str(&text, "scene.toml", cwd.as_deref(), &opts)
                    .map_err(|e| to_py(Error::Scene(e.with_mesh_hint(MESH_DIR_HINT))))
            });
        }
        return guard(|| {
            load_named(&text, mesh_dirs, MESH_DIR_HINT).map_err(|e| to_py(Error::Scene(e)))
        });
    }
    let path: PathBuf = scene.extract().map_err(|_| {
        PyTypeError::new_err(
            "scene must be a Scene, a dict (as load_dict takes), a path (str or os.PathLike), a \
             built-in scene's name or TOML text",
        )
    })?;
    let name = path.to_string_lossy().into_owned();
    guard(|| load_named(&name, mesh_dirs, MESH_DIR_HINT).map_err(|e| to_py(Error::Scene(e))))
}

/// The options of `method` among those `given`, and a warning for each option given that
/// another method takes (ignored, as the command line ignores another method's flag with a
/// warning). An option no method takes is a `TypeError` (a misspelling, most likely) naming
/// the options `method` does take.
fn options_of(method: &str, given: &MethodOptions) -> PyResult<(MethodOptions, Vec<String>)> {
    let m = guard(|| integrators::method(method).map_err(to_py))?;
    let keyword = |name: &str| name.replace('-', "_");
    let (options, others) = given.partition(m);
    let mut ignored = Vec::new();
    for name in &others {
        if integrators::METHODS
            .iter()
            .any(|other| other.options.iter().any(|o| o.name == *name))
        {
            ignored.push(format!(
                "{} is not an option of method {method}; ignored",
                keyword(name)
            ));
        } else {
            let known: Vec<String> = m.options.iter().map(|o| keyword(o.name)).collect();
            return Err(PyTypeError::new_err(format!(
                "render() got an unexpected keyword argument '{}' (method {method} takes {})",
                keyword(name),
                if known.is_empty() {
                    "no options".to_string()
                } else {
                    known.join(", ")
                }
            )));
        }
    }
    Ok((options, ignored))
}

/// Method options from Python keyword arguments: `spp=4` is `--spp 4`, `uniform_taps=True`
/// the switch `--uniform-taps` (False leaves it off).
fn method_options(options: Option<&Bound<'_, PyDict>>) -> PyResult<MethodOptions> {
    let mut out = MethodOptions::new();
    if let Some(d) = options {
        for (key, value) in d.iter() {
            let name = key.extract::<String>()?.replace('_', "-");
            if let Ok(b) = value.cast::<pyo3::types::PyBool>() {
                if b.is_true() {
                    out.set(&name, "");
                }
                continue;
            }
            out.set(&name, value.str()?.to_cow()?);
        }
    }
    Ok(out)
}

/// render(scene, method="exact", *, seed=1, threads=None, max_memory=None, mesh_dirs=None,
/// progress=None, resolution=None, pixel_samples=None, **options) -> dict
///
/// Renders `scene` (a `Scene`, a dict as `load_dict` takes, a path, a built-in scene's name,
/// or TOML text) with `method` as
/// `sss render` does; `options` are the method's options (`spp=16`, `kernel="svd3"`,
/// `uniform_taps=True`): one of another method is ignored with a `UserWarning` (as the
/// command line does), one of no method is a `TypeError`. `resolution=(width, height)` and
/// `pixel_samples=n` override the scene's camera (`camera.resolution`,
/// `camera.pixel_samples`), as `--resolution` and `--pixel-samples` do. Returns a dict: the layers `total`, `subsurface`, `std_error`
/// (stochastic methods) and the method's own (`irradiance`, `surface`, ...) as float32
/// (H, W, 3); `coverage` (translucent objects) and `alpha` (any object: the silhouette, the
/// EXR's channel A) float32 (H, W); `stats` {name: value}; `stages` {name: seconds};
/// `method`, `settings` (the method's description), `irradiance_samples`,
/// `irradiance_left_out` (about how many more the parts out of the profile's reach of every
/// visible point would have taken), `warnings`.
/// Releases the GIL; `progress(done, total)` is called with shaded samples (`progress=True`
/// draws a text bar on `sys.stderr`); Ctrl-C stops it (KeyboardInterrupt), and so does an
/// exception raised by `progress`.
#[pyfunction]
#[pyo3(signature = (scene, method="exact", *, seed=1, threads=None, max_memory=None, mesh_dirs=None, progress=None, resolution=None, pixel_samples=None, **options))]
#[allow(clippy::too_many_arguments)]
pub fn render<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    method: &str,
    seed: u64,
    threads: Option<usize>,
    max_memory: Option<&Bound<'py, PyAny>>,
    mesh_dirs: Option<Vec<PathBuf>>,
    progress: Option<Bound<'py, PyAny>>,
    resolution: Option<(u32, u32)>,
    pixel_samples: Option<u32>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    if resolution.is_some_and(|(w, h)| w == 0 || h == 0) {
        return Err(value_error(
            "resolution must be (width, height), both at least 1",
        ));
    }
    if pixel_samples == Some(0) {
        return Err(value_error("pixel_samples must be at least 1"));
    }
    let given = method_options(options)?;
    let (opts, ignored) = options_of(method, &given)?;
    let warn = |msg: &str| -> PyResult<()> {
        let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
        let text = std::ffi::CString::new(msg.replace('\0', " "))
            .map_err(|e| value_error(e.to_string()))?;
        PyErr::warn(py, &category, &text, 1)
    };
    for msg in &ignored {
        warn(msg)?;
    }
    let integrator = guard(|| integrators::build(method, &opts).map_err(to_py))?;
    if threads == Some(0) {
        return Err(value_error("threads must be at least 1"));
    }
    let max_memory = match max_memory {
        None => sss_render::budget::default_budget(),
        Some(v) => match v.extract::<u64>() {
            Ok(n) => n,
            Err(_) => {
                let s: String = v.extract().map_err(|_| {
                    PyTypeError::new_err("max_memory must be bytes (int) or a size like \"8G\"")
                })?;
                sss_render::budget::parse_bytes(&s)
                    .map_err(|e| value_error(format!("max_memory: {e}")))?
            }
        },
    };
    let mut scene = scene_from(scene, &mesh_dirs.unwrap_or_default())?;
    if let Some((w, h)) = resolution {
        scene.camera.width = w;
        scene.camera.height = h;
    }
    if let Some(n) = pixel_samples {
        scene.camera.pixel_samples = n;
    }
    let settings = RenderSettings {
        seed,
        max_memory,
        ..RenderSettings::default()
    };
    let pool = match threads {
        Some(n) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| value_error(format!("cannot start {n} threads: {e}")))?,
        ),
        None => None,
    };
    let integrator_ref = integrator.as_ref();
    let out = run_cancellable(
        py,
        crate::progress::callback(progress, method)?,
        |monitor| {
            let go = || render_scene(&scene, integrator_ref, &settings, monitor);
            match &pool {
                Some(p) => p.install(go),
                None => go(),
            }
        },
    )?;
    let d = PyDict::new(py);
    let (w, h) = (out.width, out.height);
    d.set_item("total", image(py, &out.total, w, h)?)?;
    d.set_item("subsurface", image(py, &out.subsurface, w, h)?)?;
    if let Some(se) = &out.std_error {
        d.set_item("std_error", image(py, se, w, h)?)?;
    }
    for layer in &out.layers {
        d.set_item(layer.name, image(py, &layer.pixels, w, h)?)?;
    }
    for (name, values) in [("coverage", &out.coverage), ("alpha", &out.alpha)] {
        let clean: Vec<f32> = values
            .iter()
            .map(|&c| if c.is_finite() { c } else { 0.0 })
            .collect();
        d.set_item(name, new_array(py, clean, &[h as usize, w as usize])?)?;
    }
    let stats = PyDict::new(py);
    for s in &out.stats {
        stats.set_item(s.name, s.value)?;
    }
    d.set_item("stats", stats)?;
    let stages = PyDict::new(py);
    for s in &out.stages {
        stages.set_item(s.name, s.seconds)?;
    }
    d.set_item("stages", stages)?;
    d.set_item("method", out.method)?;
    d.set_item("settings", integrator.describe())?;
    d.set_item("irradiance_samples", out.irradiance_samples)?;
    d.set_item("irradiance_left_out", out.irradiance_left_out)?;
    let warnings: Vec<String> = scene
        .warnings
        .iter()
        .chain(out.warnings.iter())
        .map(|w| python_terms(w))
        .collect();
    for msg in &warnings {
        warn(msg)?;
    }
    let warnings: Vec<String> = ignored.into_iter().chain(warnings).collect();
    d.set_item("warnings", warnings)?;
    Ok(d)
}

/// read_exr(path) -> dict[str, ndarray]
///
/// Every RGB layer of an OpenEXR file (as `sss render --out/--gbuffer` and `sss filter` write
/// them), by name, as float32 (H, W, 3), and `alpha` float32 (H, W) when the file has the
/// channel A (as `sss render --out` writes). Raises OSError for a file that cannot be read.
#[pyfunction(name = "read_exr")]
pub fn read_exr_layers<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let (w, h, layers, alpha) = py.detach(|| {
        guard(|| {
            let (w, h, layers) = read_exr(&path).map_err(to_py)?;
            let alpha = read_exr_alpha(&path).map_err(to_py)?;
            Ok((w, h, layers, alpha))
        })
    })?;
    let d = PyDict::new(py);
    if let Some(a) = alpha {
        d.set_item("alpha", new_array(py, a, &[h as usize, w as usize])?)?;
    }
    for (name, pixels) in &layers {
        // Callers that look layers up by name take the first (as `sss diff`).
        if !d.contains(name)? {
            d.set_item(name, image(py, pixels, w, h)?)?;
        }
    }
    Ok(d)
}

/// An image argument of `diff`: an array (H, W, 3) of float32 or float64, or an EXR path
/// whose layer `layer` is taken.
fn diff_input(
    obj: &Bound<'_, PyAny>,
    what: &str,
    layer: &str,
    param: &str,
) -> PyResult<(usize, usize, Vec<Rgb>)> {
    if obj.cast::<numpy::PyUntypedArray>().is_ok() {
        let (px, w, h) = crate::files::image_arg(obj, what)?;
        if let Some(i) = px.iter().flatten().position(|x| !x.is_finite()) {
            return Err(value_error(format!(
                "{what} holds a non-finite value ({}) at flat index {i}",
                px[i / 3][i % 3]
            )));
        }
        return Ok((w, h, px));
    }
    let path: PathBuf = obj.extract().map_err(|_| {
        PyTypeError::new_err(format!(
            "{what} must be an image array (H, W, 3) or the path of an EXR file"
        ))
    })?;
    let (w, h, layers) = guard(|| read_exr(&path).map_err(to_py))?;
    let pixels = layers
        .iter()
        .find(|(n, _)| n == layer)
        .map(|(_, d)| d.clone())
        .ok_or_else(|| {
            let names: Vec<&str> = layers.iter().map(|(n, _)| n.as_str()).collect();
            value_error(format!(
                "{}: no layer `{layer}` (it has: {}; choose with {param}=)",
                path.display(),
                names.join(", ")
            ))
        })?;
    Ok((w as usize, h as usize, pixels))
}

/// diff(a, ref, *, layer="subsurface", reference_layer=None, eps=0.05) -> dict
///
/// The error figures of `sss diff` of image `a` against `ref`: each an array (H, W, 3) of
/// float32 or float64, or an EXR path (then `layer` is read, or for `ref` `reference_layer`
/// when given: `"beauty"` for another renderer's plain R,G,B). Pixels where either image is
/// positive are compared. Returns {"pixels", "rmse", "rel_rmse", "frac_within_eps",
/// "mean_ratio" (float64 (3,)), "flip" (HDR-FLIP's mean over every pixel)}.
#[pyfunction]
#[pyo3(signature = (a, reference, *, layer="subsurface", reference_layer=None, eps=0.05))]
pub fn diff<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    reference: &Bound<'py, PyAny>,
    layer: &str,
    reference_layer: Option<&str>,
    eps: f64,
) -> PyResult<Bound<'py, PyDict>> {
    if !(eps.is_finite() && eps > 0.0) {
        return Err(value_error(format!(
            "eps must be a finite number > 0, got {eps}"
        )));
    }
    let (w, h, img) = diff_input(a, "a", layer, "layer")?;
    let (wr, hr, reference) = diff_input(
        reference,
        "ref",
        reference_layer.unwrap_or(layer),
        "reference_layer",
    )?;
    if (w, h) != (wr, hr) {
        return Err(value_error(format!(
            "a has shape ({h}, {w}, 3) but ref has shape ({hr}, {wr}, 3)"
        )));
    }
    // The pixels `sss diff` compares: where either image is positive.
    let pixels: Vec<usize> = (0..img.len())
        .filter(|&i| reference[i].iter().chain(img[i].iter()).any(|v| *v > 0.0))
        .collect();
    let (f, ratio, flip) = guard(|| {
        Ok((
            error_figures(&img, &reference, &pixels, eps),
            mean_ratio_rgb(&img, &reference, &pixels),
            sss_render::flip::hdr_flip(&img, &reference, w, h, &Default::default()).mean,
        ))
    })?;
    let clean = |v: f64| if v.is_finite() { v } else { 0.0 };
    let d = PyDict::new(py);
    d.set_item("pixels", pixels.len())?;
    d.set_item("rmse", clean(f.rmse))?;
    d.set_item("rel_rmse", clean(f.rel_rmse))?;
    d.set_item("frac_within_eps", clean(f.frac_within_eps))?;
    d.set_item("mean_ratio", crate::arrays::rgb(py, ratio.map(clean))?)?;
    d.set_item("flip", clean(flip))?;
    Ok(d)
}
