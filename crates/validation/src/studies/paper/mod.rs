//! `lash study paper`: the paper's whole §4, its figures, and its claims checked against runs.
//!
//! ```text
//! cases        dry and lubricated at 120, 150, 180, 200 rpm (c = 0.1 mm) and at 150 rpm with
//!              c = 0.1, 0.2, 0.3, 0.5 mm; the ideal mechanism at the four speeds (18 cases)
//! realisation  k = 0..N−1 (N = 8): the case with the crank's initial angle θ₀ = k·Δθ,
//!              Δθ = 1e-6 rad (k = 0 is the paper's case; the ideal cases run once)
//! run          BDF, rtol 1e-10, atol 1e-12, 2 event samples per step, no h_max; two
//!              revolutions through the shared runner (simulate::simulate, no energy
//!              accounting); samples on metrics::grid of each revolution (2 × 2001 points:
//!              the run's metrics window and, as extra output times, the revolution before)
//! reference    every realisation again at rtol 1e-12, atol 1e-14 (convergence check), and
//! loose        at rtol 1e-8, atol 1e-10 (to show what a looser tolerance changes)
//! statistics   metrics of the last revolution (docs/outputs.md, "`metrics`") + [`Deviations`]
//! claims       claims::evaluate on the ensemble means (and per realisation)
//! files        DIR/figures/figNN[a-d].{svg,png} → DIR/report.md → DIR/study.json (last)
//! resuming     every finished run is kept in DIR/cache/ under the hash of its inputs
//!              (crate::store::cache); a rerun reuses it, so an interrupted study (SIGINT, SIGTERM:
//!              the runs in flight are abandoned) goes on where it stopped
//! ```
//!
//! The dry cases are chaotic (docs/model.md §9), which is why each case is an ensemble and the
//! claims compare statistics, never pointwise values. The realisations differ by a crank phase
//! of micro-radians: physically nothing (r·Δθ = 15 nm per step), but more than the integration
//! error at either setting (rtol·|q| ≈ 4e-11 m at rtol 1e-10), so that they are different
//! trajectories rather than copies of one numerical trajectory, and a smooth change of every
//! case alike (the journal's initial eccentricity is not perturbed: e = 0 is where the film's
//! attitude angle is undefined, docs/model.md §2, and nanometre offsets there change the
//! lubricated start discontinuously). Nothing but the cache of finished runs is written if any
//! run fails.
//!
//! Source: the paper's §4 and Figures 5–16; docs/model.md §5, §6, §9; docs/outputs.md (`metrics`).

pub mod claims;
mod figures;
pub mod markdown;

use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use lash_model::scene::JointSpec;
use lash_model::{IdealSliderCrank, Scene};
use lash_solver::{Atol, Method, SolverOptions, Stats};
use rayon::prelude::*;

use crate::error::Error;
use crate::progress::{NoProgress, Progress};
use crate::report::metrics::{self, Metrics, Sample};
use crate::run::case::Case;
use crate::run::simulate::{simulate, Prepared, RunRequest, DEFAULT_MAX_STEPS};
use crate::run::steady::UntilPeriodic;
use crate::store::cache::{RunCache, CACHE_DIR};
use crate::store::io;

pub use claims::{Claim, Number, Origin, Quantity, Verdict};

/// File name of the markdown report.
pub const REPORT_FILE: &str = "report.md";
/// File name of the machine-readable results.
pub const JSON_FILE: &str = "study.json";
/// Folder of the figures inside the output directory.
pub const FIGURES_DIR: &str = "figures";

/// Tolerance of the study's runs until periodic, units of c: 5 × tighter than the claim's
/// "periodic" threshold [`claims::PERIODIC`].
pub const STEADY_TOL: f64 = 1e-2;
/// Cap on the revolutions of the study's runs until periodic.
pub const STEADY_MAX_REVOLUTIONS: usize = 40;

/// Half-width of the windows around the dead centres, degrees of crank angle.
pub const DEAD_CENTRE_WINDOW_DEG: f64 = 15.0;

/// The 18 cases of the study: the speed and clearance studies, dry then lubricated, then the
/// ideal mechanism.
pub fn case_names() -> Vec<&'static str> {
    let mut v: Vec<&str> = Vec::new();
    for set in [
        &claims::DRY_SPEEDS[..],
        &claims::DRY_CLEARANCES[1..],
        &claims::LUB_SPEEDS[..],
        &claims::LUB_CLEARANCES[1..],
        &claims::IDEALS[..],
    ] {
        v.extend_from_slice(set);
    }
    v
}

/// Number of figures the study draws (each an SVG and a PNG in `figures/`).
pub fn figure_count() -> usize {
    figures::count()
}

/// Solver settings of one study run.
///
/// ```text
/// method, rtol, atol (scalar), event_samples interior points per step for the event search
/// (an adaptive step may otherwise hold a whole contact, onset and loss, and skip it)
/// ```
///
/// Source: this study (chosen and checked for convergence in the report);
/// `lash_solver::SolverOptions`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Settings {
    /// Integration method.
    pub method: Method,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
    /// Interior points sampled per step by the event search.
    pub event_samples: usize,
}

impl Settings {
    /// The solver options of a study run: these settings, event location on, no h_max, the
    /// runner's step limit (`simulate::DEFAULT_MAX_STEPS`).
    fn options(&self) -> SolverOptions {
        let mut o = SolverOptions::with_method(self.method);
        o.rtol = self.rtol;
        o.atol = Atol::Scalar(self.atol);
        o.event_samples = self.event_samples;
        o.max_steps = DEFAULT_MAX_STEPS;
        o
    }
}

/// What the study runs.
///
/// ```text
/// every case × realisations k = 0..N−1 (crank θ₀ = k·Δθ) × {settings, reference, loose}
/// ```
///
/// Source: this module (docs/model.md §9 for why an ensemble).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Plan {
    /// Settings of the reported runs.
    pub settings: Settings,
    /// Tighter settings of the convergence check.
    pub reference: Settings,
    /// Looser settings, run to show what they would change.
    pub loose: Settings,
    /// Realisations per clearance case (N ≥ 1).
    pub realisations: usize,
    /// Step Δθ of the crank's initial angle between realisations, rad.
    pub phase_step_rad: f64,
    /// Steady state of the periodicity claim: runs until the section settles.
    pub steady: UntilPeriodic,
}

impl Plan {
    /// The plan of `lash study paper`: BDF at rtol 1e-10 (reference 1e-12, loose 1e-8),
    /// atol = rtol/100,
    /// two event samples per step, 8 realisations 1e-6 rad of crank phase apart.
    pub fn paper() -> Plan {
        let s = |rtol: f64| Settings {
            method: Method::Bdf,
            rtol,
            atol: rtol * 1e-2,
            event_samples: 2,
        };
        Plan {
            settings: s(1e-10),
            reference: s(1e-12),
            loose: s(1e-8),
            realisations: 8,
            phase_step_rad: 1e-6,
            steady: UntilPeriodic {
                tol: STEADY_TOL,
                max_revolutions: STEADY_MAX_REVOLUTIONS,
            },
        }
    }
}

/// Which of the plan's solver settings.
///
/// ```text
/// Study = Plan::settings (reported);  Reference = Plan::reference;  Loose = Plan::loose
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Setting {
    /// The reported runs.
    Study,
    /// The tighter convergence check.
    Reference,
    /// The looser comparison.
    Loose,
}

impl Setting {
    /// All three, study first.
    pub const ALL: [Setting; 3] = [Setting::Study, Setting::Reference, Setting::Loose];
}

impl Plan {
    /// The solver settings of `which`.
    pub fn get(&self, which: Setting) -> Settings {
        match which {
            Setting::Study => self.settings,
            Setting::Reference => self.reference,
            Setting::Loose => self.loose,
        }
    }
}

impl CaseResult {
    /// The realisations at `which` settings.
    pub fn ensemble(&self, which: Setting) -> &Ensemble {
        match which {
            Setting::Study => &self.study,
            Setting::Reference => &self.reference,
            Setting::Loose => &self.loose,
        }
    }
}

/// Deviations of one run from the ideal mechanism and the journal's motion, over the last
/// revolution (the 2001-point grid), at the same crank angle θ.
///
/// ```text
/// stroke        = max x_id − min x_id                      (≈ 2r)
/// q_dev_max     = max |q − q_id|,  q ∈ {x, ẋ, ẍ};  a_ideal_peak = max |ẍ_id|
/// x_dev_bdc     = max |x − x_id| over |θ mod 2π| ≤ 15°      (bottom dead centre: x = r + l)
/// a_dev_dead_centres = max |ẍ − ẍ_id| over |θ mod π| ≤ 15°
/// q_dev_rel     = RMS(q − q_id) / RMS(q_id − mean q_id)
/// fluctuation_sectors = #{ 45° sectors s : max_s |ẍ − ẍ_id| > 0.1 a_ideal_peak }
/// contact_fraction = #{ i : δ_i > 0 } / 2001;  orbit_closure = max_i |e(t_i) − e(t_i − T)| / c
/// ```
///
/// Source: this study's reading of the paper's §4 (the claims module says which claim uses
/// which); docs/model.md §5 for the ideal mechanism.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Deviations {
    /// max x_ideal − min x_ideal, m.
    pub stroke: f64,
    /// max |x − x_ideal|, m.
    pub x_dev_max: f64,
    /// max |ẋ − ẋ_ideal|, m/s.
    pub v_dev_max: f64,
    /// max |ẍ − ẍ_ideal|, m/s².
    pub a_dev_max: f64,
    /// max |ẍ_ideal|, m/s².
    pub a_ideal_peak: f64,
    /// max |x − x_ideal| within ±15° of θ ≡ 0, m.
    pub x_dev_bdc: f64,
    /// max |ẍ − ẍ_ideal| within ±15° of θ ≡ 0 or π, m/s².
    pub a_dev_dead_centres: f64,
    /// RMS(x − x_ideal) / RMS(x_ideal − mean).
    pub x_dev_rel: f64,
    /// RMS(ẋ − ẋ_ideal) / RMS(ẋ_ideal − mean).
    pub v_dev_rel: f64,
    /// RMS(ẍ − ẍ_ideal) / RMS(ẍ_ideal − mean).
    pub a_dev_rel: f64,
    /// 45° sectors whose max |ẍ − ẍ_ideal| exceeds 10 % of the ideal peak (0..=8).
    pub fluctuation_sectors: usize,
    /// Fraction of the grid in contact, δ > 0 (clearance joint).
    pub contact_fraction: Option<f64>,
    /// max |e(t) − e(t − T)| / c over the last revolution (clearance joint).
    pub orbit_closure: Option<f64>,
}

/// The statistics of one realisation of one case.
///
/// ```text
/// metrics (docs/outputs.md, "`metrics`": last revolution) + deviations from the ideal mechanism
/// ```
///
/// Source: docs/outputs.md (`metrics`); [`Deviations`].
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CaseStats {
    /// The metrics of docs/outputs.md ("`metrics`"; energy null: the study does not account
    /// energy).
    pub metrics: Metrics,
    /// Deviations from the ideal mechanism.
    pub dev: Deviations,
}

/// The realisations of one case at one setting.
///
/// ```text
/// members[k] = statistics of realisation k;
/// acc_spread = max_i ( max_k ẍ_k(t_i) − min_k ẍ_k(t_i) )  over the last revolution's grid
/// ```
///
/// Source: this module (docs/model.md §9: chaotic cases are compared through statistics).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Ensemble {
    /// One entry per realisation (k = 0 is the paper's case).
    pub members: Vec<CaseStats>,
    /// Pointwise spread of the slider acceleration over the realisations, m/s².
    pub acc_spread: f64,
}

/// What the solver did for the paper's realisation (k = 0) at the study's settings, and the
/// wall time of all runs of the case.
///
/// ```text
/// stats, events of realisation 0;  wall_time_s of realisation 0;  total_wall_time_s = Σ runs
/// ```
///
/// Source: `lash_solver::Stats`; docs/outputs.md (`wall_time_s`, `events`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SolverRecord {
    /// The solver's counters.
    pub stats: Stats,
    /// Events located during the whole run.
    pub events: usize,
    /// Wall time of the integration alone, s.
    pub wall_time_s: f64,
    /// Wall time of every run of this case (all realisations, both settings), s.
    pub total_wall_time_s: f64,
}

/// The joint of a study case.
///
/// ```text
/// Dry (IMPACT + Coulomb) | Lubricated (long Gümbel film + contact) | Ideal (pin)
/// ```
///
/// Source: docs/model.md §3–§5.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// Dry clearance joint.
    Dry,
    /// Lubricated clearance joint.
    Lubricated,
    /// Ideal revolute joint.
    Ideal,
}

/// Everything measured for one case.
///
/// ```text
/// name, kind, rpm, c;  study = Ensemble at Plan::settings;  reference, loose = at
/// Plan::reference, Plan::loose
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CaseResult {
    /// Case name (file stem in cases/press/).
    pub name: String,
    /// Dry, lubricated or ideal.
    pub kind: Kind,
    /// Crank speed, rpm.
    pub rpm: f64,
    /// Radial clearance, m (null for the ideal mechanism).
    pub clearance_m: Option<f64>,
    /// Realisations at the study's settings.
    pub study: Ensemble,
    /// The same realisations at the reference settings.
    pub reference: Ensemble,
    /// The same realisations at the loose settings.
    pub loose: Ensemble,
    /// max_i |ẍ(t_i) at the study's settings − ẍ(t_i) at the reference settings| of the
    /// paper's realisation over the last revolution, m/s².
    pub acc_tolerance_diff: f64,
    /// Solver counters and times.
    pub solver: SolverRecord,
    /// The same realisations run until the orbit settles (the cases of the periodicity claim;
    /// null for the others).
    pub steady: Option<SteadyRuns>,
}

/// A case's realisations run until periodic ([`crate::run::steady`]) at the three settings.
///
/// ```text
/// run until |s_k − s_{k−1}| < tol·c (section once per revolution), at most max_revolutions;
/// statistics of the last revolution, as for the two-revolution runs
/// ```
///
/// Source: [`crate::run::steady`].
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SteadyRuns {
    /// The request.
    pub until: UntilPeriodic,
    /// Revolutions run by each realisation at the study's settings.
    pub revolutions: Vec<usize>,
    /// Whether each realisation settled within the cap (study's settings).
    pub settled: Vec<bool>,
    /// Realisations at the study's settings.
    pub study: Ensemble,
    /// At the reference settings.
    pub reference: Ensemble,
    /// At the loose settings.
    pub loose: Ensemble,
}

/// A written figure.
///
/// ```text
/// id "fig06a" → figures/fig06a.svg, figures/fig06a.png
/// ```
///
/// Source: the paper's Figures 5–16 (panel letters as in the paper; panel (c) of the
/// displacement figures is added: x − x_ideal).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FigureRecord {
    /// File stem, e.g. `fig06a`.
    pub id: String,
    /// Figure title.
    pub title: String,
    /// Cases drawn.
    pub cases: Vec<String>,
}

/// Wall times of the study, s.
///
/// ```text
/// total = runs + figures + writing
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Timing {
    /// All integrations and statistics (parallel).
    pub runs_s: f64,
    /// Rendering of the figures (parallel).
    pub figures_s: f64,
    /// The whole command.
    pub total_s: f64,
    /// Worker threads used.
    pub threads: usize,
}

/// The content of study.json.
///
/// ```text
/// { version, plan, cases[], claims[] (study settings), reference_claims[],
///   loose_claims[] (the other settings), verdicts_agree, figures[], timing }
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StudyResult {
    /// lash version string.
    pub version: String,
    /// What was run.
    pub plan: Plan,
    /// The cases, in the order of [`case_names`].
    pub cases: Vec<CaseResult>,
    /// The claims judged on the study's settings.
    pub claims: Vec<Claim>,
    /// The same claims judged on the reference settings.
    pub reference_claims: Vec<Claim>,
    /// The same claims judged on the loose settings.
    pub loose_claims: Vec<Claim>,
    /// True when every claim has the same verdict at the study's and the reference settings.
    pub verdicts_agree: bool,
    /// The figures written.
    pub figures: Vec<FigureRecord>,
    /// Wall times.
    pub timing: Timing,
}

impl StudyResult {
    /// The case of this name.
    pub fn case(&self, name: &str) -> Option<&CaseResult> {
        self.cases.iter().find(|c| c.name == name)
    }

    /// The ensembles at one of the settings, by case name; the steady-state runs under
    /// [`claims::at_steady_state`] of the name.
    pub fn ensembles(&self, which: Setting) -> claims::Cases {
        let mut m: claims::Cases = self
            .cases
            .iter()
            .map(|c| (c.name.clone(), c.ensemble(which).clone()))
            .collect();
        for c in &self.cases {
            if let Some(st) = &c.steady {
                let e = match which {
                    Setting::Study => &st.study,
                    Setting::Reference => &st.reference,
                    Setting::Loose => &st.loose,
                };
                m.insert(claims::at_steady_state(&c.name), e.clone());
            }
        }
        m
    }
}

// ---------------------------------------------------------------------------------------------
// Running one case: through the shared runner, `simulate::simulate`, with the study's own solver
// options, the metrics grid of the last revolution (RunResult::window) and that of the
// revolution before it as extra output times; no trajectory, no energy accounting.
// ---------------------------------------------------------------------------------------------

/// One finished run: the samples of the last two revolutions and what the solver did.
#[derive(Clone, Debug)]
struct Run {
    /// Samples on `metrics::grid(t_end − T, T)` (the revolution before the last).
    previous: Vec<Sample>,
    /// Samples on `metrics::grid(t_end, T)` (the last revolution).
    last: Vec<Sample>,
    metrics: Metrics,
    stats: Stats,
    wall_time_s: f64,
    events: usize,
    ideal: Option<IdealSliderCrank>,
    /// |ω| of the crank driver, rpm.
    rpm: f64,
    /// Radial clearance of the clearance-joint role, m.
    clearance: Option<f64>,
    /// Revolutions run.
    revolutions: usize,
    /// Whether the orbit settled (runs until periodic).
    settled: Option<bool>,
}

/// Runs the press scene `scene` (the catalogue case `name`, or one of its realisations) over
/// its span through [`simulate`], or with `until` until its orbit settles
/// ([`crate::run::steady`]); samples its last two revolutions.
fn run_case(
    name: &str,
    scene: &Scene,
    settings: &Settings,
    until: Option<&UntilPeriodic>,
) -> Result<Run, Error> {
    let p = Prepared::with_scene(Case::catalogue(name)?, scene.clone())?;
    let info = p
        .info
        .as_ref()
        .ok_or_else(|| Error::Internal(format!("case {name}: no mechanism")))?;
    let (period, omega) = info
        .period
        .zip(info.crank_speed)
        .ok_or_else(|| Error::Input(format!("case {name}: no crank_driver role")))?;
    let settled = until
        .map(|u| crate::run::steady::settle(&p, &settings.options(), u))
        .transpose()?;
    let t0 = info.t_start;
    let t_end = match &settled {
        Some(s) => t0 + period * s.revolutions as f64,
        None => info.t_end,
    };
    if !(t_end - 2.0 * period >= t0 - 1e-9 * period) {
        return Err(Error::Input(format!(
            "case {name}: the study needs two crank revolutions, the scene runs {:.3}",
            (t_end - t0) / period
        )));
    }
    let mut req = RunRequest::new(settings.options());
    req.t_end = Some(t_end);
    req.trajectory_points = Some(0);
    req.energy = false;
    // The grid may start a few ulps before t0 (t_end = 2T): clamp into the run.
    req.extra_times = metrics::grid(t_end - period, period)
        .into_iter()
        .map(|t| t.max(t0))
        .collect();
    let r = simulate(&p, &req)?;
    let n = metrics::GRID_POINTS;
    if r.window.len() != n || r.extra.len() != n {
        return Err(Error::Internal(format!(
            "case {name}: {} and {} samples of the last two revolutions, expected {n}",
            r.extra.len(),
            r.window.len()
        )));
    }
    let metrics = r
        .summary
        .metrics
        .ok_or_else(|| Error::Internal(format!("case {name}: no metrics")))?;
    Ok(Run {
        previous: r.extra,
        last: r.window,
        metrics,
        stats: r.summary.stats,
        wall_time_s: r.summary.wall_time_s,
        events: r.summary.events,
        ideal: r.ideal,
        rpm: omega * 30.0 / PI,
        clearance: info.joint.map(|j| j.clearance),
        revolutions: ((t_end - t0) / period).round() as usize,
        settled: settled.map(|s| s.settled),
    })
}

// ---------------------------------------------------------------------------------------------
// Statistics of one run
// ---------------------------------------------------------------------------------------------

/// A required column of the samples.
fn need(s: &[Sample], name: &str, f: impl Fn(&Sample) -> Option<f64>) -> Result<Vec<f64>, Error> {
    s.iter()
        .map(|x| {
            f(x).filter(|v| v.is_finite()).ok_or_else(|| {
                Error::Internal(format!(
                    "study: {name} missing or not finite at t = {:e}",
                    x.t
                ))
            })
        })
        .collect()
}

fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for x in v {
        s += x * x;
        n += 1;
    }
    (s / n.max(1) as f64).sqrt()
}

fn max_abs(v: impl Iterator<Item = f64>) -> f64 {
    v.fold(0.0, |m: f64, x| m.max(x.abs()))
}

/// RMS(q − q_ideal) / RMS(q_ideal − mean q_ideal).
fn relative_rms(q: &[f64], qi: &[f64]) -> f64 {
    let mean = qi.iter().sum::<f64>() / qi.len() as f64;
    let num = rms(q.iter().zip(qi).map(|(a, b)| a - b));
    let den = rms(qi.iter().map(|b| b - mean));
    if den > 0.0 {
        num / den
    } else {
        0.0
    }
}

/// The [`Deviations`] of the last revolution `last` (with `previous`, the revolution before
/// it on the same phases) from the ideal mechanism `ideal`. Errors ([`Error::Internal`]): a
/// missing slider or crank column, different lengths.
pub fn deviations(
    last: &[Sample],
    previous: &[Sample],
    ideal: &IdealSliderCrank,
) -> Result<Deviations, Error> {
    if last.is_empty() || previous.len() != last.len() {
        return Err(Error::Internal(format!(
            "study: {} and {} samples in the last two revolutions",
            previous.len(),
            last.len()
        )));
    }
    let phi = need(last, "crank_angle", |s| s.crank_angle)?;
    let x = need(last, "slider_x", |s| s.slider_x)?;
    let v = need(last, "slider_v", |s| s.slider_v)?;
    let a = need(last, "slider_a", |s| s.slider_a)?;
    let theta: Vec<f64> = phi.iter().map(|&p| ideal.theta_of_crank_angle(p)).collect();
    let xi: Vec<f64> = theta.iter().map(|&t| ideal.x_at(t)).collect();
    let vi: Vec<f64> = theta.iter().map(|&t| ideal.v_at(t)).collect();
    let ai: Vec<f64> = theta.iter().map(|&t| ideal.a_at(t)).collect();
    let dx: Vec<f64> = x.iter().zip(&xi).map(|(p, q)| (p - q).abs()).collect();
    let da: Vec<f64> = a.iter().zip(&ai).map(|(p, q)| (p - q).abs()).collect();
    let a_ideal_peak = max_abs(ai.iter().copied());
    let w = DEAD_CENTRE_WINDOW_DEG.to_radians();
    let phase: Vec<f64> = theta.iter().map(|t| t.rem_euclid(2.0 * PI)).collect();
    let near_bdc = |p: f64| p.min(2.0 * PI - p) <= w;
    let near_dc = |p: f64| near_bdc(p) || (p - PI).abs() <= w;
    let x_dev_bdc = max_abs((0..x.len()).filter(|&i| near_bdc(phase[i])).map(|i| dx[i]));
    let a_dev_dead_centres = max_abs((0..x.len()).filter(|&i| near_dc(phase[i])).map(|i| da[i]));
    let mut sector_max = [0.0f64; 8];
    for (p, d) in phase.iter().zip(&da) {
        let k = ((p / (PI / 4.0)) as usize).min(7);
        sector_max[k] = sector_max[k].max(*d);
    }
    let fluctuation_sectors = sector_max
        .iter()
        .filter(|&&m| m > claims::SECTOR_FLUCTUATION * a_ideal_peak)
        .count();
    let contact_fraction = if last.iter().all(|s| s.delta.is_some()) {
        let d = need(last, "delta", |s| s.delta)?;
        Some(d.iter().filter(|&&x| x > 0.0).count() as f64 / d.len() as f64)
    } else {
        None
    };
    let has_e = |s: &[Sample]| {
        s.iter()
            .all(|p| p.ex_over_c.is_some() && p.ey_over_c.is_some())
    };
    let orbit_closure = if has_e(last) && has_e(previous) {
        let (ex, ey) = (
            need(last, "ex_over_c", |s| s.ex_over_c)?,
            need(last, "ey_over_c", |s| s.ey_over_c)?,
        );
        let (px, py) = (
            need(previous, "ex_over_c", |s| s.ex_over_c)?,
            need(previous, "ey_over_c", |s| s.ey_over_c)?,
        );
        Some(max_abs(
            (0..ex.len()).map(|i| (ex[i] - px[i]).hypot(ey[i] - py[i])),
        ))
    } else {
        None
    };
    let fold = |v: &[f64], f: fn(f64, f64) -> f64, z: f64| v.iter().copied().fold(z, f);
    Ok(Deviations {
        stroke: fold(&xi, f64::max, f64::NEG_INFINITY) - fold(&xi, f64::min, f64::INFINITY),
        x_dev_max: max_abs(dx.iter().copied()),
        v_dev_max: max_abs(v.iter().zip(&vi).map(|(p, q)| p - q)),
        a_dev_max: max_abs(da.iter().copied()),
        a_ideal_peak,
        x_dev_bdc,
        a_dev_dead_centres,
        x_dev_rel: relative_rms(&x, &xi),
        v_dev_rel: relative_rms(&v, &vi),
        a_dev_rel: relative_rms(&a, &ai),
        fluctuation_sectors,
        contact_fraction,
        orbit_closure,
    })
}

// ---------------------------------------------------------------------------------------------
// The study
// ---------------------------------------------------------------------------------------------

/// Curves of the paper's realisation for the figures (last revolution).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub(crate) struct Curves {
    /// Crank angle θ, degrees, 0..360 over the last revolution.
    pub deg: Vec<f64>,
    pub x: Vec<f64>,
    pub v: Vec<f64>,
    pub a: Vec<f64>,
    pub x_ideal: Vec<f64>,
    pub v_ideal: Vec<f64>,
    pub a_ideal: Vec<f64>,
    /// e/c of the journal (clearance cases).
    pub orbit: Option<(Vec<f64>, Vec<f64>)>,
}

fn curves(last: &[Sample], ideal: &IdealSliderCrank) -> Result<Curves, Error> {
    let phi = need(last, "crank_angle", |s| s.crank_angle)?;
    let theta: Vec<f64> = phi.iter().map(|&p| ideal.theta_of_crank_angle(p)).collect();
    // The window starts at a whole number of turns; start it at 0° even if θ rounds below.
    let turns = (theta[0] / (2.0 * PI) + 1e-9).floor();
    let orbit = match (
        last.iter().map(|s| s.ex_over_c).collect::<Option<Vec<_>>>(),
        last.iter().map(|s| s.ey_over_c).collect::<Option<Vec<_>>>(),
    ) {
        (Some(ex), Some(ey)) => Some((ex, ey)),
        _ => None,
    };
    Ok(Curves {
        deg: theta
            .iter()
            .map(|t| (t - 2.0 * PI * turns).to_degrees())
            .collect(),
        x: need(last, "slider_x", |s| s.slider_x)?,
        v: need(last, "slider_v", |s| s.slider_v)?,
        a: need(last, "slider_a", |s| s.slider_a)?,
        x_ideal: theta.iter().map(|&t| ideal.x_at(t)).collect(),
        v_ideal: theta.iter().map(|&t| ideal.v_at(t)).collect(),
        a_ideal: theta.iter().map(|&t| ideal.a_at(t)).collect(),
        orbit,
    })
}

/// The scene of realisation `k`: the crank driver's initial angle θ₀ moved by k·Δθ.
fn realisation(scene: &Scene, k: usize, step_rad: f64) -> Scene {
    let mut s = scene.clone();
    let driver = s.roles.crank_driver.clone();
    for j in s.joints.iter_mut() {
        if let JointSpec::Driver(d) = j {
            if Some(&d.name) == driver.as_ref() {
                d.theta0 += k as f64 * step_rad;
            }
        }
    }
    s
}

pub(crate) struct Job<'a> {
    pub(crate) case: usize,
    pub(crate) name: &'a str,
    /// The case's scene (before the realisation's crank phase).
    pub(crate) scene: Scene,
    pub(crate) setting: Setting,
    pub(crate) member: usize,
    /// Run until the orbit settles instead of the scene's two revolutions.
    pub(crate) until: Option<UntilPeriodic>,
}

/// What one job gives: stored in the cache of finished runs ([`crate::store::cache`]).
#[derive(Clone, serde::Serialize, serde::Deserialize)]
pub(crate) struct JobOut {
    pub(crate) stats: CaseStats,
    pub(crate) acc: Vec<f64>,
    pub(crate) curves: Option<Curves>,
    pub(crate) solver: (Stats, usize, f64),
    pub(crate) meta: (f64, Option<f64>),
    /// Revolutions run and, until periodic, whether the orbit settled.
    #[serde(default)]
    pub(crate) length: (usize, Option<bool>),
}

fn run_job(job: &Job<'_>, plan: &Plan) -> Result<JobOut, Error> {
    let settings = plan.get(job.setting);
    let scene = realisation(&job.scene, job.member, plan.phase_step_rad);
    let r = run_case(job.name, &scene, &settings, job.until.as_ref())?;
    let ideal = r.ideal.ok_or_else(|| {
        Error::Input(format!(
            "case {}: not an in-line slider-crank with slider and crank_driver roles",
            job.name
        ))
    })?;
    let dev = deviations(&r.last, &r.previous, &ideal)?;
    let curves = (job.setting == Setting::Study && job.member == 0)
        .then(|| curves(&r.last, &ideal))
        .transpose()?;
    Ok(JobOut {
        acc: need(&r.last, "slider_a", |s| s.slider_a)?,
        stats: CaseStats {
            metrics: r.metrics,
            dev,
        },
        curves,
        solver: (r.stats, r.events, r.wall_time_s),
        meta: (r.rpm, r.clearance),
        length: (r.revolutions, r.settled),
    })
}

pub(crate) fn spread(accs: &[&Vec<f64>]) -> f64 {
    let n = accs.first().map_or(0, |a| a.len());
    (0..n)
        .map(|i| {
            let (lo, hi) = accs
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), a| {
                    (l.min(a[i]), h.max(a[i]))
                });
            hi - lo
        })
        .fold(0.0, f64::max)
}

pub(crate) fn kind_of(name: &str) -> Kind {
    if name.starts_with("dry") {
        Kind::Dry
    } else if name.starts_with("lubricated") {
        Kind::Lubricated
    } else {
        Kind::Ideal
    }
}

/// The inputs a job's result depends on (its cache key, with the build: [`crate::store::cache`]).
#[derive(serde::Serialize)]
struct JobKey<'a> {
    case: &'a str,
    setting: Setting,
    member: usize,
    scene: &'a Scene,
    options: SolverOptions,
    #[serde(skip_serializing_if = "Option::is_none")]
    until_periodic: Option<UntilPeriodic>,
}

/// Runs `jobs` in parallel (returning their results and the number of distinct runs), each
/// at most once: a run found in `cache` is reused, a finished
/// one stored there; `progress` gets one item per run done. A stop request
/// (`lash_solver::interrupt`) abandons the runs in flight and starts no other:
/// [`Error::Interrupted`], with what is kept. `what` names the command in notes.
pub(crate) fn run_jobs(
    jobs: &[Job<'_>],
    plan: &Plan,
    cache: &RunCache,
    progress: &dyn Progress,
    what: &str,
) -> Result<(Vec<JobOut>, usize), Error> {
    let keys: Vec<String> = jobs
        .iter()
        .map(|j| {
            let scene = realisation(&j.scene, j.member, plan.phase_step_rad);
            cache.key(
                "study run",
                &JobKey {
                    case: j.name,
                    setting: j.setting,
                    member: j.member,
                    scene: &scene,
                    options: plan.get(j.setting).options(),
                    until_periodic: j.until,
                },
            )
        })
        .collect::<Result<_, _>>()?;
    // Identical runs (a variant that leaves a case as it is) are done once.
    let mut first: BTreeMap<&str, usize> = BTreeMap::new();
    for (i, k) in keys.iter().enumerate() {
        first.entry(k.as_str()).or_insert(i);
    }
    let unique: Vec<usize> = first.values().copied().collect();
    let cached = unique.iter().filter(|&&i| cache.contains(&keys[i])).count();
    if cached > 0 {
        progress.note(
            &format!(
                "{what}: {cached} of {} runs finished before, reused from {}",
                unique.len(),
                cache.dir().display()
            )
            .into(),
        );
    }
    progress.started("runs", unique.len() - cached);
    let done = AtomicUsize::new(0);
    let outs: Result<Vec<JobOut>, Error> = unique
        .par_iter()
        .map(|&i| {
            let (j, key) = (&jobs[i], &keys[i]);
            if let Some(o) = cache.load::<JobOut>(key) {
                return Ok(o);
            }
            if lash_solver::interrupt::stop_requested() {
                return Err(Error::Interrupted(String::new()));
            }
            let clock = Instant::now();
            let o = run_job(j, plan)?;
            cache.store(key, &o)?;
            done.fetch_add(1, Ordering::Relaxed);
            let length = match j.until {
                Some(_) => format!(" until periodic ({} revolutions)", o.length.0),
                None => String::new(),
            };
            progress.finished(
                &format!(
                    "{} {:?} realisation {}{length}",
                    j.name, j.setting, j.member
                )
                .to_lowercase(),
                clock.elapsed().as_secs_f64(),
            );
            Ok(o)
        })
        .collect();
    let outs = match outs {
        Err(Error::Interrupted(_)) => {
            let kept = cached + done.load(Ordering::Relaxed);
            return Err(Error::Interrupted(format!(
                "{what}: {kept} of {} runs finished and kept in {}; rerun the same command to \
                 resume",
                unique.len(),
                cache.dir().display()
            )));
        }
        other => other?,
    };
    let by_key: BTreeMap<&str, &JobOut> = unique
        .iter()
        .map(|&i| keys[i].as_str())
        .zip(&outs)
        .collect();
    let all = keys
        .iter()
        .map(|k| {
            by_key
                .get(k.as_str())
                .map(|o| (*o).clone())
                .ok_or_else(|| Error::Internal(format!("{what}: a run went missing")))
        })
        .collect::<Result<_, _>>()?;
    Ok((all, unique.len()))
}

/// Runs every case of the study under `plan` (in parallel) and judges the claims. Figures
/// are not drawn; see [`paper`]. Returns the result and the curves of the paper's
/// realisations. Every finished run is stored in `cache` and a run found there is not done
/// again; `progress` gets one item per run done. A stop request (`lash_solver::interrupt`)
/// abandons the runs in flight and starts no other: [`Error::Interrupted`], with what is
/// kept.
fn run_plan(
    plan: &Plan,
    cache: &RunCache,
    progress: &dyn Progress,
) -> Result<(StudyResult, BTreeMap<String, Curves>), Error> {
    if plan.realisations == 0 {
        return Err(Error::Usage("study: at least one realisation".into()));
    }
    let catalogue: BTreeMap<String, Scene> =
        lash_model::cases::press_catalogue().into_iter().collect();
    let names = case_names();
    let scenes: Vec<&Scene> = names
        .iter()
        .map(|n| {
            catalogue
                .get(*n)
                .ok_or_else(|| Error::Internal(format!("study: case {n} is not in the catalogue")))
        })
        .collect::<Result<_, _>>()?;
    let mut jobs = Vec::new();
    for (i, name) in names.iter().enumerate() {
        let members = if kind_of(name) == Kind::Ideal {
            1
        } else {
            plan.realisations
        };
        // The periodicity claims are judged at steady state (claims::LUB_CLEARANCES).
        let steady = claims::LUB_CLEARANCES.contains(name);
        for setting in Setting::ALL {
            for until in std::iter::once(None).chain(steady.then_some(Some(plan.steady))) {
                for member in 0..members {
                    jobs.push(Job {
                        case: i,
                        name,
                        scene: scenes[i].clone(),
                        setting,
                        member,
                        until,
                    });
                }
            }
        }
    }
    // Longest jobs (dry, reference) first so that the threads finish together.
    jobs.sort_by_key(|j| {
        (
            kind_of(j.name) != Kind::Dry,
            j.setting != Setting::Reference,
        )
    });
    let (outs, _) = run_jobs(&jobs, plan, cache, progress, "study")?;

    let mut cases = Vec::new();
    let mut all_curves = BTreeMap::new();
    for (i, name) in names.iter().enumerate() {
        let group = |setting: Setting| {
            let mut v: Vec<(usize, &JobOut)> = jobs
                .iter()
                .zip(&outs)
                .filter(|(j, _)| j.case == i && j.setting == setting && j.until.is_none())
                .map(|(j, o)| (j.member, o))
                .collect();
            v.sort_by_key(|x| x.0);
            v
        };
        let (study, refr, loose) = (
            group(Setting::Study),
            group(Setting::Reference),
            group(Setting::Loose),
        );
        let ensemble = |v: &[(usize, &JobOut)]| Ensemble {
            members: v.iter().map(|(_, o)| o.stats.clone()).collect(),
            acc_spread: spread(&v.iter().map(|(_, o)| &o.acc).collect::<Vec<_>>()),
        };
        let nominal = study[0].1;
        let total: f64 = study
            .iter()
            .chain(&refr)
            .chain(&loose)
            .map(|(_, o)| o.solver.2)
            .sum();
        if let Some(c) = &nominal.curves {
            all_curves.insert(name.to_string(), c.clone());
        }
        let acc_tolerance_diff =
            max_abs(nominal.acc.iter().zip(&refr[0].1.acc).map(|(a, b)| a - b));
        let steady_group = |setting: Setting| {
            let mut v: Vec<(usize, &JobOut)> = jobs
                .iter()
                .zip(&outs)
                .filter(|(j, _)| j.case == i && j.setting == setting && j.until.is_some())
                .map(|(j, o)| (j.member, o))
                .collect();
            v.sort_by_key(|x| x.0);
            v
        };
        let steady_study = steady_group(Setting::Study);
        let steady = (!steady_study.is_empty()).then(|| SteadyRuns {
            until: plan.steady,
            revolutions: steady_study.iter().map(|(_, o)| o.length.0).collect(),
            settled: steady_study
                .iter()
                .map(|(_, o)| o.length.1.unwrap_or(false))
                .collect(),
            study: ensemble(&steady_study),
            reference: ensemble(&steady_group(Setting::Reference)),
            loose: ensemble(&steady_group(Setting::Loose)),
        });
        cases.push(CaseResult {
            steady,
            acc_tolerance_diff,
            name: name.to_string(),
            kind: kind_of(name),
            rpm: nominal.meta.0,
            clearance_m: nominal.meta.1,
            study: ensemble(&study),
            reference: ensemble(&refr),
            loose: ensemble(&loose),
            solver: SolverRecord {
                stats: nominal.solver.0,
                events: nominal.solver.1,
                wall_time_s: nominal.solver.2,
                total_wall_time_s: total,
            },
        });
    }
    let mut result = StudyResult {
        version: env!("CARGO_PKG_VERSION").to_string(),
        plan: *plan,
        cases,
        claims: Vec::new(),
        reference_claims: Vec::new(),
        loose_claims: Vec::new(),
        verdicts_agree: false,
        figures: Vec::new(),
        timing: Timing {
            runs_s: 0.0,
            figures_s: 0.0,
            total_s: 0.0,
            threads: rayon::current_num_threads(),
        },
    };
    result.claims = claims::evaluate(&result.ensembles(Setting::Study))?;
    result.reference_claims = claims::evaluate(&result.ensembles(Setting::Reference))?;
    result.loose_claims = claims::evaluate(&result.ensembles(Setting::Loose))?;
    result.verdicts_agree = result
        .claims
        .iter()
        .zip(&result.reference_claims)
        .all(|(a, b)| a.verdict == b.verdict);
    Ok((result, all_curves))
}

/// Runs the study with `plan` and writes `out/figures/*`, `out/report.md` and (last)
/// `out/study.json`, each atomically. Nothing is written if a run fails but the finished runs
/// in `out/cache/` ([`crate::store::cache`]), from which a rerun resumes.
pub fn run_and_write(plan: &Plan, out: &Path) -> Result<StudyResult, Error> {
    run_and_write_with(plan, out, &NoProgress)
}

/// [`run_and_write`], reporting each run to `progress`.
pub fn run_and_write_with(
    plan: &Plan,
    out: &Path,
    progress: &dyn Progress,
) -> Result<StudyResult, Error> {
    let clock = Instant::now();
    // Temporary files of a study killed while writing (a second signal, SIGKILL).
    crate::store::claim::remove_dead_temporaries(out);
    crate::store::claim::remove_dead_temporaries(&out.join(FIGURES_DIR));
    let cache = RunCache::new(&out.join(CACHE_DIR));
    let (mut result, curves) = run_plan(plan, &cache, progress)?;
    result.timing.runs_s = clock.elapsed().as_secs_f64();
    let fig_clock = Instant::now();
    io::create_dir(&out.join(FIGURES_DIR))?;
    result.figures = figures::write(&out.join(FIGURES_DIR), &curves)?;
    result.timing.figures_s = fig_clock.elapsed().as_secs_f64();
    result.timing.total_s = clock.elapsed().as_secs_f64();
    io::write_atomic(&out.join(REPORT_FILE), markdown::report(&result).as_bytes())?;
    io::write_json_atomic(&out.join(JSON_FILE), &result)?;
    Ok(result)
}

/// `lash study paper [--out DIR]`: runs the paper's §4 (see the module doc) and writes the
/// figures, the report and study.json into `out` ([`describe_paper`] says it in one line).
pub fn paper(out: &Path, progress: &dyn Progress) -> Result<StudyResult, Error> {
    run_and_write_with(&Plan::paper(), out, progress)
}

/// One line of results of the paper's study written to `out`: cases, realisations, times,
/// how many of the paper's claims hold, where the report is.
pub fn describe_paper(r: &StudyResult, out: &Path) -> String {
    let paper: Vec<&Claim> = r
        .claims
        .iter()
        .filter(|c| c.origin == Origin::Paper)
        .collect();
    let holding = paper.iter().filter(|c| c.verdict == Verdict::Holds).count();
    format!(
        "study paper: {} cases × {} realisations, runs {:.1} s, figures {:.1} s; {} of {} paper claims hold; report {}",
        r.cases.len(),
        r.plan.realisations,
        r.timing.runs_s,
        r.timing.figures_s,
        holding,
        paper.len(),
        out.join(REPORT_FILE).display()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const RPM: f64 = 150.0;

    fn ideal() -> IdealSliderCrank {
        IdealSliderCrank {
            r: 0.015,
            l: 0.35,
            omega: RPM * PI / 30.0,
            theta0: 0.0,
            offset: 0.0,
        }
    }

    /// Samples of the second revolution (or the first) built from the ideal mechanism plus
    /// the given deviations of x, ẍ and e/c, as functions of the crank angle θ.
    fn window(
        second: bool,
        dx: impl Fn(f64) -> f64,
        da: impl Fn(f64) -> f64,
        e: impl Fn(f64) -> (f64, f64),
    ) -> Vec<Sample> {
        let m = ideal();
        let period = 60.0 / RPM;
        let t_end = if second { 2.0 * period } else { period };
        metrics::grid(t_end, period)
            .into_iter()
            .map(|t| {
                let th = m.omega * t;
                let (ex, ey) = e(th);
                let eps = ex.hypot(ey);
                Sample {
                    crank_angle: Some(th),
                    slider_x: Some(m.x_at(th) + dx(th)),
                    slider_v: Some(m.v_at(th)),
                    slider_a: Some(m.a_at(th) + da(th)),
                    ex_over_c: Some(ex),
                    ey_over_c: Some(ey),
                    eps: Some(eps),
                    delta: Some(1e-4 * (eps - 1.0)),
                    ..Sample::at(t)
                }
            })
            .collect()
    }

    #[test]
    fn deviations_of_the_ideal_itself_vanish() {
        let w = window(true, |_| 0.0, |_| 0.0, |_| (0.5, 0.0));
        let d = deviations(&w, &w, &ideal()).unwrap();
        assert_eq!(
            (d.x_dev_max, d.v_dev_max, d.a_dev_max, d.x_dev_bdc),
            (0.0, 0.0, 0.0, 0.0)
        );
        assert_eq!(
            (d.x_dev_rel, d.a_dev_rel, d.fluctuation_sectors),
            (0.0, 0.0, 0)
        );
        assert_eq!(
            (d.contact_fraction, d.orbit_closure),
            (Some(0.0), Some(0.0))
        );
        // Stroke 2r: θ = 0 and π are grid points (i = 0, 1000, 2000).
        assert!((d.stroke - 0.03).abs() < 1e-15, "{}", d.stroke);
        // Ideal peak |ẍ| at θ = 0: r ω² (1 + r/l) (docs/model.md §5: 3.85972 m/s² at 150 rpm).
        assert!(
            (d.a_ideal_peak - 3.85972).abs() < 5e-6,
            "{}",
            d.a_ideal_peak
        );
    }

    #[test]
    fn deviations_measure_known_offsets() {
        let (d0, amp) = (2e-4, 0.3);
        // x off by d0 sin θ: max d0 at 90° (grid point i = 500); within ±15° of θ = 0 the largest
        // grid angle is 83 × 0.18° = 14.94°. ẍ off by amp sin 4θ: peaks amp at 22.5° + k 45°, all
        // grid points (i = 125 + 250 k), one per 45° sector.
        let last = window(
            true,
            |th| d0 * th.sin(),
            |th| amp * (4.0 * th).sin(),
            |th| {
                // In contact (ε = 1.2) for θ in (45.09°, 135.09°): grid points i = 251..=750.
                let deg = th.to_degrees().rem_euclid(360.0);
                let eps = if deg > 45.09 && deg < 135.09 {
                    1.2
                } else {
                    0.5
                };
                (eps, 0.0)
            },
        );
        let mut prev = last.clone();
        for s in prev.iter_mut() {
            s.ex_over_c = s.ex_over_c.map(|x| x + 0.03);
            s.ey_over_c = s.ey_over_c.map(|y| y - 0.04);
        }
        let d = deviations(&last, &prev, &ideal()).unwrap();
        assert!((d.x_dev_max - d0).abs() < 1e-15, "{}", d.x_dev_max); // x ≈ 0.365 m: rounding 1e-16
        let bdc = d0 * (83.0 * 0.18f64).to_radians().sin();
        assert!((d.x_dev_bdc - bdc).abs() < 1e-15, "{} {bdc}", d.x_dev_bdc);
        assert!((d.a_dev_max - amp).abs() < 1e-12);
        // 0.3 is 7.8 % of the 3.86 m/s² peak: no sector passes the 10 % mark.
        assert_eq!(d.fluctuation_sectors, 0);
        // Near θ = 0: |sin 4θ| is largest at the window's edge, 4 × 14.94°; near π likewise.
        let dc = amp * (4.0 * 83.0 * 0.18f64).to_radians().sin();
        assert!(
            (d.a_dev_dead_centres - dc).abs() < 1e-12,
            "{}",
            d.a_dev_dead_centres
        );
        assert_eq!(d.contact_fraction, Some(500.0 / 2001.0));
        assert!((d.orbit_closure.unwrap() - 0.05).abs() < 1e-15);
        // RMS of d0 sin θ over the 2001 points is d0 sqrt(1000/2001); the ideal x about its mean
        // is about r/√2 (plus the small l-term): the ratio is checked against its definition.
        let xi: Vec<f64> = last
            .iter()
            .map(|s| ideal().x_at(s.crank_angle.unwrap()))
            .collect();
        let mean = xi.iter().sum::<f64>() / 2001.0;
        let den = (xi.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 2001.0).sqrt();
        let rel = d0 * (1000.0f64 / 2001.0).sqrt() / den;
        assert!(
            (d.x_dev_rel - rel).abs() < 1e-12 * rel,
            "{} {rel}",
            d.x_dev_rel
        );
        // With amp above 10 % of the peak every sector fluctuates.
        let big = window(true, |_| 0.0, |th| 0.5 * (4.0 * th).sin(), |_| (0.5, 0.0));
        assert_eq!(
            deviations(&big, &big, &ideal())
                .unwrap()
                .fluctuation_sectors,
            8
        );
    }

    #[test]
    fn deviations_refuse_mismatched_or_missing_samples() {
        let w = window(true, |_| 0.0, |_| 0.0, |_| (0.5, 0.0));
        assert!(deviations(&w, &w[1..], &ideal()).is_err());
        let mut bad = w.clone();
        bad[3].slider_v = None;
        let e = deviations(&bad, &w, &ideal()).unwrap_err();
        assert!(e.to_string().contains("slider_v missing"), "{e}");
        // No clearance joint: no contact fraction, no orbit.
        let bare: Vec<Sample> = w
            .iter()
            .map(|s| Sample {
                ex_over_c: None,
                ey_over_c: None,
                delta: None,
                eps: None,
                ..s.clone()
            })
            .collect();
        let d = deviations(&bare, &bare, &ideal()).unwrap();
        assert_eq!((d.contact_fraction, d.orbit_closure), (None, None));
    }

    #[test]
    fn spread_is_the_largest_pointwise_range() {
        let (a, b, c) = (
            vec![1.0, 2.0, 3.0],
            vec![1.5, 0.0, 3.0],
            vec![1.2, 2.5, 3.1],
        );
        assert_eq!(spread(&[&a, &b, &c]), 2.5);
        assert_eq!(spread(&[&a]), 0.0);
    }

    #[test]
    fn realisations_move_only_the_crank_phase() {
        let cat: BTreeMap<String, Scene> =
            lash_model::cases::press_catalogue().into_iter().collect();
        let s = &cat["dry_150rpm_c0.1"];
        let r = realisation(s, 3, 1e-6);
        let theta0 = |s: &Scene| {
            s.joints
                .iter()
                .find_map(|j| match j {
                    JointSpec::Driver(d) => Some(d.theta0),
                    _ => None,
                })
                .unwrap()
        };
        assert_eq!(theta0(&r), theta0(s) + 3e-6);
        let mut back = r.clone();
        for j in back.joints.iter_mut() {
            if let JointSpec::Driver(d) = j {
                d.theta0 = theta0(s);
            }
        }
        assert_eq!(&back, s);
        assert_eq!(&realisation(s, 0, 1e-6), s);
    }

    #[test]
    fn ideal_run_reproduces_the_closed_form() {
        // docs/model.md §5: ẍ(θ = 0) = −r ω² (1 + r/l) = −3.85972 m/s² at 150 rpm; the last grid
        // point is θ = 4π. The run's RMS deviation from the closed form is the integration
        // error, far below the 1e-6 relative that M1 asks for.
        let cat: BTreeMap<String, Scene> =
            lash_model::cases::press_catalogue().into_iter().collect();
        let r = run_case(
            "ideal_150rpm",
            &cat["ideal_150rpm"],
            &Plan::paper().settings,
            None,
        )
        .unwrap();
        assert_eq!((r.last.len(), r.previous.len()), (2001, 2001));
        assert_eq!(r.last[0].t, r.previous[2000].t);
        let m = &r.metrics;
        assert!((m.slider_acc_min.unwrap() + 3.85972).abs() < 5e-6, "{m:?}");
        assert!(m.slider_acc_rms_dev_ideal.unwrap() < 1e-6 * 3.86, "{m:?}");
        assert_eq!((m.eps_max, m.contact_onsets), (None, None));
        let d = deviations(&r.last, &r.previous, r.ideal.as_ref().unwrap()).unwrap();
        assert!((d.stroke - 0.03).abs() < 1e-9, "{}", d.stroke);
    }

    #[test]
    fn a_failing_study_writes_nothing() {
        let d = tempfile::tempdir().unwrap();
        let out = d.path().join("study");
        let mut plan = Plan::paper();
        plan.settings.rtol = 0.0; // refused by the solver's option check
        plan.realisations = 1;
        let e = run_and_write(&plan, &out).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::Solver, "{e}");
        // Only the cache of the runs that finished (at the other settings) may be there.
        for f in [JSON_FILE, REPORT_FILE, FIGURES_DIR] {
            assert!(!out.join(f).exists(), "{f}");
        }
        if out.exists() {
            let names: Vec<_> = std::fs::read_dir(&out)
                .unwrap()
                .map(|e| e.unwrap().file_name())
                .collect();
            assert_eq!(names, [CACHE_DIR]);
        }
        let out = d.path().join("study2");
        plan = Plan::paper();
        plan.realisations = 0;
        assert_eq!(
            run_and_write(&plan, &out).unwrap_err().kind(),
            crate::ErrorKind::BadInput
        );
        assert!(!out.exists());
    }

    #[test]
    fn the_study_has_the_papers_eighteen_cases() {
        let names = case_names();
        assert_eq!(names.len(), 18);
        let cat: BTreeMap<String, Scene> =
            lash_model::cases::press_catalogue().into_iter().collect();
        for n in &names {
            assert!(cat.contains_key(*n), "{n}");
        }
        let mut sorted = names.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), 18);
        assert_eq!(figure_count(), 44);
    }
}
