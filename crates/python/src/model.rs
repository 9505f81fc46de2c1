//! `Model`, `presets()` and `monte_carlo()`: the radial profiles of `sss profile` and the
//! measured materials of `sss presets`.

use crate::arrays::{check_range, extract_rgb, read_f64s, rgb, rgb_rows};
use crate::errors::{guard, to_py, value_error};
use crate::progress::run_cancellable;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyFloat, PyTuple};
use sss_bssrdf::profile_rows::{ProfileModel, ProfileRequest, check_budget, compute};
use sss_bssrdf::{Bssrdf, Medium, MediumSpec, ModelKind, Rgb, make_model};
use sss_render::Error;

/// The medium named by the keyword arguments shared by `Model` and `monte_carlo`: a preset
/// (g = 0, σ_s = σ'_s), or σ_a and σ_s with an optional g; η defaults to 1.3.
pub fn medium_spec(
    preset: Option<String>,
    sigma_a: Option<&Bound<'_, PyAny>>,
    sigma_s: Option<&Bound<'_, PyAny>>,
    g: Option<f64>,
) -> PyResult<MediumSpec> {
    match (preset, sigma_a, sigma_s) {
        (Some(name), None, None) => {
            if g.is_some() {
                return Err(value_error(
                    "g applies to sigma_a/sigma_s; a preset has g = 0 (give sigma_a, sigma_s and g instead)",
                ));
            }
            Ok(MediumSpec::Preset(name))
        }
        (None, Some(a), Some(s)) => Ok(MediumSpec::Coefficients {
            sigma_a: extract_rgb(a, "sigma_a")?,
            sigma_s: extract_rgb(s, "sigma_s")?,
            g: g.unwrap_or(0.0),
        }),
        _ => Err(value_error(
            "give either preset=NAME or both sigma_a=(R, G, B) and sigma_s=(R, G, B)",
        )),
    }
}

/// The message `sss profile` gives for η outside the `mc-table` tables (its check, so a
/// `Model("mc-table", ...)` refuses what `sss profile --model mc-table` refuses).
fn check_mc_table_eta(kind: ModelKind, medium: &Medium) -> Result<(), Error> {
    use sss_bssrdf::mc_table::{ETAS, eta_in_range};
    if kind == ModelKind::McTable && !eta_in_range(medium.eta()) {
        return Err(Error::Input(format!(
            "--eta {} is outside the range of the mc-table tables (η from {} to {}); use \
             another model for this medium",
            medium.eta(),
            ETAS[0],
            ETAS[ETAS.len() - 1]
        )));
    }
    Ok(())
}

fn finite(what: impl Fn() -> String, v: f64) -> PyResult<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(to_py(Error::NonFinite(format!(
            "{} is {v}, not a finite number (a bug in the model)",
            what()
        ))))
    }
}

fn channel(ch: i64) -> PyResult<usize> {
    if (0..3).contains(&ch) {
        Ok(ch as usize)
    } else {
        Err(value_error(format!(
            "channel must be 0, 1 or 2 (R, G, B), got {ch}"
        )))
    }
}

/// A BSSRDF model for a medium: its radial profile R_d(r), importance sampling of radii and
/// total diffuse reflectance, as `sss profile` evaluates them. Lengths in mm.
#[pyclass(module = "sss", frozen)]
pub struct Model {
    kind: ModelKind,
    spec: MediumSpec,
    medium: Medium,
    model: Box<dyn Bssrdf>,
}

impl Model {
    /// The model's kind.
    pub fn kind(&self) -> ModelKind {
        self.kind
    }

    /// The medium as named (preset or coefficients).
    pub fn spec(&self) -> &MediumSpec {
        &self.spec
    }

    /// The validated medium.
    pub fn medium(&self) -> &Medium {
        &self.medium
    }

    /// The model itself.
    pub fn bssrdf(&self) -> &dyn Bssrdf {
        self.model.as_ref()
    }
}

#[pymethods]
impl Model {
    /// Model(kind, preset=None, sigma_a=None, sigma_s=None, g=None, eta=None)
    ///
    /// `kind` is one of "standard-dipole", "better-dipole", "directional-dipole", "pbd",
    /// "burley", "mc-table". The medium is a preset (see `presets()`) or `sigma_a` and
    /// `sigma_s` (1/mm, three numbers each) with anisotropy `g` (default 0); `eta` is the
    /// relative index of refraction (default 1.3). Raises ValueError for an unknown kind or
    /// preset or an invalid medium.
    #[new]
    #[pyo3(signature = (kind, preset=None, sigma_a=None, sigma_s=None, g=None, eta=None))]
    fn new(
        kind: &str,
        preset: Option<String>,
        sigma_a: Option<&Bound<'_, PyAny>>,
        sigma_s: Option<&Bound<'_, PyAny>>,
        g: Option<f64>,
        eta: Option<f64>,
    ) -> PyResult<Self> {
        guard(|| {
            let kind: ModelKind = kind.parse().map_err(|e| to_py(Error::Bssrdf(e)))?;
            let spec = medium_spec(preset, sigma_a, sigma_s, g)?;
            let medium = spec.medium(eta).map_err(|e| to_py(e.into()))?;
            check_mc_table_eta(kind, &medium).map_err(to_py)?;
            let model = make_model(kind, &medium);
            Ok(Model {
                kind,
                spec,
                medium,
                model,
            })
        })
    }

    /// The model's name ("better-dipole", ...).
    #[getter(kind)]
    fn kind_name(&self) -> &'static str {
        self.kind.name()
    }

    /// The preset's name, or None for a medium given by coefficients.
    #[getter]
    fn preset(&self) -> Option<String> {
        match &self.spec {
            MediumSpec::Preset(p) => Some(p.clone()),
            MediumSpec::Coefficients { .. } => None,
        }
    }

    /// Absorption coefficients σ_a (1/mm), float64 (3,).
    #[getter]
    fn sigma_a<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        rgb(py, self.medium.sigma_a())
    }

    /// Scattering coefficients σ_s (1/mm), float64 (3,).
    #[getter]
    fn sigma_s<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        rgb(py, self.medium.sigma_s())
    }

    /// Henyey-Greenstein anisotropy g.
    #[getter]
    fn g(&self) -> f64 {
        self.medium.g()
    }

    /// Relative index of refraction η.
    #[getter]
    fn eta(&self) -> f64 {
        self.medium.eta()
    }

    /// Total diffuse reflectance ∫ 2πr R_d(r) dr per channel, float64 (3,) (as the
    /// `# total_diffuse_reflectance=` line of `sss profile`).
    #[getter]
    fn total_diffuse_reflectance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut total: Rgb = [0.0; 3];
        for (ch, t) in total.iter_mut().enumerate() {
            *t = finite(
                || format!("{} total diffuse reflectance [{ch}]", self.kind),
                guard(|| Ok(self.model.total_diffuse_reflectance(ch)))?,
            )?;
        }
        rgb(py, total)
    }

    /// rd(r) -> float64 array (N, 3)
    ///
    /// The radial profile R_d(r) (1/mm²) at radii `r` (mm, float64 array (N,), each finite
    /// and >= 0), one column per channel; a float `r` gives shape (3,).
    fn rd<'py>(&self, py: Python<'py>, r: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let (radii, scalar) = read_f64s(r, "r")?;
        check_range("r", &radii, 0.0, f64::INFINITY, false)?;
        let rows = guard(|| {
            radii
                .iter()
                .map(|&r| {
                    let v = self.model.rd_rgb(r);
                    for (ch, x) in v.iter().enumerate() {
                        finite(|| format!("{} Rd[{ch}]({r} mm)", self.kind), *x)?;
                    }
                    Ok(v)
                })
                .collect::<PyResult<Vec<Rgb>>>()
        })?;
        if scalar {
            rgb(py, rows[0])
        } else {
            rgb_rows(py, &rows)
        }
    }

    /// sample_r(u, channel) -> float64 array (N,)
    ///
    /// Radii (mm) drawn with density proportional to 2πr R_d(r) of `channel` (0, 1, 2) from
    /// uniform numbers `u` in [0, 1) (float or float64 array (N,)).
    fn sample_r<'py>(
        &self,
        py: Python<'py>,
        u: &Bound<'py, PyAny>,
        channel: i64,
    ) -> PyResult<Bound<'py, PyAny>> {
        let ch = self::channel(channel)?;
        let (us, scalar) = read_f64s(u, "u")?;
        check_range("u", &us, 0.0, 1.0, true)?;
        let radii = guard(|| {
            us.iter()
                .map(|&u| {
                    finite(
                        || format!("{} sample_r({u})", self.kind),
                        self.model.sample_sr(ch, u),
                    )
                })
                .collect::<PyResult<Vec<f64>>>()
        })?;
        scalar_or_array(py, radii, scalar)
    }

    /// pdf_r(r, channel) -> float64 array (N,)
    ///
    /// The density (per mm of radius) with which `sample_r` returns `r` for `channel`;
    /// divide by 2πr for the density per unit area.
    fn pdf_r<'py>(
        &self,
        py: Python<'py>,
        r: &Bound<'py, PyAny>,
        channel: i64,
    ) -> PyResult<Bound<'py, PyAny>> {
        let ch = self::channel(channel)?;
        let (radii, scalar) = read_f64s(r, "r")?;
        check_range("r", &radii, 0.0, f64::INFINITY, false)?;
        let pdf = guard(|| {
            radii
                .iter()
                .map(|&r| {
                    finite(
                        || format!("{} pdf_r({r})", self.kind),
                        self.model.pdf_sr(ch, r),
                    )
                })
                .collect::<PyResult<Vec<f64>>>()
        })?;
        scalar_or_array(py, pdf, scalar)
    }

    fn __repr__(&self) -> String {
        match &self.spec {
            MediumSpec::Preset(p) => format!(
                "Model({:?}, preset={p:?}, eta={})",
                self.kind.name(),
                self.medium.eta()
            ),
            MediumSpec::Coefficients {
                sigma_a,
                sigma_s,
                g,
            } => format!(
                "Model({:?}, sigma_a={sigma_a:?}, sigma_s={sigma_s:?}, g={g}, eta={})",
                self.kind.name(),
                self.medium.eta()
            ),
        }
    }
}

fn scalar_or_array<'py>(py: Python<'py>, v: Vec<f64>, scalar: bool) -> PyResult<Bound<'py, PyAny>> {
    if scalar {
        Ok(PyFloat::new(py, v[0]).into_any())
    } else {
        let n = v.len();
        crate::arrays::new_array(py, v, &[n])
    }
}

/// presets() -> dict[str, dict]
///
/// The measured materials of Jensen et al. 2001 (Table 2), as `sss presets` lists them: by
/// name, a dict with `sigma_s_reduced` and `sigma_a` (1/mm, float64 (3,)), `eta` and
/// `published_rd` (the total diffuse reflectance printed in the paper).
#[pyfunction]
pub fn presets(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    use sss_bssrdf::presets::{PRESET_ETA, PRESETS};
    let out = PyDict::new(py);
    for p in &PRESETS {
        let d = PyDict::new(py);
        d.set_item("sigma_s_reduced", rgb(py, p.sigma_s_reduced)?)?;
        d.set_item("sigma_a", rgb(py, p.sigma_a)?)?;
        d.set_item("eta", PRESET_ETA)?;
        d.set_item("published_rd", rgb(py, p.published_rd)?)?;
        out.set_item(p.name, d)?;
    }
    Ok(out)
}

/// monte_carlo(*, preset=None, sigma_a=None, sigma_s=None, g=None, eta=None, r_max,
/// bins=100, photons=1000000, seed=1, progress=None) -> (r, rd, se)
///
/// The Monte Carlo photon random walk of `sss profile --model monte-carlo`: `bins` linear bins
/// over [0, r_max] mm, `photons` per channel. Returns the bin centres (float64 (N,)), R_d per
/// bin and channel (float64 (N, 3), 1/mm²) and its standard errors (float64 (N, 3)). Releases
/// the GIL; `progress(done, total)` is called with photons finished (total = 3 × photons;
/// `progress=True` draws a text bar on `sys.stderr`);
/// Ctrl-C stops it (KeyboardInterrupt), and so does an exception raised by `progress`.
#[pyfunction]
#[pyo3(signature = (*, preset=None, sigma_a=None, sigma_s=None, g=None, eta=None, r_max, bins=100, photons=1_000_000, seed=1, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn monte_carlo<'py>(
    py: Python<'py>,
    preset: Option<String>,
    sigma_a: Option<&Bound<'py, PyAny>>,
    sigma_s: Option<&Bound<'py, PyAny>>,
    g: Option<f64>,
    eta: Option<f64>,
    r_max: f64,
    bins: usize,
    photons: u64,
    seed: u64,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let spec = medium_spec(preset, sigma_a, sigma_s, g)?;
    let req = ProfileRequest {
        model: ProfileModel::MonteCarlo,
        medium: spec,
        eta,
        r_max,
        steps: bins,
        log: false,
        photons,
        seed,
    };
    check_budget(&req, sss_render::budget::default_budget()).map_err(|e| to_py(e.into()))?;
    let table = run_cancellable(
        py,
        crate::progress::callback(progress, "photons")?,
        |monitor| {
            monitor.set_total(req.photons.saturating_mul(3));
            compute(&req, &|n| monitor.set_done(n)).map_err(Error::from)
        },
    )?;
    let r: Vec<f64> = table.rows.iter().map(|row| row.r).collect();
    let rd: Vec<Rgb> = table.rows.iter().map(|row| row.rd).collect();
    let se: Vec<Rgb> = table
        .rows
        .iter()
        .map(|row| row.se.unwrap_or([0.0; 3]))
        .collect();
    let n = r.len();
    PyTuple::new(
        py,
        [
            crate::arrays::new_array(py, r, &[n])?,
            rgb_rows(py, &rd)?,
            rgb_rows(py, &se)?,
        ],
    )
}
