//! The engine's commands: plain options in, typed results and written files out. Each front
//! end (the `lash` command line, a Python binding) fills the options and shows the results;
//! nothing here parses arguments, prints or knows about terminals.
//!
//! ```text
//! default_run(out, progress)            → Written<Headline>     (module headline)
//! run(RunOptions, progress)             → Written<RunResult>    summary.json, trajectory.csv
//!                                                               (streamed), figures; on a
//!                                                               solver failure failure.json,
//!                                                               partial_trajectory.csv
//! study_paper(StudyOptions, progress)   → Written<StudyResult>  figures, report.md, study.json
//! compare(CompareOptions, progress)     → Written<Comparison>   compare.md, compare.json
//! work_precision(WorkPrecisionOptions, progress) → Written<WorkPrecisionResult>
//! sweep(SweepRunOptions, progress)      → SweepOutcome          one result.json per point
//! merge(MergeOptions)                   → Merged                merged.csv, merged.md
//! stiffness(StiffnessOptions, progress) → Written<StiffnessResult>
//! poincare(PoincareOptions, progress)   → Written<PoincareResult>
//! extremes(ExtremesOptions, progress)   → Written<Matrix>       extremes.md, extremes.json
//! animate(AnimateOptions)               → Written<Animated>     RUN_DIR/animation.html
//! plot(PlotOptions)                     → Written<Plotted>      a figure of trajectory columns
//! out = the option, else default_out(COMMAND, case name) = out/COMMAND/NAME
//! ```
//!
//! Progress ([`Progress`]) gets the notes a command makes while it works (the reference of a
//! comparison, a derived RK4 step, runs reused from a cache) and every long command's work
//! as batches of items (a sweep's points, a study's runs, the extremes matrix's references
//! and runs, a comparison's reference and runs, a diagnostic's phases). A stop request
//! (`lash_solver::interrupt`, raised by SIGINT or SIGTERM in `lash`) ends every command with
//! [`Error::Interrupted`]: the item in flight abandoned, finished items kept (a sweep's
//! points, the study's and the extremes matrix's caches of finished runs). Errors are typed ([`Error`]); those about options name them by the engine's names.
//!
//! Source: docs/outputs.md ("Files each command writes"); ARCHITECTURE.md ("Invariants": one
//! engine behind every front end, knowing no command line).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use lash_solver::{ControllerKind, Method, SolveError, SolverOptions};

use crate::compare::reference::{
    self as compare, Compared, Comparison, Reference, COMPARE_TOLERANCES,
};
use crate::compare::workprecision::{WorkPrecisionPlan, WpRun, WpTable, DEFAULT_TARGETS};
use crate::diagnostics::poincare::{self, PoincareResult, PoincareSettings};
use crate::diagnostics::stiffness::{
    self as stiffness_cmd, StiffnessResult, StiffnessSettings, DEFAULT_SAMPLES,
};
use crate::error::{Error, Message, OptionError};
use crate::options::SolverChoice;
use crate::progress::Progress;
use crate::report::summary::RunHeader;
use crate::report::trajectory::{CsvFile, PARTIAL_TRAJECTORY_FILE, TRAJECTORY_FILE};
use crate::run::case::Case;
use crate::run::files::{self as report, Failure, FAILURE_FILE};
use crate::run::simulate::{simulate, simulate_into, Prepared, RunRequest, RunResult};
use crate::store::cache::{RunCache, CACHE_DIR};
use crate::store::io::{OutDir, Written};
use crate::studies::extremes::{self, Matrix};
use crate::studies::headline::{self, Headline};
use crate::studies::paper::{self as study, StudyResult};
use crate::sweep::{self, MergedTable, PointResult, Shard, SweepOptions, SweepPoint, SweepReport};

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
/// failure), never summary.json; `progress` notes what was written
/// budget: solver.max_wall_time counts from this call; past it the run fails with
/// BudgetExhausted, also after the integration (before the figures)
/// ```
pub fn run(o: &RunOptions, progress: &dyn Progress) -> Result<Written<RunResult>, Error> {
    let start = Instant::now();
    let deadline = o
        .solver
        .max_wall_time
        .map(|w| start + Duration::from_secs_f64(w));
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
                &prepared.state_names(),
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

/// `lash animate RUN_DIR` (and `lash run --animate` after the run): the run as one
/// self-contained HTML page, from the directory's scene.json and trajectory.csv (module
/// `animation`).
pub fn animate(
    o: &crate::animation::AnimateOptions,
) -> Result<Written<crate::animation::Animated>, Error> {
    crate::animation::animate_dir(o)
}

/// `lash plot RUN_DIR COLUMN…`: trajectory columns against time or another column, as SVG and
/// PNG (module `column_plot`).
pub fn plot(
    o: &crate::report::column_plot::PlotOptions,
) -> Result<Written<crate::report::column_plot::Plotted>, Error> {
    crate::report::column_plot::plot_columns(o)
}

/// The checked case and the request of a run (the same for [`run`] and [`run_in_memory`]):
/// the solver choice checked against the defaults before the scene is read, then laid over
/// the case's own options; with `until_periodic`, the settling pass (crate::run::steady) that
/// decides the end time, and its report.
fn run_request(
    case: Case,
    o: &RunOptions,
    deadline: Option<Instant>,
) -> Result<(Prepared, RunRequest, Option<crate::run::steady::Settled>), Error> {
    o.solver.apply(&SolverOptions::default())?;
    let prepared = Prepared::load(case)?;
    let opts = prepared.options(&o.solver)?;
    let settled = match &o.until_periodic {
        Some(u) => {
            if o.t_end.is_some() {
                return Err(Error::Usage(
                    "--until-periodic decides the end time: give it or --t-end, not both".into(),
                ));
            }
            Some(crate::run::steady::settle(&prepared, &opts, u)?)
        }
        None => None,
    };
    let mut req = RunRequest::new(opts);
    req.t_end = match (&settled, &prepared.info) {
        (Some(s), Some(i)) => i.period.map(|t| i.t_start + t * s.revolutions as f64),
        _ => o.t_end,
    };
    req.samples_per_revolution = o.samples_per_revolution;
    req.output_every = o.output_every;
    req.deadline = deadline;
    Ok((prepared, req, settled))
}

/// A finished run, or `BudgetExhausted` when the wall-clock budget ran out meanwhile.
fn within(r: RunResult, o: &RunOptions, deadline: Option<Instant>) -> Result<RunResult, Error> {
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
/// ([`RunResult::trajectory`]) and every event of the run kept ([`RunResult::events`]);
/// returned with the prepared case, whose [`MechanismInfo`](crate::run::simulate::MechanismInfo)
/// names the state components and the event functions.
///
/// ```text
/// case: loaded by the caller (Case::load, or a Case built from JSON text in memory);
///       o.case and o.out are not used
/// budget: solver.max_wall_time counts from this call, as in run
/// solver failure: Error::Solver with time and state; nothing is written
/// ```
pub fn run_in_memory(case: Case, o: &RunOptions) -> Result<(Prepared, RunResult), Error> {
    let deadline = o
        .solver
        .max_wall_time
        .map(|w| Instant::now() + Duration::from_secs_f64(w));
    let (prepared, req, settled) = run_request(case, o, deadline)?;
    let mut r = simulate(&prepared, &req).and_then(|r| within(r, o, deadline))?;
    r.summary.until_periodic = settled;
    Ok((prepared, r))
}

/// What to study.
///
/// ```text
/// paper = the paper's speeds (120–200 rpm) and clearances (0.1–0.5 mm), dry and lubricated
/// ```
///
/// Source: docs/model.md §6.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StudyOptions {
    /// Output directory; None = `out/study/paper`.
    pub out: Option<PathBuf>,
    /// Run the robustness study instead (`studies::robustness`): robustness.md and
    /// robustness.json in the same directory, sharing its cache of runs.
    pub robustness: bool,
}

/// Runs the paper's study (module `study`): figures, report.md and study.json in the output
/// directory ([`study::describe_paper`] says it in one line); each run as an item of
/// `progress`; finished runs are kept in DIR/cache/ and reused by a rerun.
pub fn study_paper(
    o: &StudyOptions,
    progress: &dyn Progress,
) -> Result<Written<StudyResult>, Error> {
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| default_out("study", "paper"));
    let r = study::paper(&out, progress)?;
    let files = vec![out.join(study::REPORT_FILE), out.join(study::JSON_FILE)];
    Ok(Written {
        result: r,
        dir: out,
        files,
    })
}

/// `lash study paper --robustness`: the claims under the modelling choices the paper leaves
/// open (`studies::robustness`), written to the study's directory.
pub fn study_robustness(
    o: &StudyOptions,
    progress: &dyn Progress,
) -> Result<Written<crate::studies::robustness::RobustnessResult>, Error> {
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| default_out("study", "paper"));
    let r = crate::studies::robustness::paper(&out, progress)?;
    let files = vec![
        out.join(crate::studies::robustness::MD_FILE),
        out.join(crate::studies::robustness::JSON_FILE),
    ];
    Ok(Written {
        result: r,
        dir: out,
        files,
    })
}

/// The RK4 steps of a comparison: the given ones, else the largest stable step h and h/2,
/// h/4 (`halvings` + 1 steps) for scene cases with a crank, none for test problems.
fn rk4_steps(
    p: &Prepared,
    given: &Option<Vec<f64>>,
    t_end: Option<f64>,
    halvings: usize,
    progress: &dyn Progress,
) -> Result<Vec<f64>, Error> {
    match given {
        Some(v) => Ok(v.clone()),
        None if p.period().is_some() => {
            let clock = Instant::now();
            let h = compare::stable_rk4_step(p, t_end)?;
            progress.finished(
                &format!(
                    "{}: largest stable RK4 step {h:e} s (1-2-5 series from T/400, ‖Φ‖ < 1e-8)",
                    p.case.name
                ),
                clock.elapsed().as_secs_f64(),
            );
            Ok((0..=halvings).map(|k| h / f64::from(1u32 << k)).collect())
        }
        None => Ok(Vec::new()),
    }
}

/// What to compare: one case, every method.
///
/// ```text
/// case [tolerances] [steps] [t_end] [out]
/// ```
///
/// Source: docs/outputs.md ("`lash compare CASE`").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CompareOptions {
    /// The case: a scene file (JSON) or `testset:NAME`.
    pub case: String,
    /// Relative tolerances of the adaptive methods; None = [`COMPARE_TOLERANCES`].
    pub tolerances: Option<Vec<f64>>,
    /// RK4 steps, s; None = the largest stable step h of the case and h/2, h/4 (scene cases
    /// with a crank), none for test problems.
    pub steps: Option<Vec<f64>>,
    /// End time override, s (scene cases only).
    pub t_end: Option<f64>,
    /// Output directory; None = `out/compare/CASE`.
    pub out: Option<PathBuf>,
}

/// Compares the methods on one case: RK4 at several steps, every embedded pair and every stiff
/// method at each tolerance, against the case's reference; writes compare.md and
/// compare.json. Notes the reference and a derived RK4 step.
pub fn compare(o: &CompareOptions, progress: &dyn Progress) -> Result<Written<Comparison>, Error> {
    let p = Prepared::load_spec(&o.case, None)?;
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| default_out("compare", &p.case.name));
    let tolerances = o
        .tolerances
        .clone()
        .unwrap_or_else(|| COMPARE_TOLERANCES.to_vec());
    let derive = o.steps.is_none() && p.period().is_some();
    let n_steps = o
        .steps
        .as_ref()
        .map_or(if derive { 3 } else { 0 }, Vec::len);
    let adaptive = Method::ALL.iter().filter(|m| !m.is_fixed_step()).count();
    progress.started(
        "runs",
        1 + usize::from(derive) + n_steps + adaptive * tolerances.len(),
    );
    let clock = Instant::now();
    let reference = Reference::compute(&p, o.t_end)?;
    progress.finished(
        &format!("{}: reference {}", p.case.name, reference.how),
        clock.elapsed().as_secs_f64(),
    );
    let steps = rk4_steps(&p, &o.steps, o.t_end, 2, progress)?;
    let mut runs = Vec::new();
    let mut push = |c: Compared, secs: f64| {
        progress.finished(&run_line(&c), secs);
        runs.push(c);
    };
    for &h in &steps {
        let t = Instant::now();
        let c = compare::compare_one(&p, &reference, Method::Rk4, None, Some(h), None)?.0;
        push(c, t.elapsed().as_secs_f64());
    }
    for m in Method::ALL.into_iter().filter(|m| !m.is_fixed_step()) {
        for &r in &tolerances {
            let t = Instant::now();
            let c = compare::compare_one(&p, &reference, m, Some(r), None, None)?.0;
            push(c, t.elapsed().as_secs_f64());
        }
    }
    let c = Comparison {
        case: p.case.name.clone(),
        reference: reference.how.clone(),
        reference_agreement: reference.agreement.clone(),
        window: reference.window.clone(),
        t_end: reference.t_end,
        runs,
    };
    let files = c.write(&out)?;
    Ok(Written {
        result: c,
        dir: out,
        files,
    })
}

/// What to measure: error against cost on one case.
///
/// ```text
/// case [methods] [tolerances] [steps] [controllers] [t_end] [out]   (None = the default)
/// ```
///
/// Source: docs/outputs.md ("`lash work-precision CASE`").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WorkPrecisionOptions {
    /// The case: a scene file (JSON) or `testset:NAME`.
    pub case: String,
    /// Methods; None = every method of this build.
    pub methods: Option<Vec<Method>>,
    /// Relative tolerances of the adaptive methods (atol as in the case); None = the
    /// defaults ([`crate::compare::workprecision::DEFAULT_TOLERANCES`]).
    pub tolerances: Option<Vec<f64>>,
    /// Steps of the fixed-step methods, s; None = derived from the case.
    pub steps: Option<Vec<f64>>,
    /// Controllers compared on one adaptive method; None = all.
    pub controllers: Option<Vec<ControllerKind>>,
    /// End time override, s (scene cases only).
    pub t_end: Option<f64>,
    /// Output directory; None = `out/work-precision/CASE`.
    pub out: Option<PathBuf>,
}

impl WorkPrecisionOptions {
    /// Checks the lists against each other and applies the defaults
    /// ([`WorkPrecisionPlan::new`]).
    pub fn plan(&self) -> Result<WorkPrecisionPlan, Error> {
        WorkPrecisionPlan::new(
            self.methods.as_deref(),
            self.tolerances.as_deref(),
            self.steps.as_deref(),
            self.controllers.as_deref(),
        )
    }
}

/// What [`work_precision`] measured: the table and how its reference was obtained.
///
/// Source: this module.
#[derive(Debug)]
pub struct WorkPrecisionResult {
    /// The runs and the cheapest per target.
    pub table: WpTable,
    /// How the reference was obtained.
    pub reference: String,
}

/// Error against cost on one case: every method × tolerance and RK4 × step, and the
/// controllers compared on one method of ours ([`WorkPrecisionPlan::controller_method`]),
/// against the case's reference; writes the markdown and JSON tables and the log–log figures.
/// Notes the reference, a derived RK4 step (or that RK4 is left out) and each run as it ends.
pub fn work_precision(
    o: &WorkPrecisionOptions,
    progress: &dyn Progress,
) -> Result<Written<WorkPrecisionResult>, Error> {
    let case = Case::load(&o.case, None)?;
    let plan = o.plan()?;
    let p = Prepared::load(case)?;
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| default_out("work-precision", &p.case.name));
    let wants_rk4 = plan.methods.iter().any(|m| m.is_fixed_step());
    if wants_rk4 && plan.steps.is_none() && p.period().is_none() {
        if o.methods.is_some() {
            return Err(OptionError::new("steps")
                .text("rk4 needs ")
                .name("steps")
                .text(format!(
                    " for {} (no crank period to derive them from)",
                    p.case.name
                ))
                .into());
        }
        progress.note(
            &Message::default()
                .text(format!("{}: rk4 left out (give ", p.case.name))
                .name("steps")
                .text(" to include it)"),
        );
    }
    let ctl_method = plan.controller_method();
    let derive = wants_rk4 && plan.steps.is_none() && p.period().is_some();
    let n_steps = match &plan.steps {
        Some(v) => v.len(),
        None if derive => 4,
        None => 0,
    };
    let total_runs: usize = plan
        .methods
        .iter()
        .map(|&m| {
            if m.is_fixed_step() {
                n_steps
            } else if Some(m) == ctl_method && !plan.controllers.is_empty() {
                plan.controllers.len() * plan.tolerances.len()
            } else {
                plan.tolerances.len()
            }
        })
        .sum();
    progress.started("runs", 1 + usize::from(derive) + total_runs);
    let clock = Instant::now();
    let reference = Reference::compute(&p, o.t_end)?;
    progress.finished(
        &format!("{}: reference {}", p.case.name, reference.how),
        clock.elapsed().as_secs_f64(),
    );
    let steps = if wants_rk4 {
        rk4_steps(&p, &plan.steps, o.t_end, 3, progress)?
    } else {
        Vec::new()
    };
    let mut runs = Vec::new();
    let mut clock = Instant::now();
    let mut push = |c: Compared| {
        progress.finished(&run_line(&c), clock.elapsed().as_secs_f64());
        clock = Instant::now();
        runs.push(WpRun {
            method: c.method,
            controller: c.controller,
            rtol: c.rtol,
            step: c.step,
            error: c.error,
            rhs_evals: c.rhs_evals,
            wall_time_s: c.wall_time_s,
            failure: c.failure,
        });
    };
    for &m in &plan.methods {
        if m.is_fixed_step() {
            for &h in &steps {
                push(compare::compare_one(&p, &reference, m, None, Some(h), None)?.0);
            }
        } else if Some(m) == ctl_method && !plan.controllers.is_empty() {
            for &c in &plan.controllers {
                for &r in &plan.tolerances {
                    push(compare::compare_one(&p, &reference, m, Some(r), None, Some(c))?.0);
                }
            }
        } else {
            for &r in &plan.tolerances {
                push(compare::compare_one(&p, &reference, m, Some(r), None, None)?.0);
            }
        }
    }
    let mut table = WpTable::new(&p.case.name, runs, &DEFAULT_TARGETS)?;
    table.error_measure = reference.measure();
    let files = table.write(&out)?;
    Ok(Written {
        result: WorkPrecisionResult {
            table,
            reference: reference.how,
        },
        dir: out,
        files,
    })
}

/// What to diagnose: the stiffness of one case.
///
/// ```text
/// case [solver choice] [samples] [t_end] [measure] [out]
/// ```
///
/// Source: docs/outputs.md ("`lash stiffness CASE`").
#[derive(Debug, Clone, PartialEq)]
pub struct StiffnessOptions {
    /// The case: a scene file (JSON) or a built-in test problem `testset:NAME`.
    pub case: String,
    /// Solver of the reference run over the case's defaults.
    pub solver: SolverChoice,
    /// Sample points along the run, both ends included (≥ 2); None = [`DEFAULT_SAMPLES`].
    pub samples: Option<usize>,
    /// End time override, s (scene cases only).
    pub t_end: Option<f64>,
    /// Whether to measure the RK4 limit (the bisection runs RK4 over the whole run many
    /// times).
    pub measure: bool,
    /// Output directory; None = `out/stiffness/CASE`.
    pub out: Option<PathBuf>,
}

impl Default for StiffnessOptions {
    fn default() -> Self {
        StiffnessOptions {
            case: String::new(),
            solver: SolverChoice::default(),
            samples: None,
            t_end: None,
            measure: true,
            out: None,
        }
    }
}

/// Stiffness diagnostics: checks the case and the options, integrates the reference run
/// analysing the Jacobian at the sample points, measures the RK4 limit, and writes
/// stiffness.csv, stiffness.{svg,png}, stiffness.md and stiffness.json.
pub fn stiffness(
    o: &StiffnessOptions,
    progress: &dyn Progress,
) -> Result<Written<StiffnessResult>, Error> {
    let case = Case::load(&o.case, None)?;
    o.solver.apply(&SolverOptions::default())?;
    let prepared = Prepared::load(case)?;
    let opts = prepared.options(&o.solver)?;
    prepared.t_span(o.t_end)?;
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| default_out("stiffness", &prepared.case.name));
    let settings = StiffnessSettings {
        samples: o.samples.unwrap_or(DEFAULT_SAMPLES),
        t_end: o.t_end,
        measure: o.measure,
        ..Default::default()
    };
    let r = stiffness_cmd::analyse(&prepared, &opts, &settings, progress)?;
    let files = r.write(&out)?;
    Ok(Written {
        result: r,
        dir: out,
        files,
    })
}

/// What to diagnose: the Poincaré section and Lyapunov exponent of one case.
///
/// ```text
/// case [revolutions] [perturbation] [renorm_per_rev] [solver choice] [out]
/// ```
///
/// Source: docs/outputs.md ("`lash poincare CASE`").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PoincareOptions {
    /// The case: a scene file (JSON) with a crank driver and a clearance joint role.
    pub case: String,
    /// Crank revolutions (≥ 1); None = the default.
    pub revolutions: Option<usize>,
    /// Initial and renormalised separation, in clearances, in (0, 1); None = the default.
    pub perturbation: Option<f64>,
    /// Renormalisations per crank revolution (≥ 1); None = the default.
    pub renorm_per_rev: Option<usize>,
    /// Solver of both trajectories over the case's defaults ([`poincare::options`]).
    pub solver: SolverChoice,
    /// Output directory; None = `out/poincare/CASE`.
    pub out: Option<PathBuf>,
}

/// Chaos diagnostics: checks the case (a crank driver and a clearance joint role) and the
/// options, integrates the section run and the two Lyapunov trajectories, and writes
/// poincare.csv, lyapunov.csv, the figures, poincare.md and poincare.json.
pub fn poincare(
    o: &PoincareOptions,
    progress: &dyn Progress,
) -> Result<Written<PoincareResult>, Error> {
    let case = Case::load(&o.case, None)?;
    o.solver.apply(&SolverOptions::default())?;
    let prepared = Prepared::load(case)?;
    let opts = poincare::options(&prepared, &o.solver)?;
    let d = PoincareSettings::default();
    let settings = PoincareSettings {
        revolutions: o.revolutions.unwrap_or(d.revolutions),
        perturbation: o.perturbation.unwrap_or(d.perturbation),
        renorm_per_rev: o.renorm_per_rev.unwrap_or(d.renorm_per_rev),
    };
    settings.validate()?;
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| default_out("poincare", &prepared.case.name));
    let r = poincare::analyse(&prepared, &opts, &settings, progress)?;
    let files = r.write(&out)?;
    Ok(Written {
        result: r,
        dir: out,
        files,
    })
}

/// What to run: the extremes matrix.
///
/// ```text
/// [quick] [jobs] [max_steps] [max_wall_time] [out]
/// ```
///
/// Source: docs/outputs.md ("`lash extremes`"); module `extremes`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExtremesOptions {
    /// The quick subset (3 scenes × every method × 3 tolerances).
    pub quick: bool,
    /// Parallel runs (≥ 1, capped at the available parallelism); None = 1 (the wall-clock
    /// budget is per run).
    pub jobs: Option<usize>,
    /// Step budget of every run (attempts); None = the plan's.
    pub max_steps: Option<usize>,
    /// Wall-clock budget of every run, s; None = the plan's.
    pub max_wall_time: Option<f64>,
    /// Output directory; None = `out/extremes` (`out/extremes-quick` when quick).
    pub out: Option<PathBuf>,
}

/// Runs the extremes matrix (or its quick subset) and writes extremes.md and extremes.json
/// (in that order in `files`); each reference and run is an item of `progress`. Finished
/// references and runs are kept in DIR/cache/ and reused by a rerun ([`extremes::run_cached`]).
/// A run that ended in an outcome that is not allowed is in the result, not an error: see
/// [`extremes::check`].
pub fn extremes(o: &ExtremesOptions, progress: &dyn Progress) -> Result<Written<Matrix>, Error> {
    let mut plan = if o.quick {
        extremes::Plan::quick()
    } else {
        extremes::Plan::full()
    };
    if let Some(n) = o.max_steps {
        plan.budget.max_steps = n;
    }
    if let Some(w) = o.max_wall_time {
        plan.budget.max_wall_time = w;
    }
    plan.jobs = o.jobs.unwrap_or(1);
    let out = o.out.clone().unwrap_or_else(|| {
        PathBuf::from("out").join(if o.quick {
            "extremes-quick"
        } else {
            "extremes"
        })
    });
    crate::store::claim::remove_dead_temporaries(&out);
    let cache = RunCache::new(&out.join(CACHE_DIR));
    let m = extremes::run_cached(&plan, Some(&cache), progress)?;
    let files = m.write(&out)?;
    Ok(Written {
        result: m,
        dir: out,
        files,
    })
}

/// What to sweep.
///
/// ```text
/// SWEEP.json [jobs] [shard] [out]
/// ```
///
/// Source: docs/outputs.md ("Sweeps").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SweepRunOptions {
    /// The sweep file (JSON): a base case and lists of parameter values.
    pub file: PathBuf,
    /// Parallel jobs (≥ 1, capped at the available parallelism with a note); None = the
    /// number of cores.
    pub jobs: Option<usize>,
    /// The points to run; None = all.
    pub shard: Option<Shard>,
    /// Output directory (one subdirectory per point); None = `out/sweep/STEM` of the file.
    pub out: Option<PathBuf>,
}

/// What a sweep did.
///
/// Source: this module.
#[derive(Debug)]
pub struct SweepOutcome {
    /// Counts of the shard's points.
    pub report: SweepReport,
    /// The shard run.
    pub shard: Shard,
    /// Points in the whole grid.
    pub points: usize,
    /// The output directory.
    pub dir: PathBuf,
}

/// Runs a sweep of scene runs ([`sweep_point`]): loads and checks the sweep file and its base
/// case, then [`sweep_with`].
pub fn sweep(o: &SweepRunOptions, progress: &dyn Progress) -> Result<SweepOutcome, Error> {
    let spec = sweep::SweepSpec::load(&o.file)?;
    spec.points()?;
    let base = Prepared::load(spec.case.clone())?;
    sweep_with(o, |p, dir| sweep_point(&base, p, dir), progress)
}

/// Runs a sweep with a point runner: loads and checks the sweep file, runs the shard's
/// unfinished points in parallel (progress: each point as it ends). A point that failed
/// otherwise than in the solver makes the whole sweep an error, after the others ran
/// ([`SweepReport::into_result`]).
pub fn sweep_with<F>(
    o: &SweepRunOptions,
    runner: F,
    progress: &dyn Progress,
) -> Result<SweepOutcome, Error>
where
    F: Fn(&SweepPoint, &Path) -> Result<PointResult, Error> + Sync,
{
    let spec = sweep::SweepSpec::load(&o.file)?;
    let points = spec.points()?;
    let out = o.out.clone().unwrap_or_else(|| {
        let stem = o
            .file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "sweep".into());
        default_out("sweep", &stem)
    });
    let opts = SweepOptions {
        jobs: o.jobs,
        shard: o.shard.unwrap_or(Shard::ALL),
    };
    let report =
        sweep::run_sweep_with_progress(&points, &out, &opts, runner, progress)?.into_result()?;
    Ok(SweepOutcome {
        report,
        shard: opts.shard,
        points: points.len(),
        dir: out,
    })
}

/// The point runner of a sweep: the base case with the point's physical parameters laid over
/// its scene ([`sweep::apply_params`]) and its solver choice over the case's defaults;
/// writes DIR/summary.json and returns the summary, flattened, for the merged table. A
/// solver failure is returned as such (the sweep records it as a finished point).
pub fn sweep_point(base: &Prepared, point: &SweepPoint, dir: &Path) -> Result<PointResult, Error> {
    let pp = &point.params;
    let physical = pp.speed_rpm.is_some()
        || pp.clearance.is_some()
        || pp.viscosity.is_some()
        || pp.stiffness.is_some();
    let prepared = match base.scene() {
        Some(scene) if physical => {
            let mut s = scene.clone();
            sweep::apply_params(&mut s, pp)?;
            Prepared::with_scene(base.case.clone(), s)?
        }
        None if physical => {
            return Err(Error::Input(format!(
                "sweep: speed_rpm, clearance, viscosity and stiffness need a scene case, not {}",
                base.case.name
            )))
        }
        _ => base.clone(),
    };
    let choice = SolverChoice {
        method: pp.method,
        rtol: pp.rtol,
        step: pp.step,
        controller: pp.controller,
        ..Default::default()
    };
    let mut req = RunRequest::new(prepared.options(&choice)?);
    req.trajectory_points = Some(0);
    let r = simulate(&prepared, &req)?;
    r.summary.write(dir)?;
    let v = serde_json::to_value(&r.summary)
        .map_err(|e| Error::Internal(format!("summary of point {}: {e}", point.id)))?;
    Ok(point_values(v))
}

/// A point's summary as merged-table values: `case` and `scene_sha256` dropped (the point's
/// parameters hold them), the solver settings actually used renamed `used.method`,
/// `used.controller`, `used.rtol`, `used.step` (the parameters say what was asked for), `atol`
/// left in the point's summary.json only.
pub fn point_values(mut summary: serde_json::Value) -> PointResult {
    if let Some(o) = summary.as_object_mut() {
        for k in ["case", "scene_sha256", "atol"] {
            o.remove(k);
        }
        for k in ["method", "controller", "rtol", "step"] {
            if let Some(v) = o.remove(k) {
                o.insert(format!("used.{k}"), v);
            }
        }
    }
    PointResult::flatten(&summary)
}

/// What to merge.
///
/// ```text
/// DIR... [out]
/// ```
///
/// Source: docs/outputs.md ("Sweeps").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MergeOptions {
    /// Sweep output directories (or point directories) to join; at least one.
    pub dirs: Vec<PathBuf>,
    /// Where merged.csv and merged.md go; None = the first directory.
    pub out: Option<PathBuf>,
    /// Merge what finished even if some points of the grid are unfinished or corrupt (they
    /// get rows with status `unfinished` / `corrupt`); else that is an error.
    pub allow_partial: bool,
}

/// What [`merge`] wrote.
///
/// Source: this module.
#[derive(Debug)]
pub struct Merged {
    /// The table.
    pub table: MergedTable,
    /// merged.csv.
    pub csv: PathBuf,
    /// merged.md.
    pub md: PathBuf,
}

/// Joins the finished points of sweep directories into one table: merged.csv and merged.md.
/// Points of the grids that are unfinished or whose result is corrupt make it an input error
/// that names them (nothing written), unless `allow_partial`: then they are rows of their own
/// (status `unfinished`, `corrupt`).
pub fn merge(o: &MergeOptions) -> Result<Merged, Error> {
    let Some(first) = o.dirs.first() else {
        return Err(Error::Usage("merge: no directory to merge".into()));
    };
    let out = o.out.clone().unwrap_or_else(|| first.clone());
    let table = sweep::merge(&o.dirs)?;
    let complete = table.unfinished.is_empty() && table.corrupt.is_empty();
    if !complete && !o.allow_partial {
        return Err(OptionError::new("allow_partial")
            .text(format!(
                "merge: the sweep is incomplete ({} finished): {}; rerun the sweep to finish \
                 them, or give ",
                table.rows.len(),
                table.missing_summary(5)
            ))
            .name("allow_partial")
            .text(" to merge what finished")
            .into());
    }
    let table = table.with_missing();
    let (csv, md) = table.write(&out)?;
    Ok(Merged { table, csv, md })
}

/// One line on a comparison run: label, setting, error, work.
fn run_line(c: &Compared) -> String {
    format!(
        "{} {}: error {}, {} RHS evaluations, {:.3} s",
        c.label(),
        c.setting(),
        c.error.map_or("failed".into(), |e| format!("{e:.3e}")),
        c.rhs_evals,
        c.wall_time_s
    )
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
            out.push_str(&format!(
                "  energy: driver work {:.6} J, balance error {:.3e} J (quadrature error {:.1e} J)\n",
                e.driver_work, e.balance_error, e.quadrature_error
            ));
        }
    }
    out
}

/// Default output directory of a command for a case: `out/COMMAND/NAME` (a `:` in a built-in
/// name becomes `_`).
pub fn default_out(command: &str, name: &str) -> PathBuf {
    PathBuf::from("out")
        .join(command)
        .join(name.replace(':', "_"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_out_is_per_command_and_case() {
        assert_eq!(
            default_out("run", "testset:hires"),
            PathBuf::from("out/run/testset_hires")
        );
    }
}
