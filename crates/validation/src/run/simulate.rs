//! Running one case: the core every command (run, compare, work-precision, sweep, the default
//! run, the studies) calls.
//!
//! ```text
//! Prepared::load(case)        scene file → checked Scene (SceneError → exit 2) | testset:NAME
//!                             | a catalogue scene (Case::catalogue)
//! Prepared::options(choice)   the defaults below, the request's SolverChoice laid over them
//! simulate_into(prepared, request, sink)
//!                             → RunResult { summary, window samples (2001-point metrics grid of
//!                               the last revolution), extra samples and states, events,
//!                               energy totals, ideal slider-crank }; the trajectory's rows go
//!                               to the sink as the run makes them (trajectory::TrajectorySink)
//! simulate(prepared, request) the same with the rows kept in memory (RunResult::trajectory)
//!
//! the integration loop (Integrator, one accepted step at a time):
//!   wall time     = time spent in Problem::new, Problem::integrator and Integrator::step only (no output, no
//!                   energy quadrature, no I/O)
//!   outputs       = dense output at every requested time (the trajectory grid, the metrics
//!                   grid, the extra times, merged in time order and computed one at a time);
//!                   mechanism samples are evaluated at once (so a contact law's stored impact
//!                   velocity is the one in force)
//!   extrema       every accepted step in the metrics window: metrics::Peaks on its dense
//!                   output (5 samples, golden-section search where a maximum appears)
//!   energy        ∫ P dt of Mechanism::power over every accepted step: Boole's rule on five
//!                   equally spaced nodes, error estimate |S₂ − S₁|/15 (S₁, S₂ Simpson on one
//!                   and two panels), panels no longer than T/400; a fixed-step method groups
//!                   four equal steps into one panel (nodes = step ends, one power evaluation
//!                   per step)
//!   balance       W_driver − ΔT − ΔV − D_damping − D_friction − D_film
//!   events        located hits; a run without event location (the paper's RK4) counts the
//!                   sign changes of the event functions between consecutive step ends
//!                   (crossing time by linear interpolation), so contact onsets are still counted
//!
//! memory: independent of the run's length — the mechanism and the solver's state (O(n²) for
//!   the implicit methods), the 2001 window samples, the extra samples asked for, the events
//!   of the window (all of them only with RunRequest::keep_events), and what the sink keeps
//!   (trajectory::CsvFile: one 64 KiB buffer)
//! ```
//!
//! The checks of a request before anything runs are `plan`'s, the defaults of a run
//! `prepare`'s, the integration loop `drive`'s; a mechanism run is `mechanism`'s (with
//! `sample` and `quadrature`), a built-in test problem's `testset`'s.
//!
//! A built-in test problem runs rodas5p at rtol 1e-6 with the problem's own atol (its
//! reference_error threshold) and records every accepted step as its trajectory.
//!
//! Metrics window: the last crank revolution [t_end − T, t_end] (docs/outputs.md, "`metrics`");
//! when the run is shorter than T (a `--t-end` override) or has no crank driver, the whole run.
//!
//! Source: docs/outputs.md (summary.json, trajectory.csv, the metrics window, the energy
//! balance), docs/model.md §5–§7, §9.

use crate::error::Error;
use crate::report::trajectory::{Columns, TrajectorySink};
use crate::run::mechanism::simulate_mechanism;
use crate::run::plan::RunRequest;
use crate::run::prepare::Model;
use crate::run::prepare::Prepared;
pub(crate) use crate::run::result::RunResult;
use crate::run::testset::simulate_testset;

/// Runs a case, keeping the trajectory's rows in memory ([`RunResult::trajectory`]). Solver
/// failures are `Error::Solver` (exit 3); nothing is written.
pub(crate) fn simulate(p: &Prepared, req: &RunRequest) -> Result<RunResult, Error> {
    let mut rows = Columns::new();
    let mut r = simulate_into(p, req, &mut rows)?;
    r.trajectory = rows;
    Ok(r)
}

/// Runs a case, pushing the trajectory's rows into `sink` as the run goes (module doc);
/// memory does not grow with the run's length unless the sink keeps the rows. On a solver
/// failure (`Error::Solver`, exit 3) the sink holds the rows up to it, and has been finished.
pub(crate) fn simulate_into(
    p: &Prepared,
    req: &RunRequest,
    sink: &mut dyn TrajectorySink,
) -> Result<RunResult, Error> {
    let (t0, t_end) = p.t_span(req.t_end)?;
    let result = match &p.model {
        Model::Mechanism(scene) => simulate_mechanism(p, scene, req, t0, t_end, sink),
        Model::TestSet(_) => simulate_testset(p, req, t0, t_end, sink),
    };
    let finished = sink.finish();
    let r = result?;
    finished?;
    Ok(r)
}
