//! # lash-python
//!
//! The extension module `lash._lash` of the Python package `lash` (python/lash/): scenes run
//! by lash's engine with the results in memory, and lash's integrators, step-size controllers
//! and event location for a right-hand side written in Python, behind scipy's `solve_ivp`
//! interface.
//!
//! ```text
//! lash.run (python/lash/_run.py)             checks the options as `lash run` does, builds
//!        │                                    Run (summary dict, numpy columns, events)
//!        ▼
//! _lash.run_core (scene.rs)                   RunArgs (the keyword arguments, one dict) →
//!                                             lash_validation::run_in_memory, the GIL
//!                                             released, Ctrl-C watched through Python's
//!                                             signal wakeup fd (scene::run_watched)
//!
//! lash.sweep (python/lash/_sweep.py)        expands a sweep (sweep_points_core) and runs
//!        │                                    its points, in process or one per task of an
//!        ▼                                    executor, reading each point's result.json
//! _lash.sweep_*_core (sweep.rs)               lash_validation::sweep_points / sweep_run
//!
//! lash.solve_ivp (python/lash/_ivp.py)       checks and normalises the arguments (scipy's
//!        │                                    meaning), builds OdeResult / OdeSolution
//!        ▼
//! _lash.solve_ivp_core (ivp/)                 parse (IvpArgs, the keyword arguments → options),
//!        │                                    system (PySystem: OdeSystem calling fun, jac,
//!        ▼                                    events and hooks with the GIL held), drive,
//! lash_solver::Problem → Integrator           collect (raw arrays as bytes)
//! ```
//!
//! Arrays cross the boundary as bytes of native-endian f64 (one copy, no per-element
//! conversion); the Python side wraps them with `numpy.frombuffer`. Errors: option errors
//! raise `lash.UsageError`, a rejected scene `lash.SceneError` with its JSON path, solver
//! failures `lash.SolveError` with time and state (`lash.solve_ivp` adds the partial result),
//! dense matrices over the memory budget `lash.OutOfMemoryError` (a `MemoryError`), and an
//! exception raised inside a Python callback stops the integration and propagates as itself
//! (python/lash/_errors.py). Every entry point runs inside a panic guard
//! (`errors::guard`): a panic becomes `lash.InternalError`, or `lash.OutOfMemoryError` for an
//! allocation that failed, never pyo3's `PanicException` (a `BaseException`).

mod animation;
mod convert;
mod errors;
mod ivp;
mod scene;
mod sweep;

use pyo3::prelude::*;
use pyo3::types::PyTuple;

use lash_solver::{ControllerKind, Method};

/// The module `lash._lash`.
#[pymodule]
fn _lash(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_function(wrap_pyfunction!(ivp::solve_ivp_core, m)?)?;
    m.add_function(wrap_pyfunction!(scene::run_core, m)?)?;
    m.add_function(wrap_pyfunction!(animation::animation_html, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep_points_core, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep_run_core, m)?)?;
    m.add(
        "METHODS",
        PyTuple::new(py, Method::ALL.iter().map(|x| x.name()))?,
    )?;
    m.add(
        "CONTROLLERS",
        PyTuple::new(py, ControllerKind::ALL.iter().map(|c| c.name()))?,
    )?;
    m.add(
        "DEFAULT_CONTROLLERS",
        PyTuple::new(py, ivp::default_controllers())?,
    )?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
