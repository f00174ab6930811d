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
//! - [`Method`]: the methods, with one table of their facts ([`Method::info`]: family, orders,
//!   stages, default controller, dense-output degree).
//! - [`SolverOptions`]: method, tolerances, step limits, controller, output, events; its
//!   rules are written once ([`options`]) and [`SolverOptions::configure`] turns it into the
//!   validated configuration of the method's family ([`Config`]), or a typed
//!   [`OptionError`] naming the field.
//! - [`solve`] integrates a span; a [`Problem`] (system + validated options) builds an
//!   [`Integrator`], which steps one step at a time and says where the state is after each
//!   ([`StepOutcome`]).
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
//!
//! One step driver ([`onestep`]) runs every one-step method (the explicit pairs, Rodas5P):
//! step-size control, rejections, landing on the stop time, budgets and counters are written
//! once. After every located event the integrator restarts the method with a freshly chosen
//! first step and samples the event functions inside every step, so a bounce is not missed
//! (see [`integrator`]).
//!
//! # Van der Pol with a stiff method
//!
//! ```
//! use lash_solver::{solve, Method, OdeSystem, Output, SolverOptions, Atol};
//!
//! /// y1' = y2,  y2' = μ (1 − y1²) y2 − y1  with μ = 1000: relaxation oscillations whose
//! /// fast jumps make the problem stiff (HNW II §IV.1).
//! struct VanDerPol;
//! impl OdeSystem for VanDerPol {
//!     fn dim(&self) -> usize { 2 }
//!     fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
//!         dy[0] = y[1];
//!         dy[1] = 1000.0 * (1.0 - y[0] * y[0]) * y[1] - y[0];
//!     }
//! }
//!
//! let opts = SolverOptions {
//!     method: Method::Rodas5p,
//!     rtol: 1e-8,
//!     atol: Atol::Scalar(1e-11),
//!     output: Output::Final,
//!     ..Default::default()
//! };
//! let sol = solve(&VanDerPol, (0.0, 2000.0), &[2.0, 0.0], &opts).unwrap();
//! // Reference y1(2000) of the IVP Test Set (Mazzia & Magherini, problem VDPOLM).
//! let reference = 1.706167732170469;
//! assert!((sol.y_final[0] - reference).abs() < 1e-6 * reference);
//! // An explicit method would need steps below ~2.8/|λ| ≈ 1e-3 over much of the span.
//! assert!(sol.stats.accepted < 5_000, "{:?}", sol.stats);
//! ```
//!
//! # A bouncing ball with an event
//!
//! ```
//! use lash_solver::*;
//!
//! /// Height and velocity under gravity; the event h = 0 (falling) reverses the velocity
//! /// with restitution 0.8.
//! struct Ball;
//! impl OdeSystem for Ball {
//!     fn dim(&self) -> usize { 2 }
//!     fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
//!         dy[0] = y[1];
//!         dy[1] = -9.81;
//!     }
//!     fn n_events(&self) -> usize { 1 }
//!     fn event_spec(&self, _i: usize) -> EventSpec {
//!         EventSpec { direction: Direction::Falling, action: EventAction::Continue }
//!     }
//!     fn events(&self, _t: f64, y: &[f64], g: &mut [f64]) { g[0] = y[0]; }
//!     fn on_event(&self, _hit: &EventHit, y: &mut [f64]) -> EventAction {
//!         y[1] *= -0.8;
//!         EventAction::Continue
//!     }
//! }
//!
//! let sol = solve(&Ball, (0.0, 2.5), &[1.0, 0.0], &SolverOptions::with_method(Method::Dopri54))
//!     .unwrap();
//! // Closed form from 1 m at rest: t1 = √(2/g), each flight lasts 2 e v_k / g.
//! let t1 = (2.0 / 9.81f64).sqrt();
//! let mut expected = vec![t1];
//! let mut v = 9.81 * t1;
//! while expected.len() < sol.events.len() {
//!     v *= 0.8;
//!     expected.push(expected.last().unwrap() + 2.0 * v / 9.81);
//! }
//! assert_eq!(sol.events.len(), 4);
//! for (hit, t) in sol.events.iter().zip(&expected) {
//!     assert!((hit.t - t).abs() < 1e-9 * t);
//! }
//! ```

#![warn(missing_docs)]

pub mod analysis;
mod auto_lu;
pub mod controller;
pub mod diffsol_backend;
pub mod erk;
pub mod error;
pub mod integrator;
pub mod interrupt;
pub mod jacobian;
pub mod kkt;
pub mod linear_algebra;
pub mod memory;
pub mod method;
pub mod onestep;
pub mod options;
pub mod rk4;
pub mod rosenbrock;
mod sparse_lu;
pub mod stats;
pub mod stepper;
pub mod system;
pub mod testset;

pub use controller::{Controller, ControllerKind, Soderlind, StepLimits, StepSizeControl};
pub use error::SolveError;
pub use integrator::{make_stepper, solve, Integrator, Problem, Solution, StepOutcome};
pub use linear_algebra::LinearAlgebra;
pub use method::{Method, MethodInfo};
pub use options::{Atol, Config, OptionError, OptionField, Output, Rule, SolverOptions};
pub use stats::Stats;
pub use stepper::{StepQuadrature, Stepper};
pub use system::{
    Direction, EventAction, EventHit, EventSpec, OdeSystem, QuadratureFn, Rejection, WithQuadrature,
};
