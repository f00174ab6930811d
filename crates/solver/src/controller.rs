//! Step-size controllers: the general Söderlind digital filter and its presets, plus the
//! separate layer of limits (safety, growth and shrink caps, dead-band, h_min, h_max).
//!
//! ```text
//! Söderlind filter (Söderlind 2003, "Digital filters in adaptive time-stepping", ACM TOMS 29(1)
//! 1–26; SUNDIALS SUNAdaptController_Soderlind, sunadaptcontroller_soderlind.c), with ε_n the
//! scaled error norm of step n (≤ 1 accepts) and k = q̂ + 1 (q̂ the order of the error
//! estimate, ARKODE's p + 1 with p the embedding order):
//!
//!   h_{n+1} = h_n · ε_n^{−k1/k} · ε_{n−1}^{−k2/k} · ε_{n−2}^{−k3/k}
//!                 · (h_n / h_{n−1})^{k4} · (h_{n−1} / h_{n−2})^{k5}
//!
//! start-up (as SUNDIALS): a preset needs m accepted steps of history, m = 2 if k3 or k5 ≠ 0,
//! else 1 if k2 or k4 ≠ 0, else 0; until it has them it is the I controller
//!   h_{n+1} = h_n · ε_n^{−1/k}
//! ```
//!
//! The controller only proposes a raw factor; [`StepLimits`] applies the safety factor and the
//! caps. History is committed only after a step is accepted ([`Controller::accept`]), so a
//! rejected step never pollutes it (SUNDIALS calls `UpdateH` only on accepted steps). Error
//! norms are floored at 1e-10 before taking powers, so an exact step (ε = 0) gives a finite
//! factor that the growth cap then limits.

/// The controller presets. Names are the contract of docs/outputs.md ("Method and controller
/// names").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ControllerKind {
    /// Integral (elementary) controller, k = (1, 0, 0, 0, 0):
    /// ```text
    /// h_{n+1} = h_n ε_n^{−1/k}
    /// ```
    /// HNW I (4.13); SUNDIALS `SUNAdaptController_I` (DEFAULT_I_K1 = 1).
    I,
    /// PI controller, k = (0.8, −0.31, 0, 0, 0):
    /// ```text
    /// h_{n+1} = h_n ε_n^{−0.8/k} ε_{n−1}^{0.31/k}
    /// ```
    /// SUNDIALS `SUNAdaptController_PI` defaults (DEFAULT_PI_K1 = 0.8, DEFAULT_PI_K2 = −0.31;
    /// the PI structure of Gustafsson 1991, ACM TOMS 17(4) 533–554, and Söderlind 2003).
    Pi,
    /// PID controller, k = (0.58, −0.21, 0.1, 0, 0):
    /// ```text
    /// h_{n+1} = h_n ε_n^{−0.58/k} ε_{n−1}^{0.21/k} ε_{n−2}^{−0.1/k}
    /// ```
    /// SUNDIALS `SUNAdaptController_PID` defaults (DEFAULT_PID_K1..K3).
    Pid,
    /// Söderlind's H211b digital filter with b = 4, k = (1/4, 1/4, 0, −1/4, 0):
    /// ```text
    /// h_{n+1} = h_n ε_n^{−1/(4k)} ε_{n−1}^{−1/(4k)} (h_n/h_{n−1})^{−1/4}
    /// ```
    /// Söderlind 2003, ACM TOMS 29(1), H211b (β₁ = β₂ = 1/b, α₂ = 1/b);
    /// SUNDIALS `SUNAdaptController_H211`.
    H211,
    /// Söderlind's H312b digital filter with b = 8, k = (1/8, 2/8, 1/8, −3/8, −1/8):
    /// ```text
    /// h_{n+1} = h_n (ε_n ε_{n−1}² ε_{n−2})^{−1/(8k)} (h_n/h_{n−1})^{−3/8} (h_{n−1}/h_{n−2})^{−1/8}
    /// ```
    /// Söderlind 2003, ACM TOMS 29(1), H312b (β = (1, 2, 1)/b, α = (3, 1)/b);
    /// SUNDIALS `SUNAdaptController_H312`.
    H312,
    /// Gustafsson's predictive controller for implicit methods, k = (1.93, −0.95, 0, 1, 0):
    /// ```text
    /// h_{n+1} = h_n (h_n/h_{n−1}) ε_n^{−k̂1/k} (ε_n/ε_{n−1})^{−k̂2/k},  k̂1 = 0.98, k̂2 = 0.95
    ///         ⇔ k1 = k̂1 + k̂2 = 1.93, k2 = −k̂2 = −0.95, k4 = 1
    /// ```
    /// Gustafsson 1994, ACM TOMS 20(4) 496–512; SUNDIALS `SUNAdaptController_ImpGus`
    /// (DEFAULT_IMPGUS_K1 = 0.98, DEFAULT_IMPGUS_K2 = 0.95, SetParams_ImpGus mapping).
    Gustafsson,
}

impl ControllerKind {
    /// All presets.
    pub const ALL: [ControllerKind; 6] = [
        ControllerKind::I,
        ControllerKind::Pi,
        ControllerKind::Pid,
        ControllerKind::H211,
        ControllerKind::H312,
        ControllerKind::Gustafsson,
    ];

    /// Name in the CLI and summary.json.
    pub fn name(self) -> &'static str {
        match self {
            ControllerKind::I => "i",
            ControllerKind::Pi => "pi",
            ControllerKind::Pid => "pid",
            ControllerKind::H211 => "h211",
            ControllerKind::H312 => "h312",
            ControllerKind::Gustafsson => "gustafsson",
        }
    }

    /// Parses a controller name.
    pub fn from_name(s: &str) -> Option<ControllerKind> {
        ControllerKind::ALL.into_iter().find(|c| c.name() == s)
    }

    /// The five Söderlind coefficients (k1, k2, k3, k4, k5) of this preset.
    pub fn coefficients(self) -> [f64; 5] {
        match self {
            ControllerKind::I => [1.0, 0.0, 0.0, 0.0, 0.0],
            ControllerKind::Pi => [0.8, -0.31, 0.0, 0.0, 0.0],
            ControllerKind::Pid => [0.58, -0.21, 0.1, 0.0, 0.0],
            ControllerKind::H211 => [0.25, 0.25, 0.0, -0.25, 0.0],
            ControllerKind::H312 => [0.125, 0.25, 0.125, -0.375, -0.125],
            ControllerKind::Gustafsson => [1.93, -0.95, 0.0, 1.0, 0.0],
        }
    }

    /// A fresh controller of this preset.
    pub fn build(self) -> Soderlind {
        Soderlind::new(self.coefficients())
    }
}

impl std::fmt::Display for ControllerKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A step-size controller: proposes, then commits history on acceptance.
pub trait Controller {
    /// Raw step factor h_{n+1}/h_n proposed after a step of size `h` whose scaled error norm is
    /// `err` (> 0; ≤ 1 means accepted), for an error estimate of order `p_hat` (exponent
    /// 1/(p_hat + 1)). Does not change history.
    fn factor(&self, h: f64, err: f64, p_hat: usize) -> f64;
    /// Commits (h, err) of an accepted step to the history.
    fn accept(&mut self, h: f64, err: f64);
    /// Forgets the history (after an event, a restart, or a change of order).
    fn reset(&mut self);
}

/// The general Söderlind filter with five coefficients.
///
/// ```text
/// h_{n+1}/h_n = ε_n^{−k1/k} ε_{n−1}^{−k2/k} ε_{n−2}^{−k3/k} (h_n/h_{n−1})^{k4} (h_{n−1}/h_{n−2})^{k5}
/// (ε_n^{−1/k} until `history_needed()` steps have been accepted)
/// ```
/// Söderlind 2003; SUNDIALS `SUNAdaptController_EstimateStep_Soderlind`.
#[derive(Clone, Debug, PartialEq)]
pub struct Soderlind {
    /// Coefficients (k1, …, k5).
    pub k: [f64; 5],
    /// ε_{n−1}, ε_{n−2} of accepted steps (None until known).
    err_hist: [Option<f64>; 2],
    /// h_{n−1}, h_{n−2} of accepted steps.
    h_hist: [Option<f64>; 2],
    /// Accepted steps since the start or the last reset, capped at `history_needed()`.
    accepted: usize,
}

impl Soderlind {
    /// A controller with the given coefficients and empty history.
    pub fn new(k: [f64; 5]) -> Self {
        Soderlind {
            k,
            err_hist: [None; 2],
            h_hist: [None; 2],
            accepted: 0,
        }
    }

    /// Accepted steps of history the full filter needs: 2 if k3 or k5 ≠ 0, else 1 if k2 or
    /// k4 ≠ 0, else 0 (SUNDIALS' `historysize`).
    pub fn history_needed(&self) -> usize {
        let [_, k2, k3, k4, k5] = self.k;
        if k3 != 0.0 || k5 != 0.0 {
            2
        } else if k2 != 0.0 || k4 != 0.0 {
            1
        } else {
            0
        }
    }
}

/// Floor on error norms before taking powers (an exact step would give ε = 0).
const ERR_FLOOR: f64 = 1e-10;

impl Controller for Soderlind {
    fn factor(&self, h: f64, err: f64, p_hat: usize) -> f64 {
        let ord = (p_hat + 1) as f64;
        let e0 = err.max(ERR_FLOOR);
        let need = self.history_needed();
        if self.accepted < need {
            // Not enough history: the I controller (SUNDIALS falls back the same way).
            return e0.powf(-1.0 / ord);
        }
        let [k1, k2, k3, k4, k5] = self.k;
        let mut fac = e0.powf(-k1 / ord);
        if need >= 1 {
            let e1 = self.err_hist[0].unwrap_or(e0);
            let h1 = self.h_hist[0].unwrap_or(h);
            fac *= e1.powf(-k2 / ord) * (h / h1).powf(k4);
        }
        if need >= 2 {
            let e2 = self.err_hist[1].unwrap_or(e0);
            let h1 = self.h_hist[0].unwrap_or(h);
            let h2 = self.h_hist[1].unwrap_or(h1);
            fac *= e2.powf(-k3 / ord) * (h1 / h2).powf(k5);
        }
        fac
    }

    fn accept(&mut self, h: f64, err: f64) {
        self.err_hist = [Some(err.max(ERR_FLOOR)), self.err_hist[0]];
        self.h_hist = [Some(h), self.h_hist[0]];
        if self.accepted < self.history_needed() {
            self.accepted += 1;
        }
    }

    fn reset(&mut self) {
        self.err_hist = [None; 2];
        self.h_hist = [None; 2];
        self.accepted = 0;
    }
}

/// Limits applied around any controller (ARKODE's adaptivity layer, arkode_adapt.c).
///
/// ```text
/// accepted step:  η = clamp(safety · controller factor, min_shrink, cap)
///                 cap = max_first_growth (first step), max_growth_after_reject (after a
///                 rejection), max_growth (otherwise); η ∈ deadband → η = 1
/// rejected step:  η = clamp(safety · ε^(−1/k), min_shrink, max_after_reject)
///                 (max_after_repeated_reject from the second failure in a row on)
/// ```
/// A rejected step uses the elementary controller, as Hairer's codes do (HNW I §II.4);
/// ARKODE applies its full filter there too (arkCheckTemporalError → arkAdapt).
/// safety, max_first_growth (etamx1) and max_after_repeated_reject (etamxf after small_nef = 2
/// failures) are ARKODE's defaults; ARKODE grows by at most 20 and shrinks by at least 0.1,
/// the defaults here (5, 0.2) are the tighter bounds of Hairer's codes (HNW I §II.4).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StepLimits {
    /// Safety factor multiplying every proposed factor. Default 0.9; range (0, 1].
    pub safety: f64,
    /// Largest growth factor after an accepted step. Default 5; > 1.
    pub max_growth: f64,
    /// Largest growth factor on the first accepted step. Default 10 000 (ARKODE's etamx1); > 1.
    pub max_first_growth: f64,
    /// Smallest factor (largest shrink) after any step. Default 0.2; range (0, 1).
    pub min_shrink: f64,
    /// Largest factor after a rejected step. Default 0.9; range (0, 1].
    pub max_after_reject: f64,
    /// Largest factor after an accepted step that directly follows a rejection. Default 1.
    pub max_growth_after_reject: f64,
    /// Largest factor after two or more error-test failures in a row. Default 0.3 (ARKODE
    /// etamxf).
    pub max_after_repeated_reject: f64,
    /// Dead-band: factors inside [lower, upper] keep h unchanged (saves Jacobian refactoring).
    /// Default (1, 1) (no dead-band); lower ≤ 1 ≤ upper.
    pub deadband: (f64, f64),
}

impl Default for StepLimits {
    fn default() -> Self {
        StepLimits {
            safety: 0.9,
            max_growth: 5.0,
            max_first_growth: 10_000.0,
            min_shrink: 0.2,
            max_after_reject: 0.9,
            max_growth_after_reject: 1.0,
            max_after_repeated_reject: 0.3,
            deadband: (1.0, 1.0),
        }
    }
}

/// A controller with its limits and the per-solve counters the limits need: what every
/// adaptive stepper of this crate holds.
///
/// ```text
/// h_next = h · clamp(safety · C(h, ε, history), limits)   (see [`StepLimits`])
/// ```
/// The proposal/commit split of SUNDIALS' SUNAdaptController (EstimateStep, UpdateH).
pub struct StepSizeControl {
    controller: Box<dyn Controller>,
    limits: StepLimits,
    /// Error-test failures in a row on the current step.
    rejects_in_row: usize,
    /// Whether the previous attempt was rejected (caps the growth of the next accepted step).
    after_reject: bool,
    /// Whether no step has been accepted since the start or the last reset.
    first: bool,
}

impl StepSizeControl {
    /// Wraps a controller with limits.
    pub fn new(controller: Box<dyn Controller>, limits: StepLimits) -> Self {
        StepSizeControl {
            controller,
            limits,
            rejects_in_row: 0,
            after_reject: false,
            first: true,
        }
    }

    /// The limits in force.
    pub fn limits(&self) -> &StepLimits {
        &self.limits
    }

    /// After an accepted step of size `h` with error `err` (≤ 1): commits history and returns the
    /// next step size (before h_min/h_max clipping, which the stepper does).
    pub fn accept(&mut self, h: f64, err: f64, p_hat: usize) -> f64 {
        let l = &self.limits;
        let mut fac = l.safety * self.controller.factor(h, err, p_hat);
        let cap = if self.first {
            l.max_first_growth
        } else if self.after_reject {
            l.max_growth_after_reject
        } else {
            l.max_growth
        };
        fac = fac.clamp(l.min_shrink, cap);
        if fac >= l.deadband.0 && fac <= l.deadband.1 {
            fac = 1.0;
        }
        self.controller.accept(h, err);
        self.rejects_in_row = 0;
        self.after_reject = false;
        self.first = false;
        h * fac
    }

    /// After a step of size `h` rejected by the error test with error `err` (> 1): returns the
    /// step size to retry with. History is not touched.
    pub fn reject(&mut self, h: f64, err: f64, p_hat: usize) -> f64 {
        let l = &self.limits;
        self.rejects_in_row += 1;
        self.after_reject = true;
        let cap = if self.rejects_in_row >= 2 {
            l.max_after_repeated_reject
        } else {
            l.max_after_reject
        };
        // The rejected step uses the elementary controller: the filter's history belongs to
        // accepted steps only.
        let ord = (p_hat + 1) as f64;
        let fac = (l.safety * err.max(ERR_FLOOR).powf(-1.0 / ord)).clamp(l.min_shrink, cap);
        h * fac
    }

    /// After a step rejected for another reason (Newton failure): shrink by a quarter.
    pub fn reject_newton(&mut self, h: f64) -> f64 {
        self.after_reject = true;
        h * 0.25
    }

    /// Forgets all history (event restart).
    pub fn reset(&mut self) {
        self.controller.reset();
        self.rejects_in_row = 0;
        self.after_reject = false;
        self.first = true;
    }
}
