//! Integration counters, one serialisable struct (names follow CVODE's counters where one
//! exists). `Stats` is `Copy` and is read by value: asking for the counters never changes them.

/// Counters of one integration.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Stats {
    /// Step attempts (accepted + rejected); CVODE `nst` counts accepted only.
    pub steps: usize,
    /// Accepted steps (CVODE `nst`).
    pub accepted: usize,
    /// Steps rejected by the error test (CVODE `netf`).
    pub rejected_error: usize,
    /// Steps rejected because the Newton iteration failed (CVODE `ncfn`).
    pub rejected_newton: usize,
    /// Right-hand-side evaluations, finite-difference Jacobian columns included (CVODE `nfe`).
    pub rhs_evals: usize,
    /// Jacobian evaluations, analytic or by finite differences (CVODE `nje`).
    pub jac_evals: usize,
    /// LU factorisations (CVODE `nsetups`, roughly).
    pub lu_factorizations: usize,
    /// Newton iterations (CVODE `nni`).
    pub newton_iters: usize,
    /// Evaluations of the vector of event functions (CVODE `nge`).
    pub event_evals: usize,
    /// Events located.
    pub events: usize,
    /// Smallest accepted step (0 when no step was accepted).
    pub h_min_used: f64,
    /// Largest accepted step.
    pub h_max_used: f64,
}

impl Stats {
    /// Records an accepted step of size `h` in the min/max step counters.
    pub fn record_step_size(&mut self, h: f64) {
        let h = h.abs();
        self.h_min_used = if self.h_min_used == 0.0 {
            h
        } else {
            self.h_min_used.min(h)
        };
        self.h_max_used = self.h_max_used.max(h);
    }
}
