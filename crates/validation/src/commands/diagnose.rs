//! `lash stiffness` and `lash poincare`: diagnostics of one case.
//!
//! Source: docs/outputs.md ("`lash stiffness CASE`", "`lash poincare CASE`").

use std::path::PathBuf;

use lash_solver::{Method, SolverOptions};

use crate::commands::default_out;
use crate::diagnostics::poincare::{self, PoincareResult, PoincareSettings};
use crate::diagnostics::stiffness::report::StiffnessResult;
use crate::diagnostics::stiffness::sample::StiffnessSettings;
use crate::diagnostics::stiffness::sample::DEFAULT_SAMPLES;
use crate::error::Error;
use crate::options::SolverChoice;
use crate::progress::Progress;
use crate::run::case::Case;
use crate::run::mechanism::paper_formulation;
use crate::run::prepare::Prepared;
use crate::store::io::Written;

/// What to diagnose: the stiffness of one case.
///
/// ```text
/// case [solver choice] [samples] [t_end] [measure] [out]
/// ```
///
/// Source: docs/outputs.md ("`lash stiffness CASE`").
#[derive(Debug, Clone, PartialEq)]
pub struct StiffnessOptions {
    /// The case: a scene file (JSON) or a built-in test problem `testset:NAME`.
    pub case: String,
    /// Solver of the reference run over the case's defaults.
    pub solver: SolverChoice,
    /// Sample points along the run, both ends included (≥ 2); None = `DEFAULT_SAMPLES`.
    pub samples: Option<usize>,
    /// End time override, s (scene cases only).
    pub t_end: Option<f64>,
    /// Whether to measure the RK4 limit (the bisection runs RK4 over the whole run many
    /// times).
    pub measure: bool,
    /// Output directory; None = `out/stiffness/CASE`.
    pub out: Option<PathBuf>,
}

impl Default for StiffnessOptions {
    fn default() -> Self {
        StiffnessOptions {
            case: String::new(),
            solver: SolverChoice::default(),
            samples: None,
            t_end: None,
            measure: true,
            out: None,
        }
    }
}

/// Stiffness diagnostics: checks the case and the options, integrates the reference run
/// analysing the Jacobian at the sample points, measures the RK4 limit, and writes
/// stiffness.csv, stiffness.{svg,png}, stiffness.md and stiffness.json.
pub fn stiffness(
    o: &StiffnessOptions,
    progress: &dyn Progress,
) -> Result<Written<StiffnessResult>, Error> {
    let case = Case::load(&o.case, None)?;
    o.solver.apply(&SolverOptions::default())?;
    let mut prepared = Prepared::load(case)?;
    // The analysis predicts and measures RK4's limit, so it analyses the formulation
    // `lash run --method rk4` integrates: on a scene whose formulation is `auto` that is the
    // paper's lagrange_baumgarte (`paper_formulation`), for the reference run too, whatever its
    // method; a scene that names its formulation is analysed in it.
    if let Some(s) = prepared.scene() {
        let f = paper_formulation(s, Method::Rk4).formulation;
        if f != s.formulation {
            prepared = prepared.with_formulation(f)?;
        }
    }
    let opts = prepared.options(&o.solver)?;
    prepared.t_span(o.t_end)?;
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| default_out("stiffness", &prepared.case.name));
    let settings = StiffnessSettings {
        samples: o.samples.unwrap_or(DEFAULT_SAMPLES),
        t_end: o.t_end,
        measure: o.measure,
        ..Default::default()
    };
    let r = crate::diagnostics::stiffness::analyse::analyse(&prepared, &opts, &settings, progress)?;
    let files = r.write(&out)?;
    Ok(Written {
        result: r,
        dir: out,
        files,
    })
}

/// What to diagnose: the Poincaré section and Lyapunov exponent of one case.
///
/// ```text
/// case [revolutions] [perturbation] [renorm_per_rev] [solver choice] [out]
/// ```
///
/// Source: docs/outputs.md ("`lash poincare CASE`").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PoincareOptions {
    /// The case: a scene file (JSON) with a crank driver and a clearance joint role.
    pub case: String,
    /// Crank revolutions (≥ 1); None = the default.
    pub revolutions: Option<usize>,
    /// Initial and renormalised separation, in clearances, in (0, 1); None = the default.
    pub perturbation: Option<f64>,
    /// Renormalisations per crank revolution (≥ 1); None = the default.
    pub renorm_per_rev: Option<usize>,
    /// Solver of both trajectories over the case's defaults (`poincare::options`).
    pub solver: SolverChoice,
    /// Output directory; None = `out/poincare/CASE`.
    pub out: Option<PathBuf>,
}

/// Chaos diagnostics: checks the case (a crank driver and a clearance joint role) and the
/// options, integrates the section run and the two Lyapunov trajectories, and writes
/// poincare.csv, lyapunov.csv, the figures, poincare.md and poincare.json.
pub fn poincare(
    o: &PoincareOptions,
    progress: &dyn Progress,
) -> Result<Written<PoincareResult>, Error> {
    let case = Case::load(&o.case, None)?;
    o.solver.apply(&SolverOptions::default())?;
    let prepared = Prepared::load(case)?;
    let opts = poincare::options(&prepared, &o.solver)?;
    let d = PoincareSettings::default();
    let settings = PoincareSettings {
        revolutions: o.revolutions.unwrap_or(d.revolutions),
        perturbation: o.perturbation.unwrap_or(d.perturbation),
        renorm_per_rev: o.renorm_per_rev.unwrap_or(d.renorm_per_rev),
    };
    settings.validate()?;
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| default_out("poincare", &prepared.case.name));
    let r = poincare::analyse(&prepared, &opts, &settings, progress)?;
    let files = r.write(&out)?;
    Ok(Written {
        result: r,
        dir: out,
        files,
    })
}
