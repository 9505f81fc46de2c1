//! `truth.csv` and the report section: per case, every model's floor against real light
//! transport, the fast methods' error against time, and when `volpath` itself reaches the same
//! error.

use super::*;

/// What the report needs of one case.
pub(crate) struct CaseResult {
    pub case: String,
    pub truth: Truth,
    pub runs: Vec<TruthRun>,
    pub crossover: Option<Crossover>,
    pub unsupported: Vec<String>,
}

/// The columns of `truth.csv` (documented in `docs/compare.md`).
pub const COLUMNS: [&str; 21] = [
    "case",
    "scene",
    "medium",
    "light",
    "renderer",
    "method",
    "model",
    "param",
    "value",
    "threads",
    "seconds",
    "shading_s",
    "mean_ratio_r",
    "mean_ratio_g",
    "mean_ratio_b",
    "rel_rmse",
    "rel_rmse_floor",
    "reference_noise",
    "reference_spp",
    "volpath_same_error_s",
    "warnings",
];

/// `truth.csv` of every case's runs.
pub(crate) fn truth_csv(results: &[CaseResult]) -> Csv {
    let mut csv = Csv::new(COLUMNS);
    for c in results {
        for r in &c.runs {
            let same = c.crossover.and_then(|x| x.seconds_for(r.score.rel_rmse));
            csv.row([
                csv_text(&r.case),
                csv_text(r.scene),
                csv_text(r.medium),
                csv_text(r.light),
                csv_text(r.renderer),
                csv_text(r.method),
                csv_text(r.model),
                csv_text(r.param),
                csv_num(Some(r.value)),
                r.threads.to_string(),
                csv_num(Some(r.seconds)),
                csv_num(Some(r.shading)),
                csv_num(Some(r.score.mean_ratio[0])),
                csv_num(Some(r.score.mean_ratio[1])),
                csv_num(Some(r.score.mean_ratio[2])),
                csv_num(Some(r.score.rel_rmse)),
                csv_num(r.floor),
                csv_num(Some(c.truth.noise())),
                c.truth.spp.to_string(),
                csv_num(same),
                r.warnings.to_string(),
            ]);
        }
    }
    csv
}

fn ratios(r: &TruthRun) -> String {
    r.score
        .mean_ratio
        .iter()
        .map(|v| md_num(Some(*v), 3))
        .collect::<Vec<_>>()
        .join(" / ")
}

/// The report section of every case's results; `skipped` lists cases not run (a missing mesh).
pub(crate) fn section(
    results: &[CaseResult],
    skipped: &[String],
    peers: &[String],
    threads: usize,
) -> Section {
    let mut summary = String::from(
        "Every BSSRDF model against real light transport: `volpath`, volumetric path tracing \
         of the medium in the mesh (checked against Mitsuba 3 and MCML), rendered until its own \
         relative noise is small; every model under `exact` (its sum) and `pathtrace` (the \
         integral it discretises), the fast methods with `mc-table` over their sweeps \
         (`dual-tree-fmm` with `mc-table+albedo+local` too: each point's own ball; and \
         `mc-table+albedo+local+bounce+unscattered`, the same with one bounce of the light \
         the surfaces trade, `--bounces 1`, and the light refracted through the objects \
         without a collision, `unscattered = true`), and \
         `volpath` at fewer paths, all scored \
         over the pixels inside the silhouette (a pixel and its eight neighbours covered) with \
         the reference's noise removed. *volpath to the same \
         error*: the total seconds `volpath` takes to reach that relative RMSE, from its own \
         error-against-time fit (error ∝ 1/√shading time).\n\n",
    );
    let mut rows = Vec::new();
    for c in results {
        let names = ModelKind::ALL
            .iter()
            .map(|m| m.name())
            .chain(runs::VARIANTS);
        for model in names {
            let find = |method: &str| {
                c.runs
                    .iter()
                    .find(|r| r.method == method && r.model == model)
            };
            let Some(exact) = find("exact") else {
                continue;
            };
            // A model `pathtrace` refuses (each point's own ball): its means from `exact`, no
            // floor.
            let pt = find("pathtrace");
            let floor = pt.map(|pt| pt.floor.unwrap_or(pt.score.rel_rmse));
            rows.push(vec![
                c.case.clone(),
                model.to_string(),
                match pt {
                    Some(pt) => ratios(pt),
                    None => format!("{} (exact)", ratios(exact)),
                },
                md_pct(floor),
                if exact.warnings > 0 {
                    format!("{} ⚠", md_pct(Some(exact.score.rel_rmse)))
                } else {
                    md_pct(Some(exact.score.rel_rmse))
                },
                md_num(Some(exact.seconds), 3),
                md_num(
                    floor.and_then(|f| c.crossover.and_then(|x| x.seconds_for(f))),
                    3,
                ),
            ]);
        }
    }
    summary.push_str(&md_table(
        &[
            "case",
            "model",
            "mean / truth (R / G / B)",
            "floor: rel. RMSE",
            "exact's rel. RMSE",
            "exact s",
            "volpath to the floor, s",
        ],
        &rows,
    ));
    let _ = write!(
        summary,
        "\n*floor*: `pathtrace` at {PATHTRACE_SPP} samples with its own noise removed (the \
         model's integral, nothing discretised); *exact's*: its sum at the comparison's spacing, \
         at most {EXACT_SAMPLES} samples per object (⚠: the cap bound, samples coarser than \
         asked).\n"
    );
    let refs: Vec<Vec<String>> = results
        .iter()
        .map(|c| {
            vec![
                c.case.clone(),
                c.truth.pixels.len().to_string(),
                c.truth.spp.to_string(),
                md_pct(Some(c.truth.noise())),
                md_num(Some(c.truth.seconds), 3),
            ]
        })
        .collect();
    let _ = write!(
        summary,
        "\nReferences ({threads} threads):\n\n{}",
        md_table(
            &[
                "case",
                "scored pixels",
                "paths per pixel",
                "own noise",
                "seconds"
            ],
            &refs
        )
    );
    for s in skipped {
        let _ = writeln!(summary, "\nSkipped {s}");
    }
    if !peers.is_empty() {
        summary.push_str(
            "\nPeers, on the same axes (dashed in the plots; their time is their render alone, \
             scene loading excluded):\n\n",
        );
        for n in peers {
            let _ = writeln!(summary, "- {n}");
        }
    }
    let mut body = String::new();
    for c in results {
        let _ = writeln!(
            body,
            "### {}\n\nReference: `volpath`, {} paths per pixel, own relative noise {}. \
             Pictures in `truth/{}/` (the reference, each model under `exact` at the same \
             exposure, and `<model>_difference.png`: its luminance minus the reference's, over \
             the reference's mean, ±{} %); curve in `truth_error_vs_time_{}.png`.\n",
            c.case,
            c.truth.spp,
            md_pct(Some(c.truth.noise())),
            c.case,
            100.0 * SIGNED_RANGE,
            c.case
        );
        let rows: Vec<Vec<String>> = c
            .runs
            .iter()
            .map(|r| {
                vec![
                    if r.renderer == "sss" {
                        r.method.to_string()
                    } else {
                        format!("{} ({})", r.method, r.renderer)
                    },
                    if r.model.is_empty() {
                        "–".into()
                    } else {
                        r.model.to_string()
                    },
                    if r.param.is_empty() {
                        "–".into()
                    } else if r.warnings > 0 {
                        format!("{}={} ⚠", r.param, r.value)
                    } else {
                        format!("{}={}", r.param, r.value)
                    },
                    md_num(Some(r.seconds), 3),
                    ratios(r),
                    md_pct(Some(r.score.rel_rmse)),
                    md_num(c.crossover.and_then(|x| x.seconds_for(r.score.rel_rmse)), 3),
                ]
            })
            .collect();
        body.push_str(&md_table(
            &[
                "method",
                "model",
                "param",
                "total s",
                "mean / truth (R / G / B)",
                "rel. RMSE",
                "volpath to the same error, s",
            ],
            &rows,
        ));
        for u in &c.unsupported {
            let _ = writeln!(body, "\nNot run: {u}");
        }
        body.push('\n');
    }
    Section {
        title: "Truth: every model against volumetric light transport".into(),
        summary,
        body,
    }
}
