//! `lash poincare CASE`: the clearance journal's eccentricity once per crank revolution
//! (a stroboscopic Poincaré section) and the largest Lyapunov exponent by Benettin's method.
//!
//! ```text
//! section       T = 2π/|ω_crank| (= 60/rpm); y_j = y(t_0 + jT), j = 0..N (N = --revolutions);
//!               a crank that a motor turns (roles.crank, no driver): y_j = y(t_j) at its full
//!               turns φ(t_j) = φ_0 ± 2πj (crate::run::turns), T = (t_N − t_0)/N the mean turn;
//!               (e_x/c, e_y/c, |e|/c) of the clearance-joint role at each y_j
//! Lyapunov      two trajectories (two Mechanism instances: contact hooks keep state), the
//!               second displaced by d0 = --perturbation along u, u_i ∝ 1/w_i;
//!               every Δt = T/R (R = --renorm-per-rev, default 10): d_k = ‖z − y‖_w,
//!               g_k = ln(d_k/d0), z ← y + (d0/d_k)(z − y)   (Benettin et al. 1980)
//!               weights w_i = 1/L on positions and angles, 1/(L ω) on velocities
//!               (L = the smallest clearance, ω the crank speed): d0 is in clearances
//! running       λ(t_k) = (g_1 + … + g_k)/(t_k − t_0)            (Benettin's estimate)
//! estimate      λ = Σ_{late} g_k / (t_N − t_late),  late = revolutions ⌊N/2⌋..N: the first
//!               half aligns the separation with the most expanding direction and is discarded
//! uncertainty   σ_λ = sd(λ_r)/√m over the m late revolutions, λ_r = Σ_{rev r} g_k / T;
//!               spread = max − min of λ(t_k) over the late half
//! verdict       chaotic if λ > 3σ_λ; not chaotic if λ < −3σ_λ; else inconclusive
//! files         poincare.csv, poincare.{svg,png} (section in the clearance circle),
//!               poincare_eps.{svg,png} (|e|/c against revolution), lyapunov.csv,
//!               lyapunov.{svg,png} (running estimate), poincare.md, poincare.json (last)
//! ```
//!
//! The renormalisation interval T/10 keeps the separation small: at the exponents measured on
//! the dry press (BENCHMARKS.md, "Chaos diagnostics") it grows by e^{λT/10}, a factor of order
//! 2, between renormalisations. Both trajectories
//! use the case's solver options; the integration error must stay well below d0 (the default
//! atol is rtol·c, so rtol 1e-8 against d0 = 1e-4 clearances). Sources: G. Benettin,
//! L. Galgani, A. Giorgilli, J.-M. Strelcyn, Meccanica 15 (1980) 9–20; J. C. Sprott, *Chaos
//! and Time-Series Analysis*, Oxford 2003, §5.6; J. Guckenheimer, P. Holmes, *Nonlinear
//! Oscillations, Dynamical Systems, and Bifurcations of Vector Fields*, Springer 1983, §1.4
//! (stroboscopic sections of periodically forced systems).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use lash_model::Mechanism;
use lash_solver::analysis::lyapunov::{
    largest_lyapunov_pair, stroboscopic_map, LyapunovEstimate, LyapunovOptions,
};
use lash_solver::{Problem, SolverOptions, StepOutcome};

use crate::diagnostics::stiffness::sample::analysis_error;
use crate::error::{Error, OptionError};
use crate::options::SolverChoice;
use crate::progress::Progress;
use crate::report::plot::{self, Axes, Panel, Series, SeriesStyle};
use crate::report::summary::RunHeader;
use crate::report::trajectory::fmt_num;
use crate::run::prepare::scene_error;
use crate::run::prepare::{Model, Prepared, DEFAULT_LENGTH_SCALE};
use crate::run::sample::Sampler;
use crate::run::turns::{Turns, HORIZON_FACTOR};
use crate::store::io;

/// Default number of revolutions.
pub(crate) const DEFAULT_REVOLUTIONS: usize = 20;
/// Default initial and renormalised separation d0, in clearances (weighted norm).
pub(crate) const DEFAULT_PERTURBATION: f64 = 1e-4;
/// Default renormalisations per crank revolution.
pub(crate) const DEFAULT_RENORM_PER_REV: usize = 10;
/// Relative tolerance of `lash poincare`'s adaptive runs when `--rtol` is not given.
///
/// Benettin's method needs the integration error of each trajectory far below d0 (the two
/// trajectories take different steps and locate their own events, so their errors do not
/// cancel). On the dry press at 150 rpm the estimate at the case default rtol 1e-8 depends on
/// d0, and from rtol 1e-10 down it does not; 1e-11 adds a margin at a moderate cost
/// (measurements: BENCHMARKS.md, "Chaos diagnostics").
pub(crate) const DEFAULT_RTOL: f64 = 1e-11;
/// What poincare.md adds for a crank that a motor turns.
const AUTONOMOUS_NOTE: &str = "\nThe crank is turned by a motor, not driven: the section is \
    taken where the crank angle completes each full turn, T is the mean turn, and the \
    mechanism is autonomous. A shift along the orbit neither grows nor decays, so a stable \
    periodic response has λ = 0 (inconclusive), not λ < 0; λ > 3σ still reads chaotic.\n";
/// Standard errors by which the estimate must clear zero for a verdict.
pub(crate) const SIGMAS: f64 = 3.0;

/// What `lash poincare` does besides the solver options.
///
/// ```text
/// N revolutions ≥ 1, d0 ∈ (0, 1) clearances, R ≥ 1 renormalisations per revolution
/// ```
///
/// Source: docs/outputs.md ("`lash poincare CASE`").
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PoincareSettings {
    /// Revolutions N (section points j = 0..N; Lyapunov averaging over N T).
    pub revolutions: usize,
    /// d0 in clearances (weighted norm).
    pub perturbation: f64,
    /// Renormalisations per revolution R.
    pub renorm_per_rev: usize,
}

impl Default for PoincareSettings {
    fn default() -> Self {
        PoincareSettings {
            revolutions: DEFAULT_REVOLUTIONS,
            perturbation: DEFAULT_PERTURBATION,
            renorm_per_rev: DEFAULT_RENORM_PER_REV,
        }
    }
}

impl PoincareSettings {
    /// Checks the ranges (usage errors).
    pub(crate) fn validate(&self) -> Result<(), Error> {
        if self.revolutions == 0 {
            return Err(OptionError::leading("revolutions", " must be >= 1").into());
        }
        if !(self.perturbation.is_finite() && self.perturbation > 0.0 && self.perturbation < 1.0) {
            return Err(OptionError::leading(
                "perturbation",
                format!(" must be in (0, 1) clearances, got {}", self.perturbation),
            )
            .into());
        }
        if self.renorm_per_rev == 0 {
            return Err(OptionError::leading("renorm_per_rev", " must be >= 1").into());
        }
        Ok(())
    }
}

/// How the estimate reads.
///
/// ```text
/// Chaotic: λ > 3σ · NotChaotic: λ < −3σ · Inconclusive otherwise (or no σ)
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Chaos {
    /// λ clearly > 0: nearby trajectories separate exponentially.
    Chaotic,
    /// λ clearly < 0: nearby trajectories converge (a stable periodic response).
    NotChaotic,
    /// Not distinguishable from zero, or too few revolutions for an uncertainty.
    Inconclusive,
}

/// The estimate of the largest exponent and its uncertainty (module doc).
///
/// ```text
/// λ = Σ_late g_k / (t_N − t_late),  σ = sd(λ_r)/√m,  spread = max − min λ(t_k), k late
/// ```
///
/// Benettin et al. (1980); Sprott (2003), §5.6.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub(crate) struct LyapunovSummary {
    /// λ over the late half, 1/s.
    pub exponent: f64,
    /// σ_λ, 1/s (None with fewer than 2 late revolutions).
    pub std_error: Option<f64>,
    /// λ T: nats per revolution.
    pub per_revolution: f64,
    /// Benettin's running estimate at the end (transient included), 1/s.
    pub exponent_running: f64,
    /// max − min of the running estimate over the late half, 1/s.
    pub running_spread: f64,
    /// Start of the late window, s.
    pub late_from: f64,
    /// Revolutions in the late window.
    pub late_revolutions: usize,
    /// The reading.
    pub chaos: Chaos,
    /// One sentence with the numbers.
    pub sentence: String,
}

/// Summarises Benettin's log growths `est` over whole revolutions of period `period`, with
/// `per_rev` renormalisations each (module doc). `est.log_growth.len()` must be a positive
/// multiple of `per_rev`.
pub(crate) fn summarize(
    est: &LyapunovEstimate,
    period: f64,
    per_rev: usize,
) -> Result<LyapunovSummary, Error> {
    let k = est.log_growth.len();
    if per_rev == 0
        || k == 0
        || !k.is_multiple_of(per_rev)
        || est.t.len() != k
        || est.running.len() != k
    {
        return Err(Error::Internal(format!(
            "lyapunov: {k} intervals are not whole revolutions of {per_rev}"
        )));
    }
    let n = k / per_rev;
    let first_late = n / 2;
    let start = first_late * per_rev;
    let late_from = if start == 0 {
        est.t_start
    } else {
        est.t[start - 1]
    };
    let dur = est.t[k - 1] - late_from;
    let exponent = est.log_growth[start..].iter().sum::<f64>() / dur;
    let rates: Vec<f64> = est.log_growth[start..]
        .chunks(per_rev)
        .map(|c| c.iter().sum::<f64>() / period)
        .collect();
    let m = rates.len();
    let std_error = (m >= 2).then(|| {
        let mean = rates.iter().sum::<f64>() / m as f64;
        let var = rates.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / (m - 1) as f64;
        (var / m as f64).sqrt()
    });
    let late_running = &est.running[start..];
    let running_spread = late_running
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max)
        - late_running.iter().copied().fold(f64::INFINITY, f64::min);
    let exponent_running = est.running[k - 1];
    for (name, v) in [
        ("exponent", exponent),
        ("running estimate", exponent_running),
        ("spread", running_spread),
    ] {
        if !v.is_finite() {
            return Err(Error::Internal(format!("lyapunov: {name} is {v}")));
        }
    }
    let chaos = match std_error {
        Some(s) if exponent > SIGMAS * s && exponent > 0.0 => Chaos::Chaotic,
        Some(s) if exponent < -SIGMAS * s && exponent < 0.0 => Chaos::NotChaotic,
        _ => Chaos::Inconclusive,
    };
    let pm = std_error.map_or(String::new(), |s| format!(" ± {s:.3}"));
    let head = format!(
        "λ = {exponent:.4}{pm} 1/s ({:.3} per revolution; over revolutions {first_late}–{n})",
        exponent * period
    );
    let sentence = match chaos {
        Chaos::Chaotic => format!(
            "{head} is clearly positive: nearby trajectories separate by a factor e^(λT) ≈ {:.3e} \
             per revolution, so the response is chaotic and pointwise comparisons of two runs \
             lose meaning after a few revolutions",
            (exponent * period).exp()
        ),
        Chaos::NotChaotic => format!(
            "{head} is clearly negative: nearby trajectories converge (by e^(λT) ≈ {:.3e} per \
             revolution) onto a stable periodic response; not chaotic",
            (exponent * period).exp()
        ),
        Chaos::Inconclusive => match std_error {
            Some(_) => format!(
                "{head} is within {SIGMAS} standard errors of zero: inconclusive, run more \
                 revolutions"
            ),
            None => format!(
                "{head}: too few revolutions for an uncertainty (at least 4 give 2 late ones)"
            ),
        },
    };
    Ok(LyapunovSummary {
        exponent,
        std_error,
        per_revolution: exponent * period,
        exponent_running,
        running_spread,
        late_from,
        late_revolutions: m,
        chaos,
        sentence,
    })
}

/// The solver options of `lash poincare`: the case's defaults with the choice laid over them,
/// as `lash run`, except that an adaptive method without an rtol runs at [`DEFAULT_RTOL`].
pub(crate) fn options(p: &Prepared, choice: &SolverChoice) -> Result<SolverOptions, Error> {
    let mut f = choice.clone();
    let method = f.method.unwrap_or(p.default_options().method);
    if !method.is_fixed_step() && f.rtol.is_none() {
        f.rtol = Some(DEFAULT_RTOL);
    }
    p.options(&f)
}

/// A usage error naming the case unless it is a mechanism with a crank (a driven one, or
/// `roles.crank` that a motor turns).
fn check_crank(p: &Prepared) -> Result<(), Error> {
    let has_crank = p.period().is_some() || p.info.as_ref().is_some_and(|i| i.has_crank);
    match (&p.model, has_crank) {
        (Model::Mechanism(_), true) => Ok(()),
        _ => Err(Error::Usage(format!(
            "poincare needs a scene with a crank (roles.crank_driver with ω ≠ 0, or roles.crank \
             that a motor turns); {} has none",
            p.case.name
        ))),
    }
}

/// Norm weights of the Lyapunov separation: 1/L on positions, 1/(L ω) on velocities, with
/// ω = 2π/T (T the crank period: the driver's, or the mean turn of the section).
pub(crate) fn weights(p: &Prepared, period: f64) -> Vec<f64> {
    let (l, w, n) = match &p.info {
        Some(i) => (
            i.clearance_min.unwrap_or(DEFAULT_LENGTH_SCALE),
            i.crank_speed.unwrap_or(std::f64::consts::TAU / period),
            i.dim,
        ),
        None => (DEFAULT_LENGTH_SCALE, 1.0, p.dim()),
    };
    (0..n)
        .map(|k| if k < n / 2 { 1.0 / l } else { 1.0 / (l * w) })
        .collect()
}

/// A Lyapunov computation: the estimate and its summary.
///
/// ```text
/// estimate: t_k, g_k, λ(t_k) for k = 1..N R;  summary: module doc
/// ```
///
/// Source: Benettin et al. (1980).
#[derive(Clone, Debug)]
pub(crate) struct LyapunovRun {
    /// The raw estimate (per renormalisation).
    pub estimate: LyapunovEstimate,
    /// The summary.
    pub summary: LyapunovSummary,
    /// Crank period T, s.
    pub period: f64,
    /// Renormalisation interval Δt = T/R, s.
    pub renorm_interval: f64,
    /// Wall time of both trajectories, s.
    pub wall_time_s: f64,
}

/// The largest Lyapunov exponent of a mechanism case with a crank (module doc), with solver
/// options `opts` for both trajectories; `period` is the driven crank's period, or for a crank
/// that a motor turns the mean turn of its section ([`Section::period`]).
pub(crate) fn lyapunov(
    p: &Prepared,
    opts: &SolverOptions,
    s: &PoincareSettings,
    period: f64,
) -> Result<LyapunovRun, Error> {
    s.validate()?;
    check_crank(p)?;
    if !(period.is_finite() && period > 0.0) {
        return Err(Error::Internal(format!("lyapunov: period {period}")));
    }
    let Some(scene) = p.scene() else {
        return Err(Error::Internal("poincare: no scene".into()));
    };
    let build = || Mechanism::from_scene(scene).map_err(|e| scene_error(&p.case, e));
    let (a, b) = (build()?, build()?);
    let y0 = a.initial_state();
    let w = weights(p, period);
    let dir: Vec<f64> = w.iter().map(|w| 1.0 / w).collect();
    let dt = period / s.renorm_per_rev as f64;
    let lo = LyapunovOptions {
        solver: opts.clone(),
        renorm_interval: dt,
        duration: period * s.revolutions as f64,
        transient: 0.0,
        d0: s.perturbation,
        direction: Some(dir),
        weights: Some(w),
    };
    let clock = Instant::now();
    let est = largest_lyapunov_pair(&a, &b, a.t_start(), &y0, &lo).map_err(analysis_error)?;
    let wall = clock.elapsed().as_secs_f64();
    if est.log_growth.len() != s.revolutions * s.renorm_per_rev {
        return Err(Error::Internal(format!(
            "lyapunov: {} intervals, expected {}",
            est.log_growth.len(),
            s.revolutions * s.renorm_per_rev
        )));
    }
    let summary = summarize(&est, period, s.renorm_per_rev)?;
    Ok(LyapunovRun {
        estimate: est,
        summary,
        period,
        renorm_interval: dt,
        wall_time_s: wall,
    })
}

/// One point of the section (a row of poincare.csv).
///
/// ```text
/// t_j = t_0 + jT;  e/c of the clearance-joint role at y(t_j)
/// ```
///
/// Source: Guckenheimer & Holmes (1983), §1.4.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub(crate) struct SectionPoint {
    /// Revolution j.
    pub revolution: usize,
    /// t_j, s.
    pub t: f64,
    /// Crank angle, rad (not wrapped).
    pub crank_angle: Option<f64>,
    /// e_x / c.
    pub ex_over_c: f64,
    /// e_y / c.
    pub ey_over_c: f64,
    /// |e| / c.
    pub eps: f64,
}

/// The stroboscopic section of a case and the run that made it.
///
/// ```text
/// points j = 0..N
/// ```
///
/// Source: Guckenheimer & Holmes (1983), §1.4.
#[derive(Clone, Debug)]
pub(crate) struct Section {
    /// The points.
    pub points: Vec<SectionPoint>,
    /// Wall time of the run, s.
    pub wall_time_s: f64,
    /// The crank period T: the driver's, or for a crank that a motor turns the mean turn
    /// (t_N − t_0)/N.
    pub period: f64,
    /// Whether the points are taken on the crank angle (a crank that is not driven) rather
    /// than every period.
    pub on_angle: bool,
}

/// The settings and the case's roles checked (usage errors naming what is missing).
fn check(p: &Prepared, s: &PoincareSettings) -> Result<(), Error> {
    s.validate()?;
    check_crank(p)?;
    if p.info.as_ref().and_then(|i| i.joint.as_ref()).is_none() {
        return Err(Error::Usage(format!(
            "poincare needs a clearance joint role (roles.clearance_joint); {} has none",
            p.case.name
        )));
    }
    Ok(())
}

/// The stroboscopic section of the clearance-joint role's e/c (one run with `opts`).
pub(crate) fn section(
    p: &Prepared,
    opts: &SolverOptions,
    s: &PoincareSettings,
) -> Result<Section, Error> {
    check(p, s)?;
    let Some(scene) = p.scene() else {
        return Err(Error::Internal("poincare: no scene".into()));
    };
    let mech = Mechanism::from_scene(scene).map_err(|e| scene_error(&p.case, e))?;
    let sampler = Sampler::new(&mech, scene);
    let y0 = mech.initial_state();
    let clock = Instant::now();
    let Some(period) = p.period() else {
        let (t, states) = turn_sections(p, &mech, &y0, opts, s.revolutions)?;
        let wall = clock.elapsed().as_secs_f64();
        let points = section_points(&sampler, &t, &states, y0.len())?;
        return Ok(Section {
            period: (t[s.revolutions] - t[0]) / s.revolutions as f64,
            points,
            wall_time_s: wall,
            on_angle: true,
        });
    };
    let map = stroboscopic_map(
        &mech,
        mech.t_start(),
        &y0,
        period,
        0,
        s.revolutions + 1,
        opts,
        |t, y| sampler.sample(t, y).eps.unwrap_or(f64::NAN),
    )
    .map_err(analysis_error)?;
    let wall = clock.elapsed().as_secs_f64();
    Ok(Section {
        points: section_points(&sampler, &map.t, &map.states, map.dim)?,
        wall_time_s: wall,
        period,
        on_angle: false,
    })
}

/// The times and states (row-major) of the crank's turns k = 0..=N (crate::run::turns) of a
/// crank that is not driven: one integration up to the turns' horizon, stopped after turn N.
fn turn_sections(
    p: &Prepared,
    mech: &Mechanism,
    y0: &[f64],
    opts: &SolverOptions,
    turns: usize,
) -> Result<(Vec<f64>, Vec<f64>), Error> {
    let t0 = mech.t_start();
    let mut tr =
        Turns::new(mech, t0, y0).ok_or_else(|| Error::Internal("poincare: no crank".into()))?;
    let t_cap = tr
        .horizon(t0, turns)
        .ok_or_else(|| Turns::at_rest("poincare", &p.case.name))?;
    let problem = Problem::new(mech, opts)?;
    let mut it = problem.integrator(t0, t_cap, y0)?;
    let n = y0.len();
    let (mut t, mut states) = (vec![t0], y0.to_vec());
    let mut probe = vec![0.0; n];
    let mut buf = vec![0.0; n];
    while t.len() <= turns {
        let outcome = it.step()?;
        let mut from = it.t_prev();
        while t.len() <= turns {
            let mut phi = |s: f64| {
                it.interpolate(s, &mut probe);
                mech.outputs(s, &probe).crank_angle.unwrap_or(f64::NAN)
            };
            let Some(tk) = tr.crossing(t.len(), from, it.t(), &mut phi) else {
                break;
            };
            it.interpolate(tk, &mut buf);
            t.push(tk);
            states.extend_from_slice(&buf);
            from = tk;
        }
        if t.len() <= turns && (matches!(outcome, StepOutcome::StopTime { .. }) || it.is_finished())
        {
            return Err(Error::Input(format!(
                "poincare: the crank of {} turned {} of {turns} times before t = {} s ({} \
                 times as long as {turns} turns at its starting speed): too slow for a section",
                p.case.name,
                t.len() - 1,
                fmt_num(it.t()),
                HORIZON_FACTOR
            )));
        }
    }
    Ok((t, states))
}

/// The section points of the states at times `ts` (row-major, `n` entries each).
fn section_points(
    sampler: &Sampler,
    ts: &[f64],
    states: &[f64],
    n: usize,
) -> Result<Vec<SectionPoint>, Error> {
    let mut points = Vec::with_capacity(ts.len());
    for (j, &t) in ts.iter().enumerate() {
        let smp = sampler.sample(t, &states[j * n..(j + 1) * n]);
        let (Some(ex), Some(ey), Some(eps)) = (smp.ex_over_c, smp.ey_over_c, smp.eps) else {
            return Err(Error::Internal("poincare: no clearance sample".into()));
        };
        if !(ex.is_finite() && ey.is_finite() && eps.is_finite()) {
            return Err(Error::Internal(format!(
                "poincare: e/c not finite at t = {t:e}"
            )));
        }
        points.push(SectionPoint {
            revolution: j,
            t,
            crank_angle: smp.crank_angle,
            ex_over_c: ex,
            ey_over_c: ey,
            eps,
        });
    }
    Ok(points)
}

/// poincare.json.
///
/// ```text
/// settings, T, Δt, d0, the section's |e|/c range over the late half, the Lyapunov summary
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, serde::Serialize)]
pub(crate) struct PoincareReport {
    /// Case and settings (the keys of summary.json).
    #[serde(flatten)]
    pub run: RunHeader,
    /// Crank period T, s: the driver's, or for a crank that a motor turns the mean turn
    /// (t_N − t_0)/N of the section.
    pub period: f64,
    /// Whether the section is taken at the crank's full turns (a crank that a motor turns)
    /// rather than every period T.
    pub section_on_crank_angle: bool,
    /// Revolutions N.
    pub revolutions: usize,
    /// d0, clearances.
    pub perturbation: f64,
    /// Renormalisation interval Δt = T/R, s.
    pub renorm_interval: f64,
    /// The norm of the separation, in words.
    pub norm: String,
    /// Smallest |e|/c of the section over its late half (revolutions ⌊N/2⌋..N).
    pub section_eps_min_late: f64,
    /// Largest |e|/c of the section over its late half.
    pub section_eps_max_late: f64,
    /// Largest distance between consecutive late section points, clearances (0 for a
    /// period-1 response).
    pub section_step_max_late: f64,
    /// The Lyapunov estimate.
    pub lyapunov: LyapunovSummary,
    /// RHS evaluations of both Lyapunov trajectories.
    pub lyapunov_rhs_evals: usize,
    /// Events located on both Lyapunov trajectories.
    pub lyapunov_events: usize,
    /// Wall time of the section run, s.
    pub wall_time_section_s: f64,
    /// Wall time of the Lyapunov runs, s.
    pub wall_time_lyapunov_s: f64,
    /// Accepted steps of both Lyapunov trajectories.
    pub lyapunov_steps: usize,
}

/// The section, the exponent and the report: what the files are made of.
///
/// ```text
/// section + lyapunov + report
/// ```
///
/// Source: this module.
#[derive(Clone, Debug)]
pub struct PoincareResult {
    /// The section.
    pub(crate) section: Section,
    /// The exponent.
    pub(crate) lyapunov: LyapunovRun,
    /// poincare.json.
    pub(crate) report: PoincareReport,
}

/// Both analyses of a case; `progress` gets each as an item.
pub(crate) fn analyse(
    p: &Prepared,
    opts: &SolverOptions,
    s: &PoincareSettings,
    progress: &dyn Progress,
) -> Result<PoincareResult, Error> {
    // Usage errors come before any progress line: a bad call prints one line.
    check(p, s)?;
    progress.started("phases", 2);
    let clock = Instant::now();
    let section = section(p, opts, s)?;
    progress.finished(
        &format!("Poincaré section: {} revolutions", s.revolutions),
        clock.elapsed().as_secs_f64(),
    );
    let clock = Instant::now();
    let ly = lyapunov(p, opts, s, section.period)?;
    progress.finished(
        &format!(
            "Lyapunov exponent: two trajectories, {} renormalisations per revolution",
            s.renorm_per_rev
        ),
        clock.elapsed().as_secs_f64(),
    );
    let late = &section.points[s.revolutions / 2..];
    let eps_min = late.iter().map(|q| q.eps).fold(f64::INFINITY, f64::min);
    let eps_max = late.iter().map(|q| q.eps).fold(f64::NEG_INFINITY, f64::max);
    let step_max = late
        .windows(2)
        .map(|w| (w[1].ex_over_c - w[0].ex_over_c).hypot(w[1].ey_over_c - w[0].ey_over_c))
        .fold(0.0, f64::max);
    let report = PoincareReport {
        run: RunHeader::new(&p.case, opts),
        period: ly.period,
        section_on_crank_angle: section.on_angle,
        revolutions: s.revolutions,
        perturbation: s.perturbation,
        renorm_interval: ly.renorm_interval,
        norm: "‖v‖_w = √Σ(w_i v_i)², w = 1/c on positions and angles, 1/(c ω) on velocities \
               (c the smallest clearance, ω the crank speed)"
            .into(),
        section_eps_min_late: eps_min,
        section_eps_max_late: eps_max,
        section_step_max_late: step_max,
        lyapunov: ly.summary.clone(),
        lyapunov_rhs_evals: ly.estimate.rhs_evals,
        lyapunov_events: ly.estimate.events,
        wall_time_section_s: section.wall_time_s,
        wall_time_lyapunov_s: ly.wall_time_s,
        lyapunov_steps: ly.estimate.steps,
    };
    Ok(PoincareResult {
        section,
        lyapunov: ly,
        report,
    })
}

fn opt(v: Option<f64>) -> String {
    v.map(fmt_num).unwrap_or_default()
}

/// poincare.csv: `revolution,t,crank_angle,ex_over_c,ey_over_c,eps`.
pub(crate) fn section_csv(points: &[SectionPoint]) -> String {
    let mut s = String::from("revolution,t,crank_angle,ex_over_c,ey_over_c,eps\n");
    for q in points {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{}",
            q.revolution,
            fmt_num(q.t),
            opt(q.crank_angle),
            fmt_num(q.ex_over_c),
            fmt_num(q.ey_over_c),
            fmt_num(q.eps)
        );
    }
    s
}

/// lyapunov.csv: `k,t,revolution,log_growth,running` (revolution = (t − t_0)/T).
pub(crate) fn lyapunov_csv(est: &LyapunovEstimate, period: f64) -> String {
    let mut s = String::from("k,t,revolution,log_growth,running\n");
    for (k, ((&t, &g), &r)) in est
        .t
        .iter()
        .zip(&est.log_growth)
        .zip(&est.running)
        .enumerate()
    {
        let _ = writeln!(
            s,
            "{},{},{},{},{}",
            k + 1,
            fmt_num(t),
            fmt_num((t - est.t_start) / period),
            fmt_num(g),
            fmt_num(r)
        );
    }
    s
}

impl PoincareResult {
    /// The lines `lash poincare` prints.
    pub fn describe(&self) -> String {
        let r = &self.report;
        let l = &r.lyapunov;
        format!(
            "{}: {} revolutions of T = {:.6} s, {} {}\n  section: |e|/c in [{:.4}, {:.4}] over \
             the late half, consecutive points at most {:.3e} clearances apart\n  Lyapunov: {} \
             (running estimate {:.4} 1/s, spread {:.3e} over the late half; {:.2} s)\n",
            r.run.case,
            r.revolutions,
            r.period,
            r.run.method.name(),
            r.run.accuracy(),
            r.section_eps_min_late,
            r.section_eps_max_late,
            r.section_step_max_late,
            l.sentence,
            l.exponent_running,
            l.running_spread,
            r.wall_time_section_s + r.wall_time_lyapunov_s
        )
    }

    /// poincare.md.
    pub(crate) fn to_markdown(&self) -> String {
        let r = &self.report;
        let l = &r.lyapunov;
        let mut s = format!(
            "# Poincaré section and Lyapunov exponent of {}\n\n",
            r.run.case
        );
        let _ = writeln!(
            s,
            "{} revolutions of T = {:.6} s with {} ({}). Section: e/c of the clearance joint \
             once per revolution{} (poincare.png, poincare_eps.png).\n",
            r.revolutions,
            r.period,
            r.run.method.name(),
            r.run.accuracy(),
            if r.section_on_crank_angle {
                ", at each full turn of the crank angle (T the mean turn)"
            } else {
                ""
            }
        );
        s.push_str("| quantity | value |\n|---|---|\n");
        let _ = writeln!(
            s,
            "| largest Lyapunov exponent λ (late half) | {:.5} 1/s |",
            l.exponent
        );
        let _ = writeln!(
            s,
            "| standard error (per-revolution rates, late half) | {} |",
            l.std_error
                .map_or("–".to_string(), |e| format!("{e:.3e} 1/s"))
        );
        let _ = writeln!(s, "| λ T (nats per revolution) | {:.4} |", l.per_revolution);
        let _ = writeln!(
            s,
            "| Benettin's running estimate at the end | {:.5} 1/s |",
            l.exponent_running
        );
        let _ = writeln!(
            s,
            "| spread of the running estimate over the late half | {:.3e} 1/s |",
            l.running_spread
        );
        let _ = writeln!(
            s,
            "| d0, renormalisation interval | {:e} clearances, T/{} = {:.4e} s |",
            r.perturbation,
            (r.period / r.renorm_interval).round(),
            r.renorm_interval
        );
        let _ = writeln!(
            s,
            "| section \\|e\\|/c over the late half | [{:.5}, {:.5}] |",
            r.section_eps_min_late, r.section_eps_max_late
        );
        let _ = writeln!(
            s,
            "| wall time (section, Lyapunov) | {:.2} s, {:.2} s |",
            r.wall_time_section_s, r.wall_time_lyapunov_s
        );
        let _ = writeln!(
            s,
            "\n{}.\n\nNorm of the separation: {}.",
            l.sentence, r.norm
        );
        if r.section_on_crank_angle {
            s.push_str(AUTONOMOUS_NOTE);
        }
        s
    }

    /// Writes the files (module doc) into `dir`, each atomically, poincare.json last;
    /// everything is formatted before the first file is written.
    pub(crate) fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, Error> {
        let sec_csv = section_csv(&self.section.points);
        let ly_csv = lyapunov_csv(&self.lyapunov.estimate, self.lyapunov.period);
        let md = self.to_markdown();
        let json = serde_json::to_string_pretty(&self.report)
            .map_err(|e| Error::Internal(format!("poincare.json: {e}")))?;
        io::create_dir(dir)?;
        let mut written = Vec::new();
        let mut push = |w: plot::Written| {
            written.push(w.svg);
            written.push(w.png);
        };
        let pts = &self.section.points;
        let ex: Vec<f64> = pts.iter().map(|q| q.ex_over_c).collect();
        let ey: Vec<f64> = pts.iter().map(|q| q.ey_over_c).collect();
        let rev: Vec<f64> = pts.iter().map(|q| q.revolution as f64).collect();
        let eps: Vec<f64> = pts.iter().map(|q| q.eps).collect();
        let case = &plot::plain(&self.report.run.case);
        push(plot::orbits_plot(
            &dir.join("poincare"),
            &format!("Poincaré section (once per revolution): {case}"),
            &[Series {
                name: "journal centre e/c at t0 + jT",
                x: &ex,
                y: &ey,
                style: SeriesStyle::Points,
            }],
        )?);
        push(plot::line_plot(
            &dir.join("poincare_eps"),
            &Axes {
                title: &format!("|e|/c once per revolution: {case}"),
                x_label: "revolution j",
                y_label: "eccentricity |e|/c (1 = contact)",
            },
            &[Series {
                name: "|e|/c at t0 + jT",
                x: &rev,
                y: &eps,
                style: SeriesStyle::LinePoints,
            }],
        )?);
        let est = &self.lyapunov.estimate;
        let l = &self.lyapunov.summary;
        let ends = [l.late_from, est.t.last().copied().unwrap_or(l.late_from)];
        let flat = [l.exponent; 2];
        let k0 = est.t.iter().position(|&t| t > l.late_from).unwrap_or(0);
        let all = [Series {
            name: "running estimate: log growth / elapsed time",
            x: &est.t,
            y: &est.running,
            style: SeriesStyle::Line,
        }];
        let late = [
            Series {
                name: "running estimate",
                x: &est.t[k0..],
                y: &est.running[k0..],
                style: SeriesStyle::Line,
            },
            Series {
                name: "estimate over the late half",
                x: &ends,
                y: &flat,
                style: SeriesStyle::Dashed,
            },
        ];
        push(plot::panels_plot(
            &dir.join("lyapunov"),
            &format!("Largest Lyapunov exponent, Benettin's method: {case}"),
            &[
                Panel {
                    axes: Axes {
                        title: "running estimate over the whole run",
                        x_label: "t, s",
                        y_label: "exponent λ, 1/s",
                    },
                    series: &all,
                    log_y: false,
                },
                Panel {
                    axes: Axes {
                        title: "late half (the estimate's window)",
                        x_label: "t, s",
                        y_label: "exponent λ, 1/s",
                    },
                    series: &late,
                    log_y: false,
                },
            ],
        )?);
        for (name, text) in [
            ("poincare.csv", &sec_csv),
            ("lyapunov.csv", &ly_csv),
            ("poincare.md", &md),
        ] {
            let p = dir.join(name);
            io::write_atomic(&p, text.as_bytes())?;
            written.push(p);
        }
        let p = dir.join("poincare.json");
        io::write_atomic(&p, format!("{json}\n").as_bytes())?;
        written.push(p);
        Ok(written)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An estimate from log growths g over intervals of 0.5 s (two per revolution of 1 s).
    fn est(g: &[f64]) -> LyapunovEstimate {
        let t: Vec<f64> = (1..=g.len()).map(|k| 0.5 * k as f64).collect();
        let mut sum = 0.0;
        let running = g
            .iter()
            .zip(&t)
            .map(|(g, t)| {
                sum += g;
                sum / t
            })
            .collect();
        LyapunovEstimate {
            t_start: 0.0,
            t,
            log_growth: g.to_vec(),
            running,
            exponent: 0.0,
            ..Default::default()
        }
    }

    /// Four revolutions: the late half is revolutions 2–4, t ∈ [2, 4] s. With late growths
    /// (3, 3 | 2, 2) the per-revolution rates are 6 and 4 1/s: λ = 10/2 = 5, σ = sd/√2 =
    /// √2/√2 = 1, so λ > 3σ: chaotic; the mirror image is not chaotic; (3, 2 | 1, 1) gives
    /// λ = 3.5 with σ = 1.5: inconclusive.
    #[test]
    fn summary_of_known_log_growths() {
        let s = summarize(&est(&[1.0, 1.0, 2.0, 2.0, 3.0, 3.0, 2.0, 2.0]), 1.0, 2).unwrap();
        assert_eq!(s.late_revolutions, 2);
        assert_eq!(s.late_from, 2.0);
        assert!((s.exponent - 5.0).abs() < 1e-15);
        assert!((s.std_error.unwrap() - 1.0).abs() < 1e-15);
        assert_eq!(s.chaos, Chaos::Chaotic);
        // Running estimate: Σg/t = 16/4 at the end; over the late half (intervals 5–8) it
        // runs through 9/2.5, 12/3, 14/3.5, 16/4: spread 4.0 − 3.6.
        assert!((s.exponent_running - 4.0).abs() < 1e-15);
        assert!((s.running_spread - 0.4).abs() < 1e-15);
        assert!((s.per_revolution - 5.0).abs() < 1e-15);
        let neg: Vec<f64> = [1.0, 1.0, 2.0, 2.0, 3.0, 3.0, 2.0, 2.0]
            .iter()
            .map(|g| -g)
            .collect();
        assert_eq!(
            summarize(&est(&neg), 1.0, 2).unwrap().chaos,
            Chaos::NotChaotic
        );
        let s = summarize(&est(&[0.0, 0.0, 0.0, 0.0, 3.0, 2.0, 1.0, 1.0]), 1.0, 2).unwrap();
        assert!((s.exponent - 3.5).abs() < 1e-15 && (s.std_error.unwrap() - 1.5).abs() < 1e-15);
        assert_eq!(s.chaos, Chaos::Inconclusive);
        assert!(s.sentence.contains("inconclusive"));
        // One revolution: no uncertainty.
        let s = summarize(&est(&[1.0, 1.0]), 1.0, 2).unwrap();
        assert_eq!((s.std_error, s.chaos), (None, Chaos::Inconclusive));
        assert!((s.exponent - 2.0).abs() < 1e-15);
        // Not whole revolutions.
        assert!(summarize(&est(&[1.0, 1.0, 1.0]), 1.0, 2).is_err());
    }

    #[test]
    fn settings_ranges() {
        assert!(PoincareSettings::default().validate().is_ok());
        for s in [
            PoincareSettings {
                revolutions: 0,
                ..Default::default()
            },
            PoincareSettings {
                perturbation: 1.0,
                ..Default::default()
            },
            PoincareSettings {
                perturbation: f64::NAN,
                ..Default::default()
            },
            PoincareSettings {
                renorm_per_rev: 0,
                ..Default::default()
            },
        ] {
            assert_eq!(
                s.validate().unwrap_err().kind(),
                crate::ErrorKind::BadInput,
                "{s:?}"
            );
        }
    }
}
