//! The parse stage of `solve_ivp_core`: the keyword arguments (`IvpArgs`, filled from the
//! dict that python/lash/_ivp.py builds) become lash-solver's options, the time map and the
//! system's parts. Every option of `lash.solve_ivp` is named here once, beside the solver
//! field it sets:
//!
//! ```text
//! method, controller        → SolverOptions.method / .controller (names of docs/outputs.md)
//! rtol, atol                → .rtol / .atol (atol scalar or one per component)
//! first_step, max_step,     → .h0, .h_max, .h_min (diffsol's methods too: h0 and h_min are
//! min_step                     diffsol's own, h_max is imposed by stop times)
//! max_steps, step           → .max_steps, .step (rk4's fixed step)
//! max_memory                → .max_memory (the budget of the n² matrices, crate lash_solver::memory)
//! t0, t1                    → d = sign(t1 − t0), solver span [d t0, d t1]; t1 = ±∞ runs up
//!                              to the largest finite time (until a terminal event)
//! t_eval                    → output times in solver time
//! jac / jac_matrix          → Jac::Callable / Jac::Constant (row-major)
//! jac_sparsity              → for each column, its possibly nonzero rows
//! events                    → PyEvent (function, direction, terminal count, hook)
//! ```

use pyo3::prelude::*;
use pyo3::types::PyBytes;

use lash_solver::{Atol, ControllerKind, Direction, Method, SolverOptions};

use super::system::{Jac, PyEvent};
use crate::convert::f64s_from_bytes;
use crate::errors::usage_error;

/// An event as `lash.solve_ivp` passes it: `(function, direction sign, terminal count, hook
/// or None)`.
pub type EventDecl<'py> = (Bound<'py, PyAny>, i32, usize, Option<Bound<'py, PyAny>>);

/// The keyword arguments of `_lash.solve_ivp_core(fun, args)`, as one dict. Arrays are bytes
/// of native-endian f64.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct IvpArgs<'py> {
    /// Start time (finite).
    pub t0: f64,
    /// End time, ≠ t0 (may be ±∞).
    pub t1: f64,
    /// Initial state, n ≥ 1 values.
    pub y0: Bound<'py, PyBytes>,
    /// lash's method name.
    pub method: String,
    /// Output times (sorted along the integration) or None: every step.
    pub t_eval: Option<Bound<'py, PyBytes>>,
    /// Whether the dense output is recorded.
    pub dense_output: bool,
    /// `(function, direction sign, terminal count, hook or None)` per event function.
    pub events: Vec<EventDecl<'py>>,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance: one value, or one per component.
    pub atol: Bound<'py, PyBytes>,
    /// A callable Jacobian, or None.
    pub jac: Option<Bound<'py, PyAny>>,
    /// A constant Jacobian (row-major n × n), or None.
    pub jac_matrix: Option<Bound<'py, PyBytes>>,
    /// The sparsity pattern as (rows, columns) of its nonzero entries, or None.
    pub jac_sparsity: Option<(Vec<usize>, Vec<usize>)>,
    /// scipy's `vectorized`: `fun` takes y of shape (n, 1).
    pub vectorized: bool,
    /// Controller name, or None: the method's default.
    pub controller: Option<String>,
    /// Largest step (+∞: none).
    pub max_step: f64,
    /// First step, or None: chosen by the method.
    pub first_step: Option<f64>,
    /// Smallest step before failing.
    pub min_step: f64,
    /// Step attempts before failing.
    pub max_steps: usize,
    /// rk4's fixed step.
    pub step: Option<f64>,
    /// Memory budget of the dense n² matrices, bytes (None: half of what is available).
    pub max_memory: Option<u64>,
    /// Extra positional arguments of every callback.
    pub args: Vec<Bound<'py, PyAny>>,
}

/// What the parse stage gives the other stages.
pub struct Parsed<'py> {
    /// The solver's options.
    pub opts: SolverOptions,
    /// d = ±1: solver time s = d·t.
    pub dir: f64,
    /// Solver span [s0, s1]: start.
    pub s0: f64,
    /// End (the largest finite time for t1 = ±∞).
    pub s1: f64,
    /// t0 as given (the time of the first output).
    pub t0: f64,
    /// Initial state.
    pub y0: Vec<f64>,
    /// Output times in solver time, ascending.
    pub s_eval: Option<Vec<f64>>,
    /// Whether the dense output is recorded.
    pub dense_output: bool,
    /// The Jacobian.
    pub jac: Jac<'py>,
    /// For each column of ∂f/∂y its possibly nonzero rows.
    pub sparsity: Option<Vec<Vec<usize>>>,
    /// The event functions.
    pub events: Vec<PyEvent<'py>>,
    /// scipy's `vectorized`.
    pub vectorized: bool,
    /// Extra positional arguments of every callback.
    pub args: Vec<Bound<'py, PyAny>>,
}

/// Checks the names and shapes and builds the solver's options (module doc).
pub fn parse<'py>(py: Python<'py>, a: IvpArgs<'py>) -> PyResult<Parsed<'py>> {
    let method = Method::from_name(&a.method)
        .ok_or_else(|| usage_error(py, &format!("unknown method {:?}", a.method)))?;
    let controller = match &a.controller {
        None => None,
        Some(c) => Some(
            ControllerKind::from_name(c)
                .ok_or_else(|| usage_error(py, &format!("unknown controller {c:?}")))?,
        ),
    };
    let y0 = f64s_from_bytes(a.y0.as_bytes());
    let n = y0.len();
    if n == 0 {
        return Err(usage_error(py, "y0 must have at least one component"));
    }
    let (t0, t1) = (a.t0, a.t1);
    if t0 == t1 || !t0.is_finite() || t1.is_nan() {
        return Err(usage_error(
            py,
            &format!("t_span must be two different times, t0 finite, got ({t0}, {t1})"),
        ));
    }
    let dir = if t1 > t0 { 1.0 } else { -1.0 };
    // An infinite end: the largest finite time (the run ends at a terminal event).
    let s1 = if t1.is_finite() { dir * t1 } else { f64::MAX };
    let atol = f64s_from_bytes(a.atol.as_bytes());
    let atol = if atol.len() == 1 {
        Atol::Scalar(atol[0])
    } else {
        Atol::Vector(atol)
    };
    let jac = match (a.jac, a.jac_matrix) {
        (Some(f), _) => Jac::Callable(f),
        (None, Some(m)) => {
            let m = f64s_from_bytes(m.as_bytes());
            if m.len() != n * n {
                return Err(usage_error(py, &format!("jac must have shape ({n}, {n})")));
            }
            Jac::Constant(m)
        }
        (None, None) => Jac::None,
    };
    let sparsity = match a.jac_sparsity {
        None => None,
        Some((rows, cols)) => {
            if rows.len() != cols.len() || rows.iter().chain(&cols).any(|&i| i >= n) {
                return Err(usage_error(
                    py,
                    &format!("jac_sparsity must have shape ({n}, {n})"),
                ));
            }
            let mut pattern = vec![Vec::new(); n];
            for (i, j) in rows.into_iter().zip(cols) {
                pattern[j].push(i);
            }
            for col in &mut pattern {
                col.sort_unstable();
                col.dedup();
            }
            Some(pattern)
        }
    };
    let events = a
        .events
        .into_iter()
        .map(|(fun, direction, terminal, hook)| PyEvent {
            fun,
            direction: match direction.signum() {
                1 => Direction::Rising,
                -1 => Direction::Falling,
                _ => Direction::Either,
            },
            terminal,
            hook,
        })
        .collect();
    let opts = SolverOptions {
        method,
        rtol: a.rtol,
        atol,
        step: a.step,
        h0: a.first_step,
        h_min: a.min_step,
        h_max: a.max_step,
        max_steps: a.max_steps,
        max_memory: a.max_memory,
        controller,
        ..SolverOptions::default()
    };
    let s_eval = a.t_eval.map(|b| {
        f64s_from_bytes(b.as_bytes())
            .iter()
            .map(|t| dir * t)
            .collect()
    });
    Ok(Parsed {
        opts,
        dir,
        s0: dir * t0,
        s1,
        t0,
        y0,
        s_eval,
        dense_output: a.dense_output,
        jac,
        sparsity,
        events,
        vectorized: a.vectorized,
        args: a.args,
    })
}
