use super::*;

#[test]
fn score_of_a_known_error() {
    // Errors of 0.1 in every channel of every pixel: RMSE 0.1, no spread, so SE 0; the
    // reference's RMS is 1, so the relative RMSE is 0.1 too.
    let r = SubsetReference {
        pixels: (0..10).collect(),
        values: vec![[1.0; 3]; 10],
        population: 100,
        seconds: 0.0,
        samples: 0,
    };
    let s = score(&vec![[1.1; 3]; 10], &r).unwrap();
    assert!((s.rmse - 0.1).abs() < 1e-12);
    assert!(s.rmse_se.abs() < 1e-12);
    assert!((s.rel_rmse - 0.1).abs() < 1e-12);
}

#[test]
fn equal_rmse_time_interpolates_log_log() {
    let pts = [(10.0, 1e-2), (100.0, 1e-3)];
    let t = time_at_rmse(&pts, 10f64.powf(-2.5)).unwrap();
    assert!((t - 10f64.powf(1.5)).abs() < 1e-9);
    assert_eq!(time_at_rmse(&pts, 1e-4), None);
    assert_eq!(time_at_rmse(&pts, 1e-3), Some(100.0));
}

/// Every column of the experiment's CSV is documented in `docs/compare.md`.
#[test]
fn every_csv_column_is_documented() {
    assert_eq!(crate::output::undocumented(&csv(&[])), Vec::<String>::new());
}
