//! Solver options: method, tolerances, step limits, controller, output and events.
//! Every field documents its default and valid range; [`SolverOptions::validate`] checks them.

use crate::controller::{ControllerKind, StepLimits};
use crate::error::SolveError;

/// Integration method. Names are the contract of docs/outputs.md ("Method and controller names").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Classical Runge–Kutta 4, fixed step (the paper's method). Needs `step`.
    Rk4,
    /// Bogacki–Shampine 3(2), FSAL.
    Bs32,
    /// Dormand–Prince 5(4), FSAL.
    Dopri54,
    /// Tsitouras 5(4), FSAL.
    Tsit54,
    /// Dormand–Prince 8(5,3) (Hairer's DOP853).
    Dop853,
    /// diffsol's variable-order BDF.
    Bdf,
    /// diffsol's TR-BDF2 (an ESDIRK).
    Trbdf2,
    /// diffsol's ESDIRK3(4).
    Esdirk34,
    /// Our own Rosenbrock method Rodas5P (Steinebach 2023), order 5(4), stiffly accurate.
    Rodas5p,
}

impl Method {
    /// All methods, in the order the tools list them.
    pub const ALL: [Method; 9] = [
        Method::Rk4,
        Method::Bs32,
        Method::Dopri54,
        Method::Tsit54,
        Method::Dop853,
        Method::Bdf,
        Method::Trbdf2,
        Method::Esdirk34,
        Method::Rodas5p,
    ];

    /// The method's name in the CLI, scene options and summary.json.
    pub fn name(self) -> &'static str {
        match self {
            Method::Rk4 => "rk4",
            Method::Bs32 => "bs32",
            Method::Dopri54 => "dopri54",
            Method::Tsit54 => "tsit54",
            Method::Dop853 => "dop853",
            Method::Bdf => "bdf",
            Method::Trbdf2 => "trbdf2",
            Method::Esdirk34 => "esdirk34",
            Method::Rodas5p => "rodas5p",
        }
    }

    /// Parses a method name (the inverse of [`Method::name`]).
    pub fn from_name(s: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == s)
    }

    /// True for fixed-step methods (they take `step`, not tolerances).
    pub fn is_fixed_step(self) -> bool {
        matches!(self, Method::Rk4)
    }

    /// True for diffsol's methods (they take no controller of ours).
    pub fn is_diffsol(self) -> bool {
        matches!(self, Method::Bdf | Method::Trbdf2 | Method::Esdirk34)
    }

    /// True for implicit (stiff) methods.
    pub fn is_stiff(self) -> bool {
        self.is_diffsol() || matches!(self, Method::Rodas5p)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
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

/// Options of one integration.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SolverOptions {
    /// Method. Default `dopri54`.
    pub method: Method,
    /// Relative tolerance. Default 1e-6; valid range [1e-14, 1).
    pub rtol: f64,
    /// Absolute tolerance, scalar or per component. Default 1e-9; each entry ≥ 0 and finite,
    /// and rtol + atol > 0 is not enough: each atol must be > 0 for components that may be 0.
    pub atol: Atol,
    /// Fixed step of fixed-step methods (s). Required for `rk4`, rejected otherwise; > 0.
    pub step: Option<f64>,
    /// Initial step. Default None: chosen by Hairer's starting-step algorithm (HNW I, II.4).
    /// With `adaptive = false` it is the fixed step of every step.
    pub h0: Option<f64>,
    /// Whether adaptive methods control the step size. Default true. When false, an adaptive
    /// method of ours (the explicit pairs, Rosenbrock) takes `h0` (required) on every step,
    /// shortening only the last one to land on the end time, computes no error estimate and
    /// never rejects a step: the mode of fixed-step convergence-order tests. Ignored by `rk4`
    /// (always fixed-step); not available for diffsol's methods.
    pub adaptive: bool,
    /// Smallest step allowed before failing with `StepSizeTooSmall`. Default 0 (then
    /// 16·ε·|t| is the floor); ≥ 0.
    pub h_min: f64,
    /// Largest step allowed. Default +∞; > h_min.
    pub h_max: f64,
    /// Most step attempts before failing with `TooManySteps`. Default 1 000 000; ≥ 1.
    pub max_steps: usize,
    /// Step-size controller (ignored by diffsol's methods and by fixed-step methods). Default
    /// None: the method's own default (`pi` for explicit pairs, `gustafsson` for Rosenbrock).
    pub controller: Option<ControllerKind>,
    /// Safety factor, growth/shrink caps, dead-band.
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
            max_steps: 1_000_000,
            controller: None,
            limits: StepLimits::default(),
            output: Output::Steps,
            events: true,
            event_rtol: 1e-13,
            event_samples: 4,
            max_wall_time: None,
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

    /// Checks ranges and consistency for a system of dimension `n`.
    pub fn validate(&self, n: usize) -> Result<(), SolveError> {
        let bad = |m: String| Err(SolveError::InvalidOptions(m));
        if self.method.is_fixed_step() {
            match self.step {
                Some(h) if h.is_finite() && h > 0.0 => {}
                Some(h) => return bad(format!("step must be finite and > 0, got {h}")),
                None => return bad(format!("method {} needs a fixed step", self.method)),
            }
        } else {
            if self.step.is_some() {
                return bad(format!(
                    "step is only for fixed-step methods, not {}",
                    self.method
                ));
            }
            if !(self.rtol.is_finite() && (1e-14..1.0).contains(&self.rtol)) {
                return bad(format!("rtol must be in [1e-14, 1), got {}", self.rtol));
            }
            match &self.atol {
                Atol::Scalar(a) => {
                    if !(a.is_finite() && *a > 0.0) {
                        return bad(format!("atol must be finite and > 0, got {a}"));
                    }
                }
                Atol::Vector(v) => {
                    if v.len() != n {
                        return bad(format!("atol has {} entries, the system {n}", v.len()));
                    }
                    if let Some(a) = v.iter().find(|a| !(a.is_finite() && **a > 0.0)) {
                        return bad(format!("every atol must be finite and > 0, got {a}"));
                    }
                }
            }
        }
        if !(self.h_min.is_finite() && self.h_min >= 0.0) {
            return bad(format!("h_min must be finite and >= 0, got {}", self.h_min));
        }
        if !(self.h_max > self.h_min) || self.h_max.is_nan() {
            return bad(format!(
                "h_max ({}) must exceed h_min ({})",
                self.h_max, self.h_min
            ));
        }
        if let Some(h0) = self.h0 {
            if !(h0.is_finite() && h0 > 0.0) {
                return bad(format!("h0 must be finite and > 0, got {h0}"));
            }
        }
        if !self.adaptive && !self.method.is_fixed_step() {
            if self.method.is_diffsol() {
                return bad(format!(
                    "adaptive = false is not available for {}",
                    self.method
                ));
            }
            if self.h0.is_none() {
                return bad("adaptive = false needs h0 (the fixed step)".into());
            }
        }
        if self.max_steps == 0 {
            return bad("max_steps must be >= 1".into());
        }
        if !(1e-15..=1e-3).contains(&self.event_rtol) {
            return bad(format!(
                "event_rtol must be in [1e-15, 1e-3], got {}",
                self.event_rtol
            ));
        }
        if self.event_samples > 64 {
            return bad(format!(
                "event_samples must be <= 64, got {}",
                self.event_samples
            ));
        }
        if let Some(w) = self.max_wall_time {
            if !(w.is_finite() && w > 0.0) {
                return bad(format!("max_wall_time must be finite and > 0, got {w}"));
            }
        }
        if !(self.divergence_bound > 0.0) {
            return bad("divergence_bound must be > 0".into());
        }
        if let Output::Times(ts) = &self.output {
            if ts.windows(2).any(|w| !(w[1] >= w[0])) || ts.iter().any(|t| !t.is_finite()) {
                return bad("output times must be finite and non-decreasing".into());
            }
        }
        if self.controller.is_some() && (self.method.is_fixed_step() || self.method.is_diffsol()) {
            return bad(format!("method {} takes no controller", self.method));
        }
        self.limits.validate()
    }
}
