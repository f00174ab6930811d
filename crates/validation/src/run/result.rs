//! What one run produced (RunResult), and writing it into a run directory.
//!
//! Source: docs/outputs.md ("`summary.json`", "`trajectory.csv`").

use std::path::{Path, PathBuf};

use lash_model::IdealSliderCrank;
use lash_solver::Solution;

use crate::error::Error;
use crate::report::metrics::{EventRecord, Sample};
use crate::report::summary::Summary;
use crate::report::trajectory::Columns;
use crate::run::files::{self as report, RunOutput};

/// Everything one run produced.
///
/// ```text
/// summary (metrics filled in), samples on the metrics grid (window) and at the extra times,
/// the trajectory (when collected in memory), events, energy totals, the ideal mechanism
/// ```
///
/// Source: docs/outputs.md ("`summary.json`", "`trajectory.csv`").
#[derive(Clone, Debug)]
pub struct RunResult {
    /// summary.json content (metrics for mechanisms; final_state and reference_error for test
    /// problems).
    pub summary: Summary,
    /// Samples on the 2001-point metrics grid (empty for test problems).
    pub(crate) window: Vec<Sample>,
    /// The trajectory's rows (`simulate`); empty when they went to a sink
    /// (`simulate_into`).
    pub trajectory: Columns,
    /// Rows of the trajectory, wherever they went.
    pub trajectory_rows: usize,
    /// Samples at the extra times.
    pub(crate) extra: Vec<Sample>,
    /// States at the extra times.
    pub(crate) extra_states: Solution,
    /// Events: located ones, or crossings at the step ends of a run without location (all of
    /// them, or those of the metrics window: `RunRequest::keep_events`).
    pub events: Vec<EventRecord>,
    /// Each event function's kind and element, by [`EventRecord::index`]
    /// (`MechanismInfo::event_names`; empty for a test problem).
    pub event_names: Vec<(&'static str, String)>,
    /// The closed-form ideal slider-crank of the scene, if it is one.
    pub(crate) ideal: Option<IdealSliderCrank>,
}

impl RunResult {
    /// Writes the figures, trajectory.csv (from the collected rows; none when they went to a
    /// sink) and summary.json into `dir` (report::write_run: summary last).
    pub(crate) fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, Error> {
        let traj = (self.trajectory.header().is_some()).then_some(&self.trajectory);
        report::write_run(
            dir,
            &RunOutput {
                summary: &self.summary,
                trajectory: traj,
                window: &self.window,
                ideal: self.ideal.as_ref(),
            },
        )
    }
}
