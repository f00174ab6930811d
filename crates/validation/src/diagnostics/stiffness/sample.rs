//! The two measurements of `lash stiffness`: the Jacobian's eigenvalues sampled along a
//! reference run (the RK4 limit they predict), and the RK4 limit measured by bisection.
//!
//! Source: the module doc of `diagnostics::stiffness`; `lash_solver::analysis::stiffness`.

use std::time::Instant;

use lash_solver::analysis::stiffness::{
    analyze, measure_rk4_limit_where, Eigenvalue, MeasuredLimit, Rk4ProbeOptions, StateCheck,
    StiffnessOptions, StiffnessSummary,
};
use lash_solver::analysis::AnalysisError;
use lash_solver::{OdeSystem, Problem, SolverOptions, Stats, StepOutcome};

use crate::error::Error;
use crate::run::prepare::{Prepared, DEFAULT_LENGTH_SCALE};

/// Default number of sample points along the run (both ends included): every 0.72° of crank
/// angle over the paper's two revolutions; the analysis of a sample (one analytic Jacobian, the
/// eigenvalues of a 12 × 12 matrix) is cheap next to the measurement of the RK4 limit
/// (BENCHMARKS.md, "Diagnostics").
pub(crate) const DEFAULT_SAMPLES: usize = 1000;
/// Fewest sample points.
pub(crate) const MIN_SAMPLES: usize = 2;
/// Most RK4 steps one probe run of the measurement may take; a bracket that would need more
/// ends the measurement with a note instead (a stiff test problem over a long span).
pub(crate) const MAX_PROBE_STEPS: f64 = 2e7;
/// Most bracket attempts of the measurement (each widens the bracket by a factor 4).
pub(crate) const MAX_BRACKET_ATTEMPTS: usize = 8;
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
pub(crate) const PHI_MAX_PER_LENGTH: f64 = 1e-2;

/// What `lash stiffness` does besides the case's solver options.
///
/// ```text
/// samples N ≥ 2 (default 1000); t_end override; measure the RK4 limit (default yes);
/// probe: growth_bound 10, rel_tol 1e-4 (Rk4ProbeOptions)
/// ```
///
/// Source: docs/outputs.md ("`lash stiffness CASE`").
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct StiffnessSettings {
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
pub(crate) struct StiffnessPoint {
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
pub(crate) struct Sampled {
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
    pub(crate) fn median_step(&self) -> Option<f64> {
        median(&self.steps)
    }
}

/// The q-quantile of `v` (0 ≤ q ≤ 1): the value of rank ⌊q (n − 1)⌋ in increasing order.
pub(crate) fn percentile(v: &[f64], q: f64) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    Some(s[(q * (s.len() - 1) as f64).floor() as usize])
}

pub(crate) fn median(v: &[f64]) -> Option<f64> {
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
pub(crate) fn analysis_error(e: AnalysisError) -> Error {
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
pub(crate) fn sample_along<S: OdeSystem + ?Sized>(
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
pub(crate) struct Measurement {
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
pub(crate) fn measure_limit<S: OdeSystem + ?Sized>(
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

/// Φ_max of a mechanism case ([`PHI_MAX_PER_LENGTH`]), m.
pub(crate) fn phi_max(p: &Prepared) -> f64 {
    let l = p
        .info
        .as_ref()
        .and_then(|i| i.clearance_min)
        .unwrap_or(DEFAULT_LENGTH_SCALE);
    PHI_MAX_PER_LENGTH * l
}

/// The stability criterion of the measurement in words (stiffness.json and .md); `phi_max`
/// is the constraint check of a mechanism case ([`PHI_MAX_PER_LENGTH`]).
pub(crate) fn criterion_text(probe: &Rk4ProbeOptions, phi_max: Option<f64>) -> String {
    format!(
        "fixed-step RK4 over the whole run without event location is stable at h when no state \
         is non-finite, RK4's own stability check (the one `lash run` applies) does not stop \
         it{} and max ‖y‖∞ ≤ {} × that of the run at the bracket's lower end (itself \
         checked against h/2); bisection on ln h until h_unstable/h_stable ≤ 1 + {:e}",
        match phi_max {
            Some(m) => format!(", ‖Φ(q, t)‖₂ ≤ {m:.3e} m (L/100, L the smallest clearance, else 1 mm) at every accepted step"),
            None => String::new(),
        },
        probe.growth_bound,
        probe.rel_tol
    )
}
