//! Progress bars on stderr (indicatif) for the toolkit's long commands: `sss`, `cargo xtask
//! compare` and the Python bindings' progress lines share their look and their time estimate.

use indicatif::{HumanDuration, ProgressBar, ProgressState, ProgressStyle};
use std::time::Duration;

/// A progress bar of `len` steps counting `unit`s on stderr. It is hidden automatically when
/// stderr is not a terminal (CI logs stay clean).
pub fn bar(len: u64, unit: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    let template = format!(
        "{{spinner}} [{{elapsed_precise}}] {{wide_bar}} {{human_pos}}/{{human_len}} {unit} ({{eta}}) {{msg}}"
    );
    if let Ok(style) = ProgressStyle::with_template(&template) {
        bar.set_style(
            style.with_key("eta", |s: &ProgressState, w: &mut dyn std::fmt::Write| {
                let _ = w.write_str(&eta_text(s.elapsed(), s.fraction(), s.eta()));
            }),
        );
    }
    bar
}

/// The remaining time as the bar shows it: `estimating` until a second has passed and 1 % of
/// the work is done (indicatif's own estimate started at "2h" on a 12-second render), then the
/// estimate (`12s`, `3m`).
pub fn eta_text(elapsed: Duration, fraction: f32, eta: Duration) -> String {
    if elapsed < Duration::from_secs(1) || !(fraction >= 0.01) {
        "estimating".to_string()
    } else {
        HumanDuration(eta).to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::eta_text;
    use std::time::Duration;

    #[test]
    fn the_remaining_time_waits_for_evidence() {
        let s = Duration::from_secs;
        assert_eq!(
            eta_text(Duration::from_millis(300), 0.5, s(7200)),
            "estimating"
        );
        assert_eq!(eta_text(s(5), 0.001, s(7200)), "estimating");
        assert_eq!(eta_text(s(5), f32::NAN, s(7200)), "estimating");
        assert_eq!(eta_text(s(5), 0.3, s(12)), "12 seconds");
    }
}
