//! Steady state of a press: run until the once-per-revolution section of the clearance joint
//! stops moving (`lash run --until-periodic TOL`, and the study's periodicity claims).
//!
//! ```text
//! section     s_k = e(t_k)/c of the clearance-joint role,  k = 0, 1, 2, …;  t_k = t₀ + kT for a
//!             driven crank (T its period), the time of the crank's k-th turn for a crank that
//!             is not driven (a motor turns it: crate::run::turns)
//! change      d_k = |s_k − s_{k−1}|   (in units of the clearance c)
//! settled     at the first K ≥ MIN_REVOLUTIONS with d_K < TOL;  K ≤ max_revolutions
//! otherwise   K = max_revolutions, settled = false (a chaotic dry joint never settles)
//! the run     then integrates t₀ … t_K as any run (its metrics: revolution K)
//! ```
//!
//! The settling pass and the run are two integrations with the same options from the same
//! initial state: a run until periodic costs about twice a run of K revolutions. The settling
//! pass keeps nothing but the sections.
//!
//! Why: the lubricated journal starts centred (docs/model.md §6) and sinks into the film over
//! many revolutions; an orbit judged after two revolutions has not settled (BENCHMARKS.md, "The
//! paper's claims under model uncertainty").
//!
//! Source: docs/outputs.md (`until_periodic` of summary.json); docs/model.md §9.

use lash_model::Mechanism;
use lash_solver::{Problem, SolverOptions, StepOutcome};

use crate::error::{Error, OptionError};
use crate::report::summary::Settled;
use crate::run::prepare::scene_error;
use crate::run::prepare::{Model, Prepared};
use crate::run::sample::Sampler;
use crate::run::turns::Turns;

/// Fewest revolutions of a run until periodic: the metrics need a last revolution and the
/// periodicity check a revolution before it.
pub const MIN_REVOLUTIONS: usize = 2;

/// Default cap on the revolutions of a run until periodic.
pub const DEFAULT_MAX_REVOLUTIONS: usize = 100;

/// What to run until: the section's change per revolution below `tol`·c, within
/// `max_revolutions`.
///
/// ```text
/// tol > 0 (units of c);  MIN_REVOLUTIONS ≤ max_revolutions
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct UntilPeriodic {
    /// Largest change of the section between consecutive revolutions, in units of c.
    pub tol: f64,
    /// Cap on the revolutions.
    pub max_revolutions: usize,
}

impl UntilPeriodic {
    /// `tol` with the default cap.
    #[cfg(test)]
    pub(crate) fn new(tol: f64) -> UntilPeriodic {
        UntilPeriodic {
            tol,
            max_revolutions: DEFAULT_MAX_REVOLUTIONS,
        }
    }

    /// Option errors (`until_periodic`, `max_revolutions`): tol not finite and > 0, a cap below
    /// [`MIN_REVOLUTIONS`].
    pub(crate) fn validate(&self) -> Result<(), Error> {
        if !(self.tol.is_finite() && self.tol > 0.0) {
            return Err(OptionError::leading(
                "until_periodic",
                format!(
                    " must be a finite number > 0 (units of the clearance), got {}",
                    self.tol
                ),
            )
            .into());
        }
        if self.max_revolutions < MIN_REVOLUTIONS {
            return Err(OptionError::leading(
                "max_revolutions",
                format!(
                    " must be at least {MIN_REVOLUTIONS}, got {}",
                    self.max_revolutions
                ),
            )
            .into());
        }
        Ok(())
    }
}

/// The settling pass (module doc): integrates `p` with `opts` revolution by revolution from
/// its start until the section settles or the cap. Errors: a case without a crank or a
/// clearance joint ([`Error::Option`] on `until_periodic`), a bad request, solver failures.
pub(crate) fn settle(
    p: &Prepared,
    opts: &SolverOptions,
    until: &UntilPeriodic,
) -> Result<Settled, Error> {
    settle_until(p, opts, until).map(|(s, _)| s)
}

/// Where a section is taken: every period of a driven crank, or every turn of a crank that
/// is not driven (crate::run::turns).
enum Clock {
    Period(f64),
    Turns(Turns),
}

/// [`settle`] and the end time of the run it decides: t_0 + K T for a driven crank, the K-th
/// turn's time t_K for a crank that is not driven.
pub(crate) fn settle_until(
    p: &Prepared,
    opts: &SolverOptions,
    until: &UntilPeriodic,
) -> Result<(Settled, f64), Error> {
    until.validate()?;
    let (info, scene) = match (&p.info, &p.model) {
        (Some(i), Model::Mechanism(s)) => (i, s),
        _ => {
            return Err(OptionError::leading(
                "until_periodic",
                format!(
                    " needs a scene with a crank and a clearance joint; {} is a test problem",
                    p.case.name
                ),
            )
            .into())
        }
    };
    if info.period.is_none() && !info.has_crank {
        return Err(OptionError::leading(
            "until_periodic",
            format!(
                " needs a crank (roles.crank or roles.crank_driver: the section is taken once                  per revolution), and {} has none",
                p.case.name
            ),
        )
        .into());
    }
    if info.joint.is_none() {
        return Err(OptionError::leading(
            "until_periodic",
            format!(
                " needs a clearance joint (its section decides the steady state), and {} has \
                 none",
                p.case.name
            ),
        )
        .into());
    }
    let mech = Mechanism::from_scene(scene).map_err(|e| scene_error(&p.case, e))?;
    let sampler = Sampler::new(&mech, scene);
    let section = |t: f64, y: &[f64]| -> Result<[f64; 2], Error> {
        let s = sampler.sample(t, y);
        match (s.ex_over_c, s.ey_over_c) {
            (Some(x), Some(y)) if x.is_finite() && y.is_finite() => Ok([x, y]),
            _ => Err(Error::Internal(format!(
                "until periodic: no finite e/c of the clearance joint at t = {t:e}"
            ))),
        }
    };
    let t0 = info.t_start;
    let y0 = mech.initial_state();
    let mut clock = match info.period {
        Some(t) => Clock::Period(t),
        None => Clock::Turns(Turns::new(&mech, t0, &y0).ok_or_else(|| {
            Error::Internal(format!("until periodic: no crank angle in {}", p.case.name))
        })?),
    };
    let t_cap = match &clock {
        Clock::Period(t) => t0 + t * until.max_revolutions as f64,
        Clock::Turns(tr) => tr
            .horizon(t0, until.max_revolutions)
            .ok_or_else(|| Turns::at_rest("until_periodic", &p.case.name))?,
    };
    let problem = Problem::new(&mech, opts)?;
    let mut it = problem.integrator(t0, t_cap, &y0)?;
    let mut prev = section(t0, &y0)?;
    let mut changes = Vec::new();
    let mut buf = vec![0.0; y0.len()];
    let mut probe = vec![0.0; y0.len()];
    let mut k = 1usize;
    let mut t_last = t0;
    loop {
        let outcome = it.step()?;
        let tb = it.t();
        let mut from = it.t_prev();
        // Every section the step covers (h_max may exceed T when the scene sets none).
        while k <= until.max_revolutions {
            let tk = match &mut clock {
                Clock::Period(period) => {
                    let tk = if k == until.max_revolutions {
                        t_cap
                    } else {
                        t0 + *period * k as f64
                    };
                    if tk > tb {
                        break;
                    }
                    tk
                }
                Clock::Turns(tr) => {
                    let mut phi = |t: f64| {
                        it.interpolate(t, &mut probe);
                        mech.outputs(t, &probe).crank_angle.unwrap_or(f64::NAN)
                    };
                    match tr.crossing(k, from, tb, &mut phi) {
                        Some(t) => t,
                        None => break,
                    }
                }
            };
            from = tk;
            t_last = tk;
            it.interpolate(tk, &mut buf);
            let s = section(tk, &buf)?;
            let d = (s[0] - prev[0]).hypot(s[1] - prev[1]);
            changes.push(d);
            prev = s;
            if k >= MIN_REVOLUTIONS && d < until.tol {
                let settled = Settled {
                    tol: until.tol,
                    max_revolutions: until.max_revolutions,
                    revolutions: k,
                    settled: true,
                    section_changes: changes,
                };
                return Ok((settled, tk));
            }
            k += 1;
        }
        if k > until.max_revolutions
            || matches!(outcome, StepOutcome::StopTime { .. })
            || it.is_finished()
        {
            break;
        }
    }
    if changes.len() < MIN_REVOLUTIONS {
        return Err(Error::Input(format!(
            "until periodic: the crank of {} turned {} times before t = {} s ({} times its \
             starting speed's {} turns): too slow for a section",
            p.case.name,
            changes.len(),
            t_cap,
            crate::run::turns::HORIZON_FACTOR,
            until.max_revolutions
        )));
    }
    let settled = Settled {
        tol: until.tol,
        max_revolutions: until.max_revolutions,
        revolutions: changes.len(),
        settled: false,
        section_changes: changes,
    };
    Ok((settled, t_last))
}
