//! `run_core`: a scene run by the engine (crates/validation), as `lash run` runs it, with the
//! results kept in memory.
//!
//! ```text
//! lash.run (python/lash/_run.py)          checks the options as the command line's parsers do,
//!        │                                 serialises a dict scene to JSON text
//!        ▼
//! run_core                                 Case::load(path) | Case::from_json_bytes(name,
//!        │  (GIL released: Python::detach)  text); commands::run_in_memory(case, options)
//!        ▼
//! { summary: summary.json's text, names, present, rows, columns: column-major f64 bytes,
//!   events: [(t, element, kind)] }
//! ```
//!
//! Errors: a scene the model rejects → `lash.SceneError(path, reason)`; a case that is not a
//! scene (not JSON, not a file) → `lash.SceneError(".", message)`; options → `lash.UsageError`;
//! a solver failure → `lash.SolveError(message, t, y, kind)`; I/O → `OSError`; a bug →
//! `RuntimeError`.

use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyRuntimeError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use lash_model::SceneError;
use lash_solver::{Atol, ControllerKind, Method, SolveError};
use lash_validation::{Case, Error, EventRecord, RunOptions, RunResult, SolverChoice};

use crate::convert::bytearray_from_f64s;
use crate::errors::{failure_kind, scene_error, solve_error, usage_error};

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
fn engine_error(py: Python<'_>, e: Error) -> PyErr {
    match e {
        Error::Scene { error, .. } => {
            let (path, reason) = path_and_reason(&error);
            scene_error(py, &path, &reason)
        }
        Error::Input(m) => scene_error(py, ".", &m),
        Error::Usage(m) => usage_error(py, &m),
        Error::Option(o) => usage_error(py, &o.to_string()),
        Error::Solver(SolveError::InvalidOptions(m)) => usage_error(py, &m.to_string()),
        Error::Solver(s) => {
            let t = s.time().unwrap_or(f64::NAN);
            let y = s.state().map(<[f64]>::to_vec).unwrap_or_default();
            solve_error(py, &s.to_string(), t, &y, failure_kind(&s))
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

/// Runs one scene (or `testset:NAME`) by the engine, as `lash run` does, without files; the
/// engine of `lash.run` (python/lash/_run.py), which checks the options and documents them.
/// `path` names a scene file or a built-in case; otherwise `text` is a scene's JSON text,
/// recorded as case `name`. The GIL is released while the case is read and integrated.
///
/// Returns a dict: `summary` (summary.json's text), `names` and `present` (the trajectory's
/// columns and whether the run fills each), `rows`, `columns` (bytes of native-endian f64,
/// column after column; NaN in absent columns), `events` (`(t, element, kind)` of every
/// event of the run), `engine_time_s` (wall time of reading the case and the engine's run,
/// the GIL released: what the same run costs without Python).
#[pyfunction]
#[pyo3(signature = (path, text, name, method, rtol, atol, controller, step, t_end,
    samples_per_revolution, output_every, max_wall_time, max_steps, formulation=None))]
pub fn run_core<'py>(
    py: Python<'py>,
    path: Option<String>,
    text: Option<Vec<u8>>,
    name: &str,
    method: Option<&str>,
    rtol: Option<f64>,
    atol: Option<Vec<f64>>,
    controller: Option<&str>,
    step: Option<f64>,
    t_end: Option<f64>,
    samples_per_revolution: Option<usize>,
    output_every: Option<f64>,
    max_wall_time: Option<f64>,
    max_steps: Option<usize>,
    formulation: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let formulation = match formulation {
        None => None,
        Some(f) => Some(
            f.parse::<lash_validation::FormulationName>()
                .map_err(|e| usage_error(py, &e))?,
        ),
    };
    let method = match method {
        None => None,
        Some(m) => Some(
            Method::from_name(m)
                .ok_or_else(|| usage_error(py, &format!("unknown method {m:?}")))?,
        ),
    };
    let controller = match controller {
        None => None,
        Some(c) => Some(
            ControllerKind::from_name(c)
                .ok_or_else(|| usage_error(py, &format!("unknown controller {c:?}")))?,
        ),
    };
    let atol = atol.map(|a| match a.as_slice() {
        [x] => Atol::Scalar(*x),
        _ => Atol::Vector(a),
    });
    let o = RunOptions {
        case: String::new(),
        solver: SolverChoice {
            method,
            rtol,
            atol,
            step,
            controller,
            max_steps,
            max_wall_time,
        },
        t_end,
        samples_per_revolution,
        output_every,
        out: None,
        until_periodic: None,
        formulation,
    };
    let name = name.to_string();
    let outcome: Result<Ran, Error> = py.detach(move || {
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
    });
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
