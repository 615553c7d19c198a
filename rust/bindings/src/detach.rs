//! Long work off the GIL: one helper runs it on a worker thread while the calling thread
//! handles Ctrl-C and progress.

use crate::errors::to_py_err;
use pyo3::prelude::*;
use std::time::Duration;
use vtb::VtbError;

/// Runs `work` on a worker thread with the GIL released. Every 50 ms the calling thread
/// takes the GIL to process signals (Ctrl-C sets the cancel flag and re-raises) and to call
/// `tick` (progress, results as they come); an error from `tick` also cancels the work and is
/// raised. `tick` runs once more after the work ends. A panic in the worker becomes a
/// `SolverError` instead of crossing into Python.
pub(crate) fn run_detached<'py, T: Send>(
    py: Python<'py>,
    mut tick: impl FnMut(Python<'py>, &vtb::Control) -> PyResult<()>,
    work: impl FnOnce(&vtb::Control) -> T + Send,
) -> PyResult<T> {
    let control = vtb::Control::new();
    std::thread::scope(|s| {
        let handle = s.spawn(|| work(&control));
        loop {
            let finished = py.detach(|| {
                for _ in 0..10 {
                    if handle.is_finished() {
                        return true;
                    }
                    std::thread::sleep(Duration::from_millis(5));
                }
                handle.is_finished()
            });
            if let Err(e) = py.check_signals().and_then(|_| tick(py, &control)) {
                control.cancel();
                let _ = py.detach(|| handle.join());
                return Err(e);
            }
            if finished {
                break;
            }
        }
        let joined = py.detach(|| handle.join());
        joined.map_err(|panic| {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown".into());
            to_py_err(py, VtbError::Solver(format!("internal error: {what}")))
        })
    })
}
