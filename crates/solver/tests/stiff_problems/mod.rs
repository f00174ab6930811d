//! Problems with closed-form solutions shared by the stiff-method tests.

#![allow(dead_code)]

use faer::MatMut;
use lash_solver::*;

/// Every stiff method.
pub const STIFF: [Method; 4] = [
    Method::Bdf,
    Method::Trbdf2,
    Method::Esdirk34,
    Method::Rodas5p,
];

/// Stiff linear system y' = A y with A = [[−2500.5, 2499.5], [2499.5, −2500.5]]: eigenvalues
/// −1 (eigenvector (1, 1)) and −5000 (eigenvector (1, −1)). From y(0) = (2, 0):
/// y(t) = e^{−t} (1, 1) + e^{−5000 t} (1, −1). Analytic Jacobian, autonomous.
pub struct StiffLinear;

impl StiffLinear {
    pub const Y0: [f64; 2] = [2.0, 0.0];
    pub fn exact(t: f64) -> [f64; 2] {
        let (slow, fast) = ((-t).exp(), (-5000.0 * t).exp());
        [slow + fast, slow - fast]
    }
}

impl OdeSystem for StiffLinear {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = -2500.5 * y[0] + 2499.5 * y[1];
        dy[1] = 2499.5 * y[0] - 2500.5 * y[1];
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], mut jac: MatMut<'_, f64>) {
        jac[(0, 0)] = -2500.5;
        jac[(0, 1)] = 2499.5;
        jac[(1, 0)] = 2499.5;
        jac[(1, 1)] = -2500.5;
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

/// Prothero–Robinson: y' = λ (y − cos t) − sin t, λ = −10⁶, y(0) = 1, exact y = cos t
/// (Prothero & Robinson 1974). Non-autonomous, no Jacobian: the methods use finite
/// differences for ∂f/∂y (and Rodas5P for ∂f/∂t).
pub struct ProtheroRobinson;

impl OdeSystem for ProtheroRobinson {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = -1e6 * (y[0] - t.cos()) - t.sin();
    }
}

/// Prothero–Robinson y' = λ(y − sin t) + cos t, y(0) = 0, exact solution sin t (HNW II,
/// §IV.15) with the rate λ a parameter and the analytic Jacobian; forced, so Rodas5P
/// uses ∂f/∂t (by differences).
pub struct ForcedSine(pub f64);

impl OdeSystem for ForcedSine {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = self.0 * (y[0] - t.sin()) + t.cos();
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], mut jac: MatMut<'_, f64>) {
        jac[(0, 0)] = self.0;
    }
}

/// Logistic growth y' = y (1 − y), y(0) = 0.1: y(t) = 1 / (1 + 9 e^{−t}). Analytic Jacobian,
/// autonomous.
pub struct Logistic;

impl Logistic {
    pub fn exact(t: f64) -> f64 {
        1.0 / (1.0 + 9.0 * (-t).exp())
    }
}

impl OdeSystem for Logistic {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[0] * (1.0 - y[0]);
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, y: &[f64], mut jac: MatMut<'_, f64>) {
        jac[(0, 0)] = 1.0 - 2.0 * y[0];
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

/// y' = −y for t ≤ 1; the right-hand side is NaN beyond t = 1 (a system that cannot be
/// evaluated there).
pub struct Cliff;

impl OdeSystem for Cliff {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = if t > 1.0 { f64::NAN } else { -y[0] };
    }
}

/// y' = −y with a Jacobian that is NaN: no implicit method can solve its stage equations.
pub struct NanJacobian;

impl OdeSystem for NanJacobian {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = -y[0];
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], mut jac: MatMut<'_, f64>) {
        jac[(0, 0)] = f64::NAN;
    }
}

/// Options for `method` at rtol, atol.
pub fn opts(method: Method, rtol: f64, atol: f64) -> SolverOptions {
    SolverOptions {
        method,
        rtol,
        atol: Atol::Scalar(atol),
        ..Default::default()
    }
}
