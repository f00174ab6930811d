//! The exceptions of python/lash/_errors.py, raised from Rust, and the names of solver
//! failures.
//!
//! ```text
//! SolveError::InvalidOptions(m)          → lash.UsageError(m)        (raised here)
//! any other SolveError (time, state)     → (kind, message, t, y) data → lash.SolveError,
//!                                          raised by lash.solve_ivp with the partial result
//! exception inside fun / jac / an event  → that exception, unchanged (ivp.rs)
//! ```

use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyType;

use lash_solver::SolveError;

static USAGE_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// `lash.UsageError(message)`: a bad option or argument.
pub fn usage_error(py: Python<'_>, message: &str) -> PyErr {
    match USAGE_ERROR.import(py, "lash._errors", "UsageError") {
        Ok(ty) => PyErr::from_type(ty.clone(), message.to_string()),
        Err(e) => e,
    }
}

/// The name of a solver failure, `SolveError.kind` on the Python side (docs: python/lash/
/// _errors.py).
pub fn failure_kind(e: &SolveError) -> &'static str {
    match e {
        SolveError::StepSizeTooSmall { .. } => "step_size_too_small",
        SolveError::TooManySteps { .. } => "too_many_steps",
        SolveError::NonFiniteState { .. } => "non_finite_state",
        SolveError::NewtonFailure { .. } => "newton_failure",
        SolveError::InvalidOptions(_) => "invalid_options",
        SolveError::BudgetExhausted { .. } => "budget_exhausted",
    }
}
