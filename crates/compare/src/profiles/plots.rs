//! The plots: each preset's profiles and errors, and error against cost.

use super::*;

pub(super) const CHANNEL_LONG: [&str; 3] = ["red", "green", "blue"];

pub(super) fn method_color(i: usize) -> [u8; 3] {
    PALETTE[1 + i % (PALETTE.len() - 1)]
}

/// One log-y panel per channel.
pub(super) fn panels<'a>(
    titles: &'a [String],
    series: &'a [Vec<Series>],
    y_label: &'a str,
) -> Vec<Panel<'a>> {
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

pub(super) fn plot_preset(
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
                    .zip(mc.rd_of(WalkPart::Multiple))
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

pub(super) fn plot_error_vs_cost(
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
    crate::output::plot_with_hover(
        &ctx.config.out.join("error_vs_cost.png"),
        "Relative L2 error against cost (one point per preset and channel)",
        ("ns per Rd evaluation", "relative L2 error vs Monte Carlo"),
        &series,
        (true, true),
    )
}
