//! The exceptions of python/lash/_errors.py, raised from Rust, and the names of solver
//! failures.
//!
//! ```text
//! SolveError::InvalidOptions(m)          → lash.UsageError(m)        (raised here)
//! any other SolveError (time, state)     → (kind, message, t, y) data → lash.SolveError,
//!                                          raised by lash.solve_ivp with the partial result
//! exception inside fun / jac / an event  → that exception, unchanged (ivp.rs)
//! a scene the model rejects (lash.run)    → lash.SceneError(path, reason)   (scene.rs)
//! a scene run's solver failure            → lash.SolveError(message, t, y, kind)
//! ```

use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyType;

use lash_solver::SolveError;

static USAGE_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static SCENE_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static SOLVE_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// `lash.UsageError(message)`: a bad option or argument.
pub fn usage_error(py: Python<'_>, message: &str) -> PyErr {
    match USAGE_ERROR.import(py, "lash._errors", "UsageError") {
        Ok(ty) => PyErr::from_type(ty.clone(), message.to_string()),
        Err(e) => e,
    }
}

/// `lash.SceneError(path, reason)`: a scene that cannot be used, with the JSON path of the
/// offending value (docs/scene-format.md, "Errors").
pub fn scene_error(py: Python<'_>, path: &str, reason: &str) -> PyErr {
    match SCENE_ERROR.import(py, "lash._errors", "SceneError") {
        Ok(ty) => PyErr::from_type(ty.clone(), (path.to_string(), reason.to_string())),
        Err(e) => e,
    }
}

/// `lash.SolveError(message, t, y, kind)`: a failed integration with its time and last good
/// state (`y` a numpy array).
pub fn solve_error(py: Python<'_>, message: &str, t: f64, y: &[f64], kind: &str) -> PyErr {
    let ty = match SOLVE_ERROR.import(py, "lash._errors", "SolveError") {
        Ok(ty) => ty.clone(),
        Err(e) => return e,
    };
    let y = match crate::convert::Numpy::import(py).and_then(|np| np.array(y)) {
        Ok(a) => a.unbind(),
        Err(e) => return e,
    };
    PyErr::from_type(ty, (message.to_string(), t, y, kind.to_string()))
}

/// The name of a solver failure, `SolveError.kind` on the Python side (docs: python/lash/
/// _errors.py).
pub fn failure_kind(e: &SolveError) -> &'static str {
    match e {
        SolveError::StepSizeTooSmall { .. } => "step_size_too_small",
        SolveError::TooManySteps { .. } => "too_many_steps",
        SolveError::NonFiniteState { .. } => "non_finite_state",
        SolveError::Rk4Unstable { .. } => "rk4_unstable",
        SolveError::NewtonFailure { .. } => "newton_failure",
        SolveError::InvalidOptions(_) => "invalid_options",
        SolveError::BudgetExhausted { .. } => "budget_exhausted",
        SolveError::Interrupted { .. } => "interrupted",
    }
}
