//! The interface every method implements and the rules they share. The factory that builds
//! the stepper of a [`Method`] ([`crate::integrator::make_stepper`]) lives with the
//! [`crate::Integrator`] that drives it, so that this file needs none of its implementors.
//!
//! A stepper owns the state (t, y) and the dense output of its last accepted step. It never
//! sees events or output requests: the [`crate::Integrator`] drives it, locates events on its
//! dense output, and restarts it at event states.
//!
//! ```text
//! one-step methods (explicit pairs, Rodas5P)  →  crate::onestep::OneStepDriver (one loop)
//! RK4 (fixed step)                            →  crate::rk4::Rk4
//! diffsol's BDF, TR-BDF2, ESDIRK3(4)          →  crate::diffsol_backend::DiffsolStepper
//! ```
//!
//! Rules every stepper follows (one function each, below):
//! - landing ([`landing_step`]): a step that would end within max(10⁻¹⁰ h, 16 ε |t_stop|) of
//!   the stop time ends exactly on it, so no sliver is left for a later step;
//! - the stop time must lie after t ([`check_stop`]), else [`SolveError::InvalidOptions`]
//!   (field `t_stop`);
//! - the smallest step is max(h_min, 16 ε |t|) ([`step_floor`]);
//! - budgets ([`Budget`]): `max_steps` attempts (accepted and rejected) and the wall-clock
//!   budget `max_wall_time`, counted from the stepper's construction; and the process-wide
//!   stop request ([`crate::interrupt`]).

use std::time::{Duration, Instant};

use crate::error::SolveError;
use crate::method::Method;
use crate::options::{Atol, Budgets, OptionError, OptionField, Reason, Tolerances};
use crate::stats::Stats;
use crate::system::OdeSystem;

/// One integration method in motion.
pub trait Stepper {
    /// The method.
    fn method(&self) -> Method;
    /// Time of the current state (the end of the last accepted step).
    fn t(&self) -> f64;
    /// Current state.
    fn y(&self) -> &[f64];
    /// Start of the last accepted step (equals `t()` right after construction or a restart).
    fn t_prev(&self) -> f64;
    /// Takes one accepted step (retrying rejected attempts inside), never past `t_stop`; a step
    /// that would end within the landing margin of `t_stop` ends exactly on it
    /// ([`landing_step`]). Fails with a typed error when the step size underflows, a budget
    /// runs out, the Newton iteration cannot converge, or the state becomes non-finite.
    fn step(&mut self, t_stop: f64) -> Result<(), SolveError>;
    /// Dense output: writes y(t) for t in [t_prev, t] into `out`.
    fn interpolate(&self, t: f64, out: &mut [f64]);
    /// Dense output at several times of the last step, one state after another:
    /// `out[k n..(k + 1) n]` = y(`ts[k]`), each as [`Stepper::interpolate`] writes it
    /// (`out` holds `ts.len()` states of n = `y().len()`). The default calls it once a time;
    /// a stepper overrides it to set up once for the whole grid of a step.
    fn interpolate_many(&self, ts: &[f64], out: &mut [f64]) {
        let n = self.y().len();
        if n == 0 {
            return;
        }
        for (&t, o) in ts.iter().zip(out.chunks_exact_mut(n)) {
            self.interpolate(t, o);
        }
    }
    /// Restarts from (t, y), discarding all history (FSAL stage, controller history, multistep
    /// history and order). The next trial step is chosen as at the start: `opts.h0` when
    /// given, else the starting-step algorithm ([`initial_step`] or diffsol's equivalent).
    fn restart(&mut self, t: f64, y: &[f64]) -> Result<(), SolveError>;
    /// Counters so far, by value. Reading them never changes them.
    fn stats(&self) -> Stats;
    /// The increments of the system's quadrature variables ([`OdeSystem::n_quadratures`])
    /// over the last accepted step [t_prev, t], by the method's own formula at its own stage
    /// states, into `value`, and the method's estimate of their local error into `estimate`
    /// when it has one ([`StepQuadrature`]). The default (and a method that cannot give them
    /// for this step): [`StepQuadrature::Unavailable`], nothing written.
    fn step_quadrature(&self, value: &mut [f64], estimate: &mut [f64]) -> StepQuadrature {
        let _ = (value, estimate);
        StepQuadrature::Unavailable
    }
    /// Sets the largest step from the next attempt on (the contact-aware step limit of the
    /// [`crate::Integrator`], already capped by the options' `h_max`). Fixed-step methods
    /// ignore it.
    fn set_h_max(&mut self, h_max: f64);
    /// Takes the last accepted step again from its start, ending exactly at `t`
    /// (t_prev < t < t_prev + the step's length as first taken, so a retaken step can be
    /// retaken again, longer or shorter), so that the state at `t` is a step's end rather
    /// than a point of the dense output (`exact_event_steps`, [`crate::integrator`] "Exact
    /// event steps"). Returns true when t() = `t` afterwards, its state and dense output
    /// those of the new step; false when the method cannot (the default: fixed-step and
    /// diffsol's methods, and `t` outside the step) or the new step failed its error test,
    /// the last step and its dense output then being as before. Counts one attempt, two when
    /// the new step fails (the last one is taken again); the count of accepted steps does
    /// not change.
    fn retake(&mut self, t: f64) -> Result<bool, SolveError> {
        let _ = t;
        Ok(false)
    }
}

/// What [`Stepper::step_quadrature`] wrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StepQuadrature {
    /// Nothing: the method does not integrate quadratures, the system has none, or the last
    /// step has none of its own (a start, a restart, diffsol's Euler sliver).
    Unavailable,
    /// The increments, without an error estimate (diffsol's methods).
    Value,
    /// The increments and the method's estimate of their local error (|increment − the
    /// embedded formula's|, componentwise).
    ValueAndEstimate,
}

/// The landing rule of every stepper: the step to try from `t` towards `t_stop` with the
/// proposed size `h`, and whether it lands on `t_stop`.
///
/// ```text
/// r = t_stop − t,  sliver = max(10⁻¹⁰ h, 16 ε |t_stop|)
/// r − h ≤ sliver  →  (r, lands)         else  (h, not lands)
/// ```
/// A step that lands ends exactly on `t_stop` (the caller sets t = t_stop, not t + r).
pub fn landing_step(t: f64, t_stop: f64, h: f64) -> (f64, bool) {
    let remaining = t_stop - t;
    let sliver = (1e-10 * h).max(16.0 * f64::EPSILON * t_stop.abs());
    if remaining - h <= sliver {
        (remaining, true)
    } else {
        (h, false)
    }
}

/// The precondition of [`Stepper::step`]: the stop time lies after t. Every stepper reports
/// its violation the same way, as [`SolveError::InvalidOptions`] of the field `t_stop`.
pub fn check_stop(t: f64, t_stop: f64) -> Result<(), SolveError> {
    if t_stop > t {
        Ok(())
    } else {
        Err(OptionError::new(OptionField::TStop, Reason::NotAfter { value: t_stop, t }).into())
    }
}

/// The smallest step a stepper may take at time t: max(h_min, 16 ε |t|) (below 16 ulps of t
/// a step no longer moves t reliably).
pub fn step_floor(h_min: f64, t: f64) -> f64 {
    h_min.max(16.0 * f64::EPSILON * t.abs())
}

/// The instant `w` seconds after `start`: the deadline of a wall-clock budget.
///
/// ```text
/// w finite, > 0, within the clock's range → Some(start + w)
/// anything else (NaN, ≤ 0, ∞, beyond ~2⁶⁴ s) → None: no deadline
/// ```
/// The option rules reject NaN and w ≤ 0 (`Rule::MAX_WALL_TIME`) before a budget runs; a
/// finite budget too long for the clock is no budget. `Duration::from_secs_f64` would panic
/// on both.
pub fn deadline_after(start: Instant, w: f64) -> Option<Instant> {
    Duration::try_from_secs_f64(w)
        .ok()
        .filter(|d| !d.is_zero())
        .and_then(|d| start.checked_add(d))
}

/// The budgets of one integration: step attempts and wall-clock time.
///
/// ```text
/// stop requested            → Interrupted   (crate::interrupt)
/// attempts ≥ max_steps      → TooManySteps
/// now ≥ start + max_wall    → BudgetExhausted
/// the thread's deadline     → BudgetExhausted (crate::interrupt::deadline_scope)
/// ```
#[derive(Clone, Debug)]
pub struct Budget {
    max_steps: usize,
    deadline: Option<(Instant, f64)>,
}

impl Budget {
    /// The budgets of a configuration, the wall clock starting now.
    pub fn new(budgets: Budgets) -> Self {
        Budget {
            max_steps: budgets.max_steps(),
            deadline: budgets
                .max_wall_time()
                .and_then(|w| deadline_after(Instant::now(), w).map(|d| (d, w))),
        }
    }

    /// Checks the budgets before an attempt, with `attempts` made so far; the error carries
    /// the time and state of the last accepted step.
    ///
    /// Every check runs before every attempt. Without a wall-clock budget of its own or of the
    /// thread ([`crate::interrupt::deadline_scope`]) the answer is known from a flag, a count
    /// and whether there is a deadline, tested inline; the clock is read, and an error built,
    /// only out of line (`check_all`).
    #[inline]
    pub fn check(&self, attempts: usize, t: f64, y: &[f64]) -> Result<(), SolveError> {
        if crate::interrupt::stop_requested()
            || attempts >= self.max_steps
            || self.deadline.is_some()
            || crate::interrupt::deadline_set()
        {
            return self.check_all(attempts, t, y);
        }
        Ok(())
    }

    /// [`Budget::check`]'s checks one by one, in their order, with their errors.
    #[cold]
    #[inline(never)]
    fn check_all(&self, attempts: usize, t: f64, y: &[f64]) -> Result<(), SolveError> {
        if crate::interrupt::stop_requested() {
            return Err(SolveError::Interrupted { t, y: y.to_vec() });
        }
        if attempts >= self.max_steps {
            return Err(SolveError::TooManySteps {
                t,
                steps: attempts,
                y: y.to_vec(),
            });
        }
        if let Some((deadline, w)) = self.deadline {
            if Instant::now() >= deadline {
                return Err(SolveError::BudgetExhausted {
                    t,
                    y: y.to_vec(),
                    reason: format!("wall-clock budget of {w} s used"),
                });
            }
        }
        if let Some(w) = crate::interrupt::deadline_passed() {
            return Err(SolveError::BudgetExhausted {
                t,
                y: y.to_vec(),
                reason: format!("wall-clock budget of {w} s used"),
            });
        }
        Ok(())
    }
}

/// Hairer's starting-step algorithm (HNW I, §II.4, p. 169): a first step for a method of
/// order `order` from the scaled norms of y0, f0 and a finite-difference estimate of y'',
/// capped by `h_max`. Uses 1 extra RHS evaluation (counted by the caller).
#[allow(clippy::too_many_arguments)]
pub fn initial_step<S: OdeSystem + ?Sized>(
    sys: &S,
    t0: f64,
    y0: &[f64],
    f0: &[f64],
    order: usize,
    tol: &Tolerances,
    h_max: f64,
    t_stop: f64,
) -> f64 {
    let n = y0.len();
    let span = (t_stop - t0).abs();
    let (rtol, atol) = (tol.rtol(), tol.atol());
    let sc = |i: usize| atol.get(i) + rtol * y0[i].abs();
    let rms = |v: &dyn Fn(usize) -> f64| -> f64 {
        ((0..n).map(|i| v(i).powi(2)).sum::<f64>() / n.max(1) as f64).sqrt()
    };
    let d0 = rms(&|i| y0[i] / sc(i));
    let d1 = rms(&|i| f0[i] / sc(i));
    let mut h0 = if d0 < 1e-5 || d1 < 1e-5 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    h0 = h0.min(span).min(h_max);
    let y1: Vec<f64> = (0..n).map(|i| y0[i] + h0 * f0[i]).collect();
    let mut f1 = vec![0.0; n];
    sys.rhs(t0 + h0, &y1, &mut f1);
    let d2 = rms(&|i| (f1[i] - f0[i]) / sc(i)) / h0;
    let h1 = if d1.max(d2) <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / d1.max(d2)).powf(1.0 / (order as f64 + 1.0))
    };
    let h = (100.0 * h0).min(h1).min(span).min(h_max);
    if h.is_finite() && h > 0.0 {
        h
    } else {
        (span * 1e-6).max(f64::MIN_POSITIVE)
    }
}

/// Weighted RMS norm of an error vector: sqrt(mean((err_i / (atol_i + rtol·max(|y_i|, |ŷ_i|)))²)),
/// the norm of HNW I (4.11). NaN in `err` gives +∞ (the step is rejected).
pub fn error_norm(err: &[f64], y_old: &[f64], y_new: &[f64], rtol: f64, atol: &Atol) -> f64 {
    let n = err.len();
    let mut s = 0.0;
    for i in 0..n {
        let sc = atol.get(i) + rtol * y_old[i].abs().max(y_new[i].abs());
        let r = err[i] / sc;
        s += r * r;
    }
    let e = (s / n.max(1) as f64).sqrt();
    if e.is_nan() {
        f64::INFINITY
    } else {
        e
    }
}
