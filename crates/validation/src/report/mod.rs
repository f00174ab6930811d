//! What runs report: summary.json, trajectory.csv, the metrics, the figures.

pub mod metrics;
pub mod plot;
pub mod summary;
pub mod trajectory;
