//! The collect stage of `solve_ivp_core`: the record, the event log and the counters as the
//! dict python/lash/_ivp.py turns into `OdeResult` (arrays as bytes of native-endian f64).

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use lash_solver::SolveError;

use super::drive::Record;
use super::parse::Parsed;
use super::system::{Jac, PySystem};
use crate::convert::bytearray_from_f64s;
use crate::errors::failure_kind;

/// The result dict (`solve_ivp_core`'s doc).
pub fn collect<'py>(
    py: Python<'py>,
    sys: &PySystem<'py>,
    p: &Parsed<'py>,
    rec: &Record,
    nodes: &[f64],
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("n", sys.n)?;
    out.set_item("t", bytearray_from_f64s(py, &rec.t)?)?;
    out.set_item("y", bytearray_from_f64s(py, &rec.y)?)?;
    let log = sys.log.borrow();
    let t_events = PyList::empty(py);
    let y_events = PyList::empty(py);
    for (te, ye) in log.t.iter().zip(&log.y) {
        t_events.append(bytearray_from_f64s(py, te)?)?;
        y_events.append(bytearray_from_f64s(py, ye)?)?;
    }
    out.set_item("t_events", t_events)?;
    out.set_item("y_events", y_events)?;
    let stats = &rec.stats;
    let st = PyDict::new(py);
    st.set_item("steps", stats.steps)?;
    st.set_item("accepted", stats.accepted)?;
    st.set_item("rejected_error", stats.rejected_error)?;
    st.set_item("rejected_newton", stats.rejected_newton)?;
    st.set_item("rhs_evals", stats.rhs_evals)?;
    st.set_item("jac_evals", stats.jac_evals)?;
    st.set_item("lu_factorizations", stats.lu_factorizations)?;
    st.set_item("newton_iters", stats.newton_iters)?;
    st.set_item("event_evals", stats.event_evals)?;
    st.set_item("events", stats.events)?;
    st.set_item("h_min_used", stats.h_min_used)?;
    st.set_item("h_max_used", stats.h_max_used)?;
    st.set_item("fun_calls", sys.fun_calls.get())?;
    st.set_item("jac_calls", sys.jac_calls.get())?;
    out.set_item("stats", st)?;
    // scipy's njev: evaluations of the Jacobian, by `jac` or by differences; a constant
    // matrix is never evaluated.
    let njev = match sys.jac {
        Jac::Constant(_) => 0,
        _ => stats.jac_evals,
    };
    out.set_item("njev", njev)?;
    out.set_item(
        "controller",
        p.opts
            .controller
            .map(|c| c.name())
            .or_else(|| p.opts.method.default_controller().map(|c| c.name())),
    )?;
    if p.dense_output {
        let dense = (
            bytearray_from_f64s(py, nodes)?,
            bytearray_from_f64s(py, &rec.seg_t0)?,
            bytearray_from_f64s(py, &rec.seg_t1)?,
            bytearray_from_f64s(py, &rec.seg_values)?,
        );
        out.set_item("dense", dense)?;
    } else {
        out.set_item("dense", py.None())?;
    }
    match &rec.failure {
        None => {
            out.set_item("status", rec.status)?;
            out.set_item(
                "message",
                if rec.status == 1 {
                    "A termination event occurred."
                } else {
                    "The solver successfully reached the end of the integration interval."
                },
            )?;
            out.set_item("failure", py.None())?;
        }
        Some(e) => {
            let t_fail = e.time().map_or(p.t0, |s| p.dir * s);
            let y_fail = e.state().map_or_else(|| p.y0.clone(), <[f64]>::to_vec);
            let message = failure_message(e, t_fail, p.dir, &|i| event_name(sys, i));
            out.set_item("status", -1)?;
            out.set_item("message", &message)?;
            out.set_item(
                "failure",
                (
                    failure_kind(e),
                    message,
                    t_fail,
                    bytearray_from_f64s(py, &y_fail)?,
                ),
            )?;
        }
    }
    Ok(out)
}

/// An event function's name for messages: its `__name__` (a lambda's is `<lambda>`), else
/// its `repr`.
fn event_name(sys: &PySystem<'_>, i: usize) -> String {
    let Some(ev) = sys.events.get(i) else {
        return "?".into();
    };
    ev.fun
        .getattr("__name__")
        .and_then(|n| n.extract::<String>())
        .or_else(|_| ev.fun.repr().map(|r| r.to_string()))
        .unwrap_or_else(|_| "?".into())
}

/// The failure's message with the time in the caller's t (the solver's own message uses
/// solver time, which is −t when integrating backwards: `dir`); `name` names event `i`.
fn failure_message(e: &SolveError, t: f64, dir: f64, name: &dyn Fn(usize) -> String) -> String {
    match e {
        SolveError::StepSizeTooSmall { h, .. } => {
            format!("step size too small at t = {t:e}: h = {h:e}")
        }
        SolveError::TooManySteps { steps, .. } => {
            format!("too many steps: {steps} step attempts (max_steps) taken, reached t = {t:e}")
        }
        SolveError::NonFiniteState { .. } => format!(
            "non-finite or diverging state at t = {t:e} (fun returned NaN or inf, or the \
             solution grew past 1e100)"
        ),
        SolveError::Rk4Unstable {
            h, h_limit, steps, ..
        } => format!(
            "RK4 beyond its stability limit at t = {t:e}: step {h:e}, estimated limit \
             {h_limit:.3e} (h·ρ > 2.785 on {steps} steps in a row)"
        ),
        SolveError::NewtonFailure { reason, .. } => {
            format!("Newton iteration failed at t = {t:e}: {reason}")
        }
        SolveError::BudgetExhausted { reason, .. } => {
            format!("budget exhausted at t = {t:e}: {reason}")
        }
        SolveError::InvalidOptions(m) => format!("invalid options: {m}"),
        SolveError::Interrupted { .. } => format!("stop requested at t = {t:e}"),
        SolveError::EventNan { index, at, .. } => format!(
            "event {index} ({}) returned NaN at t = {:e}, which has no sign: its crossings \
             cannot be told (last good state at t = {t:e})",
            name(*index),
            dir * at
        ),
        SolveError::OutOfMemory(m) => m.to_string(),
        SolveError::LawOutOfRange { reason, .. } => {
            format!("model outside the range of its laws at t = {t:e}: {reason}")
        }
        SolveError::StateRejected { reason, .. } => reason.clone(),
    }
}
