//! Explicit embedded Runge–Kutta pairs: one generic stepper for every tableau of
//! [`tableaus`].
//!
//! ```text
//! k_1 = f(t_n, y_n)                                   (the previous step's last stage: FSAL)
//! k_i = f(t_n + c_i h, y_n + h Σ_{j<i} a_ij k_j),  i = 2..s
//! y_{n+1} = y_n + h Σ b_i k_i                         (order p)
//! ε = ‖h Σ (b_i − b̂_i) k_i‖                           (weighted RMS norm, HNW I (4.11))
//! ε ≤ 1: accept, h ← h · controller(ε, history)       (Söderlind filter, default PI)
//! ε > 1: reject, h ← h · max(min_shrink, safety · ε^(−1/(q̂+1)))
//! dense output: y(t_n + θh) = y_n + h Σ b_i(θ) k_i
//! ```
//!
//! Methods ([`tableaus`] names the book or paper, table and page of each):
//!
//! | method | order | error estimate | stages per step | dense output |
//! |---|---|---|---|---|
//! | `bs32` Bogacki–Shampine 1989 | 3 | 2 | 3 (FSAL) | Hermite, order 3 |
//! | `dopri54` Dormand–Prince 1980, HNW I Table 5.2 | 5 | 4 | 6 (FSAL) | Hairer/Shampine, order 4 |
//! | `tsit54` Tsitouras 2011 | 5 | 4 | 6 (FSAL) | Tsitouras, order 4 |
//! | `dop853` Hairer & Wanner, HNW I §II.5–6, §II.10 | 8 | 5 and 3 | 12 | order 7, +3 stages when used |
//!
//! Behaviour shared by all pairs:
//!
//! - The first step is `opts.h0` or Hairer's starting step ([`crate::stepper::initial_step`],
//!   one extra RHS evaluation). After [`Stepper::restart`] the next trial step is the last
//!   accepted step (capped by `h_max`).
//! - Step-size control goes through [`StepSizeControl`] only: `opts.controller` or `pi`, with
//!   `opts.limits`. Accepted proposals are clipped to [h_min, h_max].
//! - A non-finite stage (NaN or ±∞ in the RHS or the stage value) counts as an error-test
//!   failure with ε = ∞, so the step shrinks by `min_shrink`. When the step would fall below
//!   max(h_min, 16·ε_mach·|t|) the step fails: [`SolveError::NonFiniteState`] if the last
//!   attempt was non-finite, [`SolveError::StepSizeTooSmall`] otherwise.
//! - `max_steps` bounds the step attempts (accepted + rejected) of the whole integration
//!   ([`SolveError::TooManySteps`]).
//! - With `opts.adaptive == false` the stepper takes `opts.h0` every step (the last one is
//!   shortened to land on the stop time), computes no error estimate and never rejects: the
//!   mode of fixed-step convergence-order tests. A non-finite stage then fails with
//!   [`SolveError::NonFiniteState`].
//! - DOP853's three extra dense-output stages are evaluated only when the dense output of a
//!   step is first used (interior mutability), and counted in `Stats::rhs_evals` at the next
//!   `step`, `restart` or `stats_mut` call.

pub mod tableaus;

use std::cell::{Cell, RefCell};

pub use tableaus::{Dense, ErrorEstimate, Tableau, BS32, DOP853, DOPRI54, TSIT54};

use crate::controller::{Controller, ControllerKind, StepSizeControl};
use crate::error::SolveError;
use crate::options::{Method, SolverOptions};
use crate::stats::Stats;
use crate::stepper::{error_norm, initial_step, Stepper};
use crate::system::OdeSystem;

/// The tableau of an explicit pair, or None for other methods.
pub fn tableau_of(method: Method) -> Option<&'static Tableau> {
    match method {
        Method::Bs32 => Some(&BS32),
        Method::Dopri54 => Some(&DOPRI54),
        Method::Tsit54 => Some(&TSIT54),
        Method::Dop853 => Some(&DOP853),
        _ => None,
    }
}

/// Lazily computed extra stages of the dense output (DOP853).
struct DenseCache {
    /// Whether the extra stages belong to the current step.
    ready: bool,
    /// Extra stages, indices `f_new_stage()+1 ..` of the tableau.
    k: Vec<Vec<f64>>,
    /// Scratch stage value.
    ytmp: Vec<f64>,
    /// The extra stages were non-finite: fall back to the cubic Hermite interpolant.
    hermite_fallback: bool,
}

/// Generic explicit embedded Runge–Kutta stepper over a [`Tableau`].
///
/// ```text
/// y_{n+1} = y_n + h Σ b_i k_i,  ε = ‖h Σ e_i k_i‖,  y(t_n + θh) = y_n + h Σ b_i(θ) k_i
/// ```
/// See the [module documentation](self) for the control logic and its sources.
pub struct ErkStepper<'a, S: OdeSystem + ?Sized> {
    sys: &'a S,
    method: Method,
    tab: &'static Tableau,
    /// Dense weights r[i][m]: coefficient of θ^(m+1) in b_i(θ).
    dense_w: Vec<Vec<f64>>,
    opts: SolverOptions,
    control: StepSizeControl,
    t: f64,
    t_prev: f64,
    y: Vec<f64>,
    y_prev: Vec<f64>,
    /// f(t, y) at the current state (the next step's first stage).
    f0: Vec<f64>,
    /// Stages of the last attempt (the last accepted step after `step` returns).
    k: Vec<Vec<f64>>,
    y_new: Vec<f64>,
    ytmp: Vec<f64>,
    errv: Vec<f64>,
    errv3: Vec<f64>,
    /// Error weights e = b − b̂ (DOP853: e5).
    err_w: Vec<f64>,
    /// DOP853 only: b − b̂3.
    err_w3: Vec<f64>,
    /// Trial step for the next attempt (None: starting-step estimate needed).
    h_next: Option<f64>,
    /// Size of the last accepted step (None before the first one).
    h_last: Option<f64>,
    dense: RefCell<DenseCache>,
    /// RHS evaluations made by the lazy dense output, not yet in `stats`.
    pending_rhs: Cell<usize>,
    stats: Stats,
}

impl<'a, S: OdeSystem + ?Sized> ErkStepper<'a, S> {
    /// Builds the stepper of `opts.method` (an explicit pair) at (t0, y0); evaluates f(t0, y0).
    pub fn new(sys: &'a S, t0: f64, y0: &[f64], opts: &SolverOptions) -> Result<Self, SolveError> {
        let tab = tableau_of(opts.method).ok_or_else(|| {
            SolveError::InvalidOptions(format!(
                "method {} is not an explicit Runge–Kutta pair",
                opts.method
            ))
        })?;
        Self::with_tableau(sys, t0, y0, opts, tab)
    }

    /// Builds a stepper for any tableau (`opts.method` is only reported by
    /// [`Stepper::method`]).
    pub fn with_tableau(
        sys: &'a S,
        t0: f64,
        y0: &[f64],
        opts: &SolverOptions,
        tab: &'static Tableau,
    ) -> Result<Self, SolveError> {
        let n = y0.len();
        tab.validate().map_err(SolveError::InvalidOptions)?;
        if !opts.adaptive && opts.h0.is_none() {
            return Err(SolveError::InvalidOptions(
                "adaptive = false needs h0 (the fixed step)".into(),
            ));
        }
        let kind = opts.controller.unwrap_or(ControllerKind::Pi);
        let controller: Box<dyn Controller> = Box::new(kind.build());
        let n_extra = tab.total_stages() - tab.f_new_stage() - 1;
        let (err_w, err_w3) = match tab.error {
            ErrorEstimate::Embedded { e } => (e.to_vec(), vec![]),
            ErrorEstimate::Dop853 { e5, b3 } => (
                e5.to_vec(),
                tab.b.iter().zip(b3).map(|(b, b3)| b - b3).collect(),
            ),
        };
        let mut s = ErkStepper {
            sys,
            method: opts.method,
            tab,
            dense_w: tab.dense_weights(),
            opts: opts.clone(),
            control: StepSizeControl::new(controller, opts.limits.clone()),
            t: t0,
            t_prev: t0,
            y: y0.to_vec(),
            y_prev: y0.to_vec(),
            f0: vec![0.0; n],
            k: vec![vec![0.0; n]; tab.f_new_stage() + 1],
            y_new: vec![0.0; n],
            ytmp: vec![0.0; n],
            errv: vec![0.0; n],
            errv3: vec![0.0; n],
            err_w,
            err_w3,
            h_next: opts.h0,
            h_last: None,
            dense: RefCell::new(DenseCache {
                ready: false,
                k: vec![vec![0.0; n]; n_extra],
                ytmp: vec![0.0; n],
                hermite_fallback: false,
            }),
            pending_rhs: Cell::new(0),
            stats: Stats::default(),
        };
        s.eval_f0()?;
        s.k[0].copy_from_slice(&s.f0);
        Ok(s)
    }

    /// The tableau this stepper runs.
    pub fn tableau(&self) -> &'static Tableau {
        self.tab
    }

    fn eval_f0(&mut self) -> Result<(), SolveError> {
        self.sys.rhs(self.t, &self.y, &mut self.f0);
        self.stats.rhs_evals += 1;
        if self.f0.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(SolveError::NonFiniteState {
                t: self.t,
                y: self.y.clone(),
            })
        }
    }

    fn flush_pending(&mut self) {
        self.stats.rhs_evals += self.pending_rhs.replace(0);
    }

    /// One attempt of size h from (t, y): fills the stages, `y_new` and returns the error norm
    /// (∞ when a stage or y_new is non-finite; 0 when `adaptive` is off). For a non-FSAL pair
    /// the f(t+h, y_new) stage is not evaluated here.
    fn attempt(&mut self, h: f64) -> f64 {
        let tab = self.tab;
        let s = tab.stages();
        let n = self.y.len();
        let (t, sys) = (self.t, self.sys);
        let last_main = if tab.fsal { s - 1 } else { s };
        let mut rhs = 0;
        let mut finite = true;
        for i in 1..last_main {
            let row = tab.a[i];
            for q in 0..n {
                let mut acc = 0.0;
                for (j, a) in row.iter().enumerate() {
                    if *a != 0.0 {
                        acc += a * self.k[j][q];
                    }
                }
                self.ytmp[q] = self.y[q] + h * acc;
            }
            sys.rhs(t + tab.c[i] * h, &self.ytmp, &mut self.k[i]);
            rhs += 1;
            if !self.k[i].iter().all(|v| v.is_finite()) {
                finite = false;
                break;
            }
        }
        if finite {
            for q in 0..n {
                let mut acc = 0.0;
                for (j, b) in tab.b.iter().enumerate() {
                    if *b != 0.0 {
                        acc += b * self.k[j][q];
                    }
                }
                self.y_new[q] = self.y[q] + h * acc;
            }
            finite = self.y_new.iter().all(|v| v.is_finite());
        }
        if finite && tab.fsal {
            sys.rhs(t + h, &self.y_new, &mut self.k[s - 1]);
            rhs += 1;
            finite = self.k[s - 1].iter().all(|v| v.is_finite());
        }
        self.stats.rhs_evals += rhs;
        if !finite {
            return f64::INFINITY;
        }
        if !self.opts.adaptive {
            return 0.0;
        }
        let comb = |e: &[f64], k: &[Vec<f64>], out: &mut [f64]| {
            for q in 0..n {
                let mut acc = 0.0;
                for (j, ej) in e.iter().enumerate() {
                    if *ej != 0.0 {
                        acc += ej * k[j][q];
                    }
                }
                out[q] = h * acc;
            }
        };
        comb(&self.err_w, &self.k, &mut self.errv);
        let n5 = error_norm(&self.errv, &self.y, &self.y_new, &self.opts);
        if self.err_w3.is_empty() {
            return n5;
        }
        // DOP853: err = E₅² / √(E₅² + 0.01 E₃²) (HNW I §II.10; dop853.f).
        comb(&self.err_w3, &self.k, &mut self.errv3);
        let n3 = error_norm(&self.errv3, &self.y, &self.y_new, &self.opts);
        let den = (n5 * n5 + 0.01 * n3 * n3).sqrt();
        if !den.is_finite() {
            f64::INFINITY
        } else if den > 0.0 {
            n5 * n5 / den
        } else {
            0.0
        }
    }

    /// The failure when the step size cannot shrink further.
    fn too_small(&self, h: f64, nonfinite: bool) -> SolveError {
        if nonfinite {
            SolveError::NonFiniteState {
                t: self.t,
                y: self.y.clone(),
            }
        } else {
            SolveError::StepSizeTooSmall {
                t: self.t,
                h,
                y: self.y.clone(),
            }
        }
    }

    /// Computes DOP853-style extra dense stages into the cache (once per step).
    fn prepare_dense(&self) {
        let mut cache = self.dense.borrow_mut();
        if cache.ready || cache.k.is_empty() {
            return;
        }
        let DenseCache { k, ytmp, .. } = &mut *cache;
        let tab = self.tab;
        let h = self.t - self.t_prev;
        let base = tab.f_new_stage() + 1;
        let n = self.y.len();
        let mut finite = true;
        for e in 0..k.len() {
            let i = base + e;
            let row = tab.a[i];
            for q in 0..n {
                let mut acc = 0.0;
                for (j, a) in row.iter().enumerate() {
                    if *a != 0.0 {
                        let kj = if j < base {
                            self.k[j][q]
                        } else {
                            k[j - base][q]
                        };
                        acc += a * kj;
                    }
                }
                ytmp[q] = self.y_prev[q] + h * acc;
            }
            self.sys.rhs(self.t_prev + tab.c[i] * h, ytmp, &mut k[e]);
            self.pending_rhs.set(self.pending_rhs.get() + 1);
            if !k[e].iter().all(|v| v.is_finite()) {
                finite = false;
                break;
            }
        }
        cache.hermite_fallback = !finite;
        cache.ready = true;
    }
}

impl<S: OdeSystem + ?Sized> Stepper for ErkStepper<'_, S> {
    fn method(&self) -> Method {
        self.method
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
        self.flush_pending();
        if !(t_stop > self.t) {
            return Err(SolveError::InvalidOptions(format!(
                "step: stop time {t_stop} is not after t = {}",
                self.t
            )));
        }
        let tab = self.tab;
        let p_hat = tab.estimate_order;
        self.k[0].copy_from_slice(&self.f0);
        let mut h = match self.h_next {
            Some(h) => h,
            None => {
                let h = initial_step(
                    self.sys, self.t, &self.y, &self.f0, p_hat, &self.opts, t_stop,
                );
                self.stats.rhs_evals += 1;
                h
            }
        };
        if self.opts.adaptive {
            h = h.min(self.opts.h_max).max(self.opts.h_min);
        }
        let mut last_nonfinite = false;
        loop {
            if self.stats.steps >= self.opts.max_steps {
                return Err(SolveError::TooManySteps {
                    t: self.t,
                    steps: self.stats.steps,
                    y: self.y.clone(),
                });
            }
            let remaining = t_stop - self.t;
            // Land exactly on t_stop when the step would leave a sliver below 1e-10·h or
            // within 16 ulps of t_stop (a sliver no later step could take).
            let sliver = (1e-10 * h).max(16.0 * f64::EPSILON * t_stop.abs());
            let lands = remaining - h <= sliver;
            let h_try = if lands { remaining } else { h };
            let floor = 16.0 * f64::EPSILON * self.t.abs();
            if !(h_try > 0.0) || (!lands && (!(h_try > floor) || self.t + h_try == self.t)) {
                return Err(self.too_small(h_try, last_nonfinite));
            }
            let err = self.attempt(h_try);
            self.stats.steps += 1;
            let mut accepted = err <= 1.0;
            let mut err = err;
            if accepted && !tab.fsal {
                // f(t + h, y_new): the next step's first stage (and the dense output's).
                let fi = tab.f_new_stage();
                self.sys.rhs(self.t + h_try, &self.y_new, &mut self.k[fi]);
                self.stats.rhs_evals += 1;
                if !self.k[fi].iter().all(|v| v.is_finite()) {
                    accepted = false;
                    err = f64::INFINITY;
                }
            }
            if !self.opts.adaptive && !accepted {
                return Err(SolveError::NonFiniteState {
                    t: self.t,
                    y: self.y.clone(),
                });
            }
            if accepted {
                self.t_prev = self.t;
                self.t = if lands { t_stop } else { self.t + h_try };
                std::mem::swap(&mut self.y_prev, &mut self.y);
                self.y.copy_from_slice(&self.y_new);
                self.f0.copy_from_slice(&self.k[tab.f_new_stage()]);
                self.stats.accepted += 1;
                self.stats.record_step_size(h_try);
                self.h_last = Some(h_try);
                self.h_next = Some(if self.opts.adaptive {
                    self.control
                        .accept(h_try, err, p_hat)
                        .min(self.opts.h_max)
                        .max(self.opts.h_min)
                } else {
                    h
                });
                self.dense.borrow_mut().ready = false;
                return Ok(());
            }
            // Rejected by the error test (or a non-finite stage).
            last_nonfinite = !err.is_finite();
            self.stats.rejected_error += 1;
            let h_new = self.control.reject(h_try, err, p_hat);
            if self.opts.h_min > 0.0 && h_new < self.opts.h_min {
                if h_try <= self.opts.h_min {
                    return Err(self.too_small(h_new, last_nonfinite));
                }
                h = self.opts.h_min;
            } else {
                h = h_new;
            }
        }
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) {
        let h = self.t - self.t_prev;
        if h == 0.0 {
            out.copy_from_slice(&self.y);
            return;
        }
        let th = (t - self.t_prev) / h;
        let tab = self.tab;
        self.prepare_dense();
        let cache = self.dense.borrow();
        if cache.hermite_fallback {
            let fnew = &self.k[tab.f_new_stage()];
            let h00 = (1.0 + 2.0 * th) * (1.0 - th) * (1.0 - th);
            let h10 = th * (1.0 - th) * (1.0 - th);
            let h01 = th * th * (3.0 - 2.0 * th);
            let h11 = th * th * (th - 1.0);
            for (i, o) in out.iter_mut().enumerate() {
                *o = h00 * self.y_prev[i]
                    + h10 * h * self.k[0][i]
                    + h01 * self.y[i]
                    + h11 * h * fnew[i];
            }
            return;
        }
        let base = tab.f_new_stage() + 1;
        // w_j = b_j(θ) by Horner on θ·(r0 + θ(r1 + …)).
        let w: Vec<f64> = self
            .dense_w
            .iter()
            .map(|r| th * r.iter().rev().fold(0.0, |acc, c| acc * th + c))
            .collect();
        out.copy_from_slice(&self.y_prev);
        for (j, wj) in w.iter().enumerate() {
            if *wj == 0.0 {
                continue;
            }
            let kj: &[f64] = if j < base {
                &self.k[j]
            } else {
                &cache.k[j - base]
            };
            for (o, k) in out.iter_mut().zip(kj) {
                *o += h * wj * k;
            }
        }
    }

    fn restart(&mut self, t: f64, y: &[f64]) -> Result<(), SolveError> {
        self.flush_pending();
        self.t = t;
        self.t_prev = t;
        self.y.copy_from_slice(y);
        self.y_prev.copy_from_slice(y);
        self.control.reset();
        self.dense.borrow_mut().ready = false;
        self.h_next = match (self.h_last, self.opts.adaptive) {
            (_, false) => self.opts.h0,
            (Some(h), true) => Some(h.min(self.opts.h_max)),
            (None, true) => self.opts.h0,
        };
        self.eval_f0()?;
        self.k[0].copy_from_slice(&self.f0);
        Ok(())
    }

    fn stats(&self) -> &Stats {
        &self.stats
    }
    fn stats_mut(&mut self) -> &mut Stats {
        self.flush_pending();
        &mut self.stats
    }
}
