//! Inputs found by `cargo xtask fuzz` that once misbehaved, kept as regression tests.

use sss_plot::{Series, line_plot};
use std::path::PathBuf;
use std::sync::mpsc;
use std::time::Duration;

/// A fresh, empty directory under the system temporary directory.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "sss-plot-fuzz-regressions-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// Draws `points` on log-log axes on another thread; fails (rather than hangs) when drawing
/// takes longer than 30 s.
fn plot_within_time_limit(path: PathBuf, points: Vec<(f64, f64)>) {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let r = line_plot(
            &path,
            "fuzz",
            "r (mm)",
            "Rd",
            &[Series::line("rd", points)],
            true,
            true,
        );
        let _ = tx.send(r.map_err(|e| e.to_string()));
    });
    match rx.recv_timeout(Duration::from_secs(30)) {
        Ok(r) => r.expect("the plot is written"),
        Err(_) => panic!("drawing the plot did not finish within 30 s (the log-axis hang)"),
    }
}

/// `cargo xtask fuzz --seed 1 --seconds 60` (target `cli`, iteration 2374): `sss profile
/// --model pbd … --r-max 5e-324 --steps 8 --log --plot p.svg` never finished. Every radius
/// but the last underflowed to 0 and was dropped; the last, 5e-324, gave a log x range whose
/// lower end 10^-324 rounded to 0, and plotters' log tick generation looped forever. Subnormal
/// and huge values on either log axis now give a finite, positive range.
#[test]
fn log_axes_over_subnormal_and_huge_values_finish() {
    let dir = temp_dir("log");
    let cases: Vec<Vec<(f64, f64)>> = vec![
        vec![(0.0, 1.0), (5e-324, 75.8)],
        vec![(5e-324, 5e-324), (1e-323, 1e-322)],
        vec![(1e-310, 1.0), (1e308, f64::MAX)],
        vec![(f64::MAX, f64::MAX)],
    ];
    for (i, points) in cases.into_iter().enumerate() {
        let path = dir.join(format!("log{i}.svg"));
        plot_within_time_limit(path.clone(), points);
        assert!(
            path.metadata().is_ok_and(|m| m.len() > 0),
            "{}",
            path.display()
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
