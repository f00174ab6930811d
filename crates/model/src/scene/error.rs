//! Why a scene is rejected.

/// Why a scene is rejected. Every message names where (a JSON path such as
/// `joints[3].bearing.radius`, or a body/point name) and why.
///
/// ```text
/// Syntax      JSON syntax error at line L, column C: …
/// Schema      <path>: unknown field / wrong type / missing field (serde, path tracked)
/// Invalid     <path>: <reason>                    (a value out of range, a missing name, …)
/// Redundant   <path>: redundant or contradictory constraints: …
/// Assembly    <path>: initial assembly did not converge: equation …, residual …
/// Dynamics    <path>: the equations of motion fail at the initial state: … (not finite, or
///             Φ_q M⁻¹ Φ_qᵀ singular in f64)
/// Unknown     unknown body 'x' / unknown point 'p' on body 'x'   (output look-ups)
/// Budget      the call's wall-clock budget ran out during set-up     (not the scene's fault:
/// Interrupted a stop was requested during set-up                      front ends report them
///                                                                     as the solver's)
/// ```
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// The text is not valid JSON.
    #[error("JSON syntax error at line {line}, column {column}: {message}")]
    Syntax {
        /// Line (1-based).
        line: usize,
        /// Column (1-based).
        column: usize,
        /// serde_json's message.
        message: String,
    },
    /// Valid JSON that does not fit the schema: unknown field, wrong type, missing field.
    #[error("{path}: {message}")]
    Schema {
        /// JSON path of the offending value.
        path: String,
        /// serde's message (with line and column).
        message: String,
    },
    /// A value out of range, a name that refers to nothing, a missing choice.
    #[error("{path}: {reason}")]
    Invalid {
        /// JSON path of the offending value.
        path: String,
        /// Why it is rejected.
        reason: String,
    },
    /// The constraint Jacobian is rank deficient at the initial state.
    #[error("{path}: redundant or contradictory constraints: {reason}")]
    Redundant {
        /// JSON path of the joint whose equation depends on earlier ones.
        path: String,
        /// Which equation, and the rank found.
        reason: String,
    },
    /// Newton's method on the position (or velocity) constraints did not converge.
    #[error("{path}: initial assembly did not converge: {reason}")]
    Assembly {
        /// JSON path of the joint with the largest residual.
        path: String,
        /// Which equation and by how much.
        reason: String,
    },
    /// The equations of motion are not finite, or their KKT system is singular in f64, at the
    /// assembled initial state (numbers each finite, but beyond what f64 can combine).
    #[error("{path}: the equations of motion fail at the initial state: {reason}")]
    Dynamics {
        /// JSON path of the body or joint to blame.
        path: String,
        /// Which quantity, its value, and the numbers of the scene behind it.
        reason: String,
    },
    /// An output asked for a body or point the scene does not have.
    #[error("unknown {0}")]
    Unknown(String),
    /// The wall-clock budget of the call ran out during set-up
    /// (`lash_solver::interrupt::deadline_scope`): not a fault of the scene, a budget that a
    /// front end reports as the solver's `BudgetExhausted` (exit 3).
    #[error("wall-clock budget of {budget} s used during set-up ({phase}, t = {t} s)")]
    Budget {
        /// What set-up was doing: "building the constraints", "assembly", ….
        phase: &'static str,
        /// The scene's start time.
        t: f64,
        /// The budget, s.
        budget: f64,
    },
    /// A stop was requested during set-up (`lash_solver::interrupt::request_stop`): a front end
    /// reports it as the solver's `Interrupted`.
    #[error("stop requested during set-up ({phase}, t = {t} s)")]
    Interrupted {
        /// What set-up was doing.
        phase: &'static str,
        /// The scene's start time.
        t: f64,
    },
    /// The scene file could not be read.
    #[error("cannot read {path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// The OS error.
        message: String,
    },
}

pub(crate) fn invalid(path: impl Into<String>, reason: impl Into<String>) -> SceneError {
    SceneError::Invalid {
        path: path.into(),
        reason: reason.into(),
    }
}

/// A point where set-up may stop: after `phase`, the call's deadline passed
/// ([`lash_solver::interrupt::deadline_passed`]) → [`SceneError::Budget`], a stop requested →
/// [`SceneError::Interrupted`]. Between the phases of `Mechanism::from_scene` and inside its
/// long loops (assembly's iterations, the initial Jacobian's check), so that a budget is
/// overrun by at most one phase's step, not the whole set-up.
pub(crate) fn checkpoint(phase: &'static str, t: f64) -> Result<(), SceneError> {
    if lash_solver::interrupt::stop_requested() {
        return Err(SceneError::Interrupted { phase, t });
    }
    if let Some(budget) = lash_solver::interrupt::deadline_passed() {
        return Err(SceneError::Budget { phase, t, budget });
    }
    Ok(())
}
