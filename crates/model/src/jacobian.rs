//! The Jacobian ∂f/∂y of the mechanism ODE for implicit methods.
//!
//! ```text
//! f = (q̇, q̈(t, q, q̇))      ∂f/∂y = [ 0        I        ]
//!                                   [ ∂q̈/∂q   ∂q̈/∂q̇   ]
//! ∂q̈/∂y_j ≈ (q̈(y + h_j e_j) − q̈(y − h_j e_j)) / (2 h_j),  h_j = 1e-8 · max(|y_j|, 1)
//! ```
//! The upper blocks are exact; the lower ones are central differences of the KKT solution
//! (finite differences are what MODEL.md allows for the KKT part). The step is small against
//! the penetrations of the contact law (≥ 1e-7 m in practice), so the relative truncation error
//! is about (h/δ)², and the rounding error about 1e-8 relative.

use faer::MatMut;
use lash_solver::OdeSystem;

use crate::mechanism::Mechanism;

/// Relative finite-difference step.
pub const FD_STEP: f64 = 1e-8;

/// Fills `jac` (n × n) with ∂f/∂y at (t, y).
pub(crate) fn jacobian(mech: &Mechanism, t: f64, y: &[f64], mut jac: MatMut<'_, f64>) {
    let n = y.len();
    let nq = n / 2;
    let mut yp = y.to_vec();
    let mut fp = vec![0.0; n];
    let mut fm = vec![0.0; n];
    for i in 0..n {
        for j in 0..n {
            jac[(i, j)] = 0.0;
        }
    }
    for i in 0..nq {
        jac[(i, nq + i)] = 1.0;
    }
    for j in 0..n {
        let h = FD_STEP * y[j].abs().max(1.0);
        yp[j] = y[j] + h;
        mech.rhs(t, &yp, &mut fp);
        yp[j] = y[j] - h;
        mech.rhs(t, &yp, &mut fm);
        yp[j] = y[j];
        let inv = 0.5 / h;
        for i in nq..n {
            jac[(i, j)] = (fp[i] - fm[i]) * inv;
        }
    }
}
