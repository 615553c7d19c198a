//! `vtb._core`: the Python binding of the vtb core. It converts configurations (JSON text
//! produced by the Python dataclasses) and numpy arrays, maps core errors onto the exception
//! classes of `vtb.errors`, and runs the work with the GIL released on a worker thread while
//! the calling thread watches for Ctrl-C and reports progress.

use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use vtb::{BatchOptions, Config, Job, Profile, Record, RunResult, VtbError};

/// Raises the `vtb.errors` exception matching a core error.
fn to_py_err(py: Python<'_>, e: VtbError) -> PyErr {
    match make_exception(py, &e) {
        Ok(obj) => PyErr::from_value(obj),
        Err(err) => err,
    }
}

/// The exception instance (not raised) for a core error.
fn make_exception<'py>(py: Python<'py>, e: &VtbError) -> PyResult<Bound<'py, PyAny>> {
    let errors = py.import("vtb.errors")?;
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

/// Runs `work` on a worker thread with the GIL released. Every 50 ms the calling thread
/// takes the GIL to process signals (Ctrl-C sets the cancel flag and re-raises) and to call
/// `tick` (progress, results as they come); an error from `tick` also cancels the work and is
/// raised. `tick` runs once more after the work ends. A panic in the worker becomes a
/// `SolverError` instead of crossing into Python.
fn run_detached<'py, T: Send>(
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
            let errors = py
                .import("vtb.errors")
                .and_then(|m| m.getattr("SolverError"));
            match errors.and_then(|cls| cls.call1((format!("internal error: {what}"),))) {
                Ok(obj) => PyErr::from_value(obj),
                Err(e) => e,
            }
        })
    })
}

fn parse_config(py: Python<'_>, json: &str) -> PyResult<Config> {
    Config::from_json(json).map_err(|e| to_py_err(py, e))
}

fn to_vec(v: &PyReadonlyArray1<'_, f64>) -> PyResult<Vec<f64>> {
    Ok(v.as_slice()
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?
        .to_vec())
}

/// A profile from its grid, the rail's samples and the wheels' tread rows (empty = round).
fn make_profile(
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

fn result_to_dict<'py>(py: Python<'py>, r: RunResult) -> PyResult<Bound<'py, PyDict>> {
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
    let losses = PyList::empty(py);
    for l in &r.contact_loss {
        losses.append((l.wheel, l.t_start, l.t_end))?;
    }
    d.set_item("contact_loss", losses)?;
    Ok(d)
}

/// The stretch (m) the wheels of a run roll over (`Config::wheel_travel`); `None` when the
/// configuration does not parse or has no vehicles.
#[pyfunction]
fn wheel_travel(config_json: &str) -> Option<(f64, f64)> {
    let cfg = vtb::Config::from_json(config_json).ok()?;
    if !(cfg.solver.dt > 0.0 && cfg.t_end().is_finite())
        || cfg.t_end() / cfg.solver.dt > vtb::config::MAX_STEPS as f64
    {
        return None;
    }
    cfg.wheel_travel()
}

/// The train library (`vtb::trains::library`) as JSON.
#[pyfunction]
fn train_library() -> String {
    serde_json::to_string(&vtb::trains::library()).expect("the library serialises")
}

/// Each vehicle model's DOF names and wheel count: `{name: (dofs, wheels)}`.
#[pyfunction]
fn vehicle_models() -> std::collections::BTreeMap<&'static str, (Vec<&'static str>, usize)> {
    vtb::vehicle::VehicleKind::ALL
        .iter()
        .map(|k| (k.name(), k.layout()))
        .collect()
}

/// The JSON configuration of a named preset (`"paper"`).
#[pyfunction]
fn preset(py: Python<'_>, name: &str) -> PyResult<String> {
    vtb::presets::by_name(name)
        .map(|c| c.to_json())
        .ok_or_else(|| {
            to_py_err(
                py,
                VtbError::config(
                    "preset",
                    name,
                    format!("unknown preset (known: {:?})", vtb::presets::PRESETS),
                ),
            )
        })
}

/// Validates a JSON configuration against an irregularity profile; raises on the first
/// problem.
#[pyfunction]
#[pyo3(signature = (config_json, profile_x0=0.0, profile_dx=1.0, profile=None, treads=Vec::new()))]
fn validate(
    py: Python<'_>,
    config_json: &str,
    profile_x0: f64,
    profile_dx: f64,
    profile: Option<PyReadonlyArray1<'_, f64>>,
    treads: Vec<PyReadonlyArray1<'_, f64>>,
) -> PyResult<()> {
    let cfg = parse_config(py, config_json)?;
    let p = make_profile(profile_x0, profile_dx, profile, treads)?;
    cfg.validate(&p).map_err(|e| to_py_err(py, e))
}

/// The assembled structure matrices M, K, C of a configuration as COO triplets
/// (rows, cols, values) with their dimension, plus each layer's DOF offset.
#[pyfunction]
fn matrices<'py>(py: Python<'py>, config_json: &str) -> PyResult<Bound<'py, PyDict>> {
    let cfg = parse_config(py, config_json)?;
    let model = vtb::Model::new(cfg, Profile::flat()).map_err(|e| to_py_err(py, e))?;
    let st = &model.structure;
    let d = PyDict::new(py);
    d.set_item("n", st.n_dofs)?;
    for (name, m) in [("m", &st.m), ("k", &st.k), ("c", &st.c)] {
        let mut rows = Vec::with_capacity(m.nnz());
        for i in 0..m.n {
            rows.extend(std::iter::repeat_n(
                i as i64,
                m.row_ptr[i + 1] - m.row_ptr[i],
            ));
        }
        let cols: Vec<i64> = m.col_idx.iter().map(|&c| c as i64).collect();
        d.set_item(
            name,
            (
                PyArray1::from_vec(py, rows),
                PyArray1::from_vec(py, cols),
                PyArray1::from_vec(py, m.values.clone()),
            ),
        )?;
    }
    d.set_item(
        "layer_offsets",
        st.layers
            .iter()
            .map(|l| (l.name.clone(), l.offset, l.n_dofs()))
            .collect::<Vec<_>>(),
    )?;
    Ok(d)
}

/// Shape vectors of layer `layer` (index, top = 0) at the positions `xs` (m), in the
/// structure's DOF numbering: (starts, values) with values of shape (len(xs), width); row i is
/// nonzero on the DOFs starts[i] .. starts[i] + width. The hybrid rail's vectors carry the
/// FE–SEA correction, exactly as the wheels and the outputs see them.
#[pyfunction]
fn shapes<'py>(
    py: Python<'py>,
    config_json: &str,
    layer: usize,
    xs: PyReadonlyArray1<'_, f64>,
) -> PyResult<(Bound<'py, PyArray1<i64>>, Bound<'py, PyArray2<f64>>)> {
    let cfg = parse_config(py, config_json)?;
    let model = vtb::Model::new(cfg, Profile::flat()).map_err(|e| to_py_err(py, e))?;
    let st = &model.structure;
    if layer >= st.layers.len() {
        return Err(to_py_err(
            py,
            VtbError::config("layer", layer, "no such layer index"),
        ));
    }
    let xs = xs
        .as_slice()
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    let width = st.layers[layer].basis.shape_len();
    let mut starts = Vec::with_capacity(xs.len());
    let mut values = Vec::with_capacity(xs.len() * width);
    for (i, &x) in xs.iter().enumerate() {
        let (a, b) = st.layers[layer].extent();
        if !(x.is_finite() && (a..=b).contains(&x)) {
            return Err(to_py_err(
                py,
                VtbError::config(
                    &format!("x[{i}]"),
                    x,
                    format!(
                        "must lie on layer {:?}, {a} ≤ x ≤ {b}",
                        st.layers[layer].name
                    ),
                ),
            ));
        }
        let s = st.shape(layer, x);
        starts.push(s.start as i64);
        values.extend_from_slice(&s.values);
    }
    let values = PyArray1::from_vec(py, values).reshape([xs.len(), width])?;
    Ok((PyArray1::from_vec(py, starts), values))
}

/// The FE–SEA correction of a hybrid configuration: ω_r, the resonant band, the modal
/// density, ΔM/ΔK/ΔC on the rail's cubic DOFs and every local mode's properties.
#[pyfunction]
fn fesea<'py>(py: Python<'py>, config_json: &str) -> PyResult<Bound<'py, PyDict>> {
    let cfg = parse_config(py, config_json)?;
    let model = vtb::Model::new(cfg, Profile::flat()).map_err(|e| to_py_err(py, e))?;
    let Some(fs) = &model.structure.fesea else {
        return Err(to_py_err(
            py,
            VtbError::config(
                "discretisation.method",
                format!("{:?}", model.cfg.discretisation.method).to_lowercase(),
                "the FE–SEA correction exists for the hybrid method only",
            ),
        ));
    };
    let d = PyDict::new(py);
    d.set_item("coupling", format!("{:?}", fs.coupling).to_lowercase())?;
    d.set_item("omega_r", fs.omega_r)?;
    d.set_item("band", fs.band)?;
    d.set_item("modal_density", fs.modal_density())?;
    d.set_item("dofs", fs.dofs.to_vec())?;
    for (name, m) in [
        ("delta_m", &fs.delta_m),
        ("delta_k", &fs.delta_k),
        ("delta_c", &fs.delta_c),
    ] {
        d.set_item(name, m.iter().map(|r| r.to_vec()).collect::<Vec<_>>())?;
    }
    let modes = PyDict::new(py);
    let col =
        |f: &dyn Fn(&vtb::fesea::LocalMode) -> f64| fs.modes.iter().map(f).collect::<Vec<f64>>();
    modes.set_item(
        "index",
        fs.modes.iter().map(|m| m.index as i64).collect::<Vec<_>>(),
    )?;
    modes.set_item("frequency", PyArray1::from_vec(py, col(&|m| m.frequency)))?;
    modes.set_item("omega", PyArray1::from_vec(py, col(&|m| m.omega)))?;
    modes.set_item("mass", PyArray1::from_vec(py, col(&|m| m.mass)))?;
    modes.set_item("stiffness", PyArray1::from_vec(py, col(&|m| m.stiffness)))?;
    modes.set_item("damping", PyArray1::from_vec(py, col(&|m| m.damping)))?;
    modes.set_item(
        "loss_factor",
        PyArray1::from_vec(py, col(&|m| m.loss_factor)),
    )?;
    modes.set_item(
        "class",
        fs.modes
            .iter()
            .map(|m| format!("{:?}", m.class).to_lowercase())
            .collect::<Vec<_>>(),
    )?;
    d.set_item("modes", modes)?;
    Ok(d)
}

/// A structure's complex-modal reduction held by the core (built by `vtb.synthesis`): the
/// arrays are converted once and shared by every run that is given it.
#[pyclass(frozen, module = "vtb._core")]
struct Reduction(Arc<vtb::synthesis::Reduction>);

#[pymethods]
impl Reduction {
    #[new]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        n_dofs: usize,
        lambda_re: PyReadonlyArray1<'_, f64>,
        lambda_im: PyReadonlyArray1<'_, f64>,
        weight: PyReadonlyArray1<'_, f64>,
        psi_re: PyReadonlyArray1<'_, f64>,
        psi_im: PyReadonlyArray1<'_, f64>,
        rail_dofs: usize,
        band: usize,
        residual: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Self> {
        let v = |a: PyReadonlyArray1<'_, f64>| a.as_array().to_vec();
        vtb::synthesis::Reduction::new(
            n_dofs,
            v(lambda_re),
            v(lambda_im),
            v(weight),
            v(psi_re),
            v(psi_im),
            rail_dofs,
            band,
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

    /// The reduction's static flexibility sᵀK⁻¹s at rail shapes (start, values) pairs.
    fn static_flexibility(&self, start: usize, values: Vec<f64>) -> f64 {
        let s = vtb::basis::Shape { start, values };
        self.0.static_flexibility(&s, &s)
    }
}

/// Runs one configuration; returns a dict of histories and metrics. `progress(done, total)`
/// (steps) is called from the calling thread every 50 ms while it runs.
#[pyfunction]
#[pyo3(signature = (config_json, profile_x0=0.0, profile_dx=1.0, profile=None, treads=Vec::new(), reduction=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn simulate<'py>(
    py: Python<'py>,
    config_json: &str,
    profile_x0: f64,
    profile_dx: f64,
    profile: Option<PyReadonlyArray1<'_, f64>>,
    treads: Vec<PyReadonlyArray1<'_, f64>>,
    reduction: Option<&Reduction>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let cfg = parse_config(py, config_json)?;
    let p = make_profile(profile_x0, profile_dx, profile, treads)?;
    let red = reduction.map(|r| Arc::clone(&r.0));
    let out = run_detached(
        py,
        |_, control| match &progress {
            Some(f) => f.call1(control.progress()).map(|_| ()),
            None => Ok(()),
        },
        |control| vtb::simulate_with(&cfg, &p, red.as_deref(), Some(control)),
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
#[pyo3(signature = (configs, profiles, profile_index, threads=0, progress=None, histories=false, max_lanes=vtb::simulate::DEFAULT_LANES, reduction=None, on_result=None))]
#[allow(clippy::too_many_arguments)]
fn batch<'py>(
    py: Python<'py>,
    configs: Vec<String>,
    profiles: Vec<(
        f64,
        f64,
        Option<PyReadonlyArray1<'_, f64>>,
        Vec<PyReadonlyArray1<'_, f64>>,
    )>,
    profile_index: Vec<usize>,
    threads: usize,
    progress: Option<Bound<'py, PyAny>>,
    histories: bool,
    max_lanes: usize,
    reduction: Option<&Reduction>,
    on_result: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyList>> {
    let red = reduction.map(|r| Arc::clone(&r.0));
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
        pool.install(|| vtb::run_batch_each(&jobs, opts, red.as_deref(), Some(cancel), &sink))
    })?;
    let out = PyList::empty(py);
    for item in items {
        out.append(item.expect("every configuration has a result"))?;
    }
    Ok(out)
}

/// Parses a JSON configuration against the schema (types, ranges, unknown and missing
/// fields) without validating its values; raises naming the field.
#[pyfunction]
fn check_schema(py: Python<'_>, config_json: &str) -> PyResult<()> {
    parse_config(py, config_json).map(|_| ())
}

/// The JSON schema of the configuration (fields, types, defaults, docs) from the core's
/// serde types: the single definition of the configuration.
#[pyfunction]
fn schema() -> String {
    Config::schema()
}

/// Every index a run of the configuration can report (what `output.indices` may name).
#[pyfunction]
fn index_names(py: Python<'_>, config_json: &str) -> PyResult<Vec<String>> {
    Ok(vtb::results::index_names(&parse_config(py, config_json)?))
}

/// The key under which the core lets jobs share one model (and run in lockstep): their
/// configurations equal up to the dampers' parameters.
#[pyfunction]
fn model_key(py: Python<'_>, config_json: &str) -> PyResult<String> {
    Ok(vtb::simulate::model_key(&parse_config(py, config_json)?))
}

/// `x` (sampled every `dt` s) low-passed at `band_limit` Hz by the core's zero-phase filter,
/// the one every band-limited index uses.
#[pyfunction]
fn low_pass<'py>(
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
    vtb::filter::check("band_limit", band_limit, dt).map_err(|e| to_py_err(py, e))?;
    let x = x.as_slice()?;
    if let Some(v) = x.iter().find(|v| !v.is_finite()) {
        return Err(to_py_err(
            py,
            VtbError::config("x", format!("{v:?}"), "every sample must be finite"),
        ));
    }
    Ok(PyArray1::from_vec(
        py,
        vtb::filter::low_pass(x, band_limit, dt),
    ))
}

/// The band each layer of a configuration resolves (`vtb::resolution`): a list of dicts
/// (layer, f_max, basis_f_max, time_f_max in Hz; shortest_wavelength in m), top layer first,
/// and the top layer's pinned–pinned frequency (Hz, or None).
#[pyfunction]
fn resolved_bands<'py>(
    py: Python<'py>,
    config_json: &str,
) -> PyResult<(Bound<'py, PyList>, Option<f64>)> {
    let cfg = parse_config(py, config_json)?;
    cfg.validate(&Profile::flat())
        .map_err(|e| to_py_err(py, e))?;
    let out = PyList::empty(py);
    for b in vtb::resolution::resolved_bands(&cfg) {
        let d = PyDict::new(py);
        d.set_item("layer", b.layer)?;
        d.set_item("f_max", b.f_max)?;
        d.set_item("basis_f_max", b.basis_f_max)?;
        d.set_item("time_f_max", b.time_f_max)?;
        d.set_item("shortest_wavelength", b.shortest_wavelength)?;
        out.append(d)?;
    }
    Ok((out, vtb::resolution::pinned_pinned_frequency(&cfg)))
}

/// Half-length (m) along the rail of the Hertz contact patch of a steel wheel of rolling
/// radius `wheel_radius` (m) on a steel rail head of crown radius `rail_radius` (m) under
/// `load` (N) (`vtb::contact::patch_half_length`).
#[pyfunction]
fn patch_half_length(
    py: Python<'_>,
    load: f64,
    wheel_radius: f64,
    rail_radius: f64,
) -> PyResult<f64> {
    for (field, v) in [
        ("load", load),
        ("wheel_radius", wheel_radius),
        ("rail_crown_radius", rail_radius),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(to_py_err(
                py,
                VtbError::config(field, format!("{v:?}"), "must be a finite number > 0"),
            ));
        }
    }
    Ok(vtb::contact::patch_half_length(
        load,
        wheel_radius,
        rail_radius,
    ))
}

/// Refuses a configuration with an implausible value (a likely unit mistake), naming it.
#[pyfunction]
fn check_plausible(py: Python<'_>, config_json: &str) -> PyResult<()> {
    let cfg = parse_config(py, config_json)?;
    vtb::plausibility::check(&cfg).map_err(|e| to_py_err(py, e))
}

/// The plausible ranges of the physical fields: (field, min, max, unit, covers) rows.
#[pyfunction]
fn plausible_ranges() -> Vec<(&'static str, f64, f64, &'static str, &'static str)> {
    vtb::plausibility::table()
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(preset, m)?)?;
    m.add_function(wrap_pyfunction!(train_library, m)?)?;
    m.add_function(wrap_pyfunction!(vehicle_models, m)?)?;
    m.add_function(wrap_pyfunction!(wheel_travel, m)?)?;
    m.add_function(wrap_pyfunction!(validate, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(matrices, m)?)?;
    m.add_function(wrap_pyfunction!(fesea, m)?)?;
    m.add_function(wrap_pyfunction!(shapes, m)?)?;
    m.add_function(wrap_pyfunction!(batch, m)?)?;
    m.add_function(wrap_pyfunction!(schema, m)?)?;
    m.add_function(wrap_pyfunction!(index_names, m)?)?;
    m.add_function(wrap_pyfunction!(model_key, m)?)?;
    m.add_function(wrap_pyfunction!(check_schema, m)?)?;
    m.add_function(wrap_pyfunction!(low_pass, m)?)?;
    m.add_function(wrap_pyfunction!(resolved_bands, m)?)?;
    m.add_function(wrap_pyfunction!(patch_half_length, m)?)?;
    m.add_class::<Reduction>()?;
    m.add_function(wrap_pyfunction!(plausible_ranges, m)?)?;
    m.add_function(wrap_pyfunction!(check_plausible, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("DEFAULT_LANES", vtb::simulate::DEFAULT_LANES)?;
    m.add("SYNTHESIS_LANES", vtb::simulate::SYNTHESIS_LANES)?;
    m.add("MIN_BINS_PER_BAND", vtb::bands::MIN_BINS_PER_BAND)?;
    m.add("ACC_REFERENCE", vtb::bands::ACC_REFERENCE)?;
    Ok(())
}
