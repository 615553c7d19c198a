//! Runs: one configuration, a batch of many, and the shared modal reduction.

use crate::convert::{make_profile, parse_config, result_to_dict};
use crate::detach::run_detached;
use crate::errors::{make_exception, to_py_err};
use numpy::{
    Complex64, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::sync::{Arc, Mutex};

/// A profile as the batch receives it: (x0, dx, values, one tread row per wheel).
type ProfileArrays<'a> = (
    f64,
    f64,
    Option<PyReadonlyArray1<'a, f64>>,
    Vec<PyReadonlyArray1<'a, f64>>,
);
use vtb::{BatchOptions, Config, Job, Profile, Record, RunResult, VtbError};

/// A structure's complex-modal reduction held by the core (built by `vtb.synthesis`): the
/// arrays are converted once and shared by every run that is given it.
#[pyclass(frozen, module = "vtb._core")]
pub(crate) struct Reduction(Arc<vtb::engine::synthesis::Reduction>);

#[pymethods]
impl Reduction {
    #[new]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        lambda_re: PyReadonlyArray1<'_, f64>,
        lambda_im: PyReadonlyArray1<'_, f64>,
        weight: PyReadonlyArray1<'_, f64>,
        psi: PyReadonlyArray2<'_, Complex64>,
        rail_dofs: usize,
        band: usize,
        step_band: usize,
        residual: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Self> {
        let v = |a: PyReadonlyArray1<'_, f64>| a.as_array().to_vec();
        // ψ read in place when in C order (the core's padded copy is then the only other one);
        // any other layout is copied in C order first.
        let n_dofs = psi.shape()[0];
        let owned: Vec<f64>;
        let psi: &[f64] = if psi.is_c_contiguous() {
            bytemuck::cast_slice(psi.as_slice()?)
        } else {
            owned = psi.as_array().iter().flat_map(|z| [z.re, z.im]).collect();
            &owned
        };
        vtb::engine::synthesis::Reduction::new(
            n_dofs,
            v(lambda_re),
            v(lambda_im),
            v(weight),
            psi,
            rail_dofs,
            band,
            step_band,
            v(residual),
        )
        .map(|r| Self(Arc::new(r)))
        .map_err(|e| to_py_err(py, e))
    }

    #[getter]
    fn n_modes(&self) -> usize {
        self.0.n_modes()
    }

    #[getter]
    fn nbytes(&self) -> usize {
        self.0.bytes()
    }

    /// Rows of ψ at the DOFs `rows`: (re, im), each `len(rows)` × modes.
    #[allow(clippy::type_complexity)]
    fn psi_rows<'py>(
        &self,
        py: Python<'py>,
        rows: Vec<usize>,
    ) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>)> {
        let (re, im) = self.0.psi_rows(&rows).map_err(|e| to_py_err(py, e))?;
        let shape = [rows.len(), self.0.n_modes()];
        Ok((
            PyArray1::from_vec(py, re).reshape(shape)?,
            PyArray1::from_vec(py, im).reshape(shape)?,
        ))
    }

    /// The reduction's static flexibility sᵀK⁻¹s at rail shapes (start, values) pairs.
    fn static_flexibility(&self, start: usize, values: Vec<f64>) -> f64 {
        let s = vtb::model::basis::Shape { start, values };
        self.0.static_flexibility(&s, &s)
    }

    /// (α, β) of the residual's filter 1/(1 + αs + βs²) under a load of rail shape (start,
    /// values), as the engine steps it; `None` where there is no residual.
    fn residual_filter(
        &self,
        py: Python<'_>,
        start: usize,
        values: Vec<f64>,
    ) -> PyResult<Option<(f64, f64)>> {
        let s = vtb::model::basis::Shape { start, values };
        let at = || format!("a load at rail DOF {start}");
        self.0
            .load_moments(&s, at)
            .and_then(|r| vtb::engine::Filter::from_moments(r, at))
            .map(|f| f.map(|f| (f.alpha, f.beta)))
            .map_err(|e| to_py_err(py, e))
    }
}

/// A structure's substructured coordinates held by the core (built by
/// `vtb.run.substructures`): shared by every run that is given it.
#[pyclass(frozen, module = "vtb._core")]
pub(crate) struct Substructures(Arc<vtb::model::substructures::Substructured>);

#[pymethods]
impl Substructures {
    /// From the Python layer's parts (`vtb::model::substructures::Parts`, field by field);
    /// `matrices` is ((rows, cols, values) of M, C, K); `residual` each group's rows ×
    /// (`residual_band` + 1) band of its residual flexibility, one group after another.
    #[new]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        dof_piece: PyReadonlyArray1<'_, i64>,
        dof_index: PyReadonlyArray1<'_, i64>,
        piece_group: Vec<usize>,
        piece_modes: Vec<usize>,
        bound_ptr: Vec<usize>,
        bound: Vec<usize>,
        group_rows: Vec<usize>,
        group_modes: Vec<usize>,
        group_bound: Vec<usize>,
        phi: PyReadonlyArray1<'_, f64>,
        psi: PyReadonlyArray1<'_, f64>,
        n: usize,
        matrices: [(Vec<usize>, Vec<usize>, PyReadonlyArray1<'_, f64>); 3],
        residual: PyReadonlyArray1<'_, f64>,
        residual_band: usize,
    ) -> PyResult<Self> {
        let parts = vtb::model::substructures::Parts {
            dof_piece: dof_piece.as_array().to_vec(),
            dof_index: dof_index.as_array().to_vec(),
            piece_group,
            piece_modes,
            bound_ptr,
            bound,
            group_rows,
            group_modes,
            group_bound,
            phi: phi.as_array().to_vec(),
            psi: psi.as_array().to_vec(),
            n,
            matrices: matrices.map(|(r, c, v)| (r, c, v.as_array().to_vec())),
            residual: residual.as_array().to_vec(),
            residual_band,
        };
        vtb::model::substructures::Substructured::new(parts)
            .map(|s| Self(Arc::new(s)))
            .map_err(|e| to_py_err(py, e))
    }

    /// Reduced DOFs (the layers').
    #[getter]
    fn n(&self) -> usize {
        self.0.n
    }
}

/// A run's reduction as handed in: a `Reduction` or `Substructures` (or None).
enum Held {
    Modes(Arc<vtb::engine::synthesis::Reduction>),
    Substructures(Arc<vtb::model::substructures::Substructured>),
}

impl Held {
    fn of(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Self>> {
        let Some(obj) = obj else { return Ok(None) };
        if let Ok(r) = obj.cast::<Reduction>() {
            return Ok(Some(Held::Modes(Arc::clone(&r.get().0))));
        }
        if let Ok(s) = obj.cast::<Substructures>() {
            return Ok(Some(Held::Substructures(Arc::clone(&s.get().0))));
        }
        Err(pyo3::exceptions::PyTypeError::new_err(
            "reduction must be a vtb._core.Reduction or vtb._core.Substructures",
        ))
    }

    fn as_reduced(&self) -> vtb::Reduced<'_> {
        match self {
            Held::Modes(r) => vtb::Reduced::Modes(r),
            Held::Substructures(s) => vtb::Reduced::Substructures(s),
        }
    }
}

/// Runs one configuration; returns a dict of histories and metrics. `progress(done, total)`
/// (steps) is called from the calling thread every 50 ms while it runs.
#[pyfunction]
#[pyo3(signature = (config_json, profile_x0=0.0, profile_dx=1.0, profile=None, treads=Vec::new(), reduction=None, progress=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn simulate<'py>(
    py: Python<'py>,
    config_json: &str,
    profile_x0: f64,
    profile_dx: f64,
    profile: Option<PyReadonlyArray1<'_, f64>>,
    treads: Vec<PyReadonlyArray1<'_, f64>>,
    reduction: Option<Bound<'py, PyAny>>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let cfg = parse_config(py, config_json)?;
    let p = make_profile(profile_x0, profile_dx, profile, treads)?;
    let red = Held::of(reduction.as_ref())?;
    let out = run_detached(
        py,
        |_, control| match &progress {
            Some(f) => f.call1(control.progress()).map(|_| ()),
            None => Ok(()),
        },
        |control| vtb::simulate_with(&cfg, &p, red.as_ref().map(Held::as_reduced), Some(control)),
    )?;
    let r = out.map_err(|e| to_py_err(py, e))?;
    result_to_dict(py, r)
}

/// Runs many configurations in parallel (rayon, `threads` workers, all cores when 0; jobs of
/// one model in lockstep groups) and returns, in order, each run's metrics dict (or with
/// `histories`, its full result dict) or its (unraised) exception. `profiles` are
/// (x0, dx, values, treads) shared by index through `profile_index`. From the calling thread,
/// as each lockstep group finishes: `on_result(i, item)` for each of its runs (i indexes
/// `configs`), then `progress(done)`.
#[pyfunction]
#[pyo3(signature = (configs, profiles, profile_index, threads=0, progress=None, histories=false, max_lanes=vtb::engine::DEFAULT_LANES, reduction=None, on_result=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn batch<'py>(
    py: Python<'py>,
    configs: Vec<String>,
    profiles: Vec<ProfileArrays<'_>>,
    profile_index: Vec<usize>,
    threads: usize,
    progress: Option<Bound<'py, PyAny>>,
    histories: bool,
    max_lanes: usize,
    reduction: Option<Bound<'py, PyAny>>,
    on_result: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyList>> {
    let red = Held::of(reduction.as_ref())?;
    if configs.len() != profile_index.len() {
        return Err(to_py_err(
            py,
            VtbError::config(
                "profile_index",
                profile_index.len(),
                format!("needs one entry per config ({})", configs.len()),
            ),
        ));
    }
    let shared: Vec<Arc<Profile>> = profiles
        .into_iter()
        .map(|(x0, dx, v, t)| make_profile(x0, dx, v, t).map(Arc::new))
        .collect::<PyResult<_>>()?;
    let mut jobs = Vec::with_capacity(configs.len());
    let mut items: Vec<Option<Bound<'py, PyAny>>> = vec![None; configs.len()];
    // The configuration each job runs (parse errors are results of their own).
    let mut job_config = Vec::with_capacity(configs.len());
    for (i, (text, &pi)) in configs.iter().zip(&profile_index).enumerate() {
        let profile = shared.get(pi).cloned().ok_or_else(|| {
            to_py_err(
                py,
                VtbError::config(
                    format!("profile_index[{i}]"),
                    pi,
                    format!("only {} profiles given", shared.len()),
                ),
            )
        })?;
        match Config::from_json(text) {
            Ok(config) => {
                jobs.push(Job { config, profile });
                job_config.push(i);
            }
            Err(e) => items[i] = Some(make_exception(py, &e)?),
        }
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    let finished: Mutex<Vec<(usize, vtb::Result<RunResult>)>> = Mutex::new(Vec::new());
    let mut done = 0;
    let tick = |py: Python<'py>, _: &vtb::Control| -> PyResult<()> {
        let ready = std::mem::take(&mut *finished.lock().unwrap_or_else(|e| e.into_inner()));
        if ready.is_empty() {
            return Ok(());
        }
        for (j, r) in ready {
            let i = job_config[j];
            let item = match r {
                Ok(r) if histories => result_to_dict(py, r)?.into_any(),
                Ok(r) => r.metrics().into_pyobject(py)?.into_any(),
                Err(VtbError::Cancelled) => {
                    return Err(pyo3::exceptions::PyKeyboardInterrupt::new_err("cancelled"));
                }
                Err(e) => make_exception(py, &e)?,
            };
            if let Some(cb) = &on_result {
                cb.call1((i, &item))?;
            }
            items[i] = Some(item);
            done += 1;
        }
        if let Some(cb) = &progress {
            cb.call1((done,))?;
        }
        Ok(())
    };
    run_detached(py, tick, |cancel| {
        let record = if histories {
            Record::Full
        } else {
            Record::Metrics
        };
        let opts = BatchOptions { record, max_lanes };
        let sink = |mut group: Vec<(usize, vtb::Result<RunResult>)>| {
            finished
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .append(&mut group);
        };
        pool.install(|| {
            vtb::run_batch_each(
                &jobs,
                opts,
                red.as_ref().map(Held::as_reduced),
                Some(cancel),
                &sink,
            )
        })
    })?;
    let out = PyList::empty(py);
    for item in items {
        out.append(item.expect("every configuration has a result"))?;
    }
    Ok(out)
}
