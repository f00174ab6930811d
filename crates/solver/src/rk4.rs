//! The paper's method: classical fourth-order Runge–Kutta with a fixed step.
//!
//! ```text
//! k1 = f(t, y)
//! k2 = f(t + h/2, y + h/2 k1)
//! k3 = f(t + h/2, y + h/2 k2)
//! k4 = f(t + h,   y + h k3)
//! y_{n+1} = y_n + h/6 (k1 + 2 k2 + 2 k3 + k4)
//! quadrature (OdeSystem::quadrature): Q_{n+1} = Q_n + h/6 (q1 + 2 q2 + 2 q3 + q4),
//!   q_i = q at stage i's time and state; estimate h/3 |q2 − q3|
//! ```
//! Kutta (1901); HNW I, Table 1.2 (p. 138). The step is fixed; only the last step is shortened
//! to land on the stop time (the landing rule of [`crate::stepper::landing_step`]). Dense output is the cubic Hermite interpolant through
//! (y_n, f_n) and (y_{n+1}, f_{n+1}) (order 3, continuous derivative); f_{n+1} is the next
//! step's k1, so it costs nothing extra: 4 RHS evaluations per step, plus 1 at the start.
//!
//! Without error control a step past the stability limit makes the state grow without bound;
//! the integrator reports that as `NonFiniteState` once a component exceeds the divergence
//! bound or stops being finite.
//!
//! Growth need not be unbounded: when the unstable mode's rate falls as its amplitude grows
//! (the oil film of a clearance joint, whose squeeze damping grows with the eccentricity), the
//! numerical solution drifts to where the step is stable again and stays finite and wrong
//! (spurious bounded solutions: Yee, Sweby & Griffiths, J. Comput. Phys. 97 (1991) 249). The
//! optional stability check catches that from the stages themselves:
//!
//! ```text
//! k2, k3 are f at the same time t + h/2, at Y2 = y + h/2 k1 and Y3 = y + h/2 k2, so
//!   ρ = ‖k3 − k2‖ / ‖Y3 − Y2‖,   h ρ = 2 ‖k3 − k2‖ / ‖k2 − k1‖       (Euclidean norms)
//! estimates h|λ| of the dominant mode (HNW II §IV.2, the stiffness detection of DOPRI5).
//! a step is suspect when h ρ > r = 2.785293563 (RK4's radius on the negative real axis);
//! steps where ‖k2 − k1‖ is at rounding level (‖k2 − k1‖² ≤ (64 ε)² · 2 (‖k1‖² + ‖k2‖²))
//! are not judged.
//! a suspect step is confirmed from the spectrum: the eigenvalues λ_i of J = ∂f/∂y at (t, y)
//! (the system's Jacobian, else central differences; faer's real Schur form), and the step
//! is flagged when some λ_i with Re λ_i ≤ 0 has |R(h λ_i)| > 1 (R(z) = 1 + z + z²/2 + z³/6 +
//! z⁴/24: h λ_i outside RK4's stability region).
//! the run fails with Rk4Unstable (the step, the limit min_i r(θ_i)/|λ_i| over the decaying
//! eigenvalues of the last flagged step, r(θ) the region's extent along the ray of λ_i, the
//! time and state) after n flagged steps in a row (n = rk4_instability_steps; 15 as in
//! DOPRI5's detection).
//! ```
//! Why the confirmation: the quotient is a power-iteration estimate of ‖J v‖/‖v‖ for the one
//! direction v = Y3 − Y2, and for a non-normal J it can exceed the spectral radius by far. On
//! a mechanism J = [[0, I], [∂q̈/∂q, ∂q̈/∂q̇]] mixes positions and velocities: on the
//! lubricated press at h = 3 µs it flagged runs of hundreds of steps where every h λ_i lies
//! inside the region and RK4 runs stably (BENCHMARKS.md, "RK4 beyond its stability limit").
//! Eigenvalues with Re λ > 0 are growing modes of the system itself (|R(z)| < e^{Re z} there
//! for small z): they are not judged.
//! Consecutive, because across a kink of f (contact onset, the end of the damping ramp) the
//! difference quotient is not an eigenvalue and spikes for one or two steps. On the press the
//! kinks flag a few steps in a row and a real instability hundreds (BENCHMARKS.md, "RK4 beyond
//! its stability limit").

use crate::analysis::spectrum::{eigenvalues, jacobian_at, rk4_amplification, rk4_ray_limit};
use crate::error::SolveError;
use crate::method::Method;
use crate::options::FixedConfig;
use crate::stats::Stats;
use crate::stepper::{check_stop, landing_step, Budget, StepQuadrature, Stepper};
use crate::system::OdeSystem;

/// Radius r of RK4's stability region on the negative real axis: −r is the real root of
/// z³ + 4z² + 12z + 24 (where R(z) = 1 + z + z²/2 + z³/6 + z⁴/24 returns to 1).
///
/// ```text
/// r = 2.785293563405282…   (HNW II §IV.2, Fig. 2.1)
/// ```
pub const RK4_STABILITY_RADIUS: f64 = 2.785_293_563_405_282;

/// Fixed-step classical RK4.
pub struct Rk4<'a, S: OdeSystem + ?Sized> {
    sys: &'a S,
    h: f64,
    budget: Budget,
    /// Consecutive flagged steps that fail the run (0: no check).
    instability_steps: usize,
    /// Flagged steps in a row so far.
    unstable_run: usize,
    t: f64,
    t_prev: f64,
    y: Vec<f64>,
    y_prev: Vec<f64>,
    /// f(t_prev, y_prev)
    f_prev: Vec<f64>,
    /// f(t, y)
    f: Vec<f64>,
    k2: Vec<f64>,
    k3: Vec<f64>,
    k4: Vec<f64>,
    tmp: Vec<f64>,
    /// The last step's h (the quadrature's; 0 after a start or restart).
    h_last: f64,
    stats: Stats,
}

impl<'a, S: OdeSystem + ?Sized> Rk4<'a, S> {
    /// Builds the stepper at (t0, y0) with the configuration's step, stability check and
    /// budgets. Evaluates f(t0, y0) (a non-finite value fails with `NonFiniteState`).
    pub fn new(sys: &'a S, t0: f64, y0: &[f64], cfg: &FixedConfig) -> Result<Self, SolveError> {
        let n = y0.len();
        let mut s = Rk4 {
            sys,
            h: cfg.step(),
            budget: Budget::new(cfg.budgets()),
            instability_steps: cfg.instability_steps(),
            unstable_run: 0,
            t: t0,
            t_prev: t0,
            y: y0.to_vec(),
            y_prev: y0.to_vec(),
            f_prev: vec![0.0; n],
            f: vec![0.0; n],
            k2: vec![0.0; n],
            k3: vec![0.0; n],
            k4: vec![0.0; n],
            tmp: vec![0.0; n],
            h_last: 0.0,
            stats: Stats::default(),
        };
        s.eval_f()?;
        s.f_prev.copy_from_slice(&s.f);
        Ok(s)
    }

    fn eval_f(&mut self) -> Result<(), SolveError> {
        self.sys.rhs(self.t, &self.y, &mut self.f);
        self.stats.rhs_evals += 1;
        if self.f.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(SolveError::NonFiniteState {
                t: self.t,
                y: self.y.clone(),
            })
        }
    }

    /// The spectral confirmation of a suspect step (module doc): Some(limit) when some decaying
    /// eigenvalue λ of ∂f/∂y at (t, y) has |R(h λ)| > 1, the limit being the largest step
    /// that keeps every decaying h λ inside the region along its ray; None when every h λ is
    /// inside. A Jacobian or spectrum that cannot be computed confirms the suspicion, with
    /// the quotient's limit `fallback`.
    fn spectral_check(&self, h: f64, fallback: f64) -> Option<f64> {
        let Ok(ev) =
            jacobian_at(self.sys, self.t, &self.y, None).and_then(|j| eigenvalues(j.as_ref()))
        else {
            return Some(fallback);
        };
        let decaying = ev.iter().filter(|e| e.re <= 0.0);
        if !decaying
            .clone()
            .any(|e| rk4_amplification(h * e.re, h * e.im) > 1.0)
        {
            return None;
        }
        let limit = decaying
            .filter_map(|e| rk4_ray_limit(e.re, e.im).map(|r| r / e.modulus()))
            .fold(f64::INFINITY, f64::min);
        Some(if limit.is_finite() { limit } else { fallback })
    }

    /// h ρ = 2 ‖k3 − k2‖ / ‖k2 − k1‖ when it exceeds [`RK4_STABILITY_RADIUS`] (module doc);
    /// None inside the region or when ‖k2 − k1‖ is at rounding level.
    fn outside_stability_region(&self) -> Option<f64> {
        let (mut num, mut den, mut size) = (0.0, 0.0, 0.0);
        for i in 0..self.y.len() {
            let (k1, k2, k3) = (self.f[i], self.k2[i], self.k3[i]);
            num += (k3 - k2) * (k3 - k2);
            den += (k2 - k1) * (k2 - k1);
            size += k1 * k1 + k2 * k2;
        }
        let floor = 64.0 * f64::EPSILON;
        if !(den > floor * floor * 2.0 * size) {
            return None;
        }
        (4.0 * num > RK4_STABILITY_RADIUS * RK4_STABILITY_RADIUS * den)
            .then(|| 2.0 * (num / den).sqrt())
    }
}

impl<S: OdeSystem + ?Sized> Stepper for Rk4<'_, S> {
    fn method(&self) -> Method {
        Method::Rk4
    }
    fn t(&self) -> f64 {
        self.t
    }
    fn y(&self) -> &[f64] {
        &self.y
    }
    fn t_prev(&self) -> f64 {
        self.t_prev
    }

    fn step(&mut self, t_stop: f64) -> Result<(), SolveError> {
        check_stop(self.t, t_stop)?;
        self.budget.check(self.stats.steps, self.t, &self.y)?;
        let (h, lands) = landing_step(self.t, t_stop, self.h);
        let n = self.y.len();
        let (t, sys) = (self.t, self.sys);
        // k1 = self.f
        for i in 0..n {
            self.tmp[i] = self.y[i] + 0.5 * h * self.f[i];
        }
        sys.rhs(t + 0.5 * h, &self.tmp, &mut self.k2);
        for i in 0..n {
            self.tmp[i] = self.y[i] + 0.5 * h * self.k2[i];
        }
        sys.rhs(t + 0.5 * h, &self.tmp, &mut self.k3);
        if self.instability_steps > 0 {
            let flagged = self
                .outside_stability_region()
                .and_then(|h_rho| self.spectral_check(h, h * RK4_STABILITY_RADIUS / h_rho));
            if let Some(h_limit) = flagged {
                self.unstable_run += 1;
                if self.unstable_run >= self.instability_steps {
                    return Err(SolveError::Rk4Unstable {
                        t: self.t,
                        y: self.y.clone(),
                        h,
                        h_limit,
                        steps: self.unstable_run,
                    });
                }
            } else {
                self.unstable_run = 0;
            }
        }
        for i in 0..n {
            self.tmp[i] = self.y[i] + h * self.k3[i];
        }
        sys.rhs(t + h, &self.tmp, &mut self.k4);
        self.stats.rhs_evals += 3;
        self.stats.steps += 1;
        self.y_prev.copy_from_slice(&self.y);
        self.f_prev.copy_from_slice(&self.f);
        for i in 0..n {
            self.y[i] += h / 6.0 * (self.f[i] + 2.0 * self.k2[i] + 2.0 * self.k3[i] + self.k4[i]);
        }
        self.t_prev = t;
        self.t = if lands { t_stop } else { t + h };
        self.h_last = h;
        self.stats.accepted += 1;
        self.stats.record_step_size(h);
        if !self.y.iter().all(|v| v.is_finite()) {
            return Err(SolveError::NonFiniteState {
                t: self.t_prev,
                y: self.y_prev.clone(),
            });
        }
        self.eval_f()
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) {
        let h = self.t - self.t_prev;
        if h == 0.0 {
            out.copy_from_slice(&self.y);
            return;
        }
        let s = (t - self.t_prev) / h;
        // Cubic Hermite basis.
        let h00 = (1.0 + 2.0 * s) * (1.0 - s) * (1.0 - s);
        let h10 = s * (1.0 - s) * (1.0 - s);
        let h01 = s * s * (3.0 - 2.0 * s);
        let h11 = s * s * (s - 1.0);
        for (i, o) in out.iter_mut().enumerate() {
            *o = h00 * self.y_prev[i]
                + h10 * h * self.f_prev[i]
                + h01 * self.y[i]
                + h11 * h * self.f[i];
        }
    }

    /// RK4's own quadrature (module documentation): h/6 (q₁ + 2 q₂ + 2 q₃ + q₄) at the
    /// stage states, estimate h/3 |q₂ − q₃| (the order-3 rule h/6 (q₁ + 4 q₂ + q₄) on the
    /// same stages).
    fn step_quadrature(&self, value: &mut [f64], estimate: &mut [f64]) -> StepQuadrature {
        let m = self.sys.n_quadratures();
        if m == 0 || self.t == self.t_prev {
            return StepQuadrature::Unavailable;
        }
        let (h, t, y) = (self.h_last, self.t_prev, &self.y_prev);
        let mut ys = vec![0.0; y.len()];
        let mut q = vec![0.0; m];
        let mut stage = |c: f64, a: f64, k: &[f64], q: &mut [f64]| {
            for i in 0..y.len() {
                ys[i] = y[i] + a * h * k[i];
            }
            self.sys.quadrature(t + c * h, &ys, q);
        };
        let mut q2 = vec![0.0; m];
        stage(0.0, 0.0, &self.f_prev, &mut q);
        value.copy_from_slice(&q);
        stage(0.5, 0.5, &self.f_prev, &mut q2);
        stage(0.5, 0.5, &self.k2, &mut q);
        for c in 0..m {
            value[c] += 2.0 * (q2[c] + q[c]);
            estimate[c] = h / 3.0 * (q2[c] - q[c]).abs();
        }
        stage(1.0, 1.0, &self.k3, &mut q);
        for c in 0..m {
            value[c] = h / 6.0 * (value[c] + q[c]);
        }
        StepQuadrature::ValueAndEstimate
    }

    fn set_h_max(&mut self, _h_max: f64) {}

    fn restart(&mut self, t: f64, y: &[f64]) -> Result<(), SolveError> {
        self.unstable_run = 0;
        self.t = t;
        self.t_prev = t;
        self.y.copy_from_slice(y);
        self.y_prev.copy_from_slice(y);
        self.eval_f()?;
        self.f_prev.copy_from_slice(&self.f);
        Ok(())
    }

    fn stats(&self) -> Stats {
        self.stats
    }
}
