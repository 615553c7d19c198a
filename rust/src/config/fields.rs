//! The fields' own checks (finite, positive, within a range) and the limits that keep a run
//! from hanging or exhausting memory: the rules every configuration part applies to itself.

use crate::error::{Result, VtbError};

/// Largest magnitude accepted for any parameter: beyond it products of parameters overflow.
pub const MAX_MAGNITUDE: f64 = 1e30;

pub(crate) fn finite(field: &str, v: f64) -> Result<f64> {
    if !v.is_finite() {
        Err(VtbError::config(
            field,
            format!("{v:?}"),
            "must be a finite number",
        ))
    } else if v.abs() > MAX_MAGNITUDE {
        Err(VtbError::config(
            field,
            format!("{v:?}"),
            format!("magnitude beyond {MAX_MAGNITUDE:e} is not physical"),
        ))
    } else {
        Ok(v)
    }
}

pub(crate) fn positive(field: &str, v: f64) -> Result<f64> {
    finite(field, v)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(VtbError::config(field, format!("{v:?}"), "must be > 0"))
    }
}

pub(crate) fn non_negative(field: &str, v: f64) -> Result<f64> {
    finite(field, v)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(VtbError::config(field, format!("{v:?}"), "must be >= 0"))
    }
}

pub(crate) fn within(field: &str, v: f64, lo: f64, hi: f64, what: &str) -> Result<f64> {
    finite(field, v)?;
    if v >= lo - 1e-12 && v <= hi + 1e-12 {
        Ok(v)
    } else {
        Err(VtbError::config(
            field,
            format!("{v:?}"),
            format!("must lie within [{lo}, {hi}] ({what})"),
        ))
    }
}

/// Upper bound on time steps of one run (guards against hangs and memory blow-ups).
pub const MAX_STEPS: usize = 20_000_000;
/// Upper bound on sine modes of one layer.
pub const MAX_MODES: usize = 20_000;
/// Upper bound on the dampers of a run: their coupling is a dense count × count matrix,
/// inverted once per run (O(count³)) and applied every step (O(count²)).
pub const MAX_TIDS: usize = 2_000;
/// Time-step counts within this of a whole number are whole (t_end is a multiple of dt).
pub(crate) const STEP_TOL: f64 = 1e-6;
/// Upper bound on FEM elements per layer.
pub const MAX_ELEMENTS: usize = 200_000;
/// The widest lockstep group the engines compile (lanes of one model run together).
pub const MAX_LANES: usize = 8;

/// A position within this (relative to the structure's scale) of a layer's end is at the end:
/// sums of lengths round (a car's rear wheelset placed on x = 0 lands at −6.7e-16 m).
const END_TOL: f64 = 1e-9;

/// `x` on the interval [a, b] with the ends' rounding tolerance: `x` itself inside, the end it
/// rounds to within the tolerance of an end, `None` outside.
pub fn on_interval(x: f64, a: f64, b: f64) -> Option<f64> {
    let tol = END_TOL * a.abs().max(b.abs()).max(1.0);
    if a <= x && x <= b {
        Some(x)
    } else if (x - a).abs() <= tol {
        Some(a)
    } else if (x - b).abs() <= tol {
        Some(b)
    } else {
        None
    }
}
