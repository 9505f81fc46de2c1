//! Long calls: the work runs on a helper thread with the GIL released, while the calling
//! thread wakes every [`POLL`] to check for Ctrl-C (`PyErr_CheckSignals`, which only the main
//! thread may run) and to call the user's progress callback with `(done, total)`.
//!
//! Stopping: the renderer and the Monte Carlo walk have no cancel flag of their own, but both
//! report progress from their inner loops ([`sss_render::progress::Progress`], the photon
//! counter of `sss_bssrdf::profile_rows::compute`). When a callback raises or Ctrl-C arrives,
//! the monitor's `cancel` flag is set and the next progress report on any worker thread unwinds with
//! [`Cancelled`] (through `resume_unwind`, which prints nothing); rayon carries the unwind to
//! the helper thread, which catches it. Everything the call allocated is dropped on the way;
//! nothing global is left half-built (progress is never reported inside a cache's
//! initialisation). The Python exception (the callback's own, or `KeyboardInterrupt`) is then
//! raised in the caller.

use crate::errors::{panic_text, to_py};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc;
use std::time::Duration;

/// How often the calling thread checks for Ctrl-C and reports progress.
pub const POLL: Duration = Duration::from_millis(100);

/// The payload of the unwind that stops a cancelled call.
pub struct Cancelled;

/// Progress counters and the cancel flag shared between the worker threads and the caller.
#[derive(Default)]
pub struct Monitor {
    done: AtomicU64,
    total: AtomicU64,
    cancel: AtomicBool,
}

impl Monitor {
    /// Stops the calling worker (unwinding with [`Cancelled`]) when the call was cancelled.
    pub fn check(&self) {
        if self.cancel.load(Ordering::Relaxed) {
            std::panic::resume_unwind(Box::new(Cancelled));
        }
    }

    /// Sets the total units of work.
    pub fn set_total(&self, total: u64) {
        self.total.store(total, Ordering::Relaxed);
        self.check();
    }

    /// Sets the units done so far.
    pub fn set_done(&self, done: u64) {
        self.done.store(done, Ordering::Relaxed);
        self.check();
    }

    fn snapshot(&self) -> (u64, u64) {
        (
            self.done.load(Ordering::Relaxed),
            self.total.load(Ordering::Relaxed),
        )
    }
}

impl sss_render::progress::Progress for Monitor {
    fn start(&self, total: u64) {
        self.set_total(total);
    }
    fn advance(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
        self.check();
    }
}

/// The bar `progress=True` shows: one line on `sys.stderr`, redrawn with a carriage return
/// (as tqdm draws in a terminal and in a notebook's output cell), `label  37% 2390/6456
/// [00:03 < 5 seconds]`, the remaining time as the command line's bar gives it
/// ([`sss_util::progress::eta_text`]), a line break once everything is done.
#[pyclass(name = "TextBar", module = "sss")]
pub struct TextBar {
    label: String,
    start: std::time::Instant,
    finished: std::sync::atomic::AtomicBool,
}

/// `m:ss` (or `h:mm:ss`) of `d`.
fn clock(d: Duration) -> String {
    let s = d.as_secs();
    if s >= 3600 {
        format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
    } else {
        format!("{:02}:{:02}", s / 60, s % 60)
    }
}

impl TextBar {
    /// The line for `done` of `total` after `elapsed`.
    fn line(&self, done: u64, total: u64, elapsed: Duration) -> String {
        let fraction = if total > 0 {
            (done as f64 / total as f64).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let eta = if fraction > 0.0 {
            elapsed.mul_f64((1.0 - fraction) / fraction)
        } else {
            Duration::ZERO
        };
        let eta = sss_util::progress::eta_text(elapsed, fraction as f32, eta);
        format!(
            "{} {:3.0}% {done}/{total} [{} < {eta}]",
            self.label,
            100.0 * fraction,
            clock(elapsed)
        )
    }
}

#[pymethods]
impl TextBar {
    /// TextBar(label) -> callable progress(done, total) drawing the bar on sys.stderr.
    #[new]
    fn new(label: String) -> Self {
        TextBar {
            label,
            start: std::time::Instant::now(),
            finished: Default::default(),
        }
    }

    fn __call__(&self, py: Python<'_>, done: u64, total: u64) -> PyResult<()> {
        if self.finished.load(Ordering::Relaxed) {
            return Ok(());
        }
        let mut text = format!("\r{}", self.line(done, total, self.start.elapsed()));
        if total > 0 && done >= total {
            text.push('\n');
            self.finished.store(true, Ordering::Relaxed);
        }
        let stderr = py.import("sys")?.getattr("stderr")?;
        stderr.call_method1("write", (text,))?;
        stderr.call_method0("flush")?;
        Ok(())
    }
}

/// The `progress` argument of a long call: None or False (no progress), True (a [`TextBar`]
/// labelled `label`), or a callable (else a `TypeError` now rather than at the first report).
pub fn callback(progress: Option<Bound<'_, PyAny>>, label: &str) -> PyResult<Option<Py<PyAny>>> {
    let py_bool = |p: &Bound<'_, PyAny>| p.cast::<pyo3::types::PyBool>().ok().map(|b| b.is_true());
    match progress {
        None => Ok(None),
        Some(p) if p.is_none() => Ok(None),
        Some(p) if py_bool(&p) == Some(false) => Ok(None),
        Some(p) if py_bool(&p) == Some(true) => Ok(Some(
            Py::new(p.py(), TextBar::new(label.to_string()))?.into_any(),
        )),
        Some(p) if p.is_callable() => Ok(Some(p.unbind())),
        Some(p) => Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "progress must be True, False, None or a callable progress(done, total), got {}",
            p.get_type()
                .name()
                .map(|n| n.to_string())
                .unwrap_or_else(|_| "?".into())
        ))),
    }
}

/// Runs `work` on a helper thread with the GIL released, reporting progress to `callback`
/// (called on this thread as `callback(done, total)`, every [`POLL`] and once at the end) and
/// stopping on Ctrl-C (`KeyboardInterrupt`) or when the callback raises (its exception). An
/// error of `work` becomes its Python exception ([`to_py`]); a panic a `RuntimeError`.
pub fn run_cancellable<T: Send>(
    py: Python<'_>,
    callback: Option<Py<PyAny>>,
    work: impl FnOnce(&Monitor) -> Result<T, sss_render::Error> + Send,
) -> PyResult<T> {
    let monitor = Monitor::default();
    let poll = |monitor: &Monitor| -> PyResult<()> {
        Python::attach(|py| {
            py.check_signals()?;
            if let Some(cb) = &callback {
                let (done, total) = monitor.snapshot();
                cb.bind(py).call1((done, total))?;
            }
            Ok(())
        })
    };
    let (outcome, stop) = py.detach(|| {
        std::thread::scope(|s| {
            let (tx, rx) = mpsc::channel::<()>();
            let monitor = &monitor;
            let handle = s.spawn(move || {
                // `tx` is dropped when this closure ends, normally or by unwinding.
                let _tx = tx;
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| work(monitor)))
            });
            let mut stop: Option<PyErr> = None;
            while let Err(mpsc::RecvTimeoutError::Timeout) = rx.recv_timeout(POLL) {
                if stop.is_none()
                    && let Err(e) = poll(monitor)
                {
                    monitor.cancel.store(true, Ordering::Relaxed);
                    stop = Some(e);
                }
            }
            let outcome = handle.join().unwrap_or_else(Err);
            (outcome, stop)
        })
    });
    if let Some(e) = stop {
        return Err(e);
    }
    match outcome {
        Ok(Ok(value)) => {
            // The last report: everything done (or whatever the work counted).
            poll(&monitor)?;
            Ok(value)
        }
        Ok(Err(e)) => Err(to_py(e)),
        Err(payload) => Err(PyRuntimeError::new_err(format!(
            "internal error (a bug): {}",
            if payload.is::<Cancelled>() {
                "cancelled without a reason".to_string()
            } else {
                panic_text(payload.as_ref())
            }
        ))),
    }
}
