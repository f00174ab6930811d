//! Errors against a converged reference: the error window, the reference run and its check,
//! the error norms, and `lash compare`.
//!
//! ```text
//! error window   dry clearance joint (chaotic, docs/model.md §9): the first half revolution
//!                  [t0, t0 + T/2]   (two correct runs still agree there; docs/model.md §9)
//!                otherwise: the metrics window (the last revolution)
//!                sampled on 2001 equally spaced times, both ends
//! reference      IFToMM A02 (the N-four-bar of lash_model::iftomm): its exact
//!                one-degree-of-freedom reduction (compare/one_dof.rs), no run
//!                a scene with an oil film (stiff): bdf at rtol 1e-12, checked by esdirk34 at
//!                1e-12; otherwise dop853 at rtol 1e-12, checked by tsit54 at 1e-12; atol as
//!                every run (rtol · scale, simulate.rs); the check's error against the
//!                reference is reported as the reference's agreement (an upper estimate of its
//!                error when the check is the less accurate of the two)
//!                test problems: the published solution (IVP Test Set), no run
//! norms          acc   = sqrt( Σ (a − a_ref)² / Σ a_ref² )    slider x acceleration, relative RMS
//!                acc∞  = max |a − a_ref|                      m/s²
//!                orbit = max |e/c − e_ref/c|                  journal centre, units of c
//!                state = sqrt( Σ |y − y_ref|² / Σ |y_ref|² )  all state components
//! error          acc when the scene has a slider, else orbit, else state;
//!                test problems: reference_error (largest relative error over components)
//! ```
//!
//! Source: docs/model.md §9; docs/outputs.md (`summary.json`: `reference_error`; "`lash compare
//! CASE`": every method against a converged reference, saying how it was obtained).

use std::path::{Path, PathBuf};

use lash_model::MetricsWindow;
use lash_solver::{ControllerKind, Method};

use crate::compare::one_dof::{a02_reference, Exact};
use crate::compare::workprecision::fmt_num;
use crate::error::{Error, OptionError};
use crate::report::metrics::{EventQuantity, Sample, GRID_POINTS};
use crate::run::plan::{uniform_grid, RunRequest};
use crate::run::prepare::Prepared;
use crate::run::result::RunResult;
use crate::run::simulate::simulate;
use crate::run::window::WindowPlan;
use crate::store::io;

/// Relative tolerance of reference runs.
pub(crate) const REFERENCE_RTOL: f64 = 1e-12;

/// Default tolerances of the adaptive methods in a comparison.
pub(crate) const COMPARE_TOLERANCES: [f64; 2] = [1e-6, 1e-9];

/// The RK4 steps tried by [`stable_rk4_step`], as multiples of a power of ten (1–2–5 series).
pub(crate) const STEP_SERIES: [f64; 3] = [5.0, 2.0, 1.0];

/// Largest ‖Φ‖ a stable RK4 run may reach on its trajectory (the model's criterion for the
/// press cases, crates/model/tests/press_cases.rs).
pub(crate) const STABLE_PHI_MAX: f64 = 1e-8;

/// Where errors are measured.
///
/// ```text
/// [start, end] sampled at 2001 equally spaced times;  label says which rule chose it
/// ```
///
/// Source: docs/model.md §9.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ErrorWindow {
    /// Start, s.
    pub start: f64,
    /// End, s.
    pub end: f64,
    /// Which rule: "first half revolution" | "last revolution" | "whole run" | "end point".
    pub label: String,
}

impl ErrorWindow {
    /// The window of a case run from `t0` to `t_end` (module doc).
    pub(crate) fn of(p: &Prepared, t0: f64, t_end: f64) -> ErrorWindow {
        let Some(info) = &p.info else {
            return ErrorWindow {
                start: t_end,
                end: t_end,
                label: "end point".into(),
            };
        };
        match info.period {
            Some(t) if info.has_dry_joint => ErrorWindow {
                start: t0,
                end: (t0 + 0.5 * t).min(t_end),
                label: "first half revolution".into(),
            },
            Some(t) if t_end - t0 >= t => ErrorWindow {
                start: t_end - t,
                end: t_end,
                label: "last revolution".into(),
            },
            _ => ErrorWindow {
                start: t0,
                end: t_end,
                label: "whole run".into(),
            },
        }
    }

    /// The window `--window` chooses for a scene case run to `t_end` (crate::run::window):
    /// last-revolution (a driven crank's last period; for a crank a motor turns, its last
    /// turn as a run at the case's own options finds it), all, or T0:T1. Option errors: a
    /// test problem (compared at its end point), a window the run cannot have.
    pub(crate) fn chosen(
        p: &Prepared,
        t_end: Option<f64>,
        choice: MetricsWindow,
    ) -> Result<ErrorWindow, Error> {
        if p.info.is_none() {
            return Err(OptionError::leading(
                "window",
                format!(
                    " applies to scene cases; {} is a test problem, compared at its end point",
                    p.case.name
                ),
            )
            .into());
        }
        let (t0, te) = p.t_span(t_end)?;
        let label = match choice {
            MetricsWindow::LastRevolution => "last revolution".to_string(),
            MetricsWindow::All => "whole run".to_string(),
            MetricsWindow::Span { from, to } => {
                format!("chosen span {}:{}", fmt_num(from), fmt_num(to))
            }
        };
        let (start, end) = match p.window_plan(Some(choice), t0, te)? {
            WindowPlan::Known(w) => (w.t_end - w.period, w.t_end),
            WindowPlan::CrankTurn => {
                let mut req = RunRequest::new(p.default_options());
                req.t_end = t_end;
                req.window = Some(choice);
                req.trajectory_points = Some(0);
                req.energy = false;
                let r = simulate(p, &req)?;
                let [a, b] = r.summary.metrics_window.ok_or_else(|| {
                    Error::Internal("compare: the crank's last turn was not found".into())
                })?;
                (a, b)
            }
        };
        Ok(ErrorWindow { start, end, label })
    }

    /// The 2001 sampling times (none for test problems, which compare end points).
    pub(crate) fn grid(&self) -> Vec<f64> {
        if self.end > self.start {
            uniform_grid(self.start, self.end, GRID_POINTS)
        } else {
            Vec::new()
        }
    }
}

/// Error norms of a run against the reference on the error window.
///
/// ```text
/// see the module doc: acc (relative RMS), acc∞ (m/s²), orbit (units of c), state (relative)
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ErrorNorms {
    /// Relative RMS error of the slider acceleration.
    pub slider_acc_rel_rms: Option<f64>,
    /// Largest absolute error of the slider acceleration, m/s².
    pub slider_acc_max_abs: Option<f64>,
    /// Largest error of the journal centre e/c.
    pub orbit_max: Option<f64>,
    /// Relative RMS error of the whole state.
    pub state_rel_rms: f64,
}

impl ErrorNorms {
    /// The one number tables and work–precision use (module doc).
    pub fn headline(&self) -> f64 {
        self.slider_acc_rel_rms
            .or(self.orbit_max)
            .unwrap_or(self.state_rel_rms)
    }

    /// The norms of `run` (samples and states at the window grid) against `reference`.
    pub(crate) fn between(
        run: &[Sample],
        run_states: &[f64],
        reference: &[Sample],
        ref_states: &[f64],
    ) -> Result<ErrorNorms, Error> {
        if run.len() != reference.len() || run_states.len() != ref_states.len() {
            return Err(Error::Internal(format!(
                "compare: {} samples against {} reference samples",
                run.len(),
                reference.len()
            )));
        }
        let pairs = |f: fn(&Sample) -> Option<f64>| -> Option<Vec<(f64, f64)>> {
            run.iter()
                .zip(reference)
                .map(|(a, b)| Some((f(a)?, f(b)?)))
                .collect::<Option<Vec<_>>>()
                .filter(|v| !v.is_empty())
        };
        let acc = pairs(|s| s.slider_a);
        let (rel, max_abs) = match &acc {
            Some(v) => {
                let num: f64 = v.iter().map(|(a, b)| (a - b) * (a - b)).sum();
                let den: f64 = v.iter().map(|(_, b)| b * b).sum();
                let m = v.iter().fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                (Some((num / den.max(f64::MIN_POSITIVE)).sqrt()), Some(m))
            }
            None => (None, None),
        };
        let ex = pairs(|s| s.ex_over_c);
        let ey = pairs(|s| s.ey_over_c);
        let orbit = match (ex, ey) {
            (Some(x), Some(y)) => Some(
                x.iter()
                    .zip(&y)
                    .fold(0.0f64, |m, (a, b)| m.max((a.0 - a.1).hypot(b.0 - b.1))),
            ),
            _ => None,
        };
        let num: f64 = run_states
            .iter()
            .zip(ref_states)
            .map(|(a, b)| (a - b) * (a - b))
            .sum();
        let den: f64 = ref_states.iter().map(|b| b * b).sum();
        let norms = ErrorNorms {
            slider_acc_rel_rms: rel,
            slider_acc_max_abs: max_abs,
            orbit_max: orbit,
            state_rel_rms: (num / den.max(f64::MIN_POSITIVE)).sqrt(),
        };
        let all = [
            norms.slider_acc_rel_rms,
            norms.slider_acc_max_abs,
            norms.orbit_max,
            Some(norms.state_rel_rms),
        ];
        if all.iter().flatten().any(|v| !v.is_finite()) {
            return Err(Error::Internal(format!(
                "compare: non-finite norms {norms:?}"
            )));
        }
        Ok(norms)
    }
}

/// The converged solution errors are measured against.
///
/// ```text
/// mechanism: (method, rtol) run on the error window, checked by (check_method, rtol);
/// test problem: the published solution
/// ```
///
/// Source: module doc.
#[derive(Clone, Debug)]
pub(crate) struct Reference {
    /// How it was obtained, in words.
    pub how: String,
    /// Where errors are measured.
    pub window: ErrorWindow,
    /// End time of the runs, s.
    pub t_end: f64,
    /// The reference run (None for test problems and A02).
    pub run: Option<RunResult>,
    /// A02's exact reference: its samples and states on the window's grid (None otherwise).
    pub exact: Option<Exact>,
    /// The check's error norms against the reference (None for test problems).
    pub agreement: Option<ErrorNorms>,
    /// Wall time of the reference and its check, s.
    pub wall_time_s: f64,
}

/// Reference and check methods of a case (module doc).
pub(crate) fn reference_methods(p: &Prepared) -> (Method, Method) {
    let film = p
        .scene()
        .map(|s| {
            s.joints.iter().any(
                |j| matches!(j, lash_model::scene::JointSpec::Clearance(c) if c.film.is_some()),
            )
        })
        .unwrap_or(false);
    if film {
        (Method::Bdf, Method::Esdirk34)
    } else {
        (Method::Dop853, Method::Tsit54)
    }
}

/// Runs `opts` on the case and samples the error window.
fn run_on_window(
    p: &Prepared,
    opts: lash_solver::SolverOptions,
    t_end: Option<f64>,
    window: &ErrorWindow,
    energy: bool,
    trajectory: bool,
) -> Result<RunResult, Error> {
    let mut req = RunRequest::new(opts);
    req.t_end = t_end;
    req.extra_times = window.grid();
    req.energy = energy;
    if !trajectory {
        req.trajectory_points = Some(0);
    }
    simulate(p, &req)
}

impl Reference {
    /// Computes the reference of a case run to `t_end` (None: the scene's end time). A
    /// failure of the reference itself is the solver's error (exit 3).
    pub(crate) fn compute(p: &Prepared, t_end: Option<f64>) -> Result<Reference, Error> {
        Reference::compute_in(p, t_end, None)
    }

    /// [`Reference::compute`] with the error window chosen (`--window`; None: the case's own
    /// rule, [`ErrorWindow::of`]; [`ErrorWindow::chosen`]).
    pub(crate) fn compute_in(
        p: &Prepared,
        t_end: Option<f64>,
        choice: Option<MetricsWindow>,
    ) -> Result<Reference, Error> {
        let (t0, te) = p.t_span(t_end)?;
        let window = match choice {
            None => ErrorWindow::of(p, t0, te),
            Some(c) => ErrorWindow::chosen(p, t_end, c)?,
        };
        if p.info.is_none() {
            return Ok(Reference {
                how: "the published reference solution at t_end (IVP Test Set 2.4, \
                      lash_solver::testset)"
                    .into(),
                window,
                t_end: te,
                run: None,
                exact: None,
                agreement: None,
                wall_time_s: 0.0,
            });
        }
        if let Some(scene) = p.scene() {
            let clock = std::time::Instant::now();
            if let Some(exact) = a02_reference(scene, t0, &window.grid())? {
                return Ok(Reference {
                    how: format!(
                        "the exact one-degree-of-freedom reduction of IFToMM A02, J θ̈ = −g K \
                         cos θ (lash_model::iftomm), by dop853 at rtol 1e-13, mapped to every \
                         body, on the {}",
                        window.label
                    ),
                    window,
                    t_end: te,
                    run: None,
                    exact: Some(exact),
                    agreement: None,
                    wall_time_s: clock.elapsed().as_secs_f64(),
                });
            }
        }
        let (m, check) = reference_methods(p);
        let run = run_on_window(
            p,
            p.options_for(m, Some(REFERENCE_RTOL), None, None)?,
            t_end,
            &window,
            true,
            true,
        )?;
        let chk = run_on_window(
            p,
            p.options_for(check, Some(REFERENCE_RTOL), None, None)?,
            t_end,
            &window,
            false,
            false,
        )?;
        let agreement = ErrorNorms::between(
            &chk.extra,
            &chk.extra_states.y,
            &run.extra,
            &run.extra_states.y,
        )?;
        let how = format!(
            "{m} at rtol {} (atol = rtol × scale), checked by {check} at the same rtol: they \
             differ by {} (headline error) on the {}",
            fmt_num(REFERENCE_RTOL),
            fmt_num(agreement.headline()),
            window.label
        );
        let wall = run.summary.wall_time_s + chk.summary.wall_time_s;
        Ok(Reference {
            how,
            window,
            t_end: te,
            run: Some(run),
            exact: None,
            agreement: Some(agreement),
            wall_time_s: wall,
        })
    }

    /// What the headline error ([`ErrorNorms::headline`]) measures, in words (axis labels).
    pub(crate) fn measure(&self) -> String {
        let first = match (&self.run, &self.exact) {
            (Some(r), _) => r.extra.first(),
            (None, Some((samples, _))) => samples.first(),
            (None, None) => {
                return "largest relative error of a component at t_end (IVP Test Set solution)"
                    .into()
            }
        };
        if first.is_some_and(|s| s.slider_a.is_some()) {
            "relative RMS error of the slider acceleration".into()
        } else if first.is_some_and(|s| s.ex_over_c.is_some()) {
            "largest error of the journal centre, in clearances".into()
        } else {
            "relative RMS error of the state".into()
        }
    }

    /// The error norms of a run made with the same t_end and `extra_times = window.grid()`
    /// (None for test problems: their error is `reference_error`).
    pub(crate) fn norms(&self, r: &RunResult) -> Result<Option<ErrorNorms>, Error> {
        let (samples, states) = match (&self.run, &self.exact) {
            (Some(reference), _) => (&reference.extra, &reference.extra_states.y),
            (None, Some((samples, states))) => (samples, states),
            (None, None) => return Ok(None),
        };
        ErrorNorms::between(&r.extra, &r.extra_states.y, samples, states).map(Some)
    }
}

/// One run of a comparison.
///
/// ```text
/// (method, controller, rtol | step) → error norms, headline error, cost, events
/// ```
///
/// Source: docs/outputs.md ("`lash compare CASE`").
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Compared {
    /// Method.
    pub method: Method,
    /// Controller (our adaptive methods).
    pub controller: Option<ControllerKind>,
    /// Relative tolerance (adaptive methods).
    pub rtol: Option<f64>,
    /// Fixed step, s (fixed-step methods).
    pub step: Option<f64>,
    /// Error norms against the reference (mechanisms).
    pub norms: Option<ErrorNorms>,
    /// The headline error (None when the run failed).
    pub error: Option<f64>,
    /// Wall time of the integration, s.
    pub wall_time_s: f64,
    /// RHS evaluations.
    pub rhs_evals: usize,
    /// Accepted steps.
    pub steps: usize,
    /// Located events.
    pub events: usize,
    /// Contact onsets over the whole run (located, or counted at the step ends).
    pub contact_onsets: Option<usize>,
    /// The solver failure, if it failed.
    pub failure: Option<String>,
    /// The formulation the run was made with, when formulations are compared
    /// (`--formulations`); None: the case's own (and not written).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub formulation: Option<String>,
}

impl Compared {
    /// The method's setting in words: `rtol 1e-8` or `h 2e-4`.
    pub(crate) fn setting(&self) -> String {
        match (self.rtol, self.step) {
            (_, Some(h)) => format!("h {}", fmt_num(h)),
            (Some(r), None) => format!("rtol {}", fmt_num(r)),
            _ => "default".into(),
        }
    }

    /// `method` or `method/controller`, then ` [formulation]` when formulations are compared.
    pub(crate) fn label(&self) -> String {
        let m = match self.controller {
            Some(c) => format!("{}/{}", self.method, c),
            None => self.method.to_string(),
        };
        match &self.formulation {
            Some(f) => format!("{m} [{f}]"),
            None => m,
        }
    }
}

/// Runs one setting against the reference; a solver failure is recorded, not returned.
pub(crate) fn compare_one(
    p: &Prepared,
    reference: &Reference,
    method: Method,
    rtol: Option<f64>,
    step: Option<f64>,
    controller: Option<ControllerKind>,
) -> Result<(Compared, Option<RunResult>), Error> {
    let opts = p.options_for(method, rtol, step, controller)?;
    let t_end = p.info.as_ref().map(|_| reference.t_end);
    let base = Compared {
        method,
        controller: opts.controller_in_use(),
        rtol: (!method.is_fixed_step()).then_some(opts.rtol),
        step: opts.step,
        norms: None,
        error: None,
        wall_time_s: 0.0,
        rhs_evals: 0,
        steps: 0,
        events: 0,
        contact_onsets: None,
        failure: None,
        formulation: None,
    };
    match timed(|| run_on_window(p, opts.clone(), t_end, &reference.window, false, false)) {
        Ok(r) => {
            let norms = reference.norms(&r)?;
            let error = match &norms {
                Some(n) => Some(n.headline()),
                None => r.summary.reference_error,
            };
            let onsets = p.info.as_ref().and_then(|i| i.joint).map(|_| {
                r.events
                    .iter()
                    .filter(|e| e.quantity == EventQuantity::Penetration && e.rising)
                    .count()
            });
            let s = &r.summary;
            let c = Compared {
                norms,
                error,
                wall_time_s: s.wall_time_s,
                rhs_evals: s.stats.rhs_evals,
                steps: s.stats.accepted,
                events: s.events,
                contact_onsets: onsets,
                ..base
            };
            Ok((c, Some(r)))
        }
        Err(Error::Solver(e)) => Ok((
            Compared {
                failure: Some(e.to_string()),
                ..base
            },
            None,
        )),
        Err(e) => Err(e),
    }
}

/// Runs `f` once, and again while its runs are short (below 0.1 s each, at most 5 runs and
/// 0.3 s in all), keeping the smallest integration wall time: a short run's single timing is
/// dominated by noise from other processes. The runs are deterministic, so every other field
/// is the same.
fn timed(f: impl Fn() -> Result<RunResult, Error>) -> Result<RunResult, Error> {
    let mut best = f()?;
    let mut spent = best.summary.wall_time_s;
    for _ in 1..5 {
        if best.summary.wall_time_s >= 0.1 || spent >= 0.3 {
            break;
        }
        let again = f()?;
        spent += again.summary.wall_time_s;
        if again.summary.wall_time_s < best.summary.wall_time_s {
            best.summary.wall_time_s = again.summary.wall_time_s;
        }
    }
    Ok(best)
}

/// Where the search for a stable RK4 step starts and what it accepts ([`stable_rk4_step`]).
///
/// ```text
/// driven crank (T = 2π/|ω|)      top T/400 (1 ms at 150 rpm), floor T·1e-7, ‖Φ‖ < 1e-8
/// any other scene                 τ = 2π/|φ̇(t_0)| for a crank turning at the start, else the
///                                 run's span t_end − t_0; top τ/400, floor τ·1e-7,
///                                 ‖Φ‖ ≤ L/100 (the constraint check of `lash stiffness`)
/// ```
///
/// Source: docs/outputs.md ("`lash compare CASE`").
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Rk4Search {
    /// Largest step tried, s.
    pub top: f64,
    /// Smallest step tried, s.
    pub floor: f64,
    /// Largest ‖Φ‖ on the 401-point trajectory of a stable run, m.
    pub phi_max: f64,
    /// The rule in words (the progress line).
    pub rule: String,
}

impl Rk4Search {
    /// The search of a scene case over [t_0, t_end]; an option error for a test problem.
    pub(crate) fn of(p: &Prepared, t_end: Option<f64>) -> Result<Rk4Search, Error> {
        if let Some(period) = p.period() {
            return Ok(Rk4Search {
                top: period / 400.0,
                floor: period * 1e-7,
                phi_max: STABLE_PHI_MAX,
                rule: "1-2-5 series from T/400, ‖Φ‖ < 1e-8".into(),
            });
        }
        let Some(scene) = p.scene() else {
            return Err(OptionError::new("steps")
                .text("RK4 needs ")
                .name("steps")
                .text(" for a test problem")
                .into());
        };
        let mech = lash_model::Mechanism::from_scene(scene)
            .map_err(|e| crate::run::prepare::scene_error(&p.case, e))?;
        let (t0, t1) = p.t_span(t_end)?;
        let rate = mech
            .outputs(t0, &mech.initial_state())
            .crank_rate
            .map_or(0.0, f64::abs);
        let (tau, what) = if rate > 0.0 && rate.is_finite() {
            (std::f64::consts::TAU / rate, "the crank's starting turn τ")
        } else {
            (t1 - t0, "the run's span τ")
        };
        let phi_max = crate::diagnostics::stiffness::sample::phi_max(p);
        Ok(Rk4Search {
            top: tau / 400.0,
            floor: tau * 1e-7,
            phi_max,
            rule: format!(
                "1-2-5 series from τ/400, τ = {tau:.4e} s {what}; the run's own stability check \
                 and ‖Φ‖ ≤ {phi_max:.1e} m"
            ),
        })
    }
}

/// The largest RK4 step of the 1–2–5 series not above the search's top ([`Rk4Search`]) whose
/// run to `t_end` succeeds — the run's own stability check (RK4's stage check confirmed by the
/// eigenvalues, the check `lash stiffness` measures with) does not stop it and no state is
/// non-finite — with ‖Φ‖ below the search's bound on a 401-point trajectory: how the paper
/// would choose a fixed step ("the largest step that runs stably"). Tries down to the floor.
pub(crate) fn stable_rk4_step(p: &Prepared, t_end: Option<f64>) -> Result<f64, Error> {
    let search = Rk4Search::of(p, t_end)?;
    let top = search.top;
    let mut exp = top.log10().floor() as i32;
    loop {
        for k in STEP_SERIES {
            // The literal k·10^exp, exactly as one would type it.
            let h: f64 = format!("{k}e{exp}").parse().unwrap_or(k * 10f64.powi(exp));
            if h > top * (1.0 + 1e-12) {
                continue;
            }
            if h < search.floor {
                return Err(Error::Input(format!(
                    "no stable RK4 step down to {h:e} s for {}",
                    p.case.name
                )));
            }
            let mut req = RunRequest::new(p.options_for(Method::Rk4, None, Some(h), None)?);
            req.t_end = t_end;
            req.trajectory_points = Some(401);
            req.energy = false;
            match simulate(p, &req) {
                Ok(r) => {
                    let phi = r
                        .trajectory
                        .column("constraint_violation")
                        .unwrap_or_default()
                        .iter()
                        .fold(0.0, |m: f64, v| m.max(*v));
                    if phi < search.phi_max {
                        return Ok(h);
                    }
                }
                Err(Error::Solver(_)) => {}
                Err(e) => return Err(e),
            }
        }
        exp -= 1;
    }
}

/// The result of `lash compare`.
///
/// ```text
/// { case, reference: how, window, t_end, runs: [Compared] }
/// ```
///
/// Source: docs/outputs.md ("`lash compare CASE`": compare.json).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Comparison {
    /// Case name.
    pub case: String,
    /// How the reference was obtained.
    pub reference: String,
    /// The check's agreement with the reference (mechanisms).
    pub reference_agreement: Option<ErrorNorms>,
    /// Where errors were measured.
    pub window: ErrorWindow,
    /// End time of every run, s.
    pub t_end: f64,
    /// What `error` measures for this case, in words (the slider acceleration's relative RMS
    /// error, the journal centre's largest error in clearances, the state's relative RMS
    /// error, or a test problem's largest relative error at t_end).
    #[serde(default)]
    pub error_measure: String,
    /// The runs, in order.
    pub runs: Vec<Compared>,
}

fn opt(v: Option<f64>) -> String {
    v.map_or("–".into(), fmt_num)
}

impl Comparison {
    /// The markdown report.
    pub fn to_markdown(&self) -> String {
        let mut s = format!("# Method comparison: {}\n\n", self.case);
        s.push_str(&format!(
            "Reference: {}.\n\nErrors over the {} [{}, {}] s, t_end = {} s. `error` is the \
             {} for this case; `acc max` (m/s², the slider acceleration's largest error) and \
             `orbit` (the largest error of e/c) where the scene has those roles.\n\n",
            self.reference,
            self.window.label,
            fmt_num(self.window.start),
            fmt_num(self.window.end),
            fmt_num(self.t_end),
            self.error_measure
        ));
        s.push_str("| method | setting | error | acc max, m/s² | orbit | wall time, s | RHS evals | steps | events | contact onsets |\n");
        s.push_str("|---|---|---|---|---|---|---|---|---|---|\n");
        for r in &self.runs {
            let n = r.norms.as_ref();
            let err = match (&r.error, &r.failure) {
                (Some(e), _) => fmt_num(*e),
                (None, Some(f)) => format!("failed: {}", f.replace('|', "\\|")),
                (None, None) => "–".into(),
            };
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
                r.label(),
                r.setting(),
                err,
                opt(n.and_then(|n| n.slider_acc_max_abs)),
                opt(n.and_then(|n| n.orbit_max)),
                fmt_num(r.wall_time_s),
                r.rhs_evals,
                r.steps,
                r.events,
                r.contact_onsets.map_or("–".into(), |c| c.to_string()),
            ));
        }
        s
    }

    /// Writes compare.md and compare.json into `dir`; returns their paths.
    pub(crate) fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, Error> {
        io::create_dir(dir)?;
        let md = dir.join("compare.md");
        let js = dir.join("compare.json");
        io::write_atomic(&md, self.to_markdown().as_bytes())?;
        io::write_json_atomic(&js, self)?;
        Ok(vec![md, js])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hub on a pivot at its centre (I = 0.5 kg m²), turned by a motor T_s(1 − ω/ω_0) from
    /// 10 rad/s (ω_0 = 4π rad/s), and a free wheel on it through a clearance joint (no
    /// gravity: no contact). The hub's speed relaxes at the rate λ = T_s/(I ω_0); with
    /// T_s = 58 327 N m, λ = 9 283 1/s and RK4's limit on the real axis is 2.7853/λ = 3.0e-4 s.
    /// The search starts at τ/400, τ = 2π/10 s (1.57 ms), so the series runs 1e-3 and 5e-4
    /// (|R(−hλ)| = 219 and 9.8: the run fails) and accepts 2e-4 (|R| = 0.30).
    #[test]
    fn rk4_step_of_a_scene_without_a_driven_crank() {
        let d = tempfile::tempdir().unwrap();
        let scene = crate::run::tests::motor_hub_scene(58327.0, 0.05);
        let path = d.path().join("stiff_motor.json");
        std::fs::write(&path, scene.to_string()).unwrap();
        let p = Prepared::load_spec(path.to_str().unwrap(), None).unwrap();
        let search = Rk4Search::of(&p, None).unwrap();
        let tau = std::f64::consts::TAU / 10.0;
        assert!((search.top - tau / 400.0).abs() < 1e-15, "{search:?}");
        // L/100 with c = 0.05 − 0.0499 m (to the rounding of the difference).
        assert!((search.phi_max / 1e-6 - 1.0).abs() < 1e-12, "{search:?}");
        assert_eq!(stable_rk4_step(&p, None).unwrap(), 2e-4);
        // A test problem has no scene to search: an option error naming the steps.
        let t = Prepared::load_spec("testset:hires", None).unwrap();
        let e = Rk4Search::of(&t, None).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::BadInput, "{e}");
    }

    fn s(t: f64, a: f64, ex: f64) -> Sample {
        Sample {
            slider_a: Some(a),
            ex_over_c: Some(ex),
            ey_over_c: Some(0.0),
            ..Sample::at(t)
        }
    }

    #[test]
    fn norms_of_known_differences() {
        // a_ref = (3, 4): Σ a_ref² = 25; a = (3, 4.5): Σ Δ² = 0.25 → relative RMS 0.1.
        let r = [s(0.0, 3.0, 0.1), s(1.0, 4.0, 0.2)];
        let a = [s(0.0, 3.0, 0.4), s(1.0, 4.5, 0.2)];
        let n = ErrorNorms::between(&a, &[1.0, 0.0], &r, &[1.0, 0.0]).unwrap();
        assert!((n.slider_acc_rel_rms.unwrap() - 0.1).abs() < 1e-15);
        assert_eq!(n.slider_acc_max_abs, Some(0.5));
        assert!((n.orbit_max.unwrap() - 0.3).abs() < 1e-15);
        assert_eq!(n.state_rel_rms, 0.0);
        assert_eq!(n.headline(), n.slider_acc_rel_rms.unwrap());
        // Without a slider the orbit is the headline; without either, the state.
        let bare = [Sample::at(0.0)];
        let n = ErrorNorms::between(&bare, &[2.0, 0.0], &bare, &[1.0, 0.0]).unwrap();
        assert_eq!((n.slider_acc_rel_rms, n.orbit_max), (None, None));
        assert_eq!(n.headline(), 1.0);
        assert!(ErrorNorms::between(&a[..1], &[], &r, &[]).is_err());
    }

    #[test]
    fn markdown_names_the_reference_and_marks_failures() {
        let c = Comparison {
            case: "x".into(),
            reference: "dop853 at rtol 1e-12".into(),
            reference_agreement: None,
            window: ErrorWindow {
                start: 0.0,
                end: 0.2,
                label: "first half revolution".into(),
            },
            t_end: 0.4,
            error_measure: "largest error of the journal centre, in clearances".into(),
            runs: vec![Compared {
                method: Method::Rk4,
                controller: None,
                rtol: None,
                step: Some(2e-4),
                norms: None,
                error: None,
                wall_time_s: 0.5,
                rhs_evals: 10,
                steps: 2,
                events: 0,
                contact_onsets: None,
                failure: Some("non-finite | state".into()),
                formulation: None,
            }],
        };
        let md = c.to_markdown();
        assert!(md.contains("Reference: dop853 at rtol 1e-12."));
        assert!(md.contains("first half revolution [0, 0.2] s"));
        // It names the error of the scene at hand, not the slider's.
        assert!(
            md.contains(
                "`error` is the largest error of the journal centre, in clearances for this case"
            ),
            "{md}"
        );
        assert!(
            !md.contains("relative RMS error of the slider acceleration"),
            "{md}"
        );
        assert!(
            md.contains("| rk4 | h 2e-4 | failed: non-finite \\| state |"),
            "{md}"
        );
    }
}
