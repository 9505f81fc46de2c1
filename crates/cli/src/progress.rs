//! Progress bars on stderr (indicatif), shared by the `sss` binary and the `xtask` harness, and
//! the adapter that lets the renderer drive one ([`Bar`]).

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

/// An indicatif bar as the renderer's [`sss_render::progress::Progress`].
pub struct Bar(pub ProgressBar);

impl sss_render::progress::Progress for Bar {
    fn start(&self, total: u64) {
        self.0.set_length(total);
    }
    fn advance(&self, n: u64) {
        self.0.inc(n);
    }
}
