//! The adapter that lets the renderer drive a progress bar ([`Bar`]); the bars themselves are
//! `sss_util::progress`'s.

use indicatif::ProgressBar;
pub use sss_util::progress::bar;

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
