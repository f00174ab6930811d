//! Studies: the default run, the paper's §4, its robustness, the extremes matrix.

pub(crate) mod extremes;
pub(crate) mod headline;
pub(crate) mod paper;
pub(crate) mod robustness;

#[cfg(test)]
mod robustness_tests;
