//! Preparing a case: the scene checked and its mechanism assembled once (or a built-in test
//! problem), what the mechanism offers the commands (crank period, clearances, state and event
//! names), and the default solver options of a run.
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
//! exact event    on for scenes with kink events (the scene's `kink_events`, else on when a
//!  steps         revolute clearance joint is dry and its laws have a kink: the mechanism
//!                decides, lash_model::Mechanism::kink_events; off otherwise and for fixed-step
//!                methods, which locate no events): the step that contains an event is
//!                taken again to end exactly on it and the run restarts from that step's end
//!                (lash_solver::integrator, "Exact event steps"), so that no step of a
//!                one-step method spans a kink; the kink events exist for that (docs/model.md
//!                §7)
//! h_max          ∞
//! step limit     h_max_near_events = T/100 (T the crank period; off without a crank driver
//!  near contact  or without a clearance joint, where nothing can be stepped over): the
//!                contact-aware step limit of lash_solver::integrator (docs/model.md §7):
//!                a step is longer than T/100 only while no event function can reach zero
//!                within it, predicted from its value, rate and the rate's change over the
//!                last step; near a zero (and after an event) it is T/100, and with 4 samples
//!                an interval of sign change longer than T/500 (0.8 ms at 150 rpm) cannot
//!                hide inside a step; the contacts and flights of the dry press are longer
//!                than that (BENCHMARKS.md, "Defaults of a run"); a step over a whole contact
//!                would miss both its onset and its loss (run/tests/simulate.rs checks the
//!                onset count against a reference). Away from every wall (a lubricated
//!                journal on its film) the step is set by accuracy alone.
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
//! A scene's `solver` section (lash_model::scene::SolverSpec) replaces the method, rtol and
//! atol above where it gives them; a request's choice replaces both.
//!
//! A built-in test problem runs rodas5p at rtol 1e-6 with the problem's own atol (its
//! reference_error threshold) and records every accepted step as its trajectory.
//!
//!
//! Source: docs/outputs.md (`case`, `scene_sha256`), docs/model.md §1, §5, §7.

use std::path::Path;

use lash_model::scene::JointSpec;
use lash_model::{Mechanism, Scene};
use lash_solver::{testset, Atol, Method, OdeSystem, SolveError, SolverOptions};

use crate::error::{Error, OptionError};
use crate::options::SolverChoice;
use crate::report::metrics::JointInfo;
use crate::run::case::{Case, CaseSource};
use crate::run::window::WindowPlan;
use lash_model::MetricsWindow;

/// Default method of a mechanism run.
pub(crate) const DEFAULT_METHOD: Method = Method::Bdf;
/// Default relative tolerance of a mechanism run.
pub(crate) const DEFAULT_RTOL: f64 = 1e-8;
/// Interior event samples per step of a mechanism run.
pub(crate) const DEFAULT_EVENT_SAMPLES: usize = 4;
/// The step limit near contact (`h_max_near_events`) of a mechanism run with a crank driver
/// and a clearance joint, as a fraction of the crank period.
pub(crate) const H_MAX_PER_PERIOD: f64 = 1.0 / 100.0;
/// Step limit of a mechanism run.
pub(crate) const DEFAULT_MAX_STEPS: usize = 50_000_000;
/// Divergence bound of a mechanism run (module doc), in SI units.
pub(crate) const MECHANISM_DIVERGENCE_BOUND: f64 = 1e6;
/// Consecutive RK4 steps outside the stability region that fail a mechanism run (module doc).
pub(crate) const MECHANISM_RK4_INSTABILITY_STEPS: usize = 15;
/// Length scale L of the default atol for scenes without a clearance joint, m.
pub(crate) const DEFAULT_LENGTH_SCALE: f64 = 1e-3;
/// Longest energy-quadrature panel of a run with a crank, as a fraction of the period: long
/// adaptive steps are split (the power terms oscillate at multiples of the crank frequency).
pub(crate) const QUADRATURE_PANEL_PER_PERIOD: f64 = 1.0 / 400.0;
/// Default method of a built-in test problem.
pub(crate) const TESTSET_METHOD: Method = Method::Rodas5p;
/// Default relative tolerance of a built-in test problem.
pub(crate) const TESTSET_RTOL: f64 = 1e-6;

/// What a case integrates.
///
/// ```text
/// Mechanism(scene) → Mechanism::from_scene per run (fresh event state) | TestSet(name)
/// ```
///
/// Source: docs/outputs.md (`case`).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Model {
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
pub(crate) struct MechanismInfo {
    /// Crank period T, s (crank driver role with ω ≠ 0).
    pub period: Option<f64>,
    /// |ω| of the crank driver, rad/s.
    pub crank_speed: Option<f64>,
    /// Whether the scene has a crank (`roles.crank`, or `roles.crank_driver`).
    pub has_crank: bool,
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
    /// Whether the scene's mechanism has kink events (`lash_model::Mechanism::kink_events`:
    /// the scene's `kink_events`, else on with a dry revolute clearance joint whose laws have
    /// a kink); the default options take exact event steps with them.
    pub kink_events: bool,
    /// State dimension.
    pub dim: usize,
    /// Whether the scene is an in-line slider-crank with a closed-form ideal.
    pub has_ideal: bool,
    /// Names of the components of an absolute state: `<body>.x`, `<body>.y`, `<body>.theta`
    /// of every integrated body, then `<body>.vx`, `<body>.vy`, `<body>.omega` (the layout of
    /// lagrange_baumgarte and augmented_lagrangian, and of RK4's runs of an `auto` scene).
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
pub(crate) struct Prepared {
    /// The case reference (name and sha256 recorded in summary.json).
    pub case: Case,
    /// What is integrated.
    pub model: Model,
    /// Mechanism facts (None for test problems).
    pub info: Option<MechanismInfo>,
    /// Wall-clock budget of each integration of this case, s (`--max-wall-time` of compare,
    /// work-precision and sweep); None: none. Laid into [`Prepared::default_options`].
    pub max_wall_time: Option<f64>,
}

/// How an error names the case: the scene file's path, else the case's name.
fn case_label(case: &Case) -> String {
    match &case.source {
        CaseSource::File { path, .. } => path.display().to_string(),
        CaseSource::BuiltIn(_) | CaseSource::Press(_) => case.name.clone(),
    }
}

/// A case that cannot be used for a reason other than the model's (`case LABEL: REASON`).
fn case_error(case: &Case, e: impl std::fmt::Display) -> Error {
    Error::Input(format!("case {}: {e}", case_label(case)))
}

/// A scene the model rejects (`case LABEL: PATH: REASON`), its path and reason kept; set-up
/// stopped by the call's deadline or a stop request is the solver's `BudgetExhausted` or
/// `Interrupted` at the scene's start time, before any state (exit 3, not a bad scene).
pub(crate) fn scene_error(case: &Case, error: lash_model::SceneError) -> Error {
    use lash_model::SceneError as S;
    match error {
        S::Budget { phase, t, budget } => Error::Solver(SolveError::BudgetExhausted {
            t,
            y: Vec::new(),
            reason: format!("wall-clock budget of {budget} s used during set-up ({phase})"),
        }),
        S::Interrupted { t, .. } => Error::Solver(SolveError::Interrupted { t, y: Vec::new() }),
        error => Error::Scene {
            case: case_label(case),
            error,
        },
    }
}

impl Prepared {
    /// Loads a case reference (a scene path or `testset:NAME`), relative paths taken from
    /// `base_dir` or the working directory.
    pub(crate) fn load_spec(spec: &str, base_dir: Option<&Path>) -> Result<Prepared, Error> {
        Prepared::load(Case::load(spec, base_dir)?)
    }

    /// Checks the case: parses and validates the scene and assembles its mechanism once
    /// (scene errors are input errors, exit code 2).
    pub(crate) fn load(case: Case) -> Result<Prepared, Error> {
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
                    max_wall_time: None,
                })
            }
            CaseSource::File { bytes, .. } => {
                let text = std::str::from_utf8(bytes).map_err(|e| case_error(&case, e))?;
                let scene = Scene::from_json_str(text).map_err(|e| scene_error(&case, e))?;
                Prepared::with_scene(case, scene)
            }
            CaseSource::Press(press) => {
                let scene = press.scene();
                Prepared::with_scene(case, scene)
            }
        }
    }

    /// A case whose scene was built or modified in code (a sweep point), recorded under the
    /// base case's name and hash.
    pub(crate) fn with_scene(case: Case, scene: Scene) -> Result<Prepared, Error> {
        let mech = Mechanism::from_scene(&scene).map_err(|e| scene_error(&case, e))?;
        let info = mechanism_info(&scene, &mech);
        Ok(Prepared {
            case,
            model: Model::Mechanism(Box::new(scene)),
            info: Some(info),
            max_wall_time: None,
        })
    }

    /// The same case with its scene's formulation replaced by `f` (docs/model.md §12); an
    /// input error for a built-in test problem, which has no constraints.
    pub(crate) fn with_formulation(
        self,
        f: lash_model::FormulationName,
    ) -> Result<Prepared, Error> {
        match self.scene() {
            Some(s) => {
                let mut scene = s.clone();
                scene.formulation = f;
                Prepared::with_scene(self.case, scene)
            }
            None => Err(Error::Input(format!(
                "formulation {f}: {} is a built-in test problem, not a scene",
                self.case.name
            ))),
        }
    }

    /// The scene, for mechanism cases.
    pub(crate) fn scene(&self) -> Option<&Scene> {
        match &self.model {
            Model::Mechanism(s) => Some(s),
            Model::TestSet(_) => None,
        }
    }

    /// The test problem, for built-in cases.
    pub(crate) fn test_problem(&self) -> Option<testset::TestProblem> {
        match self.model {
            Model::TestSet(n) => testset::by_name(n),
            Model::Mechanism(_) => None,
        }
    }

    /// State dimension.
    pub(crate) fn dim(&self) -> usize {
        match (&self.info, self.test_problem()) {
            (Some(i), _) => i.dim,
            (None, Some(p)) => p.y0.len(),
            (None, None) => 0,
        }
    }

    /// Names of the components of a state of length `n` (`<body>.x`, … for an absolute state
    /// of a scene; `y0`, `y1`, … for a test problem or a state in joint coordinates). A run may
    /// build another formulation than the prepared mechanism's (RK4 of an `auto` scene runs
    /// lagrange_baumgarte), hence the length.
    pub(crate) fn state_names_of(&self, n: usize) -> Vec<String> {
        match &self.info {
            Some(i) if i.state_names.len() == n => i.state_names.clone(),
            _ => (0..n).map(|i| format!("y{i}")).collect(),
        }
    }

    /// The time span of a run, with an optional end-time override (mechanisms only).
    pub(crate) fn t_span(&self, t_end: Option<f64>) -> Result<(f64, f64), Error> {
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
    pub(crate) fn default_atol(&self, rtol: f64) -> Atol {
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
    pub(crate) fn default_options(&self) -> SolverOptions {
        match &self.info {
            Some(i) => {
                // The scene's own solver section, where it has one (lash_model::scene::SolverSpec).
                let own = self.scene().map(|s| s.solver).unwrap_or_default();
                let rtol = own.rtol.unwrap_or(DEFAULT_RTOL);
                let mut o = SolverOptions::with_method(own.method.unwrap_or(DEFAULT_METHOD));
                o.rtol = rtol;
                o.atol = own
                    .atol
                    .map_or_else(|| self.default_atol(rtol), Atol::Scalar);
                o.event_samples = DEFAULT_EVENT_SAMPLES;
                o.exact_event_steps = i.kink_events;
                o.h_max_near_events = match (i.period, i.clearance_min) {
                    (Some(t), Some(_)) => t * H_MAX_PER_PERIOD,
                    _ => f64::INFINITY,
                };
                o.max_steps = DEFAULT_MAX_STEPS;
                o.divergence_bound = MECHANISM_DIVERGENCE_BOUND;
                o.rk4_instability_steps = MECHANISM_RK4_INSTABILITY_STEPS;
                o.max_wall_time = self.max_wall_time;
                o
            }
            None => {
                let mut o = SolverOptions::with_method(TESTSET_METHOD);
                o.rtol = TESTSET_RTOL;
                o.atol = self.default_atol(TESTSET_RTOL);
                o.max_wall_time = self.max_wall_time;
                o
            }
        }
    }

    /// The case's defaults with the solver choice laid over them: atol follows rtol unless
    /// the choice gives atol; a fixed-step method runs without event location, an adaptive
    /// one with it. Inconsistent options (an atol array of the wrong length) are usage errors.
    pub(crate) fn options(&self, choice: &SolverChoice) -> Result<SolverOptions, Error> {
        let base = self.default_options();
        let mut o = choice.apply(&base)?;
        self.finish_options(&mut o, choice.atol.is_some())?;
        Ok(o)
    }

    /// Options for `method` at tolerance `rtol` (adaptive) or step `step` (fixed-step), the
    /// rest as the defaults: what compare and work-precision run.
    pub(crate) fn options_for(
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
        let scene_atol = self.scene().is_some_and(|s| s.solver.atol.is_some());
        if !o.method.is_fixed_step() && !atol_given && !scene_atol {
            o.atol = self.default_atol(o.rtol);
        }
        if self.info.is_some() {
            o.events = !o.method.is_fixed_step();
            // Exact event steps retake a step at a located event: none without location.
            o.exact_event_steps &= o.events;
        }
        Ok(o.validate(self.dim())?)
    }

    /// The crank period, if the scene has a crank driver.
    pub(crate) fn period(&self) -> Option<f64> {
        self.info.as_ref().and_then(|i| i.period)
    }

    /// How a run over [t_start, t_end] finds its metrics window (`choice`, None: the
    /// default; crate::run::window): the last revolution of a crank, else the whole run.
    pub(crate) fn window_plan(
        &self,
        choice: Option<MetricsWindow>,
        t_start: f64,
        t_end: f64,
    ) -> Result<WindowPlan, Error> {
        let has_crank = self.info.as_ref().is_some_and(|i| i.has_crank);
        crate::run::window::plan(choice, t_start, t_end, self.period(), has_crank)
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
    let mut state_names: Vec<String> = Vec::with_capacity(6 * bodies.len());
    for suffixes in [["x", "y", "theta"], ["vx", "vy", "omega"]] {
        for b in &bodies {
            state_names.extend(suffixes.iter().map(|s| format!("{b}.{s}")));
        }
    }
    MechanismInfo {
        period: w.map(|w| 2.0 * std::f64::consts::PI / w),
        crank_speed: w,
        has_crank: roles.crank.is_some(),
        t_start: mech.t_start(),
        t_end: mech.t_end(),
        clearance_min: c_min,
        joint,
        has_dry_joint: dry,
        kink_events: mech.kink_events(),
        dim: mech.dim(),
        has_ideal: mech.ideal_slider_crank().is_some(),
        state_names,
        event_names: (0..mech.n_events())
            .filter_map(|i| mech.event_name(i))
            .map(|(kind, name)| (kind, name.to_string()))
            .collect(),
    }
}
