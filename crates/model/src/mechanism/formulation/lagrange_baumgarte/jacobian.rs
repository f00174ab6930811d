//! The Jacobian ∂f/∂y of the Lagrange–Baumgarte formulation (docs/model.md §1.7), given the
//! applied forces' ∂g/∂(q, q̇) (the clearance joints and force elements give it).
//!
//! ```text
//! f = (q̇, q̈(t, q, q̇)),   ∂f/∂y = [ 0        I       ]
//!                                 [ ∂q̈/∂q   ∂q̈/∂q̇  ]
//! at the evaluation:         M q̈ + Φ_qᵀ λ = g,   Φ_q q̈ = r,   r = γ − 2αΦ̇ − β²Φ
//! differentiated in y_j:     M ∂q̈ + Φ_qᵀ ∂λ = ∂F,  Φ_q ∂q̈ = ∂C
//!   ∂F = ∂g/∂y_j − (∂Φ_q/∂y_j)ᵀ λ,   ∂C = ∂r/∂y_j − (∂Φ_q/∂y_j) q̈
//! solved through two operators, built once per Jacobian:
//!   ∂q̈ = N ∂F + Wᵀ ∂C,   G = Φ_q M⁻¹,  W = S⁻¹ G  (m × n_q),  N = M⁻¹ − Gᵀ W  (n_q × n_q)
//! ```
//! ∂F and ∂C of each column in closed form (augmented_lagrangian/jacobian.rs, `ColumnTerms`:
//! the same system with (2ξω, ω²) = (2α, β²); Φ_q depends on q only through the angles, a
//! point term w · r^P having the row (w_x, w_y, w · b), b = ∂(A s)/∂φ, ∂(w · b)/∂φ = −w · A s).
//! W by the evaluation's envelope factor of S on all n_q right-hand sides at once
//! (`Envelope::solve_rows`: a chain's S is banded, so O(m n_q)); N by the sparse rows of Φ_q
//! (at most six entries each). Both ∂F and ∂C are sparse (a force couples few bodies, a row of
//! Φ_q acts on at most two), so every column of ∂q̈ is a sum of a few rows of N and W: the
//! Jacobian costs O(n n_q) products beyond the evaluation. docs/model.md §1 (1.7) allows finite
//! differences for the constraint part; the closed forms are exact. Before (BENCHMARKS.md,
//! "Minimal with loop closures"): S⁻¹ by m scalar envelope solves, P = M⁻¹Φ_qᵀS⁻¹, and per-column scalar
//! loops, 10.7 right-hand sides on Andrews' mechanism.

use faer::reborrow::ReborrowMut;
use faer::MatMut;

use crate::linalg::{first_order_jacobian_frame, zeroed};
use crate::mechanism::constraints::Constraints;
use crate::mechanism::formulation::column_terms::ColumnTerms;
use crate::mechanism::formulation::lagrange_baumgarte::{JacWork, LagrangeBaumgarte};
use crate::mechanism::scratch::Scratch;

impl LagrangeBaumgarte {
    /// The lower blocks of ∂f/∂y (y = (q, q̇), f = (q̇, q̈)) into `jac` (n × n, its upper
    /// blocks [0 I] set too), after an evaluation at (t, y) (the kinematics and q̈ in `sc`, λ
    /// and the factor of S in the work), given `dg` = ∂g/∂(q, q̇) of the applied forces
    /// (n_q × n, column-major); `dg` = None: the evaluation failed, the lower rows are NaN.
    ///
    /// Through the operators N and W of the module doc.
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
        // Every body prescribed (n_q = 0): an empty Jacobian.
        let (Some(dg), true) = (dg, nq > 0) else {
            return;
        };
        let mut w0 = self.work.borrow_mut();
        self.dense_constraint_jacobian(cons, &mut w0);
        let mut work = self.jac_work.borrow_mut();
        let JacWork {
            w,
            nmat,
            low,
            phiq,
            terms,
        } = &mut *work;
        // W = S⁻¹ G, G = Φ_q M⁻¹ (m × n_q, row-major).
        let w = zeroed(w, m * nq);
        for (a, wa) in w.chunks_exact_mut(nq).enumerate() {
            for ((x, p), mi) in wa.iter_mut().zip(&w0.jac[a * nq..]).zip(&self.minv) {
                *x = p * mi;
            }
        }
        self.env.solve_rows(&w0.smat, w, nq);
        // N = M⁻¹ − Gᵀ W (n_q × n_q, symmetric; row i = column i), over Φ_q's nonzero entries.
        let nmat = zeroed(nmat, nq * nq);
        for (i, mi) in self.minv[..nq].iter().enumerate() {
            nmat[i * nq + i] = *mi;
        }
        for a in 0..m {
            let wa = &w[a * nq..(a + 1) * nq];
            for c in self.row_columns(cons, a) {
                let g = w0.jac[a * nq + c] * self.minv[c];
                if g != 0.0 {
                    for (x, v) in nmat[c * nq..(c + 1) * nq].iter_mut().zip(wa) {
                        *x -= g * v;
                    }
                }
            }
        }
        // Φ_q column-major for the columns' terms.
        let phiq = zeroed(phiq, m * nq);
        for a in 0..m {
            for c in self.row_columns(cons, a) {
                phiq[c * m + a] = w0.jac[a * nq + c];
            }
        }
        let terms = terms.get_or_insert_with(|| ColumnTerms::new(nq, m));
        let ab = (2.0 * self.alpha, self.beta * self.beta);
        let low = zeroed(low, nq);
        for j in 0..n {
            let rows = &self.rows_of_body[(j % nq) / 3];
            if !terms.column(cons, sc, dg, phiq, &w0.lam, ab, j, Some(rows)) {
                continue;
            }
            // ∂q̈_j = N ∂F + Wᵀ ∂C: the rows of N and W at the nonzero entries (a column of
            // ∂g that is not finite spreads its NaN through N).
            low.fill(0.0);
            for (i, &fi) in terms.f.iter().enumerate() {
                if fi != 0.0 {
                    for (x, v) in low.iter_mut().zip(&nmat[i * nq..(i + 1) * nq]) {
                        *x += fi * v;
                    }
                }
            }
            for &a in rows {
                let ca = terms.c[a];
                if ca != 0.0 {
                    for (x, v) in low.iter_mut().zip(&w[a * nq..(a + 1) * nq]) {
                        *x += ca * v;
                    }
                }
            }
            let mut col = jac.rb_mut().col_mut(j).subrows_mut(nq, nq);
            for (i, &x) in low.iter().enumerate() {
                col[i] = x;
            }
        }
    }

    /// The columns of row `a` of Φ_q on integrated bodies, increasing (three per body).
    fn row_columns(&self, cons: &Constraints, a: usize) -> impl Iterator<Item = usize> {
        let mut b = cons.row_int[a];
        if let [Some(x), Some(y)] = b {
            if x == y {
                b[1] = None;
            } else if y < x {
                b = [Some(y), Some(x)];
            }
        }
        b.into_iter().flatten().flat_map(|i| 3 * i..3 * i + 3)
    }
}
