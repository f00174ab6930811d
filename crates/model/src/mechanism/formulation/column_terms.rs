//! One column of the differentiated KKT system M q̈ + Φ_qᵀλ = g, Φ_q q̈ = c, shared by the
//! closed-form Jacobians of the augmented Lagrangian (augmented_lagrangian/jacobian.rs, its
//! multipliers converged) and of Lagrange–Baumgarte (lagrange_baumgarte/jacobian.rs, the same
//! system with (2ξω, ω²) = (2α, β²)).

use crate::mechanism::constraints::Constraints;
use crate::mechanism::scratch::Scratch;

/// The right-hand sides of one column of the differentiated KKT system (module doc):
///
/// ```text
/// column j = q_j:  ∂F = ∂g/∂q_j − (∂Φ_q/∂q_j)ᵀ λ,   ∂C = ∂c/∂q_j − (∂Φ_q/∂q_j) q̈
/// column j = q̇_j:  ∂F = ∂g/∂q̇_j,                   ∂C = ∂c/∂q̇_j
/// ```
#[derive(Debug)]
pub(crate) struct ColumnTerms {
    /// ∂F of the last column (n_q).
    pub f: Vec<f64>,
    /// ∂C of the last column (m).
    pub c: Vec<f64>,
    dphiq: Vec<f64>,
    dcdq: Vec<f64>,
    dcdv: Vec<f64>,
    /// The rows the last column wrote (given `rows`): c and the scratch are zero elsewhere.
    touched: Vec<usize>,
}

impl ColumnTerms {
    /// Buffers for n_q coordinates and m constraint rows.
    pub(crate) fn new(nq: usize, m: usize) -> ColumnTerms {
        ColumnTerms {
            f: vec![0.0; nq],
            c: vec![0.0; m],
            dphiq: vec![0.0; m],
            dcdq: vec![0.0; m],
            dcdv: vec![0.0; m],
            touched: Vec::new(),
        }
    }

    /// Column `j` (of y = (q, q̇)) into `f` and `c`, given ∂g/∂y (`dg`, n_q × n
    /// column-major), Φ_q (`phiq`, m × n_q column-major), the multipliers `lam` and
    /// (a2, b2) = (2ξω, ω²) of c = γ − a2 Φ̇ − b2 Φ (q̈ from `sc`); false where both are zero
    /// (the column of ∂q̈ is zero). `rows`: the rows acting on the column's body, increasing,
    /// where the caller has them: then only those entries of `c` are written and every other
    /// is zero (∂Φ_q/∂y_j and Φ_q[:, j] vanish there); None: every row.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn column(
        &mut self,
        cons: &Constraints,
        sc: &Scratch,
        dg: &[f64],
        phiq: &[f64],
        lam: &[f64],
        (a2, b2): (f64, f64),
        j: usize,
        rows: Option<&[usize]>,
    ) -> bool {
        let (nq, m) = (self.f.len(), self.c.len());
        let ColumnTerms {
            f,
            c,
            dphiq,
            dcdq,
            dcdv,
            touched,
        } = self;
        let (qj, vel) = (j % nq, j >= nq);
        let (body_i, comp) = (qj / 3, qj % 3);
        let col = &phiq[qj * m..(qj + 1) * m];
        f.copy_from_slice(&dg[j * nq..(j + 1) * nq]);
        if let Some(rows) = rows {
            for &a in touched.iter() {
                (dphiq[a], dcdq[a], dcdv[a], c[a]) = (0.0, 0.0, 0.0, 0.0);
            }
            touched.clear();
            touched.extend_from_slice(rows);
            if comp == 2 {
                cons.for_point_terms_in(rows.iter().copied(), sc, body_i, |a, wa, wb, om| {
                    dphiq[a] -= wa;
                    dcdq[a] += om * om * wb + a2 * wa * om;
                    dcdv[a] += 2.0 * om * wa;
                });
            }
            if vel {
                for &a in rows {
                    c[a] = dcdv[a] - a2 * col[a];
                }
            } else {
                let u: f64 = rows.iter().map(|&a| dphiq[a] * lam[a]).sum();
                f[qj] -= u;
                let qdd = sc.qdd[qj];
                for &a in rows {
                    c[a] = dcdq[a] - b2 * col[a] - dphiq[a] * qdd;
                }
            }
            return !(f.iter().all(|&v| v == 0.0) && rows.iter().all(|&a| c[a] == 0.0));
        }
        dphiq.iter_mut().for_each(|v| *v = 0.0);
        dcdq.iter_mut().for_each(|v| *v = 0.0);
        dcdv.iter_mut().for_each(|v| *v = 0.0);
        // Per angle coordinate φ_i: the nonzero column of ∂Φ_q/∂φ_i and the velocity parts
        // of ∂c/∂φ_i and ∂c/∂φ̇_i.
        if comp == 2 {
            cons.for_point_terms_on(sc, body_i, |a, wa, wb, om| {
                dphiq[a] -= wa;
                dcdq[a] += om * om * wb + a2 * wa * om;
                dcdv[a] += 2.0 * om * wa;
            });
        }
        if vel {
            for a in 0..m {
                c[a] = dcdv[a] - a2 * col[a];
            }
        } else {
            let u: f64 = (0..m).map(|a| dphiq[a] * lam[a]).sum();
            f[qj] -= u;
            let qdd = sc.qdd[qj];
            for a in 0..m {
                c[a] = dcdq[a] - b2 * col[a] - dphiq[a] * qdd;
            }
        }
        !(f.iter().all(|&v| v == 0.0) && c.iter().all(|&v| v == 0.0))
    }
}
