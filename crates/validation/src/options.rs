//! The solver choice of a request, laid over a case's own options.
//!
//! ```text
//! SolverChoice { method, rtol, atol, step, controller, max_steps, max_wall_time, max_memory }
//!   (each optional)
//! choice.apply(base) = base with the choice laid over it, checked against the method:
//!   fixed-step: step only;  adaptive: rtol, atol, controller only;  budgets: any method
//! ```
//!
//! Errors name the options by their engine names ([`OptionError`]): `rtol`, `atol`, `step`,
//! `controller`, `method`, `max_steps`, `max_wall_time`, `max_memory`.
//!
//! Source: docs/outputs.md ("Method and controller names", "Defaults of a run").

use lash_solver::{Atol, ControllerKind, Method, SolverOptions};

use crate::error::{Error, OptionError};

/// Smallest relative tolerance accepted (the solver's range, `SolverOptions::rtol`); the range
/// of rtol is [`RTOL_MIN`, 1).
pub const RTOL_MIN: f64 = 1e-14;

/// What a request says about the solver; `None` means "as the case says".
///
/// ```text
/// method, rtol, atol, step, controller:  the method and its error or step control
/// max_steps, max_wall_time:             budgets; running out is a solver failure
///                                       ("too many steps", "budget exhausted")
/// max_memory:                           the budget of the implicit methods' n² matrices
///                                       (lash_solver::memory; "not enough memory")
/// ```
///
/// Source: docs/outputs.md ("Method and controller names").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SolverChoice {
    /// Integration method.
    pub method: Option<Method>,
    /// Relative tolerance of adaptive methods, in [[`RTOL_MIN`], 1).
    pub rtol: Option<f64>,
    /// Absolute tolerance of adaptive methods: one number, or one per state component.
    pub atol: Option<Atol>,
    /// Fixed step of fixed-step methods, s.
    pub step: Option<f64>,
    /// Step-size controller of our adaptive methods.
    pub controller: Option<ControllerKind>,
    /// Step budget: most step attempts (accepted and rejected).
    pub max_steps: Option<usize>,
    /// Wall-clock budget of the integration, s.
    pub max_wall_time: Option<f64>,
    /// Memory budget of the dense n² matrices, bytes (default: half of what is available).
    pub max_memory: Option<u64>,
}

impl SolverChoice {
    /// Lays the choice over `base` (the case's own options, or the defaults) and checks that
    /// it fits the method that results.
    ///
    /// ```text
    /// method = choice.method or base.method
    /// fixed-step: rtol, atol, controller are errors; step = choice.step, or base.step
    ///             if the method did not change; none → "needs step"
    /// adaptive:   step is an error; a controller on diffsol's methods is an error;
    ///             rtol, atol = the choice or base; controller = the choice, or base's if the
    ///             method did not change
    /// budgets:    max_steps, max_wall_time, max_memory replace base's for any method
    /// ```
    pub fn apply(&self, base: &SolverOptions) -> Result<SolverOptions, Error> {
        let method = self.method.unwrap_or(base.method);
        let same = method == base.method;
        let mut o = base.clone();
        o.method = method;
        if let Some(n) = self.max_steps {
            o.max_steps = n;
        }
        if let Some(w) = self.max_wall_time {
            o.max_wall_time = Some(w);
        }
        if let Some(m) = self.max_memory {
            o.max_memory = Some(m);
        }
        if method.is_fixed_step() {
            for (option, given) in [
                ("rtol", self.rtol.is_some()),
                ("atol", self.atol.is_some()),
                ("controller", self.controller.is_some()),
            ] {
                if given {
                    return Err(OptionError::leading(
                        option,
                        format!(" is only for adaptive methods, and {method} is fixed-step"),
                    )
                    .into());
                }
            }
            o.step = self.step.or(if same { base.step } else { None });
            if o.step.is_none() {
                return Err(OptionError::new("step")
                    .text(format!("method {method} is fixed-step and needs "))
                    .name("step")
                    .into());
            }
            o.controller = None;
        } else {
            if self.step.is_some() {
                return Err(OptionError::leading(
                    "step",
                    format!(" is only for fixed-step methods, and {method} is adaptive"),
                )
                .into());
            }
            if self.controller.is_some() && method.is_diffsol() {
                return Err(OptionError::leading(
                    "controller",
                    format!(" does not apply to {method}, which uses diffsol's own step control"),
                )
                .into());
            }
            o.step = None;
            if let Some(r) = self.rtol {
                o.rtol = r;
            }
            if let Some(a) = &self.atol {
                o.atol = a.clone();
            }
            o.controller = if method.is_diffsol() {
                None
            } else {
                self.controller
                    .or(if same { base.controller } else { None })
            };
        }
        Ok(o)
    }
}

/// Checks that a list names no item twice: the error names the list's option.
pub fn no_duplicates<T>(
    option: &'static str,
    v: &[T],
    name: impl Fn(&T) -> String,
) -> Result<(), Error> {
    for (i, a) in v.iter().enumerate() {
        if v[..i].iter().any(|b| name(b) == name(a)) {
            return Err(OptionError::leading(option, format!(" lists {} twice", name(a))).into());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_engine_options() {
        let d = SolverOptions::default(); // dopri54
        let c = SolverChoice {
            method: Some(Method::Rk4),
            ..Default::default()
        };
        let e = c.apply(&d).unwrap_err();
        assert_eq!(e.to_string(), "method rk4 is fixed-step and needs step");
        let Error::Option(o) = e else { panic!() };
        assert_eq!(o.option, "step");
        let c = SolverChoice {
            method: Some(Method::Rk4),
            step: Some(1e-4),
            max_steps: Some(9),
            rtol: Some(1e-6),
            ..Default::default()
        };
        assert_eq!(
            c.apply(&d).unwrap_err().to_string(),
            "rtol is only for adaptive methods, and rk4 is fixed-step"
        );
        let e = no_duplicates("methods", &[1, 2, 1], |x| x.to_string()).unwrap_err();
        assert_eq!(e.to_string(), "methods lists 1 twice");
    }
}
