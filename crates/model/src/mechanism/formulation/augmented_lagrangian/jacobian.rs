//! The Jacobian ∂f/∂y of the augmented Lagrangian formulation, given the applied forces'
//! ∂g/∂(q, q̇).
//!
//! ```text
//! at the converged (q̈, λ):  M q̈ + Φ_qᵀ λ = Q,  Φ_q q̈ = c      (c = γ − 2ξωΦ̇ − ω²Φ)
//! differentiated in y_j:    M ∂q̈ + Φ_qᵀ ∂λ = ∂Q/∂y_j − (∂Φ_q/∂y_j)ᵀ λ
//!                           Φ_q ∂q̈ = ∂c/∂y_j − (∂Φ_q/∂y_j) q̈
//! ```
//! a system of the same form, solved column by column by columns.rs (directly with
//! B = A⁻¹Φ_qᵀ and the factor of T = Φ_q B where Φ_q has full row rank, else by the
//! multiplier iteration). Where Φ_q has full row rank
//! this is the derivative of the Lagrange–Baumgarte q̈ with (α_B, β_B) = (ξω, ω)
//! (crates/model/src/mechanism/formulation/lagrange_baumgarte/jacobian.rs has the same closed
//! forms); where it has not, the derivative of the q̈ the iteration converges to.
//!
//! Closed forms (Φ_q depends on q only through the angles; a point term w · r^P has the row
//! (w_x, w_y, w · b), b = ∂(A s)/∂φ, ∂(w · b)/∂φ = −w · A s):
//! ```text
//! ∂Φ_q/∂φ_i: one nonzero column (φ_i), entries −w · A s of the point terms on body i
//! ∂c/∂q_j   = φ̇_i² (w · b) + 2ξω (w · A s) φ̇_i  [φ_i, point terms]   − ω² Φ_q[:, j]
//! ∂c/∂q̇_j   = 2 φ̇_i (w · A s)  [φ̇_i, point terms]                     − 2ξω Φ_q[:, j]
//! ```

use faer::MatMut;

use crate::linalg::first_order_jacobian_frame;
use crate::mechanism::constraints::Constraints;
use crate::mechanism::formulation::augmented_lagrangian::columns::KktColumns;
use crate::mechanism::formulation::augmented_lagrangian::{AugmentedLagrangian, Work};
use crate::mechanism::scratch::Scratch;

impl AugmentedLagrangian {
    /// ∂f/∂y (module doc) into `jac` (n × n) after an evaluation at (t, y); `dg` = None: the
    /// evaluation failed, the lower rows are NaN.
    pub(crate) fn jacobian(
        &self,
        cons: &Constraints,
        sc: &Scratch,
        dg: Option<&[f64]>,
        mut jac: MatMut<'_, f64>,
    ) {
        let nq = self.nq;
        let n = 2 * nq;
        let m = cons.len();
        first_order_jacobian_frame(&mut jac, nq, dg.is_some());
        let Some(dg) = dg else {
            return;
        };
        let mut guard = self.work.borrow_mut();
        let Work {
            rows, core, lam, ..
        } = &mut *guard;
        let lam = lam.clone();
        // Φ_q[:, j] of every column, dense (m × nq, column-major).
        let mut phiq = vec![0.0; m * nq];
        for r in 0..m {
            for e in rows.start[r]..rows.start[r + 1] {
                phiq[rows.col[e] * m + r] += rows.val[e];
            }
        }
        // Per angle coordinate φ_i: the nonzero column of ∂Φ_q/∂φ_i and the velocity parts
        // of ∂c/∂φ_i and ∂c/∂φ̇_i.
        let mut dphiq = vec![0.0; m];
        let mut dcdq = vec![0.0; m];
        let mut dcdv = vec![0.0; m];
        let mut f = vec![0.0; nq];
        let mut c = vec![0.0; m];
        let mut dl = vec![0.0; m];
        let mut x = vec![0.0; nq];
        // B and the factor of T where Φ_q has full row rank (columns.rs).
        let mut kkt = KktColumns::new(core, rows, nq);
        for j in 0..n {
            let (qj, vel) = (j % nq, j >= nq);
            let (body_i, comp) = (qj / 3, qj % 3);
            dphiq.iter_mut().for_each(|v| *v = 0.0);
            dcdq.iter_mut().for_each(|v| *v = 0.0);
            dcdv.iter_mut().for_each(|v| *v = 0.0);
            if comp == 2 {
                cons.for_point_terms_on(sc, body_i, |a, wa, wb, om| {
                    dphiq[a] -= wa;
                    dcdq[a] += om * om * wb + self.a2 * wa * om;
                    dcdv[a] += 2.0 * om * wa;
                });
            }
            let col = &phiq[qj * m..(qj + 1) * m];
            f.copy_from_slice(&dg[j * nq..(j + 1) * nq]);
            if vel {
                for a in 0..m {
                    c[a] = dcdv[a] - self.a2 * col[a];
                }
            } else {
                let u: f64 = (0..m).map(|a| dphiq[a] * lam[a]).sum();
                f[qj] -= u;
                let qdd = sc.qdd[qj];
                for a in 0..m {
                    c[a] = dcdq[a] - self.b2 * col[a] - dphiq[a] * qdd;
                }
            }
            if f.iter().all(|&v| v == 0.0) && c.iter().all(|&v| v == 0.0) {
                continue;
            }
            kkt.solve(core, rows, &f, &c, &mut dl, &mut x);
            for i in 0..nq {
                jac[(nq + i, j)] = x[i];
            }
        }
    }
}
