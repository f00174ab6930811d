//! Exact event steps (`SolverOptions::exact_event_steps`, one-step methods;
//! [`Stepper::retake`]): the state at an event is not read off the dense output of the step
//! [t_a, t_b] that contains it: that step is taken again from t_a with h = t* − t_a, and y* is
//! its end.
//!
//! The event time itself was located on the dense output of the step across the event and
//! is corrected by Newton's method along retaken steps ([`Integrator::refine_retaken`]).
//!
//! When the system gives the rates ġ, the step after an accepted step is also limited to end
//! just past the predicted crossing of an event function that approaches zero
//! ([`Integrator::crossing_limit`]), so that the step across an event holds little of the
//! motion beyond it: it passes its error test at the first attempt more often, and the
//! retaken step is nearly the step itself.

use super::{Integrator, OdeSystem, SolveError};
#[cfg(doc)]
use crate::stepper::Stepper;

impl<S: OdeSystem + ?Sized> Integrator<'_, S> {
    /// Exact event steps (module documentation): after the step was retaken to end at the
    /// located time `t_ev`, Newton's method on g_i along the retaken steps' ends. The time was
    /// located on the dense output of the step across the event, which is only as accurate
    /// as that step's smoothness allows; g_i at the retaken end is accurate, and its rate is
    /// read off the retaken step's dense output:
    ///
    /// ```text
    /// ġ ≈ (g_i(t) − g_i(u(t − η))) / η,  η = 10⁻³ (t − t_a),  u the retaken dense output
    /// t ← t − g_i(t)/ġ,  the step retaken to end there
    /// ```
    /// at most [`NEWTON_RETAKES`] times, while the correction is more than 8 ulps of t, at
    /// most half the retaken step (a g_i that jumps at the event, or a rate of the wrong
    /// sign, leaves t as located) and, with error control, moves the state by more than the
    /// tolerance ([`Integrator::shift_within_tolerance`]). Returns the event time.
    pub(super) fn refine_retaken(&mut self, mut t_ev: f64, i: usize) -> Result<f64, SolveError> {
        let mut g = vec![0.0; self.specs.len()];
        for _ in 0..NEWTON_RETAKES {
            let t_a = self.stepper.t_prev();
            self.sys.events(t_ev, self.stepper.y(), &mut g);
            self.event_evals += 1;
            let g_end = g[i];
            let eta = 1e-3 * (t_ev - t_a);
            self.eval_g_dense(t_ev - eta, &mut g)?;
            let rate = (g_end - g[i]) / eta;
            let dt = -g_end / rate;
            if !dt.is_finite()
                || dt.abs() <= 8.0 * f64::EPSILON * t_ev.abs()
                || dt.abs() > 0.5 * (t_ev - t_a)
                || (self.opts.adaptive && self.shift_within_tolerance(dt, eta))
            {
                break;
            }
            if !self.stepper.retake(t_ev + dt)? {
                break;
            }
            t_ev = self.stepper.t();
        }
        Ok(t_ev)
    }
}

impl<S: OdeSystem + ?Sized> Integrator<'_, S> {
    /// Whether moving the end of the retaken step by `dt` moves its state by at most the
    /// error tolerance: ‖ẏ dt‖ ≤ 1 in the error norm of the steps (weights
    /// atol_i + rtol |y_i|), ẏ ≈ (y − u(t − η))/η from the retaken dense output u, which
    /// [`Integrator::refine_retaken`] has just left in `ybuf`. Such a correction changes
    /// nothing at the accuracy asked for and is not worth a step.
    fn shift_within_tolerance(&self, dt: f64, eta: f64) -> bool {
        let y = self.stepper.y();
        let n = y.len();
        let (rtol, atol) = (self.opts.rtol, &self.opts.atol);
        let s: f64 = (0..n)
            .map(|k| {
                let sc = atol.get(k) + rtol * y[k].abs();
                ((y[k] - self.ybuf[k]) / eta * dt / sc).powi(2)
            })
            .sum();
        (s / n.max(1) as f64).sqrt() <= 1.0
    }
}

impl<S: OdeSystem + ?Sized> Integrator<'_, S> {
    /// Whether the predicted-crossing limit is on: exact event steps, with error control,
    /// and the rates ġ given.
    pub(super) fn crossing_limit_on(&self) -> bool {
        self.opts.exact_event_steps && self.opts.adaptive && self.rates
    }

    /// The step limit after an accepted step of length `h` that located no event, from the
    /// limit `limit` otherwise in force (h_max, or the contact-aware one):
    ///
    /// ```text
    /// τ_i = −g_i / ġ_i   for every g_i approaching zero (g_i ġ_i < 0), at the step's end
    /// c_i = (1 + η) τ_i,  η = CROSSING_MARGIN = 0.02
    /// limit ← min(limit, min over i with c_i ≥ h/4 of c_i)
    /// ```
    /// The next step then ends 2 % past the linear prediction of the nearest crossing, so
    /// the kink or contact change it holds lies in its last few per cent. A crossing
    /// predicted within a quarter of the last step is not used (the motion is already at
    /// the crossing, or g_i creeps towards zero without reaching it, and repeated cuts would
    /// shrink the steps geometrically), nor is a limit applied twice in a row without an
    /// event between (the step it limited has just ended before the predicted crossing: the
    /// prediction was early, and the next one is as uncertain). The limit only shortens
    /// steps, so it keeps every argument of "why events are never missed".
    pub(super) fn crossing_limit(&mut self, limit: f64, h: f64) -> f64 {
        let mut cap = limit;
        if !self.crossing_limited {
            for i in 0..self.specs.len() {
                let (g, gd) = (self.g_b[i], self.gd_b[i]);
                if g * gd < 0.0 {
                    let c = (1.0 + CROSSING_MARGIN) * (-g / gd);
                    if c >= 0.25 * h {
                        cap = cap.min(c);
                    }
                }
            }
        }
        self.crossing_limited = cap < limit;
        cap
    }
}

/// η of the predicted-crossing limit ([`Integrator::crossing_limit`]): the limited step
/// ends this fraction past the predicted crossing.
const CROSSING_MARGIN: f64 = 0.02;

/// The most Newton corrections of an event time by retaken steps
/// ([`Integrator::refine_retaken`]).
const NEWTON_RETAKES: usize = 2;
