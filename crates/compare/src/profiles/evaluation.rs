//! Evaluating a method on one preset: its bins and totals against the Monte Carlo reference,
//! and its cost per evaluation and per build.

use super::*;

/// Calls per timing round of `rd`.
pub(super) const TIMING_CALLS: usize = 100_000;

/// The comparison of one (preset, method, channel).
#[derive(Clone, Debug)]
pub struct Evaluation {
    /// Preset name.
    pub preset: &'static str,
    /// Method name.
    pub method: String,
    /// Channel 0..3.
    pub channel: usize,
    /// The Monte Carlo part the method is measured against.
    pub part: WalkPart,
    /// The method's area averages over the reference bins (1/mm²).
    pub bin_avg: Vec<f64>,
    /// Relative L2 error of the energy per bin.
    pub rel_l2: Option<f64>,
    /// Largest relative error over well-resolved bins.
    pub max_rel: Option<f64>,
    /// The method's total diffuse reflectance.
    pub total_model: f64,
    /// Monte Carlo total of `part`.
    pub total_mc: f64,
    /// Standard error of the full Monte Carlo total (an estimate for the multiple-scattering
    /// part too).
    pub total_mc_se: f64,
    /// ns per `rd(ch, r)` call.
    pub ns_per_eval: f64,
    /// ns per `rd_rgb(r)` call (all three channels).
    pub ns_per_rgb: f64,
    /// Seconds of a cold build of the method for this medium.
    pub build_seconds: f64,
}

impl Evaluation {
    /// (model − mc)/mc of the totals.
    pub fn total_rel_error(&self) -> Option<f64> {
        (self.total_mc > 0.0).then(|| (self.total_model - self.total_mc) / self.total_mc)
    }
}

pub(super) fn finite_or_zero(v: f64) -> f64 {
    if v.is_finite() { v } else { 0.0 }
}

/// Evaluates every method on one preset.
pub fn evaluate(
    reference: &PresetReference,
    methods: &[Box<dyn ProfileMethod>],
) -> Vec<Evaluation> {
    let mut out = Vec::new();
    for method in methods {
        let build_seconds = method.cold_build_seconds(&reference.medium);
        let model = method.build(&reference.medium);
        let all_centers: Vec<f64> = reference
            .channels
            .iter()
            .flat_map(|c| c.centers())
            .collect();
        let ns_per_rgb = ns_per_call(&all_centers, TIMING_CALLS / 3, |r| model.rd_rgb(r));
        for (ch, mc) in reference.channels.iter().enumerate() {
            let scale = reference.medium.reduced_mean_free_path(ch);
            let part = method.reference_part();
            let reference_rd = mc.rd_of(part);
            let bin_avg = bin_averages(&mc.edges, &|r| model.rd(ch, r), scale);
            let ns_per_eval = ns_per_call(&mc.centers(), TIMING_CALLS, |r| model.rd(ch, r));
            out.push(Evaluation {
                preset: reference.preset.name,
                method: method.name(),
                channel: ch,
                part,
                rel_l2: rel_l2_error(&mc.areas(), &bin_avg, &reference_rd),
                max_rel: max_rel_error(&bin_avg, &reference_rd, &mc.se),
                total_model: finite_or_zero(model.total_diffuse_reflectance(ch)),
                total_mc: mc.total_of(part),
                total_mc_se: mc.total_se,
                ns_per_eval,
                ns_per_rgb,
                build_seconds,
                bin_avg,
            });
        }
    }
    out
}
