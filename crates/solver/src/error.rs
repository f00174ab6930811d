//! Typed solver failures. Every failure carries the time and, where one exists, the state.

use crate::options::OptionError;

/// Why an integration failed. Never a panic, never a silent NaN.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// The step size needed to meet the tolerance fell below `h_min` (or below the floating
    /// point resolution of t).
    #[error("step size too small at t = {t:e}: h = {h:e}")]
    StepSizeTooSmall {
        /// Time of the last accepted state.
        t: f64,
        /// The step size that was rejected.
        h: f64,
        /// Last accepted state.
        y: Vec<f64>,
    },
    /// `max_steps` steps were taken before reaching the end time.
    #[error("too many steps: {steps} steps taken, reached t = {t:e}")]
    TooManySteps {
        /// Time reached.
        t: f64,
        /// Number of steps taken.
        steps: usize,
        /// Last accepted state.
        y: Vec<f64>,
    },
    /// The right-hand side or the state became non-finite (NaN or ±∞), or the state grew past
    /// the divergence bound.
    #[error("non-finite or diverging state at t = {t:e}")]
    NonFiniteState {
        /// Time of the last finite state.
        t: f64,
        /// Last finite state.
        y: Vec<f64>,
    },
    /// Fixed-step RK4 (with `rk4_instability_steps` > 0) took that many steps in a row outside
    /// its stability region: h·ρ > 2.785 with ρ estimated from the stages, confirmed by an
    /// eigenvalue λ of ∂f/∂y with |R(hλ)| > 1 (`rk4` module doc).
    /// The state is finite; its numbers are not a solution any more.
    #[error(
        "RK4 beyond its stability limit at t = {t:e}: step {h:e} s, estimated limit {h_limit:.3e} s \
         (h·λ outside the stability region on {steps} steps in a row)"
    )]
    Rk4Unstable {
        /// Time of the last accepted state.
        t: f64,
        /// Last accepted state.
        y: Vec<f64>,
        /// The step, s.
        h: f64,
        /// The largest stable step at the last flagged step, from the eigenvalues of ∂f/∂y
        /// there (`rk4` module doc), s.
        h_limit: f64,
        /// Flagged steps in a row (`rk4_instability_steps`).
        steps: usize,
    },
    /// The Newton iteration of an implicit method failed to converge even at the smallest step.
    #[error("Newton iteration failed at t = {t:e}: {reason}")]
    NewtonFailure {
        /// Time of the last accepted state.
        t: f64,
        /// Last accepted state.
        y: Vec<f64>,
        /// What failed (singular matrix, divergence, backend message).
        reason: String,
    },
    /// The options are inconsistent or out of range: which field, what is wrong, the value
    /// and what is allowed ([`OptionError`]; the rules: [`crate::options`]).
    #[error("invalid options: {0}")]
    InvalidOptions(#[from] OptionError),
    /// A budget (wall clock) ran out before the end time.
    #[error("budget exhausted at t = {t:e}: {reason}")]
    BudgetExhausted {
        /// Time reached.
        t: f64,
        /// Last accepted state.
        y: Vec<f64>,
        /// Which budget.
        reason: String,
    },
    /// A stop was requested ([`crate::interrupt::request_stop`], e.g. by SIGINT) and the
    /// integration ended at a step boundary.
    #[error("interrupted at t = {t:e}")]
    Interrupted {
        /// Time of the last accepted state.
        t: f64,
        /// Last accepted state.
        y: Vec<f64>,
    },
    /// An event function returned NaN, which has no sign: its crossings cannot be told, so
    /// the integration stops rather than miss them silently.
    #[error("event function {index} returned NaN at t = {at:e}")]
    EventNan {
        /// Time of the last accepted state (the start of the step in which it happened).
        t: f64,
        /// Last accepted state.
        y: Vec<f64>,
        /// Which event function ([`crate::OdeSystem::events`]'s index).
        index: usize,
        /// Where it returned NaN.
        at: f64,
    },
    /// The system refused an accepted state ([`crate::OdeSystem::check_accepted`]): the
    /// numbers are finite but no longer a solution of the system's model (for a mechanism: a
    /// singular configuration its formulation cannot pass, or a constraint violation above
    /// its tolerance). `t` and `y` are the refused state's.
    #[error("{reason}")]
    StateRejected {
        /// Time of the refused state (the end of the step that reached it).
        t: f64,
        /// The refused state.
        y: Vec<f64>,
        /// What happened, as a snake_case name (the system's [`crate::Rejection::kind`]).
        kind: &'static str,
        /// The system's message, naming the time and what happened.
        reason: String,
    },
    /// The dense matrices the method needs (its Jacobian and LU, n² each) do not fit the
    /// memory budget ([`crate::memory`]), or the allocator refused them; nothing was
    /// integrated.
    #[error("{0}")]
    OutOfMemory(crate::memory::MemoryError),
    /// The state left the range in which the model's laws hold (for a mechanism: a journal
    /// as deep in its bearing as its own radius, a block's corner half its width into a guide
    /// face; docs/model.md §3.5). The state is finite; the model's
    /// numbers are not a solution of the problem it describes any more.
    #[error("model outside the range of its laws at t = {t:e}: {reason}")]
    LawOutOfRange {
        /// Time of the accepted state that left the range.
        t: f64,
        /// That state.
        y: Vec<f64>,
        /// Which law, which part of the model, the value and the limit.
        reason: String,
    },
}

impl SolveError {
    /// Time at which the failure happened (None for invalid options and refused memory).
    pub fn time(&self) -> Option<f64> {
        match self {
            SolveError::StepSizeTooSmall { t, .. }
            | SolveError::TooManySteps { t, .. }
            | SolveError::NonFiniteState { t, .. }
            | SolveError::Rk4Unstable { t, .. }
            | SolveError::NewtonFailure { t, .. }
            | SolveError::BudgetExhausted { t, .. }
            | SolveError::Interrupted { t, .. }
            | SolveError::EventNan { t, .. }
            | SolveError::LawOutOfRange { t, .. }
            | SolveError::StateRejected { t, .. } => Some(*t),
            SolveError::InvalidOptions(_) | SolveError::OutOfMemory(_) => None,
        }
    }

    /// State at the failure (None for invalid options and refused memory).
    pub fn state(&self) -> Option<&[f64]> {
        match self {
            SolveError::StepSizeTooSmall { y, .. }
            | SolveError::TooManySteps { y, .. }
            | SolveError::NonFiniteState { y, .. }
            | SolveError::Rk4Unstable { y, .. }
            | SolveError::NewtonFailure { y, .. }
            | SolveError::BudgetExhausted { y, .. }
            | SolveError::Interrupted { y, .. }
            | SolveError::EventNan { y, .. }
            | SolveError::LawOutOfRange { y, .. }
            | SolveError::StateRejected { y, .. } => Some(y),
            SolveError::InvalidOptions(_) | SolveError::OutOfMemory(_) => None,
        }
    }
}
