//! The driver: steps any [`Stepper`], locates events on its dense output, runs the system's
//! event hook, restarts, and records output.
//!
//! ```text
//! after each accepted step [t_a, t_b], h = t_b − t_a:
//!   g at t_b; when the system gives the rates ġ (OdeSystem::event_rates) and every g_i is
//!     far from zero over the step,
//!       sign g_i(t_a) = sign g_i(t_b) ≠ 0  and  min(|g_i(t_a)|, |g_i(t_b)|) ≥ κ h max(|ġ_i(t_a)|, |ġ_i(t_b)|),
//!     κ = FAR_FACTOR = 2, no interior sample is taken; otherwise
//!   sample g at t_a + j (t_b − t_a)/(s + 1), j = 1..s (s = event_samples)
//!   first sub-interval with a sign change of some g_i in its direction
//!     → each such i: Brent's method on g_i(t, y_dense(t)) until the bracket is at most
//!       2 ε |t| wide (a few ulps of t: the floating-point limit of the event time)
//!     → t* = earliest root (the end of its final bracket on the side after the crossing,
//!       where g_i already has the sign the event's direction gives it, or the point where
//!       g_i is exactly zero); every component whose root lies within
//!       tol = event_rtol · max(|t|, |t_b − t_a|) of t* is reported with it
//!   hook: y* = on_event(hits, y_dense(t*)); g re-read at (t*, y*) (the signs the next step
//!         is compared with); then stop, or restart the stepper at (t*, y*)
//!   restart: all history discarded, the first step chosen as at t0 (opts.h0, else the
//!         starting-step algorithm of HNW I §II.4 from (t*, y*))
//! ```
//!
//! # Exact event steps
//!
//! With `exact_event_steps` (one-step methods; [`Stepper::retake`]) the state at an event
//! is not read off the dense output of the step [t_a, t_b] that contains it: that step is
//! taken again from t_a with h = t* − t_a, and y* is its end (`integrator/exact.rs`).
//!
//! ```text
//! y* = y_a + (t* − t_a) Σ b_i k_i    stages at t_a + c_i (t* − t_a) ≤ t*: one side of the event
//! its error norm ≤ 1  → y* and its dense output replace the step's (rows in [t_a, t*] too)
//! its error norm > 1  → the original step is taken again (the same stages, bit for bit) and
//!                       y* is its dense output, as without the option
//! t* corrected by Newton's method on g along retaken steps, at most twice, where the
//!   correction moves the state by more than the tolerance (exact.rs, refine_retaken)
//! first step after the restart = min(fresh first step, the original step [t_a, t_b]'s length)
//! with the rates ġ: the step after a step without an event ends at most 2 % past the
//!   linear prediction −g_i/ġ_i of the nearest approaching crossing (exact.rs, crossing_limit)
//! ```
//!
//! Where an event function marks a point at which the right-hand side is not smooth (a
//! contact onset, a kink of a force law: docs/model.md §7), a step across it has the
//! local error of the smoothness there (h² at a C⁰ kink, not h^{p+1}), and so has the dense
//! output inside it; the retaken step sees only the smooth piece before t*, and the restart
//! only the piece after. The fresh first step alone would be a guess from ‖f‖ and one
//! difference of f; the step of the motion just before the event is the better bound, and
//! taking the smaller keeps the first step at most the fresh one (the argument below).
//! A retaken step that ends a rounding short of the crossing (g* still on the old side,
//! not moved there by the hook) keeps the crossing's sign, so the same crossing is not
//! reported twice.
//!
//! Why events are never missed (at the default options): a crossing pair g: − → + → −
//! inside one step is invisible at the step's ends. Two things prevent it. After an event
//! the method restarts with a fresh first step, a small fraction of the local time scale
//! |y|/|f|, so a motion the hook starts (a rebound) is seen on its way out before any long
//! step can span it; the method's old step size, fitted to the motion before the event,
//! never carries over. Inside every later step g is also sampled at `event_samples`
//! (default 4) interior points of the dense output, so an excursion longer than h/(s + 1)
//! is seen. A property test over 500 random bouncing balls (tests/events_never_missed.rs)
//! finds every bounce with every adaptive method at default options.
//!
//! The far test skips the samples only where they could not find anything: for g_i to reach
//! zero inside the step it must travel min(|g_i(t_a)|, |g_i(t_b)|) in a time h, so its rate
//! must somewhere exceed κ = 2 times the larger of its two end rates. (The cubic Hermite
//! interpolant of the two ends and rates, exact for a constant ġ̇, deviates from the chord by
//! at most 4/27 h (|ġ_a| + |ġ_b|) ≤ 8/27 h max|ġ|, a quarter of the margin.) A lubricated
//! journal that never comes near its bearing's wall is thus checked at the step ends only,
//! for one kinematic evaluation per step.
//!
//! # The contact-aware step limit
//!
//! With `h_max_near_events` = H finite and the rates ġ given, the step after every accepted
//! step is limited by
//!
//! ```text
//! h ≤ max(H, min_i r_i),   r_i: the largest h with  κ (|ġ_i| h + ½ |g̈_i| h²) ≤ |g_i|,
//!                          r_i = 2 d / (|ġ_i| + √(ġ_i² + 2 |g̈_i| d)),  d = |g_i| / κ
//! g_i, ġ_i at the end of the step just taken;  g̈_i ≈ (ġ_i(t_b) − ġ_i(t_a)) / (t_b − t_a)
//! ```
//! (and by `h_max` always). A step longer than H is taken only while the distance every g_i
//! is predicted to travel in it, to second order, is at most 1/κ = 1/2 of its distance from
//! zero: no g_i can change sign inside it unless its motion departs from the prediction by a
//! factor 2. Near a zero (a journal at its bearing's wall, in contact or in flight) the
//! limit is H, and with the interior samples an excursion to the other side of zero longer
//! than H/(s + 1) cannot hide in a step. Away from every zero (a lubricated journal far from
//! the wall, a journal crossing its clearance) the step is free up to `h_max`. After an
//! event, and at the start, where no rate change is known yet, the limit is H. The limit
//! goes to the method as [`Stepper::set_h_max`] and counts in `h_max_used` like any step.
//!
//! Rule for zeros: an event function that is exactly zero at the start (or after a restart)
//! has no sign yet; it takes the sign of its first nonzero value, and no event is reported for
//! that first value. A crossing is a change between nonzero signs. The event time is taken on
//! the far side of the root, or exactly on it when g is exactly zero there; in that case the
//! triggering function keeps the sign the crossing gave it (`handle_event`), so a restart
//! never begins with an unknown sign (the diffsol pitfall of a missed next crossing).
//!
//! An event function that returns NaN (at the start, a step end, an interior sample, a trial
//! point of the root finder or after a hook) ends the integration with
//! [`SolveError::EventNan`] naming it: NaN has no sign, so skipping it could miss a crossing
//! silently.

mod brent;
mod exact;
mod span;

use span::check_span;

use crate::diffsol_backend::DiffsolProblem;
use crate::error::SolveError;
use crate::method::Method;
use crate::options::{Config, OptionError, OptionField, Output, Reason, SolverOptions};
use crate::stats::Stats;
use crate::stepper::{StepQuadrature, Stepper};
use crate::system::{Direction, EventAction, EventHit, EventSpec, OdeSystem};

/// κ of the far test (module documentation): an event function whose distance from zero at
/// both ends of a step is at least κ h times its larger end rate is not sampled inside it.
pub const FAR_FACTOR: f64 = 2.0;

/// r of the contact-aware step limit (module documentation): the longest step over which
/// an event function at `g`, with rate `gd` and rate change `gdd` (per second), is predicted
/// to travel at most 1/κ of its distance from zero; 0 at g = 0, ∞ when it does not move.
#[inline]
pub fn reach_limit(g: f64, gd: f64, gdd: f64) -> f64 {
    let d = g.abs() / FAR_FACTOR;
    if d == 0.0 {
        return 0.0;
    }
    let a = gd.abs();
    2.0 * d / (a + (a * a + 2.0 * gdd.abs() * d).sqrt())
}

/// Whether g stays on one side of zero over a step of length `h` by the far test (module
/// documentation), from its values and rates at both ends.
#[inline]
pub fn far_from_zero(g_a: f64, gd_a: f64, g_b: f64, gd_b: f64, h: f64) -> bool {
    // The same nonzero sign at both ends (NaN has none), without forming the signs.
    let same_side = (g_a > 0.0 && g_b > 0.0) || (g_a < 0.0 && g_b < 0.0);
    same_side && g_a.abs().min(g_b.abs()) >= FAR_FACTOR * h * gd_a.abs().max(gd_b.abs())
}

/// What one call of [`Integrator::step`] did, and where the state is afterwards.
#[derive(Clone, Debug, PartialEq)]
pub enum StepOutcome {
    /// A step was accepted; the state is at `t`, the end of the step. The dense output covers
    /// [t_prev, t].
    Accepted {
        /// End of the step.
        t: f64,
    },
    /// One or more events were located in the step; the state is at the event time `t`, after
    /// the hook ran (so it may differ from the dense output's left limit at `t`). The dense
    /// output covers [t_prev, t]. If the hook asked to stop, the integration is finished.
    Event {
        /// Event time.
        t: f64,
        /// The events, all at `t` within the location tolerance.
        hits: Vec<EventHit>,
        /// Whether the integration stopped there.
        stopped: bool,
    },
    /// The end time was reached; the state is at `t = t_end`. Further calls return this again.
    StopTime {
        /// The end time.
        t: f64,
    },
}

/// What an integration borrows: the system, its validated options and, for diffsol's methods,
/// diffsol's problem built from them (diffsol's own pattern: the caller owns the problem and
/// the solver borrows it). One `Problem` can serve any number of integrations.
///
/// ```text
/// let problem = Problem::new(&sys, &opts)?;           // validates opts for sys.dim()
/// let mut it = problem.integrator(t0, t_end, &y0)?;  // or problem.solve((t0, t_end), &y0)
/// ```
pub struct Problem<'a, S: OdeSystem + ?Sized> {
    sys: &'a S,
    opts: SolverOptions,
    config: Config,
    diffsol: Option<DiffsolProblem<'a, S>>,
    /// Rodas5P's pattern on the sparse path (crate::linear_algebra), coloured.
    rodas_sparse: Option<crate::jacobian::Colouring>,
}

impl<'a, S: OdeSystem + ?Sized> Problem<'a, S> {
    /// Validates `opts` for `sys` ([`SolverOptions::configure`]), checks the method's dense
    /// matrices against the memory budget ([`crate::memory`]: `OutOfMemory` before anything
    /// is allocated) and builds what the method needs besides the state.
    ///
    /// A system without state (n = 0: a mechanism whose every body is prescribed) has nothing
    /// to integrate; diffsol's methods cannot be built for it (their LU panics on an empty
    /// matrix), so dopri54's loop stands in for them: it goes to the end in steps that
    /// change nothing.
    pub fn new(sys: &'a S, opts: &SolverOptions) -> Result<Self, SolveError> {
        let config = opts.configure(sys.dim())?;
        Self::configured(sys, opts.clone(), config)
    }

    /// [`Problem::new`] from options `opts` already validated for `sys` into `config`
    /// ([`SolverOptions::configure`]), which the problem keeps without copying them again.
    fn configured(
        sys: &'a S,
        mut opts: SolverOptions,
        mut config: Config,
    ) -> Result<Self, SolveError> {
        if sys.dim() == 0 && matches!(config, Config::Diffsol(_)) {
            opts.method = Method::Dopri54;
            opts.controller = None;
            config = opts.configure(0)?;
        }
        // diffsol's methods check their own matrices: dense or sparse (crate::linear_algebra).
        let diffsol = match &config {
            Config::Diffsol(c) => Some(DiffsolProblem::new(
                sys,
                c,
                opts.linear_algebra,
                opts.max_memory,
            )?),
            _ => None,
        };
        // Rodas5P takes the sparse path as diffsol's methods do; the other one-step methods
        // (explicit) have no matrices.
        let mut rodas_sparse = None;
        if diffsol.is_none() {
            let pattern = (opts.method == Method::Rodas5p)
                .then(|| crate::linear_algebra::sparse_pattern(sys, opts.linear_algebra))
                .flatten();
            if let Some(pattern) = pattern {
                let nnz = pattern.iter().map(Vec::len).sum::<usize>();
                crate::memory::check_sparse(opts.method, sys.dim(), nnz, opts.max_memory)
                    .map_err(SolveError::OutOfMemory)?;
                // sparse_pattern's rows are in range: the colouring exists.
                rodas_sparse = crate::jacobian::Colouring::new(pattern);
            }
            if rodas_sparse.is_none() {
                crate::memory::check_method(opts.method, sys.dim(), opts.max_memory)
                    .map_err(SolveError::OutOfMemory)?;
            }
        }
        Ok(Problem {
            sys,
            opts,
            config,
            diffsol,
            rodas_sparse,
        })
    }

    /// Whether the method runs on sparse matrices (crate::linear_algebra: diffsol's methods
    /// and Rodas5P).
    pub fn is_sparse(&self) -> bool {
        self.rodas_sparse.is_some() || self.diffsol.as_ref().is_some_and(|d| d.is_sparse())
    }

    /// The validated configuration of the method's family, which the steppers consume.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The system.
    pub fn system(&self) -> &'a S {
        self.sys
    }

    /// The (validated) options.
    pub fn options(&self) -> &SolverOptions {
        &self.opts
    }

    /// diffsol's problem (diffsol's methods only).
    pub fn diffsol(&self) -> Option<&DiffsolProblem<'a, S>> {
        self.diffsol.as_ref()
    }

    /// An integrator from (t0, y0) up to `t_end`.
    pub fn integrator(
        &self,
        t0: f64,
        t_end: f64,
        y0: &[f64],
    ) -> Result<Integrator<'_, S>, SolveError> {
        Integrator::new(self, t0, t_end, y0)
    }

    /// Integrates from `t_span.0` to `t_span.1` starting at `y0`, recording what
    /// `opts.output` asks for.
    pub fn solve(&self, t_span: (f64, f64), y0: &[f64]) -> Result<Solution, SolveError> {
        let it = self.integrator(t_span.0, t_span.1, y0)?;
        drive(it, t_span.0, y0, &self.opts.output)
    }
}

/// Builds the stepper of the problem's method at (t0, y0), from the validated configuration
/// of its family ([`Problem::config`]).
pub fn make_stepper<'p, S: OdeSystem + ?Sized>(
    problem: &'p Problem<'_, S>,
    t0: f64,
    y0: &[f64],
) -> Result<Box<dyn Stepper + 'p>, SolveError> {
    let sys = problem.system();
    match problem.config() {
        Config::Fixed(c) => Ok(Box::new(crate::rk4::Rk4::new(sys, t0, y0, c)?)),
        Config::OneStep(c) if c.method() == Method::Rodas5p => {
            let m = match &problem.rodas_sparse {
                Some(colouring) => {
                    crate::rosenbrock::Rodas5pMethod::sparse(sys, c.tolerances(), colouring.clone())
                }
                None => crate::rosenbrock::Rodas5pMethod::new(sys, c.tolerances()),
            };
            Ok(Box::new(crate::onestep::OneStepDriver::new(
                sys, m, t0, y0, c,
            )))
        }
        Config::OneStep(c) => {
            let m = crate::erk::ErkMethod::new(c.method(), c.tolerances(), y0.len())?;
            Ok(Box::new(crate::onestep::OneStepDriver::new(
                sys, m, t0, y0, c,
            )))
        }
        Config::Diffsol(c) => {
            // Problem::new builds diffsol's problem for every diffsol configuration.
            let backend = problem.diffsol().ok_or(OptionError::new(
                OptionField::Method,
                Reason::Invalid(format!("{} has no diffsol problem", c.method())),
            ))?;
            Ok(Box::new(crate::diffsol_backend::DiffsolStepper::new(
                backend,
                t0,
                y0,
                problem.options(),
            )?))
        }
    }
}

/// A solver in motion: call [`Integrator::step`] until it returns `StopTime` (or a stopping
/// event), or use [`solve`] for the whole span. Built by [`Problem::integrator`].
pub struct Integrator<'p, S: OdeSystem + ?Sized> {
    sys: &'p S,
    stepper: Box<dyn Stepper + 'p>,
    opts: &'p SolverOptions,
    t_end: f64,
    specs: Vec<EventSpec>,
    /// Last nonzero sign of each event function (0 = none yet).
    signs: Vec<i8>,
    g_a: Vec<f64>,
    g_b: Vec<f64>,
    /// Rates ġ at the start and the end of the step (when `rates`).
    gd_a: Vec<f64>,
    gd_b: Vec<f64>,
    /// Whether the system gives the rates of its event functions.
    rates: bool,
    /// Scratch: g at an interior sample, at a trial point of the root finder, and at the left end of
    /// the sub-interval being scanned.
    g_s: Vec<f64>,
    g_t: Vec<f64>,
    g_l: Vec<f64>,
    /// Interior samples skipped by the far test.
    samples_skipped: usize,
    /// Whether the step limit in force is the predicted crossing's (exact event steps:
    /// `integrator/exact.rs`, [`Integrator::crossing_limit`]).
    crossing_limited: bool,
    /// H of the contact-aware step limit (module documentation), when it is on: finite, the
    /// rates given, events on.
    h_near: Option<f64>,
    ybuf: Vec<f64>,
    /// Segment end: the end of the step, or the event time when a step was cut.
    seg_end: f64,
    /// State set by an event hook, applied to the stepper at the next step.
    pending_restart: Option<(f64, Vec<f64>)>,
    /// Copy of the state after the last step (post-hook after an event).
    y_cur: Vec<f64>,
    t_cur: f64,
    finished: bool,
    /// Evaluations of the vector of event functions.
    event_evals: usize,
    /// Events located.
    events: usize,
}

impl<'p, S: OdeSystem + ?Sized> Integrator<'p, S> {
    /// Checks the time span and the initial state and builds the problem's method at (t0, y0)
    /// for integration up to `t_end`.
    pub fn new(
        problem: &'p Problem<'_, S>,
        t0: f64,
        t_end: f64,
        y0: &[f64],
    ) -> Result<Self, SolveError> {
        let sys = problem.system();
        let opts = problem.options();
        let n = sys.dim();
        check_span(t0, t_end, y0, n)?;
        let stepper = make_stepper(problem, t0, y0)?;
        let m = if opts.events { sys.n_events() } else { 0 };
        let specs = (0..m).map(|i| sys.event_spec(i)).collect();
        let mut it = Integrator {
            sys,
            stepper,
            opts,
            t_end,
            specs,
            signs: vec![0; m],
            g_a: vec![0.0; m],
            g_b: vec![0.0; m],
            gd_a: vec![0.0; m],
            gd_b: vec![0.0; m],
            rates: false,
            g_s: vec![0.0; m],
            g_t: vec![0.0; m],
            g_l: vec![0.0; m],
            samples_skipped: 0,
            crossing_limited: false,
            h_near: None,
            ybuf: vec![0.0; n],
            seg_end: t0,
            pending_restart: None,
            y_cur: y0.to_vec(),
            t_cur: t0,
            finished: false,
            event_evals: 0,
            events: 0,
        };
        if m > 0 {
            it.rates = it.sys.event_rates(t0, y0, &mut it.g_a, &mut it.gd_a);
            if !it.rates {
                it.sys.events(t0, y0, &mut it.g_a);
            }
            it.event_evals += 1;
            it.check_nan(&it.g_a, t0)?;
            for i in 0..m {
                it.signs[i] = sign(it.g_a[i]);
            }
            let h_near = opts.h_max_near_events;
            if it.rates && h_near.is_finite() && !opts.method.is_fixed_step() {
                it.h_near = Some(h_near);
                it.stepper.set_h_max(h_near.min(opts.h_max));
            }
        }
        Ok(it)
    }

    /// Current time (end of the last step, or the event time).
    pub fn t(&self) -> f64 {
        self.t_cur
    }

    /// Current state (after the hook, when the last step ended in an event).
    pub fn y(&self) -> &[f64] {
        &self.y_cur
    }

    /// Start of the last step.
    pub fn t_prev(&self) -> f64 {
        self.stepper.t_prev()
    }

    /// Whether the end time or a stopping event was reached.
    pub fn is_finished(&self) -> bool {
        self.finished
    }

    /// Counters so far, by value: the method's work (RHS evaluations a stepper made lazily
    /// for the dense output included) and the integrator's event counters.
    pub fn stats(&self) -> Stats {
        let mut s = self.stepper.stats();
        s.event_evals = self.event_evals;
        s.events = self.events;
        s
    }

    /// Dense output of the last step: y(t) for t in [t_prev, t] (the left limit at an event).
    pub fn interpolate(&self, t: f64, out: &mut [f64]) {
        if t >= self.seg_end && self.pending_restart.is_none() {
            out.copy_from_slice(&self.y_cur);
        } else {
            self.stepper.interpolate(t, out);
        }
    }

    /// The increments of the system's quadrature variables ([`OdeSystem::quadrature`]) over
    /// the last step [t_prev, t], by the method's own formula at its own stages, and the
    /// method's estimate of their error when it has one ([`Stepper::step_quadrature`]).
    /// [`StepQuadrature::Unavailable`] (nothing written) when the system has none, the method
    /// gives none, or the step was cut at an event inside it (the method's formula covers the
    /// whole step, the state at the event is its dense output's: the caller integrates
    /// [t_prev, t] itself).
    pub fn step_quadrature(&self, value: &mut [f64], estimate: &mut [f64]) -> StepQuadrature {
        if self.seg_end != self.stepper.t() {
            return StepQuadrature::Unavailable;
        }
        self.stepper.step_quadrature(value, estimate)
    }

    /// Takes one step; see [`StepOutcome`] for where the state is afterwards. After an event
    /// the next call restarts the method at the event state, with a freshly chosen first step.
    pub fn step(&mut self) -> Result<StepOutcome, SolveError> {
        if self.finished {
            return Ok(StepOutcome::StopTime { t: self.t_cur });
        }
        if let Some((t, y)) = self.pending_restart.take() {
            self.stepper.restart(t, &y)?;
        }
        self.stepper.step(self.t_end)?;
        let t_b = self.stepper.t();
        {
            // The new state, asked of the stepper once for both checks.
            let y = self.stepper.y();
            let bound = self.opts.divergence_bound;
            // |v| ≤ a finite bound fails for NaN and ±∞ alike: one comparison per entry.
            let bounded = if bound.is_finite() {
                y.iter().all(|v| v.abs() <= bound)
            } else {
                y.iter().all(|v| v.is_finite())
            };
            if !bounded {
                return Err(SolveError::NonFiniteState {
                    t: self.t_cur,
                    y: self.y_cur.clone(),
                });
            }
            if let Err(r) = self.sys.check_accepted(self.t_cur, &self.y_cur, t_b, y) {
                return Err(SolveError::StateRejected {
                    t: t_b,
                    y: y.to_vec(),
                    kind: r.kind,
                    reason: r.reason,
                });
            }
        }
        if !self.specs.is_empty() {
            if let Some((t_ev, hits)) = self.locate_events(t_b)? {
                return self.handle_event(t_ev, hits);
            }
        }
        self.t_cur = t_b;
        self.seg_end = t_b;
        self.y_cur.copy_from_slice(self.stepper.y());
        if t_b >= self.t_end {
            self.finished = true;
            Ok(StepOutcome::StopTime { t: t_b })
        } else {
            Ok(StepOutcome::Accepted { t: t_b })
        }
    }

    /// [`SolveError::EventNan`] when some g_i evaluated at `at` is NaN (NaN has no sign, so
    /// a crossing could not be told), with the last accepted state.
    fn check_nan(&self, g: &[f64], at: f64) -> Result<(), SolveError> {
        match g.iter().position(|v| v.is_nan()) {
            None => Ok(()),
            Some(index) => Err(SolveError::EventNan {
                t: self.t_cur,
                y: self.y_cur.clone(),
                index,
                at,
            }),
        }
    }

    fn eval_g_dense(&mut self, t: f64, g: &mut [f64]) -> Result<(), SolveError> {
        self.stepper.interpolate(t, &mut self.ybuf);
        self.sys.events(t, &self.ybuf, g);
        self.event_evals += 1;
        self.check_nan(g, t)
    }

    /// Evaluates g (and ġ when the system gives it) at the end of the step into `g_b`/`gd_b`.
    fn eval_end(&mut self, t_b: f64) -> Result<(), SolveError> {
        let y = self.stepper.y();
        if self.rates {
            self.sys.event_rates(t_b, y, &mut self.g_b, &mut self.gd_b);
        } else {
            self.sys.events(t_b, y, &mut self.g_b);
        }
        self.event_evals += 1;
        self.check_nan(&self.g_b, t_b)
    }

    /// Interior samples skipped by the far test so far (module documentation).
    pub fn samples_skipped(&self) -> usize {
        self.samples_skipped
    }

    /// Scans the step [t_prev, t_b]; returns the earliest event time and its hits, having
    /// updated the signs, or None (signs updated to the end of the step); an event function
    /// that returns NaN is [`SolveError::EventNan`].
    #[allow(clippy::type_complexity)]
    fn locate_events(&mut self, t_b: f64) -> Result<Option<(f64, Vec<EventHit>)>, SolveError> {
        let m = self.specs.len();
        let t_a0 = self.stepper.t_prev();
        self.eval_end(t_b)?;
        let mut samples = self.opts.event_samples;
        if self.rates {
            let h = t_b - t_a0;
            let (a, b) = (
                self.g_a.iter().zip(&self.gd_a),
                self.g_b.iter().zip(&self.gd_b),
            );
            let far = a
                .zip(b)
                .all(|((&g_a, &gd_a), (&g_b, &gd_b))| far_from_zero(g_a, gd_a, g_b, gd_b, h));
            if far {
                self.samples_skipped += samples;
                samples = 0;
                // Every g_i also on the side its recorded sign says: the scan below would find
                // no crossing at the end and update no sign.
                if self
                    .signs
                    .iter()
                    .zip(&self.g_b)
                    .all(|(&s, &g)| s == sign(g))
                {
                    self.end_without_event(h);
                    return Ok(None);
                }
            }
        }
        let mut t_a = t_a0;
        let mut g_l = std::mem::take(&mut self.g_l);
        let mut g_s = std::mem::take(&mut self.g_s);
        g_l.copy_from_slice(&self.g_a);
        let mut found = None;
        for j in 1..=samples + 1 {
            let last = j == samples + 1;
            let t_j = if last {
                t_b
            } else {
                t_a0 + (t_b - t_a0) * j as f64 / (samples + 1) as f64
            };
            if last {
                g_s.copy_from_slice(&self.g_b);
            } else if let Err(e) = self.eval_g_dense(t_j, &mut g_s) {
                (self.g_l, self.g_s) = (g_l, g_s);
                return Err(e);
            }
            // Components crossing in [t_a, t_j].
            let mut crossing: Vec<usize> = Vec::new();
            for i in 0..m {
                let s_new = sign(g_s[i]);
                if s_new == 0 {
                    continue;
                }
                let s_old = self.signs[i];
                if s_old != 0 && s_old != s_new {
                    let dir_ok = self.specs[i].direction.matches(s_old as f64, s_new as f64);
                    if dir_ok {
                        crossing.push(i);
                    } else {
                        self.signs[i] = s_new;
                    }
                } else {
                    self.signs[i] = s_new;
                }
            }
            if !crossing.is_empty() {
                let tol = self.opts.event_rtol * t_j.abs().max((t_b - t_a0).abs());
                let mut roots: Vec<(usize, f64)> = Vec::new();
                for &i in &crossing {
                    let left = if sign(g_l[i]) == self.signs[i] {
                        g_l[i]
                    } else {
                        // The left value is zero or on the wrong side (a dense-output
                        // artefact): use the sign that was recorded.
                        -(self.signs[i] as f64) * f64::MIN_POSITIVE
                    };
                    let r = match self.brent(i, t_a, left, t_j, g_s[i]) {
                        Ok(r) => r,
                        Err(e) => {
                            (self.g_l, self.g_s) = (g_l, g_s);
                            return Err(e);
                        }
                    };
                    roots.push((i, r));
                }
                let t_star = roots.iter().map(|r| r.1).fold(f64::INFINITY, f64::min);
                let hits: Vec<EventHit> = roots
                    .iter()
                    .filter(|(_, r)| *r <= t_star + tol)
                    .map(|&(i, _)| EventHit {
                        index: i,
                        t: t_star,
                        rising: self.signs[i] < 0,
                    })
                    .collect();
                found = Some((t_star, hits));
                break;
            }
            t_a = t_j;
            g_l.copy_from_slice(&g_s);
        }
        self.g_l = g_l;
        self.g_s = g_s;
        if found.is_none() {
            self.end_without_event(t_b - t_a0);
        }
        Ok(found)
    }

    /// After a step of length `h` without an event: the step limit for the next step (the
    /// contact-aware one, the predicted crossing's) and g, ġ at its end become the next
    /// step's start values (the left bracket of its root finding): swapped in, not copied,
    /// as the end values are written afresh after every step.
    fn end_without_event(&mut self, h: f64) {
        let mut limit = None;
        if let Some(h_near) = self.h_near {
            let ends = self.g_b.iter().zip(&self.gd_b).zip(&self.gd_a);
            let reach = ends
                .map(|((&g, &gd), &gd_a)| reach_limit(g, gd, (gd - gd_a) / h))
                .fold(f64::INFINITY, f64::min);
            limit = Some(h_near.max(reach).min(self.opts.h_max));
        }
        if self.crossing_limit_on() {
            limit = Some(self.crossing_limit(limit.unwrap_or(self.opts.h_max), h));
        }
        if let Some(limit) = limit {
            self.stepper.set_h_max(limit);
        }
        std::mem::swap(&mut self.g_a, &mut self.g_b);
        std::mem::swap(&mut self.gd_a, &mut self.gd_b);
    }

    fn handle_event(
        &mut self,
        mut t_ev: f64,
        mut hits: Vec<EventHit>,
    ) -> Result<StepOutcome, SolveError> {
        let n = self.ybuf.len();
        let mut y = vec![0.0; n];
        let retaken = self.opts.exact_event_steps && self.stepper.retake(t_ev)?;
        if retaken {
            t_ev = self.refine_retaken(t_ev, hits[0].index)?;
            for h in &mut hits {
                h.t = t_ev;
            }
        }
        if retaken {
            y.copy_from_slice(self.stepper.y());
        } else {
            self.stepper.interpolate(t_ev, &mut y);
        }
        let m = self.specs.len();
        let mut g_pre = vec![0.0; m];
        if retaken {
            self.sys.events(t_ev, &y, &mut g_pre);
            self.event_evals += 1;
        }
        let mut stop = false;
        for h in &hits {
            if self.sys.on_event(h, &mut y) == EventAction::Stop {
                stop = true;
            }
        }
        self.events += hits.len();
        // Signs after the hook (the hook may move the state across a surface).
        let mut g = vec![0.0; m];
        if self.rates {
            self.sys.event_rates(t_ev, &y, &mut g, &mut self.gd_a);
        } else {
            self.sys.events(t_ev, &y, &mut g);
        }
        self.event_evals += 1;
        self.check_nan(&g, t_ev)?;
        for i in 0..m {
            let s = sign(g[i]);
            if s != 0 {
                self.signs[i] = s;
            } else if hits.iter().any(|h| h.index == i) {
                // Zero after the hook: keep the sign the crossing produced.
                self.signs[i] = if self.signs[i] < 0 { 1 } else { -1 };
            }
        }
        for h in &hits {
            // Record the post-crossing sign for the triggering components when g was nonzero.
            let s = sign(g[h.index]);
            let post: i8 = if h.rising { 1 } else { -1 };
            if retaken && s == -post && sign(g_pre[h.index]) != post {
                // The retaken step ends a rounding short of the crossing (not the hook's
                // doing): the crossing stands.
                self.signs[h.index] = post;
            } else if s != 0 {
                self.signs[h.index] = s;
            }
        }
        self.g_a.copy_from_slice(&g);
        if let Some(h_near) = self.h_near {
            self.stepper.set_h_max(h_near.min(self.opts.h_max));
        } else if self.crossing_limit_on() {
            self.stepper.set_h_max(self.opts.h_max);
        }
        self.crossing_limited = false;
        self.t_cur = t_ev;
        self.seg_end = t_ev;
        self.y_cur.copy_from_slice(&y);
        if stop || t_ev >= self.t_end {
            self.finished = true;
        } else {
            self.pending_restart = Some((t_ev, y));
        }
        Ok(StepOutcome::Event {
            t: t_ev,
            hits,
            stopped: stop,
        })
    }
}

fn sign(v: f64) -> i8 {
    if v > 0.0 {
        1
    } else if v < 0.0 {
        -1
    } else {
        0
    }
}

/// The result of [`solve`].
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Solution {
    /// Dimension n.
    pub dim: usize,
    /// Output times.
    pub t: Vec<f64>,
    /// Output states, row-major: state k is `y[k*dim .. (k+1)*dim]`.
    pub y: Vec<f64>,
    /// Located events, in order.
    pub events: Vec<EventHit>,
    /// Counters.
    pub stats: Stats,
    /// Final time reached (t_end, or a stopping event's time).
    pub t_final: f64,
    /// Final state.
    pub y_final: Vec<f64>,
}

impl Solution {
    /// The state at output index k.
    pub fn state(&self, k: usize) -> &[f64] {
        &self.y[k * self.dim..(k + 1) * self.dim]
    }
    /// Number of output points.
    pub fn len(&self) -> usize {
        self.t.len()
    }
    /// True when nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
}

/// Integrates `sys` from `t_span.0` to `t_span.1` starting at `y0`: [`Problem::new`] and
/// [`Problem::solve`] in one call.
pub fn solve<S: OdeSystem + ?Sized>(
    sys: &S,
    t_span: (f64, f64),
    y0: &[f64],
    opts: &SolverOptions,
) -> Result<Solution, SolveError> {
    // The options are validated as given (the output grid included); the problem keeps a copy
    // without the grid, which only `drive` reads, here from `opts` itself.
    let config = opts.configure(sys.dim())?;
    let problem = Problem::configured(sys, opts.without_output(), config)?;
    let it = problem.integrator(t_span.0, t_span.1, y0)?;
    drive(it, t_span.0, y0, &opts.output)
}

/// Runs an integrator to its end, recording what `output` asks for.
fn drive<S: OdeSystem + ?Sized>(
    mut it: Integrator<'_, S>,
    t0: f64,
    y0: &[f64],
    output: &Output,
) -> Result<Solution, SolveError> {
    let n = y0.len();
    let mut sol = Solution {
        dim: n,
        ..Default::default()
    };
    let times: &[f64] = match output {
        Output::Times(ts) => ts,
        _ => &[],
    };
    let mut next_time = 0usize;
    // The rows of a grid are known: no growth of the record while integrating.
    sol.t.reserve(times.len());
    sol.y.reserve(times.len().saturating_mul(n));
    // Output times at or before the start.
    while next_time < times.len() && times[next_time] <= t0 {
        sol.t.push(times[next_time]);
        sol.y.extend_from_slice(y0);
        next_time += 1;
    }
    if matches!(output, Output::Steps) {
        sol.t.push(t0);
        sol.y.extend_from_slice(y0);
    }
    loop {
        let outcome = it.step()?;
        let t_now = it.t();
        if let Output::Times(_) = output {
            // The grid's times inside the step, before its end (the times are validated
            // non-decreasing): the stepper's dense output, as `Integrator::interpolate` gives
            // it before the end, for all of them at once and into the record in place.
            let first = next_time;
            while next_time < times.len() && times[next_time] < t_now {
                next_time += 1;
            }
            if next_time > first {
                let ts = &times[first..next_time];
                let k = sol.y.len();
                sol.y.resize(k + ts.len() * n, 0.0);
                it.stepper.interpolate_many(ts, &mut sol.y[k..]);
                sol.t.extend_from_slice(ts);
            }
            // At the end: the state itself (after the hook, at an event).
            while next_time < times.len() && times[next_time] <= t_now {
                sol.t.push(times[next_time]);
                sol.y.extend_from_slice(it.y());
                next_time += 1;
            }
        } else if matches!(output, Output::Steps) {
            sol.t.push(t_now);
            sol.y.extend_from_slice(it.y());
        }
        match outcome {
            StepOutcome::Accepted { .. } => {}
            StepOutcome::Event { hits, stopped, .. } => {
                sol.events.extend(hits);
                if stopped {
                    break;
                }
            }
            StepOutcome::StopTime { .. } => break,
        }
        if it.is_finished() {
            break;
        }
    }
    sol.t_final = it.t();
    sol.y_final = it.y().to_vec();
    if matches!(output, Output::Final) {
        sol.t.push(sol.t_final);
        sol.y.extend_from_slice(&sol.y_final);
    }
    sol.stats = it.stats();
    Ok(sol)
}

/// Convenience for direction filtering in tests and tools.
pub fn direction_of(rising: bool) -> Direction {
    if rising {
        Direction::Rising
    } else {
        Direction::Falling
    }
}
