//! How a run of the matrix ended (agreement within its promise, a typed error, a known
//! finding, or a failure) and the matrix of all runs.
//!
//! Source: the module doc of `studies::extremes`; docs/outputs.md ("`lash extremes`").

use std::collections::BTreeMap;

use lash_solver::{Method, SolveError};

use crate::compare::reference::ErrorWindow;
use crate::compare::workprecision::fmt_num;
use crate::studies::extremes::plan::Plan;
use crate::studies::extremes::plan::Setting;

/// A typed solver failure, by kind.
///
/// ```text
/// StepSizeTooSmall | TooManySteps | NonFiniteState | Rk4Unstable | NewtonFailure
/// | BudgetExhausted
/// ```
///
/// Source: `lash_solver::SolveError`.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum FailureKind {
    /// The step size fell below its floor.
    StepSizeTooSmall,
    /// The step budget ran out.
    TooManySteps,
    /// A non-finite or diverging state.
    NonFiniteState,
    /// RK4 outside its stability region (its stability check).
    Rk4Unstable,
    /// Newton's iteration failed.
    NewtonFailure,
    /// The wall-clock budget ran out.
    BudgetExhausted,
    /// The system refused an accepted state (a singular configuration, a constraint
    /// violation above its tolerance).
    StateRejected,
}

impl FailureKind {
    /// Short name for the tables.
    pub(crate) fn short(self) -> &'static str {
        match self {
            FailureKind::StepSizeTooSmall => "h-min",
            FailureKind::TooManySteps => "steps",
            FailureKind::NonFiniteState => "diverged",
            FailureKind::Rk4Unstable => "unstable",
            FailureKind::NewtonFailure => "newton",
            FailureKind::BudgetExhausted => "wall",
            FailureKind::StateRejected => "refused",
        }
    }

    pub(crate) fn of(e: &SolveError) -> Option<FailureKind> {
        Some(match e {
            SolveError::StepSizeTooSmall { .. } => FailureKind::StepSizeTooSmall,
            SolveError::TooManySteps { .. } => FailureKind::TooManySteps,
            SolveError::NonFiniteState { .. } => FailureKind::NonFiniteState,
            SolveError::Rk4Unstable { .. } => FailureKind::Rk4Unstable,
            SolveError::NewtonFailure { .. } => FailureKind::NewtonFailure,
            SolveError::BudgetExhausted { .. } => FailureKind::BudgetExhausted,
            SolveError::StateRejected { .. } => FailureKind::StateRejected,
            SolveError::InvalidOptions(_)
            | SolveError::Interrupted { .. }
            | SolveError::EventNan { .. }
            | SolveError::LawOutOfRange { .. }
            | SolveError::OutOfMemory(_) => return None,
        })
    }
}

/// A run known to break its promise: a finding, reported in every report and kept out of
/// the failures so that `lash extremes` stays a regression check for everything else.
///
/// ```text
/// (scene, method, rtol ≤ rtol_max) → the reason, from measurements
/// ```
///
/// Source: module doc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct KnownFinding {
    /// Scene stem.
    pub scene: &'static str,
    /// Method.
    pub method: Method,
    /// The finding covers runs at rtol ≤ this.
    pub rtol_max: f64,
    /// What was found.
    pub why: &'static str,
}

/// The known findings (BENCHMARKS.md "Extremes").
///
/// ```text
/// lubricated_viscosity_10: rodas5p and dop853 at rtol ≤ 1e-10
/// ```
/// The journal of lubricated_viscosity_10 passes close to the bearing centre, where the film
/// force turns with e/|e| and a perturbation of e is amplified by ~1/ε: the errors of every run
/// before the passage leave it orders of magnitude larger. bdf, trbdf2 and esdirk34 stay within
/// their promise there (their α < 1 allows it), rodas5p and dop853 (α = 1) do not: rodas5p
/// because its order reduction on this stiff driven problem (BENCHMARKS.md (d)) keeps it from
/// converging at its nominal rate, dop853 because it is stability-bound and the passage
/// amplifies the round-off of its many steps. The numbers: BENCHMARKS.md, "Extremes" → "What
/// the matrix found".
pub(crate) const KNOWN_FINDINGS: [KnownFinding; 2] = [
    KnownFinding {
        scene: "lubricated_viscosity_10",
        method: Method::Rodas5p,
        rtol_max: 1e-10,
        why: "passage near the bearing centre amplifies errors ~1/ε; Rodas5P's order reduction",
    },
    KnownFinding {
        scene: "lubricated_viscosity_10",
        method: Method::Dop853,
        rtol_max: 1e-10,
        why: "passage near the bearing centre amplifies the round-off of 7e5 stability-bound steps",
    },
];

/// The known finding that covers a run, if one does.
pub(crate) fn known_finding(scene: &str, setting: &Setting) -> Option<&'static KnownFinding> {
    let Setting::Adaptive { method, rtol } = *setting else {
        return None;
    };
    KNOWN_FINDINGS
        .iter()
        .find(|k| k.scene == scene && k.method == method && rtol <= k.rtol_max)
}

/// How one run ended.
///
/// ```text
/// allowed:  Agrees { e ≤ promise } | Failed { typed error, finite t in the run, finite y }
/// known:    Known { e > promise, covered by KNOWN_FINDINGS }
/// failure:  Disagrees { e > promise } | Rejected { anything else } | Panicked
/// ```
///
/// Source: module doc.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
pub enum Outcome {
    /// A result within its promise.
    Agrees {
        /// e(run; ref).
        error: f64,
        /// The promise.
        promise: f64,
    },
    /// A result that breaks its promise, covered by `KNOWN_FINDINGS` (a finding, not a
    /// failure).
    Known {
        /// e(run; ref).
        error: f64,
        /// The promise.
        promise: f64,
        /// The finding.
        why: String,
    },
    /// A result that breaks its promise (a failure).
    Disagrees {
        /// e(run; ref).
        error: f64,
        /// The promise.
        promise: f64,
    },
    /// A typed solver error with a finite time and state (allowed).
    Failed {
        /// Which error.
        kind: FailureKind,
        /// Time of the failure, s.
        t: f64,
        /// The error's message.
        message: String,
    },
    /// Any other ending: non-finite numbers returned, an untyped error, a typed error without
    /// a finite time or state, RK4 beyond its limit not failing with Rk4Unstable or
    /// NonFiniteState (a failure).
    Rejected {
        /// Why.
        reason: String,
    },
    /// The run panicked (a failure; caught).
    Panicked {
        /// The panic message.
        message: String,
    },
}

impl Outcome {
    /// Whether the outcome is allowed (agreement or a typed error).
    pub(crate) fn is_allowed(&self) -> bool {
        matches!(self, Outcome::Agrees { .. } | Outcome::Failed { .. })
    }

    /// Whether the outcome is a failure (neither allowed nor a known finding).
    pub(crate) fn is_failure(&self) -> bool {
        !self.is_allowed() && !matches!(self, Outcome::Known { .. })
    }

    /// One short cell for the markdown tables.
    pub(crate) fn cell(&self) -> String {
        match self {
            Outcome::Agrees { error, promise } => format!("ok {}", ratio(*error, *promise)),
            Outcome::Known { error, promise, .. } => {
                format!("*known* {}", ratio(*error, *promise))
            }
            Outcome::Disagrees { error, promise } => {
                format!("**WRONG** {}", ratio(*error, *promise))
            }
            Outcome::Failed { kind, t, .. } => format!("{} @{}", kind.short(), fmt_num(*t)),
            Outcome::Rejected { .. } => "**REJECTED**".into(),
            Outcome::Panicked { .. } => "**PANIC**".into(),
        }
    }
}

fn ratio(e: f64, p: f64) -> String {
    if p > 0.0 {
        format!("{:.0e}", e / p)
    } else {
        "–".into()
    }
}

/// One run of the matrix.
///
/// ```text
/// (scene, setting) → outcome, e/rtol^α (measured C), work
/// ```
///
/// Source: module doc.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Cell {
    /// Scene stem.
    pub scene: String,
    /// Setting.
    pub setting: Setting,
    /// How it ended.
    pub outcome: Outcome,
    /// The measured promise constant of a result: (e − F·E_ref)/rtol^α for an adaptive
    /// method, (e − F·E_ref)/e(h; h/2) for RK4 (None without a result).
    pub measured_c: Option<f64>,
    /// Wall time of the integration, s (0 when it failed).
    pub wall_time_s: f64,
    /// Accepted steps (0 when it failed).
    pub steps: usize,
}

/// The reference of one scene.
///
/// ```text
/// methods (A, B) at rtol;  E_ref = max(e(B; A), e(A at 10 rtol; A))
/// ```
///
/// Source: module doc.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SceneReport {
    /// Scene stem.
    pub stem: String,
    /// What it stresses.
    pub stresses: String,
    /// End time, s.
    pub t_end: f64,
    /// Error window.
    pub window: ErrorWindow,
    /// Reference method A (the reference).
    pub reference: Method,
    /// Check method B.
    pub check: Method,
    /// The rtol of both.
    pub reference_rtol: f64,
    /// Reference rungs that failed before, in words.
    pub reference_failures: Vec<String>,
    /// e(B; A): the disagreement of the two methods.
    pub agreement_methods: f64,
    /// e(A at 10·rtol; A): the disagreement of two tolerances.
    pub agreement_tolerance: f64,
    /// E_ref = the larger of the two.
    pub agreement: f64,
    /// Largest ε = |e|/c of the reference on the window grid.
    pub eps_max: Option<f64>,
    /// Wall time of the reference runs, s.
    pub reference_wall_time_s: f64,
    /// RK4 steps: inside and beyond, s.
    pub rk4_steps: (f64, f64),
}

/// Counts of one row (a method, RK4 inside, RK4 beyond) over the matrix.
///
/// ```text
/// runs = agreed + errored + known + failures;  errored by kind
/// ```
///
/// Source: module doc.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct RowCount {
    /// Row label (Setting::label).
    pub label: String,
    /// Runs.
    pub runs: usize,
    /// Results within the promise.
    pub agreed: usize,
    /// Allowed typed errors, by kind.
    pub errored: BTreeMap<String, usize>,
    /// Known findings ([`KNOWN_FINDINGS`]).
    pub known: usize,
    /// Failures (not allowed).
    pub failures: usize,
    /// Largest measured C of this row (known findings left out).
    pub measured_c_max: Option<f64>,
}

/// The whole matrix.
///
/// ```text
/// plan, constants, scene reports, cells, counts per row, failures, wall time
/// ```
///
/// Source: module doc.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Matrix {
    /// lash version.
    pub(crate) version: String,
    /// What ran.
    pub(crate) plan: Plan,
    /// C of the promise on scenes with a dry joint.
    pub(crate) promise_c_dry: f64,
    /// C of the promise on lubricated scenes.
    pub(crate) promise_c_lubricated: f64,
    /// C_rk4 of RK4's promise.
    pub(crate) promise_c_rk4: f64,
    /// F of the reference floor.
    pub(crate) promise_f: f64,
    /// The scenes and their references.
    pub(crate) scenes: Vec<SceneReport>,
    /// Every run.
    pub(crate) cells: Vec<Cell>,
    /// Counts per row.
    pub(crate) counts: Vec<RowCount>,
    /// Runs whose outcome is a failure (not allowed, not a known finding).
    pub(crate) failures: usize,
    /// Wall time of the whole matrix, s.
    pub(crate) wall_time_s: f64,
}
