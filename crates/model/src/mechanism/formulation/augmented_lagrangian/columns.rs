//! The columns of an augmented Lagrangian Jacobian: the differentiated KKT system
//!
//! ```text
//! M ∂x + Φ_qᵀ ∂λ = ∂f,   Φ_q ∂x = ∂c
//! ```
//! on any (M, Φ_q) whose A = M + αΦ_qᵀΦ_q is factored in an [`AlCore`] (absolute
//! coordinates: augmented_lagrangian/jacobian.rs; a reduced system's loop closures:
//! minimal/loops.rs). Where Φ_q has full row rank it is solved directly, every column with the
//! factor of A and one m × m Cholesky factor (the exact solution the iteration converges to):
//! ```text
//! B = A⁻¹ Φ_qᵀ (m solves),  T = Φ_q B = S (I + αS)⁻¹, S = Φ_q M⁻¹ Φ_qᵀ   (SPD)
//! per column:  z = A⁻¹ (∂f + αΦ_qᵀ ∂c),  T ∂λ = Φ_q z − ∂c,  ∂x = z − B ∂λ
//! ```
//! (A ∂x = ∂f − Φ_qᵀ∂λ + αΦ_qᵀΦ_q∂x with Φ_q∂x = ∂c.) When T has a relative Cholesky pivot
//! below `mechanism::accepted::PIVOT_MIN` (a singular configuration, redundant rows) the
//! columns are solved by the same multiplier iteration as a right-hand side (core.rs) from
//! ∂λ = 0, column by column.

use crate::linalg::{block_cholesky_inv, cholesky_solve};
use crate::mechanism::accepted::PIVOT_MIN;
use crate::mechanism::formulation::augmented_lagrangian::core::{AlCore, SparseRows};

/// B, the factor of T and whether the direct solve applies (module doc), for the columns of
/// one Jacobian.
#[derive(Clone, Debug)]
pub(crate) struct KktColumns {
    n: usize,
    m: usize,
    direct: bool,
    /// B (n × m, column-major).
    bmat: Vec<f64>,
    /// The factor of T (m × m, row-major).
    tmat: Vec<f64>,
    z: Vec<f64>,
    ac: Vec<f64>,
}

impl KktColumns {
    /// B and T for the factored `core` and the rows `rows` (m of them, over n coordinates).
    pub(crate) fn new(core: &AlCore, rows: &SparseRows, n: usize) -> KktColumns {
        let m = rows.rows();
        let mut bmat = vec![0.0; n * m];
        for a in 0..m {
            let col = &mut bmat[a * n..(a + 1) * n];
            for e in rows.start[a]..rows.start[a + 1] {
                col[rows.col[e]] += rows.val[e];
            }
            core.apply_inverse(col);
        }
        let mut tmat = vec![0.0; m * m];
        for a in 0..m {
            for b in 0..=a {
                let col = &bmat[b * n..(b + 1) * n];
                let mut v = 0.0;
                for e in rows.start[a]..rows.start[a + 1] {
                    v += rows.val[e] * col[rows.col[e]];
                }
                tmat[a * m + b] = v;
            }
        }
        let diag: Vec<f64> = (0..m).map(|a| tmat[a * m + a]).collect();
        let all: Vec<usize> = (0..m).collect();
        let direct = m > 0
            && block_cholesky_inv(&mut tmat, m, &all).is_ok()
            && (0..m).all(|a| {
                let l = tmat[a * m + a];
                1.0 / (l * l) >= PIVOT_MIN * diag[a]
            });
        KktColumns {
            n,
            m,
            direct,
            bmat,
            tmat,
            z: vec![0.0; n],
            ac: vec![0.0; m],
        }
    }

    /// Whether the columns are solved directly (T factored with every relative pivot at
    /// least `PIVOT_MIN`).
    pub(crate) fn direct(&self) -> bool {
        self.direct
    }

    /// B (n × m, column-major).
    pub(crate) fn bmat(&self) -> &[f64] {
        &self.bmat
    }

    /// The factor of T as `block_cholesky_inv` leaves it (m × m, row-major).
    pub(crate) fn tmat(&self) -> &[f64] {
        &self.tmat
    }

    /// ∂x of one column into `x` (n) from ∂f (n) and ∂c (m); `dl` (m) holds ∂λ after.
    pub(crate) fn solve(
        &mut self,
        core: &mut AlCore,
        rows: &SparseRows,
        f: &[f64],
        c: &[f64],
        dl: &mut [f64],
        x: &mut [f64],
    ) {
        let (n, m) = (self.n, self.m);
        if self.direct {
            let alpha = core.alpha;
            let z = &mut self.z;
            z.copy_from_slice(&f[..n]);
            for (v, &ci) in self.ac.iter_mut().zip(c) {
                *v = alpha * ci;
            }
            rows.mul_t_add(&self.ac, z);
            core.apply_inverse(z);
            rows.mul(z, dl);
            for (d, &ci) in dl.iter_mut().zip(c) {
                *d -= ci;
            }
            cholesky_solve(&self.tmat, m, dl);
            x[..n].copy_from_slice(z);
            for (a, &da) in dl.iter().enumerate() {
                for (xi, &bi) in x.iter_mut().zip(&self.bmat[a * n..(a + 1) * n]) {
                    *xi -= bi * da;
                }
            }
        } else {
            dl.iter_mut().for_each(|v| *v = 0.0);
            core.solve(rows, f, c, dl, x);
        }
    }
}
