//! Stiffness diagnostics: the dominant eigenvalues of ∂f/∂y, the classical RK4 step limit they
//! imply, the same limit measured by bisection, a stiffness ratio, and a verdict on which method
//! family should win.
//!
//! ```text
//! J = ∂f/∂y (t, y)               analytic if the system has one, else central differences
//! λ_1, …, λ_n = eig(J)            sorted by |λ| (largest first); complex pairs for real J
//!
//! RK4 on y' = λy:  y_{n+1} = R(hλ) y_n,   R(z) = 1 + z + z²/2 + z³/6 + z⁴/24
//! ray limit        r(θ) = sup { r ≥ 0 : |R(s e^{iθ})| ≤ 1 for all 0 ≤ s ≤ r },  Re e^{iθ} ≤ 0
//!                  r(π)   = 2.785293563…  (−r(π) is the real root of z³ + 4z² + 12z + 24,
//!                                          where R(z) = +1 again)
//!                  r(π/2) = 2√2 = 2.828427…  (|R(iy)|² = 1 − y⁶/72 + y⁸/576)
//!                  576 (|R(r e^{iθ})|² − 1) = 1152c r + 1152c² r² + 768c³ r³ + 384c⁴ r⁴
//!                      + (192c³ − 48c) r⁵ + (48c² − 8) r⁶ + 8c r⁷ + r⁸,   c = cos θ
//! step limit       h_max = min { r(arg λ_i)/|λ_i| : Re λ_i ≤ 0, λ_i ≉ 0 }
//!                  Re λ_i > 0: a growing mode of the ODE itself (reported, never a limit)
//! stiffness ratio  S = max |Re λ_i| / min |Re λ_i| over Re λ_i < 0   (Lambert 1991, ch. 6)
//! ```
//!
//! Sources: E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd ed.,
//! Springer 1996, §IV.2 (stability functions and domains of explicit Runge–Kutta methods,
//! Fig. 2.1); J. D. Lambert, *Numerical Methods for Ordinary Differential Systems*, Wiley 1991,
//! ch. 6 (stiffness ratio).
//!
//! The eigenvalue analysis is local: it describes the linearisation at one point. The measured
//! limit ([`measure_rk4_limit`]) answers the global question on a span directly, and agrees with
//! the prediction on linear problems (the tests show it to 2e-3, the resolution of a finite span).

// The spectrum at one point lives in `spectrum` (it integrates nothing, and RK4's stability
// check reads it); its items keep their paths here.
pub use super::spectrum::{eigenvalues, jacobian_at, rk4_amplification, rk4_ray_limit, Eigenvalue};

use super::error::AnalysisError;
use crate::error::SolveError;
use crate::integrator::{solve, Problem, Solution, StepOutcome};
use crate::method::Method;
use crate::options::{Output, SolverOptions};
use crate::system::OdeSystem;

/// Options of the eigenvalue analysis.
///
/// ```text
/// FD step      δ_j = ε^{1/3} · max(|y_j|, s_j)     (central differences, error O(δ²))
/// "zero"       |λ| ≤ tol,   "on the imaginary axis"  |Re λ| ≤ tol,   tol = neutral_rtol · max_i |λ_i|
/// ```
/// Central differences: Dennis & Schnabel, *Numerical Methods for Unconstrained Optimization
/// and Nonlinear Equations*, SIAM 1996, §5.6 (step ε^{1/3} balances truncation and rounding).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StiffnessOptions {
    /// How many eigenvalues (largest modulus first) [`StiffnessSummary::dominant`] keeps.
    /// Default 6; ≥ 1.
    pub keep: usize,
    /// Relative threshold below which an eigenvalue counts as zero (no step limit) and a real
    /// part counts as zero (on the imaginary axis: neither growing nor a decay rate). The
    /// eigenvalues of a computed Jacobian carry errors of order ε‖J‖ (analytic) or ε^{2/3}‖J‖
    /// (central differences), so a pure oscillation can come out with Re λ = ±1e−12 |λ|.
    /// Default 1e-8; range [0, 1).
    pub neutral_rtol: f64,
    /// Scale s_j of each component for the finite-difference step (length n); None: s_j = 1.
    /// Give the natural size of each state component when it is far from 1 (a clearance-joint
    /// eccentricity of 1e-5 m wants s_j ≈ 1e-5; `atol_j / rtol` is a good choice). Unused when
    /// the system has an analytic Jacobian.
    pub fd_scale: Option<Vec<f64>>,
}

impl Default for StiffnessOptions {
    fn default() -> Self {
        StiffnessOptions {
            keep: 6,
            neutral_rtol: 1e-8,
            fd_scale: None,
        }
    }
}

impl StiffnessOptions {
    fn validate(&self, n: usize) -> Result<(), AnalysisError> {
        let bad = |m: String| Err(AnalysisError::InvalidInput(m));
        if self.keep == 0 {
            return bad("keep must be >= 1".into());
        }
        if !(0.0..1.0).contains(&self.neutral_rtol) {
            return bad(format!(
                "neutral_rtol must be in [0, 1), got {}",
                self.neutral_rtol
            ));
        }
        if let Some(s) = &self.fd_scale {
            if s.len() != n {
                return bad(format!("fd_scale has {} entries, the system {n}", s.len()));
            }
            if let Some(v) = s.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
                return bad(format!(
                    "every fd_scale entry must be finite and > 0, got {v}"
                ));
            }
        }
        Ok(())
    }
}

/// The eigenvalue picture at one point (t, y).
///
/// ```text
/// ρ = max |λ_i|,  h_max = min r(arg λ_i)/|λ_i| over Re λ_i ≤ 0 (RK4),  S = max|Re λ|/min|Re λ|
/// ```
/// HNW II §IV.2 (stability domain of RK4); Lambert (1991), ch. 6 (stiffness ratio).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StiffnessSummary {
    /// Time of the point.
    pub t: f64,
    /// The `keep` eigenvalues of largest modulus, largest first (a complex pair: +im first).
    pub dominant: Vec<Eigenvalue>,
    /// Spectral radius ρ = max |λ_i| (1/s).
    pub spectral_radius: f64,
    /// Largest stable RK4 step over all decaying and oscillating modes (s); None when no
    /// eigenvalue limits the step (all zero or growing).
    pub rk4_h_max: Option<f64>,
    /// The eigenvalue that sets `rk4_h_max`.
    pub limiting: Option<Eigenvalue>,
    /// Growing modes of the ODE itself (Re λ > tol): no step size makes them decay, and they
    /// are not step limits.
    pub unstable: Vec<Eigenvalue>,
    /// max |Re λ| / min |Re λ| over the decaying modes (Re λ < −tol); None when there is none.
    pub stiffness_ratio: Option<f64>,
}

/// The summary of a set of eigenvalues at time t (see [`StiffnessSummary`]); the eigenvalues
/// need not be sorted.
pub fn summarize(
    t: f64,
    eigs: &[Eigenvalue],
    opts: &StiffnessOptions,
) -> Result<StiffnessSummary, AnalysisError> {
    opts.validate(opts.fd_scale.as_ref().map_or(0, |s| s.len()))?;
    if eigs.iter().any(|e| !(e.re.is_finite() && e.im.is_finite())) {
        return Err(AnalysisError::NonFinite {
            t,
            what: "eigenvalue".into(),
        });
    }
    let mut sorted = eigs.to_vec();
    sorted.sort_by(|a, b| {
        b.modulus()
            .total_cmp(&a.modulus())
            .then(b.im.total_cmp(&a.im))
    });
    let rho = sorted.first().map_or(0.0, |e| e.modulus());
    let tol = opts.neutral_rtol * rho;
    let mut h_max: Option<f64> = None;
    let mut limiting = None;
    let mut unstable = Vec::new();
    let (mut re_max, mut re_min) = (0.0f64, f64::INFINITY);
    for e in &sorted {
        let m = e.modulus();
        if m <= tol || m == 0.0 {
            continue;
        }
        if e.re > tol {
            unstable.push(*e);
            continue;
        }
        let re = if e.re >= -tol { 0.0 } else { e.re };
        if re < 0.0 {
            re_max = re_max.max(-re);
            re_min = re_min.min(-re);
        }
        if let Some(r) = rk4_ray_limit(re, e.im) {
            let h = r / m;
            if h_max.is_none_or(|hm| h < hm) {
                h_max = Some(h);
                limiting = Some(*e);
            }
        }
    }
    let stiffness_ratio = if re_min.is_finite() {
        Some(re_max / re_min)
    } else {
        None
    };
    sorted.truncate(opts.keep);
    Ok(StiffnessSummary {
        t,
        dominant: sorted,
        spectral_radius: rho,
        rk4_h_max: h_max,
        limiting,
        unstable,
        stiffness_ratio,
    })
}

/// Jacobian, eigenvalues and summary at one point (t, y).
pub fn analyze<S: OdeSystem + ?Sized>(
    sys: &S,
    t: f64,
    y: &[f64],
    opts: &StiffnessOptions,
) -> Result<StiffnessSummary, AnalysisError> {
    opts.validate(sys.dim())?;
    let jac = jacobian_at(sys, t, y, opts.fd_scale.as_deref())?;
    let eigs = eigenvalues(jac.as_ref()).map_err(|e| with_time(e, t))?;
    summarize(t, &eigs, opts)
}

fn with_time(e: AnalysisError, t: f64) -> AnalysisError {
    match e {
        AnalysisError::NonFinite { what, .. } => AnalysisError::NonFinite { t, what },
        AnalysisError::EigenNoConvergence { .. } => AnalysisError::EigenNoConvergence { t },
        e => e,
    }
}

/// [`analyze`] at each of a list of points: times `t` and states `y`, row-major (state k is
/// `y[k·n .. (k+1)·n]`, the layout of [`Solution`]). The `lash stiffness` command plots the
/// result against crank angle.
pub fn sample_states<S: OdeSystem + ?Sized>(
    sys: &S,
    t: &[f64],
    y: &[f64],
    opts: &StiffnessOptions,
) -> Result<Vec<StiffnessSummary>, AnalysisError> {
    let n = sys.dim();
    if y.len() != t.len() * n {
        return Err(AnalysisError::InvalidInput(format!(
            "{} states of dimension {n} need {} values, got {}",
            t.len(),
            t.len() * n,
            y.len()
        )));
    }
    t.iter()
        .enumerate()
        .map(|(k, &tk)| analyze(sys, tk, &y[k * n..(k + 1) * n], opts))
        .collect()
}

/// [`analyze`] at every recorded point of a solution (use `Output::Times` for an even grid).
pub fn sample_solution<S: OdeSystem + ?Sized>(
    sys: &S,
    sol: &Solution,
    opts: &StiffnessOptions,
) -> Result<Vec<StiffnessSummary>, AnalysisError> {
    if sol.dim != sys.dim() {
        return Err(AnalysisError::InvalidInput(format!(
            "the solution has dimension {}, the system {}",
            sol.dim,
            sys.dim()
        )));
    }
    sample_states(sys, &sol.t, &sol.y, opts)
}

/// Integrates from (t_span.0, y0) with `solver` and analyses the dense output at `times`
/// (increasing, inside the span).
pub fn sample_trajectory<S: OdeSystem + ?Sized>(
    sys: &S,
    t_span: (f64, f64),
    y0: &[f64],
    solver: &SolverOptions,
    times: &[f64],
    opts: &StiffnessOptions,
) -> Result<Vec<StiffnessSummary>, AnalysisError> {
    if let (Some(&a), Some(&b)) = (times.first(), times.last()) {
        if !(a >= t_span.0 && b <= t_span.1) {
            return Err(AnalysisError::InvalidInput(format!(
                "sample times [{a}, {b}] leave the span [{}, {}]",
                t_span.0, t_span.1
            )));
        }
    }
    let mut o = solver.clone();
    o.output = Output::Times(times.to_vec());
    let sol = solve(sys, t_span, y0, &o)?;
    if sol.t.len() != times.len() {
        return Err(AnalysisError::Degenerate {
            t: sol.t_final,
            reason: format!(
                "a stopping event ended the run after {} of {} sample times",
                sol.t.len(),
                times.len()
            ),
        });
    }
    sample_solution(sys, &sol, opts)
}

/// Which method family a problem favours.
///
/// ```text
/// q = h_accuracy / h_stability:   Explicit (q ≤ 1) · Either (1 < q < 10) · Implicit (q ≥ 10)
/// ```
/// HNW II, §IV.1–IV.2 (stiffness: stability, not accuracy, limits the explicit step).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    /// Explicit Runge–Kutta (rk4, dopri54, tsit54, …): accuracy, not stability, sets the step.
    Explicit,
    /// No clear winner: stability costs an explicit method a few times more steps than
    /// accuracy needs, about what an implicit step costs more than an explicit one.
    Either,
    /// Implicit (rodas5p, bdf): stability forces an explicit method to steps far below what
    /// accuracy needs.
    Implicit,
}

/// The verdict of [`verdict`].
///
/// ```text
/// q = h_accuracy / h_stability:   q ≤ 1 explicit,   1 < q < 10 either,   q ≥ 10 implicit
/// ```
/// HNW II, §IV.1–IV.2 (stiffness as the stability limit forcing steps far below the accuracy
/// need); the factor 10 is an order-of-magnitude rule, [`IMPLICIT_FACTOR`].
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Verdict {
    /// The family that should win.
    pub family: Family,
    /// q = h_accuracy / h_stability (0 when no eigenvalue limits the step).
    pub step_ratio: f64,
    /// One or two sentences with the numbers.
    pub reason: String,
}

/// Ratio q of accuracy step to stability limit from which an implicit method wins: an implicit
/// step (a Jacobian, an LU, a few stages or Newton iterations) costs several explicit steps for
/// the small systems lash integrates, so stability must force roughly ten times more explicit
/// steps than accuracy needs before the implicit method pays for itself (HNW II, §IV.10
/// compares both families on stiff problems; the factor is an order of magnitude, not a
/// measurement).
pub const IMPLICIT_FACTOR: f64 = 10.0;

/// Which family should win, from measured numbers:
/// - `h_accuracy`: the step the accuracy needs (an adaptive explicit run's typical step away
///   from stability trouble, or the RK4 step the study asks for);
/// - `h_stability`: the RK4 stability limit, predicted ([`StiffnessSummary::rk4_h_max`]) or
///   measured ([`measure_rk4_limit`]); None when nothing limits the step;
/// - `n_unstable`: the number of growing modes of the ODE (mentioned in the reason).
pub fn verdict(
    h_accuracy: f64,
    h_stability: Option<f64>,
    n_unstable: usize,
) -> Result<Verdict, AnalysisError> {
    if !(h_accuracy.is_finite() && h_accuracy > 0.0) {
        return Err(AnalysisError::InvalidInput(format!(
            "h_accuracy must be finite and > 0, got {h_accuracy}"
        )));
    }
    if let Some(h) = h_stability {
        if !(h.is_finite() && h > 0.0) {
            return Err(AnalysisError::InvalidInput(format!(
                "h_stability must be finite and > 0, got {h}"
            )));
        }
    }
    let (family, q, mut reason) = match h_stability {
        None => (
            Family::Explicit,
            0.0,
            format!(
                "no decaying or oscillating mode limits the step; accuracy sets it \
                 (h = {h_accuracy:.3e} s), so an explicit method wins"
            ),
        ),
        Some(hs) => {
            let q = h_accuracy / hs;
            if q <= 1.0 {
                (
                    Family::Explicit,
                    q,
                    format!(
                        "the step accuracy needs ({h_accuracy:.3e} s) is below the RK4 stability \
                         limit ({hs:.3e} s): an explicit method is stable at the accuracy step"
                    ),
                )
            } else if q < IMPLICIT_FACTOR {
                (
                    Family::Either,
                    q,
                    format!(
                        "the RK4 stability limit ({hs:.3e} s) is {q:.1}× below the accuracy step \
                         ({h_accuracy:.3e} s): an explicit method takes {q:.1}× more steps than \
                         accuracy needs, about the extra cost of an implicit step; no clear winner"
                    ),
                )
            } else {
                (
                    Family::Implicit,
                    q,
                    format!(
                        "the RK4 stability limit ({hs:.3e} s) is {q:.0}× below the accuracy step \
                         ({h_accuracy:.3e} s): stiff; an implicit method (rodas5p, bdf) steps at \
                         the accuracy step"
                    ),
                )
            }
        }
    };
    if n_unstable > 0 {
        reason.push_str(&format!(
            "; the ODE itself has {n_unstable} growing mode(s) (Re λ > 0): no method damps them, \
             the step must resolve them"
        ));
    }
    Ok(Verdict {
        family,
        step_ratio: q,
        reason,
    })
}

/// Settings of the measured RK4 stability limit.
///
/// ```text
/// stable(h)  ⇔  fixed-step RK4 over the span does not fail with NonFiniteState (nor with
///               Rk4Unstable, when `base` turns RK4's own stability check on)
///               and max_k ‖y_k‖∞ ≤ growth_bound · M_ref
/// M_ref = max_k ‖y_k‖∞ of the run at the lower end h_lo of the bracket (the reference run);
///         h_lo is trusted when the run at h_lo/2 reaches the same size within growth_bound
///         (both ways), so an unstable lower end is caught rather than taken as the scale
/// bisection on ln h until h_unstable / h_stable ≤ 1 + rel_tol
/// measure_rk4_limit_where: stable(h) also needs valid(t_k, y_k) at every accepted state
/// ```
/// The reference is a run, not ‖y0‖, because the state of a nonlinear system may grow
/// legitimately (a mechanism starting at rest). Past the limit the unstable mode grows like
/// |R(hλ)|^N over N = T/h steps; a step h = h*(1 + δ) is detected once |R|^N exceeds
/// `growth_bound`, i.e. for δ ≳ ln(growth_bound) / (N κ) with κ = d ln|R(hλ)| / d ln h at the
/// limit (κ = 2.785·|R'(−2.785)| ≈ 4.2 on the negative real axis, ≈ 7.1 on the imaginary
/// axis). A longer span sharpens the measurement; the measured bracket lies above the true
/// limit by about that δ.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Rk4ProbeOptions {
    /// Growth factor over the reference run's largest state that counts as unstable.
    /// Default 10; > 1.
    pub growth_bound: f64,
    /// Relative width of the final bracket. Default 1e-4; range [1e-12, 1).
    pub rel_tol: f64,
    /// Most RK4 runs (the three bracket checks included). Default 100; ≥ 3.
    pub max_runs: usize,
}

impl Default for Rk4ProbeOptions {
    fn default() -> Self {
        Rk4ProbeOptions {
            growth_bound: 10.0,
            rel_tol: 1e-4,
            max_runs: 100,
        }
    }
}

/// The result of [`measure_rk4_limit`].
///
/// ```text
/// h_stable ≤ h* < h_unstable,   h_unstable / h_stable ≤ 1 + rel_tol
/// ```
/// (The definition of stable is that of [`Rk4ProbeOptions`].)
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MeasuredLimit {
    /// Largest step found stable.
    pub h_stable: f64,
    /// Smallest step found unstable.
    pub h_unstable: f64,
    /// Runs made.
    pub runs: usize,
    /// RHS evaluations over all runs.
    pub rhs_evals: usize,
    /// M_ref: the reference run's largest ‖y‖∞.
    pub reference_size: f64,
}

impl MeasuredLimit {
    /// The geometric mean of the bracket ends.
    pub fn estimate(&self) -> f64 {
        (self.h_stable * self.h_unstable).sqrt()
    }
}

/// A predicate on the accepted states of a probe run: `valid(t, y)` false counts the run as
/// unstable ([`measure_rk4_limit_where`]).
pub type StateCheck<'a> = &'a dyn Fn(f64, &[f64]) -> bool;

/// Result of one probe run: Some(max ‖y‖∞) when the run stayed finite, within `bound` and
/// `valid` at every accepted state (None when it failed with NonFiniteState or Rk4Unstable,
/// exceeded the bound or left the valid set), and the RHS evaluations.
fn rk4_probe<S: OdeSystem + ?Sized>(
    sys: &S,
    t_span: (f64, f64),
    y0: &[f64],
    h: f64,
    base: &SolverOptions,
    bound: f64,
    valid: StateCheck<'_>,
) -> Result<(Option<f64>, usize), AnalysisError> {
    let mut o = base.clone();
    o.method = Method::Rk4;
    o.step = Some(h);
    o.controller = None;
    o.output = Output::Final;
    let problem = Problem::new(sys, &o)?;
    let mut it = problem.integrator(t_span.0, t_span.1, y0)?;
    let norm = |y: &[f64]| y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut size = norm(y0);
    loop {
        match it.step() {
            Ok(out) => {
                size = size.max(norm(it.y()));
                if size > bound || !valid(it.t(), it.y()) {
                    return Ok((None, it.stats().rhs_evals));
                }
                let done = match out {
                    StepOutcome::StopTime { .. } => true,
                    StepOutcome::Event { stopped, .. } => stopped,
                    StepOutcome::Accepted { .. } => false,
                };
                if done || it.is_finished() {
                    return Ok((Some(size), it.stats().rhs_evals));
                }
            }
            Err(SolveError::NonFiniteState { .. } | SolveError::Rk4Unstable { .. }) => {
                return Ok((None, it.stats().rhs_evals))
            }
            Err(e) => return Err(e.into()),
        }
    }
}

/// Whether fixed-step RK4 with step `h` stays finite and within ‖y‖∞ ≤ `bound` over the span
/// (the other settings, events and `max_steps` included, come from `base`; its method, step and
/// output are replaced). Failures other than `NonFiniteState` are errors.
pub fn rk4_is_stable<S: OdeSystem + ?Sized>(
    sys: &S,
    t_span: (f64, f64),
    y0: &[f64],
    h: f64,
    base: &SolverOptions,
    bound: f64,
) -> Result<bool, AnalysisError> {
    if !(bound > 0.0) {
        return Err(AnalysisError::InvalidInput(format!(
            "bound must be > 0, got {bound}"
        )));
    }
    Ok(rk4_probe(sys, t_span, y0, h, base, bound, &|_, _| true)?
        .0
        .is_some())
}

/// The largest stable RK4 step on a span, measured by bisection inside `bracket = (h_lo,
/// h_hi)`: h_lo must be stable (its run is the reference, checked against a run at h_lo/2),
/// h_hi unstable ([`AnalysisError::NoBracket`] otherwise). See [`Rk4ProbeOptions`] for the definition of
/// stable and the resolution.
pub fn measure_rk4_limit<S: OdeSystem + ?Sized>(
    sys: &S,
    t_span: (f64, f64),
    y0: &[f64],
    bracket: (f64, f64),
    base: &SolverOptions,
    probe: &Rk4ProbeOptions,
) -> Result<MeasuredLimit, AnalysisError> {
    measure_rk4_limit_where(sys, t_span, y0, bracket, base, probe, &|_, _| true)
}

/// [`measure_rk4_limit`] with a further condition on stability: a run is stable only if
/// `valid(t, y)` holds at every accepted state (t, y) (the start excluded), besides staying
/// finite and bounded. For systems whose instabilities stay bounded: a mechanism's clearance
/// joint beyond its RK4 limit rattles within about a clearance while ‖y‖∞ (the link
/// positions) hardly changes, but its constraints drift far from Φ = 0 (lash's `stiffness`
/// command checks ‖Φ‖ ≤ c/100). The check sees accepted states only, never the RK4 stages.
pub fn measure_rk4_limit_where<S: OdeSystem + ?Sized>(
    sys: &S,
    t_span: (f64, f64),
    y0: &[f64],
    bracket: (f64, f64),
    base: &SolverOptions,
    probe: &Rk4ProbeOptions,
    valid: StateCheck<'_>,
) -> Result<MeasuredLimit, AnalysisError> {
    let (mut lo, mut hi) = bracket;
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo) {
        return Err(AnalysisError::InvalidInput(format!(
            "bracket must satisfy 0 < h_lo < h_hi, got ({lo}, {hi})"
        )));
    }
    if !(probe.growth_bound > 1.0 && probe.growth_bound.is_finite()) {
        return Err(AnalysisError::InvalidInput(format!(
            "growth_bound must be finite and > 1, got {}",
            probe.growth_bound
        )));
    }
    if !(1e-12..1.0).contains(&probe.rel_tol) {
        return Err(AnalysisError::InvalidInput(format!(
            "rel_tol must be in [1e-12, 1), got {}",
            probe.rel_tol
        )));
    }
    if probe.max_runs < 3 {
        return Err(AnalysisError::InvalidInput("max_runs must be >= 3".into()));
    }
    let unbounded = base.divergence_bound;
    let (reference, mut evals) = rk4_probe(sys, t_span, y0, lo, base, unbounded, valid)?;
    let (half, e) = rk4_probe(sys, t_span, y0, 0.5 * lo, base, unbounded, valid)?;
    evals += e;
    let (m_ref, m_half) = match (reference, half) {
        (Some(a), Some(b)) => (a, b),
        _ => {
            return Err(AnalysisError::NoBracket {
                h: lo,
                stable: false,
            })
        }
    };
    if !(m_ref > 0.0) {
        return Err(AnalysisError::InvalidInput(
            "the reference run stays at y = 0: growth cannot be measured; start from y0 ≠ 0".into(),
        ));
    }
    let g = probe.growth_bound;
    if m_ref > g * m_half || m_half > g * m_ref {
        return Err(AnalysisError::NoBracket {
            h: lo,
            stable: false,
        });
    }
    let bound = g * m_ref;
    let (r, e) = rk4_probe(sys, t_span, y0, hi, base, bound, valid)?;
    evals += e;
    if r.is_some() {
        return Err(AnalysisError::NoBracket {
            h: hi,
            stable: true,
        });
    }
    let mut runs = 3;
    while hi / lo > 1.0 + probe.rel_tol {
        if runs >= probe.max_runs {
            return Err(AnalysisError::InvalidInput(format!(
                "max_runs = {} reached with bracket ({lo:e}, {hi:e})",
                probe.max_runs
            )));
        }
        let mid = (lo * hi).sqrt();
        let (r, e) = rk4_probe(sys, t_span, y0, mid, base, bound, valid)?;
        evals += e;
        runs += 1;
        if r.is_some() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(MeasuredLimit {
        h_stable: lo,
        h_unstable: hi,
        runs,
        rhs_evals: evals,
        reference_size: m_ref,
    })
}
