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
//! Checks before a run (exit 2, naming the field or option; nothing runs):
//!
//! ```text
//! step          RK4's step longer than the run                                → step
//! trajectory    more than MAX_TRAJECTORY_ROWS rows                            → samples_per_
//!                                                                    revolution, output_every
//! time axis     16 ε max(|t_start|, |t_end|) (the smallest step f64 allows there) above
//!               TIME_RESOLUTION × the shortest time the run must resolve: the trajectory's
//!               and the metrics grid's spacing, h_max, the RK4 step, span/100 → t_start,
//!               t_end or revolutions (t_start = 1e15 s: steps ≥ 3.6 s)
//! deadline      RunRequest::deadline (a command's budget from its start) already past
//!               → BudgetExhausted (exit 3); otherwise the integration gets what is left
//! ```
//!
//! Defaults of a mechanism run (a scene), each overridable by a request's SolverChoice:
//!
//! ```text
//! method         bdf: the one method that is never far from the cheapest in `lash
//!                work-precision` on the paper's press: on the lubricated case the film makes
//!                the explicit pairs stability-bound, and on the dry and ideal cases bdf stays
//!                close to the best explicit pair (BENCHMARKS.md, "Defaults of a run")
//! rtol           1e-8
//! atol_i         rtol · s_i, per state component y = (q, q̇), q = (x, y, φ) per integrated body:
//!                  x, y      s = L                  (m)
//!                  φ         s = L / (1 m)          (rad: L of arc on a 1 m lever)
//!                  ẋ, ẏ, φ̇   s = L · ω_ref          (m/s, rad/s)
//!                L = the smallest radial clearance of the scene (1e-3 m without a clearance
//!                joint), ω_ref = |ω| of the crank driver (1 s⁻¹ without one). Every method
//!                weighs the local error of component i by atol_i + rtol·|y_i|, so atol is
//!                the floor that applies where y_i passes near 0 (rod angle, velocities at
//!                reversal, a journal at the centre). Body positions of the press are
//!                |y_i| ≈ 0.4 m, so there the relative term dominates and positions are
//!                controlled to about rtol·0.4 m, not rtol·c: for that reason the errors of
//!                the dry scenes of the extremes matrix lie decades above rtol (BENCHMARKS.md,
//!                "Extremes"). atol scales with rtol, so tolerance
//!                proportionality holds down to rtol = 1e-13.
//!                An atol in the request (SolverChoice::atol, `--atol`) replaces the whole vector.
//! event_samples  4: g is also sampled at 4 interior points of every step
//! h_max          T/100 (T the crank period; ∞ without a crank driver or without a clearance
//!                joint, where nothing can be stepped over): with 4 samples an
//!                interval of sign change longer than T/500 (0.8 ms at 150 rpm) cannot hide
//!                inside a step, and the contacts and flights of the dry press are longer
//!                than that (BENCHMARKS.md, "Defaults of a run"); a step over a whole contact
//!                would miss both its onset and its loss (tests/simulate.rs checks the onset
//!                count against a reference).
//! max_steps      50 000 000
//! divergence     1e6: a state component (m, rad, m/s, rad/s) beyond 1e6 in magnitude is
//!  bound         divergence (NonFiniteState), not motion of a mechanism: 1000 km, 1000 km/s,
//!                1.6e5 revolutions of an integrated body. The solver's own default, 1e100,
//!                let an unstable RK4 run go on for ~16× as many steps of growth first.
//! rk4 stability  15: fixed-step RK4 fails with Rk4Unstable after 15 consecutive steps
//!  check         outside its stability region (h·λ outside it for an eigenvalue λ of ∂f/∂y,
//!                suspected from the stages: lash_solver::rk4). Past the
//!                limit the oil film of a lubricated joint does not blow up: the numerical
//!                journal drifts to a lower eccentricity where the step is stable, finite
//!                and wrong (BENCHMARKS.md, "Extremes" → "What the matrix found"), which no
//!                bound on the state catches.
//! events         located for adaptive methods; off for fixed-step methods (the paper's RK4
//!                runs without event location, docs/model.md §7), whose crossings are counted at
//!                the step ends
//! ```
//!
//! A built-in test problem runs rodas5p at rtol 1e-6 with the problem's own atol (its
//! reference_error threshold) and records every accepted step as its trajectory.
//!
//! Metrics window: the last crank revolution [t_end − T, t_end] (docs/outputs.md, "`metrics`");
//! when the run is shorter than T (a `--t-end` override) or has no crank driver, the whole run.
//!
//! Source: docs/outputs.md (summary.json, trajectory.csv, the metrics window, the energy
//! balance), docs/model.md §5–§7, §9.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use lash_model::scene::JointSpec;
use lash_model::{IdealSliderCrank, Mechanism, Outputs, Scene};
use lash_solver::{
    testset, Atol, EventHit, Method, OdeSystem, Problem, Solution, SolveError, SolverOptions,
    Stats, StepOutcome,
};

use crate::error::{Error, OptionError};
use crate::options::SolverChoice;
use crate::report::metrics::{
    self, DenseExtremes, EnergyTotals, EventQuantity, EventRecord, JointExtremes, JointInfo, Peaks,
    Sample, Window, GRID_POINTS,
};
use crate::report::summary::Summary;
use crate::report::trajectory::{fmt_num, Columns, Header, TrajectorySink};
use crate::run::case::{Case, CaseSource};
use crate::run::files::{self as report, RunOutput};

/// Default method of a mechanism run.
pub const DEFAULT_METHOD: Method = Method::Bdf;
/// Default relative tolerance of a mechanism run.
pub const DEFAULT_RTOL: f64 = 1e-8;
/// Interior event samples per step of a mechanism run.
pub const DEFAULT_EVENT_SAMPLES: usize = 4;
/// h_max of a mechanism run with a crank driver, as a fraction of the crank period.
pub const H_MAX_PER_PERIOD: f64 = 1.0 / 100.0;
/// Step limit of a mechanism run.
pub const DEFAULT_MAX_STEPS: usize = 50_000_000;
/// Divergence bound of a mechanism run (module doc), in SI units.
pub const MECHANISM_DIVERGENCE_BOUND: f64 = 1e6;
/// Consecutive RK4 steps outside the stability region that fail a mechanism run (module doc).
pub const MECHANISM_RK4_INSTABILITY_STEPS: usize = 15;
/// Length scale L of the default atol for scenes without a clearance joint, m.
pub const DEFAULT_LENGTH_SCALE: f64 = 1e-3;
/// Longest energy-quadrature panel of a run with a crank, as a fraction of the period: long
/// adaptive steps are split (the power terms oscillate at multiples of the crank frequency).
pub const QUADRATURE_PANEL_PER_PERIOD: f64 = 1.0 / 400.0;
/// Default method of a built-in test problem.
pub const TESTSET_METHOD: Method = Method::Rodas5p;
/// Default relative tolerance of a built-in test problem.
pub const TESTSET_RTOL: f64 = 1e-6;

/// What a case integrates.
///
/// ```text
/// Mechanism(scene) → Mechanism::from_scene per run (fresh event state) | TestSet(name)
/// ```
///
/// Source: docs/outputs.md (`case`).
#[derive(Clone, Debug, PartialEq)]
pub enum Model {
    /// A checked scene; each run builds its own `Mechanism` from it.
    Mechanism(Box<Scene>),
    /// A problem of `lash_solver::testset`, by name.
    TestSet(&'static str),
}

/// What the mechanism of a scene offers the commands, found once when the case is prepared.
///
/// ```text
/// T = 2π/|ω_crank|,  L = min_k c_k,  dim = 2·3·(integrated bodies)
/// ```
///
/// Source: docs/model.md §1, §5.
#[derive(Clone, Debug, PartialEq)]
pub struct MechanismInfo {
    /// Crank period T, s (crank driver role with ω ≠ 0).
    pub period: Option<f64>,
    /// |ω| of the crank driver, rad/s.
    pub crank_speed: Option<f64>,
    /// Start time, s.
    pub t_start: f64,
    /// End time of the scene, s.
    pub t_end: f64,
    /// The smallest radial clearance of the scene's clearance joints, m.
    pub clearance_min: Option<f64>,
    /// The clearance-joint role: its clearance and whether it is lubricated.
    pub joint: Option<JointInfo>,
    /// Whether some clearance joint has no oil film (dry contact: chaotic, docs/model.md §9).
    pub has_dry_joint: bool,
    /// State dimension.
    pub dim: usize,
    /// Whether the scene is an in-line slider-crank with a closed-form ideal.
    pub has_ideal: bool,
    /// Names of the state components: `<body>.x`, `<body>.y`, `<body>.theta` of every
    /// integrated body, then `<body>.vx`, `<body>.vy`, `<body>.omega`.
    pub state_names: Vec<String>,
    /// Each event function's kind and element (`lash_model::Mechanism::event_name`:
    /// `("contact" | "eps_cap", clearance joint)`, `("corner_contact", prismatic joint)`), by
    /// [`crate::report::metrics::EventRecord::index`].
    pub event_names: Vec<(&'static str, String)>,
}

/// A case ready to run.
///
/// ```text
/// (case: name and hash, model: scene | test problem, info: what the scene offers)
/// ```
///
/// Source: docs/outputs.md (`case`, `scene_sha256`).
#[derive(Clone, Debug, PartialEq)]
pub struct Prepared {
    /// The case reference (name and sha256 recorded in summary.json).
    pub case: Case,
    /// What is integrated.
    pub model: Model,
    /// Mechanism facts (None for test problems).
    pub info: Option<MechanismInfo>,
}

/// How an error names the case: the scene file's path, else the case's name.
fn case_label(case: &Case) -> String {
    match &case.source {
        CaseSource::File { path, .. } => path.display().to_string(),
        CaseSource::BuiltIn(_) | CaseSource::Catalogue(_) => case.name.clone(),
    }
}

/// A case that cannot be used for a reason other than the model's (`case LABEL: REASON`).
fn case_error(case: &Case, e: impl std::fmt::Display) -> Error {
    Error::Input(format!("case {}: {e}", case_label(case)))
}

/// A scene the model rejects (`case LABEL: PATH: REASON`), its path and reason kept.
fn scene_error(case: &Case, error: lash_model::SceneError) -> Error {
    Error::Scene {
        case: case_label(case),
        error,
    }
}

impl Prepared {
    /// Loads a case reference (a scene path or `testset:NAME`), relative paths taken from
    /// `base_dir` or the working directory.
    pub fn load_spec(spec: &str, base_dir: Option<&Path>) -> Result<Prepared, Error> {
        Prepared::load(Case::load(spec, base_dir)?)
    }

    /// Checks the case: parses and validates the scene and assembles its mechanism once
    /// (scene errors are input errors, exit code 2).
    pub fn load(case: Case) -> Result<Prepared, Error> {
        match &case.source {
            CaseSource::BuiltIn(name) => {
                let name = testset::NAMES
                    .iter()
                    .copied()
                    .find(|n| n == name)
                    .ok_or_else(|| Error::Input(format!("unknown built-in case '{name}'")))?;
                Ok(Prepared {
                    case,
                    model: Model::TestSet(name),
                    info: None,
                })
            }
            CaseSource::File { bytes, .. } => {
                let text = std::str::from_utf8(bytes).map_err(|e| case_error(&case, e))?;
                let scene = Scene::from_json_str(text).map_err(|e| scene_error(&case, e))?;
                Prepared::with_scene(case, scene)
            }
            CaseSource::Catalogue(name) => {
                let scene = lash_model::cases::press_catalogue()
                    .into_iter()
                    .find_map(|(n, s)| (&n == name).then_some(s))
                    .ok_or_else(|| case_error(&case, "not in the press catalogue"))?;
                Prepared::with_scene(case, scene)
            }
        }
    }

    /// A case whose scene was built or modified in code (a sweep point), recorded under the
    /// base case's name and hash.
    pub fn with_scene(case: Case, scene: Scene) -> Result<Prepared, Error> {
        let mech = Mechanism::from_scene(&scene).map_err(|e| scene_error(&case, e))?;
        let info = mechanism_info(&scene, &mech);
        Ok(Prepared {
            case,
            model: Model::Mechanism(Box::new(scene)),
            info: Some(info),
        })
    }

    /// The scene, for mechanism cases.
    pub fn scene(&self) -> Option<&Scene> {
        match &self.model {
            Model::Mechanism(s) => Some(s),
            Model::TestSet(_) => None,
        }
    }

    /// The test problem, for built-in cases.
    pub fn test_problem(&self) -> Option<testset::TestProblem> {
        match self.model {
            Model::TestSet(n) => testset::by_name(n),
            Model::Mechanism(_) => None,
        }
    }

    /// State dimension.
    pub fn dim(&self) -> usize {
        match (&self.info, self.test_problem()) {
            (Some(i), _) => i.dim,
            (None, Some(p)) => p.y0.len(),
            (None, None) => 0,
        }
    }

    /// Names of the state components (`<body>.x`, … for a scene; `y0`, `y1`, … for a test
    /// problem).
    pub fn state_names(&self) -> Vec<String> {
        match &self.info {
            Some(i) => i.state_names.clone(),
            None => (0..self.dim()).map(|i| format!("y{i}")).collect(),
        }
    }

    /// The time span of a run, with an optional end-time override (mechanisms only).
    pub fn t_span(&self, t_end: Option<f64>) -> Result<(f64, f64), Error> {
        match (&self.info, self.test_problem()) {
            (Some(i), _) => {
                let te = t_end.unwrap_or(i.t_end);
                if !(te.is_finite() && te > i.t_start) {
                    return Err(OptionError::leading(
                        "t_end",
                        format!(
                            " must be a finite time after the start {} s, got {te}",
                            i.t_start
                        ),
                    )
                    .into());
                }
                Ok((i.t_start, te))
            }
            (None, Some(p)) => {
                if t_end.is_some() {
                    return Err(OptionError::leading(
                        "t_end",
                        format!(
                            " does not apply to {}: its reference solution holds at t = {:e}",
                            self.case.name, p.t_end
                        ),
                    )
                    .into());
                }
                Ok((p.t0, p.t_end))
            }
            (None, None) => Err(Error::Internal("case without a model".into())),
        }
    }

    /// The default absolute tolerance for relative tolerance `rtol` (module doc).
    pub fn default_atol(&self, rtol: f64) -> Atol {
        match (&self.info, self.test_problem()) {
            (Some(i), _) => {
                let l = i.clearance_min.unwrap_or(DEFAULT_LENGTH_SCALE);
                let w = i.crank_speed.unwrap_or(1.0);
                let nq = i.dim / 2;
                Atol::Vector(
                    (0..i.dim)
                        .map(|k| if k < nq { rtol * l } else { rtol * l * w })
                        .collect(),
                )
            }
            (None, Some(p)) => Atol::Scalar(p.atol),
            (None, None) => Atol::default(),
        }
    }

    /// The default options of this case (module doc).
    pub fn default_options(&self) -> SolverOptions {
        match &self.info {
            Some(i) => {
                let mut o = SolverOptions::with_method(DEFAULT_METHOD);
                o.rtol = DEFAULT_RTOL;
                o.atol = self.default_atol(DEFAULT_RTOL);
                o.event_samples = DEFAULT_EVENT_SAMPLES;
                o.h_max = match (i.period, i.clearance_min) {
                    (Some(t), Some(_)) => t * H_MAX_PER_PERIOD,
                    _ => f64::INFINITY,
                };
                o.max_steps = DEFAULT_MAX_STEPS;
                o.divergence_bound = MECHANISM_DIVERGENCE_BOUND;
                o.rk4_instability_steps = MECHANISM_RK4_INSTABILITY_STEPS;
                o
            }
            None => {
                let mut o = SolverOptions::with_method(TESTSET_METHOD);
                o.rtol = TESTSET_RTOL;
                o.atol = self.default_atol(TESTSET_RTOL);
                o
            }
        }
    }

    /// The case's defaults with the solver choice laid over them: atol follows rtol unless
    /// the choice gives atol; a fixed-step method runs without event location, an adaptive
    /// one with it. Inconsistent options (an atol array of the wrong length) are usage errors.
    pub fn options(&self, choice: &SolverChoice) -> Result<SolverOptions, Error> {
        let base = self.default_options();
        let mut o = choice.apply(&base)?;
        self.finish_options(&mut o, choice.atol.is_some())?;
        Ok(o)
    }

    /// Options for `method` at tolerance `rtol` (adaptive) or step `step` (fixed-step), the
    /// rest as the defaults: what compare and work-precision run.
    pub fn options_for(
        &self,
        method: Method,
        rtol: Option<f64>,
        step: Option<f64>,
        controller: Option<lash_solver::ControllerKind>,
    ) -> Result<SolverOptions, Error> {
        let choice = SolverChoice {
            method: Some(method),
            rtol: rtol.filter(|_| !method.is_fixed_step()),
            step: step.filter(|_| method.is_fixed_step()),
            controller,
            ..Default::default()
        };
        self.options(&choice)
    }

    fn finish_options(&self, o: &mut SolverOptions, atol_given: bool) -> Result<(), Error> {
        if !o.method.is_fixed_step() && !atol_given {
            o.atol = self.default_atol(o.rtol);
        }
        if self.info.is_some() {
            o.events = !o.method.is_fixed_step();
        }
        Ok(o.validate(self.dim())?)
    }

    /// The crank period, if the scene has a crank driver.
    pub fn period(&self) -> Option<f64> {
        self.info.as_ref().and_then(|i| i.period)
    }

    /// The metrics window of a run ending at `t_end`: the last revolution, or the whole run
    /// when it is shorter or there is no crank driver.
    pub fn metrics_window(&self, t_start: f64, t_end: f64) -> Window {
        let span = t_end - t_start;
        let period = self.period().map_or(span, |t| t.min(span));
        Window { t_end, period }
    }
}

fn mechanism_info(scene: &Scene, mech: &Mechanism) -> MechanismInfo {
    let w = mech.crank_speed().filter(|w| *w != 0.0).map(f64::abs);
    let mut c_min: Option<f64> = None;
    let mut dry = false;
    for j in &scene.joints {
        if let JointSpec::Clearance(c) = j {
            let c_k = c.bearing.radius - c.journal.radius;
            c_min = Some(c_min.map_or(c_k, |m| m.min(c_k)));
            dry |= c.film.is_none();
        }
    }
    let roles = mech.roles();
    let joint =
        roles
            .clearance_joint
            .zip(roles.clearance_index)
            .and_then(|(j, index)| match &scene.joints[j] {
                JointSpec::Clearance(c) => Some(JointInfo {
                    index,
                    clearance: c.bearing.radius - c.journal.radius,
                    lubricated: c.film.is_some(),
                }),
                _ => None,
            });
    // y = (q, q̇), q = (x, y, θ) per integrated body (docs/model.md §1).
    let bodies = mech.integrated_bodies();
    let mut state_names: Vec<String> = Vec::with_capacity(mech.dim());
    for suffixes in [["x", "y", "theta"], ["vx", "vy", "omega"]] {
        for b in &bodies {
            state_names.extend(suffixes.iter().map(|s| format!("{b}.{s}")));
        }
    }
    if state_names.len() != mech.dim() {
        state_names = (0..mech.dim()).map(|i| format!("y{i}")).collect();
    }
    MechanismInfo {
        period: w.map(|w| 2.0 * std::f64::consts::PI / w),
        crank_speed: w,
        t_start: mech.t_start(),
        t_end: mech.t_end(),
        clearance_min: c_min,
        joint,
        has_dry_joint: dry,
        dim: mech.dim(),
        has_ideal: mech.ideal_slider_crank().is_some(),
        state_names,
        event_names: (0..mech.n_events())
            .filter_map(|i| mech.event_name(i))
            .map(|(kind, name)| (kind, name.to_string()))
            .collect(),
    }
}

/// Longest trajectory a run writes, rows: beyond it a run is refused (exit 2) and asks to be
/// thinned. At the press's 47 columns a row is about 1 KB of CSV, so this is about 100 GB, a
/// file no script reads whole.
pub const MAX_TRAJECTORY_ROWS: u64 = 100_000_000;

/// The steps the f64 time axis must resolve: 16 ε |t| (the smallest step the solvers take at
/// time t, `lash_solver` step floor) must stay below this fraction of the shortest time the
/// run must resolve (module doc, "Checks before a run").
pub const TIME_RESOLUTION: f64 = 1e-3;

/// Default trajectory rows per crank revolution.
pub const SAMPLES_PER_REVOLUTION: usize = 2000;

/// What to run and what to record.
///
/// ```text
/// opts (method, tolerances, …; opts.output is ignored: the grids below are recorded),
/// t_end override, trajectory grid, extra output times, energy on/off, events kept,
/// the whole run's wall-clock deadline
/// trajectory grid: trajectory_points (a total, both ends) | output_every DT | samples per
///   revolution N (default 2000) | 4001 points without a crank driver
/// ```
///
/// Source: docs/outputs.md (`trajectory.csv`, `metrics`, `energy`).
#[derive(Clone, Debug, PartialEq)]
pub struct RunRequest {
    /// Solver options (from [`Prepared::options`]). Their `max_wall_time` counts from the
    /// start of the integration unless `deadline` is given.
    pub opts: SolverOptions,
    /// End time override, s (mechanisms only). None = the scene's.
    pub t_end: Option<f64>,
    /// Points of the trajectory grid (uniform over the whole run, both ends); Some(0) = no
    /// trajectory. Overrides `output_every` and `samples_per_revolution`. Test problems
    /// record every accepted step instead.
    pub trajectory_points: Option<usize>,
    /// Spacing of the trajectory grid, s: t_start + k·DT, and t_end (mechanisms).
    pub output_every: Option<f64>,
    /// Trajectory rows per crank revolution (scenes with a crank driver); None = 2000.
    pub samples_per_revolution: Option<usize>,
    /// Further output times (sorted, inside the run), sampled like the others.
    pub extra_times: Vec<f64>,
    /// Whether to integrate the power terms for the energy balance (mechanisms only).
    pub energy: bool,
    /// Whether [`RunResult::events`] keeps every event of the run; false: only those of the
    /// metrics window (memory independent of the run's length).
    pub keep_events: bool,
    /// Wall-clock deadline of the whole run (a command's `max_wall_time` counted from its
    /// start): the integration gets what is left, and a run past it fails with
    /// `BudgetExhausted`.
    pub deadline: Option<Instant>,
}

impl RunRequest {
    /// A request with these options and the defaults: the scene's end time, the default
    /// trajectory grid, no extra times, energy on, every event kept, no deadline.
    pub fn new(opts: SolverOptions) -> RunRequest {
        RunRequest {
            opts,
            t_end: None,
            trajectory_points: None,
            output_every: None,
            samples_per_revolution: None,
            extra_times: Vec::new(),
            energy: true,
            keep_events: true,
            deadline: None,
        }
    }
}

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
    pub window: Vec<Sample>,
    /// The trajectory's rows ([`simulate`]); empty when they went to a sink
    /// ([`simulate_into`]).
    pub trajectory: Columns,
    /// Rows of the trajectory, wherever they went.
    pub trajectory_rows: usize,
    /// Samples at the extra times.
    pub extra: Vec<Sample>,
    /// States at the extra times.
    pub extra_states: Solution,
    /// Events: located ones, or crossings at the step ends of a run without location (all of
    /// them, or those of the metrics window: [`RunRequest::keep_events`]).
    pub events: Vec<EventRecord>,
    /// Energy totals over the whole run (mechanisms with `energy`).
    pub energy: Option<EnergyTotals>,
    /// The closed-form ideal slider-crank of the scene, if it is one.
    pub ideal: Option<IdealSliderCrank>,
    /// The metrics window.
    pub metrics_window: Option<Window>,
    /// Power evaluations spent on the energy quadrature.
    pub energy_evals: usize,
    /// Output evaluations spent on the extrema over the dense output, and their searches.
    pub peak_evals: (usize, usize),
}

impl RunResult {
    /// Writes the figures, trajectory.csv (from the collected rows; none when they went to a
    /// sink) and summary.json into `dir` (report::write_run: summary last).
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, Error> {
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

/// Uniform grid of `n ≥ 2` points over [a, b], both ends exact.
pub fn uniform_grid(a: f64, b: f64, n: usize) -> Vec<f64> {
    let g = Grid::uniform(a, b, n.max(2));
    (0..g.n).map(|i| g.time(i)).collect()
}

/// The trajectory's output times, computed one at a time (never held as a whole).
///
/// ```text
/// uniform:  t_i = a + (b − a) i/(n − 1), t_{n−1} = b
/// spaced:   t_i = a + i·dt for i < n − 1, t_{n−1} = b
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
struct Grid {
    a: f64,
    b: f64,
    n: usize,
    dt: Option<f64>,
}

impl Grid {
    fn uniform(a: f64, b: f64, n: usize) -> Grid {
        Grid { a, b, n, dt: None }
    }

    fn time(&self, i: usize) -> f64 {
        if i + 1 == self.n {
            return self.b;
        }
        match self.dt {
            Some(dt) => self.a + dt * i as f64,
            None => self.a + (self.b - self.a) * i as f64 / (self.n - 1) as f64,
        }
    }

    /// The shortest spacing of the grid (∞ with fewer than two points).
    fn spacing(&self) -> f64 {
        match (self.n, self.dt) {
            (0 | 1, _) => f64::INFINITY,
            (_, Some(dt)) => dt.min(self.b - self.time(self.n - 2)),
            (n, None) => (self.b - self.a) / (n - 1) as f64,
        }
    }
}

/// Runs a case, keeping the trajectory's rows in memory ([`RunResult::trajectory`]). Solver
/// failures are `Error::Solver` (exit 3); nothing is written.
pub fn simulate(p: &Prepared, req: &RunRequest) -> Result<RunResult, Error> {
    let mut rows = Columns::new();
    let mut r = simulate_into(p, req, &mut rows)?;
    r.trajectory = rows;
    Ok(r)
}

/// Runs a case, pushing the trajectory's rows into `sink` as the run goes (module doc);
/// memory does not grow with the run's length unless the sink keeps the rows. On a solver
/// failure (`Error::Solver`, exit 3) the sink holds the rows up to it, and has been finished.
pub fn simulate_into(
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

/// The solver options of a request: its `max_wall_time` cut to what is left before its
/// deadline; a deadline already past is `BudgetExhausted` at (t0, y0).
fn options_within(req: &RunRequest, t0: f64, y0: &[f64]) -> Result<SolverOptions, Error> {
    let mut opts = req.opts.clone();
    if let Some(d) = req.deadline {
        let left = d.saturating_duration_since(Instant::now()).as_secs_f64();
        if !(left > 0.0) {
            return Err(Error::Solver(SolveError::BudgetExhausted {
                t: t0,
                y: y0.to_vec(),
                reason: format!(
                    "wall-clock budget of {} s used before the integration started",
                    opts.max_wall_time.unwrap_or_default()
                ),
            }));
        }
        opts.max_wall_time = Some(left);
    }
    Ok(opts)
}

fn check_times(times: &[f64], t0: f64, t_end: f64) -> Result<(), Error> {
    if times.windows(2).any(|w| !(w[1] >= w[0]))
        || times
            .iter()
            .any(|t| !(t.is_finite() && *t >= t0 && *t <= t_end))
    {
        return Err(Error::Internal(format!(
            "extra output times must be sorted and inside [{t0}, {t_end}]"
        )));
    }
    Ok(())
}

/// The checks of a request against its case before anything runs (module doc, "Checks before
/// a run"); returns the trajectory grid.
fn plan_run(p: &Prepared, req: &RunRequest, t0: f64, t_end: f64) -> Result<Grid, Error> {
    let o = &req.opts;
    let span = t_end - t0;
    let period = p.period();
    if let Some(h) = o.step.filter(|_| o.method.is_fixed_step()) {
        if h > span {
            return Err(OptionError::leading(
                "step",
                format!(
                    " {} s is longer than the run ({} s from t_start {} s to t_end {} s)",
                    fmt_num(h),
                    fmt_num(span),
                    fmt_num(t0),
                    fmt_num(t_end)
                ),
            )
            .into());
        }
    }
    if p.info.is_none() {
        return Ok(Grid::uniform(t0, t_end, 0));
    }
    // The trajectory grid.
    if let Some(n) = req.samples_per_revolution {
        if period.is_none() {
            return Err(OptionError::leading(
                "samples_per_revolution",
                format!(" needs a crank driver, and {} has none", p.case.name),
            )
            .text("; ")
            .name("output_every")
            .text(" spaces rows in time")
            .into());
        }
        if n == 0 {
            return Err(OptionError::leading("samples_per_revolution", " must be >= 1").into());
        }
    }
    if let Some(dt) = req.output_every {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(OptionError::leading(
                "output_every",
                format!(" must be finite and > 0, got {dt}"),
            )
            .into());
        }
    }
    let rows: f64 = match (req.trajectory_points, req.output_every, period) {
        (Some(n), _, _) => n as f64,
        (None, Some(dt), _) => (span / dt * (1.0 - 1e-9)).ceil().max(1.0) + 1.0,
        (None, None, Some(t)) => {
            let n = req.samples_per_revolution.unwrap_or(SAMPLES_PER_REVOLUTION) as f64;
            1.0 + (n * span / t).round().max(1.0)
        }
        (None, None, None) => (2 * (GRID_POINTS - 1) + 1) as f64,
    };
    if rows > MAX_TRAJECTORY_ROWS as f64 {
        let thin = if period.is_some() {
            OptionError::new("samples_per_revolution")
                .text(format!(
                    "the trajectory would have {} rows, more than the {} lash writes: thin it \
                     with ",
                    fmt_count(rows),
                    fmt_count(MAX_TRAJECTORY_ROWS as f64)
                ))
                .name("samples_per_revolution")
                .text(" or ")
        } else {
            OptionError::new("output_every").text(format!(
                "the trajectory would have {} rows, more than the {} lash writes: thin it with ",
                fmt_count(rows),
                fmt_count(MAX_TRAJECTORY_ROWS as f64)
            ))
        };
        return Err(thin
            .name("output_every")
            .text(", or shorten ")
            .name("t_end")
            .into());
    }
    let n = rows as usize;
    let grid = match (req.trajectory_points, req.output_every) {
        (None, Some(dt)) => Grid {
            a: t0,
            b: t_end,
            n,
            dt: Some(dt),
        },
        _ => Grid::uniform(t0, t_end, n),
    };
    // The time axis: f64 must resolve the shortest time the run must resolve.
    let mut need = vec![(grid.spacing(), "the trajectory's spacing".to_string())];
    if let Some(t) = period {
        need.push((
            t / (GRID_POINTS - 1) as f64,
            "the metrics grid's spacing T/2000".into(),
        ));
    }
    if o.h_max.is_finite() {
        need.push((o.h_max, "h_max".into()));
    }
    if let Some(h) = o.step.filter(|_| o.method.is_fixed_step()) {
        need.push((h, "the RK4 step".into()));
    }
    need.push((span / 100.0, "a hundredth of the run".into()));
    let (need, what) = need
        .into_iter()
        .fold((f64::INFINITY, String::new()), |a, b| {
            if b.0 < a.0 {
                b
            } else {
                a
            }
        });
    let floor_at = |t: f64| 16.0 * f64::EPSILON * t.abs();
    let floor = floor_at(t0).max(floor_at(t_end));
    if floor > TIME_RESOLUTION * need {
        // Blame t_start when it alone is too far out, else the end time.
        let start = floor_at(t0) > TIME_RESOLUTION * need;
        let text = format!(
            " = {:.6e} s is too far from 0 for f64 time: steps there are at least {:.2e} s \
             (16 ε |t|), but the run must resolve {:.2e} s ({what}); shift the scene's times \
             toward 0",
            if start { t0 } else { t_end },
            floor,
            need
        );
        let scene_field =
            |field: &str| Err(Error::Input(format!("case {}: {field}{text}", p.case.name)));
        return if start {
            scene_field("t_start")
        } else if req.t_end.is_some() {
            Err(OptionError::leading("t_end", text).into())
        } else if p.scene().is_some_and(|s| s.t_end.is_none()) {
            scene_field("revolutions (t_end)")
        } else {
            scene_field("t_end")
        };
    }
    Ok(grid)
}

/// A count in words a reader takes in at once: 5e9, 2.5e8, 40000.
fn fmt_count(x: f64) -> String {
    if x < 1e6 {
        format!("{x:.0}")
    } else {
        let s = format!("{x:.1e}");
        s.replace(".0e", "e")
    }
}

/// Receives what a run produces, as `drive` integrates (module doc).
trait Observer {
    /// The next requested output time (sorted), if any.
    fn next_time(&self) -> Option<f64>;
    /// The state at the next requested output time.
    fn output(&mut self, t: f64, y: &[f64]) -> Result<(), Error>;
    /// An accepted step [ta, tb] (`cut`: ended at an event); `dense(t, out)` is its dense
    /// output; `y` the state at tb (after the event hook).
    fn step(
        &mut self,
        ta: f64,
        tb: f64,
        cut: bool,
        y: &[f64],
        dense: &dyn Fn(f64, &mut [f64]),
    ) -> Result<(), Error>;
    /// An event (located, or a crossing between step ends).
    fn event(&mut self, hit: EventHit);
}

/// What the integration loop produced.
struct Drive {
    stats: Stats,
    wall: f64,
    t_final: f64,
    y_final: Vec<f64>,
    located: usize,
}

impl Drive {
    /// summary.json of the run, without metrics or test-problem fields.
    fn summary(&self, p: &Prepared, opts: &SolverOptions, t_end: f64) -> Summary {
        Summary::new(&p.case, opts, t_end, self.stats, self.wall, self.located)
    }
}

/// Integrates from t0 to t_end, handing the observer every requested output time (as soon as
/// the dense output covers it), every accepted step and every event.
fn drive<S: OdeSystem + ?Sized>(
    sys: &S,
    t0: f64,
    t_end: f64,
    y0: &[f64],
    opts: &SolverOptions,
    obs: &mut dyn Observer,
) -> Result<Drive, Error> {
    let n = y0.len();
    let mut wall = Duration::ZERO;
    let clock = Instant::now();
    let problem = Problem::new(sys, opts)?;
    let mut it = problem.integrator(t0, t_end, y0)?;
    wall += clock.elapsed();
    while let Some(t) = obs.next_time().filter(|t| *t <= t0) {
        obs.output(t, y0)?;
    }
    let m = sys.n_events();
    let detect = !opts.events && m > 0;
    let mut g_prev = vec![0.0; if detect { m } else { 0 }];
    let mut g_now = g_prev.clone();
    let mut t_g = t0;
    if detect {
        sys.events(t0, y0, &mut g_prev);
    }
    let mut located = 0;
    let mut buf = vec![0.0; n];
    loop {
        let clock = Instant::now();
        let outcome = it.step()?;
        wall += clock.elapsed();
        let (ta, tb) = (it.t_prev(), it.t());
        while let Some(t) = obs.next_time().filter(|t| *t <= tb) {
            it.interpolate(t, &mut buf);
            obs.output(t, &buf)?;
        }
        let cut = matches!(outcome, StepOutcome::Event { .. });
        obs.step(ta, tb, cut, it.y(), &|t, out| it.interpolate(t, out))?;
        if detect {
            sys.events(tb, it.y(), &mut g_now);
            for i in 0..m {
                let (a, b) = (g_prev[i], g_now[i]);
                if (a < 0.0 && b > 0.0) || (a > 0.0 && b < 0.0) {
                    obs.event(EventHit {
                        index: i,
                        t: t_g + (tb - t_g) * a / (a - b),
                        rising: b > 0.0,
                    });
                }
                if b != 0.0 {
                    g_prev[i] = b;
                }
            }
            t_g = tb;
        }
        match outcome {
            StepOutcome::Accepted { .. } => {}
            StepOutcome::Event {
                hits: h, stopped, ..
            } => {
                located += h.len();
                for hit in h {
                    obs.event(hit);
                }
                if stopped {
                    break;
                }
            }
            StepOutcome::StopTime { .. } => break,
        }
        if it.is_finished() {
            break;
        }
    }
    // Requested times past a stopping event get the final state.
    while let Some(t) = obs.next_time() {
        obs.output(t, it.y())?;
    }
    Ok(Drive {
        stats: it.stats(),
        wall: wall.as_secs_f64(),
        t_final: it.t(),
        y_final: it.y().to_vec(),
        located,
    })
}

fn checked_power(pw: PowerFn<'_>, t: f64, y: &[f64]) -> Result<[f64; 4], Error> {
    let v = pw(t, y);
    if v.iter().all(|x| x.is_finite()) {
        Ok(v)
    } else {
        Err(Error::Internal(format!(
            "energy: power terms {v:?} not finite at t = {t:e}"
        )))
    }
}

type PowerFn<'a> = &'a dyn Fn(f64, &[f64]) -> [f64; 4];

fn empty_solution(dim: usize) -> Solution {
    Solution {
        dim,
        ..Default::default()
    }
}

/// The observer of a test problem: a row per accepted step (the start included), states at
/// the extra times.
struct TestSetRun<'a> {
    header: Header,
    sink: &'a mut dyn TrajectorySink,
    rows: usize,
    row: Vec<f64>,
    extra_times: &'a [f64],
    next: usize,
    extra_states: Solution,
}

impl TestSetRun<'_> {
    fn push(&mut self, t: f64, y: &[f64]) -> Result<(), Error> {
        self.row.clear();
        self.row.push(t);
        self.row.extend([f64::NAN; 10]);
        self.row.push(0.0);
        self.row.push(f64::NAN);
        self.row.extend_from_slice(y);
        self.header.check(&self.row)?;
        self.sink.row(&self.row)?;
        self.rows += 1;
        Ok(())
    }
}

impl Observer for TestSetRun<'_> {
    fn next_time(&self) -> Option<f64> {
        self.extra_times.get(self.next).copied()
    }
    fn output(&mut self, t: f64, y: &[f64]) -> Result<(), Error> {
        self.extra_states.t.push(t);
        self.extra_states.y.extend_from_slice(y);
        self.next += 1;
        Ok(())
    }
    fn step(
        &mut self,
        _: f64,
        tb: f64,
        _: bool,
        y: &[f64],
        _: &dyn Fn(f64, &mut [f64]),
    ) -> Result<(), Error> {
        self.push(tb, y)
    }
    fn event(&mut self, _: EventHit) {}
}

fn simulate_testset(
    p: &Prepared,
    req: &RunRequest,
    t0: f64,
    t_end: f64,
    sink: &mut dyn TrajectorySink,
) -> Result<RunResult, Error> {
    let prob = p
        .test_problem()
        .ok_or_else(|| Error::Internal("not a test problem".into()))?;
    check_times(&req.extra_times, t0, t_end)?;
    plan_run(p, req, t0, t_end)?;
    let opts = &options_within(req, t0, &prob.y0)?;
    let n = prob.y0.len();
    let mut fixed = [false; 13];
    fixed[0] = true;
    fixed[11] = true;
    let header = Header::new(fixed, (0..n).map(|i| format!("y{i}")).collect())?;
    sink.start(&header)?;
    let mut obs = TestSetRun {
        header,
        sink,
        rows: 0,
        row: Vec::with_capacity(13 + n),
        extra_times: &req.extra_times,
        next: 0,
        extra_states: empty_solution(n),
    };
    obs.push(t0, &prob.y0)?;
    let d = drive(&*prob.system, t0, t_end, &prob.y0, opts, &mut obs)?;
    let mut extra_states = obs.extra_states;
    extra_states.stats = d.stats;
    extra_states.t_final = d.t_final;
    extra_states.y_final = d.y_final.clone();
    let mut summary = d.summary(p, opts, t_end);
    let err = testset::reference_error(&d.y_final, &prob.reference, prob.atol);
    if !err.is_finite() {
        return Err(Error::Internal(format!(
            "{}: reference error is not finite (final state {:?})",
            p.case.name, d.y_final
        )));
    }
    summary.final_state = Some(d.y_final.clone());
    summary.reference_error = Some(err);
    Ok(RunResult {
        summary,
        window: Vec::new(),
        trajectory: Columns::new(),
        trajectory_rows: obs.rows,
        extra: Vec::new(),
        extra_states,
        events: Vec::new(),
        energy: None,
        ideal: None,
        metrics_window: None,
        energy_evals: 0,
        peak_evals: (0, 0),
    })
}

/// The role-based view of one mechanism evaluation: maps `Mechanism::outputs` to a metrics
/// [`Sample`] through the scene's roles (slider, crank driver, clearance joint), with the ideal
/// closed-form slider acceleration beside. Used by every command that samples a run.
pub struct Sampler<'a> {
    mech: &'a Mechanism,
    ideal: Option<IdealSliderCrank>,
    clearance_index: Option<usize>,
    driver_pos: Option<usize>,
}

impl<'a> Sampler<'a> {
    /// The sampler of `mech`, built from `scene` (the scene the mechanism was made from).
    pub fn new(mech: &'a Mechanism, scene: &Scene) -> Sampler<'a> {
        let roles = mech.roles();
        let driver_pos = roles.crank_driver.map(|j| {
            scene.joints[..j]
                .iter()
                .filter(|x| matches!(x, JointSpec::Driver(_)))
                .count()
        });
        Sampler {
            mech,
            ideal: mech.ideal_slider_crank(),
            clearance_index: roles.clearance_index,
            driver_pos,
        }
    }

    /// One sample at (t, y).
    pub fn sample(&self, t: f64, y: &[f64]) -> Sample {
        self.of_outputs(t, &self.mech.outputs(t, y))
    }

    /// The sample of one evaluation `o` at time t.
    pub fn of_outputs(&self, t: f64, o: &Outputs) -> Sample {
        let c = self.clearance_index.and_then(|k| o.clearance.get(k));
        let ideal_a = match (&self.ideal, o.crank_angle, o.slider_a) {
            (Some(i), Some(phi), Some(_)) => Some(i.a_at(i.theta_of_crank_angle(phi))),
            _ => None,
        };
        Sample {
            t,
            crank_angle: o.crank_angle,
            slider_x: o.slider_x,
            slider_v: o.slider_v,
            slider_a: o.slider_a,
            ex_over_c: c.map(|c| c.ex_over_c),
            ey_over_c: c.map(|c| c.ey_over_c),
            eps: c.map(|c| c.eps),
            delta: c.map(|c| c.delta),
            contact_force: c.map(|c| c.contact_force),
            friction_force: c.map(|c| c.friction_force),
            film_force: c.map(|c| c.film_force),
            constraint_violation: o.constraint_violation,
            driver_torque: self
                .driver_pos
                .and_then(|i| o.driver_torques.get(i).copied()),
            ideal_slider_a: ideal_a,
        }
    }

    /// Which fixed trajectory columns ([`crate::report::trajectory::COLUMNS`]) this mechanism fills.
    pub fn fixed_present(&self) -> [bool; 13] {
        let roles = self.mech.roles();
        let (crank, slider, joint) = (
            roles.crank_body.is_some(),
            roles.slider.is_some(),
            self.clearance_index.is_some(),
        );
        [
            true,
            crank,
            slider,
            slider,
            slider,
            joint,
            joint,
            joint,
            joint,
            joint,
            joint,
            true,
            self.driver_pos.is_some(),
        ]
    }
}

/// The fixed trajectory columns of a sample (NaN where absent), in the order of
/// [`crate::report::trajectory::COLUMNS`].
fn fixed_values(s: &Sample) -> [f64; 13] {
    let v = |x: Option<f64>| x.unwrap_or(f64::NAN);
    [
        s.t,
        v(s.crank_angle),
        v(s.slider_x),
        v(s.slider_v),
        v(s.slider_a),
        v(s.ex_over_c),
        v(s.ey_over_c),
        v(s.delta),
        v(s.contact_force),
        v(s.friction_force),
        v(s.film_force),
        s.constraint_violation,
        v(s.driver_torque),
    ]
}

/// Output lists of a mechanism run, merged in time order.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum List {
    Window,
    Trajectory,
    Extra,
}

/// The observer of a mechanism run (module doc): rows into the sink, samples of the window
/// and at the extra times, the extrema over the dense output, the energy quadrature, events.
struct MechanismRun<'a> {
    mech: &'a Mechanism,
    sampler: Sampler<'a>,
    header: Header,
    sink: &'a mut dyn TrajectorySink,
    row: Vec<f64>,
    // The three output lists, merged lazily.
    wgrid: Vec<f64>,
    tgrid: Grid,
    extra_times: &'a [f64],
    idx: [usize; 3],
    t0: f64,
    t_end: f64,
    window: Vec<Sample>,
    extra: Vec<Sample>,
    extra_states: Solution,
    rows: usize,
    // Extrema over the window's dense output.
    w0: f64,
    peaks: Peaks,
    cv_max: f64,
    has_slider: bool,
    n_clr: usize,
    // Energy.
    quad: Option<Quadrature>,
    power: Option<PowerFn<'a>>,
    // Events.
    names: Vec<(&'static str, Option<usize>)>,
    keep_events: bool,
    events: Vec<EventRecord>,
    ybuf: Vec<f64>,
}

impl MechanismRun<'_> {
    fn next(&self) -> Option<(f64, List)> {
        let w = self.wgrid.get(self.idx[0]).map(|&t| (t, List::Window));
        let tr =
            (self.idx[1] < self.tgrid.n).then(|| (self.tgrid.time(self.idx[1]), List::Trajectory));
        let x = self.extra_times.get(self.idx[2]).map(|&t| (t, List::Extra));
        [w, tr, x]
            .into_iter()
            .flatten()
            .fold(None, |best: Option<(f64, List)>, c| match best {
                Some(b) if b.0 <= c.0 => Some(b),
                _ => Some(c),
            })
    }

    /// The quantities whose extrema the metrics take (module doc): slider a and −a, then per
    /// clearance joint ε, δ, F_N, |F_film|.
    fn quantities(&mut self, o: &Outputs) -> Result<Vec<f64>, Error> {
        let mut v = Vec::with_capacity(2 + 4 * self.n_clr);
        if self.has_slider {
            let a = o.slider_a.unwrap_or(f64::NAN);
            v.extend([a, -a]);
        }
        for c in &o.clearance {
            v.extend([c.eps, c.delta, c.contact_force, c.film_force.abs()]);
        }
        if v.iter().any(|x| !x.is_finite()) || !o.constraint_violation.is_finite() {
            return Err(Error::Internal(format!(
                "metrics: a non-finite output on the dense output: {v:?}, ‖Φ‖ = {}",
                o.constraint_violation
            )));
        }
        self.cv_max = self.cv_max.max(o.constraint_violation);
        Ok(v)
    }

    fn dense_extremes(&self, scene: &Scene) -> DenseExtremes {
        let m = self.peaks.max();
        let found = |x: f64| x.is_finite().then_some(x);
        let (slider_acc, off) = if self.has_slider {
            (found(-m[1]).zip(found(m[0])), 2)
        } else {
            (None, 0)
        };
        let joints = scene
            .joints
            .iter()
            .filter_map(|j| match j {
                JointSpec::Clearance(c) => Some(c),
                _ => None,
            })
            .enumerate()
            .map(|(k, c)| {
                let q = &m[off + 4 * k..off + 4 * k + 4];
                JointExtremes {
                    name: c.name.clone(),
                    clearance: c.bearing.radius - c.journal.radius,
                    lubricated: c.film.is_some(),
                    eps_max: q[0],
                    delta_max: q[1],
                    contact_force_max: q[2],
                    film_force_max: q[3],
                }
            })
            .collect();
        DenseExtremes {
            slider_acc,
            constraint_violation_max: self.cv_max,
            joints,
        }
    }
}

impl Observer for MechanismRun<'_> {
    fn next_time(&self) -> Option<f64> {
        // The metrics grid may start a few ulps before t0 (t_end − T): clamp into the run.
        self.next().map(|(t, _)| t.clamp(self.t0, self.t_end))
    }

    fn output(&mut self, _t: f64, y: &[f64]) -> Result<(), Error> {
        let Some((t_req, list)) = self.next() else {
            return Err(Error::Internal(
                "an output past the last requested time".into(),
            ));
        };
        let o = self.mech.outputs(t_req, y);
        let s = self.sampler.of_outputs(t_req, &o);
        match list {
            List::Window => {
                self.window.push(s);
                self.idx[0] += 1;
            }
            List::Extra => {
                self.extra_states.t.push(t_req);
                self.extra_states.y.extend_from_slice(y);
                self.extra.push(s);
                self.idx[2] += 1;
            }
            List::Trajectory => {
                self.row.clear();
                self.row.extend(fixed_values(&s));
                o.column_values(&mut self.row);
                self.header.check(&self.row)?;
                self.sink.row(&self.row)?;
                self.rows += 1;
                self.idx[1] += 1;
            }
        }
        Ok(())
    }

    fn step(
        &mut self,
        ta: f64,
        tb: f64,
        cut: bool,
        _y: &[f64],
        dense: &dyn Fn(f64, &mut [f64]),
    ) -> Result<(), Error> {
        if let (Some(q), Some(pw)) = (self.quad.as_mut(), self.power) {
            let buf = &mut self.ybuf;
            let mut node = |t: f64| -> Result<[f64; 4], Error> {
                dense(t, buf);
                checked_power(pw, t, buf)
            };
            q.step(ta, tb, cut, &mut node)?;
        }
        if tb >= self.w0 {
            let a = ta.max(self.w0);
            let mut peaks = std::mem::replace(&mut self.peaks, Peaks::new(0));
            let mut buf = std::mem::take(&mut self.ybuf);
            let r = peaks.step(a, tb, &mut |t| {
                dense(t, &mut buf);
                let o = self.mech.outputs(t, &buf);
                self.quantities(&o)
            });
            self.ybuf = buf;
            self.peaks = peaks;
            r?;
        }
        Ok(())
    }

    fn event(&mut self, h: EventHit) {
        if !self.keep_events && h.t < self.w0 {
            return;
        }
        let (kind, joint) = self.names.get(h.index).copied().unwrap_or(("", None));
        let quantity = match kind {
            "contact" => EventQuantity::Penetration,
            "eps_cap" => EventQuantity::FilmCap,
            _ => EventQuantity::Other,
        };
        self.events.push(EventRecord {
            t: h.t,
            quantity,
            rising: h.rising,
            joint,
            index: h.index,
        });
    }
}

fn simulate_mechanism(
    p: &Prepared,
    scene: &Scene,
    req: &RunRequest,
    t0: f64,
    t_end: f64,
    sink: &mut dyn TrajectorySink,
) -> Result<RunResult, Error> {
    let info = p
        .info
        .as_ref()
        .ok_or_else(|| Error::Internal("mechanism without info".into()))?;
    check_times(&req.extra_times, t0, t_end)?;
    let tgrid = plan_run(p, req, t0, t_end)?;
    options_within(req, t0, &[])?;
    let mech = Mechanism::from_scene(scene).map_err(|e| scene_error(&p.case, e))?;
    let opts = &options_within(req, t0, &mech.initial_state())?;
    let sampler = Sampler::new(&mech, scene);
    let window = p.metrics_window(t0, t_end);
    let header = Header::new(sampler.fixed_present(), mech.output_columns())?;
    sink.start(&header)?;
    let y0 = mech.initial_state();
    let n = y0.len();
    let clr_names = mech.clearance_names();
    let names: Vec<(&'static str, Option<usize>)> = (0..mech.n_events())
        .map(|i| match mech.event_name(i) {
            Some((kind, j)) => (kind, clr_names.iter().position(|c| *c == j)),
            None => ("", None),
        })
        .collect();
    let power = |t: f64, y: &[f64]| {
        let p = mech.power(t, y);
        [p.driver, p.contact_damping, p.friction, p.film]
    };
    let power_ref: PowerFn<'_> = &power;
    let max_panel = info
        .period
        .map_or(f64::INFINITY, |t| t * QUADRATURE_PANEL_PER_PERIOD);
    let quad = if req.energy {
        Some(Quadrature::new(
            opts.method.is_fixed_step(),
            max_panel,
            t0,
            checked_power(power_ref, t0, &y0)?,
        ))
    } else {
        None
    };
    let has_slider = mech.roles().slider.is_some();
    let n_clr = clr_names.len();
    let n_q = if has_slider { 2 } else { 0 } + 4 * n_clr;
    let w0 = window.t_end - window.period;
    let mut obs = MechanismRun {
        mech: &mech,
        sampler,
        header,
        sink,
        row: Vec::new(),
        wgrid: metrics::grid(window.t_end, window.period),
        tgrid,
        extra_times: &req.extra_times,
        idx: [0; 3],
        t0,
        t_end,
        window: Vec::with_capacity(GRID_POINTS),
        extra: Vec::with_capacity(req.extra_times.len()),
        extra_states: empty_solution(n),
        rows: 0,
        w0,
        peaks: Peaks::new(n_q),
        cv_max: 0.0,
        has_slider,
        n_clr,
        quad,
        power: req.energy.then_some(power_ref),
        names,
        keep_events: req.keep_events,
        events: Vec::new(),
        ybuf: vec![0.0; n],
    };
    let d = drive(&mech, t0, t_end, &y0, opts, &mut obs)?;
    // The window's grid samples are samples of the extrema too.
    let mut dense = obs.dense_extremes(scene);
    for s in &obs.window {
        if let (Some(a), Some((lo, hi))) = (s.slider_a, dense.slider_acc.as_mut()) {
            *lo = lo.min(a);
            *hi = hi.max(a);
        }
    }
    let mut extra_states = std::mem::replace(&mut obs.extra_states, empty_solution(n));
    extra_states.stats = d.stats;
    extra_states.t_final = d.t_final;
    extra_states.y_final = d.y_final.clone();
    let energy = match obs.quad.as_mut() {
        Some(q) => {
            q.finish();
            let o0 = mech.outputs(t0, &y0);
            let o1 = mech.outputs(d.t_final, &d.y_final);
            Some(EnergyTotals {
                driver_work: q.total[0],
                kinetic_change: o1.kinetic_energy - o0.kinetic_energy,
                potential_change: o1.potential_energy - o0.potential_energy,
                dissipated_damping: q.total[1],
                dissipated_friction: q.total[2],
                dissipated_film: q.total[3],
                quadrature_error: q.err.iter().sum(),
            })
        }
        None => None,
    };
    let energy_evals = obs.quad.as_ref().map_or(0, |q| q.evals);
    let metrics = metrics::compute(
        &obs.window,
        window,
        info.joint,
        &obs.events,
        energy,
        Some(&dense),
    )?;
    let mut summary = d.summary(p, opts, t_end);
    summary.metrics = Some(metrics);
    Ok(RunResult {
        summary,
        window: std::mem::take(&mut obs.window),
        trajectory: Columns::new(),
        trajectory_rows: obs.rows,
        extra: std::mem::take(&mut obs.extra),
        extra_states,
        events: std::mem::take(&mut obs.events),
        energy,
        ideal: obs.sampler.ideal,
        metrics_window: Some(window),
        energy_evals,
        peak_evals: (obs.peaks.evals, obs.peaks.refinements),
    })
}

/// Time integrals of the power terms over accepted steps.
///
/// ```text
/// panel of 5 equally spaced nodes f0..f4, spacing d:
///   S1 = 2d/3 (f0 + 4 f2 + f4),  S2 = d/3 (f0 + 4 f1 + 2 f2 + 4 f3 + f4)
///   value = S2 + (S2 − S1)/15 (Boole's rule),  error estimate |S2 − S1|/15
/// adaptive step [a, b]: ⌈(b − a)/w⌉ panels (w = max_panel), each with 3 interior nodes from
///   the dense output
/// fixed-step method: four consecutive equal steps form one panel (nodes = step ends);
///   a partial group (at the end, or before an unequal or event-cut step) uses Simpson 3/8,
///   Simpson or the trapezoid, error estimated by the difference with the trapezoid
///   (trapezoid alone: d/2 |f1 − f0|)
/// ```
///
/// Source: Boole's rule and Richardson extrapolation of Simpson's rule (Davis & Rabinowitz,
/// Methods of Numerical Integration, §2.2, §6.3).
#[derive(Clone, Debug)]
pub struct Quadrature {
    fixed: bool,
    max_panel: f64,
    group: Vec<(f64, [f64; 4])>,
    /// Integrals so far of (driver, contact damping, friction, film), J.
    pub total: [f64; 4],
    /// Error estimates so far, J.
    pub err: [f64; 4],
    /// Power evaluations so far (the initial one included).
    pub evals: usize,
}

impl Quadrature {
    /// Starts at (t0, P(t0)); `fixed` groups equal steps; a step longer than `max_panel`
    /// (> 0, may be ∞) is split into panels no longer than it.
    pub fn new(fixed: bool, max_panel: f64, t0: f64, p0: [f64; 4]) -> Quadrature {
        Quadrature {
            fixed,
            max_panel,
            group: vec![(t0, p0)],
            total: [0.0; 4],
            err: [0.0; 4],
            evals: 1,
        }
    }

    fn last(&self) -> (f64, [f64; 4]) {
        *self
            .group
            .last()
            .expect("the group always holds its left node")
    }

    /// Adds the accepted step [ta, tb]; `cut` when it ended at an event; `node(t)` evaluates
    /// the power on the step's dense output.
    pub fn step(
        &mut self,
        ta: f64,
        tb: f64,
        cut: bool,
        node: &mut dyn FnMut(f64) -> Result<[f64; 4], Error>,
    ) -> Result<(), Error> {
        let h = tb - ta;
        if h <= 0.0 {
            return Ok(());
        }
        if self.fixed && !cut {
            let k = self.group.len();
            let equal = k < 2 || {
                let d = self.group[1].0 - self.group[0].0;
                (h - d).abs() <= 1e-6 * d
            };
            if equal {
                self.group.push((tb, node(tb)?));
                self.evals += 1;
                if self.group.len() == 5 {
                    self.boole();
                }
                return Ok(());
            }
        }
        self.flush();
        let panels = if self.max_panel.is_finite() {
            ((h / self.max_panel).ceil() as usize).max(1)
        } else {
            1
        };
        let w = h / panels as f64;
        for k in 0..panels {
            let a = self.last();
            let pa = a.0;
            let pb = if k + 1 == panels {
                tb
            } else {
                ta + w * (k + 1) as f64
            };
            let mut nodes = [a; 5];
            for (j, nd) in nodes.iter_mut().enumerate().skip(1) {
                let t = if j == 4 {
                    pb
                } else {
                    pa + (pb - pa) * j as f64 / 4.0
                };
                *nd = (t, node(t)?);
            }
            self.evals += 4;
            self.group = nodes.to_vec();
            self.boole();
        }
        Ok(())
    }

    /// Boole's rule on the five nodes of the group; the group restarts at its last node.
    fn boole(&mut self) {
        let g = &self.group;
        let d = (g[4].0 - g[0].0) / 4.0;
        for c in 0..4 {
            let f: [f64; 5] = std::array::from_fn(|j| g[j].1[c]);
            let s1 = 2.0 * d / 3.0 * (f[0] + 4.0 * f[2] + f[4]);
            let s2 = d / 3.0 * (f[0] + 4.0 * f[1] + 2.0 * f[2] + 4.0 * f[3] + f[4]);
            self.total[c] += s2 + (s2 - s1) / 15.0;
            self.err[c] += (s2 - s1).abs() / 15.0;
        }
        let last = self.last();
        self.group = vec![last];
    }

    /// Integrates a partial group of 2–4 equally spaced nodes.
    fn flush(&mut self) {
        let g = &self.group;
        let k = g.len();
        if k >= 2 {
            let d = (g[k - 1].0 - g[0].0) / (k - 1) as f64;
            for c in 0..4 {
                let f: Vec<f64> = g.iter().map(|x| x.1[c]).collect();
                let trap = d * (f.iter().sum::<f64>() - 0.5 * (f[0] + f[k - 1]));
                let (v, e) = match k {
                    2 => (trap, 0.5 * d * (f[1] - f[0]).abs()),
                    3 => {
                        let s = d / 3.0 * (f[0] + 4.0 * f[1] + f[2]);
                        (s, (s - trap).abs())
                    }
                    _ => {
                        let s = 3.0 * d / 8.0 * (f[0] + 3.0 * f[1] + 3.0 * f[2] + f[3]);
                        (s, (s - trap).abs())
                    }
                };
                self.total[c] += v;
                self.err[c] += e;
            }
        }
        let last = self.last();
        self.group = vec![last];
    }

    /// Integrates what is left at the end of the run.
    pub fn finish(&mut self) {
        self.flush();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn poly(t: f64) -> [f64; 4] {
        // Degree 5: Boole's rule is exact up to degree 5.
        [
            1.0 + t + t * t * t * t * t,
            3.0 * t * t,
            4.0 * t * t * t,
            (2.0 * t).cos(),
        ]
    }

    fn exact(a: f64, b: f64) -> [f64; 4] {
        let f0 = |t: f64| t + t * t / 2.0 + t.powi(6) / 6.0;
        [
            f0(b) - f0(a),
            b.powi(3) - a.powi(3),
            b.powi(4) - a.powi(4),
            ((2.0 * b).sin() - (2.0 * a).sin()) / 2.0,
        ]
    }

    #[test]
    fn boole_panels_integrate_quintics_exactly_on_uneven_steps() {
        let mut q = Quadrature::new(false, f64::INFINITY, 0.0, poly(0.0));
        let ts = [0.0, 0.1, 0.35, 0.4, 1.0, 1.7];
        for w in ts.windows(2) {
            q.step(w[0], w[1], false, &mut |t| Ok(poly(t))).unwrap();
        }
        q.finish();
        let ex = exact(0.0, 1.7);
        for c in 0..3 {
            assert!((q.total[c] - ex[c]).abs() < 1e-13 * ex[c].abs(), "{c}");
            // The error estimate is |S2 − S1|/15: zero for cubics (Simpson exact), not for
            // the quintic.
        }
        assert!(q.err[1] < 1e-15 && q.err[2] < 1e-15);
        assert!(q.err[0] > 0.0);
        // cos: the estimate bounds the actual error of the Boole value.
        let e3 = (q.total[3] - ex[3]).abs();
        assert!(e3 <= q.err[3], "{e3} vs {}", q.err[3]);
        assert_eq!(q.evals, 1 + 4 * 5);
    }

    #[test]
    fn long_steps_are_split_into_panels() {
        // One step over [0, 3] of cos(2t): one panel vs 12 panels (max_panel 0.25).
        let integrate = |max_panel: f64| {
            let mut q = Quadrature::new(false, max_panel, 0.0, poly(0.0));
            q.step(0.0, 3.0, false, &mut |t| Ok(poly(t))).unwrap();
            q.finish();
            (q.total[3], q.err[3], q.evals)
        };
        let ex = exact(0.0, 3.0)[3];
        let (one, est_one, n1) = integrate(f64::INFINITY);
        let (many, est_many, n12) = integrate(0.25);
        assert_eq!((n1, n12), (5, 1 + 4 * 12));
        assert!(
            (one - ex).abs() > 1e-3,
            "one panel is coarse: {one} vs {ex}"
        );
        assert!((many - ex).abs() < 1e-8 && (many - ex).abs() <= est_many);
        assert!(est_many < 1e-3 * est_one);
    }

    #[test]
    fn fixed_steps_group_into_fours_and_converge_at_order_six() {
        // ∫₀^1 cos(2t) with n equal steps: Boole panels of 4 steps, error O(h⁶).
        let run = |n: usize| {
            let h = 1.0 / n as f64;
            let mut q = Quadrature::new(true, f64::INFINITY, 0.0, poly(0.0));
            for k in 0..n {
                let (a, b) = (k as f64 * h, (k + 1) as f64 * h);
                q.step(a, b, false, &mut |t| Ok(poly(t))).unwrap();
            }
            q.finish();
            assert_eq!(q.evals, n + 1, "one evaluation per step");
            ((q.total[3] - exact(0.0, 1.0)[3]).abs(), q.err[3])
        };
        let ((e1, est1), (e2, est2)) = (run(8), run(16));
        let order = (e1 / e2).log2();
        assert!((5.7..6.5).contains(&order), "order {order}: {e1} {e2}");
        assert!(e1 <= est1 && e2 <= est2, "{e1} {est1} {e2} {est2}");
        // A partial group (10 steps = 2 panels + 2 steps) is closed by Simpson, whose error
        // is estimated by its difference with the trapezoid.
        let (e, est) = run(10);
        assert!(e <= est && est < 1e-3, "{e} {est}");
    }

    #[test]
    fn event_cut_steps_flush_the_group() {
        let mut q = Quadrature::new(true, f64::INFINITY, 0.0, poly(0.0));
        let h = 0.01;
        for k in 0..6 {
            q.step(k as f64 * h, (k + 1) as f64 * h, false, &mut |t| {
                Ok(poly(t))
            })
            .unwrap();
        }
        // A step cut by an event: the two pending steps are closed with Simpson, the cut step
        // gets its own Boole panel.
        q.step(0.06, 0.063, true, &mut |t| Ok(poly(t))).unwrap();
        q.step(0.063, 0.073, false, &mut |t| Ok(poly(t))).unwrap();
        q.finish();
        let ex = exact(0.0, 0.073);
        for c in 0..4 {
            let e = (q.total[c] - ex[c]).abs();
            assert!(
                e <= q.err[c] + 1e-16 && q.err[c] < 1e-4,
                "{c}: {e} {}",
                q.err[c]
            );
        }
        // Nodes: the start, 6 step ends, 4 for the cut step (its own Boole panel), 1 for the
        // last step (closed alone by the trapezoid, error bound d/2 |f1 − f0|).
        assert_eq!(q.evals, 1 + 6 + 4 + 1);
    }

    #[test]
    fn uniform_grid_has_exact_ends() {
        let g = uniform_grid(0.1, 0.9, 7);
        assert_eq!((g.len(), g[0], g[6]), (7, 0.1, 0.9));
        assert!((g[3] - 0.5).abs() < 1e-15);
    }
}
