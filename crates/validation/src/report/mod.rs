//! What runs report: summary.json, trajectory.csv, the metrics, the figures; `lash plot`'s
//! figures of any trajectory columns (`column_plot`).

pub(crate) mod column_plot;
pub(crate) mod metrics;
pub(crate) mod number;
pub(crate) mod plot;
pub(crate) mod summary;
pub(crate) mod trajectory;
