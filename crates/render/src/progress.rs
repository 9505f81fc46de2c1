//! Progress bars on stderr, shared by the `sss` binary and the `xtask` harness.

use indicatif::{ProgressBar, ProgressStyle};

/// A progress bar of `len` steps counting `unit`s on stderr. It is hidden automatically when
/// stderr is not a terminal (CI logs stay clean).
pub fn bar(len: u64, unit: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    let template = format!(
        "{{spinner}} [{{elapsed_precise}}] {{wide_bar}} {{human_pos}}/{{human_len}} {unit} ({{eta}}) {{msg}}"
    );
    if let Ok(style) = ProgressStyle::with_template(&template) {
        bar.set_style(style);
    }
    bar
}
