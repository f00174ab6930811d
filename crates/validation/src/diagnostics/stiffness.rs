//! `lash stiffness CASE`: the Jacobian's dominant eigenvalues along a trajectory, the RK4 step
//! limit they predict, the limit measured by bisection, and which method family should win.
//!
//! ```text
//! reference run     the case's solver options (default bdf rtol 1e-8; test problems rodas5p),
//!                   one Integrator; at each of N equally spaced times t_k (both ends) the dense
//!                   output y_k is analysed at once (so a contact law's stored impact velocity is
//!                   the one in force): J = ∂f/∂y (t_k, y_k), λ_i = eig(J) (faer)
//! per sample        ρ = max|λ_i|,  h_k = min_i r(arg λ_i)/|λ_i| over Re λ_i ≤ 0 (RK4's ray
//!                   limit: r = 2.785 on the negative real axis, 2√2 on the imaginary axis),
//!                   S = max|Re λ| / min|Re λ| over decaying modes, growing modes Re λ > 0
//! predicted limit   h_pred = min_k h_k (and where: t, crank angle, the limiting λ); also the
//!                   5th percentile of h_k (the limit on 95 % of the run: a single deep impact
//!                   between flights sets the minimum but not the percentile)
//! measured limit    fixed-step RK4 over the whole run, without event location, bisection on
//!                   ln h until h_unstable/h_stable ≤ 1 + 1e-4; stable(h) ⇔ no non-finite state
//!                   and max_k ‖y_k‖∞ ≤ 10 · M_ref (M_ref: the run at the bracket's lower end,
//!                   checked against h/2), and for a mechanism ‖Φ(q_k, t_k)‖₂ ≤ c/100 at every
//!                   accepted step ([`PHI_MAX_PER_LENGTH`]); bracket [h_pred/2, 2 h_pred]
//!                   widened by ×4 until it brackets
//!                   (lash_solver::analysis::stiffness::measure_rk4_limit_where)
//! accuracy step     h_acc = median accepted step of the reference run (an implicit method's
//!                   steps are set by accuracy alone, not by stability)
//! verdict           q = h_acc / h_stab (h_stab = measured h_stable, else h_pred):
//!                   q ≤ 1 explicit · 1 < q < 10 either · q ≥ 10 implicit
//! files             stiffness.csv, stiffness.{svg,png}, stiffness.md, stiffness.json (last)
//! ```
//!
//! The eigenvalue analysis is local (the linearisation at one point); the measured limit
//! answers the global question over the run. Sources: E. Hairer, G. Wanner, *Solving Ordinary
//! Differential Equations II*, 2nd ed., Springer 1996, §IV.2 (RK4's stability domain) and
//! §IV.1 (stiffness); J. D. Lambert, *Numerical Methods for Ordinary Differential Systems*,
//! Wiley 1991, ch. 6 (stiffness ratio).

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use lash_model::Mechanism;
use lash_solver::analysis::stiffness::{
    analyze, measure_rk4_limit_where, verdict, Eigenvalue, MeasuredLimit, Rk4ProbeOptions,
    StateCheck, StiffnessOptions, StiffnessSummary, Verdict,
};
use lash_solver::analysis::AnalysisError;
use lash_solver::{Method, OdeSystem, Problem, SolverOptions, Stats, StepOutcome};

use crate::error::{Error, OptionError};
use crate::progress::Progress;
use crate::report::plot::{self, Axes, Panel, Series, SeriesStyle};
use crate::report::summary::RunHeader;
use crate::report::trajectory::fmt_num;
use crate::run::simulate::{uniform_grid, Model, Prepared, Sampler, DEFAULT_LENGTH_SCALE};
use crate::store::io;

/// Default number of sample points along the run (both ends included): every 0.72° of crank
/// angle over the paper's two revolutions; the analysis of a sample (one analytic Jacobian, the
/// eigenvalues of a 12 × 12 matrix) is cheap next to the measurement of the RK4 limit
/// (BENCHMARKS.md, "Diagnostics").
pub const DEFAULT_SAMPLES: usize = 1000;
/// Fewest sample points.
pub const MIN_SAMPLES: usize = 2;
/// Most RK4 steps one probe run of the measurement may take; a bracket that would need more
/// ends the measurement with a note instead (a stiff test problem over a long span).
pub const MAX_PROBE_STEPS: f64 = 2e7;
/// Most bracket attempts of the measurement (each widens the bracket by a factor 4).
pub const MAX_BRACKET_ATTEMPTS: usize = 8;
/// Largest constraint violation ‖Φ(q, t)‖₂ of a stable RK4 run of a mechanism, as a fraction
/// of its length scale L (the smallest clearance, else 1e-3 m): Φ_max = L/100.
///
/// Why: beyond its RK4 limit the clearance joint's fast mode (the oil film's squeeze damping,
/// the contact stiffness) does not always blow the state up. The nonlinear film and contact
/// forces keep the journal within about a clearance, so max ‖y‖∞ (0.4 m of slider travel) never
/// grows tenfold while the run is garbage, and whether a run diverges is not even monotonic in
/// h. ‖Φ‖ tells them apart: past the limit it grows by orders of magnitude, while stable runs
/// keep it at the Baumgarte and truncation level, far below L/100 (measurements on the press:
/// BENCHMARKS.md, "RK4 beyond its stability limit").
/// The check sees the accepted states only: an RK4 stage state y_n + (h/2)k moves pinned points
/// along tangents and violates Φ by about |a| h²/8 (1e-8 m at 0.15 ms on the press) without any
/// instability.
pub const PHI_MAX_PER_LENGTH: f64 = 1e-2;
/// Stems of the files written.
pub const FILES: [&str; 4] = [
    "stiffness.csv",
    "stiffness.png",
    "stiffness.md",
    "stiffness.json",
];

/// What `lash stiffness` does besides the case's solver options.
///
/// ```text
/// samples N ≥ 2 (default 1000); t_end override; measure the RK4 limit (default yes);
/// probe: growth_bound 10, rel_tol 1e-4 (Rk4ProbeOptions)
/// ```
///
/// Source: docs/outputs.md ("`lash stiffness CASE`").
#[derive(Clone, Debug, PartialEq)]
pub struct StiffnessSettings {
    /// Sample points along the run, both ends included (≥ 2).
    pub samples: usize,
    /// End-time override, s (scene cases only).
    pub t_end: Option<f64>,
    /// Whether to measure the RK4 limit by bisection (RK4 runs over the whole span).
    pub measure: bool,
    /// The stability criterion and resolution of the measurement.
    pub probe: Rk4ProbeOptions,
}

impl Default for StiffnessSettings {
    fn default() -> Self {
        StiffnessSettings {
            samples: DEFAULT_SAMPLES,
            t_end: None,
            measure: true,
            probe: Rk4ProbeOptions::default(),
        }
    }
}

/// The analysis at one sample point (one row of stiffness.csv).
///
/// ```text
/// dominant = λ of largest modulus (+im first),  ρ = |dominant|,
/// h = min r(arg λ)/|λ| over Re λ ≤ 0,  S = max|Re λ|/min|Re λ| over Re λ < 0
/// ```
///
/// HNW II §IV.2; Lambert (1991), ch. 6.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StiffnessPoint {
    /// Time, s.
    pub t: f64,
    /// Crank angle, rad (not wrapped), when the case has a crank.
    pub crank_angle: Option<f64>,
    /// The eigenvalue of largest modulus.
    pub dominant: Eigenvalue,
    /// Spectral radius ρ = max |λ_i|, 1/s.
    pub spectral_radius: f64,
    /// Stiffness ratio over the decaying modes (None without any).
    pub stiffness_ratio: Option<f64>,
    /// RK4 step limit predicted at this point, s (None when no mode limits the step).
    pub rk4_h_max: Option<f64>,
    /// The eigenvalue that sets `rk4_h_max`.
    pub limiting: Option<Eigenvalue>,
    /// Number of growing modes (Re λ > 0) of the linearisation.
    pub n_unstable: usize,
}

impl StiffnessPoint {
    fn new(s: &StiffnessSummary, crank_angle: Option<f64>) -> StiffnessPoint {
        StiffnessPoint {
            t: s.t,
            crank_angle,
            dominant: s
                .dominant
                .first()
                .copied()
                .unwrap_or(Eigenvalue { re: 0.0, im: 0.0 }),
            spectral_radius: s.spectral_radius,
            stiffness_ratio: s.stiffness_ratio,
            rk4_h_max: s.rk4_h_max,
            limiting: s.limiting,
            n_unstable: s.unstable.len(),
        }
    }
}

/// The points of a reference run and what the run itself says about the step.
///
/// ```text
/// points at the requested times; steps = accepted step sizes t_n − t_{n−1}
/// ```
///
/// Source: this module.
#[derive(Clone, Debug)]
pub struct Sampled {
    /// One analysis per requested time (fewer if a stopping event ended the run).
    pub points: Vec<StiffnessPoint>,
    /// Accepted step sizes of the reference run, s.
    pub steps: Vec<f64>,
    /// The reference run's counters.
    pub stats: Stats,
    /// Wall time of the run and the analyses, s.
    pub wall_time_s: f64,
}

impl Sampled {
    /// The median accepted step (the accuracy step of an implicit reference run), s.
    pub fn median_step(&self) -> Option<f64> {
        median(&self.steps)
    }
}

/// The q-quantile of `v` (0 ≤ q ≤ 1): the value of rank ⌊q (n − 1)⌋ in increasing order.
fn percentile(v: &[f64], q: f64) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    Some(s[(q * (s.len() - 1) as f64).floor() as usize])
}

fn median(v: &[f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    Some(if !n.is_multiple_of(2) {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    })
}

/// An analysis failure as a command error: a solver failure stays one (exit 3); a non-finite
/// Jacobian or eigenvalue at a finite state, or an eigenvalue iteration that does not converge,
/// is a defect of the model or the analysis (exit 1); bad settings are usage errors (exit 2).
pub fn analysis_error(e: AnalysisError) -> Error {
    match e {
        AnalysisError::Solve(s) => Error::from(s),
        AnalysisError::InvalidInput(m) => Error::Usage(m),
        AnalysisError::Degenerate { t, reason } => {
            Error::Input(format!("analysis cannot go on at t = {t:e}: {reason}"))
        }
        other => Error::Internal(other.to_string()),
    }
}

/// Integrates `sys` over `t_span` from `y0` with `opts` and analyses the dense output at
/// `times` (sorted, inside the span) as soon as a step covers them; `angle(t, y)` gives the
/// crank angle of a sample (None without a crank). Records every accepted step size.
pub fn sample_along<S: OdeSystem + ?Sized>(
    sys: &S,
    t_span: (f64, f64),
    y0: &[f64],
    opts: &SolverOptions,
    times: &[f64],
    sopts: &StiffnessOptions,
    angle: &dyn Fn(f64, &[f64]) -> Option<f64>,
) -> Result<Sampled, Error> {
    if times.windows(2).any(|w| !(w[1] >= w[0]))
        || times.iter().any(|t| !(*t >= t_span.0 && *t <= t_span.1))
    {
        return Err(Error::Internal(format!(
            "stiffness: sample times must be sorted and inside [{}, {}]",
            t_span.0, t_span.1
        )));
    }
    let clock = Instant::now();
    let mut o = opts.clone();
    o.output = lash_solver::Output::Final;
    let problem = Problem::new(sys, &o)?;
    let mut it = problem.integrator(t_span.0, t_span.1, y0)?;
    let mut points = Vec::with_capacity(times.len());
    let mut analyse = |t: f64, y: &[f64]| -> Result<(), Error> {
        let s = analyze(sys, t, y, sopts).map_err(analysis_error)?;
        points.push(StiffnessPoint::new(&s, angle(t, y)));
        Ok(())
    };
    let mut next = 0;
    while next < times.len() && times[next] <= t_span.0 {
        analyse(times[next], y0)?;
        next += 1;
    }
    let mut steps = Vec::new();
    let mut buf = vec![0.0; y0.len()];
    loop {
        let outcome = it.step()?;
        let (ta, tb) = (it.t_prev(), it.t());
        if tb > ta {
            steps.push(tb - ta);
        }
        while next < times.len() && times[next] <= tb {
            it.interpolate(times[next], &mut buf);
            analyse(times[next], &buf)?;
            next += 1;
        }
        let stop = match outcome {
            StepOutcome::Accepted { .. } => false,
            StepOutcome::Event { stopped, .. } => stopped,
            StepOutcome::StopTime { .. } => true,
        };
        if stop || it.is_finished() {
            break;
        }
    }
    Ok(Sampled {
        points,
        steps,
        stats: it.stats(),
        wall_time_s: clock.elapsed().as_secs_f64(),
    })
}

/// The outcome of [`measure_limit`].
///
/// ```text
/// limit: h_stable ≤ h* < h_unstable (None with a note when no bracket was found)
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Measurement {
    /// The bisection's result.
    pub limit: Option<MeasuredLimit>,
    /// Why there is no limit (no bracket within the attempts, or too many RK4 steps).
    pub note: Option<String>,
    /// Brackets tried.
    pub brackets: usize,
    /// Wall time of all RK4 runs, s.
    pub wall_time_s: f64,
}

/// Measures the largest stable RK4 step of `sys` over `t_span` from `y0` by bisection
/// ([`measure_rk4_limit_where`], its settings in `probe`), starting from the bracket
/// [guess/2, 2·guess] and widening it by a factor 4 towards the side that failed, at most
/// [`MAX_BRACKET_ATTEMPTS`] times. `base` holds the other options of the RK4 runs (events;
/// `max_steps` is raised to what the bracket needs). A bracket whose lower end needs more than
/// [`MAX_PROBE_STEPS`] steps (at half its step, the bisection's first check), or whose
/// upper end exceeds a quarter of the span, ends the search with a note. `valid` must hold at
/// every accepted state of a stable run ([`measure_rk4_limit_where`]).
pub fn measure_limit<S: OdeSystem + ?Sized>(
    sys: &S,
    t_span: (f64, f64),
    y0: &[f64],
    base: &SolverOptions,
    guess: f64,
    probe: &Rk4ProbeOptions,
    valid: StateCheck<'_>,
) -> Result<Measurement, Error> {
    let clock = Instant::now();
    let span = t_span.1 - t_span.0;
    if !(guess.is_finite() && guess > 0.0 && span > 0.0) {
        return Err(Error::Internal(format!(
            "stiffness: the RK4 step guess must be finite and > 0, got {guess}"
        )));
    }
    let (mut lo, mut hi) = (0.5 * guess, 2.0 * guess);
    let done = |limit, note: Option<String>, brackets| Measurement {
        limit,
        note,
        brackets,
        wall_time_s: clock.elapsed().as_secs_f64(),
    };
    for attempt in 1..=MAX_BRACKET_ATTEMPTS {
        // The bisection's first check runs at lo/2.
        if 2.0 * span / lo > MAX_PROBE_STEPS {
            return Ok(done(
                None,
                Some(format!(
                    "not measured: RK4 at {lo:.3e} s would take more than {MAX_PROBE_STEPS:.0e} \
                     steps over the {span:.3e} s run"
                )),
                attempt - 1,
            ));
        }
        if hi > 0.25 * span {
            return Ok(done(
                None,
                Some(format!(
                    "not measured: RK4 stays stable up to {lo:.3e} s, and a larger step leaves \
                     fewer than 4 steps in the {span:.3e} s run"
                )),
                attempt - 1,
            ));
        }
        let mut o = base.clone();
        o.max_steps = o.max_steps.max((2.0 * span / lo).ceil() as usize + 16);
        match measure_rk4_limit_where(sys, t_span, y0, (lo, hi), &o, probe, valid) {
            Ok(m) => return Ok(done(Some(m), None, attempt)),
            Err(AnalysisError::NoBracket { stable: false, .. }) => {
                hi = lo;
                lo *= 0.25;
            }
            Err(AnalysisError::NoBracket { stable: true, .. }) => {
                lo = hi;
                hi *= 4.0;
            }
            Err(e) => return Err(analysis_error(e)),
        }
    }
    Ok(done(
        None,
        Some(format!(
            "not measured: no bracket of a stable and an unstable step in {MAX_BRACKET_ATTEMPTS} \
             attempts (last [{lo:.3e}, {hi:.3e}] s)"
        )),
        MAX_BRACKET_ATTEMPTS,
    ))
}

/// A value and where along the run it occurs.
///
/// ```text
/// (value, t, crank angle θ in rad when the case has a crank)
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct At {
    /// The value.
    pub value: f64,
    /// Time, s.
    pub t: f64,
    /// Crank angle, rad.
    pub crank_angle: Option<f64>,
    /// The eigenvalue behind it.
    pub eigenvalue: Eigenvalue,
}

/// Everything `lash stiffness` reports (stiffness.json).
///
/// ```text
/// h_pred = min_k h_k,  h_meas ∈ [h_stable, h_unstable],  ratio = h_stable / h_pred,
/// q = h_acc / h_stab,  verdict(q)
/// ```
///
/// HNW II §IV.1–IV.2.
#[derive(Clone, Debug, serde::Serialize)]
pub struct StiffnessReport {
    /// Case and settings (the keys of summary.json).
    #[serde(flatten)]
    pub run: RunHeader,
    /// Start of the run, s.
    pub t_start: f64,
    /// End of the run, s.
    pub t_end: f64,
    /// Sample points analysed.
    pub samples: usize,
    /// `analytic` or `central differences`.
    pub jacobian: String,
    /// Largest spectral radius over the samples, 1/s, and where.
    pub spectral_radius_max: At,
    /// Smallest predicted RK4 limit over the samples, s, and where (null when no mode limits).
    pub rk4_limit_predicted: Option<At>,
    /// The 5th percentile of the per-sample predicted limits, s: the limit on 95 % of the
    /// run, which a brief spike (one deep impact between flights) does not set.
    pub rk4_limit_predicted_p05: Option<f64>,
    /// The measured limit (null when not measured; see `measurement_note`).
    pub rk4_limit_measured: Option<MeasuredLimit>,
    /// Why the limit was not measured.
    pub measurement_note: Option<String>,
    /// h_stable / h_pred.
    pub measured_over_predicted: Option<f64>,
    /// h_stable / (the 5th percentile of the predicted limits).
    pub measured_over_predicted_p05: Option<f64>,
    /// The stability criterion of the measurement, in words.
    pub stability_criterion: String,
    /// The accuracy step h_acc, s: the reference run's median accepted step.
    pub accuracy_step: f64,
    /// Largest stiffness ratio over the samples.
    pub stiffness_ratio_max: Option<f64>,
    /// Most growing modes at one sample.
    pub growing_modes_max: usize,
    /// Samples with at least one growing mode.
    pub samples_with_growing_modes: usize,
    /// Which family should win, and why.
    pub verdict: Verdict,
    /// The reference run's counters.
    pub stats: Stats,
    /// Wall time of the reference run with the analyses, s.
    pub wall_time_analysis_s: f64,
    /// Wall time of the RK4 measurement, s.
    pub wall_time_measurement_s: f64,
}

/// The analysis and its samples: what the files are made of.
///
/// ```text
/// report (stiffness.json) + points (stiffness.csv rows)
/// ```
///
/// Source: this module.
#[derive(Clone, Debug)]
pub struct StiffnessResult {
    /// The summary.
    pub report: StiffnessReport,
    /// One point per sample.
    pub points: Vec<StiffnessPoint>,
}

/// Φ_max of a mechanism case ([`PHI_MAX_PER_LENGTH`]), m.
pub fn phi_max(p: &Prepared) -> f64 {
    let l = p
        .info
        .as_ref()
        .and_then(|i| i.clearance_min)
        .unwrap_or(DEFAULT_LENGTH_SCALE);
    PHI_MAX_PER_LENGTH * l
}

/// The stability criterion of the measurement in words (stiffness.json and .md); `phi_max`
/// is the constraint check of a mechanism case ([`PHI_MAX_PER_LENGTH`]).
pub fn criterion_text(probe: &Rk4ProbeOptions, phi_max: Option<f64>) -> String {
    format!(
        "fixed-step RK4 over the whole run without event location is stable at h when no state \
         is non-finite{} and max ‖y‖∞ ≤ {} × that of the run at the bracket's lower end (itself \
         checked against h/2); bisection on ln h until h_unstable/h_stable ≤ 1 + {:e}",
        match phi_max {
            Some(m) => format!(", ‖Φ(q, t)‖₂ ≤ {m:.3e} m (L/100, L the smallest clearance, else 1 mm) at every accepted step"),
            None => String::new(),
        },
        probe.growth_bound,
        probe.rel_tol
    )
}

/// Runs the analysis of a prepared case with solver options `opts` (the reference run);
/// `progress` gets its phases as items (the eigenvalues along the run, then the measured RK4
/// limit).
pub fn analyse(
    p: &Prepared,
    opts: &SolverOptions,
    settings: &StiffnessSettings,
    progress: &dyn Progress,
) -> Result<StiffnessResult, Error> {
    if settings.samples < MIN_SAMPLES {
        return Err(OptionError::leading(
            "samples",
            format!(" must be >= {MIN_SAMPLES}, got {}", settings.samples),
        )
        .into());
    }
    let t_span = p.t_span(settings.t_end)?;
    let times = uniform_grid(t_span.0, t_span.1, settings.samples);
    let sopts = StiffnessOptions::default();
    progress.started("phases", 1 + usize::from(settings.measure));
    let clock = Instant::now();
    let sampled_done = |n: usize| {
        progress.finished(
            &format!("reference run with the eigenvalues of ∂f/∂y at {n} points"),
            clock.elapsed().as_secs_f64(),
        );
        Instant::now()
    };
    let measured_done = |since: Instant| {
        if settings.measure {
            progress.finished(
                "RK4 step limit measured by bisection",
                since.elapsed().as_secs_f64(),
            );
        }
    };
    // The measured limit must be independent of the prediction: the mechanism defaults turn
    // on RK4's stability check (h·ρ from the stages, `rk4_instability_steps`), which would
    // stop the probe runs exactly where the eigenvalues predict. The probe judges stability
    // by growth and the constraint check only.
    let rk4_base = |guess: f64| -> Result<SolverOptions, Error> {
        let mut o = p.options_for(Method::Rk4, None, Some(guess), None)?;
        o.rk4_instability_steps = 0;
        Ok(o)
    };
    let (sampled, measurement, analytic) = match &p.model {
        Model::Mechanism(scene) => {
            let build = || Mechanism::from_scene(scene).map_err(|e| Error::Input(e.to_string()));
            let mech = build()?;
            let sampler = Sampler::new(&mech, scene);
            let y0 = mech.initial_state();
            let angle = |t: f64, y: &[f64]| sampler.sample(t, y).crank_angle;
            let sampled = sample_along(&mech, t_span, &y0, opts, &times, &sopts, &angle)?;
            let since = sampled_done(sampled.points.len());
            let analytic = mech.has_jacobian();
            let phi_max = phi_max(p);
            let m = measure(&sampled, settings, |guess| {
                // A fresh mechanism: the probe runs start from the scene's initial hook state.
                let fresh = build()?;
                let valid = |t: f64, y: &[f64]| fresh.outputs(t, y).constraint_violation <= phi_max;
                measure_limit(
                    &fresh,
                    t_span,
                    &y0,
                    &rk4_base(guess)?,
                    guess,
                    &settings.probe,
                    &valid,
                )
            })?;
            measured_done(since);
            (sampled, m, analytic)
        }
        Model::TestSet(_) => {
            let prob = p
                .test_problem()
                .ok_or_else(|| Error::Internal("not a test problem".into()))?;
            let sys = &*prob.system;
            let none = |_: f64, _: &[f64]| None;
            let sampled = sample_along(sys, t_span, &prob.y0, opts, &times, &sopts, &none)?;
            let since = sampled_done(sampled.points.len());
            let m = measure(&sampled, settings, |guess| {
                measure_limit(
                    sys,
                    t_span,
                    &prob.y0,
                    &rk4_base(guess)?,
                    guess,
                    &settings.probe,
                    &|_, _| true,
                )
            })?;
            measured_done(since);
            (sampled, m, sys.has_jacobian())
        }
    };
    let report = build_report(p, opts, settings, t_span, &sampled, measurement, analytic)?;
    Ok(StiffnessResult {
        report,
        points: sampled.points,
    })
}

/// The measurement, started from the predicted limit (else the accuracy step), or a note.
fn measure<F>(sampled: &Sampled, settings: &StiffnessSettings, run: F) -> Result<Measurement, Error>
where
    F: FnOnce(f64) -> Result<Measurement, Error>,
{
    if !settings.measure {
        return Ok(Measurement {
            limit: None,
            note: Some("not measured (--no-measure)".into()),
            brackets: 0,
            wall_time_s: 0.0,
        });
    }
    let guess = predicted_min(&sampled.points)
        .map(|(_, h)| h)
        .or_else(|| sampled.median_step());
    match guess {
        Some(g) => run(g),
        None => Ok(Measurement {
            limit: None,
            note: Some("not measured: no step to start the bracket from".into()),
            brackets: 0,
            wall_time_s: 0.0,
        }),
    }
}

/// Index and value of the smallest predicted limit.
fn predicted_min(points: &[StiffnessPoint]) -> Option<(usize, f64)> {
    points
        .iter()
        .enumerate()
        .filter_map(|(k, p)| p.rk4_h_max.map(|h| (k, h)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

fn check(name: &str, v: f64) -> Result<f64, Error> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::Internal(format!("stiffness: {name} is {v}")))
    }
}

#[allow(clippy::too_many_arguments)]
fn build_report(
    p: &Prepared,
    opts: &SolverOptions,
    settings: &StiffnessSettings,
    t_span: (f64, f64),
    sampled: &Sampled,
    measurement: Measurement,
    analytic: bool,
) -> Result<StiffnessReport, Error> {
    let pts = &sampled.points;
    let first = pts
        .first()
        .ok_or_else(|| Error::Internal("stiffness: no sample reached".into()))?;
    for q in pts {
        check("spectral radius", q.spectral_radius)?;
        check("eigenvalue", q.dominant.re)?;
        check("eigenvalue", q.dominant.im)?;
        if let Some(h) = q.rk4_h_max {
            check("rk4_h_max", h)?;
        }
        if let Some(s) = q.stiffness_ratio {
            check("stiffness ratio", s)?;
        }
    }
    let rho = pts
        .iter()
        .max_by(|a, b| a.spectral_radius.total_cmp(&b.spectral_radius))
        .unwrap_or(first);
    let predicted = predicted_min(pts).map(|(k, h)| At {
        value: h,
        t: pts[k].t,
        crank_angle: pts[k].crank_angle,
        eigenvalue: pts[k].limiting.unwrap_or(pts[k].dominant),
    });
    let h_acc = sampled
        .median_step()
        .ok_or_else(|| Error::Internal("stiffness: the reference run took no step".into()))?;
    let h_stab = measurement
        .limit
        .as_ref()
        .map(|m| m.h_stable)
        .or(predicted.as_ref().map(|a| a.value));
    let growing = pts.iter().map(|q| q.n_unstable).max().unwrap_or(0);
    let mut v = verdict(h_acc, h_stab, growing).map_err(analysis_error)?;
    let which = if measurement.limit.is_some() {
        "measured"
    } else {
        "predicted"
    };
    v.reason = format!(
        "{} (accuracy step: the median step of the {} reference run; stability: the {which} \
         RK4 limit)",
        v.reason,
        opts.method.name()
    );
    let ratio = match (&measurement.limit, &predicted) {
        (Some(m), Some(a)) => Some(m.h_stable / a.value),
        _ => None,
    };
    let p05 = percentile(
        &pts.iter().filter_map(|q| q.rk4_h_max).collect::<Vec<_>>(),
        0.05,
    );
    let ratio_p05 = match (&measurement.limit, p05) {
        (Some(m), Some(h)) => Some(m.h_stable / h),
        _ => None,
    };
    Ok(StiffnessReport {
        run: RunHeader::new(&p.case, opts),
        t_start: t_span.0,
        t_end: t_span.1,
        samples: pts.len(),
        jacobian: if analytic {
            "analytic".into()
        } else {
            "central differences".into()
        },
        spectral_radius_max: At {
            value: rho.spectral_radius,
            t: rho.t,
            crank_angle: rho.crank_angle,
            eigenvalue: rho.dominant,
        },
        rk4_limit_predicted: predicted,
        rk4_limit_predicted_p05: p05,
        rk4_limit_measured: measurement.limit,
        measurement_note: measurement.note,
        measured_over_predicted: ratio,
        measured_over_predicted_p05: ratio_p05,
        stability_criterion: criterion_text(&settings.probe, p.scene().map(|_| phi_max(p))),
        accuracy_step: h_acc,
        stiffness_ratio_max: pts
            .iter()
            .filter_map(|q| q.stiffness_ratio)
            .max_by(f64::total_cmp),
        growing_modes_max: growing,
        samples_with_growing_modes: pts.iter().filter(|q| q.n_unstable > 0).count(),
        verdict: v,
        stats: sampled.stats,
        wall_time_analysis_s: sampled.wall_time_s,
        wall_time_measurement_s: measurement.wall_time_s,
    })
}

fn opt(v: Option<f64>) -> String {
    v.map(fmt_num).unwrap_or_default()
}

/// stiffness.csv: one row per sample.
///
/// ```text
/// t,crank_angle,lambda_re,lambda_im,lambda_abs,spectral_radius,stiffness_ratio,rk4_h_max,
/// limiting_re,limiting_im,n_unstable
/// ```
/// (λ the eigenvalue of largest modulus, so lambda_abs = spectral_radius; `limiting` the one
/// that sets rk4_h_max; empty fields where a value does not exist).
pub fn to_csv(points: &[StiffnessPoint]) -> String {
    let mut s = String::from(
        "t,crank_angle,lambda_re,lambda_im,lambda_abs,spectral_radius,stiffness_ratio,\
         rk4_h_max,limiting_re,limiting_im,n_unstable\n",
    );
    for q in points {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{}",
            fmt_num(q.t),
            opt(q.crank_angle),
            fmt_num(q.dominant.re),
            fmt_num(q.dominant.im),
            fmt_num(q.dominant.modulus()),
            fmt_num(q.spectral_radius),
            opt(q.stiffness_ratio),
            opt(q.rk4_h_max),
            opt(q.limiting.map(|l| l.re)),
            opt(q.limiting.map(|l| l.im)),
            q.n_unstable
        );
    }
    s
}

fn where_(a: &At) -> String {
    match a.crank_angle {
        Some(th) => format!("t = {:.6} s, crank angle {:.1}°", a.t, th * 180.0 / PI),
        None => format!("t = {:.6e} s", a.t),
    }
}

fn eig(e: &Eigenvalue) -> String {
    if e.im == 0.0 {
        format!("{:.4e}", e.re)
    } else {
        format!(
            "{:.4e} {} {:.4e}i",
            e.re,
            if e.im < 0.0 { "−" } else { "+" },
            e.im.abs()
        )
    }
}

impl StiffnessReport {
    /// The lines `lash stiffness` prints: the two limits and the verdict.
    pub fn describe(&self) -> String {
        let mut s = format!(
            "{}: {} samples over [{}, {}] s, {} reference run: {} steps, median {:.3e} s\n",
            self.run.case,
            self.samples,
            self.t_start,
            self.t_end,
            self.run.method.name(),
            self.stats.accepted,
            self.accuracy_step
        );
        let _ = writeln!(
            s,
            "  largest |λ| {:.4e} 1/s (λ = {}) at {}",
            self.spectral_radius_max.value,
            eig(&self.spectral_radius_max.eigenvalue),
            where_(&self.spectral_radius_max)
        );
        match &self.rk4_limit_predicted {
            Some(a) => {
                let _ = writeln!(
                    s,
                    "  predicted RK4 limit {:.4e} s (λ = {}) at {}",
                    a.value,
                    eig(&a.eigenvalue),
                    where_(a)
                );
            }
            None => s.push_str("  predicted RK4 limit: none (no decaying or oscillating mode)\n"),
        }
        if let Some(h) = self.rk4_limit_predicted_p05 {
            let _ = writeln!(
                s,
                "  predicted RK4 limit on 95 % of the samples {h:.4e} s (5th percentile)"
            );
        }
        match (&self.rk4_limit_measured, &self.measurement_note) {
            (Some(m), _) => {
                let _ =
                    writeln!(
                    s,
                    "  measured RK4 limit {:.4e} s (stable) < h* < {:.4e} s (unstable), {} runs{}",
                    m.h_stable,
                    m.h_unstable,
                    m.runs,
                    match (self.measured_over_predicted, self.measured_over_predicted_p05) {
                        (Some(r), Some(q)) => format!(
                            ", measured/predicted {r:.4} (min), {q:.4} (5th percentile)"
                        ),
                        (Some(r), None) => format!(", measured/predicted {r:.4}"),
                        _ => String::new(),
                    }
                );
            }
            (None, Some(n)) => {
                let _ = writeln!(s, "  measured RK4 limit: {n}");
            }
            (None, None) => {}
        }
        let _ = writeln!(
            s,
            "  verdict: {}: {}",
            family_name(&self.verdict),
            self.verdict.reason
        );
        s
    }

    /// stiffness.md: the numbers and the verdict.
    pub fn to_markdown(&self) -> String {
        let mut s = format!("# Stiffness of {}\n\n", self.run.case);
        let _ = writeln!(
            s,
            "Reference run: {} ({}), t ∈ [{}, {}] s, {} accepted steps; Jacobian {}; {} samples.\n",
            self.run.method.name(),
            self.run.accuracy(),
            self.t_start,
            self.t_end,
            self.stats.accepted,
            self.jacobian,
            self.samples
        );
        s.push_str("| quantity | value | where |\n|---|---|---|\n");
        let _ = writeln!(
            s,
            "| largest spectral radius | {:.4e} 1/s (λ = {}) | {} |",
            self.spectral_radius_max.value,
            eig(&self.spectral_radius_max.eigenvalue),
            where_(&self.spectral_radius_max)
        );
        if let Some(a) = &self.rk4_limit_predicted {
            let _ = writeln!(
                s,
                "| predicted RK4 limit (min over samples) | {:.4e} s (λ = {}) | {} |",
                a.value,
                eig(&a.eigenvalue),
                where_(a)
            );
        }
        if let Some(h) = self.rk4_limit_predicted_p05 {
            let _ = writeln!(
                s,
                "| predicted RK4 limit, 5th percentile over samples | {h:.4e} s | 95 % of the run |"
            );
        }
        match &self.rk4_limit_measured {
            Some(m) => {
                let _ = writeln!(
                    s,
                    "| measured RK4 limit | {:.4e} s ≤ h* < {:.4e} s | whole run, {} RK4 runs |",
                    m.h_stable, m.h_unstable, m.runs
                );
            }
            None => {
                let _ = writeln!(
                    s,
                    "| measured RK4 limit | – | {} |",
                    self.measurement_note.as_deref().unwrap_or("")
                );
            }
        }
        if let Some(r) = self.measured_over_predicted {
            let _ = writeln!(s, "| measured / predicted (min) | {r:.4} | |");
        }
        if let Some(r) = self.measured_over_predicted_p05 {
            let _ = writeln!(s, "| measured / predicted (5th percentile) | {r:.4} | |");
        }
        let _ = writeln!(
            s,
            "| accuracy step (median step of the reference run) | {:.4e} s | |",
            self.accuracy_step
        );
        if let Some(r) = self.stiffness_ratio_max {
            let _ = writeln!(s, "| largest stiffness ratio | {r:.3e} | |");
        }
        let _ = writeln!(
            s,
            "| samples with a growing mode (Re λ > 0) | {} of {} (at most {} at once) | |",
            self.samples_with_growing_modes, self.samples, self.growing_modes_max
        );
        let reason = &self.verdict.reason;
        let mut chars = reason.chars();
        let reason = match chars.next() {
            Some(c) => c.to_uppercase().chain(chars).collect::<String>(),
            None => String::new(),
        };
        let _ = writeln!(
            s,
            "\n**Verdict: {}.** {reason}.\n\nStability criterion of the measurement: {}.",
            family_name(&self.verdict),
            self.stability_criterion
        );
        s
    }
}

/// The family's name in a sentence.
pub fn family_name(v: &Verdict) -> &'static str {
    use lash_solver::analysis::stiffness::Family;
    match v.family {
        Family::Explicit => "explicit",
        Family::Either => "either",
        Family::Implicit => "implicit",
    }
}

impl StiffnessResult {
    /// Writes stiffness.csv, stiffness.{svg,png}, stiffness.md and stiffness.json (last) into
    /// `dir`, each atomically; everything is checked before the first file is written.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, Error> {
        let csv = to_csv(&self.points);
        let md = self.report.to_markdown();
        let json = serde_json::to_string_pretty(&self.report)
            .map_err(|e| Error::Internal(format!("stiffness.json: {e}")))?;
        let (x, x_label): (Vec<f64>, &str) = if self.points.iter().all(|q| q.crank_angle.is_some())
        {
            (
                self.points
                    .iter()
                    .map(|q| q.crank_angle.unwrap_or(0.0).to_degrees())
                    .collect(),
                "crank angle θ, °",
            )
        } else {
            (self.points.iter().map(|q| q.t).collect(), "time t, s")
        };
        io::create_dir(dir)?;
        let mut written = Vec::new();
        let w = self.plot(dir, &x, x_label)?;
        written.push(w.svg);
        written.push(w.png);
        let p = dir.join("stiffness.csv");
        io::write_atomic(&p, csv.as_bytes())?;
        written.push(p);
        let p = dir.join("stiffness.md");
        io::write_atomic(&p, md.as_bytes())?;
        written.push(p);
        let p = dir.join("stiffness.json");
        io::write_atomic(&p, format!("{json}\n").as_bytes())?;
        written.push(p);
        Ok(written)
    }

    fn plot(&self, dir: &Path, x: &[f64], x_label: &str) -> Result<plot::Written, Error> {
        let (xr, rho): (Vec<f64>, Vec<f64>) = x
            .iter()
            .zip(&self.points)
            .filter(|(_, q)| q.spectral_radius > 0.0)
            .map(|(x, q)| (*x, q.spectral_radius))
            .unzip();
        let (xh, h): (Vec<f64>, Vec<f64>) = x
            .iter()
            .zip(&self.points)
            .filter_map(|(x, q)| q.rk4_h_max.map(|h| (*x, h)))
            .unzip();
        let ends = [
            x.first().copied().unwrap_or(0.0),
            x.last().copied().unwrap_or(0.0),
        ];
        let r = &self.report;
        let meas = r.rk4_limit_measured.as_ref().map(|m| [m.h_stable; 2]);
        let acc = [r.accuracy_step; 2];
        let mut s1 = Vec::new();
        if !rho.is_empty() {
            s1.push(Series {
                name: "spectral radius |λ|max",
                x: &xr,
                y: &rho,
                style: SeriesStyle::Line,
            });
        }
        let mut s2 = Vec::new();
        if !h.is_empty() {
            s2.push(Series {
                name: "predicted RK4 limit r(arg λ)/|λ|",
                x: &xh,
                y: &h,
                style: SeriesStyle::Line,
            });
        }
        if let Some(m) = &meas {
            s2.push(Series {
                name: "measured RK4 limit (whole run)",
                x: &ends,
                y: m,
                style: SeriesStyle::Dashed,
            });
        }
        s2.push(Series {
            name: "accuracy step (median step of the reference run)",
            x: &ends,
            y: &acc,
            style: SeriesStyle::Dashed,
        });
        let mut panels = Vec::new();
        if !s1.is_empty() {
            panels.push(Panel {
                axes: Axes {
                    title: "Largest eigenvalue modulus of ∂f/∂y",
                    x_label,
                    y_label: "largest |λ|, 1/s",
                },
                series: &s1,
                log_y: true,
            });
        }
        panels.push(Panel {
            axes: Axes {
                title: "RK4 step limit: predicted along the run, measured over the whole run",
                x_label,
                y_label: "step h, s",
            },
            series: &s2,
            log_y: true,
        });
        let title = format!("Stiffness along the run: {}", plot::plain(&r.run.case));
        plot::panels_plot(&dir.join("stiffness"), &title, &panels)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentile_is_the_value_of_its_rank() {
        let v: Vec<f64> = (0..=100).rev().map(f64::from).collect();
        assert_eq!(percentile(&v, 0.05), Some(5.0));
        assert_eq!(percentile(&v, 0.0), Some(0.0));
        assert_eq!(percentile(&v, 1.0), Some(100.0));
        assert_eq!(percentile(&[], 0.5), None);
    }

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&[]), None);
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), Some(2.5));
    }

    #[test]
    fn csv_leaves_missing_values_empty() {
        let p = StiffnessPoint {
            t: 0.5,
            crank_angle: None,
            dominant: Eigenvalue { re: -2.0, im: 0.0 },
            spectral_radius: 2.0,
            stiffness_ratio: None,
            rk4_h_max: Some(1.5),
            limiting: None,
            n_unstable: 1,
        };
        let csv = to_csv(&[p]);
        let row = csv.lines().nth(1).unwrap();
        assert_eq!(row, "0.5,,-2,0,2,2,,1.5,,,1");
        assert_eq!(
            csv.lines().next().unwrap().split(',').count(),
            row.split(',').count()
        );
    }
}
