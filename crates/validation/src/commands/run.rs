//! `lash` (the default run) and `lash run`: one case into its directory, or into memory for a
//! library caller.
//!
//! Source: docs/outputs.md ("`lash run CASE`", "Files each command writes").

use std::path::{Path, PathBuf};
use std::time::Instant;

use lash_solver::stepper::deadline_after;
use lash_solver::{SolveError, SolverOptions};

use crate::commands::default_out;
use crate::error::Error;
use crate::error::OptionError;
use crate::options::SolverChoice;
use crate::progress::Progress;
use crate::report::summary::RunHeader;
use crate::report::trajectory::{CsvFile, PARTIAL_TRAJECTORY_FILE, TRAJECTORY_FILE};
use crate::run::case::Case;
use crate::run::files::{self as report, Failure, FAILURE_FILE};
use crate::run::plan::RunRequest;
use crate::run::prepare::Prepared;
use crate::run::result::RunResult;
use crate::run::simulate::{simulate, simulate_into};
use crate::store::io::{OutDir, Written};
use crate::studies::headline::{self, Headline};

/// The default run (module `headline`): the 150 rpm press, ideal vs dry vs lubricated, RK4
/// against the best adaptive method; notes each case as it starts.
pub fn default_run(
    out: Option<PathBuf>,
    progress: &dyn Progress,
) -> Result<Written<Headline>, Error> {
    headline::run_with_progress(out, progress)
}

/// What to run: one case.
///
/// ```text
/// case [solver choice] [t_end] [samples_per_revolution | output_every] [out]
/// ```
///
/// Source: docs/outputs.md ("`lash run CASE`").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunOptions {
    /// The case: a scene file (JSON) or a built-in test problem `testset:NAME`.
    pub case: String,
    /// Solver choice over the case's defaults. Its `max_wall_time` is the budget of the whole
    /// run, counted from the call (reading the case, assembly, integration, output).
    pub solver: SolverChoice,
    /// End time override, s (scene cases only).
    pub t_end: Option<f64>,
    /// Trajectory rows per crank revolution (scenes with a crank driver); None = 2000.
    pub samples_per_revolution: Option<usize>,
    /// Spacing of the trajectory's rows, s (scene cases); overrides the rows per revolution.
    pub output_every: Option<f64>,
    /// Output directory; None = `out/run/CASE`.
    pub out: Option<PathBuf>,
    /// Run until the clearance joint's once-per-revolution section settles
    /// (crate::run::steady); excludes `t_end`.
    pub until_periodic: Option<crate::run::steady::UntilPeriodic>,
    /// The formulation over the scene's own (scene cases only; docs/model.md §12): a
    /// [`lash_model::FormulationName`], which front ends take from the model crate.
    pub formulation: Option<lash_model::FormulationName>,
    /// The metrics window (`--window`); None: the crank's last revolution, else the whole run
    /// (docs/outputs.md, "The metrics window").
    pub window: Option<lash_model::MetricsWindow>,
    /// Leaves out the energy check of the finished run (`--no-energy-check`; for a run that is
    /// coarse on purpose): by default a run whose energy balance is off by more than its
    /// accuracy allows is the solver failure `energy_balance` (crate::run::energy_check).
    pub skip_energy_check: bool,
}

/// Runs one case into its directory: checks the case and the solver choice (the choice first
/// against the defaults, so that an inconsistent choice is reported before the scene is
/// read), integrates while streaming trajectory.csv, and writes the figures and summary.json.
///
/// ```text
/// everything goes into a fresh sibling of DIR, swapped in when complete (io::OutDir): DIR
/// never mixes two runs; an error other than the solver's (I/O, a bug, an interruption)
/// leaves DIR as it was
/// solver failure (exit 3): DIR = failure.json + partial_trajectory.csv (the rows up to the
/// failure), never summary.json; `progress` notes what was written; a budget that runs out
/// during set-up (no state yet) writes nothing
/// budget: solver.max_wall_time counts from this call; past it the run fails with
/// BudgetExhausted: in set-up at the next of its checks (lash_model's build phases; nothing
/// written), at the next step attempt, or after the integration (before the figures)
/// ```
pub fn run(o: &RunOptions, progress: &dyn Progress) -> Result<Written<RunResult>, Error> {
    let start = Instant::now();
    let deadline = o
        .solver
        .max_wall_time
        .and_then(|w| deadline_after(start, w));
    // Set-up and every step attempt stop at the deadline (lash_solver::interrupt).
    let _scope = lash_solver::interrupt::deadline_scope(deadline.zip(o.solver.max_wall_time));
    let case = Case::load(&o.case, None)?;
    let (prepared, mut req, settled) = run_request(case, o, deadline)?;
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| default_out("run", &prepared.case.name));
    req.keep_events = false;
    let dir = OutDir::create(&out, &report::run_file)?;
    let traj = dir.path().join(TRAJECTORY_FILE);
    let mut sink = CsvFile::create(&traj)?;
    let outcome = simulate_into(&prepared, &req, &mut sink).and_then(|r| within(r, o, deadline));
    match outcome {
        Ok(mut r) => {
            r.summary.until_periodic = settled;
            let mut files = vec![traj];
            files.extend(write_scene(&prepared, dir.path())?);
            files.extend(r.write(dir.path())?);
            let files = files.iter().map(|f| dir.final_path(f)).collect();
            dir.commit()?;
            Ok(Written {
                result: r,
                dir: out,
                files,
            })
        }
        Err(Error::Solver(e)) => {
            let (t_span_end, rows) = (prepared.t_span(req.t_end)?.1, sink.rows());
            let partial = dir.path().join(PARTIAL_TRAJECTORY_FILE);
            if rows > 0 {
                std::fs::rename(&traj, &partial).map_err(|err| Error::io(&partial, err))?;
            } else {
                std::fs::remove_file(&traj).map_err(|err| Error::io(&traj, err))?;
            }
            Failure::new(
                RunHeader::new(&prepared.case, &req.opts),
                t_span_end,
                &e,
                &prepared.state_names_of(e.state().map_or(prepared.dim(), <[f64]>::len)),
                (rows > 0).then_some(rows),
            )
            .write(dir.path())?;
            dir.commit()?;
            let what = if rows > 0 {
                format!(
                    "{FAILURE_FILE} and {PARTIAL_TRAJECTORY_FILE} ({rows} row{} before the \
                     failure)",
                    if rows == 1 { "" } else { "s" }
                )
            } else {
                FAILURE_FILE.to_string()
            };
            progress.note(&format!("wrote {what} to {}", out.display()).into());
            Err(Error::Solver(e))
        }
        // The file as the user knows it, not its temporary place.
        Err(Error::Io { path, source }) => Err(Error::Io {
            path: dir.final_path(&path),
            source,
        }),
        Err(e) => Err(e),
    }
}

/// Keeps the scene a run ran in its directory as `scene.json` (before summary.json): the
/// file's bytes as read (so its SHA-256 is the summary's `scene_sha256`), a catalogue scene as
/// JSON; a built-in test problem has none.
fn write_scene(p: &Prepared, dir: &Path) -> Result<Option<PathBuf>, Error> {
    let path = dir.join(crate::animation::SCENE_FILE);
    let bytes = match (&p.case.source, p.scene()) {
        (crate::run::case::CaseSource::File { bytes, .. }, _) => bytes.clone(),
        (_, Some(scene)) => scene.to_json_pretty().into_bytes(),
        (_, None) => return Ok(None),
    };
    crate::store::io::write_atomic(&path, &bytes)?;
    Ok(Some(path))
}

/// The checked case and the request of a run (the same for [`run`] and [`run_in_memory`]):
/// the solver choice checked against the defaults before the scene is read, then laid over
/// the case's own options; with `until_periodic`, the settling pass (crate::run::steady) that
/// decides the end time, and its report.
fn run_request(
    case: Case,
    o: &RunOptions,
    deadline: Option<Instant>,
) -> Result<
    (
        Prepared,
        RunRequest,
        Option<crate::report::summary::Settled>,
    ),
    Error,
> {
    o.solver.apply(&SolverOptions::default())?;
    let mut prepared = Prepared::load(case)?;
    if let Some(f) = o.formulation {
        prepared = prepared.with_formulation(f)?;
    }
    let opts = prepared.options(&o.solver)?;
    let settled = match &o.until_periodic {
        Some(u) => {
            if o.t_end.is_some() {
                return Err(OptionError::new("until_periodic")
                    .name("until_periodic")
                    .text(" decides the end time: give it or ")
                    .name("t_end")
                    .text(", not both")
                    .into());
            }
            Some(crate::run::steady::settle_until(&prepared, &opts, u)?)
        }
        None => None,
    };
    let mut req = RunRequest::new(opts);
    req.t_end = match &settled {
        Some((_, t_end)) => Some(*t_end),
        None => o.t_end,
    };
    let settled = settled.map(|(s, _)| s);
    req.samples_per_revolution = o.samples_per_revolution;
    req.output_every = o.output_every;
    req.deadline = deadline;
    req.window = o.window;
    if prepared.info.is_some() {
        // A window the run cannot have is an option error before anything runs.
        let (t0, t_end) = prepared.t_span(req.t_end)?;
        prepared.window_plan(req.window, t0, t_end)?;
    }
    Ok((prepared, req, settled))
}

/// A finished run; `BudgetExhausted` when the wall-clock budget ran out meanwhile, or the
/// `energy_balance` failure when its energy balance is off by more than its accuracy allows
/// (crate::run::energy_check; not with `skip_energy_check`).
fn within(r: RunResult, o: &RunOptions, deadline: Option<Instant>) -> Result<RunResult, Error> {
    let r = if o.skip_energy_check {
        r
    } else {
        crate::run::energy_check::check(r).map_err(Error::Solver)?
    };
    match deadline.filter(|d| Instant::now() >= *d) {
        Some(_) => Err(Error::Solver(SolveError::BudgetExhausted {
            t: r.extra_states.t_final,
            y: r.extra_states.y_final.clone(),
            reason: format!(
                "wall-clock budget of {} s used before the output was written",
                o.solver.max_wall_time.unwrap_or_default()
            ),
        })),
        None => Ok(r),
    }
}

/// [`run`] without files, for a library caller (the Python binding's `lash.run`): the same
/// checks, defaults, integration and summary, the trajectory's rows kept in memory
/// ([`RunResult::trajectory`]) and every event of the run kept ([`RunResult::events`], their
/// functions named by [`RunResult::event_names`]).
///
/// ```text
/// case: loaded by the caller (Case::load, or a Case built from JSON text in memory);
///       o.case and o.out are not used
/// budget: solver.max_wall_time counts from this call, as in run
/// solver failure: Error::Solver with time and state; nothing is written
/// ```
pub fn run_in_memory(case: Case, o: &RunOptions) -> Result<RunResult, Error> {
    let deadline = o
        .solver
        .max_wall_time
        .and_then(|w| deadline_after(Instant::now(), w));
    let _scope = lash_solver::interrupt::deadline_scope(deadline.zip(o.solver.max_wall_time));
    let (prepared, req, settled) = run_request(case, o, deadline)?;
    let mut r = simulate(&prepared, &req).and_then(|r| within(r, o, deadline))?;
    r.summary.until_periodic = settled;
    Ok(r)
}

/// A few lines on what a run did: method, work, and the headline metrics.
pub fn describe_run(r: &RunResult) -> String {
    let s = &r.summary;
    let setting = match (s.step, s.rtol) {
        (Some(h), _) => format!("step {h:e} s"),
        (None, Some(rt)) => format!("rtol {rt:e}"),
        _ => String::new(),
    };
    let mut out = format!(
        "{}: {} {}, t_end {} s: {} steps ({} rejected), {} RHS evaluations, {} events, {:.3} s\n",
        s.case,
        s.method,
        setting,
        s.t_end,
        s.stats.accepted,
        s.stats.rejected_error + s.stats.rejected_newton,
        s.stats.rhs_evals,
        s.events,
        s.wall_time_s
    );
    if let Some(e) = s.reference_error {
        out.push_str(&format!("  reference error {e:.3e}\n"));
    }
    if let Some(f) = &s.formulation {
        out.push_str(&format!("  formulation: {f}"));
        if let Some(st) = &s.formulation_stats {
            out.push_str(&format!(
                " ({} evaluations, {} iterations, at most {} in one, {} unconverged)",
                st.evaluations, st.iterations, st.max_iterations, st.unconverged
            ));
        }
        out.push('\n');
    }
    if s.kink_events == Some(true) {
        let exact = if s.method.is_fixed_step() {
            "not located by a fixed-step method: their crossings are counted"
        } else if s.method.is_diffsol() {
            "a restart at each"
        } else {
            "a restart at each, with exact event steps"
        };
        out.push_str(&format!("  kink events: on ({exact}; docs/model.md §7)\n"));
    }
    if let Some(u) = &s.until_periodic {
        out.push_str(&format!("  {}\n", u.describe()));
    }
    out.push_str(&format!("  trajectory: {} rows\n", r.trajectory_rows));
    if let Some(m) = &s.metrics {
        let f = |v: Option<f64>| v.map_or("null".to_string(), |x| format!("{x:.6}"));
        let mut parts = Vec::new();
        if m.slider_acc_min.is_some() {
            parts.push(format!(
                "slider acceleration [{}, {}] m/s²",
                f(m.slider_acc_min),
                f(m.slider_acc_max)
            ));
        }
        if let Some(d) = m.slider_acc_rms_dev_ideal {
            parts.push(format!("RMS deviation from ideal {d:.3e} m/s²"));
        }
        if let Some(e) = m.eps_max {
            parts.push(format!("eps_max {e:.6}"));
        }
        if let Some(n) = m.contact_onsets {
            parts.push(format!("contact onsets {n}"));
        }
        parts.push(format!("max ‖Φ‖ {:.1e}", m.constraint_violation_max));
        out.push_str(&format!("  metrics: {}\n", parts.join(", ")));
        if let Some(e) = &m.energy {
            out.push_str(&format!("  energy: {}\n", energy_line(e)));
        }
    }
    out
}

/// The printed energy line: the driver's work, every other term that is not zero, and the
/// balance (docs/outputs.md, `energy`).
fn energy_line(e: &crate::report::metrics::Energy) -> String {
    let mut parts = vec![format!("driver work {:.6} J", e.driver_work)];
    for (name, v) in [
        ("motor work", e.motor_work),
        ("load work", e.load_work),
        ("damper dissipation", e.dissipated_damper),
        ("spring potential change", e.element_potential_change),
    ] {
        if v != 0.0 {
            parts.push(format!("{name} {v:.6} J"));
        }
    }
    format!(
        "{}, balance error {:.3e} J (quadrature error {:.1e} J)",
        parts.join(", "),
        e.balance_error,
        e.quadrature_error
    )
}
