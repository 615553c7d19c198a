//! Configuration services: validation, schema, presets, libraries, index names, plausibility.

use crate::convert::{make_profile, parse_config};
use crate::errors::to_py_err;
use numpy::PyReadonlyArray1;
use pyo3::prelude::*;
use vtb::{Config, VtbError};

/// The stretch (m) the wheels of a run roll over (`Config::wheel_travel`); `None` when the
/// configuration does not parse or has no vehicles.
#[pyfunction]
pub(crate) fn wheel_travel(config_json: &str) -> Option<(f64, f64)> {
    let cfg = vtb::Config::from_json(config_json).ok()?;
    if !(cfg.solver.dt > 0.0 && cfg.t_end().is_finite())
        || cfg.t_end() / cfg.solver.dt > vtb::config::fields::MAX_STEPS as f64
    {
        return None;
    }
    cfg.wheel_travel()
}

/// The train library (`vtb::library::trains::library`) as JSON.
#[pyfunction]
pub(crate) fn train_library() -> String {
    serde_json::to_string(&vtb::library::trains::library()).expect("the library serialises")
}

/// Each vehicle model's DOF names and wheel count: `{name: (dofs, wheels)}`.
#[pyfunction]
pub(crate) fn vehicle_models()
-> std::collections::BTreeMap<&'static str, (Vec<&'static str>, usize)> {
    vtb::config::VehicleKind::ALL
        .iter()
        .map(|&k| (k.name(), vtb::model::vehicle::layout(k)))
        .collect()
}

/// The JSON configuration of a named preset (`"paper"`).
#[pyfunction]
pub(crate) fn preset(py: Python<'_>, name: &str) -> PyResult<String> {
    vtb::library::presets::by_name(name)
        .map(|c| c.to_json())
        .ok_or_else(|| {
            to_py_err(
                py,
                VtbError::config(
                    "preset",
                    name,
                    format!(
                        "unknown preset (known: {:?})",
                        vtb::library::presets::PRESETS
                    ),
                ),
            )
        })
}

/// Validates a JSON configuration against an irregularity profile; raises on the first
/// problem. `full`: also refuses a run whose full histories (`simulate`) exceed the budget.
#[pyfunction]
#[pyo3(signature = (config_json, profile_x0=0.0, profile_dx=1.0, profile=None, treads=Vec::new(), full=false))]
pub(crate) fn validate(
    py: Python<'_>,
    config_json: &str,
    profile_x0: f64,
    profile_dx: f64,
    profile: Option<PyReadonlyArray1<'_, f64>>,
    treads: Vec<PyReadonlyArray1<'_, f64>>,
    full: bool,
) -> PyResult<()> {
    let cfg = parse_config(py, config_json)?;
    let p = make_profile(profile_x0, profile_dx, profile, treads)?;
    vtb::check::validate(&cfg, &p).map_err(|e| to_py_err(py, e))?;
    if full {
        vtb::check::budget::check_histories(&cfg, vtb::outputs::Record::Full, 1)
            .map_err(|e| to_py_err(py, e))?;
    }
    Ok(())
}

/// Parses a JSON configuration against the schema (types, ranges, unknown and missing
/// fields) without validating its values; raises naming the field.
#[pyfunction]
pub(crate) fn check_schema(py: Python<'_>, config_json: &str) -> PyResult<()> {
    parse_config(py, config_json).map(|_| ())
}

/// The JSON schema of the configuration (fields, types, defaults, docs) from the core's
/// serde types: the single definition of the configuration.
#[pyfunction]
pub(crate) fn schema() -> String {
    Config::schema()
}

/// Every index a run of the configuration can report (what `output.indices` may name).
#[pyfunction]
pub(crate) fn index_names(py: Python<'_>, config_json: &str) -> PyResult<Vec<String>> {
    Ok(vtb::outputs::index_names(&parse_config(py, config_json)?))
}

/// The index catalogue: one `(pattern, unit, subject, band, description)` row per kind of
/// index (`vtb::outputs::catalog`).
#[pyfunction]
pub(crate) fn index_catalog() -> Vec<(
    &'static str,
    &'static str,
    &'static str,
    &'static str,
    &'static str,
)> {
    vtb::outputs::catalog::CATALOG
        .iter()
        .map(|k| {
            (
                k.pattern,
                k.unit,
                k.subject.name(),
                k.band.name(),
                k.description,
            )
        })
        .collect()
}

/// The key under which the core lets jobs share one model (and run in lockstep): their
/// configurations equal up to the dampers' parameters.
#[pyfunction]
pub(crate) fn model_key(py: Python<'_>, config_json: &str) -> PyResult<String> {
    Ok(vtb::engine::model_key(&parse_config(py, config_json)?))
}

/// Refuses a configuration with an implausible value (a likely unit mistake), naming it.
#[pyfunction]
pub(crate) fn check_plausible(py: Python<'_>, config_json: &str) -> PyResult<()> {
    let cfg = parse_config(py, config_json)?;
    vtb::check::plausibility::check(&cfg).map_err(|e| to_py_err(py, e))
}

/// The plausible ranges of the physical fields: (field, min, max, unit, covers) rows.
#[pyfunction]
pub(crate) fn plausible_ranges() -> Vec<(&'static str, f64, f64, &'static str, &'static str)> {
    vtb::check::plausibility::table()
}
