//! The largest Lyapunov exponent by Benettin's two-trajectory method, and a stroboscopic
//! (once-per-period Poincaré) map.
//!
//! ```text
//! reference y(t) and perturbed z(t), both solving y' = f(t, y), z(t_s) = y(t_s) + d0 u, ‖u‖_w = 1
//! for k = 1..N, t_k = t_s + k Δt:
//!     integrate both over [t_{k−1}, t_k]          (each with `solve`; events are located inside)
//!     d_k = ‖z(t_k) − y(t_k)‖_w,   g_k = ln(d_k / d0)
//!     z(t_k) ← y(t_k) + (d0 / d_k) (z(t_k) − y(t_k))       (renormalise)
//! running estimate   λ(t_k) = (g_1 + … + g_k) / (t_k − t_s)  →  λ_max  as k → ∞
//! weighted norm      ‖v‖_w = √(Σ_i (w_i v_i)²)
//!
//! stroboscopic map   s_j = φ(t_0 + (m + j) T, y(t_0 + (m + j) T)),  j = 0..N−1  (m periods skipped)
//! ```
//!
//! Sources: G. Benettin, L. Galgani, A. Giorgilli, J.-M. Strelcyn, "Lyapunov characteristic
//! exponents for smooth dynamical systems and for Hamiltonian systems; a method for computing
//! all of them", Meccanica 15 (1980) 9–20 and 21–30; J. C. Sprott, *Chaos and Time-Series
//! Analysis*, Oxford 2003, §5.6 (the two-trajectory recipe) and Table A.1 (reference exponents).
//!
//! Because both trajectories are integrated segment by segment with [`crate::solve`], any method
//! can be used and contact events are located inside every segment, each trajectory at its own
//! event times. Two caveats follow from the discontinuities an event hook introduces: the
//! separation jumps by a saltation factor when the two trajectories cross an event surface at
//! slightly different times (this is part of the dynamics and belongs in the exponent), and a
//! renormalisation that falls between the two crossing times sees the full jump (a rare,
//! O(d0 / Δt) per-event outlier in g_k). A system whose hooks keep state (a stored impact
//! velocity behind a `Cell`) must give each trajectory its own instance:
//! [`largest_lyapunov_pair`].
//!
//! The separation is also affected by the integration error of each trajectory, which is not
//! correlated between them when an adaptive method picks different steps: keep the tolerance
//! well below d0 (rtol·‖y‖ ≪ d0), or use fixed-step RK4, whose errors are correlated.

use super::error::AnalysisError;
use crate::integrator::solve;
use crate::options::{Output, SolverOptions};
use crate::system::OdeSystem;

/// Settings of Benettin's method.
///
/// ```text
/// N = round(duration / renorm_interval) intervals of Δt = renorm_interval after `transient`
/// ```
/// Benettin et al. (1980); Sprott (2003), §5.6.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LyapunovOptions {
    /// Solver options for both trajectories (`output` is replaced by `Final`). Default:
    /// dopri54 with rtol 1e-10, atol 1e-12.
    pub solver: SolverOptions,
    /// Renormalisation interval Δt (time units). Default 0.1; > 0. Short enough that the
    /// separation stays small (d0·e^{λΔt} ≪ the scale of the nonlinearity), long enough that
    /// the restarts of the solver do not dominate the cost.
    pub renorm_interval: f64,
    /// Averaging time after the transient. Default 100; ≥ renorm_interval.
    pub duration: f64,
    /// Time the reference trajectory is integrated alone first, to settle on the attractor.
    /// Default 0; ≥ 0.
    pub transient: f64,
    /// Initial and renormalised separation d0 (weighted norm). Default 1e-8; > 0. It must stay
    /// far above the rounding of the state (d0 ≫ ε‖y‖, else z − y loses its digits and a zero
    /// separation ends the run as `Degenerate`) and far below the scale on which f is
    /// nonlinear; for a linear system any d0 is exact.
    pub d0: f64,
    /// Direction u of the first perturbation (length n, not all zero; normalised here).
    /// Default None: all ones.
    pub direction: Option<Vec<f64>>,
    /// Norm weights w_i (length n, > 0), for states that mix units (positions and velocities).
    /// Default None: all ones.
    pub weights: Option<Vec<f64>>,
}

impl Default for LyapunovOptions {
    fn default() -> Self {
        LyapunovOptions {
            solver: SolverOptions {
                rtol: 1e-10,
                atol: crate::options::Atol::Scalar(1e-12),
                ..Default::default()
            },
            renorm_interval: 0.1,
            duration: 100.0,
            transient: 0.0,
            d0: 1e-8,
            direction: None,
            weights: None,
        }
    }
}

/// The result of [`largest_lyapunov`].
///
/// ```text
/// running[k] = (g_1 + … + g_{k+1}) / (t[k] − t_s),   exponent = running[N − 1]
/// ```
/// Benettin et al. (1980).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LyapunovEstimate {
    /// Start of the averaging, t_s = t0 + transient.
    pub t_start: f64,
    /// End of each renormalisation interval, t_k.
    pub t: Vec<f64>,
    /// Log growth g_k = ln(d_k / d0) of each interval.
    pub log_growth: Vec<f64>,
    /// Running estimate λ(t_k) (1/time unit), for convergence plots.
    pub running: Vec<f64>,
    /// The final estimate, λ(t_N).
    pub exponent: f64,
    /// State of the reference trajectory at the end.
    pub y_final: Vec<f64>,
    /// RHS evaluations of both trajectories.
    pub rhs_evals: usize,
    /// Accepted steps of both trajectories.
    pub steps: usize,
    /// Events located on both trajectories.
    pub events: usize,
}

fn check_vec(
    name: &str,
    v: &Option<Vec<f64>>,
    n: usize,
    positive: bool,
) -> Result<(), AnalysisError> {
    if let Some(v) = v {
        if v.len() != n {
            return Err(AnalysisError::InvalidInput(format!(
                "{name} has {} entries, the system {n}",
                v.len()
            )));
        }
        let ok = |x: &f64| x.is_finite() && (!positive || *x > 0.0);
        if !v.iter().all(ok) {
            return Err(AnalysisError::InvalidInput(format!(
                "every {name} entry must be finite{}",
                if positive { " and > 0" } else { "" }
            )));
        }
    }
    Ok(())
}

/// The largest Lyapunov exponent of `sys` from (t0, y0) by Benettin's method (module docs).
/// Both trajectories use the same system instance: right for systems without hook state; see
/// [`largest_lyapunov_pair`] otherwise.
pub fn largest_lyapunov<S: OdeSystem + ?Sized>(
    sys: &S,
    t0: f64,
    y0: &[f64],
    opts: &LyapunovOptions,
) -> Result<LyapunovEstimate, AnalysisError> {
    largest_lyapunov_pair(sys, sys, t0, y0, opts)
}

/// [`largest_lyapunov`] with one system instance per trajectory (`sys_ref` for the reference,
/// `sys_pert` for the perturbed one), for systems whose event hooks keep state. Both must be
/// the same model in the same initial internal state.
pub fn largest_lyapunov_pair<S: OdeSystem + ?Sized>(
    sys_ref: &S,
    sys_pert: &S,
    t0: f64,
    y0: &[f64],
    opts: &LyapunovOptions,
) -> Result<LyapunovEstimate, AnalysisError> {
    let n = sys_ref.dim();
    let bad = |m: String| Err(AnalysisError::InvalidInput(m));
    if sys_pert.dim() != n {
        return bad(format!(
            "the two systems have dimensions {n} and {}",
            sys_pert.dim()
        ));
    }
    if y0.len() != n {
        return bad(format!("y0 has {} entries, the system {n}", y0.len()));
    }
    if !t0.is_finite() || y0.iter().any(|v| !v.is_finite()) {
        return bad("t0 and y0 must be finite".into());
    }
    let dt = opts.renorm_interval;
    if !(dt.is_finite() && dt > 0.0) {
        return bad(format!("renorm_interval must be finite and > 0, got {dt}"));
    }
    if !(opts.duration.is_finite() && opts.duration >= dt) {
        return bad(format!(
            "duration must be finite and >= renorm_interval, got {}",
            opts.duration
        ));
    }
    if !(opts.transient.is_finite() && opts.transient >= 0.0) {
        return bad(format!(
            "transient must be finite and >= 0, got {}",
            opts.transient
        ));
    }
    if !(opts.d0.is_finite() && opts.d0 > 0.0) {
        return bad(format!("d0 must be finite and > 0, got {}", opts.d0));
    }
    check_vec("direction", &opts.direction, n, false)?;
    check_vec("weights", &opts.weights, n, true)?;
    let w = |i: usize| opts.weights.as_ref().map_or(1.0, |w| w[i]);
    let wnorm =
        |v: &dyn Fn(usize) -> f64| (0..n).map(|i| (w(i) * v(i)).powi(2)).sum::<f64>().sqrt();
    let dir: Vec<f64> = opts.direction.clone().unwrap_or_else(|| vec![1.0; n]);
    let dn = wnorm(&|i| dir[i]);
    if !(dn > 0.0 && dn.is_finite()) {
        return bad("direction must not be zero".into());
    }

    let mut so = opts.solver.clone();
    so.output = Output::Final;
    let mut est = LyapunovEstimate::default();
    let mut y = y0.to_vec();
    let t_start = t0 + opts.transient;
    if opts.transient > 0.0 {
        let sol = solve(sys_ref, (t0, t_start), &y, &so)?;
        if sol.t_final < t_start {
            return Err(AnalysisError::Degenerate {
                t: sol.t_final,
                reason: "a stopping event ended the transient".into(),
            });
        }
        est.rhs_evals += sol.stats.rhs_evals;
        est.steps += sol.stats.accepted;
        est.events += sol.stats.events;
        y = sol.y_final;
    }
    let mut z: Vec<f64> = (0..n).map(|i| y[i] + opts.d0 * dir[i] / dn).collect();
    let n_int = (opts.duration / dt).round().max(1.0) as usize;
    est.t_start = t_start;
    est.t.reserve(n_int);
    est.log_growth.reserve(n_int);
    est.running.reserve(n_int);
    let mut sum = 0.0;
    let mut ta = t_start;
    for k in 1..=n_int {
        let tb = t_start + k as f64 * dt;
        let a = solve(sys_ref, (ta, tb), &y, &so)?;
        let b = solve(sys_pert, (ta, tb), &z, &so)?;
        for s in [&a, &b] {
            est.rhs_evals += s.stats.rhs_evals;
            est.steps += s.stats.accepted;
            est.events += s.stats.events;
            if s.t_final < tb {
                return Err(AnalysisError::Degenerate {
                    t: s.t_final,
                    reason: "a stopping event ended a trajectory inside a segment".into(),
                });
            }
        }
        y = a.y_final;
        z = b.y_final;
        let d = wnorm(&|i| z[i] - y[i]);
        if !(d > 0.0 && d.is_finite()) {
            return Err(AnalysisError::Degenerate {
                t: tb,
                reason: format!("separation of the two trajectories is {d}"),
            });
        }
        let g = (d / opts.d0).ln();
        sum += g;
        est.t.push(tb);
        est.log_growth.push(g);
        est.running.push(sum / (tb - t_start));
        let s = opts.d0 / d;
        for i in 0..n {
            z[i] = y[i] + s * (z[i] - y[i]);
        }
        ta = tb;
    }
    est.exponent = *est.running.last().unwrap_or(&f64::NAN);
    est.y_final = y;
    Ok(est)
}

/// The result of [`stroboscopic_map`].
///
/// ```text
/// t_j = t_0 + (m + j) T,   values[j] = φ(t_j, y(t_j)),   states: y(t_j) row-major
/// ```
/// Stroboscopic (period-T) Poincaré section: Guckenheimer & Holmes, *Nonlinear Oscillations,
/// Dynamical Systems, and Bifurcations of Vector Fields*, Springer 1983, §1.4.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Stroboscopic {
    /// Sample times t_j.
    pub t: Vec<f64>,
    /// The observable at each sample.
    pub values: Vec<f64>,
    /// Dimension n.
    pub dim: usize,
    /// States at the samples, row-major (state j is `states[j·n .. (j+1)·n]`).
    pub states: Vec<f64>,
}

/// Samples a scalar observable φ(t, y) once per period T (stroboscopic map): N samples at
/// t_0 + (m + j)T, j = 0..N, after skipping m = `skip` periods. One integration with `solver`
/// (its `output` replaced by the sample times, taken from the dense output; events are
/// located as usual).
pub fn stroboscopic_map<S, F>(
    sys: &S,
    t0: f64,
    y0: &[f64],
    period: f64,
    skip: usize,
    n_samples: usize,
    solver: &SolverOptions,
    mut observable: F,
) -> Result<Stroboscopic, AnalysisError>
where
    S: OdeSystem + ?Sized,
    F: FnMut(f64, &[f64]) -> f64,
{
    let n = sys.dim();
    if !(period.is_finite() && period > 0.0) {
        return Err(AnalysisError::InvalidInput(format!(
            "period must be finite and > 0, got {period}"
        )));
    }
    if n_samples == 0 {
        return Err(AnalysisError::InvalidInput("n_samples must be >= 1".into()));
    }
    if y0.len() != n || !t0.is_finite() || y0.iter().any(|v| !v.is_finite()) {
        return Err(AnalysisError::InvalidInput(format!(
            "y0 must have {n} finite entries and t0 be finite"
        )));
    }
    let times: Vec<f64> = (0..n_samples)
        .map(|j| t0 + (skip + j) as f64 * period)
        .collect();
    let t_last = *times.last().unwrap_or(&t0);
    let (ts, states) = if t_last > t0 {
        let mut o = solver.clone();
        o.output = Output::Times(times.clone());
        let sol = solve(sys, (t0, t_last), y0, &o)?;
        if sol.t.len() != times.len() {
            return Err(AnalysisError::Degenerate {
                t: sol.t_final,
                reason: format!(
                    "a stopping event ended the run after {} of {} samples",
                    sol.t.len(),
                    times.len()
                ),
            });
        }
        (sol.t, sol.y)
    } else {
        (times.clone(), y0.to_vec())
    };
    let mut values = Vec::with_capacity(ts.len());
    for (j, &tj) in ts.iter().enumerate() {
        let v = observable(tj, &states[j * n..(j + 1) * n]);
        if !v.is_finite() {
            return Err(AnalysisError::NonFinite {
                t: tj,
                what: "observable".into(),
            });
        }
        values.push(v);
    }
    Ok(Stroboscopic {
        t: ts,
        values,
        dim: n,
        states,
    })
}
