//! One model against one case ([`Comparison`]) and every model against every case.

use super::*;

/// One model against one case.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// Case name.
    pub case: String,
    /// Model name.
    pub model: String,
    /// What the model models: [`WalkPart::Multiple`] for the standard and better dipoles
    /// (MCML always has every order).
    pub part: WalkPart,
    /// The case's η.
    pub eta: f64,
    /// Anisotropy.
    pub g: f64,
    /// Reduced albedo.
    pub reduced_albedo: f64,
    /// Reduced mean free path (mm).
    pub mfp: f64,
    /// Over [`NEAR`].
    pub near: Option<Worst>,
    /// Median |model − MCML|/MCML over [`NEAR`].
    pub near_median: Option<f64>,
    /// Over [`NEAR`].1–[`FAR_END`].
    pub far: Option<Worst>,
    /// The model's total diffuse reflectance.
    pub total_model: f64,
    /// MCML's total diffuse reflectance per unit power entering.
    pub total_mcml: f64,
    /// Standard error of `total_mcml`.
    pub total_mcml_se: f64,
}

impl Comparison {
    /// (model total − MCML total)/MCML total.
    pub fn total_rel_error(&self) -> Option<f64> {
        let e = self.total_model / self.total_mcml - 1.0;
        e.is_finite().then_some(e)
    }

    pub(super) fn bins(&self) -> usize {
        self.near.map_or(0, |w| w.bins) + self.far.map_or(0, |w| w.bins)
    }

    pub(super) fn forgiven(&self) -> usize {
        self.near.map_or(0, |w| w.forgiven) + self.far.map_or(0, |w| w.forgiven)
    }
}

/// `model` (named `name`, modelling `part`) against `case`.
pub fn compare(case: &Case, name: &str, part: WalkPart, model: &dyn Bssrdf) -> Comparison {
    let rows = case.rows(model);
    let total_model = model.total_diffuse_reflectance(0);
    Comparison {
        case: case.name.clone(),
        model: name.to_string(),
        part,
        eta: case.medium.eta(),
        g: case.medium.g(),
        reduced_albedo: case.medium.reduced_albedo(0),
        mfp: case.medium.reduced_mean_free_path(0),
        near: worst(&rows, Range::Near),
        near_median: median_abs_error(&rows, Range::Near),
        far: worst(&rows, Range::Far),
        total_model: if total_model.is_finite() {
            total_model
        } else {
            0.0
        },
        total_mcml: case.total / case.entering(),
        total_mcml_se: case.total_se / case.entering(),
    }
}

/// Every model of [`ModelKind::ALL`] against every case (cases in order, models in order).
pub fn compare_all(cases: &[Case]) -> Vec<Comparison> {
    let jobs: Vec<(&Case, ModelKind)> = cases
        .iter()
        .flat_map(|c| ModelKind::ALL.into_iter().map(move |k| (c, k)))
        .collect();
    jobs.into_par_iter()
        .map(|(case, kind)| {
            let method = ModelMethod(kind);
            let model = make_model(kind, &case.medium);
            compare(
                case,
                &method.name(),
                method.reference_part(),
                model.as_ref(),
            )
        })
        .collect()
}
