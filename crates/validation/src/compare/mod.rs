//! Errors against a converged reference, and error against cost.

pub(crate) mod one_dof;
pub(crate) mod reference;
pub(crate) mod workprecision;
