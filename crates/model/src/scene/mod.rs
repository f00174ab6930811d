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
mod check;
pub(crate) mod de;
mod error;
mod format;
mod parse;
mod refs;
mod validate;

pub use crate::clearance::contact::{
    CoulombSpec, FrictionSpec, ImpactSpec, Material, Materials, NormalSpec, RestitutionSpec,
};
pub use crate::clearance::revolute::{ClearanceEnd, ClearanceSpec, FilmSpec};
pub use check::{MAX_MAGNITUDE, MIN_MAGNITUDE};
pub use de::NoData;
pub use error::SceneError;
pub use format::{
    Baumgarte, BodySpec, DriverSpec, InitialVelocity, JointSpec, RevoluteSpec, RoleNames, Scene,
    TranslationalSpec,
};
pub use refs::{Attachment, GROUND};

pub(crate) use check::{check_name, Checker};
pub(crate) use de::{object, tagged_object, variant, PATH_MARK};
pub(crate) use error::invalid;
pub(crate) use validate::check_contact_laws;
