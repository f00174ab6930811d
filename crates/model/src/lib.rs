//! # lash-model
//!
//! Planar multibody scenes with dry and lubricated clearance joints (docs/model.md), turned
//! into an index-1 ODE `y' = f(t, y)` for the integrators of `lash-solver`.
//!
//! ```text
//! Scene (JSON, validated) → Mechanism::from_scene (prescribed bodies, constraints, forces,
//!   formulation, assembly, the equations checked once at the initial state)
//!   → impl OdeSystem (rhs, Jacobian, events of docs/model.md §1, §7)
//!   → Mechanism::outputs / power / point_kinematics / ideal_slider_crank
//! ```
//! - [`scene`]: the JSON format, its deserialisation and its validation ([`Scene`],
//!   [`SceneError`]).
//! - [`clearance`]: both clearance joints side by side (revolute, prismatic), their contact
//!   laws, the revolute joint's kinematics ([`geometry`]) and force laws ([`laws`]).
//! - [`elements`]: force elements, one file per kind behind one interface.
//! - [`mechanism`]: the ODE ([`Mechanism`]): bodies, constraint equations, forces, the
//!   formulation (the state layout and the acceleration solve), events.
//! - [`law_range`]: the ranges the clearance joints' laws hold in, checked along a run.
//! - [`outputs`]: named outputs, energy terms, the closed-form ideal slider-crank.
//! - [`cases`]: generators of the paper's press scenes (`cases/press/`).
//! - [`iftomm`]: generators of the benchmark scenes of `cases/iftomm/` (IFToMM A01, A02,
//!   parallel cranks) and their one-degree-of-freedom references.
//!
//! # Layers
//!
//! Each module uses only the modules listed before it (line by line, and left to right within
//! a line): no import circle, unit tests included.
//!
//! ```text
//! 0  planar, linalg, labels, projection; clearance::{geometry, laws}
//! 1  scene::{error, check, de}; elements::input
//! 2  scene::refs (the SceneRefs seam: joints and elements check and compile against it)
//! 3  elements::{table, interface}; clearance::contact; mechanism::row
//! 4  elements::<one file per kind>; clearance::{revolute, prismatic, revolute_jacobian}
//! 5  elements (the registry)
//! 6  scene::{format, resolution, validate, parse}; scene (the public facade)
//! 7  roles; mechanism::{scratch, bodies, constraints, formulation, forces, events}
//! 8  mechanism (the struct, its views and its evaluation)
//! 9  outputs, jacobian, assembly, initial_check, law_range; mechanism::{ode, build}; cases,
//!    iftomm
//! ```
//! Inside the crate, parts name the scene's submodules (`scene::format`, `scene::refs`, …),
//! never the facade `scene`, which re-exports them for users.
//!
//! # A scene, built and solved
//!
//! A uniform rod of length 0.5 m pinned to the ground at one end, released from the
//! horizontal. Energy is conserved (no clearance joint, no damping), and at the bottom of the
//! swing the rod turns at ω² = 2 m g (l/2) / I_O = 3 g / l.
//!
//! ```
//! use lash_model::{Mechanism, Scene};
//! use lash_solver::{solve, Atol, Method, SolverOptions};
//!
//! let scene = Scene::from_json_str(r#"{
//!   "bodies": [{"name": "rod", "mass": 1.0, "inertia": 0.0208333333333333,
//!               "position": [0.25, 0.0], "points": {"O": [-0.25, 0.0]}}],
//!   "joints": [{"type": "revolute", "name": "pivot", "a": {"body": "rod", "point": "O"},
//!               "b": {"body": "ground", "at": [0.0, 0.0]}}],
//!   "gravity": [0.0, -9.81],
//!   "t_end": 2.0
//! }"#).unwrap();
//! let m = Mechanism::from_scene(&scene).unwrap();
//! let y0 = m.initial_state();
//! let opts = SolverOptions { method: Method::Dop853, rtol: 1e-10, atol: Atol::Scalar(1e-12),
//!                            ..Default::default() };
//! let sol = solve(&m, (m.t_start(), m.t_end()), &y0, &opts).unwrap();
//!
//! let energy = |k: usize| {
//!     let o = m.outputs(sol.t[k], sol.state(k));
//!     o.kinetic_energy + o.potential_energy
//! };
//! // Kinetic + potential energy at every step equals its initial value (0 J here).
//! for k in 0..sol.len() {
//!     assert!((energy(k) - energy(0)).abs() < 1e-6);
//! }
//! // The fastest the rod turns is at the bottom: ω² = 3 g / l.
//! let omega_max = (0..sol.len())
//!     .map(|k| m.outputs(sol.t[k], sol.state(k)).bodies[0].omega.abs())
//!     .fold(0.0, f64::max);
//! let omega_bottom = (3.0 * 9.81 / 0.5f64).sqrt();
//! assert!((omega_max - omega_bottom).abs() < 2e-3 * omega_bottom);
//! ```
#![warn(missing_docs)]

mod assembly;
pub mod cases;
pub mod clearance;
pub mod elements;
pub mod iftomm;
mod initial_check;
mod jacobian;
mod kkt;
mod labels;
pub mod law_range;
mod linalg;
pub mod mechanism;
pub mod outputs;
mod planar;
mod projection;
mod roles;
pub mod scene;

pub use clearance::{geometry, laws};
pub use labels::{Column, EventLabels};
pub use law_range::{LawRangeMonitor, LawRangeRecord, LawRangeViolation};
pub use mechanism::events::event_label;
pub use mechanism::formulation::augmented_lagrangian::FormulationStats;
pub use mechanism::Mechanism;
pub use outputs::{
    BodyOutput, ClearanceOutput, ElementOutput, IdealSliderCrank, Outputs, PointKinematics,
    PowerTerms, PrismaticOutput,
};
pub use projection::{CoordinateChange, ProjectionReport};
pub use roles::{MetricsWindow, Roles};
pub use scene::{AugmentedLagrangianParams, FormulationName, Scene, SceneError, GROUND};
