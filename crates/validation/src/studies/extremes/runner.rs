//! Running the matrix: each scene's reference (the ladder of tolerances, two methods), each
//! setting's run against it, the cache of finished references and runs, the counts per row.
//!
//! Source: the module doc of `studies::extremes`.

use std::collections::BTreeMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use lash_solver::Method;

use crate::compare::reference::ErrorWindow;
use crate::compare::workprecision::fmt_num;
use crate::error::Error;
use crate::progress::Progress;
use crate::run::plan::RunRequest;
use crate::run::prepare::Prepared;
use crate::run::result::RunResult;
use crate::run::simulate::simulate;
use crate::store::cache::RunCache;
use crate::studies::extremes::catalogue::catalogue;
use crate::studies::extremes::catalogue::ExtremeScene;
use crate::studies::extremes::outcome::known_finding;
use crate::studies::extremes::outcome::Cell;
use crate::studies::extremes::outcome::FailureKind;
use crate::studies::extremes::outcome::Matrix;
use crate::studies::extremes::outcome::Outcome;
use crate::studies::extremes::outcome::RowCount;
use crate::studies::extremes::outcome::SceneReport;
use crate::studies::extremes::plan::alpha;
use crate::studies::extremes::plan::settings;
use crate::studies::extremes::plan::Budget;
use crate::studies::extremes::plan::Plan;
use crate::studies::extremes::plan::Setting;
use crate::studies::extremes::plan::ADAPTIVE;
use crate::studies::extremes::plan::PROMISE_C_DRY;
use crate::studies::extremes::plan::PROMISE_C_LUBRICATED;
use crate::studies::extremes::plan::PROMISE_C_RK4;
use crate::studies::extremes::plan::PROMISE_F;
use crate::studies::extremes::plan::REFERENCE_MAX_STEPS;
use crate::studies::extremes::plan::REFERENCE_MAX_WALL_TIME;
use crate::studies::extremes::plan::REFERENCE_RTOLS_DRY;
use crate::studies::extremes::plan::REFERENCE_RTOLS_LUBRICATED;

/// The slider of a reference run on the error window: what the error of a run against it
/// needs (and what the cache keeps of a reference).
///
/// ```text
/// x*_k, v*_k on the window grid;  s_x = r,  s_v = max(r ω, max_k |v*_k|)
/// ```
///
/// Source: module doc.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct ReferenceSlider {
    /// Slider positions x*_k, m.
    pub x: Vec<f64>,
    /// Slider velocities v*_k, m/s.
    pub v: Vec<f64>,
    /// Position scale s_x = r, m.
    pub s_x: f64,
    /// Velocity scale s_v, m/s.
    pub s_v: f64,
}

impl ReferenceSlider {
    /// The slider of `reference` (a run with samples on the window grid).
    pub(crate) fn of(reference: &RunResult) -> Result<ReferenceSlider, Error> {
        let ideal = reference.ideal.ok_or_else(|| {
            Error::Internal("extremes: the scene is not a slider-crank with a closed form".into())
        })?;
        let mut x = Vec::with_capacity(reference.extra.len());
        let mut v = Vec::with_capacity(reference.extra.len());
        for s in &reference.extra {
            match (s.slider_x, s.slider_v) {
                (Some(a), Some(b)) => {
                    x.push(a);
                    v.push(b);
                }
                _ => {
                    return Err(Error::Internal(
                        "extremes: a sample without the slider".into(),
                    ))
                }
            }
        }
        let v_max = v.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        Ok(ReferenceSlider {
            s_x: ideal.r,
            s_v: (ideal.r * ideal.omega.abs()).max(v_max),
            x,
            v,
        })
    }

    /// The error of `run` against this reference (module doc).
    ///
    /// ```text
    /// e = max( max_k |x_k − x*_k| / s_x,  max_k |v_k − v*_k| / s_v )
    /// ```
    pub(crate) fn error(&self, run: &RunResult) -> Result<f64, Error> {
        if run.extra.len() != self.x.len() || run.extra.is_empty() {
            return Err(Error::Internal(format!(
                "extremes: {} samples against {} reference samples",
                run.extra.len(),
                self.x.len()
            )));
        }
        let mut e = 0.0f64;
        for (k, a) in run.extra.iter().enumerate() {
            match (a.slider_x, a.slider_v) {
                (Some(x), Some(v)) => {
                    e = e
                        .max((x - self.x[k]).abs() / self.s_x)
                        .max((v - self.v[k]).abs() / self.s_v);
                }
                _ => {
                    return Err(Error::Internal(
                        "extremes: a sample without the slider".into(),
                    ))
                }
            }
        }
        if !e.is_finite() {
            return Err(Error::Internal(format!("extremes: error {e} not finite")));
        }
        Ok(e)
    }
}

/// The error of a run against the reference (module doc), on the window samples
/// ([`ReferenceSlider::error`] of [`ReferenceSlider::of`] `reference`).
///
/// ```text
/// e = max( max_k |x_k − x*_k| / s_x,  max_k |v_k − v*_k| / s_v ),  s_x = r,
/// s_v = max(r ω, max_k |v*_k|)
/// ```
pub(crate) fn slider_error(run: &RunResult, reference: &RunResult) -> Result<f64, Error> {
    ReferenceSlider::of(reference)?.error(run)
}

/// Runs one setting on the error window (no trajectory, no energy) with the budget.
fn run_setting(
    p: &Prepared,
    method: Method,
    rtol: Option<f64>,
    step: Option<f64>,
    window: &ErrorWindow,
    budget: &Budget,
) -> Result<RunResult, Error> {
    let mut o = p.options_for(method, rtol, step, None)?;
    o.max_steps = budget.max_steps;
    o.max_wall_time = Some(budget.max_wall_time);
    let mut req = RunRequest::new(o);
    req.extra_times = window.grid();
    req.trajectory_points = Some(0);
    req.energy = false;
    simulate(p, &req)
}

/// Why a returned result is not acceptable as numbers (non-finite values), if it is not.
fn non_finite(r: &RunResult) -> Option<String> {
    for s in &r.extra {
        let vals = [
            s.slider_x,
            s.slider_v,
            s.slider_a,
            s.eps,
            s.delta,
            s.contact_force,
            s.friction_force,
            s.film_force,
        ];
        if vals.iter().flatten().any(|v| !v.is_finite()) || !s.constraint_violation.is_finite() {
            return Some(format!("non-finite output at t = {:e}: {s:?}", s.t));
        }
    }
    if r.extra_states.y.iter().any(|v| !v.is_finite()) {
        return Some("non-finite state in the result".into());
    }
    None
}

/// The outcome of a run that ended in an error.
fn failure_outcome(e: &Error, t0: f64, t_end: f64) -> Outcome {
    let Error::Solver(se) = e else {
        return Outcome::Rejected {
            reason: format!("untyped error: {e}"),
        };
    };
    let Some(kind) = FailureKind::of(se) else {
        return Outcome::Rejected {
            reason: format!("not an allowed solver error: {se}"),
        };
    };
    let t = se.time().unwrap_or(f64::NAN);
    let y_ok = se
        .state()
        .is_some_and(|y| !y.is_empty() && y.iter().all(|v| v.is_finite()));
    let tol = 1e-9 * (t_end - t0).abs();
    if !(t.is_finite() && t >= t0 - tol && t <= t_end + tol && y_ok) {
        return Outcome::Rejected {
            reason: format!(
                "typed error without a finite time in the run and a finite state: {se}"
            ),
        };
    }
    Outcome::Failed {
        kind,
        t,
        message: se.to_string(),
    }
}

fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "panic with a non-string payload".into()
    }
}

/// A scene ready for its runs: the case, its window and its reference run.
///
/// ```text
/// (scene, prepared case, report with window and E_ref, reference run on the window grid)
/// ```
///
/// Source: module doc.
pub struct Ready {
    /// The catalogue entry.
    pub scene: ExtremeScene,
    /// The case.
    pub(crate) prepared: Prepared,
    /// Window, reference and its agreement.
    pub report: SceneReport,
    /// The slider of the reference run (method A) on the window grid.
    pub(crate) reference: ReferenceSlider,
}

/// Whether a scene has a dry clearance joint (its promise uses [`PROMISE_C_DRY`]).
pub(crate) fn is_dry(p: &Prepared) -> bool {
    p.info.as_ref().is_some_and(|i| i.has_dry_joint)
}

/// Reference methods and rtol ladder of a scene (module doc).
pub(crate) fn reference_plan(p: &Prepared) -> (Method, Method, &'static [f64]) {
    if is_dry(p) {
        (Method::Rodas5p, Method::Dop853, &REFERENCE_RTOLS_DRY)
    } else {
        (Method::Bdf, Method::Esdirk34, &REFERENCE_RTOLS_LUBRICATED)
    }
}

/// Prepares a scene: its case, error window and reference (the ladder of
/// `reference_plan`); a reference that fails at every rung is the solver's error.
pub fn prepare(scene: ExtremeScene) -> Result<Ready, Error> {
    let p = scene.prepared()?;
    let (t0, t_end) = p.t_span(None)?;
    let window = ErrorWindow::of(&p, t0, t_end);
    let (a, b, ladder) = reference_plan(&p);
    let budget = Budget {
        max_steps: REFERENCE_MAX_STEPS,
        max_wall_time: REFERENCE_MAX_WALL_TIME,
    };
    let mut failures = Vec::new();
    let mut last = None;
    for &rtol in ladder {
        let ra = run_setting(&p, a, Some(rtol), None, &window, &budget);
        // The check runs only when the reference did.
        let rb = ra
            .is_ok()
            .then(|| run_setting(&p, b, Some(rtol), None, &window, &budget));
        match (ra, rb) {
            (Ok(ra), Some(Ok(rb))) => {
                let agreement_methods = slider_error(&rb, &ra)?;
                let agreement_tolerance =
                    match run_setting(&p, a, Some(10.0 * rtol), None, &window, &budget) {
                        Ok(loose) => slider_error(&loose, &ra)?,
                        Err(Error::Solver(se)) => {
                            return Err(Error::Internal(format!(
                                "extremes: {}: {a} at rtol {} succeeded but failed at {}: {se}",
                                scene.stem,
                                fmt_num(rtol),
                                fmt_num(10.0 * rtol)
                            )))
                        }
                        Err(e) => return Err(e),
                    };
                let agreement = agreement_methods.max(agreement_tolerance);
                let eps_max = ra
                    .extra
                    .iter()
                    .filter_map(|s| s.eps)
                    .fold(None, |m: Option<f64>, e| Some(m.map_or(e, |m| m.max(e))));
                let report = SceneReport {
                    stem: scene.stem.to_string(),
                    stresses: scene.stresses.to_string(),
                    t_end,
                    window,
                    reference: a,
                    check: b,
                    reference_rtol: rtol,
                    reference_failures: failures,
                    agreement_methods,
                    agreement_tolerance,
                    agreement,
                    eps_max,
                    reference_wall_time_s: ra.summary.wall_time_s + rb.summary.wall_time_s,
                    rk4_steps: (scene.rk4_inside, scene.rk4_beyond),
                };
                return Ok(Ready {
                    scene,
                    prepared: p,
                    report,
                    reference: ReferenceSlider::of(&ra)?,
                });
            }
            (ra, rb) => {
                for (m, r) in [(a, Some(ra)), (b, rb)] {
                    if let Some(Err(e)) = r {
                        if let Error::Solver(se) = &e {
                            failures.push(format!("{m} at rtol {}: {se}", fmt_num(rtol)));
                            last = Some(e);
                        } else {
                            return Err(e);
                        }
                    }
                }
            }
        }
    }
    Err(last.unwrap_or_else(|| Error::Internal("extremes: no reference".into())))
}

/// C of the promise of a scene: [`PROMISE_C_DRY`] or [`PROMISE_C_LUBRICATED`].
pub(crate) fn promise_c(p: &Prepared) -> f64 {
    if is_dry(p) {
        PROMISE_C_DRY
    } else {
        PROMISE_C_LUBRICATED
    }
}

/// Runs one setting on a prepared scene (never panics: a panic becomes
/// [`Outcome::Panicked`]).
pub fn run_cell(r: &Ready, setting: Setting, budget: &Budget) -> Cell {
    let t0 = r.prepared.info.as_ref().map_or(0.0, |i| i.t_start);
    let t_end = r.report.t_end;
    let floor = PROMISE_F * r.report.agreement;
    let result = catch_unwind(AssertUnwindSafe(|| -> Result<Cell, Error> {
        let p = &r.prepared;
        let w = &r.report.window;
        let (run, rtol, step) = match setting {
            Setting::Rk4Inside { h } | Setting::Rk4Beyond { h } => (
                run_setting(p, Method::Rk4, None, Some(h), w, budget),
                None,
                Some(h),
            ),
            Setting::Adaptive { method, rtol } => (
                run_setting(p, method, Some(rtol), None, w, budget),
                Some(rtol),
                None,
            ),
        };
        let mut cell = Cell {
            scene: r.scene.stem.to_string(),
            setting,
            outcome: Outcome::Rejected {
                reason: String::new(),
            },
            measured_c: None,
            wall_time_s: 0.0,
            steps: 0,
        };
        let run = match run {
            Ok(run) => run,
            Err(e) => {
                cell.outcome = failure_outcome(&e, t0, t_end);
                if let (Setting::Rk4Beyond { .. }, Outcome::Failed { kind, .. }) =
                    (setting, &cell.outcome)
                {
                    // A blown-up mechanism may first come apart: the constraint-violation
                    // check of an accepted step (docs/model.md §12.1) is a stop too.
                    if !matches!(
                        kind,
                        FailureKind::NonFiniteState
                            | FailureKind::Rk4Unstable
                            | FailureKind::StateRejected
                    ) {
                        cell.outcome = Outcome::Rejected {
                            reason: format!(
                                "rk4 beyond its stability limit failed with {e} instead of its \
                                 stability stop, a non-finite state or a refused step"
                            ),
                        };
                    }
                }
                return Ok(cell);
            }
        };
        cell.wall_time_s = run.summary.wall_time_s;
        cell.steps = run.summary.stats.accepted;
        if let Some(why) = non_finite(&run) {
            cell.outcome = Outcome::Rejected { reason: why };
            return Ok(cell);
        }
        if matches!(setting, Setting::Rk4Beyond { .. }) {
            cell.outcome = Outcome::Rejected {
                reason: "rk4 beyond its stability limit returned numbers".into(),
            };
            return Ok(cell);
        }
        let error = r.reference.error(&run)?;
        let promise = match (rtol, step) {
            (Some(rtol), _) => {
                let scale = rtol.powf(alpha(setting.method()));
                cell.measured_c = Some((error - floor).max(0.0) / scale);
                promise_c(&r.prepared) * scale + floor
            }
            (None, Some(h)) => match run_setting(p, Method::Rk4, None, Some(0.5 * h), w, budget) {
                Ok(half) => {
                    if let Some(why) = non_finite(&half) {
                        cell.outcome = Outcome::Rejected {
                            reason: format!("h/2 run: {why}"),
                        };
                        return Ok(cell);
                    }
                    let d = slider_error(&run, &half)?;
                    cell.measured_c = (d > 0.0).then(|| (error - floor).max(0.0) / d);
                    PROMISE_C_RK4 * d + floor
                }
                Err(e) => {
                    cell.outcome = match failure_outcome(&e, t0, t_end) {
                        Outcome::Failed { kind, t, message } => Outcome::Failed {
                            kind,
                            t,
                            message: format!("the h/2 run of the promise: {message}"),
                        },
                        other => other,
                    };
                    return Ok(cell);
                }
            },
            (None, None) => return Err(Error::Internal("a setting without rtol or step".into())),
        };
        cell.outcome = if error <= promise {
            Outcome::Agrees { error, promise }
        } else if let Some(k) = known_finding(&cell.scene, &setting) {
            Outcome::Known {
                error,
                promise,
                why: k.why.to_string(),
            }
        } else {
            Outcome::Disagrees { error, promise }
        };
        Ok(cell)
    }));
    let blank = |outcome| Cell {
        scene: r.scene.stem.to_string(),
        setting,
        outcome,
        measured_c: None,
        wall_time_s: 0.0,
        steps: 0,
    };
    match result {
        Ok(Ok(cell)) => cell,
        Ok(Err(e)) => blank(Outcome::Rejected {
            reason: format!("harness error: {e}"),
        }),
        Err(p) => blank(Outcome::Panicked {
            message: panic_message(p.as_ref()),
        }),
    }
}

/// What a scene's reference leaves for the cache: its report and its slider.
#[derive(serde::Serialize, serde::Deserialize)]
struct CachedReference {
    report: SceneReport,
    slider: ReferenceSlider,
}

/// Runs the matrix of `plan`. A reference that cannot be computed at any rtol of the ladder
/// is the solver's error (exit 3); everything else is recorded in the cells. `progress`
/// receives one item per reference computed and per run done. With a `cache`
/// ([`crate::store::cache`]), every finished reference and run is stored there and one found there
/// is not done again. A stop request (`lash_solver::interrupt`) abandons the work in flight
/// and starts no other: [`Error::Interrupted`], with what is kept.
pub(crate) fn run_cached(
    plan: &Plan,
    cache: Option<&RunCache>,
    progress: &dyn Progress,
) -> Result<Matrix, Error> {
    let clock = Instant::now();
    let all = catalogue();
    let mut scenes = Vec::new();
    for stem in &plan.scenes {
        let s = all
            .iter()
            .find(|s| s.stem == stem)
            .cloned()
            .ok_or_else(|| Error::Usage(format!("extremes: no scene named '{stem}'")))?;
        scenes.push(s);
    }
    let key = |kind: &str, inputs: &serde_json::Value| -> Result<Option<String>, Error> {
        cache.map(|c| c.key(kind, inputs)).transpose()
    };
    let found = |k: &Option<String>| matches!((cache, k), (Some(c), Some(k)) if c.contains(k));
    let ref_keys: Vec<Option<String>> = scenes
        .iter()
        .map(|s| {
            key(
                "extremes reference",
                &serde_json::json!({"scene": s.json()}),
            )
        })
        .collect::<Result<_, _>>()?;
    let kept = AtomicUsize::new(0);
    let interrupted = |what: &str, total: usize| {
        Error::Interrupted(format!(
            "extremes: {} {what} finished and kept{}; rerun the same command to resume",
            kept.load(Ordering::Relaxed),
            cache.map_or(String::new(), |c| format!(
                " in {} (of {total} to do)",
                c.dir().display()
            ))
        ))
    };
    let reused = ref_keys.iter().filter(|k| found(k)).count();
    progress.started("references", scenes.len() - reused);
    let mut ready = Vec::new();
    for (s, k) in scenes.into_iter().zip(&ref_keys) {
        let stem = s.stem;
        let from_cache = match (cache, k) {
            (Some(c), Some(k)) => c.load::<CachedReference>(k),
            _ => None,
        };
        let r = match from_cache {
            Some(c) => Ready {
                prepared: s.prepared()?,
                scene: s,
                report: c.report,
                reference: c.slider,
            },
            None => {
                if lash_solver::interrupt::stop_requested() {
                    return Err(interrupted("references", ref_keys.len()));
                }
                let t = Instant::now();
                let r = catch_unwind(AssertUnwindSafe(|| prepare(s))).map_err(|p| {
                    Error::Internal(format!(
                        "extremes: the reference of {stem} panicked: {}",
                        panic_message(p.as_ref())
                    ))
                })?;
                let r = match r {
                    Err(e) if e.is_interrupted() => {
                        return Err(interrupted("references", ref_keys.len()))
                    }
                    other => other?,
                };
                if let (Some(c), Some(k)) = (cache, k) {
                    c.store(
                        k,
                        &CachedReference {
                            report: r.report.clone(),
                            slider: r.reference.clone(),
                        },
                    )?;
                }
                kept.fetch_add(1, Ordering::Relaxed);
                progress.finished(
                    &format!(
                        "{stem}: reference {} vs {} at rtol {}: E_ref = {}, ε_max = {}",
                        r.report.reference,
                        r.report.check,
                        fmt_num(r.report.reference_rtol),
                        fmt_num(r.report.agreement),
                        r.report.eps_max.map_or("–".into(), fmt_num)
                    ),
                    t.elapsed().as_secs_f64(),
                );
                r
            }
        };
        ready.push(r);
    }
    let jobs: Vec<(usize, Setting)> = ready
        .iter()
        .enumerate()
        .flat_map(|(i, r)| {
            settings(&r.scene, &plan.tolerances)
                .into_iter()
                .map(move |s| (i, s))
        })
        .collect();
    let keys: Vec<Option<String>> = jobs
        .iter()
        .map(|(i, s)| {
            key(
                "extremes run",
                &serde_json::json!({
                    "scene": ready[*i].scene.json(),
                    "setting": s,
                    "budget": plan.budget,
                    "reference": ref_keys[*i],
                }),
            )
        })
        .collect::<Result<_, _>>()?;
    let reused_cells = keys.iter().filter(|k| found(k)).count();
    if reused + reused_cells > 0 {
        progress.note(
            &format!(
                "extremes: {reused} of {} references and {reused_cells} of {} runs finished \
                 before, reused from {}",
                ready.len(),
                jobs.len(),
                cache.map_or(String::new(), |c| c.dir().display().to_string())
            )
            .into(),
        );
    }
    kept.store(0, Ordering::Relaxed);
    progress.started("runs", jobs.len() - reused_cells);
    let work = |(&(i, s), k): (&(usize, Setting), &Option<String>)| -> Result<Cell, Error> {
        if let (Some(c), Some(k)) = (cache, k) {
            if let Some(cell) = c.load::<Cell>(k) {
                return Ok(cell);
            }
        }
        if lash_solver::interrupt::stop_requested() {
            return Err(Error::Interrupted(String::new()));
        }
        let t = Instant::now();
        let c = run_cell(&ready[i], s, &plan.budget);
        // A run cut short by the stop request is not a result.
        if lash_solver::interrupt::stop_requested() {
            return Err(Error::Interrupted(String::new()));
        }
        if let (Some(cache), Some(k)) = (cache, k) {
            cache.store(k, &c)?;
        }
        kept.fetch_add(1, Ordering::Relaxed);
        progress.finished(
            &format!(
                "{} {} {}: {}",
                c.scene,
                c.setting.label(),
                setting_value(&c.setting),
                c.outcome.cell()
            ),
            t.elapsed().as_secs_f64(),
        );
        Ok(c)
    };
    let threads = crate::progress::jobs_within_parallelism(Some(plan.jobs), progress);
    let cells: Result<Vec<Cell>, Error> = if threads > 1 {
        use rayon::prelude::*;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| Error::Internal(format!("extremes: thread pool: {e}")))?;
        pool.install(|| jobs.par_iter().zip(&keys).map(work).collect())
    } else {
        jobs.iter().zip(&keys).map(work).collect()
    };
    let cells = match cells {
        Err(e) if e.is_interrupted() => return Err(interrupted("runs", jobs.len())),
        other => other?,
    };
    let counts = count_rows(&cells);
    let failures = cells.iter().filter(|c| c.outcome.is_failure()).count();
    Ok(Matrix {
        version: env!("CARGO_PKG_VERSION").to_string(),
        plan: plan.clone(),
        promise_c_dry: PROMISE_C_DRY,
        promise_c_lubricated: PROMISE_C_LUBRICATED,
        promise_c_rk4: PROMISE_C_RK4,
        promise_f: PROMISE_F,
        scenes: ready.into_iter().map(|r| r.report).collect(),
        cells,
        counts,
        failures,
        wall_time_s: clock.elapsed().as_secs_f64(),
    })
}

pub(crate) fn setting_value(s: &Setting) -> String {
    match s {
        Setting::Rk4Inside { h } | Setting::Rk4Beyond { h } => format!("h {}", fmt_num(*h)),
        Setting::Adaptive { rtol, .. } => format!("rtol {}", fmt_num(*rtol)),
    }
}

fn count_rows(cells: &[Cell]) -> Vec<RowCount> {
    let mut labels: Vec<String> = vec!["rk4".into(), "rk4 beyond".into()];
    labels.extend(ADAPTIVE.iter().map(|m| m.name().to_string()));
    labels
        .into_iter()
        .map(|label| {
            let mine: Vec<&Cell> = cells
                .iter()
                .filter(|c| c.setting.label() == label)
                .collect();
            let mut errored = BTreeMap::new();
            for c in &mine {
                if let Outcome::Failed { kind, .. } = c.outcome {
                    *errored.entry(kind.short().to_string()).or_insert(0) += 1;
                }
            }
            RowCount {
                runs: mine.len(),
                agreed: mine
                    .iter()
                    .filter(|c| matches!(c.outcome, Outcome::Agrees { .. }))
                    .count(),
                errored,
                known: mine
                    .iter()
                    .filter(|c| matches!(c.outcome, Outcome::Known { .. }))
                    .count(),
                failures: mine.iter().filter(|c| c.outcome.is_failure()).count(),
                measured_c_max: mine
                    .iter()
                    .filter(|c| !matches!(c.outcome, Outcome::Known { .. }))
                    .filter_map(|c| c.measured_c)
                    .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v)))),
                label,
            }
        })
        .collect()
}
