//! Errors against a converged reference, and error against cost.

pub mod reference;
pub mod workprecision;
