//! Experiment "profiles": every radial-profile method against the Monte Carlo reference.
//!
//! For each preset and channel, each registered [`ProfileMethod`] is built, its area averages
//! over the reference's bins are compared with the Monte Carlo bins ([`super::metrics`]), its
//! total diffuse reflectance with the Monte Carlo total, and its evaluation cost is timed.
//! Writes `profiles.csv`, `profile_<preset>.png`, `error_<preset>.png` and
//! `error_vs_cost.png`, and returns the report section. Where the shared MCML profiles exist
//! ([`super::mcml`]), every model is also compared with MCML, an independent Monte Carlo code
//! (Wang, Jacques & Zheng 1995), in a subsection of its own and `mcml.csv`.
//!
//! To add a method (e.g. a fitted kernel from a later crate), implement [`ProfileMethod`] and
//! add it to [`methods`].

use super::metrics::{
    MAX_REL_SE, bin_averages, max_rel_error, ns_per_call, rel_errors, rel_l2_error,
};
use super::output::{csv_num, md_num, md_pct, md_table, write_atomic};
use super::reference::{CHANNEL_NAMES, McPart, PresetReference};
use super::{Context, Error, Experiment, Section, mcml};
use sss_bssrdf::mc_table::McTable;
use sss_bssrdf::photon_beam_diffusion::PbdTable;
use sss_bssrdf::{Bssrdf, Medium, ModelKind, make_model};
use sss_plot::{ErrorStyle, PALETTE, Panel, Series, SeriesStyle, panel_plot};
use std::fmt::Write as _;
use std::hint::black_box;
use std::time::Instant;

/// Calls per timing round of `rd`.
const TIMING_CALLS: usize = 100_000;

/// A method that produces a radial profile R_d(r) for a medium.
pub trait ProfileMethod: Sync {
    /// Name in the report and CSV.
    fn name(&self) -> String;
    /// The evaluator for `medium` (may use process-wide caches).
    fn build(&self, medium: &Medium) -> Box<dyn Bssrdf>;
    /// Seconds a build takes from scratch, without process-wide caches (best of three).
    fn cold_build_seconds(&self, medium: &Medium) -> f64;
    /// The part of the Monte Carlo transport the method models, and is measured against.
    fn reference_part(&self) -> McPart;
}

/// One of the `sss_bssrdf` models.
pub struct ModelMethod(pub ModelKind);

impl ProfileMethod for ModelMethod {
    fn name(&self) -> String {
        self.0.name().to_string()
    }

    fn build(&self, medium: &Medium) -> Box<dyn Bssrdf> {
        make_model(self.0, medium)
    }

    /// Photon beam diffusion models single and multiple scattering, normalized diffusion
    /// (Christensen & Burley 2015) is fitted to Monte Carlo profiles of all scattering orders,
    /// and `mc-table` is the Monte Carlo transport itself, tabulated.
    /// The directional dipole (Frisvad et al. 2014) puts a source of strength 1, not α′, at
    /// the ray's first scattering event, so it stands for all scattered light and is measured
    /// against the full tally too. The standard and better dipoles model multiple scattering
    /// only.
    fn reference_part(&self) -> McPart {
        match self.0 {
            ModelKind::PhotonBeamDiffusion
            | ModelKind::Burley
            | ModelKind::DirectionalDipole
            | ModelKind::McTable => McPart::All,
            ModelKind::StandardDipole | ModelKind::BetterDipole => McPart::Multiple,
        }
    }

    fn cold_build_seconds(&self, medium: &Medium) -> f64 {
        // Warm the shared caches, then time a build that redoes the cached part explicitly:
        // photon beam diffusion shares its table per (g, η); that table is its real cost.
        // Normalized diffusion takes its surface albedo from the table of (0, η). `mc-table`
        // reads its embedded tallies and solves their splines once per process; a cold build
        // redoes that for the two η tables it blends.
        black_box(self.build(medium));
        (0..3)
            .map(|_| {
                let t0 = Instant::now();
                match self.0 {
                    ModelKind::PhotonBeamDiffusion => {
                        black_box(PbdTable::new(medium.g(), medium.eta()));
                    }
                    ModelKind::Burley => {
                        black_box(PbdTable::new(0.0, medium.eta()));
                    }
                    ModelKind::McTable => {
                        black_box(McTable::from_embedded_uncached(medium.eta()));
                    }
                    _ => {}
                }
                black_box(self.build(medium));
                t0.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    }
}

/// Every method the experiment compares, in report order.
pub fn methods() -> Vec<Box<dyn ProfileMethod>> {
    ModelKind::ALL
        .into_iter()
        .map(|k| Box::new(ModelMethod(k)) as Box<dyn ProfileMethod>)
        .collect()
}

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
    pub part: McPart,
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

fn finite_or_zero(v: f64) -> f64 {
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

/// The header of `profiles.csv` (documented in `docs/compare.md`).
pub const CSV_HEADER: &str = "preset,model,channel,rel_l2_error,max_rel_error,total_model,total_mc,total_mc_se,ns_per_eval,build_seconds,mc_part";

/// `profiles.csv`: one row per (preset, model, channel).
pub fn results_csv(evals: &[Evaluation]) -> String {
    let mut s = String::from(CSV_HEADER);
    s.push('\n');
    for e in evals {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{}",
            e.preset,
            e.method,
            CHANNEL_NAMES[e.channel],
            csv_num(e.rel_l2),
            csv_num(e.max_rel),
            csv_num(Some(e.total_model)),
            csv_num(Some(e.total_mc)),
            csv_num(Some(e.total_mc_se)),
            csv_num(Some(e.ns_per_eval)),
            csv_num(Some(e.build_seconds)),
            e.part.name(),
        );
    }
    s
}

const CHANNEL_LONG: [&str; 3] = ["red", "green", "blue"];

fn method_color(i: usize) -> [u8; 3] {
    PALETTE[1 + i % (PALETTE.len() - 1)]
}

/// One log-y panel per channel.
fn panels<'a>(titles: &'a [String], series: &'a [Vec<Series>], y_label: &'a str) -> Vec<Panel<'a>> {
    (0..3)
        .map(|ch| Panel {
            title: &titles[ch],
            x_label: "r (mm)",
            y_label,
            series: &series[ch],
            log_x: false,
            log_y: true,
        })
        .collect()
}

fn plot_preset(
    ctx: &Context<'_>,
    reference: &PresetReference,
    evals: &[&Evaluation],
    method_names: &[String],
) -> Result<(), Error> {
    let name = reference.preset.name;
    let mut profile_series: Vec<Vec<Series>> = Vec::new();
    let mut error_series: Vec<Vec<Series>> = Vec::new();
    for (ch, mc) in reference.channels.iter().enumerate() {
        let centers = mc.centers();
        let mut ps = vec![
            Series::line(
                "Monte Carlo, all ± SE",
                centers.iter().copied().zip(mc.rd.iter().copied()).collect(),
            )
            .with_color(PALETTE[0])
            .with_errors(mc.se.clone(), ErrorStyle::Band),
            Series::line(
                "Monte Carlo, multiple scattering",
                centers
                    .iter()
                    .copied()
                    .zip(mc.rd_of(McPart::Multiple))
                    .collect(),
            )
            .with_color([110, 110, 110])
            .with_style(SeriesStyle::Dashed),
        ];
        let rel_se: Vec<(f64, f64)> = centers
            .iter()
            .zip(mc.rd.iter().zip(&mc.se))
            .filter(|(_, (r, _))| **r > 0.0)
            .map(|(x, (r, s))| (*x, s / r))
            .collect();
        let mut es = vec![
            Series::line("MC relative SE", rel_se)
                .with_color([120, 120, 120])
                .with_style(SeriesStyle::Dashed),
        ];
        for (i, m) in method_names.iter().enumerate() {
            let Some(e) = evals.iter().find(|e| &e.method == m && e.channel == ch) else {
                continue;
            };
            ps.push(
                Series::line(
                    m.clone(),
                    centers
                        .iter()
                        .copied()
                        .zip(e.bin_avg.iter().copied())
                        .collect(),
                )
                .with_color(method_color(i)),
            );
            let errs = rel_errors(&e.bin_avg, &mc.rd_of(e.part))
                .into_iter()
                .zip(&centers)
                .filter_map(|(err, x)| err.map(|v| (*x, v.abs())))
                .collect();
            es.push(Series::line(m.clone(), errs).with_color(method_color(i)));
        }
        profile_series.push(ps);
        error_series.push(es);
    }
    let titles: Vec<String> = (0..3)
        .map(|ch| {
            format!(
                "{} (r_max {:.3} mm)",
                CHANNEL_LONG[ch], reference.channels[ch].r_max
            )
        })
        .collect();
    let profile_path = ctx.config.out.join(format!("profile_{name}.png"));
    panel_plot(
        &profile_path,
        &format!("{name}: Rd(r), bin averages, against Monte Carlo"),
        &panels(&titles, &profile_series, "Rd (1/mm²)"),
        3,
    )
    .map_err(|e| Error(e.to_string()))?;
    let error_path = ctx.config.out.join(format!("error_{name}.png"));
    panel_plot(
        &error_path,
        &format!("{name}: |model − MC| / MC per bin"),
        &panels(&titles, &error_series, "relative error"),
        3,
    )
    .map_err(|e| Error(e.to_string()))?;
    Ok(())
}

fn plot_error_vs_cost(
    ctx: &Context<'_>,
    evals: &[Evaluation],
    method_names: &[String],
) -> Result<(), Error> {
    let series: Vec<Series> = method_names
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let pts = evals
                .iter()
                .filter(|e| &e.method == m)
                .filter_map(|e| e.rel_l2.map(|err| (e.ns_per_eval, err)))
                .collect();
            Series::line(m.clone(), pts)
                .with_color(method_color(i))
                .with_style(SeriesStyle::Markers)
        })
        .collect();
    sss_plot::line_plot(
        &ctx.config.out.join("error_vs_cost.png"),
        "Relative L2 error against cost (one point per preset and channel)",
        "ns per Rd evaluation",
        "relative L2 error vs Monte Carlo",
        &series,
        true,
        true,
    )
    .map_err(|e| Error(e.to_string()))
}

fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn median(values: impl Iterator<Item = f64>) -> Option<f64> {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

fn summary_md(evals: &[Evaluation], method_names: &[String]) -> String {
    let rows: Vec<Vec<String>> = method_names
        .iter()
        .map(|m| {
            let of = || evals.iter().filter(move |e| &e.method == m);
            vec![
                format!("`{m}`"),
                md_pct(median(of().filter_map(|e| e.rel_l2))),
                md_pct(median(of().filter_map(|e| e.max_rel))),
                md_pct(median(
                    of().filter_map(|e| e.total_rel_error().map(f64::abs)),
                )),
                md_num(median(of().map(|e| e.ns_per_eval)), 3),
                md_num(median(of().map(|e| e.ns_per_rgb)), 3),
                md_num(median(of().map(|e| e.build_seconds * 1e3)), 3),
                md_pct(mean(of().filter_map(|e| e.rel_l2))),
            ]
        })
        .collect();
    md_table(
        &[
            "model",
            "median rel. L2 error",
            "median max rel. error",
            "median abs. total error",
            "ns / eval",
            "ns / RGB eval",
            "cold build (ms)",
            "mean rel. L2 error (worst channels dominate)",
        ],
        &rows,
    )
}

/// Median relative L2 error per model (rows) and material (columns), over the channels.
fn per_material_md(evals: &[Evaluation], method_names: &[String]) -> String {
    let mut presets: Vec<&str> = Vec::new();
    for e in evals {
        if !presets.contains(&e.preset) {
            presets.push(e.preset);
        }
    }
    let rows: Vec<Vec<String>> = method_names
        .iter()
        .map(|m| {
            let mut row = vec![format!("`{m}`")];
            for p in &presets {
                let of = evals.iter().filter(|e| &e.method == m && e.preset == *p);
                row.push(md_pct(median(of.filter_map(|e| e.rel_l2))));
            }
            row
        })
        .collect();
    let mut header = vec!["model".to_string()];
    header.extend(presets.iter().map(|p| p.to_string()));
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    md_table(&header, &rows)
}

fn preset_md(
    reference: &PresetReference,
    evals: &[&Evaluation],
    method_names: &[String],
) -> String {
    let name = reference.preset.name;
    let mut s = String::new();
    let _ = writeln!(s, "### {name}\n");
    let mc_rows: Vec<Vec<String>> = (0..3)
        .map(|ch| {
            let c = &reference.channels[ch];
            vec![
                CHANNEL_LONG[ch].to_string(),
                md_num(Some(c.r_max), 4),
                format!(
                    "{} ± {}",
                    md_num(Some(c.total), 4),
                    md_num(Some(c.total_se), 2)
                ),
                md_num(Some(c.total_of(McPart::Multiple)), 4),
                md_num(Some(reference.preset.published_rd[ch]), 2),
                c.capped.to_string(),
                c.seconds.map_or("cached".into(), |t| format!("{t:.1}")),
            ]
        })
        .collect();
    s.push_str(&md_table(
        &[
            "channel",
            "r_max (mm)",
            "MC total Rd ± SE",
            "MC multiple scattering",
            "published Rd",
            "capped photons",
            "MC seconds",
        ],
        &mc_rows,
    ));
    s.push('\n');
    let mut rows = Vec::new();
    for m in method_names {
        for (ch, channel_name) in CHANNEL_LONG.iter().enumerate() {
            let Some(e) = evals.iter().find(|e| &e.method == m && e.channel == ch) else {
                continue;
            };
            let z = (e.total_mc_se > 0.0).then(|| (e.total_model - e.total_mc) / e.total_mc_se);
            rows.push(vec![
                format!("`{m}`"),
                channel_name.to_string(),
                e.part.name().to_string(),
                md_pct(e.rel_l2),
                md_pct(e.max_rel),
                md_num(Some(e.total_model), 4),
                md_pct(e.total_rel_error()),
                md_num(z, 3),
                md_num(Some(e.ns_per_eval), 3),
            ]);
        }
    }
    s.push_str(&md_table(
        &[
            "model",
            "channel",
            "against MC",
            "rel. L2 error",
            "max rel. error",
            "total Rd",
            "total vs MC",
            "(total − MC)/SE",
            "ns / eval",
        ],
        &rows,
    ));
    let _ = writeln!(
        s,
        "\n![profiles](profile_{name}.png)\n\n![errors](error_{name}.png)\n"
    );
    s
}

/// The experiment (registered in [`super::experiments`]).
pub struct ProfileComparison;

impl Experiment for ProfileComparison {
    fn name(&self) -> &'static str {
        "profiles"
    }

    fn run(&self, ctx: &Context<'_>) -> Result<Section, Error> {
        let methods = methods();
        let method_names: Vec<String> = methods.iter().map(|m| m.name()).collect();
        let bar = sss_cli::progress::bar(ctx.references.len() as u64, "presets");
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
        write_atomic(
            &ctx.config.out.join("profiles.csv"),
            results_csv(&evals).as_bytes(),
        )?;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_has_the_documented_columns() {
        let e = eval("skin1", "pbd", 2, 0.5);
        let csv = results_csv(&[e]);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[0], CSV_HEADER);
        assert_eq!(
            lines[1],
            "skin1,pbd,b,5e-1,,2.5e-1,1.25e-1,1e-3,1.25e1,5e-2,all"
        );
        assert_eq!(lines[0].split(',').count(), lines[1].split(',').count());
    }

    fn eval(preset: &'static str, method: &str, channel: usize, rel_l2: f64) -> Evaluation {
        Evaluation {
            preset,
            method: method.into(),
            channel,
            part: McPart::All,
            bin_avg: vec![],
            rel_l2: Some(rel_l2),
            max_rel: None,
            total_model: 0.25,
            total_mc: 0.125,
            total_mc_se: 0.001,
            ns_per_eval: 12.5,
            ns_per_rgb: 30.0,
            build_seconds: 0.05,
        }
    }

    #[test]
    fn summary_leads_with_medians_and_one_bad_channel_cannot_dominate_it() {
        // One material with a near-black channel whose relative error is enormous: the
        // median row and the per-material table show the typical error.
        let evals = vec![
            eval("skin1", "pbd", 0, 0.05),
            eval("skin1", "pbd", 1, 0.07),
            eval("skin1", "pbd", 2, 0.06),
            eval("ketchup", "pbd", 0, 0.04),
            eval("ketchup", "pbd", 1, 800.0),
            eval("ketchup", "pbd", 2, 0.08),
        ];
        let names = vec!["pbd".to_string()];
        let md = summary_md(&evals, &names);
        let header = md.lines().next().unwrap();
        assert!(
            header.starts_with("| model | median rel. L2 error |"),
            "{header}"
        );
        let row = md.lines().find(|l| l.starts_with("| `pbd`")).unwrap();
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        // Median of {0.04, 0.05, 0.06, 0.07, 0.08, 800} = 6.5 %; the mean is 13336 %.
        assert_eq!(cells[2], md_pct(Some(0.065)));
        assert_eq!(
            cells[8],
            md_pct(Some((0.05 + 0.07 + 0.06 + 0.04 + 800.0 + 0.08) / 6.0))
        );
        let per = per_material_md(&evals, &names);
        assert!(
            per.lines().next().unwrap().contains("| skin1 | ketchup |"),
            "{per}"
        );
        let row = per.lines().find(|l| l.starts_with("| `pbd`")).unwrap();
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        assert_eq!(cells[2], md_pct(Some(0.06)));
        assert_eq!(cells[3], md_pct(Some(0.08)));
    }

    #[test]
    fn the_directional_dipole_is_measured_against_the_full_tally() {
        assert!(matches!(
            ModelMethod(ModelKind::DirectionalDipole).reference_part(),
            McPart::All
        ));
        assert!(matches!(
            ModelMethod(ModelKind::BetterDipole).reference_part(),
            McPart::Multiple
        ));
        assert!(matches!(
            ModelMethod(ModelKind::Burley).reference_part(),
            McPart::All
        ));
        assert!(matches!(
            ModelMethod(ModelKind::McTable).reference_part(),
            McPart::All
        ));
    }

    #[test]
    fn statistics() {
        assert_eq!(mean([1.0, f64::NAN, 3.0].into_iter()), Some(2.0));
        assert_eq!(mean(std::iter::empty()), None);
        assert_eq!(median([3.0, 1.0, 2.0].into_iter()), Some(2.0));
        assert_eq!(median([4.0, 1.0, 2.0, 3.0].into_iter()), Some(2.5));
    }
}
