//! Diagnostics of one case: stiffness, Poincaré section and Lyapunov exponent.

pub(crate) mod poincare;
pub(crate) mod stiffness;

#[cfg(test)]
mod tests;
