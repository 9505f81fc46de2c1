//! The comparison's outputs in words and tables: `mcml.csv` and the subsection.

use super::*;

/// The columns of `mcml.csv` (documented in `docs/compare.md`).
pub const COLUMNS: [&str; 22] = [
    "case",
    "model",
    "model_part",
    "eta",
    "g",
    "reduced_albedo",
    "mfp_mm",
    "near_excess",
    "near_at_mfp",
    "near_rel_error",
    "near_single_excess",
    "near_median_abs_error",
    "far_excess",
    "far_at_mfp",
    "far_rel_error",
    "far_single_excess",
    "total_model",
    "total_mcml",
    "total_mcml_se",
    "total_rel_error",
    "bins",
    "bins_forgiven",
];

/// `mcml.csv`: one row per (case, model).
pub fn results_csv(rows: &[Comparison]) -> Csv {
    let mut csv = Csv::new(COLUMNS);
    for c in rows {
        let w = |w: Option<Worst>, f: fn(Worst) -> f64| csv_num(w.map(f));
        csv.row([
            csv_text(&c.case),
            csv_text(&c.model),
            csv_text(c.part.name()),
            csv_num(Some(c.eta)),
            csv_num(Some(c.g)),
            csv_num(Some(c.reduced_albedo)),
            csv_num(Some(c.mfp)),
            w(c.near, |w| w.excess),
            w(c.near, |w| w.at),
            w(c.near, |w| w.rel_error),
            w(c.near, |w| w.single),
            csv_num(c.near_median),
            w(c.far, |w| w.excess),
            w(c.far, |w| w.at),
            w(c.far, |w| w.rel_error),
            w(c.far, |w| w.single),
            csv_num(Some(c.total_model)),
            csv_num(Some(c.total_mcml)),
            csv_num(Some(c.total_mcml_se)),
            csv_num(c.total_rel_error()),
            csv_text(c.bins()),
            csv_text(c.forgiven()),
        ]);
    }
    csv
}

pub(super) fn max_of(values: impl Iterator<Item = Option<f64>>) -> Option<f64> {
    values.flatten().filter(|v| v.is_finite()).reduce(f64::max)
}

pub(super) fn dagger(part: WalkPart) -> &'static str {
    match part {
        WalkPart::Multiple => " †",
        WalkPart::All => "",
    }
}

/// The subsection and the summary line of a successful comparison.
pub(super) fn report(
    rows: &[Comparison],
    cases: &[Case],
    skipped: &[String],
    dir: &Path,
) -> (String, String) {
    let mut models: Vec<(&str, WalkPart)> = Vec::new();
    for c in rows {
        if !models.iter().any(|(m, _)| *m == c.model) {
            models.push((&c.model, c.part));
        }
    }
    fn of<'a>(rows: &'a [Comparison], m: &'a str) -> impl Iterator<Item = &'a Comparison> {
        rows.iter().filter(move |c| c.model == m)
    }
    let worst_near = |m: &str| max_of(of(rows, m).map(|c| c.near.map(|w| w.excess)));
    let mut summary = format!(
        "Against MCML (Wang, Jacques & Zheng 1995; {} media, per medium below and in \
         `{CSV_NAME}`): worst excess beyond 3 MCML standard errors over 0.25–10 reduced mean \
         free paths — ",
        cases.len()
    );
    let parts: Vec<String> = models
        .iter()
        .map(|(m, p)| format!("`{m}`{} {}", dagger(*p), md_pct(worst_near(m))))
        .collect();
    let _ = writeln!(
        summary,
        "{} († multiple scattering only).",
        parts.join(", ")
    );

    let mut body = format!("### {TITLE}\n\n");
    let _ = writeln!(
        body,
        "Each model against MCML (Wang, Jacques & Zheng 1995), a Monte Carlo code independent \
         of this project's walk, on {} semi-infinite media under a normally incident pencil \
         beam (`{}`). MCML counts its photons before the specular reflection \
         R_sp = ((η − 1)/(η + 1))² at the boundary; the models are per unit power entering, so \
         MCML's profile and total are divided by 1 − R_sp. A model's value for a bin is its \
         area average over the MCML annulus ({GAUSS_POINTS}-point Gauss–Legendre of 2πr R_d). \
         MCML's standard error per bin comes from 5 batches; as in \
         `crates/bssrdf/tests/integration/mcml.rs` it is pooled over the 21 bins around each \
         bin.\n\n\
         - *excess*: (|model − MCML| − 3 SE)/MCML, worst over the bins of the range (0 when \
         every bin is within 3 SE), in reduced mean free paths x = r/ℓ, ℓ = 1/(σ_a + σ_s(1 − g)). \
         Single MCML bins have heavy-tailed errors (a few photons of large weight), so a bin \
         counts only as far as its neighbourhood agrees: its effective excess is the smaller \
         of its own and that of the 5 bins around it (light summed, variances added). \
         *forgiven*: bins beyond the test's margin (3 % within 10 ℓ, 10 % beyond) alone but \
         within it over their 5 bins; the worst single-bin excess is in `{CSV_NAME}`.\n\
         - *median error*: median of |model − MCML|/MCML over the bins in 0.25–10 ℓ, for \
         reference (it includes MCML's noise).\n\
         - *total*: (model − MCML)/MCML of the total diffuse reflectance (MCML: all radii).\n\
         - † The standard and better dipoles model multiple scattering only; MCML has every \
         scattering order, so their figures include the missing single scattering (they are \
         measured against our walk's multiple-scattering part above).\n",
        cases.len(),
        dir.display()
    );
    for note in skipped {
        let _ = writeln!(body, "- Skipped: {note}.");
    }
    body.push('\n');
    let model_rows: Vec<Vec<String>> = models
        .iter()
        .map(|(m, p)| {
            vec![
                format!("`{m}`{}", dagger(*p)),
                md_pct(worst_near(m)),
                md_pct(max_of(of(rows, m).map(|c| c.far.map(|w| w.excess)))),
                md_pct(max_of(
                    of(rows, m).map(|c| c.total_rel_error().map(f64::abs)),
                )),
                md_pct(max_of(of(rows, m).map(|c| c.near_median))),
            ]
        })
        .collect();
    let _ = writeln!(body, "Worst over the {} media, per model:\n", cases.len());
    body.push_str(&md_table(
        &[
            "model",
            "excess 0.25–10 ℓ",
            "excess 10–16 ℓ",
            "abs. total error",
            "largest median error 0.25–10 ℓ",
        ],
        &model_rows,
    ));
    body.push('\n');
    let at = |w: Option<Worst>| match w {
        Some(w) if w.excess > 0.0 => {
            format!("{} at {}", md_pct(Some(w.excess)), md_num(Some(w.at), 3))
        }
        Some(_) => "0 %".into(),
        None => "–".into(),
    };
    let detail: Vec<Vec<String>> = rows
        .iter()
        .map(|c| {
            vec![
                c.case.clone(),
                md_num(Some(c.reduced_albedo), 4),
                format!("`{}`{}", c.model, dagger(c.part)),
                at(c.near),
                md_pct(c.near_median),
                at(c.far),
                md_pct(c.total_rel_error()),
                format!("{} / {}", c.forgiven(), c.bins()),
            ]
        })
        .collect();
    let _ = writeln!(body, "Per medium and model:\n");
    body.push_str(&md_table(
        &[
            "case",
            "α′",
            "model",
            "excess 0.25–10 ℓ (at x)",
            "median error 0.25–10 ℓ",
            "excess 10–16 ℓ (at x)",
            "total vs MCML",
            "forgiven / bins",
        ],
        &detail,
    ));
    (summary, body)
}
