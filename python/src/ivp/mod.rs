//! `solve_ivp_core`: a Python right-hand side integrated by lash-solver, in four stages.
//!
//! ```text
//! parse    (parse.rs)    IvpArgs (the keyword arguments, one dict) → SolverOptions, time map,
//!                        the system's parts                    names and shapes checked
//! system   (system.rs)   PySystem: OdeSystem calling fun, jac, events and hooks
//! drive    (drive.rs)    Problem → Integrator stepped to the end, t_eval, dense output
//! collect  (collect.rs)  the record as a dict of bytes and counters
//!
//! solver time s = d·t, d = sign(t1 − t0)     (lash integrates forward; t1 < t0 runs in s)
//! rhs(s, y)   = d · fun(d·s, y, *args)
//! jac(s, y)   = d · jac(d·s, y, *args)        (callable or constant matrix)
//! g_i(s, y)   = event_i(d·s, y, *args)        (directions are along the integration, as
//!                                              in scipy: +1 = negative to positive)
//! on event i: record (t, y); y ← hook_i(t, y, *args) if the event has a hook and it returns
//!             a state; stop when event i has occurred `terminal_i` times (0 = never)
//! ```

mod collect;
mod drive;
mod parse;
mod system;

use std::cell::{Cell, RefCell};

use pyo3::prelude::*;
use pyo3::types::PyDict;

use lash_solver::{Method, SolveError};

use crate::convert::Numpy;
use crate::errors::{keyword, memory_error, usage_error};

pub use parse::IvpArgs;
use system::{EventLog, PySystem};

/// Integrates a Python ODE; the engine of `lash.solve_ivp` (python/lash/_ivp.py), which
/// checks and normalises the arguments (scipy's meaning) and documents them. `args` holds the
/// keyword arguments ([`IvpArgs`]: arrays as bytes of native-endian f64; `events` as
/// `(function, direction, terminal count, hook or None)`).
///
/// Returns a dict: `t`, `y` (bytes, row-major (len(t), n)), `status` (0 end, 1 terminal
/// event, −1 failure), `message`, `t_events`/`y_events` (bytes per event), `stats` (lash's
/// counters and the Python call counts), `njev` (scipy's count), `controller`, `dense` (None
/// or `(nodes, t0s, t1s, values)` as bytes), `failure` (None or `(kind, message, t, y)`).
#[pyfunction]
pub fn solve_ivp_core<'py>(
    py: Python<'py>,
    fun: Bound<'py, PyAny>,
    args: IvpArgs<'py>,
) -> PyResult<Bound<'py, PyDict>> {
    crate::errors::guard(py, "lash.solve_ivp", || solve(py, fun, args))
}

/// The body of [`solve_ivp_core`] (inside its panic guard).
fn solve<'py>(
    py: Python<'py>,
    fun: Bound<'py, PyAny>,
    args: IvpArgs<'py>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut p = parse::parse(py, args)?;
    let m_events = p.events.len();
    let sys = PySystem {
        n: p.y0.len(),
        dir: p.dir,
        fun,
        vectorized: p.vectorized,
        args: std::mem::take(&mut p.args),
        jac: std::mem::replace(&mut p.jac, system::Jac::None),
        sparsity: p.sparsity.take(),
        events: std::mem::take(&mut p.events),
        np: Numpy::import(py)?,
        error: RefCell::new(None),
        log: RefCell::new(EventLog {
            t: vec![Vec::new(); m_events],
            y: vec![Vec::new(); m_events],
            pre_hook: None,
        }),
        fun_calls: Cell::new(0),
        jac_calls: Cell::new(0),
        jac_buf: RefCell::new(Vec::new()),
    };
    let nodes = drive::lobatto_nodes(p.opts.method.dense_degree());
    let rec = match drive::drive(&sys, &p, &nodes)? {
        Ok(rec) => rec,
        Err(e) => return Err(setup_error(py, &e)),
    };
    if let Some(err) = sys.take_error() {
        return Err(err);
    }
    collect::collect(py, &sys, &p, &rec, &nodes)
}

/// The controller of each method when none is given, for `lash._lash.DEFAULT_CONTROLLERS`.
pub fn default_controllers() -> impl ExactSizeIterator<Item = (&'static str, Option<&'static str>)>
{
    Method::ALL
        .iter()
        .map(|m| (m.name(), m.default_controller().map(|c| c.name())))
}

/// A failure before the first step: options (`lash.UsageError`) or memory refused for the
/// method's dense matrices (`lash.OutOfMemoryError`); other failures cannot reach here.
fn setup_error(py: Python<'_>, e: &SolveError) -> PyErr {
    match e {
        SolveError::InvalidOptions(m) => usage_error(py, &m.render(&keyword)),
        SolveError::OutOfMemory(m) => memory_error(py, m),
        other => usage_error(py, &other.to_string()),
    }
}
