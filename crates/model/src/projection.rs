//! What the initial assembly changed in a scene's initial guesses (docs/model.md §1,
//! "Initial conditions"): every coordinate it moved, and the kinetic energy before and after.

use std::fmt;

use serde::Serialize;

/// Changes below this (SI units, or relative to the given value) are not reported.
pub(crate) const REPORT_TOL: f64 = 1e-9;

/// One coordinate of an integrated body that the assembly moved.
///
/// ```text
/// change = assembled − given   (coordinate: x, y, theta, vx, vy, omega; SI units)
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CoordinateChange {
    /// Body name.
    pub body: String,
    /// `x`, `y`, `theta` (positions) or `vx`, `vy`, `omega` (velocities).
    pub coordinate: &'static str,
    /// The scene's value (its guess, or its exact `initial_velocity`).
    pub given: f64,
    /// The value of the assembled initial state.
    pub assembled: f64,
    /// assembled − given.
    pub change: f64,
}

/// What the assembly changed in the scene's initial guesses (docs/model.md §1, "Initial
/// conditions").
///
/// ```text
/// positions: Newton's minimum-norm steps onto Φ = 0
/// velocities: the mass-weighted projection min ½ (q̇ − q̇₀)ᵀ M (q̇ − q̇₀) s.t. Φ̇ = targets
/// changes: every coordinate with |assembled − given| > 1e-9 · max(1, |given|)
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ProjectionReport {
    /// The changed coordinates, in body order, positions before velocities.
    pub changes: Vec<CoordinateChange>,
    /// Largest |change| of a position coordinate (m or rad).
    pub max_position_change: f64,
    /// Largest |change| of a velocity coordinate (m/s or rad/s).
    pub max_velocity_change: f64,
    /// Kinetic energy of the given velocities (J, integrated bodies).
    pub kinetic_energy_given: f64,
    /// Kinetic energy of the assembled velocities (J, integrated bodies).
    pub kinetic_energy_assembled: f64,
    /// The kinetic energy the scene's exact initial velocities carry: the least kinetic
    /// energy of any motion that has them, the constraints aside (J; 0 without exact
    /// velocities). docs/model.md §1.6.
    pub kinetic_energy_exact: f64,
    /// Condition number σ_max/σ_min of the velocity projection's matrix J M^{-1/2} (the
    /// constraints' and the exact velocities' rows; ∞ when it lost rank, 0 for a scene
    /// without equations to assemble).
    pub condition: f64,
}

impl ProjectionReport {
    /// Whether the assembly changed nothing beyond the reporting tolerance.
    pub fn is_empty(&self) -> bool {
        self.changes.is_empty()
    }
}

impl fmt::Display for ProjectionReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.changes.is_empty() {
            return write!(f, "initial conditions: the scene's values are consistent");
        }
        write!(
            f,
            "initial conditions moved onto the constraints (velocities by the mass-weighted \
             projection, condition number {:.3e}; kinetic energy {:.6e} J → {:.6e} J):",
            self.condition, self.kinetic_energy_given, self.kinetic_energy_assembled
        )?;
        for c in &self.changes {
            write!(
                f,
                "\n  {}.{}: {:.9e} → {:.9e} (change {:+.3e})",
                c.body, c.coordinate, c.given, c.assembled, c.change
            )?;
        }
        Ok(())
    }
}
