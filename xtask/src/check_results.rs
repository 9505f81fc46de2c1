//! `cargo xtask check-results DIR`: checks the values in a `compare` run's `results.csv`, not
//! only that the file exists. CI runs it after `cargo xtask compare --quick`.
//!
//! What must hold, from the physics and the conventions (README, `results.csv`):
//! - every error figure is finite and non-negative, fractions lie in [0, 1], and no run gave
//!   a warning (the built-in scenes are within every cap);
//! - the same run with all threads and with one thread has identical error figures (renders
//!   are bit-identical for any thread count);
//! - unbiased methods agree with the reference on average: the path tracer at its largest
//!   sample count and `exact` at its coarsest spacing have a mean ratio within
//!   [`MEAN_RATIO_BOUNDS`] of the `exact` reference (measured today: 0.987–1.017 and
//!   0.98–1.08);
//! - error falls as work grows: the path tracer's relative RMSE at its largest sample count
//!   is below [`PATHTRACE_CONVERGENCE`] times its value at 1 sample (1/√16 = 0.25 in theory;
//!   0.24–0.42 measured), and `exact`'s falls from its coarsest to its finest swept spacing.

use std::collections::BTreeMap;
use std::path::Path;

/// Allowed range of the mean over the reference mean for unbiased methods.
pub const MEAN_RATIO_BOUNDS: (f64, f64) = (0.85, 1.15);

/// The path tracer's relative RMSE at its largest sample count over its value at 1 sample
/// must be below this.
pub const PATHTRACE_CONVERGENCE: f64 = 0.6;

/// One row of `results.csv`, the columns the checks read.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    scene: String,
    method: String,
    value: f64,
    threads: usize,
    rmse: f64,
    rel_rmse: f64,
    frac_within_eps: f64,
    mean_ratio: f64,
    warnings: usize,
}

/// Parses `results.csv` text into rows, by column name.
pub fn parse(text: &str) -> Result<Vec<Row>, String> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().ok_or("empty file")?.split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or(format!("no column `{name}`"))
    };
    let idx = [
        col("scene")?,
        col("method")?,
        col("value")?,
        col("threads")?,
        col("rmse")?,
        col("rel_rmse")?,
        col("frac_within_eps")?,
        col("mean_ratio")?,
        col("warnings")?,
    ];
    let mut rows = Vec::new();
    for (n, line) in lines.enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != header.len() {
            return Err(format!(
                "line {}: {} fields, expected {}",
                n + 2,
                f.len(),
                header.len()
            ));
        }
        let num = |i: usize| -> Result<f64, String> {
            f[i].parse::<f64>()
                .map_err(|_| format!("line {}: `{}` is not a number ({})", n + 2, f[i], header[i]))
        };
        rows.push(Row {
            scene: f[idx[0]].to_string(),
            method: f[idx[1]].to_string(),
            value: num(idx[2])?,
            threads: num(idx[3])? as usize,
            rmse: num(idx[4])?,
            rel_rmse: num(idx[5])?,
            frac_within_eps: num(idx[6])?,
            mean_ratio: num(idx[7])?,
            warnings: num(idx[8])? as usize,
        });
    }
    if rows.is_empty() {
        return Err("no rows".into());
    }
    Ok(rows)
}

/// Every check of the module docs; each failure is one message.
pub fn check(rows: &[Row]) -> Vec<String> {
    let mut bad = Vec::new();
    let name = |r: &Row| {
        format!(
            "{} {} {} ({} thread(s))",
            r.scene, r.method, r.value, r.threads
        )
    };
    for r in rows {
        let finite = [r.rmse, r.rel_rmse, r.mean_ratio]
            .iter()
            .all(|v| v.is_finite() && *v >= 0.0);
        if !finite || !(0.0..=1.0).contains(&r.frac_within_eps) {
            bad.push(format!("{}: a figure is out of range: {r:?}", name(r)));
        }
        if r.warnings > 0 {
            bad.push(format!("{}: {} warning(s)", name(r), r.warnings));
        }
    }
    // Thread counts: identical figures.
    let mut by_run: BTreeMap<(String, String, u64), Vec<&Row>> = BTreeMap::new();
    for r in rows {
        by_run
            .entry((r.scene.clone(), r.method.clone(), r.value.to_bits()))
            .or_default()
            .push(r);
    }
    for runs in by_run.values() {
        let a = runs[0];
        for b in &runs[1..] {
            let figures = |r: &Row| (r.rmse, r.rel_rmse, r.frac_within_eps, r.mean_ratio);
            if figures(a) != figures(b) {
                bad.push(format!(
                    "{} and {}: error figures differ between thread counts",
                    name(a),
                    name(b)
                ));
            }
        }
    }
    // Per scene and method, over the sweep (one thread count: the first seen).
    let mut sweeps: BTreeMap<(String, String), Vec<&Row>> = BTreeMap::new();
    for r in rows {
        let key = (r.scene.clone(), r.method.clone());
        let s = sweeps.entry(key).or_default();
        if s.first().is_none_or(|f| f.threads == r.threads) {
            s.push(r);
        }
    }
    let (lo, hi) = MEAN_RATIO_BOUNDS;
    for ((scene, method), runs) in &sweeps {
        let (Some(first), Some(last)) = (runs.first(), runs.last()) else {
            continue;
        };
        match method.as_str() {
            // NaN figures are reported by the range check above.
            "pathtrace" => {
                if !(lo..=hi).contains(&last.mean_ratio) {
                    bad.push(format!(
                        "{scene} pathtrace {}: mean ratio {} outside [{lo}, {hi}]",
                        last.value, last.mean_ratio
                    ));
                }
                if runs.len() > 1 && last.rel_rmse >= PATHTRACE_CONVERGENCE * first.rel_rmse {
                    bad.push(format!(
                        "{scene} pathtrace: rel. RMSE {} at {} spp is not below {} × {} at {} spp",
                        last.rel_rmse,
                        last.value,
                        PATHTRACE_CONVERGENCE,
                        first.rel_rmse,
                        first.value
                    ));
                }
            }
            "exact" => {
                // The sweep runs coarse to fine.
                if !(lo..=hi).contains(&first.mean_ratio) {
                    bad.push(format!(
                        "{scene} exact {}: mean ratio {} outside [{lo}, {hi}]",
                        first.value, first.mean_ratio
                    ));
                }
                if runs.len() > 1 && last.rel_rmse >= first.rel_rmse {
                    bad.push(format!(
                        "{scene} exact: rel. RMSE {} at spacing {} is not below {} at {}",
                        last.rel_rmse, last.value, first.rel_rmse, first.value
                    ));
                }
            }
            _ => {}
        }
    }
    bad
}

/// Reads `dir/results.csv` and runs the checks; `Err` lists every failure.
pub fn run(dir: &Path) -> Result<usize, String> {
    let path = dir.join("results.csv");
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let rows = parse(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let bad = check(&rows);
    if bad.is_empty() {
        Ok(rows.len())
    } else {
        Err(format!("{}:\n  {}", path.display(), bad.join("\n  ")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "scene,method,param,value,threads,seconds_total,rmse,rel_rmse,frac_within_eps,frac_within_3se,mean_ratio,warnings";

    fn csv(rows: &[&str]) -> String {
        let mut s = String::from(HEADER);
        for r in rows {
            s.push('\n');
            s.push_str(r);
        }
        s
    }

    /// A healthy sweep: path tracer converging and unbiased, exact improving, two thread
    /// counts agreeing.
    fn good() -> Vec<&'static str> {
        vec![
            "s,exact,spacing_mfp,4e0,2,1,0.1,0.30,0.2,,1.05,0",
            "s,exact,spacing_mfp,4e0,1,2,0.1,0.30,0.2,,1.05,0",
            "s,exact,spacing_mfp,2e0,2,1,0.05,0.10,0.5,,1.01,0",
            "s,exact,spacing_mfp,2e0,1,2,0.05,0.10,0.5,,1.01,0",
            "s,pathtrace,spp,1e0,2,1,1,1.40,0.0,0.5,0.97,0",
            "s,pathtrace,spp,1.6e1,2,1,0.3,0.37,0.1,0.9,1.002,0",
            "s,separable,taps,7e0,2,1,0.1,0.06,0.5,,0.0,0",
        ]
    }

    #[test]
    fn a_healthy_run_passes() {
        let rows = parse(&csv(&good())).unwrap();
        assert_eq!(rows.len(), 7);
        assert_eq!(check(&rows), Vec::<String>::new());
    }

    /// Each broken figure is caught, and only that one.
    #[test]
    fn each_violation_is_reported() {
        let cases: [(usize, &str, &str); 7] = [
            // biased path tracer
            (
                5,
                "s,pathtrace,spp,1.6e1,2,1,0.3,0.37,0.1,0.9,1.2,0",
                "mean ratio",
            ),
            // not converging
            (
                5,
                "s,pathtrace,spp,1.6e1,2,1,0.3,0.9,0.1,0.9,1.0,0",
                "not below",
            ),
            // exact getting worse with finer spacing
            (
                2,
                "s,exact,spacing_mfp,2e0,2,1,0.05,0.40,0.5,,1.01,0",
                "not below",
            ),
            // thread counts disagree
            (
                1,
                "s,exact,spacing_mfp,4e0,1,2,0.1,0.31,0.2,,1.05,0",
                "thread counts",
            ),
            // a warning
            (6, "s,separable,taps,7e0,2,1,0.1,0.06,0.5,,0.0,1", "warning"),
            // a fraction out of range
            (
                6,
                "s,separable,taps,7e0,2,1,0.1,0.06,1.5,,0.0,0",
                "out of range",
            ),
            // biased exact at its coarsest spacing (both thread counts)
            (
                0,
                "s,exact,spacing_mfp,4e0,2,1,0.1,0.30,0.2,,0.5,0",
                "mean ratio",
            ),
        ];
        for (i, line, needle) in cases {
            let mut rows = good();
            rows[i] = line;
            let bad = check(&parse(&csv(&rows)).unwrap());
            assert!(!bad.is_empty(), "{line}: not caught");
            assert!(bad.iter().any(|b| b.contains(needle)), "{line}: {bad:?}");
        }
    }

    #[test]
    fn malformed_files_are_errors() {
        assert!(parse("").is_err());
        assert!(parse(HEADER).is_err());
        assert!(parse("scene,method\ns,exact").is_err());
        let short = csv(&["s,exact,spacing_mfp,4e0,2"]);
        assert!(parse(&short).unwrap_err().contains("fields"));
        let nan = csv(&["s,exact,spacing_mfp,4e0,2,1,x,0.3,0.2,,1.0,0"]);
        assert!(parse(&nan).unwrap_err().contains("not a number"));
    }
}
