//! The integration loop every run goes through: one accepted step at a time, outputs at the
//! requested times from the dense output, and the observer of the run told of every step
//! and event.
//!
//! ```text
//! the integration loop (Integrator, one accepted step at a time):
//!   wall time     = time spent in Problem::new, Problem::integrator and Integrator::step only (no output, no
//!                   energy quadrature, no I/O)
//!   outputs       = dense output at every requested time (the trajectory grid, the metrics
//!                   grid, the extra times, merged in time order and computed one at a time);
//!                   mechanism samples are evaluated at once (so a contact law's stored impact
//!                   velocity is the one in force)
//!   extrema       every accepted step in the metrics window: metrics::Peaks on its dense
//!                   output (5 samples, golden-section search where a maximum appears)
//!   energy        ∫ P dt of Mechanism::power over every accepted step: integrated by the
//!                   method itself when the power terms are the system's quadrature
//!                   (Integrator::step_quadrature, crate::run::quadrature), with the
//!                   method's error estimate; else (a step cut at an event, a non-finite
//!                   stage power) Boole's rule on five equally spaced nodes of the dense
//!                   output, error estimate |S₂ − S₁|/15 (S₁, S₂ Simpson on one and two
//!                   panels), panels no longer than T/400
//!   balance       W_driver − ΔT − ΔV − D_damping − D_friction − D_film
//!   events        located hits; a run without event location (the paper's RK4) counts the
//!                   sign changes of the event functions between consecutive step ends
//!                   (crossing time by linear interpolation), so contact onsets are still counted
//! ```
//!
//! Source: ARCHITECTURE.md ("Invariants": steppers never see events; one step loop).

use std::time::{Duration, Instant};

use lash_solver::{
    EventHit, OdeSystem, Problem, Solution, SolverOptions, Stats, StepOutcome, StepQuadrature,
};

use crate::error::Error;
use crate::report::summary::Summary;
use crate::run::prepare::Prepared;
use crate::run::quadrature::{Own, Powers, TERMS};

/// Receives what a run produces, as `drive` integrates (module doc).
pub(crate) trait Observer {
    /// The next requested output time (sorted), if any.
    fn next_time(&self) -> Option<f64>;
    /// The state at the next requested output time.
    fn output(&mut self, t: f64, y: &[f64]) -> Result<(), Error>;
    /// An accepted step [ta, tb] (`cut`: ended at an event); `dense(t, out)` is its dense
    /// output; `y` the state at tb (after the event hook); `own` the method's integrals of
    /// the power terms over it when the system has them as its quadrature.
    fn step(
        &mut self,
        ta: f64,
        tb: f64,
        cut: bool,
        y: &[f64],
        own: Option<Own>,
        dense: &dyn Fn(f64, &mut [f64]),
    ) -> Result<(), Error>;
    /// An event (located, or a crossing between step ends).
    fn event(&mut self, hit: EventHit);
}

/// What the integration loop produced.
pub(crate) struct Drive {
    pub(crate) stats: Stats,
    pub(crate) wall: f64,
    pub(crate) t_final: f64,
    pub(crate) y_final: Vec<f64>,
    pub(crate) located: usize,
}

impl Drive {
    /// summary.json of the run, without metrics or test-problem fields.
    pub(crate) fn summary(&self, p: &Prepared, opts: &SolverOptions, t_end: f64) -> Summary {
        Summary::new(&p.case, opts, t_end, self.stats, self.wall, self.located)
    }
}

/// Integrates from t0 to t_end, handing the observer every requested output time (as soon as
/// the dense output covers it), every accepted step and every event.
pub(crate) fn drive<S: OdeSystem + ?Sized>(
    sys: &S,
    t0: f64,
    t_end: f64,
    y0: &[f64],
    opts: &SolverOptions,
    obs: &mut dyn Observer,
) -> Result<Drive, Error> {
    let n = y0.len();
    let mut wall = Duration::ZERO;
    let clock = Instant::now();
    let problem = Problem::new(sys, opts)?;
    let mut it = problem.integrator(t0, t_end, y0)?;
    wall += clock.elapsed();
    while let Some(t) = obs.next_time().filter(|t| *t <= t0) {
        obs.output(t, y0)?;
    }
    let m = sys.n_events();
    let detect = !opts.events && m > 0;
    let mut g_prev = vec![0.0; if detect { m } else { 0 }];
    let mut g_now = g_prev.clone();
    let mut t_g = t0;
    if detect {
        sys.events(t0, y0, &mut g_prev);
    }
    let mut located = 0;
    let mut buf = vec![0.0; n];
    let quad = sys.n_quadratures() == TERMS;
    let (mut value, mut estimate) = ([0.0; TERMS], [0.0; TERMS]);
    loop {
        let clock = Instant::now();
        let outcome = it.step()?;
        wall += clock.elapsed();
        let (ta, tb) = (it.t_prev(), it.t());
        while let Some(t) = obs.next_time().filter(|t| *t <= tb) {
            it.interpolate(t, &mut buf);
            obs.output(t, &buf)?;
        }
        let cut = matches!(outcome, StepOutcome::Event { .. });
        let own = if quad {
            own_integrals(
                it.step_quadrature(&mut value, &mut estimate),
                value,
                estimate,
            )
        } else {
            None
        };
        obs.step(ta, tb, cut, it.y(), own, &|t, out| it.interpolate(t, out))?;
        if detect {
            sys.events(tb, it.y(), &mut g_now);
            for i in 0..m {
                let (a, b) = (g_prev[i], g_now[i]);
                if (a < 0.0 && b > 0.0) || (a > 0.0 && b < 0.0) {
                    obs.event(EventHit {
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
                located += h.len();
                for hit in h {
                    obs.event(hit);
                }
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
    while let Some(t) = obs.next_time() {
        obs.output(t, it.y())?;
    }
    Ok(Drive {
        stats: it.stats(),
        wall: wall.as_secs_f64(),
        t_final: it.t(),
        y_final: it.y().to_vec(),
        located,
    })
}

/// The method's integrals of one step as [`Own`], None when it gave none or one is not
/// finite (a stage beyond the model's range: the dense output's quadrature then finds it).
fn own_integrals(got: StepQuadrature, value: Powers, estimate: Powers) -> Option<Own> {
    let finite = |v: &Powers| v.iter().all(|x| x.is_finite());
    match got {
        StepQuadrature::Unavailable => None,
        StepQuadrature::Value => finite(&value).then_some(Own {
            value,
            estimate: None,
        }),
        StepQuadrature::ValueAndEstimate => (finite(&value) && finite(&estimate)).then_some(Own {
            value,
            estimate: Some(estimate),
        }),
    }
}

pub(crate) fn checked_power(pw: PowerFn<'_>, t: f64, y: &[f64]) -> Result<Powers, Error> {
    finite_powers(pw(t, y), t)
}

/// The power terms `v` at t, or the error of a non-finite one.
pub(crate) fn finite_powers(v: Powers, t: f64) -> Result<Powers, Error> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(v)
    } else {
        Err(Error::Internal(format!(
            "energy: power terms {v:?} not finite at t = {t:e}"
        )))
    }
}

pub(crate) type PowerFn<'a> = &'a dyn Fn(f64, &[f64]) -> Powers;

pub(crate) fn empty_solution(dim: usize) -> Solution {
    Solution {
        dim,
        ..Default::default()
    }
}
