//! The one adaptive driver of every one-step method (the explicit pairs, Rodas5P, and any
//! one-step method added later).
//!
//! ```text
//! method (OneStepMethod): start(t, y)          what belongs to the step's start (f(t, y), J, ∂f/∂t)
//!                         attempt(h) → ε       one trial step to t + h, its error norm
//!                         accept(h)            commit the trial (dense output, FSAL stage)
//!                         interpolate(θ)       dense output over the accepted step
//!                         reset()              forget everything tied to the state (restart)
//!
//! driver (OneStepDriver): owns t, y, h, the controller, the landing rule, h_min, h_max,
//! the budgets and the counters:
//!   controller = the configuration's (the options' choice, else the method's default:
//!                Method::default_controller)
//!   h  = h0, else the starting-step algorithm (HNW I §II.4)          at t0 and after a restart
//!        (after a restart that follows a retaken step: min(that, the retaken step's
//!        original length); Stepper::retake, crate::integrator "Exact event steps")
//!   loop: budgets; (h_try, lands) = landing_step(t, t_stop, h); h_try ≥ floor or fail
//!         ε = attempt(h_try)
//!         ε ≤ 1 → accept; t ← t_stop if lands else t + h_try; h ← clamp(controller, h_min, h_max)
//!         ε > 1 → reject; h ← controller.reject (ε = ∞ for non-finite stages)
//!         singular iteration matrix → reject; h ← h/4
//!         proposal below h_min → one try at h_min; a rejection there fails
//! ```
//!
//! Failures (typed, with the time and state of the last accepted step): the step size fell
//! below max(h_min, 16 ε |t|) → `StepSizeTooSmall`, or `NonFiniteState` when the last attempt
//! had non-finite stages, or `NewtonFailure` when its iteration matrix was singular; a budget
//! ran out → `TooManySteps` / `BudgetExhausted`.
//!
//! With `adaptive = false` (`StepControl::Fixed`) every step is `h0` (the last one
//! shortened by the landing rule), no error estimate is used and nothing is rejected: a non-finite attempt
//! fails with `NonFiniteState` (`NewtonFailure` for a singular iteration matrix). This is the
//! mode of fixed-step convergence-order tests.

use crate::controller::StepSizeControl;
use crate::error::SolveError;
use crate::method::Method;
use crate::options::{OneStepConfig, StepControl, Tolerances};
use crate::stats::Stats;
use crate::stepper::{
    check_stop, initial_step, landing_step, step_floor, Budget, StepQuadrature, Stepper,
};
use crate::system::OdeSystem;

/// What one trial step gave.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Attempt {
    /// The scaled error norm of the trial (≤ 1 passes the error test; +∞ when a stage or the
    /// result is non-finite). Without error estimation (`estimate == false`), 0 for a finite
    /// trial.
    Error(f64),
    /// The iteration matrix of an implicit method could not be factored (a zero or non-finite
    /// pivot).
    Singular,
}

/// A one-step method as the [`OneStepDriver`] sees it. The driver owns t, y and the step
/// size; the method owns its stages and dense-output coefficients.
pub trait OneStepMethod<S: OdeSystem + ?Sized> {
    /// The method's name.
    fn method(&self) -> Method;
    /// Order p̂ of the error estimate (the controller's exponent is 1/(p̂ + 1)).
    fn error_order(&self) -> usize;
    /// Prepares a step from (t, y): what belongs to the step's start and is reused by every
    /// attempt (f(t, y), and for a Rosenbrock method J and ∂f/∂t). Called once per step, before
    /// the first attempt. Fails with `NonFiniteState` when f(t, y) is not finite.
    fn start(&mut self, sys: &S, t: f64, y: &[f64], stats: &mut Stats) -> Result<(), SolveError>;
    /// f(t, y) at the step's start (valid after [`OneStepMethod::start`]).
    fn f_start(&self) -> &[f64];
    /// One trial step of size h from (t, y). With `estimate == false` no error estimate is
    /// needed.
    fn attempt(
        &mut self,
        sys: &S,
        t: f64,
        y: &[f64],
        h: f64,
        estimate: bool,
        stats: &mut Stats,
    ) -> Attempt;
    /// The result y_{n+1} of the last attempt.
    fn y_new(&self) -> &[f64];
    /// Commits the last attempt (of size h) as the accepted step.
    fn accept(&mut self, h: f64);
    /// Dense output over the accepted step [t_prev, t_prev + h] at θ ∈ [0, 1].
    #[allow(clippy::too_many_arguments)]
    fn interpolate(
        &self,
        sys: &S,
        t_prev: f64,
        h: f64,
        y_prev: &[f64],
        y: &[f64],
        theta: f64,
        out: &mut [f64],
    );
    /// Forgets everything tied to the current state (a restart).
    fn reset(&mut self);
    /// Returns to the start of the last accepted step (the driver restores t and y), keeping
    /// what is still valid there. The default forgets everything ([`OneStepMethod::reset`]).
    fn rewind(&mut self) {
        self.reset();
    }
    /// The quadrature increments over the accepted step [t_prev, t_prev + h] (h as given to
    /// [`OneStepMethod::accept`]) from y_prev, by the method's own formula at its stage states
    /// ([`Stepper::step_quadrature`]). Default: unavailable.
    fn quadrature(
        &self,
        sys: &S,
        t_prev: f64,
        y_prev: &[f64],
        value: &mut [f64],
        estimate: &mut [f64],
    ) -> StepQuadrature {
        let _ = (sys, t_prev, y_prev, value, estimate);
        StepQuadrature::Unavailable
    }
    /// RHS evaluations made by [`OneStepMethod::interpolate`] so far (lazy dense stages),
    /// which the driver adds to its counters when they are read.
    fn lazy_rhs_evals(&self) -> usize {
        0
    }
}

/// Why the last attempt was rejected (decides the error when h underflows).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Failure {
    None,
    Error,
    Singular,
    NonFinite,
}

/// The adaptive step loop of every one-step method (module documentation).
pub struct OneStepDriver<'a, S: OdeSystem + ?Sized, M> {
    sys: &'a S,
    m: M,
    /// The error control (None with `adaptive = false`: every step is `h0`).
    control: Option<StepSizeControl>,
    tol: Tolerances,
    /// The first trial step (None: the starting-step algorithm); with `adaptive = false`
    /// the step of every step.
    h0: Option<f64>,
    h_min: f64,
    h_max: f64,
    budget: Budget,
    t: f64,
    t_prev: f64,
    y: Vec<f64>,
    y_prev: Vec<f64>,
    /// Trial step of the next attempt (None: `h0` or the starting-step algorithm).
    h_next: Option<f64>,
    /// Whether `m.start` has run for the current (t, y).
    started: bool,
    /// The step size h of the last accepted step, as attempted (t − t_prev may differ from it
    /// by a rounding).
    h_step: f64,
    /// The length of the last accepted step as first taken, when it was retaken to end on an
    /// event ([`Stepper::retake`]); None after any other step.
    h_taken: Option<f64>,
    /// After a restart that follows a retaken step: that step's length as first taken, which
    /// bounds the first step from the restart (module documentation).
    h_before_event: Option<f64>,
    stats: Stats,
}

impl<'a, S: OdeSystem + ?Sized, M: OneStepMethod<S>> OneStepDriver<'a, S, M> {
    /// The driver of method `m` at (t0, y0) with the configuration `cfg` (its controller,
    /// limits, step bounds, tolerances and budgets). Nothing is evaluated before the first
    /// step.
    pub fn new(sys: &'a S, m: M, t0: f64, y0: &[f64], cfg: &OneStepConfig) -> Self {
        let (control, h0, h_min, h_max) = match cfg.control() {
            StepControl::Adaptive(a) => {
                let b = a.bounds();
                let control =
                    StepSizeControl::new(Box::new(a.controller().build()), a.limits().clone());
                (Some(control), b.h0(), b.h_min(), b.h_max())
            }
            // The bounds are not used without error control.
            StepControl::Fixed { h } => (None, Some(*h), 0.0, f64::INFINITY),
        };
        OneStepDriver {
            sys,
            control,
            tol: cfg.tolerances().clone(),
            h0,
            h_min,
            h_max,
            m,
            budget: Budget::new(cfg.budgets()),
            t: t0,
            t_prev: t0,
            y: y0.to_vec(),
            y_prev: y0.to_vec(),
            h_next: None,
            started: false,
            h_step: 0.0,
            h_taken: None,
            h_before_event: None,
            stats: Stats::default(),
        }
    }

    /// The method.
    pub fn inner(&self) -> &M {
        &self.m
    }

    fn underflow(&self, h: f64, last: Failure) -> SolveError {
        let (t, y) = (self.t, self.y.clone());
        match last {
            Failure::Singular => SolveError::NewtonFailure {
                t,
                y,
                reason: format!(
                    "the iteration matrix is singular for every step size down to {h:e}"
                ),
            },
            Failure::NonFinite => SolveError::NonFiniteState { t, y },
            Failure::None | Failure::Error => SolveError::StepSizeTooSmall { t, h, y },
        }
    }

    /// The first trial step from the current state: `h0`, else the starting-step
    /// algorithm (one RHS evaluation), raised to h_min.
    fn first_step(&mut self, t_stop: f64) -> f64 {
        match self.h0 {
            Some(h0) => h0,
            None => {
                let h = initial_step(
                    self.sys,
                    self.t,
                    &self.y,
                    self.m.f_start(),
                    self.m.error_order(),
                    &self.tol,
                    self.h_max,
                    t_stop,
                );
                self.stats.rhs_evals += 1;
                h.max(self.h_min)
            }
        }
    }
}

impl<S: OdeSystem + ?Sized, M: OneStepMethod<S>> Stepper for OneStepDriver<'_, S, M> {
    fn method(&self) -> Method {
        self.m.method()
    }
    fn t(&self) -> f64 {
        self.t
    }
    fn y(&self) -> &[f64] {
        &self.y
    }
    fn t_prev(&self) -> f64 {
        self.t_prev
    }

    fn step(&mut self, t_stop: f64) -> Result<(), SolveError> {
        check_stop(self.t, t_stop)?;
        if !self.started {
            self.m.start(self.sys, self.t, &self.y, &mut self.stats)?;
            self.started = true;
        }
        let adaptive = self.control.is_some();
        let (h_min, h_max) = (self.h_min, self.h_max);
        let p_hat = self.m.error_order();
        let mut h = match self.h_next {
            Some(h) => h,
            None => {
                let fresh = self.first_step(t_stop);
                match self.h_before_event.take() {
                    Some(h_before) => fresh.min(h_before),
                    None => fresh,
                }
            }
        };
        if adaptive {
            h = h.min(h_max).max(h_min);
        }
        let mut last = Failure::None;
        loop {
            self.budget.check(self.stats.steps, self.t, &self.y)?;
            let (h_try, lands) = landing_step(self.t, t_stop, h);
            let floor = step_floor(0.0, self.t);
            if !(h_try > 0.0) || (!lands && (!(h_try > floor) || self.t + h_try == self.t)) {
                return Err(self.underflow(h_try, last));
            }
            self.stats.steps += 1;
            let outcome =
                self.m
                    .attempt(self.sys, self.t, &self.y, h_try, adaptive, &mut self.stats);
            let err = match outcome {
                Attempt::Error(err) if err <= 1.0 => err,
                Attempt::Error(err) => {
                    let Some(control) = self.control.as_mut() else {
                        return Err(self.underflow(h_try, Failure::NonFinite));
                    };
                    self.stats.rejected_error += 1;
                    last = if err.is_finite() {
                        Failure::Error
                    } else {
                        Failure::NonFinite
                    };
                    let proposal = control.reject(h_try, err, p_hat);
                    h = self.below_h_min(proposal, h_try, last)?;
                    continue;
                }
                Attempt::Singular => {
                    self.stats.rejected_newton += 1;
                    let Some(control) = self.control.as_mut() else {
                        return Err(self.underflow(h_try, Failure::Singular));
                    };
                    last = Failure::Singular;
                    let proposal = control.reject_newton(h_try);
                    h = self.below_h_min(proposal, h_try, last)?;
                    continue;
                }
            };
            // Accepted.
            self.h_taken = None;
            self.h_step = h_try;
            self.t_prev = self.t;
            self.t = if lands { t_stop } else { self.t + h_try };
            std::mem::swap(&mut self.y_prev, &mut self.y);
            self.y.copy_from_slice(self.m.y_new());
            self.m.accept(h_try);
            self.started = false;
            self.stats.accepted += 1;
            self.stats.record_step_size(h_try);
            self.h_next = Some(match self.control.as_mut() {
                Some(control) => control.accept(h_try, err, p_hat).min(h_max).max(h_min),
                None => h,
            });
            return Ok(());
        }
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) {
        let h = self.t - self.t_prev;
        if h == 0.0 {
            out.copy_from_slice(&self.y);
            return;
        }
        let theta = (t - self.t_prev) / h;
        self.m
            .interpolate(self.sys, self.t_prev, h, &self.y_prev, &self.y, theta, out);
    }

    fn step_quadrature(&self, value: &mut [f64], estimate: &mut [f64]) -> StepQuadrature {
        if self.t == self.t_prev || self.sys.n_quadratures() == 0 {
            return StepQuadrature::Unavailable;
        }
        self.m
            .quadrature(self.sys, self.t_prev, &self.y_prev, value, estimate)
    }

    fn set_h_max(&mut self, h_max: f64) {
        // Without error control every step is h0; the bounds are not used.
        if self.control.is_some() {
            self.h_max = h_max.max(self.h_min);
        }
    }

    fn restart(&mut self, t: f64, y: &[f64]) -> Result<(), SolveError> {
        // After a retaken step (an event located exactly, `retake`), the step size of the
        // motion before the event bounds the first step after it.
        self.h_before_event = self.h_taken.take();
        self.t = t;
        self.t_prev = t;
        self.y.copy_from_slice(y);
        self.y_prev.copy_from_slice(y);
        if let Some(control) = self.control.as_mut() {
            control.reset();
        }
        self.m.reset();
        self.started = false;
        self.h_next = None;
        Ok(())
    }

    fn retake(&mut self, t: f64) -> Result<bool, SolveError> {
        let (t0, h1) = (self.t_prev, self.h_step);
        // The step as first taken bounds every retake of it.
        let h_orig = self.h_taken.unwrap_or(h1);
        if !(t > t0 && t < t0 + h_orig) {
            return Ok(false);
        }
        // Without error control (fixed steps) the shorter step is taken as it comes.
        let estimate = self.control.is_some();
        self.budget.check(self.stats.steps, self.t, &self.y)?;
        self.m.rewind();
        self.m.start(self.sys, t0, &self.y_prev, &mut self.stats)?;
        self.stats.steps += 1;
        let outcome = self.m.attempt(
            self.sys,
            t0,
            &self.y_prev,
            t - t0,
            estimate,
            &mut self.stats,
        );
        if matches!(outcome, Attempt::Error(err) if err <= 1.0) {
            self.t = t;
            self.h_taken = Some(h_orig);
            self.h_step = t - t0;
            self.y.copy_from_slice(self.m.y_new());
            self.m.accept(t - t0);
            self.started = false;
            return Ok(true);
        }
        // The shorter step fails its error test: take the last accepted one again (the same
        // stages, bit for bit) and keep its dense output.
        self.stats.rejected_error += 1;
        self.stats.steps += 1;
        let again = self
            .m
            .attempt(self.sys, t0, &self.y_prev, h1, estimate, &mut self.stats);
        debug_assert!(matches!(again, Attempt::Error(err) if err <= 1.0));
        self.m.accept(h1);
        self.started = false;
        Ok(false)
    }

    fn stats(&self) -> Stats {
        let mut s = self.stats;
        s.rhs_evals += self.m.lazy_rhs_evals();
        s
    }
}

impl<S: OdeSystem + ?Sized, M: OneStepMethod<S>> OneStepDriver<'_, S, M> {
    /// A rejection's proposal below h_min: one more try at h_min, unless the rejected trial
    /// was already at h_min (then the step fails).
    fn below_h_min(&self, proposal: f64, h_try: f64, last: Failure) -> Result<f64, SolveError> {
        let h_min = self.h_min;
        if h_min > 0.0 && proposal < h_min {
            if h_try <= h_min {
                return Err(self.underflow(proposal, last));
            }
            Ok(h_min)
        } else {
            Ok(proposal)
        }
    }
}
