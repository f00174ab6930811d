//! Diagnostics of one case: stiffness, Poincaré section and Lyapunov exponent.

pub mod poincare;
pub mod stiffness;
