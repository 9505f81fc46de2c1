//! `kernel()` (the separable kernels of `sss kernel`, as arrays and in every export format) and
//! `filter()` (the screen-space pass of `sss filter`, on arrays instead of an EXR file).

use crate::arrays::{Axis, new_array, read};
use crate::errors::{guard, to_py, value_error};
use crate::model::Model;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use sss_bssrdf::{MediumSpec, ModelKind, make_model};
use sss_render::Error;
use sss_render::integrators::MethodOptions;
use sss_render::integrators::separable::kernel_settings;
use sss_render::kernel_choice::{KernelMethod, MaterialKernel, build_kernel, filter_options};
use sss_render::kernel_export::{KernelFormat, KernelRequest, export};
use sss_separable::{NO_OBJECT, ScreenInput, convolve2d, screen_space};

/// One tap: offset (mm) and RGB weight.
type Tap = [f64; 4];

/// A term's horizontal and vertical taps.
type Term = (Vec<Tap>, Vec<Tap>);

/// A separable subsurface-scattering kernel (Jimenez et al. 2015) for a model, exactly as
/// `sss kernel` exports it.
#[pyclass(module = "sss", frozen)]
pub struct Kernel {
    kind: ModelKind,
    spec: MediumSpec,
    eta: f64,
    method: KernelMethod,
    artist_preset: Option<String>,
    k: f64,
    taps: usize,
    uniform: bool,
    normalize: bool,
    /// Per term: horizontal and vertical taps (the same for a rank-1 kernel).
    terms: Vec<Term>,
    rank1: bool,
}

impl Kernel {
    /// The request of `sss kernel` that describes this kernel, with output `format`.
    fn args(&self, format: KernelFormat) -> KernelRequest {
        KernelRequest {
            medium: self.spec.clone(),
            eta: Some(self.eta),
            model: self.kind,
            method: self.method,
            artist_preset: self.artist_preset.clone(),
            k: self.k,
            taps: self.taps,
            uniform: self.uniform,
            format,
            normalize: self.normalize,
        }
    }
}

/// Parses the CSV of `sss kernel --format csv` (`term,direction,offset_mm,weight_r,weight_g,
/// weight_b`; numbers in shortest round-trip notation, so nothing is lost) into terms.
fn parse_csv(text: &str) -> Result<(Vec<Term>, bool), Error> {
    let bad = |line: &str| Error::Input(format!("internal: unexpected kernel CSV line `{line}`"));
    let mut terms: Vec<Term> = Vec::new();
    let mut rank1 = false;
    for line in text.lines().skip(1).filter(|l| !l.is_empty()) {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != 6 {
            return Err(bad(line));
        }
        let term: usize = f[0].parse().map_err(|_| bad(line))?;
        let mut tap = [0.0; 4];
        for (slot, s) in tap.iter_mut().zip(&f[2..]) {
            *slot = s.parse().map_err(|_| bad(line))?;
        }
        while terms.len() <= term {
            terms.push((Vec::new(), Vec::new()));
        }
        match f[1] {
            "both" => {
                rank1 = true;
                terms[term].0.push(tap);
                terms[term].1.push(tap);
            }
            "horizontal" => terms[term].0.push(tap),
            "vertical" => terms[term].1.push(tap),
            _ => return Err(bad(line)),
        }
    }
    Ok((terms, rank1))
}

fn taps_array<'py>(py: Python<'py>, taps: &[Tap]) -> PyResult<Bound<'py, PyAny>> {
    let values: Vec<f64> = taps.iter().flatten().copied().collect();
    new_array(py, values, &[taps.len(), 4])
}

#[pymethods]
impl Kernel {
    /// The kernel method ("preintegrated", "svd3", ...).
    #[getter]
    fn method(&self) -> &'static str {
        self.method.name()
    }

    /// The model whose R_d the kernel approximates.
    #[getter]
    fn model(&self) -> &'static str {
        self.kind.name()
    }

    /// Whether the weights were scaled to sum to 1 (`normalize=True`).
    #[getter]
    fn normalized(&self) -> bool {
        self.normalize
    }

    /// The taps of a rank-1 kernel (every method but svd3, svd6 and gaussians6) as float64
    /// (N, 4): offset in mm, then the R, G, B weights, in the order of the CSV export. None for
    /// a multi-term kernel (see `terms`).
    #[getter]
    fn taps<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        if self.rank1 {
            Ok(Some(taps_array(py, &self.terms[0].0)?))
        } else {
            Ok(None)
        }
    }

    /// Every term's (horizontal, vertical) taps, each float64 (N, 4) as `taps`; a rank-1
    /// kernel has one term whose two passes are the same.
    #[getter]
    fn terms<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyTuple>>> {
        self.terms
            .iter()
            .map(|(h, v)| PyTuple::new(py, [taps_array(py, h)?, taps_array(py, v)?]))
            .collect()
    }

    /// export(format="json") -> str
    ///
    /// The kernel as `sss kernel --format FORMAT` prints it: "json", "csv", or shader constants
    /// "glsl", "hlsl", "wgsl" (float4(r, g, b, offset in mm), centre tap first).
    #[pyo3(signature = (format="json"))]
    fn export(&self, py: Python<'_>, format: &str) -> PyResult<String> {
        let format: KernelFormat = format.parse().map_err(to_py)?;
        let args = self.args(format);
        py.detach(|| guard(|| export(&args).map_err(to_py)))
    }

    fn __repr__(&self) -> String {
        format!(
            "Kernel(method={:?}, model={:?}, taps={}, terms={})",
            self.method.name(),
            self.kind.name(),
            self.taps,
            self.terms.len()
        )
    }
}

/// kernel(model, method=None, *, taps=None, uniform=False, k=None, artist_preset=None,
/// normalize=False) -> Kernel
///
/// The separable kernel `sss kernel` exports for `model` (a `Model`): `method` one of
/// preintegrated, svd1, svd3, svd6, artist, guided, gaussians1, gaussians6; `taps` per 1D
/// pass; `uniform` places taps uniformly instead of by importance; `k` is the guided
/// exponent; `artist_preset` uses a Table 2 parameter set with method "artist"; `normalize`
/// scales the weights to sum to 1 instead of the total diffuse reflectance. None takes `sss
/// kernel`'s default (preintegrated, 7 taps, k = 2), from the library's one statement of them.
#[pyfunction]
#[pyo3(signature = (model, method=None, *, taps=None, uniform=false, k=None, artist_preset=None, normalize=false))]
#[allow(clippy::too_many_arguments)]
pub fn kernel(
    py: Python<'_>,
    model: &Model,
    method: Option<&str>,
    taps: Option<usize>,
    uniform: bool,
    k: Option<f64>,
    artist_preset: Option<String>,
    normalize: bool,
) -> PyResult<Kernel> {
    let defaults = KernelRequest::new(model.spec().clone());
    let method: KernelMethod = match method {
        Some(m) => m.parse().map_err(value_error)?,
        None => defaults.method,
    };
    let taps = taps.unwrap_or(defaults.taps);
    let k = k.unwrap_or(defaults.k);
    let mut kernel = Kernel {
        kind: model.kind(),
        spec: model.spec().clone(),
        eta: model.medium().eta(),
        method,
        artist_preset,
        k,
        taps,
        uniform,
        normalize,
        terms: Vec::new(),
        rank1: false,
    };
    let args = kernel.args(KernelFormat::Csv);
    let csv = py.detach(|| guard(|| export(&args).map_err(to_py)))?;
    let (terms, rank1) = parse_csv(&csv).map_err(to_py)?;
    kernel.terms = terms;
    kernel.rank1 = rank1;
    Ok(kernel)
}

/// filter(irradiance, depth, footprint, object_id, kernel=None, model=None, *,
/// units_per_mm=1.0, taps=None, uniform_taps=None, k=None, jitter=None, seed=1) -> ndarray
///
/// The screen-space separable pass of `sss filter` on arrays: `irradiance` float32 (H, W, 3),
/// `depth` and `footprint` (the world size of a pixel) float32 (H, W) in scene units,
/// `object_id` int32 (H, W), negative where no translucent object is seen. `kernel` is a kernel
/// name (None: "preintegrated"), with `model` a `Model`, or a `Kernel` from `kernel()` (its
/// model, method and taps); `taps`, `uniform_taps`, `k` and `jitter` are the options of
/// `sss filter` (None: its defaults). Returns the
/// diffuse exitance E ∗ R_d, float32 (H, W, 3).
#[pyfunction]
#[pyo3(signature = (irradiance, depth, footprint, object_id, kernel=None, model=None, *, units_per_mm=1.0, taps=None, uniform_taps=None, k=None, jitter=None, seed=1))]
#[allow(clippy::too_many_arguments)]
pub fn filter<'py>(
    py: Python<'py>,
    irradiance: &Bound<'py, PyAny>,
    depth: &Bound<'py, PyAny>,
    footprint: &Bound<'py, PyAny>,
    object_id: &Bound<'py, PyAny>,
    kernel: Option<&Bound<'py, PyAny>>,
    model: Option<&Bound<'py, PyAny>>,
    units_per_mm: f64,
    taps: Option<usize>,
    uniform_taps: Option<bool>,
    k: Option<f64>,
    jitter: Option<f64>,
    seed: u64,
) -> PyResult<Bound<'py, PyAny>> {
    let (irr, shape) = read::<f32>(
        irradiance,
        "irradiance",
        "float32",
        &[Axis::Any("H"), Axis::Any("W"), Axis::Fixed(3)],
    )?;
    let (h, w) = (shape[0], shape[1]);
    let hw = [Axis::Fixed(h), Axis::Fixed(w)];
    let (depth, _) = read::<f32>(depth, "depth", "float32", &hw)?;
    let (footprint, _) = read::<f32>(footprint, "footprint", "float32", &hw)?;
    let (ids, _) = read::<i32>(object_id, "object_id", "int32", &hw)?;
    if !(units_per_mm.is_finite() && units_per_mm > 0.0) {
        return Err(value_error(format!(
            "units_per_mm must be positive, got {units_per_mm}"
        )));
    }
    // The kernel and the model: from a Kernel object, or a name and a Model.
    let mut options = MethodOptions::new();
    let (kind, medium) = match kernel.map(|b| b.cast::<Kernel>()) {
        Some(Ok(kobj)) => {
            let kobj = kobj.get();
            if taps.is_some() || uniform_taps.is_some() || k.is_some() {
                return Err(value_error(
                    "taps, uniform_taps and k come from the Kernel; give a kernel name to set them",
                ));
            }
            if kobj.artist_preset.is_some() || kobj.normalize {
                return Err(value_error(
                    "filter needs a kernel fitted to its model (no artist_preset, no normalize)",
                ));
            }
            options.set("kernel", kobj.method.name());
            options.set("taps", kobj.taps);
            options.set("k", kobj.k);
            if kobj.uniform {
                options.set("uniform-taps", "");
            }
            let medium = kobj
                .spec
                .medium(Some(kobj.eta))
                .map_err(|e| to_py(e.into()))?;
            (kobj.kind, medium)
        }
        other => {
            let name: String =
                match other {
                    None => "preintegrated".into(),
                    Some(Err(_)) => kernel.and_then(|b| b.extract::<String>().ok()).ok_or_else(
                        || {
                            pyo3::exceptions::PyTypeError::new_err(
                                "kernel must be a kernel name (str) or a Kernel from sss.kernel()",
                            )
                        },
                    )?,
                    Some(Ok(_)) => unreachable!("handled above"),
                };
            let Some(model) = model else {
                return Err(value_error(format!(
                    "filter with kernel `{name}` needs model=sss.Model(...) (or pass a Kernel)"
                )));
            };
            let model = model.cast::<Model>().map_err(|_| {
                pyo3::exceptions::PyTypeError::new_err("model must be an sss.Model")
            })?;
            let model = model.get();
            options.set("kernel", name);
            if let Some(t) = taps {
                options.set("taps", t);
            }
            if let Some(k) = k {
                options.set("k", k);
            }
            if uniform_taps == Some(true) {
                options.set("uniform-taps", "");
            }
            (model.kind(), model.medium().clone())
        }
    };
    if let Some(j) = jitter {
        options.set("jitter", j);
    }
    let settings = kernel_settings(&options).map_err(to_py)?;
    let u = units_per_mm;
    let n = w * h;
    let mut e = vec![[0.0f32; 3]; n];
    let mut depth_mm = vec![0.0f32; n];
    let mut mm = vec![0.0f32; n];
    let mut mask = vec![NO_OBJECT; n];
    for i in 0..n {
        if ids[i] >= 0 {
            mask[i] = ids[i] as u32;
            depth_mm[i] = (depth[i] as f64 / u) as f32;
            mm[i] = (footprint[i] as f64 / u) as f32;
            e[i] = [irr[3 * i], irr[3 * i + 1], irr[3 * i + 2]];
        }
    }
    let out = py.detach(|| {
        guard(|| {
            let bssrdf = make_model(kind, &medium);
            let kernel = build_kernel(bssrdf.as_ref(), &settings).map_err(|e| {
                to_py(Error::Input(format!(
                    "cannot build the {} kernel: {e}",
                    settings.kernel
                )))
            })?;
            let input = ScreenInput {
                width: w,
                height: h,
                irradiance: &e,
                depth: &depth_mm,
                mask: &mask,
                mm_per_pixel: &mm,
            };
            let opts = filter_options(&settings, seed);
            match &kernel {
                MaterialKernel::Separable(k) => screen_space::filter(&input, k, &opts),
                MaterialKernel::Full(k2) => convolve2d::exact(&input, k2, &opts),
            }
            .map_err(|e| to_py(Error::Input(e.to_string())))
        })
    })?;
    py.check_signals()?;
    let values: Vec<f32> = out
        .iter()
        .flat_map(|p| p.map(|v| if v.is_finite() { v } else { 0.0 }))
        .collect();
    new_array(py, values, &[h, w, 3])
}
