//! Running the study: one case (or one realisation) through the shared runner, the jobs of a
//! plan in parallel with the cache of finished runs, the result and its files.
//!
//! Source: the module doc of `studies::paper`.

use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use lash_model::scene::JointSpec;
use lash_model::{IdealSliderCrank, Scene};
use lash_solver::{SolverOptions, Stats};
use rayon::prelude::*;

use crate::error::Error;
use crate::progress::Progress;
use crate::report::metrics::{self, Metrics, Sample};
use crate::run::case::Case;
use crate::run::mechanism::paper_scene;
use crate::run::plan::RunRequest;
use crate::run::prepare::Prepared;
use crate::run::press::Kind;
use crate::run::press::PressCase;
use crate::run::simulate::simulate;
use crate::run::steady::UntilPeriodic;
use crate::store::cache::{RunCache, CACHE_DIR};
use crate::store::io;
use crate::studies::paper::claims;
use crate::studies::paper::figures;
use crate::studies::paper::markdown;
use crate::studies::paper::plan::Plan;
use crate::studies::paper::plan::Setting;
use crate::studies::paper::plan::Settings;
use crate::studies::paper::plan::{study_cases, LUB_CLEARANCES};
use crate::studies::paper::result::CaseResult;
use crate::studies::paper::result::SolverRecord;
use crate::studies::paper::result::SteadyRuns;
use crate::studies::paper::result::StudyResult;
use crate::studies::paper::result::Timing;
use crate::studies::paper::result::FIGURES_DIR;
use crate::studies::paper::result::JSON_FILE;
use crate::studies::paper::result::REPORT_FILE;
use crate::studies::paper::stats::curves;
use crate::studies::paper::stats::deviations;
use crate::studies::paper::stats::max_abs;
use crate::studies::paper::stats::need;
use crate::studies::paper::stats::CaseStats;
use crate::studies::paper::stats::Curves;
use crate::studies::paper::stats::Ensemble;

// ---------------------------------------------------------------------------------------------
// Running one case: through the shared runner, `simulate::simulate`, with the study's own solver
// options, the metrics grid of the last revolution (RunResult::window) and that of the
// revolution before it as extra output times; no trajectory, no energy accounting.
// ---------------------------------------------------------------------------------------------

/// One finished run: the samples of the last two revolutions and what the solver did.
#[derive(Clone, Debug)]
pub(crate) struct Run {
    /// Samples on `metrics::grid(t_end − T, T)` (the revolution before the last).
    pub(crate) previous: Vec<Sample>,
    /// Samples on `metrics::grid(t_end, T)` (the last revolution).
    pub(crate) last: Vec<Sample>,
    pub(crate) metrics: Metrics,
    pub(crate) stats: Stats,
    pub(crate) wall_time_s: f64,
    pub(crate) events: usize,
    pub(crate) ideal: Option<IdealSliderCrank>,
    /// |ω| of the crank driver, rpm.
    pub(crate) rpm: f64,
    /// Radial clearance of the clearance-joint role, m.
    pub(crate) clearance: Option<f64>,
    /// Revolutions run.
    pub(crate) revolutions: usize,
    /// Whether the orbit settled (runs until periodic).
    pub(crate) settled: Option<bool>,
}

/// Runs the press scene `scene` (of the press case `case`, or one of its realisations) over
/// its span through [`simulate`], or with `until` until its orbit settles
/// ([`crate::run::steady`]); samples its last two revolutions.
pub(crate) fn run_case(
    case: PressCase,
    scene: &Scene,
    settings: &Settings,
    until: Option<&UntilPeriodic>,
) -> Result<Run, Error> {
    let name = case;
    // The paper's method stays the paper's (docs/model.md §12): `auto` runs Lagrange–Baumgarte,
    // and without kink events unless the scene asks for them (docs/model.md §7: the study's
    // BDF takes no exact event steps, so a restart at a kink buys it no order).
    let p = Prepared::with_scene(Case::press(case), paper_scene(scene))?;
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

/// The scene of realisation `k`: the crank driver's initial angle θ₀ moved by k·Δθ.
pub(crate) fn realisation(scene: &Scene, k: usize, step_rad: f64) -> Scene {
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

pub(crate) struct Job {
    pub(crate) case: usize,
    /// The press case.
    pub(crate) press: PressCase,
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

fn run_job(job: &Job, plan: &Plan) -> Result<JobOut, Error> {
    let settings = plan.get(job.setting);
    let scene = realisation(&job.scene, job.member, plan.phase_step_rad);
    let r = run_case(job.press, &scene, &settings, job.until.as_ref())?;
    let ideal = r.ideal.ok_or_else(|| {
        Error::Input(format!(
            "case {}: not an in-line slider-crank with slider and crank_driver roles",
            job.press
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

/// The inputs a job's result depends on (its cache key, with the build: [`crate::store::cache`]).
#[derive(serde::Serialize)]
struct JobKey<'a> {
    case: String,
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
    jobs: &[Job],
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
                    case: j.press.to_string(),
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
                    j.press, j.setting, j.member
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
/// are not drawn; see [`run_and_write_with`]. Returns the result and the curves of the paper's
/// realisations. Every finished run is stored in `cache` and a run found there is not done
/// again; `progress` gets one item per run done. A stop request (`lash_solver::interrupt`)
/// abandons the runs in flight and starts no other: [`Error::Interrupted`], with what is
/// kept.
fn run_plan(
    plan: &Plan,
    cache: &RunCache,
    progress: &dyn Progress,
) -> Result<(StudyResult, BTreeMap<PressCase, Curves>), Error> {
    if plan.realisations == 0 {
        return Err(Error::Usage("study: at least one realisation".into()));
    }
    let names = study_cases();
    let mut jobs = Vec::new();
    for (i, &name) in names.iter().enumerate() {
        let scene = name.scene();
        let members = if name.kind() == Kind::Ideal {
            1
        } else {
            plan.realisations
        };
        // The periodicity claims are judged at steady state (plan::LUB_CLEARANCES).
        let steady = LUB_CLEARANCES.contains(&name);
        for setting in Setting::ALL {
            for until in std::iter::once(None).chain(steady.then_some(Some(plan.steady))) {
                for member in 0..members {
                    jobs.push(Job {
                        case: i,
                        press: name,
                        scene: scene.clone(),
                        setting,
                        member,
                        until,
                    });
                }
            }
        }
    }
    // Longest jobs (dry, reference) first so that the threads finish together.
    jobs.sort_by_key(|j| (j.press.kind() != Kind::Dry, j.setting != Setting::Reference));
    let (outs, _) = run_jobs(&jobs, plan, cache, progress, "study")?;

    let mut cases = Vec::new();
    let mut all_curves = BTreeMap::new();
    for (i, &name) in names.iter().enumerate() {
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
            all_curves.insert(name, c.clone());
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
            kind: name.kind(),
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
    result.claims = claims::evaluate(&result.ensembles(Setting::Study)?)?;
    result.reference_claims = claims::evaluate(&result.ensembles(Setting::Reference)?)?;
    result.loose_claims = claims::evaluate(&result.ensembles(Setting::Loose)?)?;
    result.verdicts_agree = result
        .claims
        .iter()
        .zip(&result.reference_claims)
        .all(|(a, b)| a.verdict == b.verdict);
    Ok((result, all_curves))
}

/// [`run_and_write`], reporting each run to `progress`.
pub(crate) fn run_and_write_with(
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
