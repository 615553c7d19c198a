//! Errors of the core. Every failure a user can cause is a `VtbError`; nothing panics on bad
//! input. The Python bindings map the variants to `vtb.ConfigError`, `vtb.ConvergenceError`,
//! `vtb.SolverError` and `vtb.Cancelled`.

use thiserror::Error;

#[derive(Debug, Clone, Error, PartialEq)]
pub enum VtbError {
    /// A configuration field has an invalid value. `field` is a dotted path such as
    /// `vehicles[0].m_c` or `structure.layers[1].density`.
    #[error("invalid config field `{field}` = {value}: {reason}")]
    Config {
        field: String,
        value: String,
        reason: String,
    },
    /// The wheel–rail contact iteration did not reach its tolerance within the allowed
    /// number of iterations.
    #[error(
        "contact iteration did not converge at t = {time:.6} s (step {step}): \
         residual {residual:.3e} N after {iterations} iterations"
    )]
    ContactNotConverged {
        time: f64,
        step: usize,
        residual: f64,
        iterations: usize,
    },
    /// A linear-algebra failure that valid input should never produce (e.g. a singular
    /// static stiffness because the structure is not supported).
    #[error("solver failure: {0}")]
    Solver(String),
    /// The run was cancelled by the caller (e.g. Ctrl-C in Python).
    #[error("cancelled")]
    Cancelled,
}

impl VtbError {
    pub fn config(
        field: impl Into<String>,
        value: impl std::fmt::Display,
        reason: impl Into<String>,
    ) -> Self {
        VtbError::Config {
            field: field.into(),
            value: value.to_string(),
            reason: reason.into(),
        }
    }
}

pub type Result<T> = std::result::Result<T, VtbError>;
