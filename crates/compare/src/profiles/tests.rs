use super::*;

#[test]
fn csv_has_the_documented_columns() {
    let e = eval("skin1", "pbd", 2, 0.5);
    let csv = String::from(results_csv(&[e]));
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], COLUMNS.join(","));
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
        part: WalkPart::All,
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
        WalkPart::All
    ));
    assert!(matches!(
        ModelMethod(ModelKind::BetterDipole).reference_part(),
        WalkPart::Multiple
    ));
    assert!(matches!(
        ModelMethod(ModelKind::Burley).reference_part(),
        WalkPart::All
    ));
    assert!(matches!(
        ModelMethod(ModelKind::McTable).reference_part(),
        WalkPart::All
    ));
}

#[test]
fn statistics() {
    assert_eq!(mean([1.0, f64::NAN, 3.0].into_iter()), Some(2.0));
    assert_eq!(mean(std::iter::empty()), None);
    assert_eq!(median([3.0, 1.0, 2.0].into_iter()), Some(2.0));
    assert_eq!(median([4.0, 1.0, 2.0, 3.0].into_iter()), Some(2.5));
}

/// Every column of the experiment's CSV is documented in `docs/compare.md`.
#[test]
fn every_csv_column_is_documented() {
    assert_eq!(
        crate::output::undocumented(&results_csv(&[])),
        Vec::<String>::new()
    );
}
