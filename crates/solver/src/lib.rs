//! # lash-solver
//!
//! ODE integrators for stiff contact problems, knowing nothing about mechanisms.
//!
//! ```text
//! y' = f(t, y),  y(t0) = y0,  events g_i(t, y) = 0
//! ```
//!
//! - [`OdeSystem`]: the problem (right-hand side, optional Jacobian, event functions and the
//!   hook an event runs).
//! - [`SolverOptions`]: method, tolerances, step limits, controller, output, events.
//! - [`solve`] integrates a span; [`Integrator`] steps one step at a time and says where the
//!   state is after each ([`StepOutcome`]).
//! - [`Stats`] counts the work; [`SolveError`] says why a run failed, with time and state.
//!
//! Methods: the paper's fixed-step RK4 ([`rk4`]); the explicit embedded pairs Bogacki–Shampine
//! 3(2), Dormand–Prince 5(4), Tsitouras 5(4) and DOP853 ([`erk`]).
//!
//! Stiff methods: our Rosenbrock method Rodas5P ([`rosenbrock`]) and diffsol's BDF, TR-BDF2 and
//! ESDIRK3(4) ([`diffsol_backend`]), with dense Jacobians from the system or by finite
//! differences ([`jacobian`]); stiff problems of the IVP Test Set with reference solutions
//! ([`testset`]).
//!
//! Analysis ([`analysis`]): stiffness diagnostics (Jacobian eigenvalues, RK4 stability limits
//! predicted and measured) and the largest Lyapunov exponent (Benettin's method).

#![warn(missing_docs)]

pub mod analysis;
pub mod controller;
pub mod diffsol_backend;
pub mod erk;
pub mod error;
pub mod integrator;
pub mod jacobian;
pub mod options;
pub mod rk4;
pub mod rosenbrock;
pub mod stats;
pub mod stepper;
pub mod system;
pub mod testset;

pub use controller::{Controller, ControllerKind, Soderlind, StepLimits, StepSizeControl};
pub use error::SolveError;
pub use integrator::{solve, Integrator, Solution, StepOutcome};
pub use options::{Atol, Method, Output, SolverOptions};
pub use stats::Stats;
pub use stepper::{make_stepper, Stepper};
pub use system::{Direction, EventAction, EventHit, EventSpec, OdeSystem};
