//! A scene's `solver` section: the integration settings the scene asks for, used by `lash run`
//! (and `lash.run`, sweeps) where the command line gives none.
//!
//! ```text
//! "solver": { "method": "rodas5p", "rtol": 1e-10, "atol": 1e-12 }     every field optional
//! precedence:  command-line option (or Python keyword)  >  scene's solver  >  built-in default
//! method       an adaptive method (a fixed-step one needs a step, which is a run's choice)
//! rtol         lash_solver::Rule::RTOL, [1e-14, 1)
//! atol         > 0, one number for every state component (without it, the run's default
//!              atol vector at the scene's rtol)
//! ```
//!
//! Why a scene carries it: some scenes need a tighter default than the press does for their
//! answers to hold. The stress cases of `cases/extremes` (2000 rpm, a 1 µm oil film) close
//! their energy balance only below the default rtol 1e-8 (BENCHMARKS.md, "Energy balance of
//! every case"); a scene that says so runs correctly with `lash run FILE` alone. Commands that
//! choose their own methods and tolerances (compare, work-precision, the extremes matrix, the
//! paper's study) are not affected.

use serde::{Deserialize, Serialize};

use lash_solver::{Method, Rule};

use crate::scene::check::Checker;
use crate::scene::error::{invalid, SceneError};

/// The `solver` section of a scene (module doc). Every field is optional.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// Integration method (adaptive only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method: Option<Method>,
    /// Relative tolerance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rtol: Option<f64>,
    /// Absolute tolerance, one number for every state component.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub atol: Option<f64>,
}

impl SolverSpec {
    /// True when the section sets nothing (it is then left out of the scene's JSON).
    pub fn is_empty(&self) -> bool {
        *self == SolverSpec::default()
    }

    /// Checks the section (errors name `solver.FIELD`).
    pub(crate) fn check(&self) -> Result<(), SceneError> {
        if let Some(m) = self.method {
            if m.is_fixed_step() {
                return Err(invalid(
                    "solver.method",
                    format!(
                        "{m} is a fixed-step method: a scene's solver section sets adaptive \
                         defaults only (give `--method {m} --step H` to a run instead)"
                    ),
                ));
            }
        }
        if let Some(r) = self.rtol {
            Rule::RTOL
                .check(r)
                .map_err(|e| invalid("solver.rtol", e.to_string()))?;
        }
        if let Some(a) = self.atol {
            Checker::positive("solver.atol", a, "atol")?;
        }
        Ok(())
    }
}
