//! The system stage of `solve_ivp_core`: a Python right-hand side, Jacobian, event
//! functions and hooks as an [`OdeSystem`] (module doc of `ivp` for the time map).
//!
//! Callbacks run with the GIL held (the caller's thread). The first exception a callback
//! raises is stored; from then on every callback returns NaN without calling Python, so the
//! method fails within a few attempts; the stored exception is then raised unchanged, before
//! any solver error.

use std::cell::{Cell, RefCell};

use faer::MatMut;
use pyo3::intern;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use lash_solver::memory::MemoryError;
use lash_solver::{Direction, EventAction, EventHit, EventSpec, OdeSystem};

use crate::convert::Numpy;

/// The Jacobian the user gave.
pub enum Jac<'py> {
    /// None: implicit methods use finite differences of `fun`.
    None,
    /// `jac(t, y, *args)` returning an (n, n) array.
    Callable(Bound<'py, PyAny>),
    /// A constant (n, n) matrix, row-major.
    Constant(Vec<f64>),
}

/// One event function with scipy's attributes and lash's hook.
pub struct PyEvent<'py> {
    /// `event(t, y, *args) -> float`.
    pub fun: Bound<'py, PyAny>,
    /// Which crossings count (along the integration).
    pub direction: Direction,
    /// Occurrences after which the integration stops (0: never).
    pub terminal: usize,
    /// `hook(t, y, *args) -> state or None`.
    pub hook: Option<Bound<'py, PyAny>>,
}

/// What the event hooks recorded.
#[derive(Default)]
pub struct EventLog {
    /// Per event function: times (in t) and states (row-major, before the hook).
    pub t: Vec<Vec<f64>>,
    /// The states, as `t`.
    pub y: Vec<Vec<f64>>,
    /// State before the hook at the last event, when a hook changed it.
    pub pre_hook: Option<Vec<f64>>,
}

/// A Python ODE as an [`OdeSystem`].
pub struct PySystem<'py> {
    /// Dimension n.
    pub n: usize,
    /// d = ±1: solver time s = d·t.
    pub dir: f64,
    /// `fun(t, y, *args)`.
    pub fun: Bound<'py, PyAny>,
    /// Whether `fun` is called with y of shape (n, 1) (scipy's `vectorized`); its result is
    /// raveled.
    pub vectorized: bool,
    /// Extra positional arguments of every callback.
    pub args: Vec<Bound<'py, PyAny>>,
    /// The Jacobian.
    pub jac: Jac<'py>,
    /// For each column of ∂f/∂y its possibly nonzero rows (scipy's `jac_sparsity`).
    pub sparsity: Option<Vec<Vec<usize>>>,
    /// The event functions.
    pub events: Vec<PyEvent<'py>>,
    /// numpy's functions.
    pub np: Numpy<'py>,
    /// The first exception a callback raised.
    pub error: RefCell<Option<PyErr>>,
    /// What the event hooks recorded.
    pub log: RefCell<EventLog>,
    /// Calls of `fun` (Python).
    pub fun_calls: Cell<usize>,
    /// Calls of `jac` (Python).
    pub jac_calls: Cell<usize>,
    /// The values `jac` returned, row-major n × n (allocated at the first call).
    pub jac_buf: RefCell<Vec<f64>>,
}

impl<'py> PySystem<'py> {
    /// Whether a callback raised.
    pub fn failed(&self) -> bool {
        self.error.borrow().is_some()
    }

    /// Keeps the first error.
    fn store(&self, e: PyErr) {
        let mut slot = self.error.borrow_mut();
        if slot.is_none() {
            *slot = Some(e);
        }
    }

    /// The stored exception, if any (taken).
    pub fn take_error(&self) -> Option<PyErr> {
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
        if self.vectorized {
            let py = arr.py();
            let col = arr.call_method1(intern!(py, "reshape"), ((self.n, 1usize),))?;
            let r = self.call(&self.fun, t, &col)?;
            let flat = self.np.ravel(&r)?;
            return self.np.read_array(&flat, &[self.n], dy, "fun(t, y)");
        }
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
        let mut r = self.call(f, t, &arr)?;
        let py = r.py();
        // A scipy.sparse matrix (scipy's jac may return one).
        if r.hasattr(intern!(py, "toarray"))? {
            r = r.call_method0(intern!(py, "toarray"))?;
        }
        if self.n == 1 {
            // A scalar for a one-dimensional system, as scipy's LSODA accepts.
            let flat = self.np.ravel(&r)?;
            if flat.len()? == 1 {
                return self.np.read_array(&flat, &[1], out, "jac(t, y)");
            }
        }
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

    fn jacobian_sparsity(&self) -> Option<Vec<Vec<usize>>> {
        self.sparsity.clone()
    }

    fn jacobian(&self, s: f64, y: &[f64], mut jac: MatMut<'_, f64>) {
        let n = self.n;
        let copy = |jac: &mut MatMut<'_, f64>, m: &[f64]| {
            for i in 0..n {
                for j in 0..n {
                    jac[(i, j)] = self.dir * m[i * n + j];
                }
            }
        };
        let f = match &self.jac {
            Jac::None | Jac::Callable(_) if self.failed() => None,
            Jac::None => None,
            Jac::Constant(m) => return copy(&mut jac, m),
            Jac::Callable(f) => Some(f),
        };
        let Some(f) = f else {
            return jac.fill(f64::NAN);
        };
        // The callback's n² values, in a buffer allocated once and fallibly (its size comes
        // from the input: a refusal is lash.OutOfMemoryError, not an abort).
        let mut buf = self.jac_buf.borrow_mut();
        if buf.len() != n * n {
            let bytes = (n as u64).saturating_mul(n as u64).saturating_mul(8);
            if buf.try_reserve_exact(n * n).is_err() {
                let e = MemoryError {
                    what: format!("the {n} × {n} Jacobian that jac returns"),
                    needed: bytes,
                    budget: 0,
                    basis: "the allocator".into(),
                };
                self.store(crate::errors::memory_error(f.py(), &e));
                return jac.fill(f64::NAN);
            }
            buf.resize(n * n, f64::NAN);
        }
        if let Err(e) = self.eval_jac(f, self.dir * s, y, &mut buf) {
            self.store(e);
            return jac.fill(f64::NAN);
        }
        copy(&mut jac, &buf);
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
            // NaN has no sign: the solver stops (SolveError::EventNan) and the stored
            // exception is raised in its place (drive.rs).
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
