//! The experiment's outputs in words and tables: `profiles.csv` and the report section's
//! summary, per-material and per-preset tables.

use super::*;

/// The columns of `profiles.csv` (documented in `docs/compare.md`).
pub const COLUMNS: [&str; 11] = [
    "preset",
    "model",
    "channel",
    "rel_l2_error",
    "max_rel_error",
    "total_model",
    "total_mc",
    "total_mc_se",
    "ns_per_eval",
    "build_seconds",
    "mc_part",
];

/// `profiles.csv`: one row per (preset, model, channel).
pub fn results_csv(evals: &[Evaluation]) -> Csv {
    let mut csv = Csv::new(COLUMNS);
    for e in evals {
        csv.row([
            csv_text(e.preset),
            csv_text(&e.method),
            csv_text(CHANNEL_NAMES[e.channel]),
            csv_num(e.rel_l2),
            csv_num(e.max_rel),
            csv_num(Some(e.total_model)),
            csv_num(Some(e.total_mc)),
            csv_num(Some(e.total_mc_se)),
            csv_num(Some(e.ns_per_eval)),
            csv_num(Some(e.build_seconds)),
            csv_text(e.part.name()),
        ]);
    }
    csv
}

pub(super) fn summary_md(evals: &[Evaluation], method_names: &[String]) -> String {
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
pub(super) fn per_material_md(evals: &[Evaluation], method_names: &[String]) -> String {
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

pub(super) fn preset_md(
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
                md_num(Some(c.total_of(WalkPart::Multiple)), 4),
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
