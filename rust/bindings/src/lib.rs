//! `vtb._core`: the Python binding of the vtb core. It converts configurations (JSON text
//! produced by the Python dataclasses) and numpy arrays, maps core errors onto the exception
//! classes of `vtb.errors`, and runs the work with the GIL released on a worker thread while
//! the calling thread watches for Ctrl-C and reports progress.
//!
//! Layout: `errors` (core errors → exceptions), `detach` (GIL release, Ctrl-C, progress),
//! `convert` (JSON, numpy, results), `api/` (the module's functions by what they serve).

mod api;
mod convert;
mod detach;
mod errors;

use pyo3::prelude::*;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(api::config::preset, m)?)?;
    m.add_function(wrap_pyfunction!(api::config::train_library, m)?)?;
    m.add_function(wrap_pyfunction!(api::config::vehicle_models, m)?)?;
    m.add_function(wrap_pyfunction!(api::config::wheel_travel, m)?)?;
    m.add_function(wrap_pyfunction!(api::config::validate, m)?)?;
    m.add_function(wrap_pyfunction!(api::run::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(api::structure::matrices, m)?)?;
    m.add_function(wrap_pyfunction!(api::structure::fesea, m)?)?;
    m.add_function(wrap_pyfunction!(api::structure::shapes, m)?)?;
    m.add_function(wrap_pyfunction!(api::run::batch, m)?)?;
    m.add_function(wrap_pyfunction!(api::config::schema, m)?)?;
    m.add_function(wrap_pyfunction!(api::config::index_names, m)?)?;
    m.add_function(wrap_pyfunction!(api::config::index_catalog, m)?)?;
    m.add_function(wrap_pyfunction!(api::config::model_key, m)?)?;
    m.add_function(wrap_pyfunction!(api::config::check_schema, m)?)?;
    m.add_function(wrap_pyfunction!(api::signal::low_pass, m)?)?;
    m.add_function(wrap_pyfunction!(api::structure::resolved_bands, m)?)?;
    m.add_function(wrap_pyfunction!(api::structure::synthesis_build, m)?)?;
    m.add_function(wrap_pyfunction!(api::structure::patch_half_length, m)?)?;
    m.add_class::<api::run::Reduction>()?;
    m.add_class::<api::run::Substructures>()?;
    m.add_class::<api::structure::SpdSolver>()?;
    m.add_function(wrap_pyfunction!(api::config::plausible_ranges, m)?)?;
    m.add_function(wrap_pyfunction!(api::config::check_plausible, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("RESULTS_EPOCH", vtb::RESULTS_EPOCH)?;
    m.add("DEFAULT_LANES", vtb::engine::DEFAULT_LANES)?;
    m.add("SYNTHESIS_LANES", vtb::engine::SYNTHESIS_LANES)?;
    {
        use vtb::model::resolution as s;
        m.add("SYNTHESIS_BASIS_RATIO", s::BASIS_RATIO)?;
        m.add("SYNTHESIS_RESIDUAL_REACH", s::RESIDUAL_REACH)?;
        m.add("SYNTHESIS_RESIDUAL_TAPER", s::RESIDUAL_TAPER)?;
        m.add("SYNTHESIS_STEP_REACH", s::STEP_REACH)?;
        m.add("SYNTHESIS_BAND_SHARE", s::SYNTHESIS_BAND_SHARE)?;
        m.add("SUBSTRUCTURE_BAND_SHARE", s::SUBSTRUCTURE_BAND_SHARE)?;
    }
    m.add("MIN_BINS_PER_BAND", vtb::outputs::bands::MIN_BINS_PER_BAND)?;
    m.add("ACC_REFERENCE", vtb::outputs::bands::ACC_REFERENCE)?;
    Ok(())
}
