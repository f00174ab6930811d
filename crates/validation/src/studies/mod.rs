//! Studies: the default run, the paper's §4, its robustness, the extremes matrix.

pub mod extremes;
pub mod headline;
pub mod paper;
pub mod robustness;
