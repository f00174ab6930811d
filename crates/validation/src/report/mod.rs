//! What runs report: summary.json, trajectory.csv, the metrics, the figures.

pub(crate) mod metrics;
pub(crate) mod plot;
pub(crate) mod summary;
pub(crate) mod trajectory;
