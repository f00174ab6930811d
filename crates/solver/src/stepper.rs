//! The one-step interface every method implements, and the factory that builds a stepper for
//! a [`Method`].
//!
//! A stepper owns the state (t, y) and the dense output of its last accepted step. It never
//! sees events or output requests: the [`crate::Integrator`] drives it, locates events on its
//! dense output, and restarts it at event states.

use crate::error::SolveError;
use crate::options::{Method, SolverOptions};
use crate::stats::Stats;
use crate::system::OdeSystem;

/// One integration method in motion.
pub trait Stepper {
    /// The method.
    fn method(&self) -> Method;
    /// Time of the current state (the end of the last accepted step).
    fn t(&self) -> f64;
    /// Current state.
    fn y(&self) -> &[f64];
    /// Start of the last accepted step (equals `t()` right after construction or a restart).
    fn t_prev(&self) -> f64;
    /// Takes one accepted step (retrying rejected attempts inside), never past `t_stop`; a step
    /// that would end within a few ulps of `t_stop` ends exactly on it. Fails with a typed
    /// error when the step size underflows, `max_steps` attempts are used, the Newton iteration
    /// cannot converge, or the state becomes non-finite.
    fn step(&mut self, t_stop: f64) -> Result<(), SolveError>;
    /// Dense output: writes y(t) for t in [t_prev, t] into `out`.
    fn interpolate(&self, t: f64, out: &mut [f64]);
    /// Restarts from (t, y), discarding all history (FSAL stage, controller history, multistep
    /// history and order). The next trial step is min(last accepted step, h_max) when a step
    /// was accepted before, the starting-step estimate otherwise.
    fn restart(&mut self, t: f64, y: &[f64]) -> Result<(), SolveError>;
    /// Counters so far.
    fn stats(&self) -> &Stats;
    /// Mutable counters (the integrator adds event counters).
    fn stats_mut(&mut self) -> &mut Stats;
}

/// Builds the stepper of `opts.method` at (t0, y0). Options must already be validated.
pub fn make_stepper<'a, S: OdeSystem + ?Sized>(
    sys: &'a S,
    t0: f64,
    y0: &[f64],
    opts: &SolverOptions,
) -> Result<Box<dyn Stepper + 'a>, SolveError> {
    match opts.method {
        Method::Rk4 => Ok(Box::new(crate::rk4::Rk4::new(sys, t0, y0, opts)?)),
        Method::Bs32 | Method::Dopri54 | Method::Tsit54 | Method::Dop853 => {
            Ok(Box::new(crate::erk::ErkStepper::new(sys, t0, y0, opts)?))
        }
        Method::Bdf | Method::Trbdf2 | Method::Esdirk34 => Ok(Box::new(
            crate::diffsol_backend::DiffsolStepper::new(sys, t0, y0, opts)?,
        )),
        Method::Rodas5p => Ok(Box::new(crate::rosenbrock::Rodas5p::new(
            sys, t0, y0, opts,
        )?)),
    }
}

/// Hairer's starting-step algorithm (HNW I, §II.4, p. 169): a first step for a method of
/// order `order` from the scaled norms of y0, f0 and a finite-difference estimate of y''.
/// Uses 1 extra RHS evaluation (counted by the caller via the return value's second field).
pub fn initial_step<S: OdeSystem + ?Sized>(
    sys: &S,
    t0: f64,
    y0: &[f64],
    f0: &[f64],
    order: usize,
    opts: &SolverOptions,
    t_stop: f64,
) -> f64 {
    let n = y0.len();
    let span = (t_stop - t0).abs();
    let sc = |i: usize| opts.atol.get(i) + opts.rtol * y0[i].abs();
    let rms = |v: &dyn Fn(usize) -> f64| -> f64 {
        ((0..n).map(|i| v(i).powi(2)).sum::<f64>() / n.max(1) as f64).sqrt()
    };
    let d0 = rms(&|i| y0[i] / sc(i));
    let d1 = rms(&|i| f0[i] / sc(i));
    let mut h0 = if d0 < 1e-5 || d1 < 1e-5 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    h0 = h0.min(span).min(opts.h_max);
    let y1: Vec<f64> = (0..n).map(|i| y0[i] + h0 * f0[i]).collect();
    let mut f1 = vec![0.0; n];
    sys.rhs(t0 + h0, &y1, &mut f1);
    let d2 = rms(&|i| (f1[i] - f0[i]) / sc(i)) / h0;
    let h1 = if d1.max(d2) <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / d1.max(d2)).powf(1.0 / (order as f64 + 1.0))
    };
    let h = (100.0 * h0).min(h1).min(span).min(opts.h_max);
    if h.is_finite() && h > 0.0 {
        h
    } else {
        (span * 1e-6).max(f64::MIN_POSITIVE)
    }
}

/// Weighted RMS norm of an error vector: sqrt(mean((err_i / (atol_i + rtol·max(|y_i|, |ŷ_i|)))²)),
/// the norm of HNW I (4.11). NaN in `err` gives +∞ (the step is rejected).
pub fn error_norm(err: &[f64], y_old: &[f64], y_new: &[f64], opts: &SolverOptions) -> f64 {
    let n = err.len();
    let mut s = 0.0;
    for i in 0..n {
        let sc = opts.atol.get(i) + opts.rtol * y_old[i].abs().max(y_new[i].abs());
        let r = err[i] / sc;
        s += r * r;
    }
    let e = (s / n.max(1) as f64).sqrt();
    if e.is_nan() {
        f64::INFINITY
    } else {
        e
    }
}
