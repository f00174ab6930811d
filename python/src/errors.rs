//! The exceptions of python/lash/_errors.py, raised from Rust, the names of solver failures,
//! and the guard every entry point runs in.
//!
//! ```text
//! SolveError::InvalidOptions(o)          → lash.UsageError(o rendered with the keywords'
//!                                          names: h0 → first_step, h_min → min_step, …)
//! SolveError::OutOfMemory(m)             → lash.OutOfMemoryError(message, needed, budget)
//!                                          (a MemoryError)
//! any other SolveError (time, state)     → (kind, message, t, y) data → lash.SolveError,
//!                                          raised by lash.solve_ivp with the partial result
//! exception inside fun / jac / an event  → that exception, unchanged (ivp.rs)
//! a scene the model rejects (lash.run)    → lash.SceneError(path, reason)   (scene.rs)
//! a scene run's solver failure            → lash.SolveError(message, t, y, kind)
//! a panic anywhere below an entry point   → lash.InternalError(message) (a RuntimeError),
//!                                          or lash.OutOfMemoryError when an allocation
//!                                          failed (guard): never pyo3's PanicException,
//!                                          which derives from BaseException
//! ```

use std::panic::{catch_unwind, AssertUnwindSafe};

use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyType;

use lash_solver::memory::MemoryError;
use lash_solver::{OptionField, SolveError};

static USAGE_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static SCENE_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static SOLVE_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static MEMORY_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static INTERNAL_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// `lash.UsageError(message)`: a bad option or argument.
pub fn usage_error(py: Python<'_>, message: &str) -> PyErr {
    match USAGE_ERROR.import(py, "lash._errors", "UsageError") {
        Ok(ty) => PyErr::from_type(ty.clone(), message.to_string()),
        Err(e) => e,
    }
}

/// The keyword of `lash.solve_ivp` (and `lash.run`) that sets a solver option: scipy's
/// names for the step bounds (`first_step`, `min_step`, `max_step`), the solver's name for
/// the rest (`rtol`, `atol`, `step`, `max_steps`, `controller`, `method`, ...). Solver
/// option errors are rendered with it ([`lash_solver::OptionError::render`]).
pub fn keyword(field: OptionField) -> String {
    match field {
        OptionField::H0 => "first_step".into(),
        OptionField::HMin => "min_step".into(),
        OptionField::HMax => "max_step".into(),
        other => other.name().to_string(),
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
/// state (`y` a numpy array, made by the caller: `convert` builds arrays and reports its own
/// errors through this module, so this module does not import it back).
pub fn solve_error(py: Python<'_>, message: &str, t: f64, y: Py<PyAny>, kind: &str) -> PyErr {
    match SOLVE_ERROR.import(py, "lash._errors", "SolveError") {
        Ok(ty) => PyErr::from_type(ty.clone(), (message.to_string(), t, y, kind.to_string())),
        Err(e) => e,
    }
}

/// `lash.OutOfMemoryError(message, needed, budget)`: memory refused before it was allocated
/// (a `MemoryError`; `budget` 0 when the allocator itself refused).
pub fn memory_error(py: Python<'_>, e: &MemoryError) -> PyErr {
    match MEMORY_ERROR.import(py, "lash._errors", "OutOfMemoryError") {
        Ok(ty) => PyErr::from_type(ty.clone(), (e.to_string(), e.needed, e.budget)),
        Err(err) => err,
    }
}

/// `lash.InternalError(message)`: a bug in lash (a panic caught at the boundary).
pub fn internal_error(py: Python<'_>, message: &str) -> PyErr {
    match INTERNAL_ERROR.import(py, "lash._errors", "InternalError") {
        Ok(ty) => PyErr::from_type(ty.clone(), message.to_string()),
        Err(e) => e,
    }
}

/// The text of a panic's payload (`panic!` with a literal or a formatted message).
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".to_string()
    }
}

/// The exception of a panic in `what`: an allocation that failed and was unwrapped (faer's
/// `Mat::zeros` on `AllocError`, a capacity overflow) is `lash.OutOfMemoryError`, anything
/// else `lash.InternalError`, each with the panic's message.
pub fn panic_error(py: Python<'_>, what: &str, payload: &(dyn std::any::Any + Send)) -> PyErr {
    let m = panic_message(payload);
    let allocation = [
        "AllocError",
        "capacity overflow",
        "TryReserveError",
        "memory allocation",
    ]
    .iter()
    .any(|k| m.contains(k));
    if allocation {
        memory_error(
            py,
            &MemoryError {
                what: format!("{what} ({m})"),
                needed: 0,
                budget: 0,
                basis: "the allocator".into(),
            },
        )
    } else {
        internal_error(
            py,
            &format!("{what}: internal error (a bug in lash; please report it): {m}"),
        )
    }
}

/// Runs an entry point's body, turning a panic inside it into the exception of
/// [`panic_error`]: no panic crosses into Python as pyo3's `PanicException` (a
/// `BaseException` that `except Exception` misses).
pub fn guard<'py, T>(
    py: Python<'py>,
    what: &str,
    body: impl FnOnce() -> PyResult<T>,
) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(r) => r,
        Err(payload) => Err(panic_error(py, what, payload.as_ref())),
    }
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
        SolveError::EventNan { .. } => "event_nan",
        SolveError::StateRejected { kind, .. } => kind,
        SolveError::OutOfMemory(_) => "out_of_memory",
        SolveError::LawOutOfRange { .. } => "law_out_of_range",
    }
}
