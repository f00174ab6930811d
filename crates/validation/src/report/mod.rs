//! What runs report: summary.json, trajectory.csv, the metrics, the figures; `lash plot`'s
//! figures of any trajectory columns (`column_plot`).

pub mod column_plot;
pub mod metrics;
pub mod plot;
pub mod summary;
pub mod trajectory;
