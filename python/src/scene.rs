//! `run_core`: a scene run by the engine (crates/validation), as `lash run` runs it, with the
//! results kept in memory.
//!
//! ```text
//! lash.run (python/lash/_run.py)          checks the options as the command line's parsers do,
//!        │                                 serialises a dict scene to JSON text
//!        ▼
//! run_core(RunArgs)                        Case::load(path) | Case::from_json_bytes(name,
//!        │  GIL released, on the caller's   text); run_in_memory(case, options)
//!        │  thread with Python's wakeup fd
//!        │  watched for Ctrl-C (run_watched)
//!        ▼
//! { summary: summary.json's text, names, present, rows, columns: the engine's column
//!   vectors as F64Column (numpy's array interface, no copy), events: [(t, element, kind)] }
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

use crate::convert::F64Column;
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
        other @ (SceneError::Syntax { .. }
        | SceneError::Unknown(_)
        | SceneError::Io { .. }
        | SceneError::Budget { .. }
        | SceneError::Interrupted { .. }) => (".".into(), other.to_string()),
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

/// What `lash.run` keeps of the engine's result, taken before the GIL is back: summary.json's
/// text, the trajectory's columns (moved, not copied), the events and their functions'
/// names, the engine's wall time.
struct Ran {
    summary: String,
    names: Vec<String>,
    present: Vec<bool>,
    rows: usize,
    columns: Vec<Vec<f64>>,
    events: Vec<EventRecord>,
    event_names: Vec<(&'static str, String)>,
    engine_s: f64,
}

impl Ran {
    /// Takes what `lash.run` returns out of `r` (the trajectory and the events move).
    fn take(r: &mut RunResult, engine_s: f64) -> Result<Ran, Error> {
        let summary = serde_json::to_string(&r.summary)
            .map_err(|e| Error::Internal(format!("summary: {e}")))?;
        let (names, present) = match r.trajectory.header() {
            Some(h) => (h.names().to_vec(), h.present().to_vec()),
            None => (Vec::new(), Vec::new()),
        };
        Ok(Ran {
            summary,
            names,
            present,
            rows: r.trajectory_rows,
            columns: std::mem::take(&mut r.trajectory).into(),
            events: std::mem::take(&mut r.events),
            // Built-in test problems have no events.
            event_names: std::mem::take(&mut r.event_names),
            engine_s,
        })
    }
}

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
/// t_end, samples_per_revolution, output_every, formulation,
///   skip_energy_check                                          → RunOptions
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
    /// Leaves out the energy check of the finished run (`energy_check=False`).
    pub skip_energy_check: bool,
}

/// How often the calling thread looks for a pending signal while the engine runs.
pub const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Stack of the engine's thread: that of a main thread on Linux (the engine ran on the
/// caller's thread before it got its own).
const ENGINE_STACK: usize = 8 << 20;

/// Runs `work` with the GIL released while Ctrl-C stays live: on the calling thread when it
/// is Python's main thread (the common case: no hand-over between threads, issue 25), else on
/// a thread of its own ([`run_on_thread`]). Either way, a signal whose Python handler raises
/// (Ctrl-C: `KeyboardInterrupt`) raises the solver's stop request
/// (`lash_solver::interrupt`): the integration ends at its next step, and the handler's
/// exception is returned in place of the result (dropped: nothing is half-kept). A panic of
/// the work is [`errors::panic_error`]'s exception. `work` returns its result and what is
/// left to free (`D`).
///
/// ```text
/// main thread:  signal.set_wakeup_fd(w) ── work() here, GIL released ── restore the old fd
///                        │ Python's C handler writes the signal's number to w
///               watcher thread (one per process): reads r → request_stop() while watched
///               after: a signal seen → check_signals(): its handler raised → that error;
///                      it did not → the result, or (the run was stopped for nothing) the
///                      work again on a thread of its own
/// elsewhere (another thread, or a wakeup fd already set, as asyncio's): run_on_thread
/// ```
///
/// The stop request is process-wide: it also stops lash runs of other Python threads (they
/// raise `KeyboardInterrupt` too), as Ctrl-C does in the `lash` command. Python runs signal
/// handlers in the main thread only: from another thread nothing is seen, and the run goes
/// on (as any blocking call there does).
pub fn run_watched<T: Send + 'static, D: Send + 'static>(
    py: Python<'_>,
    what: &str,
    work: impl Fn() -> (T, D) + Send + Sync + 'static,
) -> PyResult<T> {
    let work = std::sync::Arc::new(work);
    let Some(watch) = Watch::start(py)? else {
        let w = work.clone();
        return run_on_thread(py, what, move || w());
    };
    let w = work.clone();
    let outcome = py.detach(move || catch_unwind(AssertUnwindSafe(|| w().0)));
    let signalled = watch.stop(py)?;
    if !signalled {
        return outcome.map_err(|payload| panic_error(py, what, payload.as_ref()));
    }
    // A signal came during the run: its Python handler runs now.
    let stopped = interrupt::stop_requested();
    interrupt::clear_stop();
    py.check_signals()?;
    // The handler did not raise: the run is good unless the stop request ended it.
    match outcome {
        Ok(r) if !stopped => Ok(r),
        Ok(_) => run_on_thread(py, what, move || work()),
        Err(payload) => Err(panic_error(py, what, payload.as_ref())),
    }
}

/// What the watcher thread and the runs share: whether a run is watched, and whether a
/// signal came during it.
type WatchState = std::sync::Arc<std::sync::Mutex<(bool, bool)>>;

/// The process's watcher (started by the first watched run, again after a fork): its pid, the
/// socket end Python's signal handler writes to, the state it shares with the runs.
static WATCHER: std::sync::Mutex<Option<(u32, std::os::unix::net::UnixStream, WatchState)>> =
    std::sync::Mutex::new(None);

/// The write end and the state of the process's watcher thread, started on first use: it
/// reads the signal numbers Python's C handler writes to the socket and, while a run is
/// watched, raises the stop request. One thread for the process's life, so that a watched run
/// starts none and wakes none (each would be a scheduling delay on a loaded machine).
fn watcher() -> Option<(std::os::unix::net::UnixStream, WatchState)> {
    let mut slot = WATCHER.lock().unwrap_or_else(|e| e.into_inner());
    let pid = std::process::id();
    if let Some((p, w, state)) = slot.as_ref() {
        if *p == pid {
            return Some((w.try_clone().ok()?, state.clone()));
        }
    }
    let (mut r, w) = std::os::unix::net::UnixStream::pair().ok()?;
    w.set_nonblocking(true).ok()?;
    let state: WatchState = std::sync::Arc::new(std::sync::Mutex::new((false, false)));
    let seen = state.clone();
    std::thread::Builder::new()
        .name("lash-signals".into())
        .spawn(move || {
            use std::io::Read;
            let mut b = [0u8; 64];
            while let Ok(n) = r.read(&mut b) {
                if n == 0 {
                    break;
                }
                let mut s = seen.lock().unwrap_or_else(|e| e.into_inner());
                if s.0 {
                    s.1 = true;
                    interrupt::request_stop();
                }
            }
        })
        .ok()?;
    let out = (w.try_clone().ok()?, state.clone());
    *slot = Some((pid, w, state));
    Some(out)
}

/// The watch of [`run_watched`] on the main thread: Python's wakeup fd pointed at the
/// process's watcher ([`watcher`]) for the time of one run.
struct Watch {
    /// The wakeup fd there was before (restored by [`Watch::stop`]).
    old: i64,
    /// The watcher's state (its lock makes sure no stop request is raised after
    /// [`Watch::stop`]).
    state: WatchState,
    /// The socket end given to Python (kept open while Python may write to it).
    _w: std::os::unix::net::UnixStream,
}

impl Watch {
    /// Starts the watch, or None where it cannot be had: not Python's main thread
    /// (`set_wakeup_fd` refuses), a wakeup fd already set (an event loop's, left alone), no
    /// socket or thread.
    fn start(py: Python<'_>) -> PyResult<Option<Watch>> {
        use std::os::fd::AsRawFd;
        let Some((w, state)) = watcher() else {
            return Ok(None);
        };
        let signal = py.import("signal")?;
        let kwargs = pyo3::types::PyDict::new(py);
        kwargs.set_item("warn_on_full_buffer", false)?;
        let old: i64 = match signal.call_method("set_wakeup_fd", (w.as_raw_fd(),), Some(&kwargs)) {
            Ok(old) => old.extract()?,
            Err(_) => return Ok(None), // not the main thread
        };
        if old != -1 {
            signal.call_method1("set_wakeup_fd", (old,))?;
            return Ok(None);
        }
        *state.lock().unwrap_or_else(|e| e.into_inner()) = (true, false);
        Ok(Some(Watch { old, state, _w: w }))
    }

    /// Ends the watch: the old wakeup fd back; whether a signal was seen (then the stop
    /// request may be raised).
    fn stop(self, py: Python<'_>) -> PyResult<bool> {
        py.import("signal")?
            .call_method1("set_wakeup_fd", (self.old,))?;
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let seen = s.1;
        *s = (false, false);
        Ok(seen)
    }
}

/// Runs `work` on its own thread (where [`run_watched`] cannot watch the calling one) while
/// the calling thread, the GIL released, waits for its result and looks for pending signals every [`SIGNAL_POLL`] (`Python::check_signals`,
/// which runs Python's handlers: Ctrl-C raises `KeyboardInterrupt` there). On the first
/// exception a handler raises, the solver's stop request is raised (`lash_solver::interrupt`):
/// the integration ends at its next step, and that exception is returned once the work has
/// ended, in place of its result (which is dropped: nothing is half-kept). A panic of the work
/// is [`errors::panic_error`]'s exception.
///
/// `work` returns its result and what is left to free (`D`). The result comes back through a
/// channel the moment the work ends; the leftover is dropped on the work's thread after that,
/// while the caller goes on, and the caller does not wait for the thread to exit (it ends on
/// its own). That saves the caller a second hand-over between the threads and the freeing of
/// the engine's buffers at the end of every call (issue 25: on a loaded machine each
/// hand-over costs a scheduling delay).
///
/// The stop request is process-wide: it also stops lash runs of other Python threads (they
/// raise `KeyboardInterrupt` too), as Ctrl-C does in the `lash` command. Python runs signal
/// handlers in the main thread only: from another thread the check finds nothing, and the
/// run goes on (as any blocking call there does).
fn run_on_thread<T: Send + 'static, D: Send + 'static>(
    py: Python<'_>,
    what: &str,
    work: impl FnOnce() -> (T, D) + Send + 'static,
) -> PyResult<T> {
    type Outcome<T> = std::thread::Result<T>;
    let (done_tx, done_rx) = mpsc::channel::<Outcome<T>>();
    std::thread::Builder::new()
        .name("lash-engine".into())
        .stack_size(ENGINE_STACK)
        .spawn(move || match catch_unwind(AssertUnwindSafe(work)) {
            Ok((r, rest)) => {
                // The receiver waits for this message (below): it cannot be gone.
                let _ = done_tx.send(Ok(r));
                // Freed here, while the caller goes on with the result.
                let _ = catch_unwind(AssertUnwindSafe(move || drop(rest)));
            }
            Err(payload) => {
                let _ = done_tx.send(Err(payload));
            }
        })
        .map_err(|e| PyOSError::new_err(format!("{what}: cannot start a thread: {e}")))?;
    let mut raised: Option<PyErr> = None;
    let mut rx = done_rx;
    let outcome: Outcome<T> = loop {
        let (got, back) = py.detach(move || (rx.recv_timeout(SIGNAL_POLL), rx));
        rx = back;
        match got {
            Ok(r) => break r,
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => {
                let why = format!("{what}: the engine's thread ended without a result");
                break Err(Box::new(why) as Box<dyn std::any::Any + Send>);
            }
        }
        if raised.is_none() {
            if let Err(e) = py.check_signals() {
                interrupt::request_stop();
                raised = Some(e);
            }
        }
    };
    if raised.is_some() {
        interrupt::clear_stop();
    }
    let result = outcome.map_err(|payload| panic_error(py, what, payload.as_ref()));
    match raised {
        Some(e) => Err(e),
        None => result,
    }
}

/// Runs one scene (or `testset:NAME`) by the engine, as `lash run` does, without files; the
/// engine of `lash.run` (python/lash/_run.py), which checks the options and documents them.
/// `args` ([`RunArgs`]) names a scene file or a built-in case, or holds a scene's JSON text,
/// recorded as case `name`. The case is read and integrated with the GIL released, Ctrl-C
/// watched ([`run_watched`]).
///
/// Returns a dict: `summary` (summary.json's text), `names` and `present` (the trajectory's
/// columns and whether the run fills each), `rows`, `columns` (one [`F64Column`] per column,
/// the engine's own vector behind numpy's array interface; NaN in absent columns), `events` (`(t, element, kind)` of every
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
        skip_energy_check: a.skip_energy_check,
    };
    let (path, text, name) = (a.path, a.text, a.name);
    let outcome: Result<Ran, Error> = run_watched(py, "lash.run", move || {
        let start = std::time::Instant::now();
        let case = match (&path, &text) {
            (Some(p), _) => Case::load(p, None),
            (None, Some(t)) => Case::from_json_bytes(&name, t.clone()),
            (None, None) => Err(Error::Internal("run_core: no scene".into())),
        };
        match case.and_then(|case| lash_validation::run_in_memory(case, &o)) {
            Ok(mut r) => {
                let engine_s = start.elapsed().as_secs_f64();
                let ran = Ran::take(&mut r, engine_s);
                // The rest of the result (dense output, samples) is freed on this thread
                // after the caller has what it needs.
                (ran, Some(r))
            }
            Err(e) => (Err(e), None),
        }
    })?;
    let ran = outcome.map_err(|e| engine_error(py, e))?;

    let out = PyDict::new(py);
    out.set_item("engine_time_s", ran.engine_s)?;
    out.set_item("summary", ran.summary)?;
    // The engine's columns themselves (NaN in absent ones), each behind numpy's array
    // interface: no copy of the trajectory.
    let columns = PyList::empty(py);
    for c in ran.columns {
        columns.append(Bound::new(py, F64Column::new(c))?)?;
    }
    out.set_item("names", ran.names)?;
    out.set_item("present", ran.present)?;
    out.set_item("rows", ran.rows)?;
    out.set_item("columns", columns)?;
    out.set_item("events", events(py, &ran.events, &ran.event_names)?)?;
    Ok(out)
}
