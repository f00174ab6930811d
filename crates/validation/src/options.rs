//! The solver choice of a request, laid over a case's own options.
//!
//! ```text
//! SolverChoice { method, rtol, atol, step, controller, max_steps, max_wall_time, max_memory }
//!   (each optional)
//! choice.apply(base) = base with the choice laid over it; the solver's rules decide
//!   which option fits which method and what values are allowed (lash_solver::options)
//! ```
//!
//! The rules are the solver's (`lash_solver::options`: `Family::takes` and
//! [`SolverOptions::check`]); its typed errors become [`OptionError`]s that name the options
//! by their engine names: `rtol`, `atol`, `step`, `controller`, `method`, `max_steps`,
//! `max_wall_time`, `max_memory`.
//!
//! Source: docs/outputs.md ("Method and controller names", "Defaults of a run").

use lash_solver::{Atol, ControllerKind, Method, OptionField, SolverOptions};

use crate::error::{Error, OptionError};

/// What a request says about the solver; `None` means "as the case says".
///
/// ```text
/// method, rtol, atol, step, controller:  the method and its error or step control
/// max_memory:                           the budget of the implicit methods' n² matrices
///                                       (lash_solver::memory; "not enough memory")
/// max_steps, max_wall_time:             budgets; running out is a solver failure
///                                       ("too many steps", "budget exhausted")
/// ```
///
/// Source: docs/outputs.md ("Method and controller names").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SolverChoice {
    /// Integration method.
    pub method: Option<Method>,
    /// Relative tolerance of adaptive methods (range: `lash_solver::Rule::RTOL`).
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
    /// Lays the choice over `base` (the case's own options, or the defaults) and checks the
    /// result by the solver's rules.
    ///
    /// ```text
    /// method = choice.method or base.method
    /// an option given that the method does not take is an error (Family::takes):
    ///   rtol, atol on fixed-step methods; step on adaptive ones; controller on fixed-step
    ///   and diffsol's methods
    /// rtol, atol, max_steps, max_wall_time, max_memory = the choice, else base's
    /// step, controller = the choice, else base's if the method did not change, where the
    ///   method takes them (none else)
    /// then SolverOptions::check (a fixed-step method needs step, the ranges)
    /// ```
    pub fn apply(&self, base: &SolverOptions) -> Result<SolverOptions, Error> {
        let method = self.method.unwrap_or(base.method);
        let family = method.info().family;
        for (field, given) in [
            (OptionField::Rtol, self.rtol.is_some()),
            (OptionField::Atol, self.atol.is_some()),
            (OptionField::Controller, self.controller.is_some()),
            (OptionField::Step, self.step.is_some()),
        ] {
            if given {
                family.check_takes(field, method)?;
            }
        }
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
        if let Some(r) = self.rtol {
            o.rtol = r;
        }
        if let Some(a) = &self.atol {
            o.atol = a.clone();
        }
        let base_step = if same { base.step } else { None };
        let base_controller = if same { base.controller } else { None };
        o.step = self
            .step
            .or(base_step)
            .filter(|_| family.takes(OptionField::Step));
        o.controller = self
            .controller
            .or(base_controller)
            .filter(|_| family.takes(OptionField::Controller));
        o.check()?;
        Ok(o)
    }
}

/// Checks that a list names no item twice: the error names the list's option.
pub(crate) fn no_duplicates<T>(
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
        assert_eq!(
            e.to_string(),
            "method rk4 is fixed-step and needs step (it needs a fixed step size)"
        );
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
