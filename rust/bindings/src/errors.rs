//! Core errors as the exception classes of `vtb.errors` (documented in Python): a
//! `ConfigError` keeps the field path, the value and the reason; a contact that does not
//! converge keeps where and how far; a cancelled run is a `KeyboardInterrupt`.

use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use vtb::VtbError;

/// `vtb.errors`, imported once per interpreter.
static ERRORS: PyOnceLock<Py<PyModule>> = PyOnceLock::new();

/// Raises the `vtb.errors` exception matching a core error.
pub(crate) fn to_py_err(py: Python<'_>, e: VtbError) -> PyErr {
    match make_exception(py, &e) {
        Ok(obj) => PyErr::from_value(obj),
        Err(err) => err,
    }
}

/// The exception instance (not raised) for a core error.
pub(crate) fn make_exception<'py>(py: Python<'py>, e: &VtbError) -> PyResult<Bound<'py, PyAny>> {
    let errors = ERRORS
        .get_or_try_init(py, || Ok::<_, PyErr>(py.import("vtb.errors")?.unbind()))?
        .bind(py);
    let msg = e.to_string();
    match e {
        VtbError::Config {
            field,
            value,
            reason,
        } => errors.getattr("ConfigError")?.call1((
            msg,
            field.as_str(),
            value.as_str(),
            reason.as_str(),
        )),
        VtbError::ContactNotConverged {
            time,
            step,
            residual,
            iterations,
        } => errors
            .getattr("ConvergenceError")?
            .call1((msg, *time, *step, *residual, *iterations)),
        VtbError::Solver(_) => errors.getattr("SolverError")?.call1((msg,)),
        VtbError::Cancelled => Ok(pyo3::exceptions::PyKeyboardInterrupt::new_err(msg)
            .into_value(py)
            .into_bound(py)
            .into_any()),
    }
}
