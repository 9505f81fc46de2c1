//! Experiment "profiles": every radial-profile method against the Monte Carlo reference.
//!
//! For each preset and channel, each registered [`ProfileMethod`] is built, its area averages
//! over the reference's bins are compared with the Monte Carlo bins ([`metrics`]), its
//! total diffuse reflectance with the Monte Carlo total, and its evaluation cost is timed.
//! Writes `profiles.csv`, `profile_<preset>.png`, `error_<preset>.png` and
//! `error_vs_cost.png`, and returns the report section. Where the shared MCML profiles exist
//! ([`mcml`]), every model is also compared with MCML, an independent Monte Carlo code
//! (Wang, Jacques & Zheng 1995), in a subsection of its own and `mcml.csv`.
//!
//! To add a method (e.g. a fitted kernel from a later crate), implement [`ProfileMethod`] and
//! add it to [`methods`].

mod evaluation;
mod mcml;
mod metrics;
mod plots;
mod registry;
mod report;
#[cfg(test)]
mod tests;

use super::output::{Csv, csv_num, csv_text, md_num, md_pct, md_table};
use super::walk_reference::{CHANNEL_NAMES, PresetReference, WalkPart};
use super::{Context, Error, Experiment, Section};
use evaluation::*;
use metrics::{
    MAX_REL_SE, bin_averages, max_rel_error, mean, median, ns_per_call, rel_errors, rel_l2_error,
};
use plots::*;
pub use registry::*;
use report::*;
use sss_bssrdf::mc_table::McTable;
use sss_bssrdf::photon_beam_diffusion::PbdTable;
use sss_bssrdf::{Bssrdf, Medium, ModelKind, make_model};
use sss_plot::{ErrorStyle, PALETTE, Panel, Series, SeriesStyle, panel_plot};
use std::fmt::Write as _;
use std::hint::black_box;
use std::time::Instant;

/// The experiment (registered in [`super::experiments`]).
pub struct ProfileComparison;

impl Experiment for ProfileComparison {
    fn name(&self) -> &'static str {
        "profiles"
    }

    fn run(&self, ctx: &Context<'_>) -> Result<Section, Error> {
        let methods = methods();
        let method_names: Vec<String> = methods.iter().map(|m| m.name()).collect();
        let bar = sss_util::progress::bar(ctx.references.len() as u64, "presets");
        bar.set_message("profiles");
        let mut evals = Vec::new();
        let mut body = String::new();
        for reference in ctx.references {
            let e = evaluate(reference, &methods);
            let mine: Vec<&Evaluation> = e.iter().collect();
            plot_preset(ctx, reference, &mine, &method_names)?;
            body.push_str(&preset_md(reference, &mine, &method_names));
            (ctx.log)(&format!("{}: models evaluated", reference.preset.name));
            evals.extend(e);
            bar.inc(1);
        }
        bar.finish_and_clear();
        results_csv(&evals).write(&ctx.config.out.join("profiles.csv"))?;
        plot_error_vs_cost(ctx, &evals, &method_names)?;
        let mcml = mcml::run(&mcml::reference_dir(), &ctx.config.out)?;
        (ctx.log)("profiles: compared with MCML");
        body.push_str(&mcml.body);
        let mut summary = String::new();
        let _ = writeln!(
            summary,
            "Error against run time: medians over presets and channels (details per preset \
             below; every number per (preset, model, channel) is in `profiles.csv`). The mean, \
             last, is dominated by the worst channels (strongly absorbing ones such as ketchup's \
             green and blue, where the scattered light is almost nothing) and is shown only for \
             that.\n"
        );
        summary.push_str(&summary_md(&evals, &method_names));
        let _ = writeln!(
            summary,
            "\nMedian rel. L2 error per material (over its three channels):\n"
        );
        summary.push_str(&per_material_md(&evals, &method_names));
        let _ = writeln!(
            summary,
            "\n![error vs cost](error_vs_cost.png)\n\n\
             - *rel. L2 error*: ‖A·(model − MC)‖ / ‖A·MC‖ over the radial bins, A the annulus area \
             (energy per bin); the model's values are its area averages over each bin.\n\
             - *max rel. error*: largest |model − MC| / MC over bins whose MC relative standard \
             error is below {:.0} %.\n\
             - *total error*: |model total − MC total| / MC total (MC counts all radii).\n\
             - *against MC*: the part of the Monte Carlo transport a model is measured against. \
             The standard and better dipoles are diffusion models of multiple scattering, so \
             they are compared with the Monte Carlo multiple-scattering part (`multiple`: \
             everything minus the photons that escaped after exactly one collision). Photon beam \
             diffusion models single and multiple scattering, normalized diffusion (`burley`) is \
             fitted to profiles of all orders, and the directional dipole's source has strength \
             1 rather than α′ (Frisvad et al. 2014), so it stands for all scattered light; \
             `mc-table` is the random walk itself, tabulated: these four are compared with \
             everything (`all`). As published the directional dipole \
             integrates to more than the transport gives at high albedo (≈ 1.34 for α′ → 1 at \
             η = 1, see `directional_dipole.rs`); that excess is the model's, and its total \
             diffuse reflectance is clamped to 1. Standard errors are those of the full tally.\n\
             - *ns / eval*: wall-clock time of one `rd(ch, r)` call at the bin centres, best of 3 \
             rounds of {TIMING_CALLS}; *ns / RGB eval*: one `rd_rgb(r)`.\n\
             - *cold build*: constructing the model without process-wide caches (for `pbd` this \
             includes its albedo × radius table, for `burley` the g = 0 table its surface albedo \
             comes from, for `mc-table` reading its embedded tallies and solving the splines of \
             the two η tables it blends).",
            100.0 * MAX_REL_SE
        );
        let _ = write!(summary, "\n{}", mcml.summary);
        Ok(Section {
            title: "Models against the Monte Carlo reference".into(),
            summary,
            body,
        })
    }
}
