//! Signal processing the core shares with Python: the band-limited indices' low-pass.

use crate::errors::to_py_err;
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use vtb::VtbError;

/// `x` (sampled every `dt` s) low-passed at `band_limit` Hz by the core's zero-phase filter,
/// the one every band-limited index uses.
#[pyfunction]
pub(crate) fn low_pass<'py>(
    py: Python<'py>,
    x: PyReadonlyArray1<'_, f64>,
    band_limit: f64,
    dt: f64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    if !(dt.is_finite() && dt > 0.0) {
        return Err(to_py_err(
            py,
            VtbError::config("dt", format!("{dt:?}"), "must be a finite number > 0"),
        ));
    }
    vtb::outputs::filter::check("band_limit", band_limit, dt).map_err(|e| to_py_err(py, e))?;
    let x = x.as_slice()?;
    if let Some(v) = x.iter().find(|v| !v.is_finite()) {
        return Err(to_py_err(
            py,
            VtbError::config("x", format!("{v:?}"), "every sample must be finite"),
        ));
    }
    Ok(PyArray1::from_vec(
        py,
        vtb::outputs::filter::low_pass(x, band_limit, dt),
    ))
}
