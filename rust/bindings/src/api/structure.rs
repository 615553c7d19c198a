//! The assembled structure and what it resolves: matrices, shapes, the FE–SEA data, the
//! resolved bands, the contact patch.

use crate::convert::parse_config;
use crate::errors::to_py_err;
use numpy::{
    PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use vtb::{Profile, VtbError};

/// (starts, values): the first DOF of each row and the rows' values.
type ShapeRows<'py> = (Bound<'py, PyArray1<i64>>, Bound<'py, PyArray2<f64>>);

/// The assembled structure matrices M, K, C of a configuration as COO triplets
/// (rows, cols, values) with their dimension, plus each layer's DOF offset and, for a
/// finite-element layer, its node positions (m).
#[pyfunction]
pub(crate) fn matrices<'py>(py: Python<'py>, config_json: &str) -> PyResult<Bound<'py, PyDict>> {
    let cfg = parse_config(py, config_json)?;
    let model = vtb::check::validated(cfg, Profile::flat()).map_err(|e| to_py_err(py, e))?;
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
    // Where each finite-element layer's DOFs sit: node j (DOFs 2j, 2j + 1) at x_j; None for
    // a modal layer, whose DOFs span its length (what a substructuring cuts by).
    let nodes = PyList::empty(py);
    for l in &st.layers {
        match &l.basis {
            vtb::model::basis::LayerBasis::Fem(f) => {
                nodes.append(PyArray1::from_vec(py, f.nodes.clone()))?
            }
            vtb::model::basis::LayerBasis::Modal(_) => nodes.append(py.None())?,
        }
    }
    d.set_item("layer_nodes", nodes)?;
    Ok(d)
}

/// Shape vectors of layer `layer` (index, top = 0) at the positions `xs` (m), in the
/// structure's DOF numbering: (starts, values) with values of shape (len(xs), width); row i is
/// nonzero on the DOFs starts[i] .. starts[i] + width. The hybrid rail's vectors carry the
/// FE–SEA correction, exactly as the wheels and the outputs see them. With `moment`, the
/// bending-moment vectors instead (N·m per unit DOF, sagging positive: `Layer::moment_shape`,
/// as the run records `deck_moment_max`).
#[pyfunction]
#[pyo3(signature = (config_json, layer, xs, moment = false))]
pub(crate) fn shapes<'py>(
    py: Python<'py>,
    config_json: &str,
    layer: usize,
    xs: PyReadonlyArray1<'_, f64>,
    moment: bool,
) -> PyResult<ShapeRows<'py>> {
    let cfg = parse_config(py, config_json)?;
    let model = vtb::check::validated(cfg, Profile::flat()).map_err(|e| to_py_err(py, e))?;
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
                    format!("x[{i}]"),
                    x,
                    format!(
                        "must lie on layer {:?}, {a} ≤ x ≤ {b}",
                        st.layers[layer].name
                    ),
                ),
            ));
        }
        let s = if moment {
            st.layers[layer].moment_shape(x)
        } else {
            st.shape(layer, x)
        };
        starts.push(s.start as i64);
        values.extend_from_slice(&s.values);
    }
    let values = PyArray1::from_vec(py, values).reshape([xs.len(), width])?;
    Ok((PyArray1::from_vec(py, starts), values))
}

/// The FE–SEA correction of a hybrid configuration: ω_r, the resonant band, the modal
/// density, ΔM/ΔK/ΔC on the rail's cubic DOFs and every local mode's properties.
#[pyfunction]
pub(crate) fn fesea<'py>(py: Python<'py>, config_json: &str) -> PyResult<Bound<'py, PyDict>> {
    let cfg = parse_config(py, config_json)?;
    let model = vtb::check::validated(cfg, Profile::flat()).map_err(|e| to_py_err(py, e))?;
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
    let col = |f: &dyn Fn(&vtb::model::fesea::LocalMode) -> f64| {
        fs.modes.iter().map(f).collect::<Vec<f64>>()
    };
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

/// The band each layer of a configuration resolves (`vtb::model::resolution`): a list of dicts
/// (layer, f_max, basis_f_max, time_f_max in Hz; shortest_wavelength in m), top layer first,
/// and the top layer's pinned–pinned frequency (Hz, or None).
#[pyfunction]
pub(crate) fn resolved_bands<'py>(
    py: Python<'py>,
    config_json: &str,
) -> PyResult<(Bound<'py, PyList>, Option<f64>)> {
    let cfg = parse_config(py, config_json)?;
    vtb::check::validate(&cfg, &Profile::flat()).map_err(|e| to_py_err(py, e))?;
    let out = PyList::empty(py);
    for b in vtb::model::resolution::resolved_bands(&cfg) {
        let d = PyDict::new(py);
        d.set_item("layer", b.layer)?;
        d.set_item("f_max", b.f_max)?;
        d.set_item("basis_f_max", b.basis_f_max)?;
        d.set_item("time_f_max", b.time_f_max)?;
        d.set_item("shortest_wavelength", b.shortest_wavelength)?;
        out.append(d)?;
    }
    Ok((out, vtb::model::resolution::pinned_pinned_frequency(&cfg)))
}

/// The estimated cost of building a configuration's synthesis reduction
/// (`vtb::check::budget::synthesis_build`): a dict of dofs, basis_modes, attachments, modes,
/// bytes, seconds and stages (the seconds of its three stages), or None without a synthesis cut-off. With `check`, a build beyond
/// `solver.memory_budget` raises ConfigError naming it (`check_synthesis_build`).
#[pyfunction]
#[pyo3(signature = (config_json, check=false))]
pub(crate) fn synthesis_build<'py>(
    py: Python<'py>,
    config_json: &str,
    check: bool,
) -> PyResult<Option<Bound<'py, PyDict>>> {
    let cfg = parse_config(py, config_json)?;
    if check {
        vtb::check::budget::check_synthesis_build(&cfg).map_err(|e| to_py_err(py, e))?;
    }
    let Some(b) = vtb::check::budget::synthesis_build(&cfg) else {
        return Ok(None);
    };
    let d = PyDict::new(py);
    d.set_item("dofs", b.dofs)?;
    d.set_item("basis_modes", b.basis_modes)?;
    d.set_item("attachments", b.attachments)?;
    d.set_item("modes", b.modes)?;
    d.set_item("bytes", b.bytes)?;
    d.set_item("seconds", b.seconds())?;
    d.set_item("stages", b.stages.to_vec())?;
    Ok(Some(d))
}

/// Half-length (m) along the rail of the Hertz contact patch of a steel wheel of rolling
/// radius `wheel_radius` (m) on a steel rail head of crown radius `rail_radius` (m) under
/// `load` (N) (`vtb::model::contact::patch_half_length`).
#[pyfunction]
pub(crate) fn patch_half_length(
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
    Ok(vtb::model::contact::patch_half_length(
        load,
        wheel_radius,
        rail_radius,
    ))
}

/// A sparse symmetric positive definite matrix factorised once (LDLᵀ, approximate minimum
/// degree ordering), for setup work with many right-hand sides (the synthesis's residual).
#[pyclass(frozen, module = "vtb._core")]
pub(crate) struct SpdSolver(vtb::linalg::sparse::Ldlt);

#[pymethods]
impl SpdSolver {
    /// From COO triplets of the whole matrix (both triangles; duplicates are summed).
    #[new]
    fn new(
        py: Python<'_>,
        n: usize,
        rows: PyReadonlyArray1<'_, i64>,
        cols: PyReadonlyArray1<'_, i64>,
        values: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Self> {
        let (rows, cols, values) = (rows.as_array(), cols.as_array(), values.as_array());
        if rows.len() != values.len() || cols.len() != values.len() {
            return Err(to_py_err(
                py,
                VtbError::config("rows", rows.len(), "rows, cols and values differ in length"),
            ));
        }
        let mut a = vtb::linalg::sparse::Assembler::new(n);
        for ((&i, &j), &v) in rows.iter().zip(cols.iter()).zip(values.iter()) {
            if !(0..n as i64).contains(&i) || !(0..n as i64).contains(&j) || !v.is_finite() {
                return Err(to_py_err(
                    py,
                    VtbError::config(
                        "values",
                        format!("({i}, {j}) = {v}"),
                        format!("needs indices below {n} and a finite value"),
                    ),
                ));
            }
            a.add(i as usize, j as usize, v);
        }
        vtb::linalg::sparse::Ldlt::new(&a.finish_exact())
            .map(Self)
            .map_err(|e| to_py_err(py, e))
    }

    /// A⁻¹·B for an (n, m) array B, on two threads with the GIL released.
    fn solve<'py>(
        &self,
        py: Python<'py>,
        b: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let shape = b.shape().to_vec();
        if shape[0] != self.0.n {
            return Err(to_py_err(
                py,
                VtbError::config(
                    "b",
                    format!("{shape:?}"),
                    format!("needs {} rows", self.0.n),
                ),
            ));
        }
        let mut x: Vec<f64> = b.as_array().iter().copied().collect();
        py.detach(|| self.0.solve_columns(&mut x, shape[1], 2));
        PyArray1::from_vec(py, x).reshape([shape[0], shape[1]])
    }
}
