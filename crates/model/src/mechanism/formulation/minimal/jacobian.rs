//! The Jacobian ∂f/∂y of the minimal formulation, given the applied forces' ∂g/∂(q, q̇).
//!
//! ```text
//! θ̈ solves  F(y, θ̈) = Rᵀ(θ) [Q(q, q̇) − M (R θ̈ + a_c(θ, θ̇))] = 0,   ∂F/∂θ̈ = −Rᵀ M R
//! ∂θ̈/∂y_j = (Rᵀ M R)⁻¹ [ Rᵀ ∂Q/∂(q, q̇) · ∂(q, q̇)/∂y_j  +  ∂_j ρ ]
//! ρ(y) = Rᵀ(θ) [Q − M q̈(θ, θ̇; θ̈)]   with Q and θ̈ held at the evaluation's values
//! ```
//! The force part chains the closed-form ∂g/∂(q, q̇) of the clearance joints and elements
//! (mechanism/forces.rs) through ∂q/∂θ = R, ∂q̇/∂θ̇ = R, ∂q/∂θ̇ = 0 and ∂q̇/∂θ; the
//! geometric part (∂q̇/∂θ and ∂ρ) is smooth and cheap — the tree's kinematics, no force — and
//! is taken by central differences of the recursive kinematics (tree.rs), step
//! h = 6e-6 (1 + |y_j|) ≈ ε^(1/3) scale, error O(h²) ≈ 1e-10 relative. One Jacobian costs the
//! forces' ∂g plus 4n passes of the tree's kinematics and n + n solves with the factor of
//! Rᵀ M R.

use faer::MatMut;

use crate::linalg::{cholesky_solve, first_order_jacobian_frame, zeroed};
use crate::mechanism::formulation::minimal::{JacWork, Minimal};
use crate::mechanism::scratch::Scratch;

impl Minimal {
    /// ∂f/∂y (module doc) into `jac` (2n × 2n) after an evaluation; `dg` = None: the
    /// evaluation failed, the lower rows are NaN.
    pub(crate) fn jacobian(&self, sc: &Scratch, dg: Option<&[f64]>, mut jac: MatMut<'_, f64>) {
        let (nq, n) = (self.nq, self.tree.n);
        first_order_jacobian_frame(&mut jac, n, dg.is_some());
        let Some(dg) = dg else {
            return;
        };
        let w = self.work.borrow();
        let mut jw = self.jac_work.borrow_mut();
        let JacWork {
            sc: s2,
            yp,
            rp,
            qddp,
            rho,
            qd,
            dq,
            dgq,
            col,
        } = &mut *jw;
        // The prescribed bodies' kinematics (functions of t) as the evaluation left them.
        match s2 {
            Some(s2) => {
                s2.pose.copy_from_slice(&sc.pose);
                s2.vel.copy_from_slice(&sc.vel);
                s2.acc.copy_from_slice(&sc.acc);
                s2.cs.copy_from_slice(&sc.cs);
            }
            None => *s2 = Some(sc.clone()),
        }
        let s2 = s2.as_mut().expect("set above");
        let y = &w.y;
        zeroed(yp, 2 * n).copy_from_slice(y);
        zeroed(rp, nq * n);
        zeroed(qddp, nq);
        zeroed(&mut rho[0], n);
        zeroed(&mut rho[1], n);
        zeroed(&mut qd[0], nq);
        zeroed(&mut qd[1], nq);
        zeroed(dq, 2 * nq);
        zeroed(dgq, nq);
        zeroed(col, n);
        for j in 0..2 * n {
            let h = 6e-6 * (1.0 + y[j].abs());
            let mut hs = [0.0; 2];
            for (side, sign) in [(0usize, 1.0), (1, -1.0)] {
                yp[j] = y[j] + sign * h;
                hs[side] = (yp[j] - y[j]).abs();
                self.tree.positions(&yp[..n], &yp[n..], s2);
                let r = if j < n {
                    self.tree.velocity_matrix(s2, nq, rp);
                    &rp[..]
                } else {
                    &w.r[..]
                };
                self.tree.accelerations(s2, Some(&w.thdd), qddp);
                for tb in &self.tree.bodies {
                    let ii = 3 * tb.int;
                    qd[side][ii..ii + 3].copy_from_slice(&s2.vel[tb.body]);
                }
                for (a, out) in rho[side].iter_mut().enumerate() {
                    let ra = &r[a * nq..(a + 1) * nq];
                    let mut s = 0.0;
                    for i in 0..nq {
                        s += ra[i] * (sc.g[i] - self.mass[i] * qddp[i]);
                    }
                    *out = s;
                }
            }
            yp[j] = y[j];
            let hh = hs[0] + hs[1];
            // ∂(q, q̇)/∂y_j.
            if j < n {
                dq[..nq].copy_from_slice(&w.r[j * nq..(j + 1) * nq]);
                for i in 0..nq {
                    dq[nq + i] = (qd[0][i] - qd[1][i]) / hh;
                }
            } else {
                dq[..nq].fill(0.0);
                dq[nq..].copy_from_slice(&w.r[(j - n) * nq..(j - n + 1) * nq]);
            }
            // ρ' + Rᵀ ∂Q/∂(q, q̇) ∂(q, q̇)/∂y_j.
            dgq.fill(0.0);
            for (c, &d) in dq.iter().enumerate() {
                if d != 0.0 {
                    for (o, &v) in dgq.iter_mut().zip(&dg[c * nq..(c + 1) * nq]) {
                        *o += v * d;
                    }
                }
            }
            for (a, out) in col.iter_mut().enumerate() {
                let ra = &w.r[a * nq..(a + 1) * nq];
                let s: f64 = ra.iter().zip(dgq.iter()).map(|(x, y)| x * y).sum();
                *out = s + (rho[0][a] - rho[1][a]) / hh;
            }
            cholesky_solve(&w.mr, n, col);
            for (a, &v) in col.iter().enumerate() {
                jac[(n + a, j)] = v;
            }
        }
    }
}
