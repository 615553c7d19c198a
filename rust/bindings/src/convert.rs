//! Conversions between Python values and the core's: configurations (JSON text), numpy
//! arrays, profiles and run results.

use crate::errors::to_py_err;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use vtb::{Config, Profile, RunResult};

pub(crate) fn parse_config(py: Python<'_>, json: &str) -> PyResult<Config> {
    Config::from_json(json).map_err(|e| to_py_err(py, e))
}

pub(crate) fn to_vec(v: &PyReadonlyArray1<'_, f64>) -> PyResult<Vec<f64>> {
    Ok(v.as_slice()
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?
        .to_vec())
}

/// A profile from its grid, the rail's samples and the wheels' tread rows (empty = round).
pub(crate) fn make_profile(
    x0: f64,
    dx: f64,
    values: Option<PyReadonlyArray1<'_, f64>>,
    treads: Vec<PyReadonlyArray1<'_, f64>>,
) -> PyResult<Profile> {
    Ok(match values {
        None => Profile::flat(),
        Some(v) => Profile {
            x0,
            dx,
            values: to_vec(&v)?,
            treads: treads.iter().map(to_vec).collect::<PyResult<_>>()?,
        },
    })
}

pub(crate) fn result_to_dict<'py>(py: Python<'py>, r: RunResult) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let steps = r.n_steps + 1;
    let (nl, np) = (r.layer_names.len(), r.points.len());
    d.set_item("dt", r.dt)?;
    d.set_item("n_steps", r.n_steps)?;
    d.set_item("layer_names", r.layer_names.clone())?;
    d.set_item("points", r.points.clone())?;
    d.set_item("metrics", r.metrics())?;
    d.set_item(
        "disp",
        PyArray1::from_vec(py, r.disp).reshape([steps, nl, np])?,
    )?;
    d.set_item(
        "acc",
        PyArray1::from_vec(py, r.acc).reshape([steps, nl, np])?,
    )?;
    d.set_item(
        "vehicle_disp",
        PyArray1::from_vec(py, r.vehicle_disp).reshape([steps, r.n_cars, r.vehicle_dofs])?,
    )?;
    d.set_item(
        "vehicle_acc",
        PyArray1::from_vec(py, r.vehicle_acc).reshape([steps, r.n_cars, r.vehicle_dofs])?,
    )?;
    d.set_item(
        "contact_force",
        PyArray1::from_vec(py, r.contact_force).reshape([steps, r.n_wheels])?,
    )?;
    d.set_item(
        "pad_force",
        PyArray1::from_vec(py, r.pad_force).reshape([steps, r.n_pads])?,
    )?;
    let losses = PyList::empty(py);
    for l in &r.contact_loss {
        losses.append((l.wheel, l.t_start, l.t_end))?;
    }
    d.set_item("contact_loss", losses)?;
    Ok(d)
}
