//! Validated configurations, one per family of methods: what the steppers consume.
//!
//! ```text
//! Config::Fixed(FixedConfig)      RK4: step, stability check, budgets
//! Config::OneStep(OneStepConfig)  explicit pairs, Rodas5P: tolerances, StepControl, budgets
//!     StepControl::Adaptive(AdaptiveControl)  controller (resolved), limits, h0, h_min, h_max
//!     StepControl::Fixed { h }                adaptive = false: every step h
//! Config::Diffsol(DiffsolConfig)  BDF, TR-BDF2, ESDIRK3(4): tolerances, h0, h_min, h_max, budgets
//! ```
//!
//! Every piece checks its own rules in its constructor ([`Tolerances::new`],
//! [`Budgets::new`], [`StepBounds::new`], [`FixedConfig::new`], …) and keeps its fields
//! private, so a configuration that exists is valid. [`crate::SolverOptions::configure`]
//! builds them from the flat options; the rules are listed in the [`crate::options`] module
//! documentation.

use crate::controller::{ControllerKind, StepLimits};
use crate::method::{Family, Method};
use crate::options::error::{OptionError, OptionField, Reason};
use crate::options::rules::Rule;

/// The validated options of one integration, by family ([`Family`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Config {
    /// A fixed-step method (RK4).
    Fixed(FixedConfig),
    /// One of our one-step methods (the explicit pairs, Rodas5P).
    OneStep(OneStepConfig),
    /// One of diffsol's methods.
    Diffsol(DiffsolConfig),
}

impl Config {
    /// The method.
    pub fn method(&self) -> Method {
        match self {
            Config::Fixed(c) => c.method,
            Config::OneStep(c) => c.method,
            Config::Diffsol(c) => c.method,
        }
    }

    /// The budgets.
    pub fn budgets(&self) -> Budgets {
        match self {
            Config::Fixed(c) => c.budgets,
            Config::OneStep(c) => c.budgets,
            Config::Diffsol(c) => c.budgets,
        }
    }
}

/// Checks that `method` is of the kind a constructor builds (`expected` says which, as
/// messages do: "one of diffsol's methods").
fn check_family(method: Method, ok: bool, expected: &'static str) -> Result<(), OptionError> {
    if ok {
        Ok(())
    } else {
        Err(OptionError::new(
            OptionField::Method,
            Reason::WrongFamily { method, expected },
        ))
    }
}

/// What the one-step configurations expect, as messages say it.
const ONE_STEP: &str = "one of our one-step methods (an explicit pair or a Rosenbrock method)";

/// The budgets of an integration: step attempts and wall-clock time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Budgets {
    max_steps: usize,
    max_wall_time: Option<f64>,
}

impl Budgets {
    /// Checks `max_steps` ≥ 1 and `max_wall_time` finite and > 0.
    pub fn new(max_steps: usize, max_wall_time: Option<f64>) -> Result<Self, OptionError> {
        Rule::MAX_STEPS.check(max_steps as f64)?;
        if let Some(w) = max_wall_time {
            Rule::MAX_WALL_TIME.check(w)?;
        }
        Ok(Budgets {
            max_steps,
            max_wall_time,
        })
    }

    /// Most step attempts (accepted and rejected).
    pub fn max_steps(&self) -> usize {
        self.max_steps
    }

    /// Wall-clock budget in seconds (None: no budget).
    pub fn max_wall_time(&self) -> Option<f64> {
        self.max_wall_time
    }
}

/// Absolute tolerance: one number for every component, or one per component.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(untagged)]
pub enum Atol {
    /// The same absolute tolerance for every component.
    Scalar(f64),
    /// One absolute tolerance per component (length n).
    Vector(Vec<f64>),
}

impl Atol {
    /// The absolute tolerance of component `i`.
    #[inline]
    pub fn get(&self, i: usize) -> f64 {
        match self {
            Atol::Scalar(a) => *a,
            Atol::Vector(v) => v[i],
        }
    }
}

impl Default for Atol {
    fn default() -> Self {
        Atol::Scalar(1e-9)
    }
}

/// Relative and absolute tolerances for a system of dimension n.
#[derive(Clone, Debug, PartialEq)]
pub struct Tolerances {
    rtol: f64,
    atol: Atol,
}

impl Tolerances {
    /// Checks rtol ∈ [1e-14, 1) and each atol finite and > 0, one per component when a vector.
    pub fn new(rtol: f64, atol: Atol, n: usize) -> Result<Self, OptionError> {
        Rule::RTOL.check(rtol)?;
        match &atol {
            Atol::Scalar(a) => {
                Rule::ATOL.check(*a)?;
            }
            Atol::Vector(v) => {
                if v.len() != n {
                    return Err(OptionError::new(
                        OptionField::Atol,
                        Reason::WrongLength {
                            len: v.len(),
                            expected: n,
                        },
                    ));
                }
                for (i, a) in v.iter().enumerate() {
                    Rule::ATOL.check_entry(i, *a)?;
                }
            }
        }
        Ok(Tolerances { rtol, atol })
    }

    /// Relative tolerance.
    pub fn rtol(&self) -> f64 {
        self.rtol
    }

    /// Absolute tolerance.
    pub fn atol(&self) -> &Atol {
        &self.atol
    }
}

/// The first step and the step-size bounds of an adaptive method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepBounds {
    h0: Option<f64>,
    h_min: f64,
    h_max: f64,
}

impl StepBounds {
    /// Checks h_min finite and ≥ 0, h_max > h_min, h0 finite and > 0.
    pub fn new(h0: Option<f64>, h_min: f64, h_max: f64) -> Result<Self, OptionError> {
        Rule::H_MIN.check(h_min)?;
        if !(h_max > h_min) {
            return Err(OptionError::new(
                OptionField::HMax,
                Reason::NotAbove {
                    value: h_max,
                    other: OptionField::HMin,
                    other_value: h_min,
                },
            ));
        }
        if let Some(h0) = h0 {
            Rule::H0.check(h0)?;
        }
        Ok(StepBounds { h0, h_min, h_max })
    }

    /// The first trial step (None: the starting-step algorithm).
    pub fn h0(&self) -> Option<f64> {
        self.h0
    }

    /// Smallest step.
    pub fn h_min(&self) -> f64 {
        self.h_min
    }

    /// Largest step.
    pub fn h_max(&self) -> f64 {
        self.h_max
    }
}

/// A fixed-step method (RK4).
#[derive(Clone, Debug, PartialEq)]
pub struct FixedConfig {
    method: Method,
    step: f64,
    instability_steps: usize,
    budgets: Budgets,
}

impl FixedConfig {
    /// Checks that the method is fixed-step and that `step` is given, finite and > 0;
    /// `instability_steps` is RK4's stability check (0: off).
    pub fn new(
        method: Method,
        step: Option<f64>,
        instability_steps: usize,
        budgets: Budgets,
    ) -> Result<Self, OptionError> {
        check_family(method, method.is_fixed_step(), Family::FixedStep.describe())?;
        let step = step.ok_or(OptionError::new(
            OptionField::Step,
            Reason::Required { method },
        ))?;
        Rule::STEP.check(step)?;
        Ok(FixedConfig {
            method,
            step,
            instability_steps,
            budgets,
        })
    }

    /// The method.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The step, s.
    pub fn step(&self) -> f64 {
        self.step
    }

    /// Flagged steps in a row that fail the run (`rk4_instability_steps`; 0: no check).
    pub fn instability_steps(&self) -> usize {
        self.instability_steps
    }

    /// The budgets.
    pub fn budgets(&self) -> Budgets {
        self.budgets
    }
}

/// How our one-step driver chooses the step.
#[derive(Clone, Debug, PartialEq)]
pub enum StepControl {
    /// Error control with a controller.
    Adaptive(AdaptiveControl),
    /// `adaptive = false`: every step is `h` (the last one shortened to land on the end),
    /// no error estimate, no rejection.
    Fixed {
        /// The step.
        h: f64,
    },
}

/// Error control of our one-step driver: the controller in use (the method's default when
/// the options name none), its limits and the step bounds.
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveControl {
    controller: ControllerKind,
    limits: StepLimits,
    bounds: StepBounds,
}

impl AdaptiveControl {
    /// The control of `method` (one of our one-step methods) with `controller` (None: the
    /// method's default, [`Method::default_controller`]); checks the limits.
    pub fn new(
        method: Method,
        controller: Option<ControllerKind>,
        limits: StepLimits,
        bounds: StepBounds,
    ) -> Result<Self, OptionError> {
        let Some(default) = method.default_controller() else {
            return Err(OptionError::new(
                OptionField::Method,
                Reason::WrongFamily {
                    method,
                    expected: ONE_STEP,
                },
            ));
        };
        limits.validate()?;
        Ok(AdaptiveControl {
            controller: controller.unwrap_or(default),
            limits,
            bounds,
        })
    }

    /// The controller in use.
    pub fn controller(&self) -> ControllerKind {
        self.controller
    }

    /// The limits of the step-size factor.
    pub fn limits(&self) -> &StepLimits {
        &self.limits
    }

    /// First step and step bounds.
    pub fn bounds(&self) -> StepBounds {
        self.bounds
    }
}

/// One of our one-step methods (the explicit pairs, Rodas5P).
#[derive(Clone, Debug, PartialEq)]
pub struct OneStepConfig {
    method: Method,
    tolerances: Tolerances,
    control: StepControl,
    budgets: Budgets,
}

impl OneStepConfig {
    /// Checks that the method is one of our one-step methods and that a fixed step is
    /// finite and > 0.
    pub fn new(
        method: Method,
        tolerances: Tolerances,
        control: StepControl,
        budgets: Budgets,
    ) -> Result<Self, OptionError> {
        check_family(method, method.info().family.is_one_step(), ONE_STEP)?;
        if let StepControl::Fixed { h } = control {
            Rule::H0.check(h)?;
        }
        Ok(OneStepConfig {
            method,
            tolerances,
            control,
            budgets,
        })
    }

    /// The method.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The tolerances.
    pub fn tolerances(&self) -> &Tolerances {
        &self.tolerances
    }

    /// How the step is chosen.
    pub fn control(&self) -> &StepControl {
        &self.control
    }

    /// The budgets.
    pub fn budgets(&self) -> Budgets {
        self.budgets
    }
}

/// One of diffsol's methods: tolerances and step bounds (diffsol's own controller).
#[derive(Clone, Debug, PartialEq)]
pub struct DiffsolConfig {
    method: Method,
    tolerances: Tolerances,
    bounds: StepBounds,
    budgets: Budgets,
}

impl DiffsolConfig {
    /// Checks that the method is one of diffsol's.
    pub fn new(
        method: Method,
        tolerances: Tolerances,
        bounds: StepBounds,
        budgets: Budgets,
    ) -> Result<Self, OptionError> {
        check_family(method, method.is_diffsol(), Family::Diffsol.describe())?;
        Ok(DiffsolConfig {
            method,
            tolerances,
            bounds,
            budgets,
        })
    }

    /// The method.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The tolerances.
    pub fn tolerances(&self) -> &Tolerances {
        &self.tolerances
    }

    /// First step and step bounds.
    pub fn bounds(&self) -> StepBounds {
        self.bounds
    }

    /// The budgets.
    pub fn budgets(&self) -> Budgets {
        self.budgets
    }
}
