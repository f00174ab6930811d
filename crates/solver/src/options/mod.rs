//! Solver options: the flat form users fill ([`SolverOptions`]), the rules it obeys, and the
//! per-family configuration its validation produces ([`SolverOptions::configure`] →
//! [`Config`]), which the steppers consume.
//!
//! # The rules
//!
//! This is the one place they are written. The engine and `lash` call them instead of
//! checking on their own (the Python binding still keeps copies of the rtol range, the
//! default controllers and the dense-output degrees, to be replaced by these and
//! [`Method::info`]), and each front end spells the typed error ([`OptionError`]: which
//! field, what is wrong, the value, what is allowed) its own way.
//!
//! Which option fits which method follows the method's family ([`Method::info`],
//! [`Family::takes`]):
//!
//! ```text
//! option                     fixed step (rk4)   one-step (pairs, rodas5p)   diffsol (bdf, trbdf2, esdirk34)
//! step                       required           rejected                    rejected
//! rtol, atol                 ignored            used                        used
//! h0                         rejected           used                        used
//! h_min, h_max               ignored            used                        used
//! h_max_near_events          ignored            used                        used
//! controller                 rejected           used (None: the default)    rejected
//! limits                     ignored            used                        ignored
//! adaptive = false           (always fixed)     needs h0: every step h0     rejected
//! rk4_instability_steps      used               ignored                     ignored
//! exact_event_steps          ignored            used                        ignored
//! max_steps, max_wall_time, output, events, event_rtol, event_samples, divergence_bound: every method
//! ```
//!
//! An option that can be absent (`step`, `h0`, `controller`, `adaptive = false`) is rejected
//! when it is given for a method it does not fit; an option that always has a value (a
//! number, the limits) is checked and used by the families it fits and ignored by the
//! others, so one set of options can be switched between methods.
//!
//! Values (each an [`Allowed`] set of a [`Rule`]; h in s):
//!
//! ```text
//! rtol                   [1e-14, 1)                      Rule::RTOL
//! atol                   finite and > 0, each entry; a vector has one entry per component
//! step, h0               finite and > 0
//! h_min                  finite and >= 0
//! h_max                  > h_min
//! h_max_near_events      > 0 (∞: off)
//! max_steps              >= 1
//! max_wall_time          finite and > 0
//! event_rtol             [1e-15, 1e-3]
//! event_samples          <= 64
//! divergence_bound       > 0
//! output times           finite and non-decreasing
//! limits                 StepLimits (each field's range on the field)
//! ```
//!
//! The default controller of a one-step method is [`Method::default_controller`] (`pi` for
//! the explicit pairs, `gustafsson` for Rodas5P); [`SolverOptions::controller_in_use`] says
//! which one a run uses.

mod config;
mod error;
mod rules;

pub use config::{
    AdaptiveControl, Atol, Budgets, Config, DiffsolConfig, FixedConfig, OneStepConfig, StepBounds,
    StepControl, Tolerances,
};
pub use error::{Allowed, Num, OptionError, OptionField, Part, Reason};
pub use rules::Rule;

use crate::controller::{ControllerKind, StepLimits};
use crate::method::{Family, Method};

/// What the solution records.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Output {
    /// The state after every accepted step (and at every event). Default.
    #[default]
    Steps,
    /// The state at these times only (increasing, inside the time span), from the dense output.
    Times(Vec<f64>),
    /// Only the final state.
    Final,
}

/// Options of one integration: the flat form users fill, every field with a default.
/// [`SolverOptions::configure`] checks it against the rules (module documentation) and
/// builds the configuration of the method's family.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SolverOptions {
    /// Method. Default `dopri54`.
    pub method: Method,
    /// Relative tolerance of adaptive methods. Default 1e-6; in [1e-14, 1) ([`Rule::RTOL`]).
    pub rtol: f64,
    /// Absolute tolerance of adaptive methods, scalar or one per component. Default 1e-9;
    /// each entry finite and > 0 (> 0 so that a component that passes through 0 keeps a
    /// finite error weight).
    pub atol: Atol,
    /// Fixed step of fixed-step methods (s). Required for `rk4`, rejected otherwise; finite
    /// and > 0.
    pub step: Option<f64>,
    /// Initial step of adaptive methods (rejected for `rk4`). Default None: chosen by
    /// Hairer's starting-step algorithm (HNW I, II.4). With `adaptive = false` it is the
    /// fixed step of every step.
    pub h0: Option<f64>,
    /// Whether adaptive methods control the step size. Default true. When false, an adaptive
    /// method of ours (the explicit pairs, Rosenbrock) takes `h0` (required) on every step,
    /// shortening only the last one to land on the end time, computes no error estimate and
    /// never rejects a step: the mode of fixed-step convergence-order tests. `rk4` is always
    /// fixed-step; rejected for diffsol's methods.
    pub adaptive: bool,
    /// Smallest step of adaptive methods before failing with `StepSizeTooSmall`. Default 0
    /// (then 16·ε·|t| is the floor); finite and ≥ 0.
    pub h_min: f64,
    /// Largest step of adaptive methods. Default +∞; > h_min.
    pub h_max: f64,
    /// The contact-aware step limit of adaptive methods with event functions whose rates the
    /// system gives ([`crate::OdeSystem::event_rates`]): a step longer than this is allowed
    /// only while no event function can reach zero within it, predicted from its value, rate
    /// and the change of its rate over the last step (the far-test reach of
    /// [`crate::integrator`], module documentation "The contact-aware step limit"); `h_max`
    /// still caps every step. Default +∞ (off); > 0. Ignored by `rk4`.
    pub h_max_near_events: f64,
    /// Most step attempts before failing with `TooManySteps`. Default 1 000 000; ≥ 1.
    pub max_steps: usize,
    /// Step-size controller of our one-step methods (rejected for fixed-step and diffsol's
    /// methods). Default None: the method's own ([`Method::default_controller`]: `pi` for
    /// the explicit pairs, `gustafsson` for Rodas5P).
    pub controller: Option<ControllerKind>,
    /// Safety factor, growth/shrink caps, dead-band of our controllers (ignored by the
    /// other methods).
    pub limits: StepLimits,
    /// What the solution records. Default every step.
    pub output: Output,
    /// Whether event functions are monitored. Default true.
    pub events: bool,
    /// Relative time tolerance within which roots of several event functions count as one
    /// event (reported together at the earliest): `event_rtol · max(|t|, |h|)`. Each root
    /// itself is located to a few ulps of t (crate::integrator). Default 1e-13; range
    /// [1e-15, 1e-3].
    pub event_rtol: f64,
    /// Interior points of every step at which the event functions are also evaluated (on the
    /// dense output), to catch two crossings inside one step: an excursion of g to the other
    /// side and back that lasts longer than h/(s + 1) cannot hide inside a step of size h.
    /// Default 4; ≤ 64; 0 looks at the step ends only. Costs s dense-output and event
    /// evaluations per step, and nothing for a system without event functions.
    pub event_samples: usize,
    /// Wall-clock budget in seconds, counted from the construction of the integrator; None for
    /// no budget. When it runs out the solve fails with `BudgetExhausted`.
    pub max_wall_time: Option<f64>,
    /// Memory budget in bytes of the n² allocations (the implicit methods' dense Jacobian and
    /// LU): more is refused with `OutOfMemory` before anything is allocated. Default None:
    /// half of the memory available to the process ([`crate::memory`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_memory: Option<u64>,
    /// Dense or sparse matrices for diffsol's implicit methods and Rodas5P
    /// ([`crate::linear_algebra::LinearAlgebra`]). Default `auto`: sparse for large systems
    /// that give a sparse Jacobian pattern. Ignored by the other methods.
    #[serde(skip_serializing_if = "crate::linear_algebra::LinearAlgebra::is_auto")]
    pub linear_algebra: crate::linear_algebra::LinearAlgebra,
    /// Whether an adaptive one-step method (the explicit pairs, Rodas5P) takes the step in
    /// which an event was located again from its start, ending exactly at the event, and
    /// restarts from that step's end instead of from the dense output there
    /// ([`crate::integrator`], module documentation "Exact event steps"). For event functions
    /// placed where the right-hand side is not smooth (a mechanism's contact onsets and
    /// kinks), the state at the event and the step before it then see one smooth piece of
    /// the right-hand side only. Costs one step attempt per event. Default false; ignored by
    /// `rk4` and diffsol's methods; `lash` turns it on for scenes with `kink_events`.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub exact_event_steps: bool,
    /// Divergence bound: a state component larger in magnitude than this is treated as
    /// non-finite (`NonFiniteState`). Default 1e100.
    pub divergence_bound: f64,
    /// Stability check of fixed-step RK4: fail with `Rk4Unstable` once this many
    /// consecutive steps lie outside RK4's stability region (suspected from the stages,
    /// h·ρ > [`crate::rk4::RK4_STABILITY_RADIUS`], and confirmed by the eigenvalues of ∂f/∂y:
    /// `rk4` module doc). Default 0: off (the paper's RK4
    /// unchanged); `lash` turns it on (15) for mechanism runs. Ignored by the other methods.
    pub rk4_instability_steps: usize,
}

impl Default for SolverOptions {
    fn default() -> Self {
        SolverOptions {
            method: Method::Dopri54,
            rtol: 1e-6,
            atol: Atol::default(),
            step: None,
            h0: None,
            adaptive: true,
            h_min: 0.0,
            h_max: f64::INFINITY,
            h_max_near_events: f64::INFINITY,
            max_steps: 1_000_000,
            controller: None,
            limits: StepLimits::default(),
            output: Output::Steps,
            events: true,
            event_rtol: 1e-13,
            event_samples: 4,
            max_wall_time: None,
            max_memory: None,
            linear_algebra: Default::default(),
            exact_event_steps: false,
            divergence_bound: 1e100,
            rk4_instability_steps: 0,
        }
    }
}

impl SolverOptions {
    /// Options for a method with default settings.
    pub fn with_method(method: Method) -> Self {
        SolverOptions {
            method,
            ..Default::default()
        }
    }

    /// A copy with `output` at its default and everything else as here: the options an
    /// integration reads while it runs (the output is read by the one who records it), without
    /// copying an output grid. Every field is named, so a new one cannot be left out.
    pub(crate) fn without_output(&self) -> SolverOptions {
        let SolverOptions {
            method,
            rtol,
            atol,
            step,
            h0,
            adaptive,
            h_min,
            h_max,
            h_max_near_events,
            max_steps,
            controller,
            limits,
            output: _,
            events,
            event_rtol,
            event_samples,
            max_wall_time,
            max_memory,
            linear_algebra,
            exact_event_steps,
            divergence_bound,
            rk4_instability_steps,
        } = self;
        SolverOptions {
            method: *method,
            rtol: *rtol,
            atol: atol.clone(),
            step: *step,
            h0: *h0,
            adaptive: *adaptive,
            h_min: *h_min,
            h_max: *h_max,
            h_max_near_events: *h_max_near_events,
            max_steps: *max_steps,
            controller: *controller,
            limits: limits.clone(),
            output: Output::default(),
            events: *events,
            event_rtol: *event_rtol,
            event_samples: *event_samples,
            max_wall_time: *max_wall_time,
            max_memory: *max_memory,
            linear_algebra: *linear_algebra,
            exact_event_steps: *exact_event_steps,
            divergence_bound: *divergence_bound,
            rk4_instability_steps: *rk4_instability_steps,
        }
    }

    /// Checks the options against the rules (module documentation) for a system of
    /// dimension `n` and builds the configuration of the method's family.
    pub fn configure(&self, n: usize) -> Result<Config, OptionError> {
        self.configure_for(Some(n))
    }

    /// Checks every rule that does not need the system: all of them but the length of a
    /// vector `atol` (a front end that lays a choice over a case's options checks them
    /// before it knows the system).
    pub fn check(&self) -> Result<(), OptionError> {
        self.configure_for(None).map(|_| ())
    }

    /// [`SolverOptions::configure`]; without `n`, a vector `atol` has the length it has.
    fn configure_for(&self, n: Option<usize>) -> Result<Config, OptionError> {
        let method = self.method;
        let family = method.info().family;
        for (field, given) in [
            (OptionField::Step, self.step.is_some()),
            (OptionField::H0, self.h0.is_some()),
            (OptionField::Adaptive, !self.adaptive),
            (OptionField::Controller, self.controller.is_some()),
        ] {
            if given {
                family.check_takes(field, method)?;
            }
        }
        let budgets = Budgets::new(self.max_steps, self.max_wall_time)?;
        let config = match family {
            Family::FixedStep => Config::Fixed(FixedConfig::new(
                method,
                self.step,
                self.rk4_instability_steps,
                budgets,
            )?),
            Family::Explicit | Family::Rosenbrock => {
                let tolerances = self.tolerances(n)?;
                let bounds = StepBounds::new(self.h0, self.h_min, self.h_max)?;
                let control = if self.adaptive {
                    StepControl::Adaptive(AdaptiveControl::new(
                        method,
                        self.controller,
                        self.limits.clone(),
                        bounds,
                    )?)
                } else {
                    let h = self.h0.ok_or(OptionError::new(
                        OptionField::H0,
                        Reason::RequiredBy {
                            other: OptionField::Adaptive,
                        },
                    ))?;
                    StepControl::Fixed { h }
                };
                Config::OneStep(OneStepConfig::new(method, tolerances, control, budgets)?)
            }
            Family::Diffsol => {
                let tolerances = self.tolerances(n)?;
                let bounds = StepBounds::new(self.h0, self.h_min, self.h_max)?;
                Config::Diffsol(DiffsolConfig::new(method, tolerances, bounds, budgets)?)
            }
        };
        Rule::H_MAX_NEAR_EVENTS.check(self.h_max_near_events)?;
        Rule::EVENT_RTOL.check(self.event_rtol)?;
        Rule::EVENT_SAMPLES.check(self.event_samples as f64)?;
        Rule::DIVERGENCE_BOUND.check(self.divergence_bound)?;
        if let Output::Times(ts) = &self.output {
            // A grid (thousands of points) is checked in one pass of comparisons; only one
            // that fails is walked again entry by entry for the error, as before.
            if output_times_ok(ts) {
                return Ok(config);
            }
            for (i, t) in ts.iter().enumerate() {
                Rule::OUTPUT_TIME.check_entry(i, *t)?;
                if i > 0 && !(*t >= ts[i - 1]) {
                    return Err(OptionError::new(
                        OptionField::Output,
                        Reason::Decreasing { index: i },
                    ));
                }
            }
        }
        Ok(config)
    }

    /// The tolerances, for a system of dimension `n` (None: a vector atol's own length).
    fn tolerances(&self, n: Option<usize>) -> Result<Tolerances, OptionError> {
        let n = match (&self.atol, n) {
            (_, Some(n)) => n,
            (Atol::Vector(v), None) => v.len(),
            (Atol::Scalar(_), None) => 1,
        };
        Tolerances::new(self.rtol, self.atol.clone(), n)
    }

    /// Checks the options against the rules for a system of dimension `n`
    /// ([`SolverOptions::configure`] without keeping the configuration).
    pub fn validate(&self, n: usize) -> Result<(), OptionError> {
        self.configure(n).map(|_| ())
    }

    /// The controller a run with these options uses: the one named, else the method's
    /// default; None for methods that take no controller of ours (RK4, diffsol's methods).
    pub fn controller_in_use(&self) -> Option<ControllerKind> {
        self.method
            .default_controller()
            .map(|default| self.controller.unwrap_or(default))
    }
}

/// Whether output times pass [`Rule::OUTPUT_TIME`] and are non-decreasing: the checks of
/// `configure_for`'s loop, without their errors.
fn output_times_ok(ts: &[f64]) -> bool {
    let mut prev = f64::NEG_INFINITY;
    let mut ok = true;
    for &t in ts {
        // Allowed by the rule and not below the one before (NaN fails both).
        ok &= Rule::OUTPUT_TIME.allowed.contains(t) & (t >= prev);
        prev = t;
    }
    ok
}

impl Family {
    /// Whether the family's methods take `field` (the table of the module documentation):
    /// `step` and `rk4_instability_steps` only the fixed-step family; tolerances, `h0`,
    /// `h_min`, `h_max` every adaptive family; `controller` and `limits` our one-step
    /// methods only; `adaptive = false` every family but diffsol's; everything else every
    /// family.
    pub const fn takes(self, field: OptionField) -> bool {
        use OptionField as F;
        let fixed = matches!(self, Family::FixedStep);
        match field {
            F::Step | F::Rk4InstabilitySteps => fixed,
            F::Rtol | F::Atol | F::H0 | F::HMin | F::HMax | F::HMaxNearEvents => !fixed,
            F::Controller
            | F::Safety
            | F::MaxGrowth
            | F::MaxFirstGrowth
            | F::MinShrink
            | F::MaxAfterReject
            | F::MaxGrowthAfterReject
            | F::MaxAfterRepeatedReject
            | F::Deadband => self.is_one_step(),
            F::Adaptive => !matches!(self, Family::Diffsol),
            _ => true,
        }
    }

    /// [`Family::takes`] as a check: the typed error of `field` given for `method` (of this
    /// family) when the family does not take it.
    pub fn check_takes(self, field: OptionField, method: Method) -> Result<(), OptionError> {
        if self.takes(field) {
            Ok(())
        } else {
            Err(OptionError::not_for(field, method))
        }
    }
}
