//! `solve_ivp_core`: a Python right-hand side integrated by lash-solver.
//!
//! ```text
//! solver time s = d·t, d = sign(t1 − t0)     (lash integrates forward; t1 < t0 runs in s)
//! rhs(s, y)   = d · fun(d·s, y, *args)
//! jac(s, y)   = d · jac(d·s, y, *args)        (callable or constant matrix)
//! g_i(s, y)   = event_i(d·s, y, *args)        (directions are along the integration, as
//!                                              in scipy: +1 = negative to positive)
//! on event i: record (t, y); y ← hook_i(t, y, *args) if the event has a hook and it returns
//!             a state; stop when event i has occurred `terminal_i` times (0 = never)
//! ```
//!
//! Callbacks run with the GIL held (the caller's thread). The first exception a callback
//! raises is stored; from then on every callback returns NaN without calling Python, so the
//! method fails within a few attempts; the stored exception is then raised unchanged, before
//! any solver error. Dense output: every step's interpolant is sampled at the m + 1
//! Chebyshev–Lobatto points of its interval, m the degree of the method's dense output
//! ([`dense_degree`]), which reproduces it exactly (a polynomial of degree ≤ m is determined
//! by m + 1 values); python/lash/_ivp.py evaluates it by barycentric interpolation (Berrut &
//! Trefethen, SIAM Review 46(3) 501–517, 2004).

use std::cell::{Cell, RefCell};

use faer::MatMut;
use pyo3::prelude::*;
use pyo3::types::{PyByteArray, PyDict, PyList, PyTuple};

use lash_solver::{
    Atol, ControllerKind, Direction, EventAction, EventHit, EventSpec, Method, OdeSystem, Problem,
    SolveError, SolverOptions, Stats, StepOutcome,
};

use crate::convert::{bytearray_from_f64s, f64s_from_bytes, Numpy};
use crate::errors::{failure_kind, usage_error};

/// The controller a method uses when none is given (docs/outputs.md, "Method and controller
/// names"): `pi` for the embedded explicit pairs, `gustafsson` for Rodas5P, none for RK4 and
/// diffsol's methods (they take no controller of ours).
pub fn default_controller(method: Method) -> Option<&'static str> {
    match method {
        Method::Bs32 | Method::Dopri54 | Method::Tsit54 | Method::Dop853 => {
            Some(ControllerKind::Pi.name())
        }
        Method::Rodas5p => Some(ControllerKind::Gustafsson.name()),
        Method::Rk4 | Method::Bdf | Method::Trbdf2 | Method::Esdirk34 => None,
    }
}

/// Degree in t of a method's dense output on one step (crates/solver: `rk4` and `bs32` cubic
/// Hermite, `dopri54`/`tsit54` order-4 continuous extensions and Rodas5P's interpolant of
/// degree 4, DOP853's of degree 7; diffsol's BDF interpolates its difference table, degree =
/// order ≤ 5, and its Runge–Kutta methods use Hermite or stage-weight polynomials of lower
/// degree, so 7 covers them). tests/test_dense.py checks that `sol(t)` equals the
/// integrator's own interpolation at `t_eval` for every method.
fn dense_degree(method: Method) -> usize {
    match method {
        Method::Rk4 | Method::Bs32 => 3,
        Method::Dopri54 | Method::Tsit54 | Method::Rodas5p => 4,
        Method::Dop853 | Method::Bdf | Method::Trbdf2 | Method::Esdirk34 => 7,
    }
}

/// θ_j = (1 − cos(π j / m)) / 2, j = 0..m: the Chebyshev–Lobatto points on [0, 1], ascending.
fn lobatto_nodes(m: usize) -> Vec<f64> {
    (0..=m)
        .map(|j| 0.5 * (1.0 - (std::f64::consts::PI * j as f64 / m as f64).cos()))
        .collect()
}

/// The Jacobian the user gave.
enum Jac<'py> {
    /// None: implicit methods use finite differences of `fun`.
    None,
    /// `jac(t, y, *args)` returning an (n, n) array.
    Callable(Bound<'py, PyAny>),
    /// A constant (n, n) matrix, row-major.
    Constant(Vec<f64>),
}

/// One event function with scipy's attributes and lash's hook.
struct PyEvent<'py> {
    fun: Bound<'py, PyAny>,
    direction: Direction,
    /// Occurrences after which the integration stops (0: never).
    terminal: usize,
    hook: Option<Bound<'py, PyAny>>,
}

/// What the event hooks recorded.
#[derive(Default)]
struct EventLog {
    /// Per event function: times (in t) and states (row-major, before the hook).
    t: Vec<Vec<f64>>,
    y: Vec<Vec<f64>>,
    /// State before the hook at the last event, when a hook changed it.
    pre_hook: Option<Vec<f64>>,
}

/// A Python ODE as an [`OdeSystem`].
struct PySystem<'py> {
    n: usize,
    /// d = ±1: solver time s = d·t.
    dir: f64,
    fun: Bound<'py, PyAny>,
    /// Extra positional arguments of every callback.
    args: Vec<Bound<'py, PyAny>>,
    jac: Jac<'py>,
    events: Vec<PyEvent<'py>>,
    np: Numpy<'py>,
    /// The first exception a callback raised.
    error: RefCell<Option<PyErr>>,
    log: RefCell<EventLog>,
    /// Calls of `fun` (Python).
    fun_calls: Cell<usize>,
    /// Calls of `jac` (Python).
    jac_calls: Cell<usize>,
}

impl<'py> PySystem<'py> {
    fn failed(&self) -> bool {
        self.error.borrow().is_some()
    }

    /// Keeps the first error.
    fn store(&self, e: PyErr) {
        let mut slot = self.error.borrow_mut();
        if slot.is_none() {
            *slot = Some(e);
        }
    }

    fn take_error(&self) -> Option<PyErr> {
        self.error.borrow_mut().take()
    }

    /// `f(t, y, *args)`.
    fn call(
        &self,
        f: &Bound<'py, PyAny>,
        t: f64,
        y: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        if self.args.is_empty() {
            f.call1((t, y))
        } else {
            let py = f.py();
            let mut items: Vec<Bound<'py, PyAny>> = Vec::with_capacity(2 + self.args.len());
            items.push(t.into_pyobject(py)?.into_any());
            items.push(y.clone());
            items.extend(self.args.iter().cloned());
            f.call1(PyTuple::new(py, items)?)
        }
    }

    fn eval_fun(&self, t: f64, y: &[f64], dy: &mut [f64]) -> PyResult<()> {
        let arr = self.np.array(y)?;
        self.fun_calls.set(self.fun_calls.get() + 1);
        let r = self.call(&self.fun, t, &arr)?;
        self.np.read_vector(&r, dy, "fun(t, y)")
    }

    fn eval_events(&self, t: f64, y: &[f64], g: &mut [f64]) -> PyResult<()> {
        let arr = self.np.array(y)?;
        for (gi, ev) in g.iter_mut().zip(&self.events) {
            *gi = self.call(&ev.fun, t, &arr)?.extract::<f64>()?;
        }
        Ok(())
    }

    fn eval_jac(&self, f: &Bound<'py, PyAny>, t: f64, y: &[f64], out: &mut [f64]) -> PyResult<()> {
        let arr = self.np.array(y)?;
        self.jac_calls.set(self.jac_calls.get() + 1);
        let r = self.call(f, t, &arr)?;
        self.np.read_array(&r, &[self.n, self.n], out, "jac(t, y)")
    }

    /// Runs event `i`'s hook; returns the new state, or None when it returned None.
    fn run_hook(&self, hook: &Bound<'py, PyAny>, t: f64, y: &[f64]) -> PyResult<Option<Vec<f64>>> {
        let arr = self.np.array(y)?;
        let r = self.call(hook, t, &arr)?;
        if r.is_none() {
            return Ok(None);
        }
        let mut y_new = vec![0.0; self.n];
        self.np
            .read_vector(&r, &mut y_new, "an event's hook(t, y)")?;
        Ok(Some(y_new))
    }
}

impl OdeSystem for PySystem<'_> {
    fn dim(&self) -> usize {
        self.n
    }

    fn rhs(&self, s: f64, y: &[f64], dy: &mut [f64]) {
        if self.failed() {
            dy.fill(f64::NAN);
            return;
        }
        match self.eval_fun(self.dir * s, y, dy) {
            Ok(()) => {
                if self.dir < 0.0 {
                    dy.iter_mut().for_each(|v| *v = -*v);
                }
            }
            Err(e) => {
                self.store(e);
                dy.fill(f64::NAN);
            }
        }
    }

    fn has_jacobian(&self) -> bool {
        !matches!(self.jac, Jac::None)
    }

    fn jacobian(&self, s: f64, y: &[f64], mut jac: MatMut<'_, f64>) {
        let n = self.n;
        let mut buf = vec![f64::NAN; n * n];
        match &self.jac {
            Jac::None => {}
            Jac::Constant(m) => buf.copy_from_slice(m),
            Jac::Callable(f) => {
                if !self.failed() {
                    if let Err(e) = self.eval_jac(f, self.dir * s, y, &mut buf) {
                        self.store(e);
                        buf.fill(f64::NAN);
                    }
                }
            }
        }
        for i in 0..n {
            for j in 0..n {
                jac[(i, j)] = self.dir * buf[i * n + j];
            }
        }
    }

    fn n_events(&self) -> usize {
        self.events.len()
    }

    fn event_spec(&self, i: usize) -> EventSpec {
        EventSpec {
            direction: self.events[i].direction,
            action: EventAction::Continue,
        }
    }

    fn events(&self, s: f64, y: &[f64], g: &mut [f64]) {
        if self.failed() {
            // NaN has no sign: no event is reported, and the stored error ends the run.
            g.fill(f64::NAN);
            return;
        }
        if let Err(e) = self.eval_events(self.dir * s, y, g) {
            self.store(e);
            g.fill(f64::NAN);
        }
    }

    fn on_event(&self, hit: &EventHit, y: &mut [f64]) -> EventAction {
        let t = self.dir * hit.t;
        let i = hit.index;
        let count = {
            let mut log = self.log.borrow_mut();
            log.t[i].push(t);
            log.y[i].extend_from_slice(y);
            log.t[i].len()
        };
        if self.failed() {
            return EventAction::Stop;
        }
        let ev = &self.events[i];
        if let Some(hook) = &ev.hook {
            match self.run_hook(hook, t, y) {
                Ok(Some(y_new)) if y_new.as_slice() != &*y => {
                    self.log.borrow_mut().pre_hook = Some(y.to_vec());
                    y.copy_from_slice(&y_new);
                }
                Ok(_) => {}
                Err(e) => {
                    self.store(e);
                    return EventAction::Stop;
                }
            }
        }
        if ev.terminal > 0 && count >= ev.terminal {
            EventAction::Stop
        } else {
            EventAction::Continue
        }
    }
}

/// An event as `lash.solve_ivp` passes it: `(function, direction sign, terminal count, hook
/// or None)`.
type EventDecl<'py> = (Bound<'py, PyAny>, i32, usize, Option<Bound<'py, PyAny>>);

/// What the integration loop records.
struct Record {
    t: Vec<f64>,
    y: Vec<f64>,
    /// Dense output: segment ends (in t) and values at the Lobatto nodes, (m + 1) · n each.
    seg_t0: Vec<f64>,
    seg_t1: Vec<f64>,
    seg_values: Vec<f64>,
}

/// Integrates a Python ODE; the engine of `lash.solve_ivp` (python/lash/_ivp.py), which
/// checks and normalises the arguments and documents them. Arrays come in as bytes of
/// native-endian f64 (`y0`, `atol`, `t_eval`, `jac_matrix`, row-major); `events` holds
/// `(function, direction, terminal count, hook or None)`.
///
/// Returns a dict: `t`, `y` (bytes, row-major (len(t), n)), `status` (0 end, 1 terminal
/// event, −1 failure), `message`, `t_events`/`y_events` (bytes per event), `stats` (lash's
/// counters and the Python call counts), `controller`, `dense` (None or `(nodes, t0s, t1s,
/// values)` as bytes), `failure` (None or `(kind, message, t, y)`).
#[pyfunction]
#[pyo3(signature = (fun, t0, t1, y0, method, t_eval, dense_output, events, rtol, atol, jac,
    jac_matrix, controller, max_step, first_step, min_step, max_steps, step, args))]
#[allow(clippy::too_many_arguments)]
pub fn solve_ivp_core<'py>(
    py: Python<'py>,
    fun: Bound<'py, PyAny>,
    t0: f64,
    t1: f64,
    y0: &[u8],
    method: &str,
    t_eval: Option<&[u8]>,
    dense_output: bool,
    events: Vec<EventDecl<'py>>,
    rtol: f64,
    atol: &[u8],
    jac: Option<Bound<'py, PyAny>>,
    jac_matrix: Option<&[u8]>,
    controller: Option<&str>,
    max_step: f64,
    first_step: Option<f64>,
    min_step: f64,
    max_steps: usize,
    step: Option<f64>,
    args: Vec<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let method = Method::from_name(method)
        .ok_or_else(|| usage_error(py, &format!("unknown method {method:?}")))?;
    let controller = match controller {
        None => None,
        Some(c) => Some(
            ControllerKind::from_name(c)
                .ok_or_else(|| usage_error(py, &format!("unknown controller {c:?}")))?,
        ),
    };
    let y0 = f64s_from_bytes(y0);
    let n = y0.len();
    if n == 0 {
        return Err(usage_error(py, "y0 must have at least one component"));
    }
    if t0 == t1 || !t0.is_finite() || !t1.is_finite() {
        return Err(usage_error(
            py,
            &format!("t_span must be two different finite times, got ({t0}, {t1})"),
        ));
    }
    let dir = if t1 > t0 { 1.0 } else { -1.0 };
    let atol = f64s_from_bytes(atol);
    let atol = if atol.len() == 1 {
        Atol::Scalar(atol[0])
    } else {
        Atol::Vector(atol)
    };
    let jac = match (jac, jac_matrix) {
        (Some(f), _) => Jac::Callable(f),
        (None, Some(m)) => {
            let m = f64s_from_bytes(m);
            if m.len() != n * n {
                return Err(usage_error(py, &format!("jac must have shape ({n}, {n})")));
            }
            Jac::Constant(m)
        }
        (None, None) => Jac::None,
    };
    let mut py_events = Vec::with_capacity(events.len());
    for (f, direction, terminal, hook) in events {
        let direction = match direction.signum() {
            1 => Direction::Rising,
            -1 => Direction::Falling,
            _ => Direction::Either,
        };
        py_events.push(PyEvent {
            fun: f,
            direction,
            terminal,
            hook,
        });
    }
    let m_events = py_events.len();
    let sys = PySystem {
        n,
        dir,
        fun,
        args,
        jac,
        events: py_events,
        np: Numpy::import(py)?,
        error: RefCell::new(None),
        log: RefCell::new(EventLog {
            t: vec![Vec::new(); m_events],
            y: vec![Vec::new(); m_events],
            pre_hook: None,
        }),
        fun_calls: Cell::new(0),
        jac_calls: Cell::new(0),
    };
    let opts = SolverOptions {
        method,
        rtol,
        atol,
        step,
        h0: first_step,
        h_min: min_step,
        h_max: max_step,
        max_steps,
        controller,
        ..SolverOptions::default()
    };
    // Output times in solver time, ascending.
    let s_eval: Option<Vec<f64>> =
        t_eval.map(|b| f64s_from_bytes(b).iter().map(|t| dir * t).collect());

    let problem = match Problem::new(&sys, &opts) {
        Ok(p) => p,
        Err(e) => {
            return Err(sys
                .take_error()
                .unwrap_or_else(|| solve_error_to_usage(py, &e)))
        }
    };
    let (s0, s1) = (dir * t0, dir * t1);
    let mut rec = Record {
        t: Vec::new(),
        y: Vec::new(),
        seg_t0: Vec::new(),
        seg_t1: Vec::new(),
        seg_values: Vec::new(),
    };
    let degree = dense_degree(method);
    let nodes = lobatto_nodes(degree);
    let mut next_eval = 0usize;
    let push = |rec: &mut Record, s: f64, y: &[f64]| {
        rec.t.push(dir * s);
        rec.y.extend_from_slice(y);
    };
    let mut status = 0i32;
    let mut failure: Option<SolveError> = None;
    let mut stats = Stats::default();
    match problem.integrator(s0, s1, &y0) {
        Err(e) => {
            if let Some(err) = sys.take_error() {
                return Err(err);
            }
            if let SolveError::InvalidOptions(_) = e {
                return Err(solve_error_to_usage(py, &e));
            }
            failure = Some(e);
        }
        Ok(mut it) => {
            if let Some(err) = sys.take_error() {
                return Err(err);
            }
            match &s_eval {
                Some(ts) => {
                    while next_eval < ts.len() && ts[next_eval] <= s0 {
                        push(&mut rec, ts[next_eval], &y0);
                        next_eval += 1;
                    }
                }
                None => push(&mut rec, s0, &y0),
            }
            let mut buf = vec![0.0; n];
            loop {
                let outcome = it.step();
                if let Some(err) = sys.take_error() {
                    return Err(err);
                }
                let outcome = match outcome {
                    Ok(o) => o,
                    Err(e) => {
                        failure = Some(e);
                        break;
                    }
                };
                let s_now = it.t();
                let s_prev = it.t_prev();
                // The state before the hook, when a hook changed it at this event.
                let pre_hook = match outcome {
                    StepOutcome::Event { .. } => sys.log.borrow_mut().pre_hook.take(),
                    _ => None,
                };
                if dense_output && s_now > s_prev {
                    rec.seg_t0.push(dir * s_prev);
                    rec.seg_t1.push(dir * s_now);
                    for (j, th) in nodes.iter().enumerate() {
                        if j == degree {
                            // The right end: the state before any hook.
                            match &pre_hook {
                                Some(yp) => rec.seg_values.extend_from_slice(yp),
                                None => rec.seg_values.extend_from_slice(it.y()),
                            }
                        } else {
                            it.interpolate(s_prev + th * (s_now - s_prev), &mut buf);
                            rec.seg_values.extend_from_slice(&buf);
                        }
                    }
                }
                match &s_eval {
                    Some(ts) => {
                        while next_eval < ts.len() && ts[next_eval] <= s_now {
                            let sq = ts[next_eval];
                            if sq >= s_now {
                                buf.copy_from_slice(it.y());
                            } else {
                                it.interpolate(sq, &mut buf);
                            }
                            push(&mut rec, sq, &buf);
                            next_eval += 1;
                        }
                    }
                    None => {
                        if let Some(yp) = &pre_hook {
                            push(&mut rec, s_now, yp);
                        }
                        push(&mut rec, s_now, it.y());
                    }
                }
                match outcome {
                    StepOutcome::Event { stopped: true, .. } => {
                        status = 1;
                        break;
                    }
                    StepOutcome::StopTime { .. } => break,
                    _ => {}
                }
                if it.is_finished() {
                    break;
                }
            }
            stats = it.stats();
        }
    }
    if let Some(err) = sys.take_error() {
        return Err(err);
    }

    let out = PyDict::new(py);
    out.set_item("n", n)?;
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
    out.set_item(
        "controller",
        controller
            .map(|c| c.name())
            .or_else(|| default_controller(method)),
    )?;
    if dense_output {
        let dense: (Bound<'py, PyByteArray>, _, _, _) = (
            bytearray_from_f64s(py, &nodes)?,
            bytearray_from_f64s(py, &rec.seg_t0)?,
            bytearray_from_f64s(py, &rec.seg_t1)?,
            bytearray_from_f64s(py, &rec.seg_values)?,
        );
        out.set_item("dense", dense)?;
    } else {
        out.set_item("dense", py.None())?;
    }
    match failure {
        None => {
            out.set_item("status", status)?;
            out.set_item(
                "message",
                if status == 1 {
                    "A termination event occurred."
                } else {
                    "The solver successfully reached the end of the integration interval."
                },
            )?;
            out.set_item("failure", py.None())?;
        }
        Some(e) => {
            let t_fail = e.time().map_or(t0, |s| dir * s);
            let y_fail = e.state().map_or_else(|| y0.clone(), <[f64]>::to_vec);
            let message = failure_message(&e, t_fail);
            out.set_item("status", -1)?;
            out.set_item("message", &message)?;
            out.set_item(
                "failure",
                (
                    failure_kind(&e),
                    message,
                    t_fail,
                    bytearray_from_f64s(py, &y_fail)?,
                ),
            )?;
        }
    }
    Ok(out)
}

/// An options error as `lash.UsageError`; other failures cannot reach here.
fn solve_error_to_usage(py: Python<'_>, e: &SolveError) -> PyErr {
    match e {
        SolveError::InvalidOptions(m) => usage_error(py, &m.to_string()),
        other => usage_error(py, &other.to_string()),
    }
}

/// The failure's message with the time in the caller's t (the solver's own message uses
/// solver time, which is −t when integrating backwards).
fn failure_message(e: &SolveError, t: f64) -> String {
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
    }
}
