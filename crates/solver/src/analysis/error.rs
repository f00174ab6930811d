//! Why an analysis failed ([`AnalysisError`]).

use crate::error::SolveError;

/// Why an analysis failed. Never a panic, never a silent NaN.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AnalysisError {
    /// An argument is out of range or inconsistent (dimension, step, interval, tolerance).
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// The Jacobian (analytic or by finite differences) or the right-hand side was not finite.
    #[error("non-finite {what} at t = {t:e}")]
    NonFinite {
        /// Time of the evaluation.
        t: f64,
        /// What was not finite.
        what: String,
    },
    /// The eigenvalue iteration (faer's Hessenberg QR) did not converge.
    #[error("eigenvalue computation did not converge at t = {t:e}")]
    EigenNoConvergence {
        /// Time of the Jacobian.
        t: f64,
    },
    /// An integration failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The step-size bracket of [`crate::analysis::measure_rk4_limit`] does not bracket the limit.
    #[error("no bracket: step {h:e} is {} (the lower end must be stable, the upper unstable)", if *stable { "stable" } else { "unstable" })]
    NoBracket {
        /// The offending end of the bracket.
        h: f64,
        /// Whether that step was found stable.
        stable: bool,
    },
    /// The analysis cannot go on (the perturbation vanished, a stopping event ended a
    /// trajectory early).
    #[error("degenerate at t = {t:e}: {reason}")]
    Degenerate {
        /// Time at which it happened.
        t: f64,
        /// What happened.
        reason: String,
    },
}
