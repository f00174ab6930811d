//! Running one case: the core every command (run, compare, work-precision, sweep, the default
//! run, the studies) calls.
//!
//! ```text
//! Prepared::load(case)        scene file → checked Scene (SceneError → exit 2) | testset:NAME
//!                             | a catalogue scene (Case::catalogue)
//! Prepared::options(choice)   the defaults below, the request's SolverChoice laid over them
//! simulate(prepared, request) → RunResult { summary, window samples (2001-point metrics grid of
//!                               the last revolution), trajectory samples, extra samples,
//!                               states, events, energy totals, ideal slider-crank }
//!
//! the integration loop (Integrator, one accepted step at a time):
//!   wall time     = time spent in Problem::new, Problem::integrator and Integrator::step only (no output, no
//!                   energy quadrature, no I/O)
//!   outputs       = dense output at every requested time; mechanism samples are evaluated
//!                   at once (so a contact law's stored impact velocity is the one in force)
//!   energy        ∫ P dt of Mechanism::power over every accepted step: Boole's rule on five
//!                   equally spaced nodes, error estimate |S₂ − S₁|/15 (S₁, S₂ Simpson on one
//!                   and two panels), panels no longer than T/400; a fixed-step method groups
//!                   four equal steps into one panel (nodes = step ends, one power evaluation
//!                   per step)
//!   balance       W_driver − ΔT − ΔV − D_damping − D_friction − D_film
//!   events        located hits; a run without event location (the paper's RK4) counts the
//!                   sign changes of the event functions between consecutive step ends
//!                   (crossing time by linear interpolation), so contact onsets are still counted
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
//! rk4 stability  15: fixed-step RK4 fails with NonFiniteState after 15 consecutive steps
//!  check         outside its stability region (h·ρ > 2.785, lash_solver::rk4). Past the
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
use lash_model::{IdealSliderCrank, Mechanism, Scene};
use lash_solver::{
    testset, Atol, EventHit, Method, OdeSystem, Problem, Solution, SolverOptions, Stats,
    StepOutcome,
};

use crate::case::{Case, CaseSource};
use crate::error::{Error, OptionError};
use crate::metrics::{
    self, EnergyTotals, EventQuantity, EventRecord, JointInfo, Sample, Window, GRID_POINTS,
};
use crate::options::SolverChoice;
use crate::report::{self, RunOutput};
use crate::summary::Summary;
use crate::trajectory::Extra;

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

fn scene_error(case: &Case, e: impl std::fmt::Display) -> Error {
    let what = match &case.source {
        CaseSource::File { path, .. } => path.display().to_string(),
        CaseSource::BuiltIn(_) | CaseSource::Catalogue(_) => case.name.clone(),
    };
    Error::Input(format!("case {what}: {e}"))
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
                let text = std::str::from_utf8(bytes).map_err(|e| scene_error(&case, e))?;
                let scene = Scene::from_json_str(text).map_err(|e| scene_error(&case, e))?;
                Prepared::with_scene(case, scene)
            }
            CaseSource::Catalogue(name) => {
                let scene = lash_model::cases::press_catalogue()
                    .into_iter()
                    .find_map(|(n, s)| (&n == name).then_some(s))
                    .ok_or_else(|| scene_error(&case, "not in the press catalogue"))?;
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
        o.validate(self.dim()).map_err(|e| match e {
            lash_solver::SolveError::InvalidOptions(m) => Error::Usage(m),
            other => Error::Solver(other),
        })
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
    let joint = mech
        .roles()
        .clearance_joint
        .and_then(|j| match &scene.joints[j] {
            JointSpec::Clearance(c) => Some(JointInfo {
                clearance: c.bearing.radius - c.journal.radius,
                lubricated: c.film.is_some(),
            }),
            _ => None,
        });
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
    }
}

/// What to run and what to record.
///
/// ```text
/// opts (method, tolerances, …; opts.output is ignored: the grids below are recorded),
/// t_end override, trajectory grid size, extra output times, energy on/off
/// ```
///
/// Source: docs/outputs.md (`trajectory.csv`, `metrics`, `energy`).
#[derive(Clone, Debug, PartialEq)]
pub struct RunRequest {
    /// Solver options (from [`Prepared::options`]).
    pub opts: SolverOptions,
    /// End time override, s (mechanisms only). None = the scene's.
    pub t_end: Option<f64>,
    /// Points of the trajectory grid (uniform over the whole run, both ends). None = 2000 per
    /// crank revolution plus one (4001 without a crank driver); Some(0) = no trajectory.
    /// Test problems record every accepted step instead.
    pub trajectory_points: Option<usize>,
    /// Further output times (sorted, inside the run), sampled like the others.
    pub extra_times: Vec<f64>,
    /// Whether to integrate the power terms for the energy balance (mechanisms only).
    pub energy: bool,
}

impl RunRequest {
    /// A request with these options and the defaults: the scene's end time, the default
    /// trajectory grid, no extra times, energy on.
    pub fn new(opts: SolverOptions) -> RunRequest {
        RunRequest {
            opts,
            t_end: None,
            trajectory_points: None,
            extra_times: Vec::new(),
            energy: true,
        }
    }
}

/// Everything one run produced.
///
/// ```text
/// summary (metrics filled in), samples on the metrics grid (window), on the trajectory grid
/// and at the extra times, with the raw states; events; energy totals; the ideal mechanism
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
    /// States on the metrics grid.
    pub window_states: Solution,
    /// Samples on the trajectory grid (test problems: `Sample::at` of every accepted step).
    pub trajectory: Vec<Sample>,
    /// States on the trajectory grid (test problems: every accepted step, the start
    /// included).
    pub trajectory_states: Solution,
    /// Samples at the extra times.
    pub extra: Vec<Sample>,
    /// States at the extra times.
    pub extra_states: Solution,
    /// Events: located ones, or crossings at the step ends of a run without location.
    pub events: Vec<EventRecord>,
    /// Energy totals over the whole run (mechanisms with `energy`).
    pub energy: Option<EnergyTotals>,
    /// The closed-form ideal slider-crank of the scene, if it is one.
    pub ideal: Option<IdealSliderCrank>,
    /// The metrics window.
    pub metrics_window: Option<Window>,
    /// Power evaluations spent on the energy quadrature.
    pub energy_evals: usize,
}

impl RunResult {
    /// Extra trajectory.csv columns: `y0..y{n-1}` for test problems, none for mechanisms.
    pub fn extra_columns(&self) -> Vec<(String, Vec<f64>)> {
        if !self.window.is_empty() || self.summary.final_state.is_none() {
            return Vec::new();
        }
        let s = &self.trajectory_states;
        (0..s.dim)
            .map(|i| {
                (
                    format!("y{i}"),
                    (0..s.len()).map(|k| s.state(k)[i]).collect(),
                )
            })
            .collect()
    }

    /// Writes summary.json, trajectory.csv and the figures into `dir` (report::write_run:
    /// everything checked first, summary last).
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, Error> {
        let cols = self.extra_columns();
        let extra: Vec<Extra<'_>> = cols
            .iter()
            .map(|(n, v)| Extra { name: n, values: v })
            .collect();
        report::write_run(
            dir,
            &RunOutput {
                summary: &self.summary,
                trajectory: &self.trajectory,
                extra: &extra,
                window: &self.window,
                ideal: self.ideal.as_ref(),
            },
        )
    }
}

/// Uniform grid of `n ≥ 2` points over [a, b], both ends exact.
pub fn uniform_grid(a: f64, b: f64, n: usize) -> Vec<f64> {
    let n = n.max(2);
    (0..n)
        .map(|i| {
            if i == n - 1 {
                b
            } else {
                a + (b - a) * i as f64 / (n - 1) as f64
            }
        })
        .collect()
}

/// Runs a case. Solver failures are `Error::Solver` (exit 3); nothing is written.
pub fn simulate(p: &Prepared, req: &RunRequest) -> Result<RunResult, Error> {
    let (t0, t_end) = p.t_span(req.t_end)?;
    match &p.model {
        Model::Mechanism(scene) => simulate_mechanism(p, scene, req, t0, t_end),
        Model::TestSet(_) => simulate_testset(p, req, t0, t_end),
    }
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

fn simulate_testset(
    p: &Prepared,
    req: &RunRequest,
    t0: f64,
    t_end: f64,
) -> Result<RunResult, Error> {
    let prob = p
        .test_problem()
        .ok_or_else(|| Error::Internal("not a test problem".into()))?;
    check_times(&req.extra_times, t0, t_end)?;
    let n = prob.y0.len();
    let mut extra_states = empty_solution(n);
    let mut sink = |_: usize, t: f64, y: &[f64]| -> Result<(), Error> {
        extra_states.t.push(t);
        extra_states.y.extend_from_slice(y);
        Ok(())
    };
    let mut d = drive(
        &*prob.system,
        t0,
        t_end,
        &prob.y0,
        &req.opts,
        &req.extra_times,
        true,
        None,
        f64::INFINITY,
        &mut sink,
    )?;
    let mut traj = d.steps.take().unwrap_or_else(|| empty_solution(n));
    for s in [&mut traj, &mut extra_states] {
        d.finish(s);
    }
    let mut summary = d.summary(p, &req.opts, t_end);
    let err = testset::reference_error(&d.y_final, &prob.reference, prob.atol);
    if !err.is_finite() {
        return Err(Error::Internal(format!(
            "{}: reference error is not finite (final state {:?})",
            p.case.name, d.y_final
        )));
    }
    summary.final_state = Some(d.y_final.clone());
    summary.reference_error = Some(err);
    let trajectory = traj.t.iter().map(|&t| Sample::at(t)).collect();
    Ok(RunResult {
        summary,
        window: Vec::new(),
        window_states: empty_solution(n),
        trajectory,
        trajectory_states: traj,
        extra: Vec::new(),
        extra_states,
        events: Vec::new(),
        energy: None,
        ideal: None,
        metrics_window: None,
        energy_evals: 0,
    })
}

fn empty_solution(dim: usize) -> Solution {
    Solution {
        dim,
        ..Default::default()
    }
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
        let o = self.mech.outputs(t, y);
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
}

/// Output lists of a mechanism run, merged in time order.
#[derive(Clone, Copy, PartialEq, Eq)]
enum List {
    Window,
    Trajectory,
    Extra,
}

fn simulate_mechanism(
    p: &Prepared,
    scene: &Scene,
    req: &RunRequest,
    t0: f64,
    t_end: f64,
) -> Result<RunResult, Error> {
    let info = p
        .info
        .as_ref()
        .ok_or_else(|| Error::Internal("mechanism without info".into()))?;
    check_times(&req.extra_times, t0, t_end)?;
    let mech = Mechanism::from_scene(scene).map_err(|e| scene_error(&p.case, e))?;
    let sampler = Sampler::new(&mech, scene);
    let window = p.metrics_window(t0, t_end);
    let wgrid = metrics::grid(window.t_end, window.period);
    let n_traj = match req.trajectory_points {
        Some(n) => n,
        None => match info.period {
            Some(t) => 1 + (2000.0 * (t_end - t0) / t).round().max(1.0) as usize,
            None => 2 * (GRID_POINTS - 1) + 1,
        },
    };
    let tgrid = if n_traj == 0 {
        Vec::new()
    } else {
        uniform_grid(t0, t_end, n_traj)
    };
    let mut merged: Vec<(f64, List, usize)> = Vec::new();
    merged.extend(wgrid.iter().enumerate().map(|(i, &t)| (t, List::Window, i)));
    merged.extend(
        tgrid
            .iter()
            .enumerate()
            .map(|(i, &t)| (t, List::Trajectory, i)),
    );
    merged.extend(
        req.extra_times
            .iter()
            .enumerate()
            .map(|(i, &t)| (t, List::Extra, i)),
    );
    merged.sort_by(|a, b| a.0.total_cmp(&b.0));
    // The metrics grid may start a few ulps before t0 (t_end − T): clamp into the run.
    let times: Vec<f64> = merged.iter().map(|m| m.0.clamp(t0, t_end)).collect();
    let y0 = mech.initial_state();
    let n = y0.len();
    let mut sol_w = empty_solution(n);
    let mut sol_t = empty_solution(n);
    let mut sol_x = empty_solution(n);
    let mut s_w: Vec<Sample> = Vec::with_capacity(wgrid.len());
    let mut s_t: Vec<Sample> = Vec::with_capacity(tgrid.len());
    let mut s_x: Vec<Sample> = Vec::with_capacity(req.extra_times.len());
    let mut sink = |k: usize, _t: f64, y: &[f64]| -> Result<(), Error> {
        let (t_req, list, _) = merged[k];
        let s = sampler.sample(t_req, y);
        let (sol, samples) = match list {
            List::Window => (&mut sol_w, &mut s_w),
            List::Trajectory => (&mut sol_t, &mut s_t),
            List::Extra => (&mut sol_x, &mut s_x),
        };
        sol.t.push(t_req);
        sol.y.extend_from_slice(y);
        samples.push(s);
        Ok(())
    };
    let power = |t: f64, y: &[f64]| {
        let p = mech.power(t, y);
        [p.driver, p.contact_damping, p.friction, p.film]
    };
    let d = drive(
        &mech,
        t0,
        t_end,
        &y0,
        &req.opts,
        &times,
        false,
        if req.energy { Some(&power) } else { None },
        info.period
            .map_or(f64::INFINITY, |t| t * QUADRATURE_PANEL_PER_PERIOD),
        &mut sink,
    )?;
    for s in [&mut sol_w, &mut sol_t, &mut sol_x] {
        d.finish(s);
    }
    let role_joint = sampler
        .clearance_index
        .and_then(|k| mech.clearance_names().get(k).map(|s| s.to_string()));
    let hits = if req.opts.events {
        &d.hits
    } else {
        &d.crossings
    };
    let events: Vec<EventRecord> = hits
        .iter()
        .map(|h| {
            let quantity = match mech.event_name(h.index) {
                Some(("contact", j)) if role_joint.as_deref() == Some(j) => {
                    EventQuantity::Penetration
                }
                Some(("eps_cap", j)) if role_joint.as_deref() == Some(j) => EventQuantity::FilmCap,
                _ => EventQuantity::Other,
            };
            EventRecord {
                t: h.t,
                quantity,
                rising: h.rising,
            }
        })
        .collect();
    let energy = match &d.energy {
        Some(q) => {
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
    let energy_evals = d.energy.as_ref().map_or(0, |q| q.evals);
    let metrics = metrics::compute(&s_w, window, info.joint, &events, energy)?;
    let mut summary = d.summary(p, &req.opts, t_end);
    summary.metrics = Some(metrics);
    Ok(RunResult {
        summary,
        window: s_w,
        window_states: sol_w,
        trajectory: s_t,
        trajectory_states: sol_t,
        extra: s_x,
        extra_states: sol_x,
        events,
        energy,
        ideal: sampler.ideal,
        metrics_window: Some(window),
        energy_evals,
    })
}

/// What the integration loop produced.
struct Drive {
    steps: Option<Solution>,
    hits: Vec<EventHit>,
    crossings: Vec<EventHit>,
    stats: Stats,
    wall: f64,
    t_final: f64,
    y_final: Vec<f64>,
    energy: Option<Quadrature>,
}

impl Drive {
    /// Copies the end of the run (stats, located events, final time and state) into `s`.
    fn finish(&self, s: &mut Solution) {
        s.stats = self.stats;
        s.events = self.hits.clone();
        s.t_final = self.t_final;
        s.y_final = self.y_final.clone();
    }

    /// summary.json of the run, without metrics or test-problem fields.
    fn summary(&self, p: &Prepared, opts: &SolverOptions, t_end: f64) -> Summary {
        Summary::new(&p.case, opts, t_end, self.stats, self.wall, self.hits.len())
    }
}

type PowerFn<'a> = &'a dyn Fn(f64, &[f64]) -> [f64; 4];

/// Integrates from t0 to t_end, calling `sink(k, t, y)` for every requested time (sorted) as
/// soon as the dense output covers it.
#[allow(clippy::type_complexity)]
fn drive<S: OdeSystem + ?Sized>(
    sys: &S,
    t0: f64,
    t_end: f64,
    y0: &[f64],
    opts: &SolverOptions,
    times: &[f64],
    record_steps: bool,
    power: Option<PowerFn<'_>>,
    max_panel: f64,
    sink: &mut dyn FnMut(usize, f64, &[f64]) -> Result<(), Error>,
) -> Result<Drive, Error> {
    let n = y0.len();
    let mut wall = Duration::ZERO;
    let clock = Instant::now();
    let problem = Problem::new(sys, opts)?;
    let mut it = problem.integrator(t0, t_end, y0)?;
    wall += clock.elapsed();
    let mut next = 0;
    while next < times.len() && times[next] <= t0 {
        sink(next, times[next], y0)?;
        next += 1;
    }
    let mut steps = record_steps.then(|| {
        let mut s = empty_solution(n);
        s.t.push(t0);
        s.y.extend_from_slice(y0);
        s
    });
    let m = sys.n_events();
    let detect = !opts.events && m > 0;
    let mut g_prev = vec![0.0; if detect { m } else { 0 }];
    let mut g_now = g_prev.clone();
    let mut t_g = t0;
    if detect {
        sys.events(t0, y0, &mut g_prev);
    }
    let mut quad = match power {
        Some(pw) => Some(Quadrature::new(
            opts.method.is_fixed_step(),
            max_panel,
            t0,
            checked_power(pw, t0, y0)?,
        )),
        None => None,
    };
    let mut hits = Vec::new();
    let mut crossings = Vec::new();
    let mut buf = vec![0.0; n];
    loop {
        let clock = Instant::now();
        let outcome = it.step()?;
        wall += clock.elapsed();
        let (ta, tb) = (it.t_prev(), it.t());
        while next < times.len() && times[next] <= tb {
            it.interpolate(times[next], &mut buf);
            sink(next, times[next], &buf)?;
            next += 1;
        }
        if let Some(s) = steps.as_mut() {
            s.t.push(tb);
            s.y.extend_from_slice(it.y());
        }
        let cut = matches!(outcome, StepOutcome::Event { .. });
        if let (Some(q), Some(pw)) = (quad.as_mut(), power) {
            let mut node = |t: f64| -> Result<[f64; 4], Error> {
                it.interpolate(t, &mut buf);
                checked_power(pw, t, &buf)
            };
            q.step(ta, tb, cut, &mut node)?;
        }
        if detect {
            sys.events(tb, it.y(), &mut g_now);
            for i in 0..m {
                let (a, b) = (g_prev[i], g_now[i]);
                if (a < 0.0 && b > 0.0) || (a > 0.0 && b < 0.0) {
                    crossings.push(EventHit {
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
                hits.extend(h);
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
    while next < times.len() {
        sink(next, times[next], it.y())?;
        next += 1;
    }
    if let Some(q) = quad.as_mut() {
        q.finish();
    }
    let stats = it.stats();
    Ok(Drive {
        steps,
        hits,
        crossings,
        stats,
        wall: wall.as_secs_f64(),
        t_final: it.t(),
        y_final: it.y().to_vec(),
        energy: quad,
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
