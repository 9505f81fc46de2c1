use super::*;

/// A temporary folder, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> TempDir {
        let d = std::env::temp_dir().join(format!("xtask-mcml-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        TempDir(d)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

const HEADER: &str = "case,sigma_a_per_mm,sigma_s_per_mm,g,eta,eta_above,dr_mm,batches,photons,total_diffuse_reflectance,total_se";

/// Writes a case whose profile is `factor` × the standard dipole's area averages per
/// incident photon (its total likewise), with zero standard errors, 0–20 mfp.
fn synthetic(dir: &Path, name: &str, eta: f64, factor: f64) -> Medium {
    let medium = Medium::new([0.01; 3], [1.0; 3], 0.0, eta).unwrap();
    let model = make_model(ModelKind::StandardDipole, &medium);
    let entering = 1.0 - ((eta - 1.0) / (eta + 1.0)).powi(2);
    let dr = 0.1;
    let mut profile = String::from("r_mm,rd_per_mm2,se_per_mm2\n");
    for i in 0..200 {
        let (lo, hi) = (i as f64 * dr, (i + 1) as f64 * dr);
        let mass = integrate(&|s| 2.0 * PI * s * model.rd(0, s), lo, hi, GAUSS_POINTS);
        let avg = factor * entering * mass / (PI * (hi * hi - lo * lo));
        let _ = writeln!(profile, "{},{avg:e},0", (i as f64 + 0.5) * dr);
    }
    std::fs::write(dir.join(format!("{name}.csv")), profile).unwrap();
    let total = factor * entering * model.total_diffuse_reflectance(0);
    let cases = dir.join("cases.csv");
    let mut text = std::fs::read_to_string(&cases).unwrap_or(format!("{HEADER}\n"));
    let _ = writeln!(text, "{name},0.01,1.0,0,{eta},1.0,{dr},5,1000,{total:e},0");
    std::fs::write(cases, text).unwrap();
    medium
}

fn one(dir: &Path) -> (Vec<Case>, Vec<String>) {
    match load(dir) {
        Reference::Found { cases, skipped } => (cases, skipped),
        other => panic!("{other:?}"),
    }
}

fn against_dipole(case: &Case) -> Comparison {
    let model = make_model(ModelKind::StandardDipole, &case.medium);
    compare(case, "standard-dipole", WalkPart::Multiple, model.as_ref())
}

#[test]
fn a_model_equal_to_the_profile_has_no_error_and_ten_percent_reads_ten_percent() {
    let tmp = TempDir::new("equal");
    synthetic(&tmp.0, "same", 1.3, 1.0);
    // The model 10 % above MCML: MCML = model / 1.1.
    synthetic(&tmp.0, "low", 1.0, 1.0 / 1.1);
    let (cases, skipped) = one(&tmp.0);
    assert!(skipped.is_empty(), "{skipped:?}");
    assert_eq!(cases.len(), 2);
    // Normalised per entering photon (η = 1.3: R_sp = 0.017).
    assert!((cases[0].entering() - (1.0 - (0.3f64 / 2.3).powi(2))).abs() < 1e-15);
    let same = against_dipole(&cases[0]);
    let near = same.near.unwrap();
    assert!(near.excess < 1e-12, "{near:?}");
    assert!(near.rel_error.abs() < 1e-9, "{near:?}");
    assert!(same.near_median.unwrap() < 1e-9);
    assert!(same.total_rel_error().unwrap().abs() < 1e-12);
    let low = against_dipole(&cases[1]);
    for w in [low.near.unwrap(), low.far.unwrap()] {
        assert!((w.excess - 0.1).abs() < 1e-9, "{w:?}");
        assert!((w.rel_error - 0.1).abs() < 1e-9, "{w:?}");
    }
    // 10 % is beyond the near margin (3 %) in every bin and its neighbourhood alike.
    // (It is the far margin itself, so rounding decides there.)
    assert_eq!(low.near.unwrap().forgiven, 0);
    assert!((low.near_median.unwrap() - 0.1).abs() < 1e-9);
    assert!((low.total_rel_error().unwrap() - 0.1).abs() < 1e-12);
    // Bins: ℓ = 1/1.01 mm, bins of 0.1 mm: 0.25–10 ℓ holds centres 0.25–9.9 mm.
    let mfp = cases[1].medium.reduced_mean_free_path(0);
    let expect = (0..200)
        .map(|i| (i as f64 + 0.5) * 0.1 / mfp)
        .filter(|x| (0.25..=10.0).contains(x))
        .count();
    assert_eq!(low.near.unwrap().bins, expect);
    let csv = String::from(results_csv(&[same, low]));
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], COLUMNS.join(","));
    for l in &lines[1..] {
        assert_eq!(l.split(',').count(), COLUMNS.len(), "{l}");
        assert!(
            !l.to_lowercase().contains("nan") && !l.contains("inf"),
            "{l}"
        );
    }
    assert!(
        lines[2].starts_with("low,standard-dipole,multiple,1e0,0e0,"),
        "{}",
        lines[2]
    );
}

#[test]
fn an_isolated_outlier_is_forgiven_but_a_shifted_neighbourhood_is_not() {
    // Eleven bins of equal light at 1–6 ℓ, SE 1 % each: 3 SE = 3 %.
    let row = |x: f64, model: f64| BinRow {
        x,
        model,
        mcml: 1.0,
        var: 1e-4,
    };
    let mut rows: Vec<BinRow> = (0..11).map(|i| row(1.0 + 0.5 * i as f64, 1.0)).collect();
    // One bin 20 % high: alone 17 % beyond 3 SE; over its 5 bins the excess is
    // (0.2 − 3·√5·0.01)/5 = 2.66 %, so it counts as 2.66 % and is forgiven (< 3 %).
    rows[5].model = 1.2;
    let w = worst(&rows, Range::Near).unwrap();
    let group = (0.2 - 3.0 * (5e-4f64).sqrt()) / 5.0;
    assert!((w.excess - group).abs() < 1e-12, "{w:?}");
    assert!((w.single - 0.17).abs() < 1e-12, "{w:?}");
    assert_eq!((w.forgiven, w.bins, w.at), (1, 11, 3.5));
    // The whole neighbourhood 20 % high: every bin counts 17 %.
    for r in &mut rows[3..8] {
        r.model = 1.2;
    }
    let w = worst(&rows, Range::Near).unwrap();
    assert!((w.excess - 0.17).abs() < 1e-12, "{w:?}");
    assert_eq!((w.forgiven, w.at), (0, 3.5));
    assert!((w.rel_error - 0.2).abs() < 1e-12);
    // Within 3 SE everywhere: 0; an empty range: undefined.
    let ok: Vec<BinRow> = (0..11).map(|i| row(1.0 + 0.5 * i as f64, 1.02)).collect();
    assert_eq!(worst(&ok, Range::Near).unwrap().excess, 0.0);
    assert!(worst(&ok, Range::Far).is_none());
}

#[test]
fn the_pooled_standard_error_follows_the_bin_variance_law() {
    // SE² · area / Rd constant over the window: the pooled SE is the bins' own SE.
    let medium = Medium::new([0.01; 3], [1.0; 3], 0.0, 1.0).unwrap();
    let mut case = Case {
        name: "c".into(),
        medium,
        dr: 0.5,
        total: 0.5,
        total_se: 0.0,
        bins: Vec::new(),
    };
    let bins: Vec<(f64, f64, f64)> = (0..30)
        .map(|i| {
            let r = (i as f64 + 0.5) * 0.5;
            (r, 2.0, (2.0 * 1e-3 / case.area(r)).sqrt())
        })
        .collect();
    case.bins = bins.clone();
    for (a, b) in case.normalised_bins().iter().zip(&bins) {
        assert_eq!(a.1, b.1);
        assert!((a.2 / b.2 - 1.0).abs() < 1e-12, "{a:?} {b:?}");
    }
}

#[test]
fn an_absent_folder_is_skipped_and_writes_no_csv() {
    let tmp = TempDir::new("absent");
    let out = tmp.0.join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join(CSV_NAME), "stale").unwrap();
    let s = run(&tmp.0.join("no-such-folder"), &out).unwrap();
    assert!(
        s.body.starts_with(&format!("### {TITLE}\n\n")),
        "{}",
        s.body
    );
    assert!(s.body.contains("was skipped: there is no `"), "{}", s.body);
    assert!(s.summary.contains("skipped"));
    assert!(!out.join(CSV_NAME).exists());
}

#[test]
fn malformed_files_are_skipped_with_a_note_naming_them() {
    let tmp = TempDir::new("malformed");
    let out = tmp.0.join("out");
    std::fs::create_dir_all(&out).unwrap();
    synthetic(&tmp.0, "good", 1.0, 1.0);
    synthetic(&tmp.0, "broken", 1.0, 1.0);
    std::fs::write(
        tmp.0.join("broken.csv"),
        "r_mm,rd_per_mm2,se_per_mm2\n0.05,1e-2,0\n0.15,NaN,0\n",
    )
    .unwrap();
    let mut cases = std::fs::read_to_string(tmp.0.join("cases.csv")).unwrap();
    cases.push_str("missing,0.01,1.0,0,1.0,1.0,0.1,5,1000,0.5,0\n");
    cases.push_str("../evil,0.01,1.0,0,1.0,1.0,0.1,5,1000,0.5,0\n");
    cases.push_str("short,0.01\n");
    std::fs::write(tmp.0.join("cases.csv"), cases).unwrap();
    let s = run(&tmp.0, &out).unwrap();
    for note in [
        "`broken.csv`: line 3: `NaN` is not a finite non-negative number",
        "`cases.csv` line 4: `missing.csv`: cannot read",
        "`cases.csv` line 5: case name `../evil` is not a plain file name",
        "`cases.csv` line 6: too few fields",
    ] {
        assert!(s.body.contains(note), "{note}\n{}", s.body);
    }
    let csv = std::fs::read_to_string(out.join(CSV_NAME)).unwrap();
    assert_eq!(csv.lines().count(), 1 + ModelKind::ALL.len());
    assert!(
        s.summary.contains("Wang, Jacques & Zheng 1995"),
        "{}",
        s.summary
    );
    // A cases.csv without a needed column: the whole comparison is skipped, no CSV.
    std::fs::write(tmp.0.join("cases.csv"), "case,eta\ngood,1\n").unwrap();
    let s = run(&tmp.0, &out).unwrap();
    assert!(
        s.body.contains("has no column `sigma_a_per_mm`"),
        "{}",
        s.body
    );
    assert!(!out.join(CSV_NAME).exists());
}

#[test]
fn the_folder_is_the_environment_variable_or_next_to_the_workspace() {
    assert_eq!(dir_from(Some("/x/y".into())), PathBuf::from("/x/y"));
    let d = dir_from(None);
    assert!(d.ends_with("../shared/reference/mcml"), "{}", d.display());
    assert_eq!(
        d.parent()
            .unwrap()
            .parent()
            .unwrap()
            .parent()
            .unwrap()
            .parent()
            .unwrap(),
        crate::workspace_root().as_path()
    );
}

/// Every column of the experiment's CSV is documented in `docs/compare.md`.
#[test]
fn every_csv_column_is_documented() {
    assert_eq!(
        crate::output::undocumented(&results_csv(&[])),
        Vec::<String>::new()
    );
}
