//! `run_core`: a scene run by the engine (crates/validation), as `lash run` runs it, with the
//! results kept in memory.
//!
//! ```text
//! lash.run (python/lash/_run.py)          checks the options as the command line's parsers do,
//!        │                                 serialises a dict scene to JSON text
//!        ▼
//! run_core(RunArgs)                        Case::load(path) | Case::from_json_bytes(name,
//!        │  engine thread, GIL released;    text); run_in_memory(case, options)
//!        │  the caller's thread looks for
//!        │  Ctrl-C every 50 ms (run_watched)
//!        ▼
//! { summary: summary.json's text, names, present, rows, columns: column-major f64 bytes,
//!   events: [(t, element, kind)] }
//! ```
//!
//! Errors: a scene the model rejects → `lash.SceneError(path, reason)`; a case that is not a
//! scene (not JSON, not a file) → `lash.SceneError(".", message)`; options → `lash.UsageError`;
//! a solver failure → `lash.SolveError(message, t, y, kind)`; dense matrices over the memory
//! budget → `lash.OutOfMemoryError`; Ctrl-C → `KeyboardInterrupt` (the run stopped at its
//! next step, its results dropped); I/O → `OSError`; a bug → `lash.InternalError` (a panic)
//! or `RuntimeError`.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyRuntimeError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use lash_model::SceneError;
use lash_solver::{interrupt, Atol, ControllerKind, Method, SolveError};
use lash_validation::{Case, Error, EventRecord, RunOptions, RunResult, SolverChoice};

use crate::convert::bytearray_from_f64s;
use crate::errors::{
    failure_kind, guard, keyword, memory_error, panic_error, scene_error, solve_error, usage_error,
};

/// The kind of a located event, as `lash.run` reports it: the label of its crossing that the
/// joint or element owning the event function declares (`lash_model::event_label`: a
/// clearance joint's `contact` rising is `contact_onset`, falling `contact_loss`; docs/model.md
/// §7).
pub fn event_kind(kind: &str, rising: bool) -> String {
    lash_model::event_label(kind, rising)
}

/// A scene error's JSON path and reason (docs/scene-format.md, "Errors"): `str(e)` of the
/// Python exception is `path: reason`, the command line's message without its `case …:`
/// prefix.
fn path_and_reason(e: &SceneError) -> (String, String) {
    match e {
        SceneError::Schema { path, message } => (path.clone(), message.clone()),
        SceneError::Invalid { path, reason } => (path.clone(), reason.clone()),
        SceneError::Redundant { path, reason } => (
            path.clone(),
            format!("redundant or contradictory constraints: {reason}"),
        ),
        SceneError::Assembly { path, reason } => (
            path.clone(),
            format!("initial assembly did not converge: {reason}"),
        ),
        SceneError::Dynamics { path, reason } => (
            path.clone(),
            format!("the equations of motion fail at the initial state: {reason}"),
        ),
        other @ (SceneError::Syntax { .. } | SceneError::Unknown(_) | SceneError::Io { .. }) => {
            (".".into(), other.to_string())
        }
    }
}

/// The Python exception of an engine error (module doc).
pub(crate) fn engine_error(py: Python<'_>, e: Error) -> PyErr {
    match e {
        Error::Scene { error, .. } => {
            let (path, reason) = path_and_reason(&error);
            scene_error(py, &path, &reason)
        }
        Error::Input(m) => scene_error(py, ".", &m),
        Error::Usage(m) => usage_error(py, &m),
        Error::Option(o) => usage_error(py, &o.to_string()),
        Error::Solver(SolveError::InvalidOptions(m)) => usage_error(py, &m.render(&keyword)),
        Error::Solver(SolveError::OutOfMemory(m)) => memory_error(py, &m),
        Error::Solver(s) => {
            let t = s.time().unwrap_or(f64::NAN);
            let y = s.state().map(<[f64]>::to_vec).unwrap_or_default();
            match crate::convert::Numpy::import(py).and_then(|np| np.array(&y)) {
                Ok(y) => solve_error(
                    py,
                    &s.to_string(),
                    t,
                    y.into_any().unbind(),
                    failure_kind(&s),
                ),
                Err(e) => e,
            }
        }
        e @ Error::Io { .. } => PyOSError::new_err(e.to_string()),
        // A stop requested through lash_solver's interrupt flag: what Ctrl-C is in Python.
        e @ Error::Interrupted(_) => PyKeyboardInterrupt::new_err(e.to_string()),
        e @ Error::Internal(_) => PyRuntimeError::new_err(e.to_string()),
    }
}

/// What the engine returns: the result, the event functions' names, the engine's wall time.
type Ran = (RunResult, Vec<(&'static str, String)>, f64);

/// The events of a run as `(t, element, kind)` tuples (element: the joint's name).
fn events<'py>(
    py: Python<'py>,
    events: &[EventRecord],
    names: &[(&'static str, String)],
) -> PyResult<Bound<'py, PyList>> {
    let out = PyList::empty(py);
    for e in events {
        let (kind, element) = names
            .get(e.index)
            .map_or(("event", ""), |(k, n)| (*k, n.as_str()));
        out.append((e.t, element, event_kind(kind, e.rising)))?;
    }
    Ok(out)
}

/// The keyword arguments of `_lash.run_core(args)`, as one dict (python/lash/_run.py checks
/// and documents them; each is the `lash run` flag of the same name).
///
/// ```text
/// path | text + name            the case: a scene file or testset:NAME | a scene's JSON text
/// method, rtol, atol,           → SolverChoice (atol: one value or one per component)
///   controller, step,
///   max_steps, max_wall_time,
///   max_memory
/// t_end, samples_per_revolution, output_every, formulation  → RunOptions
/// ```
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct RunArgs {
    /// A scene file or `testset:NAME`, or None (then `text`).
    pub path: Option<String>,
    /// A scene's JSON text (when `path` is None).
    pub text: Option<Vec<u8>>,
    /// The case name recorded for `text`.
    pub name: String,
    /// Method name, or None: the case's.
    pub method: Option<String>,
    /// Relative tolerance, or None: the case's.
    pub rtol: Option<f64>,
    /// Absolute tolerance(s), or None: the case's.
    pub atol: Option<Vec<f64>>,
    /// Controller name, or None: the method's.
    pub controller: Option<String>,
    /// rk4's fixed step, s.
    pub step: Option<f64>,
    /// End time, s.
    pub t_end: Option<f64>,
    /// Trajectory rows per crank revolution.
    pub samples_per_revolution: Option<usize>,
    /// Time between trajectory rows, s.
    pub output_every: Option<f64>,
    /// Wall-clock budget, s.
    pub max_wall_time: Option<f64>,
    /// Step attempts.
    pub max_steps: Option<usize>,
    /// Memory budget of the implicit methods' dense matrices, bytes.
    pub max_memory: Option<u64>,
    /// The formulation over the scene's, or None (docs/model.md §12).
    pub formulation: Option<String>,
}

/// How often the calling thread looks for a pending signal while the engine runs.
pub const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Stack of the engine's thread: that of a main thread on Linux (the engine ran on the
/// caller's thread before it got its own).
const ENGINE_STACK: usize = 8 << 20;

/// Runs `work` on its own thread while the calling thread, the GIL released, looks for
/// pending signals every [`SIGNAL_POLL`] (`Python::check_signals`, which runs Python's
/// handlers: Ctrl-C raises `KeyboardInterrupt` there). On the first exception a handler
/// raises, the solver's stop request is raised (`lash_solver::interrupt`): the integration
/// ends at its next step, and that exception is returned once the work has ended, in place
/// of its result (which is dropped: nothing is half-kept). A panic of the work is
/// [`errors::panic_error`]'s exception.
///
/// The stop request is process-wide: it also stops lash runs of other Python threads (they
/// raise `KeyboardInterrupt` too), as Ctrl-C does in the `lash` command. Python runs signal
/// handlers in the main thread only: from another thread the check finds nothing, and the
/// run goes on (as any blocking call there does).
pub fn run_watched<T: Send>(
    py: Python<'_>,
    what: &str,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    let (done_tx, done_rx) = mpsc::channel::<()>();
    std::thread::scope(|scope| {
        let worker = std::thread::Builder::new()
            .name("lash-engine".into())
            .stack_size(ENGINE_STACK)
            .spawn_scoped(scope, move || {
                let r = catch_unwind(AssertUnwindSafe(work));
                let _ = done_tx.send(());
                r
            })
            .map_err(|e| PyOSError::new_err(format!("{what}: cannot start a thread: {e}")))?;
        let mut raised: Option<PyErr> = None;
        let mut rx = done_rx;
        loop {
            let (got, back) = py.detach(move || (rx.recv_timeout(SIGNAL_POLL), rx));
            rx = back;
            match got {
                Err(RecvTimeoutError::Timeout) => {}
                Ok(()) | Err(RecvTimeoutError::Disconnected) => break,
            }
            if raised.is_none() {
                if let Err(e) = py.check_signals() {
                    interrupt::request_stop();
                    raised = Some(e);
                }
            }
        }
        let joined = py.detach(|| worker.join());
        if raised.is_some() {
            interrupt::clear_stop();
        }
        let result = match joined {
            Ok(Ok(r)) => Ok(r),
            Ok(Err(payload)) | Err(payload) => Err(panic_error(py, what, payload.as_ref())),
        };
        match raised {
            Some(e) => Err(e),
            None => result,
        }
    })
}

/// Runs one scene (or `testset:NAME`) by the engine, as `lash run` does, without files; the
/// engine of `lash.run` (python/lash/_run.py), which checks the options and documents them.
/// `args` ([`RunArgs`]) names a scene file or a built-in case, or holds a scene's JSON text,
/// recorded as case `name`. The case is read and integrated on an engine thread, the GIL
/// released, while this thread looks for Ctrl-C ([`run_watched`]).
///
/// Returns a dict: `summary` (summary.json's text), `names` and `present` (the trajectory's
/// columns and whether the run fills each), `rows`, `columns` (bytes of native-endian f64,
/// column after column; NaN in absent columns), `events` (`(t, element, kind)` of every
/// event of the run), `engine_time_s` (wall time of reading the case and the engine's run,
/// the GIL released: what the same run costs without Python).
#[pyfunction]
pub fn run_core<'py>(py: Python<'py>, args: RunArgs) -> PyResult<Bound<'py, PyDict>> {
    guard(py, "lash.run", || run(py, args))
}

/// The body of [`run_core`] (inside its panic guard).
fn run<'py>(py: Python<'py>, a: RunArgs) -> PyResult<Bound<'py, PyDict>> {
    let formulation = match a.formulation.as_deref() {
        None => None,
        Some(f) => Some(
            f.parse::<lash_model::FormulationName>()
                .map_err(|e| usage_error(py, &e))?,
        ),
    };
    let method = match a.method.as_deref() {
        None => None,
        Some(m) => Some(
            Method::from_name(m)
                .ok_or_else(|| usage_error(py, &format!("unknown method {m:?}")))?,
        ),
    };
    let controller = match a.controller.as_deref() {
        None => None,
        Some(c) => Some(
            ControllerKind::from_name(c)
                .ok_or_else(|| usage_error(py, &format!("unknown controller {c:?}")))?,
        ),
    };
    let atol = a.atol.map(|v| match v.as_slice() {
        [x] => Atol::Scalar(*x),
        _ => Atol::Vector(v),
    });
    let o = RunOptions {
        case: String::new(),
        solver: SolverChoice {
            method,
            rtol: a.rtol,
            atol,
            step: a.step,
            controller,
            max_steps: a.max_steps,
            max_wall_time: a.max_wall_time,
            max_memory: a.max_memory,
        },
        t_end: a.t_end,
        samples_per_revolution: a.samples_per_revolution,
        output_every: a.output_every,
        out: None,
        until_periodic: None,
        formulation,
        window: None,
    };
    let (path, text, name) = (a.path, a.text, a.name);
    let outcome: Result<Ran, Error> = run_watched(py, "lash.run", move || {
        let start = std::time::Instant::now();
        let case = match (path, text) {
            (Some(p), _) => Case::load(&p, None)?,
            (None, Some(t)) => Case::from_json_bytes(&name, t)?,
            (None, None) => return Err(Error::Internal("run_core: no scene".into())),
        };
        let r = lash_validation::run_in_memory(case, &o)?;
        // Built-in test problems have no events.
        let names = r.event_names.clone();
        Ok((r, names, start.elapsed().as_secs_f64()))
    })?;
    let (r, event_names, engine_s) = outcome.map_err(|e| engine_error(py, e))?;

    let out = PyDict::new(py);
    out.set_item("engine_time_s", engine_s)?;
    let summary = serde_json::to_string(&r.summary)
        .map_err(|e| PyRuntimeError::new_err(format!("summary: {e}")))?;
    out.set_item("summary", summary)?;
    let rows = r.trajectory.len();
    let (names, present): (Vec<String>, Vec<bool>) = match r.trajectory.header() {
        Some(h) => (h.names().to_vec(), h.present().to_vec()),
        None => (Vec::new(), Vec::new()),
    };
    let mut data = Vec::with_capacity(rows * names.len());
    for name in &names {
        match r.trajectory.column(name) {
            Some(c) => data.extend_from_slice(c),
            None => data.extend(std::iter::repeat_n(f64::NAN, rows)),
        }
    }
    out.set_item("names", names)?;
    out.set_item("present", present)?;
    out.set_item("rows", rows)?;
    out.set_item("columns", bytearray_from_f64s(py, &data)?)?;
    out.set_item("events", events(py, &r.events, &event_names)?)?;
    Ok(out)
}
