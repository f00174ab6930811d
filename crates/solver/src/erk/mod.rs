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
//! quadrature (OdeSystem::quadrature, after an accepted step, no error control):
//!   Q_{n+1} = Q_n + h Σ b_i q(t_n + c_i h, Y_i),  Y_i = y_n + h Σ_{j<i} a_ij k_j
//!   estimate |h Σ e_i q_i| (e = b − b̂; DOP853: e₅)
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
//! The step loop (step-size control, rejections, landing on the stop time, h_min/h_max,
//! budgets, failures) is the one of [`crate::onestep::OneStepDriver`]; this module supplies
//! the method: stages, error estimate and dense output ([`ErkMethod`]).
//!
//! - The first step is `opts.h0` or Hairer's starting step ([`crate::stepper::initial_step`],
//!   one extra RHS evaluation), at t0 and again after every restart.
//! - The default controller is `pi` ([`Method::default_controller`]).
//! - A non-finite stage (NaN or ±∞ in the RHS or the stage value) makes the error norm +∞:
//!   the driver rejects the attempt and shrinks the step.
//! - FSAL pairs reuse f(t + h, y_{n+1}) as the next step's first stage; DOP853 (not FSAL)
//!   evaluates f(t + h, y_{n+1}) only for an attempt that passed the error test, and a
//!   non-finite value there fails the attempt.
//! - DOP853's three extra dense-output stages are evaluated only when the dense output of a
//!   step is first used (interior mutability), and counted in the driver's `Stats::rhs_evals`
//!   from then on.

pub mod tableaus;

use std::cell::{Cell, RefCell};

pub use tableaus::{Dense, ErrorEstimate, Tableau, BS32, DOP853, DOPRI54, TSIT54};

use crate::error::SolveError;
use crate::method::{Family, Method};
use crate::onestep::{Attempt, OneStepMethod};
use crate::options::{Atol, OptionError, OptionField, Reason, Tolerances};
use crate::stats::Stats;
use crate::stepper::{error_norm, StepQuadrature};
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

/// An explicit embedded Runge–Kutta pair over a [`Tableau`], as a method of the
/// [`crate::onestep::OneStepDriver`].
///
/// ```text
/// y_{n+1} = y_n + h Σ b_i k_i,  ε = ‖h Σ e_i k_i‖,  y(t_n + θh) = y_n + h Σ b_i(θ) k_i
/// ```
/// See the [module documentation](self) for the tableaus and their sources.
pub struct ErkMethod {
    method: Method,
    tab: &'static Tableau,
    /// Dense weights r[i][m]: coefficient of θ^(m+1) in b_i(θ).
    dense_w: Vec<Vec<f64>>,
    /// f(t, y) at the current state (the next step's first stage).
    f0: Vec<f64>,
    /// Whether `f0` belongs to the current state (FSAL after an accepted step).
    f0_valid: bool,
    /// Stages of the last attempt (the last accepted step after `accept`).
    k: Vec<Vec<f64>>,
    y_new: Vec<f64>,
    ytmp: Vec<f64>,
    errv: Vec<f64>,
    errv3: Vec<f64>,
    /// Error weights e = b − b̂ (DOP853: e5).
    err_w: Vec<f64>,
    /// DOP853 only: b − b̂3.
    err_w3: Vec<f64>,
    rtol: f64,
    atol: Atol,
    dense: RefCell<DenseCache>,
    /// RHS evaluations made by the lazy dense output.
    lazy_rhs: Cell<usize>,
    /// The accepted step's h (the quadrature's).
    h_acc: f64,
    /// Scratch of the quadrature: a stage state and q there.
    quad: RefCell<(Vec<f64>, Vec<f64>)>,
}

impl ErkMethod {
    /// The pair of `method` for a system of dimension n, with tolerances `tol`.
    pub fn new(method: Method, tol: &Tolerances, n: usize) -> Result<Self, SolveError> {
        let tab = tableau_of(method).ok_or(OptionError::new(
            OptionField::Method,
            Reason::WrongFamily {
                method,
                expected: Family::Explicit.describe(),
            },
        ))?;
        Self::with_tableau(method, tol, n, tab)
    }

    /// A method for any tableau (`method` is reported by [`OneStepMethod::method`] and
    /// decides the default controller); a tableau of the wrong shape is an
    /// [`SolveError::InvalidOptions`] of the field `tableau`.
    pub fn with_tableau(
        method: Method,
        tol: &Tolerances,
        n: usize,
        tab: &'static Tableau,
    ) -> Result<Self, SolveError> {
        tab.validate()
            .map_err(|e| OptionError::new(OptionField::Tableau, Reason::Invalid(e)))?;
        let n_extra = tab.total_stages() - tab.f_new_stage() - 1;
        let (err_w, err_w3) = match tab.error {
            ErrorEstimate::Embedded { e } => (e.to_vec(), vec![]),
            ErrorEstimate::Dop853 { e5, b3 } => (
                e5.to_vec(),
                tab.b.iter().zip(b3).map(|(b, b3)| b - b3).collect(),
            ),
        };
        Ok(ErkMethod {
            method,
            tab,
            dense_w: tab.dense_weights(),
            f0: vec![0.0; n],
            f0_valid: false,
            k: vec![vec![0.0; n]; tab.f_new_stage() + 1],
            y_new: vec![0.0; n],
            ytmp: vec![0.0; n],
            errv: vec![0.0; n],
            errv3: vec![0.0; n],
            err_w,
            err_w3,
            rtol: tol.rtol(),
            atol: tol.atol().clone(),
            dense: RefCell::new(DenseCache {
                ready: false,
                k: vec![vec![0.0; n]; n_extra],
                ytmp: vec![0.0; n],
                hermite_fallback: false,
            }),
            lazy_rhs: Cell::new(0),
            h_acc: 0.0,
            quad: RefCell::new((vec![0.0; n], Vec::new())),
        })
    }

    /// The tableau this method runs.
    pub fn tableau(&self) -> &'static Tableau {
        self.tab
    }

    /// Computes DOP853-style extra dense stages into the cache (once per step).
    fn prepare_dense<S: OdeSystem + ?Sized>(&self, sys: &S, t_prev: f64, h: f64, y_prev: &[f64]) {
        let mut cache = self.dense.borrow_mut();
        if cache.ready || cache.k.is_empty() {
            return;
        }
        let DenseCache { k, ytmp, .. } = &mut *cache;
        let tab = self.tab;
        let base = tab.f_new_stage() + 1;
        let n = y_prev.len();
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
                ytmp[q] = y_prev[q] + h * acc;
            }
            sys.rhs(t_prev + tab.c[i] * h, ytmp, &mut k[e]);
            self.lazy_rhs.set(self.lazy_rhs.get() + 1);
            if !k[e].iter().all(|v| v.is_finite()) {
                finite = false;
                break;
            }
        }
        cache.hermite_fallback = !finite;
        cache.ready = true;
    }
}

impl<S: OdeSystem + ?Sized> OneStepMethod<S> for ErkMethod {
    fn method(&self) -> Method {
        self.method
    }
    fn error_order(&self) -> usize {
        self.tab.estimate_order
    }

    fn start(&mut self, sys: &S, t: f64, y: &[f64], stats: &mut Stats) -> Result<(), SolveError> {
        if !self.f0_valid {
            sys.rhs(t, y, &mut self.f0);
            stats.rhs_evals += 1;
            if !self.f0.iter().all(|v| v.is_finite()) {
                return Err(SolveError::NonFiniteState { t, y: y.to_vec() });
            }
            self.f0_valid = true;
        }
        Ok(())
    }

    fn f_start(&self) -> &[f64] {
        &self.f0
    }

    /// Fills the stages and `y_new`; returns the error norm (∞ when a stage or y_new is
    /// non-finite; 0 without estimation). DOP853 (not FSAL) also evaluates f(t + h, y_new)
    /// when the attempt passes.
    fn attempt(
        &mut self,
        sys: &S,
        t: f64,
        y: &[f64],
        h: f64,
        estimate: bool,
        stats: &mut Stats,
    ) -> Attempt {
        let tab = self.tab;
        let s = tab.stages();
        let n = y.len();
        self.k[0].copy_from_slice(&self.f0);
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
                self.ytmp[q] = y[q] + h * acc;
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
                self.y_new[q] = y[q] + h * acc;
            }
            finite = self.y_new.iter().all(|v| v.is_finite());
        }
        if finite && tab.fsal {
            sys.rhs(t + h, &self.y_new, &mut self.k[s - 1]);
            rhs += 1;
            finite = self.k[s - 1].iter().all(|v| v.is_finite());
        }
        stats.rhs_evals += rhs;
        if !finite {
            return Attempt::Error(f64::INFINITY);
        }
        let err = if estimate { self.error_norm(y, h) } else { 0.0 };
        if err <= 1.0 && !tab.fsal {
            // f(t + h, y_new): the next step's first stage (and the dense output's).
            let fi = tab.f_new_stage();
            sys.rhs(t + h, &self.y_new, &mut self.k[fi]);
            stats.rhs_evals += 1;
            if !self.k[fi].iter().all(|v| v.is_finite()) {
                return Attempt::Error(f64::INFINITY);
            }
        }
        Attempt::Error(err)
    }

    fn y_new(&self) -> &[f64] {
        &self.y_new
    }

    fn accept(&mut self, h: f64) {
        self.h_acc = h;
        self.f0.copy_from_slice(&self.k[self.tab.f_new_stage()]);
        self.f0_valid = true;
        self.dense.borrow_mut().ready = false;
    }

    fn interpolate(
        &self,
        sys: &S,
        t_prev: f64,
        h: f64,
        y_prev: &[f64],
        y: &[f64],
        th: f64,
        out: &mut [f64],
    ) {
        let tab = self.tab;
        self.prepare_dense(sys, t_prev, h, y_prev);
        let cache = self.dense.borrow();
        if cache.hermite_fallback {
            let fnew = &self.k[tab.f_new_stage()];
            let h00 = (1.0 + 2.0 * th) * (1.0 - th) * (1.0 - th);
            let h10 = th * (1.0 - th) * (1.0 - th);
            let h01 = th * th * (3.0 - 2.0 * th);
            let h11 = th * th * (th - 1.0);
            for (i, o) in out.iter_mut().enumerate() {
                *o = h00 * y_prev[i] + h10 * h * self.k[0][i] + h01 * y[i] + h11 * h * fnew[i];
            }
            return;
        }
        let base = tab.f_new_stage() + 1;
        out.copy_from_slice(y_prev);
        for (j, r) in self.dense_w.iter().enumerate() {
            // b_j(θ) = θ·(r0 + θ(r1 + …)) by Horner.
            let wj = th * r.iter().rev().fold(0.0, |acc, c| acc * th + c);
            if wj == 0.0 {
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

    /// The pair's own quadrature (module documentation): Q increments h Σ b_i q(t_n + c_i h,
    /// Y_i) and its embedded h Σ b̂_i q_i, the estimate |h Σ e_i q_i| (DOP853: e₅), at the
    /// stage states Y_i = y_n + h Σ_j a_ij k_j rebuilt from the accepted step's stages.
    fn quadrature(
        &self,
        sys: &S,
        t_prev: f64,
        y_prev: &[f64],
        value: &mut [f64],
        estimate: &mut [f64],
    ) -> StepQuadrature {
        let tab = self.tab;
        let h = self.h_acc;
        let n = y_prev.len();
        let mut guard = self.quad.borrow_mut();
        let (ys, q) = &mut *guard;
        q.resize(value.len(), 0.0);
        value.fill(0.0);
        estimate.fill(0.0);
        for i in 0..tab.stages() {
            let (b, e) = (tab.b[i], self.err_w[i]);
            if b == 0.0 && e == 0.0 {
                continue;
            }
            let row = tab.a[i];
            for l in 0..n {
                let mut acc = 0.0;
                for (j, a) in row.iter().enumerate() {
                    if *a != 0.0 {
                        acc += a * self.k[j][l];
                    }
                }
                ys[l] = y_prev[l] + h * acc;
            }
            sys.quadrature(t_prev + tab.c[i] * h, ys, q);
            for (c, qc) in q.iter().enumerate() {
                value[c] += h * b * qc;
                estimate[c] += h * e * qc;
            }
        }
        for e in estimate.iter_mut() {
            *e = e.abs();
        }
        StepQuadrature::ValueAndEstimate
    }

    fn reset(&mut self) {
        self.f0_valid = false;
        self.dense.borrow_mut().ready = false;
    }

    fn rewind(&mut self) {
        // The last accepted step's first stage is f at its start.
        self.f0.copy_from_slice(&self.k[0]);
        self.f0_valid = true;
        self.dense.borrow_mut().ready = false;
    }

    fn lazy_rhs_evals(&self) -> usize {
        self.lazy_rhs.get()
    }
}

impl ErkMethod {
    /// The error norm of the last attempt: ‖h Σ e_i k_i‖ (DOP853: E₅²/√(E₅² + 0.01 E₃²),
    /// HNW I §II.10; dop853.f).
    fn error_norm(&mut self, y: &[f64], h: f64) -> f64 {
        let n = y.len();
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
        let n5 = error_norm(&self.errv, y, &self.y_new, self.rtol, &self.atol);
        if self.err_w3.is_empty() {
            return n5;
        }
        comb(&self.err_w3, &self.k, &mut self.errv3);
        let n3 = error_norm(&self.errv3, y, &self.y_new, self.rtol, &self.atol);
        let den = (n5 * n5 + 0.01 * n3 * n3).sqrt();
        if !den.is_finite() {
            f64::INFINITY
        } else if den > 0.0 {
            n5 * n5 / den
        } else {
            0.0
        }
    }
}
