//! Running one case: case references, the runner every command calls, runs until periodic,
//! and the files of one run.

pub(crate) mod case;
pub(crate) mod drive;
pub(crate) mod energy_check;
pub(crate) mod files;
pub(crate) mod mechanism;
pub(crate) mod plan;
pub(crate) mod prepare;
pub(crate) mod press;
pub(crate) mod quadrature;
pub(crate) mod result;
pub(crate) mod sample;
pub(crate) mod simulate;
pub(crate) mod state_tolerance;
pub(crate) mod steady;
pub(crate) mod testset;
pub(crate) mod turns;
pub(crate) mod window;

#[cfg(test)]
pub(crate) mod tests;
