//! Progress reporting without a progress-bar dependency: the renderer calls a [`Progress`]
//! the caller provides (the `sss` binary hands it an indicatif bar; libraries and tests pass
//! [`NoProgress`]).

/// Receives a render's progress. Called from worker threads, so implementations are `Sync`.
pub trait Progress: Sync {
    /// Work is about to start: `total` units (pixel samples) in all.
    fn start(&self, total: u64) {
        let _ = total;
    }
    /// `n` more units are done, or about to be: every integrator calls it as a unit of work
    /// (a G-buffer sample, a pixel, a tree's slice of samples) starts, so that a caller that
    /// stops a render by unwinding from here (the Python module on Ctrl-C) starts no further
    /// unit, whatever a unit costs.
    fn advance(&self, n: u64) {
        let _ = n;
    }
}

/// Ignores progress.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {}
