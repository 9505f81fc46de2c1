//! Equal quality and equal time along measured sweeps (the comparisons of Nabata & Iwasaki's
//! Table 1 and Fig. 6): a method's sweep is a list of (seconds, RMSE) runs in the order of its
//! cost parameter (ε loosest first, or the irradiance points N fewest first), read in log-log
//! coordinates, where an error falling as a power of the time is a straight line (Monte Carlo
//! noise: RMSE ∝ N^−½ ∝ t^−½ when the time is proportional to N).

/// Where a sweep first reaches an error target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reach {
    /// Its cheapest run (this many seconds) is already at or below the target: the time the
    /// method needs is at most this.
    AtMost(f64),
    /// The first crossing, interpolated in log-log between the last run above the target and
    /// the first one at or below it.
    At(f64),
    /// No run reaches the target; the slowest run took this many seconds (the method needs
    /// more, if it gets there at all).
    NotReached(f64),
}

/// The runs of `curve` with a positive, finite time and error, in their order.
fn valid(curve: &[(f64, f64)]) -> Vec<(f64, f64)> {
    curve
        .iter()
        .copied()
        .filter(|&(t, e)| t.is_finite() && e.is_finite() && t > 0.0 && e > 0.0)
        .collect()
}

/// The time `curve` (seconds, RMSE per run, in sweep order) needs to reach the error
/// `target`: the first run at or below it, log-log interpolated from the run before; later
/// runs do not matter (a noisy, non-monotone curve counts from its first crossing). `None`
/// for an empty curve or a target that is not positive and finite.
pub fn time_to_reach(curve: &[(f64, f64)], target: f64) -> Option<Reach> {
    let c = valid(curve);
    if c.is_empty() || !(target.is_finite() && target > 0.0) {
        return None;
    }
    if c[0].1 <= target {
        return Some(Reach::AtMost(c[0].0));
    }
    for w in c.windows(2) {
        let ((t0, e0), (t1, e1)) = (w[0], w[1]);
        if e1 <= target {
            // e0 > target ≥ e1 > 0, so ln e0 > ln e1 and u ∈ (0, 1].
            let u = (target / e0).ln() / (e1 / e0).ln();
            return Some(Reach::At((t0.ln() + u * (t1 / t0).ln()).exp()));
        }
    }
    let slowest = c.iter().map(|r| r.0).fold(0.0, f64::max);
    Some(Reach::NotReached(slowest))
}

/// The error of `curve` (seconds, RMSE per run) at `seconds`, log-log interpolated between
/// the two runs around it once the runs are sorted by time; `None` outside the runs' time
/// range (no extrapolation) or for an empty curve.
pub fn error_at_time(curve: &[(f64, f64)], seconds: f64) -> Option<f64> {
    let mut c = valid(curve);
    if !(seconds.is_finite() && seconds > 0.0) {
        return None;
    }
    c.sort_by(|a, b| a.0.total_cmp(&b.0));
    if let Some(&(_, e)) = c.iter().find(|r| r.0 == seconds) {
        return Some(e);
    }
    c.windows(2)
        .find(|w| w[0].0 < seconds && seconds < w[1].0)
        .map(|w| {
            let ((t0, e0), (t1, e1)) = (w[0], w[1]);
            let u = (seconds / t0).ln() / (t1 / t0).ln();
            (e0.ln() + u * (e1 / e0).ln()).exp()
        })
}

/// The time a method whose error is Monte Carlo noise of its N points would need to reach
/// `target` from its run `(seconds, rmse)`, with the time proportional to N (the points
/// dominate, as the paper's Table 2 and our stage times show) and RMSE ∝ N^−½: seconds ×
/// (rmse / target)². An extrapolation, reported as such.
pub fn extrapolated_time((seconds, rmse): (f64, f64), target: f64) -> Option<f64> {
    let r = rmse / target;
    let t = seconds * r * r;
    (t.is_finite() && t > 0.0).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * b.abs().max(1.0)
    }

    /// On an exact power law RMSE = t^−½ the log-log interpolation is exact: the target 0.3 is
    /// reached at (1/0.3)² s, between the runs at 4 and 16 s, and the error at 9 s is 1/3.
    #[test]
    fn power_laws_are_interpolated_exactly() {
        let curve: Vec<(f64, f64)> = [1.0, 4.0, 16.0, 64.0]
            .iter()
            .map(|&t: &f64| (t, 1.0 / t.sqrt()))
            .collect();
        let Some(Reach::At(t)) = time_to_reach(&curve, 0.3) else {
            panic!("{:?}", time_to_reach(&curve, 0.3));
        };
        assert!(close(t, 1.0 / 0.09), "{t}");
        assert!(close(error_at_time(&curve, 9.0).unwrap(), 1.0 / 3.0));
        // A target met exactly at a run is met at that run's time.
        let Some(Reach::At(t)) = time_to_reach(&curve, 0.25) else {
            panic!()
        };
        assert!(close(t, 16.0), "{t}");
        assert_eq!(error_at_time(&curve, 16.0), Some(0.25));
        // Slope −1 (an error ∝ 1/t) is exact too.
        let c1 = [(2.0, 0.5), (8.0, 0.125)];
        let Some(Reach::At(t)) = time_to_reach(&c1, 0.25) else {
            panic!()
        };
        assert!(close(t, 4.0), "{t}");
        assert!(close(error_at_time(&c1, 4.0).unwrap(), 0.25));
    }

    /// A sweep that never gets there, one that starts below the target, and bad input.
    #[test]
    fn not_reached_already_reached_and_degenerate_curves() {
        let curve = [(1.0, 0.9), (3.0, 0.5), (2.5, 0.4)];
        assert_eq!(time_to_reach(&curve, 0.1), Some(Reach::NotReached(3.0)));
        assert_eq!(time_to_reach(&curve, 0.95), Some(Reach::AtMost(1.0)));
        assert_eq!(time_to_reach(&[], 0.1), None);
        assert_eq!(time_to_reach(&curve, 0.0), None);
        assert_eq!(time_to_reach(&curve, f64::NAN), None);
        // Runs with a zero or non-finite error or time are left out (a run at exactly 0 error
        // cannot be placed on a log axis).
        let holes = [(0.0, 0.5), (1.0, f64::NAN), (2.0, 0.8), (8.0, 0.2)];
        let Some(Reach::At(t)) = time_to_reach(&holes, 0.4) else {
            panic!()
        };
        assert!(close(t, 4.0), "{t}");
        // Outside the time range there is no equal-time error.
        assert_eq!(error_at_time(&curve, 0.5), None);
        assert_eq!(error_at_time(&curve, 3.5), None);
        assert_eq!(error_at_time(&[], 1.0), None);
        assert_eq!(error_at_time(&[(1.0, 0.5)], 1.0), Some(0.5));
        assert_eq!(error_at_time(&[(1.0, 0.5)], 2.0), None);
    }

    /// Non-monotone sweeps: the first crossing counts, whatever comes after; a rise before it
    /// moves the crossing to the segment that crosses. Equal time reads the runs sorted by
    /// time.
    #[test]
    fn non_monotone_curves_count_from_their_first_crossing() {
        // Down to 5 (crossing 6 between 1 s and 2 s), up to 8, down to 2.
        let c = [(1.0, 10.0), (2.0, 5.0), (4.0, 8.0), (8.0, 2.0)];
        let Some(Reach::At(t)) = time_to_reach(&c, 6.0) else {
            panic!()
        };
        let want = 2f64.powf((0.6f64).ln() / (0.5f64).ln());
        assert!(close(t, want), "{t} vs {want}");
        assert!(t > 1.0 && t < 2.0);
        // Up first, then down across the target between 2 s and 4 s.
        let c = [(1.0, 10.0), (2.0, 12.0), (4.0, 3.0)];
        let Some(Reach::At(t)) = time_to_reach(&c, 6.0) else {
            panic!()
        };
        assert!(close(t, 2.0 * 2f64.sqrt()), "{t}");
        // Times out of order (a noisy timing): equal time sorts them, 0.5 s between 0.25 and
        // 1 s on the line e = 1/t.
        let c = [(1.0, 1.0), (0.25, 4.0), (4.0, 0.25)];
        assert!(close(error_at_time(&c, 0.5).unwrap(), 2.0));
    }

    #[test]
    fn extrapolation_follows_the_inverse_square_root() {
        // 4× less error needs 16× the time.
        assert!(close(extrapolated_time((3.0, 0.04), 0.01).unwrap(), 48.0));
        assert_eq!(extrapolated_time((3.0, 0.04), 0.0), None);
        assert_eq!(extrapolated_time((0.0, 0.04), 0.01), None);
    }
}
