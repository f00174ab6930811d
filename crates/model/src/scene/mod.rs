//! The scene: a planar mechanism described in JSON (typed with serde, unknown fields rejected),
//! and its validation. The reference page of every field is `docs/scene-format.md`.
//!
//! ```text
//! scene  = { bodies[], joints[], gravity, baumgarte, t_start, t_end | revolutions, roles }
//! body   = { name, mass, inertia (about the centre of mass), points{name: [x', y']},
//!            position, angle, velocity, angular_velocity }      (initial guesses)
//! joint  = revolute {a, b} | translational {body, point, origin, direction, angle}
//!        | driver {body, theta0, omega | rpm}                     θ(t) = θ₀ + ω t
//!        | clearance {bearing, journal, normal, friction, film, initial_eccentricity}
//! ```
//! Source: docs/model.md §1–§6 (after Peng et al. 2025, Lubricants 13(3) 124).
//!
//! Errors name the JSON path (`joints[3].bearing.radius`) and the reason; see [`SceneError`].

pub(crate) mod check;
pub(crate) mod de;
pub(crate) mod error;
pub(crate) mod format;
mod names;
mod parse;
pub(crate) mod refs;
mod resolution;
pub(crate) mod solver;
mod validate;

pub use crate::clearance::contact::{
    CoulombSpec, FrictionSpec, ImpactSpec, Material, Materials, NormalSpec, RestitutionSpec,
};
pub use crate::clearance::prismatic::{BlockSpec, GuideSpec, PrismaticClearanceSpec};
pub use crate::clearance::revolute::{ClearanceEnd, ClearanceSpec, FilmSpec};
pub use crate::elements::ForceElementSpec;
pub use check::{MAX_MAGNITUDE, MIN_MAGNITUDE};
pub use de::NoData;
pub use error::SceneError;
pub use format::{
    AugmentedLagrangianParams, Baumgarte, BodySpec, DriverSpec, FormulationName, InitialVelocity,
    JointSpec, RevoluteSpec, RoleNames, Scene, TranslationalSpec,
};
pub use refs::{Attachment, GROUND};
pub use solver::SolverSpec;
