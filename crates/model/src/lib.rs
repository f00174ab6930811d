//! # lash-model
//!
//! Planar multibody scenes with dry and lubricated revolute clearance joints (docs/model.md),
//! turned into an index-1 ODE `y' = f(t, y)` with y = (q, q̇) for the integrators of `lash-solver`.
//!
//! ```text
//! Scene (JSON, validated) → Mechanism::from_scene (prescribed bodies, constraints, assembly,
//!   the equations checked once at the initial state)
//!   → impl OdeSystem (rhs: KKT of docs/model.md §1; events δ, ε − ε_cap; FD Jacobian)
//!   → Mechanism::outputs / power / point_kinematics / ideal_slider_crank
//! ```
//! - [`scene`]: the JSON format and its validation ([`Scene`], [`SceneError`]).
//! - [`mechanism`]: the ODE ([`Mechanism`]).
//! - [`outputs`]: named outputs, energy terms, the closed-form ideal slider-crank.
//! - [`geometry`], [`laws`]: clearance kinematics and force laws.
//! - [`cases`]: generators of the paper's press scenes (`cases/press/`).
#![warn(missing_docs)]

mod assembly;
pub mod cases;
pub mod geometry;
mod initial_check;
pub mod jacobian;
pub mod laws;
pub mod mechanism;
pub mod outputs;
pub mod scene;

pub use mechanism::Mechanism;
pub use outputs::{ClearanceOutput, IdealSliderCrank, Outputs, PointKinematics, PowerTerms, Roles};
pub use scene::{Scene, SceneError, GROUND};
