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
//! multiplier iteration; from `BATCHED_MIN_CONSTRAINTS` rows on, the direct solve's columns in
//! batches, below). Where Φ_q has full row rank
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

use faer::reborrow::{Reborrow, ReborrowMut};
use faer::MatMut;

use crate::linalg::{block_cholesky_inv, first_order_jacobian_frame};
use crate::mechanism::accepted::PIVOT_MIN;
use crate::mechanism::constraints::Constraints;
use crate::mechanism::formulation::augmented_lagrangian::columns::KktColumns;
use crate::mechanism::formulation::augmented_lagrangian::core::{AlCore, SparseRows};
use crate::mechanism::formulation::augmented_lagrangian::{AugmentedLagrangian, Work};
use crate::mechanism::formulation::column_terms::ColumnTerms;
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
        let mut terms = ColumnTerms::new(nq, m);
        let mut dl = vec![0.0; m];
        let mut x = vec![0.0; nq];
        // B and the factor of T where Φ_q has full row rank (columns.rs).
        // Below the batched size, the direct solve as two operators and every column through
        // one matrix product (`Operators`); otherwise, or where T is not well conditioned,
        // B and the factor of T (columns.rs) for the columns one at a time or in batches.
        let mut ops = (m < BATCHED_MIN_CONSTRAINTS)
            .then(|| Operators::new(core, rows, nq, m, n))
            .flatten();
        let mut kkt = ops.is_none().then(|| KktColumns::new(core, rows, nq));
        let alpha = core.alpha;
        let mut batch = kkt
            .as_ref()
            .filter(|k| k.direct() && m >= BATCHED_MIN_CONSTRAINTS)
            .map(|k| Batch::new(k.tmat(), nq, m));
        for j in 0..n {
            if !terms.column(cons, sc, dg, &phiq, &lam, (self.a2, self.b2), j, None) {
                continue;
            }
            let (f, c) = (&terms.f, &terms.c);
            if let Some(o) = ops.as_mut() {
                o.push(j, f, c);
                continue;
            }
            let Some(kkt) = kkt.as_mut() else { continue };
            if let Some(b) = batch.as_mut() {
                b.push(j, f, c);
                if b.cols.len() == BATCH_COLUMNS {
                    b.flush(core, rows, kkt.bmat(), alpha, &mut jac);
                }
                continue;
            }
            kkt.solve(core, rows, f, c, &mut dl, &mut x);
            for i in 0..nq {
                jac[(nq + i, j)] = x[i];
            }
        }
        if let (Some(b), Some(kkt)) = (batch.as_mut(), kkt.as_ref()) {
            b.flush(core, rows, kkt.bmat(), alpha, &mut jac);
        }
        if let Some(o) = ops {
            o.finish(&mut jac);
        }
    }
}

/// The direct solve (columns.rs) as two operators, for the Jacobian's columns at once:
///
/// ```text
/// ∂x = z − B ∂λ,  z = A⁻¹(∂f + αΦ_qᵀ∂c),  T ∂λ = Φ_q z − ∂c = Bᵀ∂f + αT∂c − ∂c
///    = (A⁻¹ − B T⁻¹ Bᵀ) ∂f + B T⁻¹ ∂c  =  N ∂f + Wᵀ ∂c,   W = T⁻¹ Bᵀ  (Φ_q A⁻¹ = Bᵀ)
/// ```
/// built from A⁻¹ (n_q solves with A's factor), B = A⁻¹Φ_qᵀ and T = Φ_q B over Φ_q's nonzero
/// entries, T's Cholesky factor and two triangular solves on Bᵀ (faer's); the columns are then
/// one matrix product [N Wᵀ] [∂F; ∂C]. The column-by-column solve spent one solve with A, two
/// triangular solves with T and a product with B per column, in dependent scalar loops
/// (Andrews' mechanism: 42 columns, n_q = 21, m = 20).
struct Operators {
    /// [N Wᵀ] (n_q × (n_q + m)).
    nw: faer::Mat<f64>,
    /// [∂F; ∂C] of every column (n_q + m) × n, zero where a column was skipped.
    rhs: faer::Mat<f64>,
}

impl Operators {
    /// The operators at the factored `core` and the rows `rows`; None where Φ_q has no rows
    /// or T's Cholesky factor has a relative pivot below `PIVOT_MIN` (a singular
    /// configuration, redundant rows: the multiplier iteration solves the columns, as in
    /// columns.rs).
    fn new(core: &AlCore, rows: &SparseRows, nq: usize, m: usize, n: usize) -> Option<Self> {
        if m == 0 {
            return None;
        }
        let mut nw = faer::Mat::<f64>::zeros(nq, nq + m);
        // A⁻¹ into N's block (symmetric: column c is row c).
        let mut e = vec![0.0; nq];
        for i in 0..nq {
            e.iter_mut().for_each(|v| *v = 0.0);
            e[i] = 1.0;
            core.apply_inverse(&mut e);
            for (k, &v) in e.iter().enumerate() {
                nw[(k, i)] = v;
            }
        }
        // B = A⁻¹ Φ_qᵀ (n_q × m).
        let mut b = faer::Mat::<f64>::zeros(nq, m);
        for a in 0..m {
            for el in rows.start[a]..rows.start[a + 1] {
                let (c, v) = (rows.col[el], rows.val[el]);
                for k in 0..nq {
                    b[(k, a)] += v * nw[(k, c)];
                }
            }
        }
        // T = Φ_q B (lower triangle, row-major, as block_cholesky_inv takes it).
        let mut t = vec![0.0; m * m];
        for a in 0..m {
            for bb in 0..=a {
                let mut v = 0.0;
                for el in rows.start[a]..rows.start[a + 1] {
                    v += rows.val[el] * b[(rows.col[el], bb)];
                }
                t[a * m + bb] = v;
            }
        }
        let diag: Vec<f64> = (0..m).map(|a| t[a * m + a]).collect();
        let all: Vec<usize> = (0..m).collect();
        if block_cholesky_inv(&mut t, m, &all).is_err()
            || (0..m).any(|a| {
                let l = t[a * m + a];
                !(1.0 / (l * l) >= PIVOT_MIN * diag[a])
            })
        {
            return None;
        }
        let l = faer::Mat::from_fn(m, m, |i, j| match j.cmp(&i) {
            std::cmp::Ordering::Less => t[i * m + j],
            std::cmp::Ordering::Equal => 1.0 / t[i * m + i],
            std::cmp::Ordering::Greater => 0.0,
        });
        // W = T⁻¹ Bᵀ (m × n_q).
        let mut w = b.transpose().to_owned();
        let par = faer::Par::Seq;
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(
            l.as_ref(),
            w.as_mut(),
            par,
        );
        faer::linalg::triangular_solve::solve_upper_triangular_in_place(
            l.transpose(),
            w.as_mut(),
            par,
        );
        // N = A⁻¹ − B W; Wᵀ beside it.
        let (mut nblk, mut wt) = nw.as_mut().split_at_col_mut(nq);
        faer::linalg::matmul::matmul(
            nblk.rb_mut(),
            faer::Accum::Add,
            b.as_ref(),
            w.as_ref(),
            -1.0,
            par,
        );
        wt.copy_from(w.transpose());
        Some(Operators {
            nw,
            rhs: faer::Mat::zeros(nq + m, n),
        })
    }

    /// Column `j`'s ∂f and ∂c.
    fn push(&mut self, j: usize, f: &[f64], c: &[f64]) {
        let mut col = self.rhs.col_mut(j);
        for (i, &v) in f.iter().chain(c).enumerate() {
            col[i] = v;
        }
    }

    /// ∂q̈ = [N Wᵀ] [∂F; ∂C] into the lower rows of `jac`.
    fn finish(self, jac: &mut MatMut<'_, f64>) {
        let nq = self.nw.nrows();
        let n = self.rhs.ncols();
        let lower = jac.rb_mut().submatrix_mut(nq, 0, nq, n);
        faer::linalg::matmul::matmul(
            lower,
            faer::Accum::Replace,
            self.nw.as_ref(),
            self.rhs.as_ref(),
            1.0,
            faer::Par::Seq,
        );
    }
}

/// From this many constraint rows on, the direct solve takes its columns in batches of
/// `BATCH_COLUMNS` through dense level-3 kernels (faer's triangular solves and matrix product)
/// instead of one column at a time: the per-column solve with T (m²) and the product with B
/// (n_q m) are the Jacobian's whole cost on a long chain (a 500-link chain, m = 1000: 73 % of
/// its first step in one Jacobian), and the level-3 kernels run them several times faster.
/// Below it (every case in cases/, A02 N = 40 included: m ≤ 242) the columns are solved one
/// at a time as before, bit for bit.
pub(crate) const BATCHED_MIN_CONSTRAINTS: usize = 256;

/// Columns per batch of the direct solve.
const BATCH_COLUMNS: usize = 64;

/// The columns of one batch of the direct solve (module doc): z = A⁻¹(∂f + αΦ_qᵀ∂c) one column
/// at a time (banded solves), then ∂λ = T⁻¹(Φ_q z − ∂c) and ∂q̈ = z − B ∂λ for the whole batch.
struct Batch {
    /// The factor L of T (lower triangular; T = L Lᵀ).
    l: faer::Mat<f64>,
    /// z of each column (n_q × k).
    z: faer::Mat<f64>,
    /// Φ_q z − ∂c of each column, then ∂λ (m × k).
    r: faer::Mat<f64>,
    /// The Jacobian's column of each batch column.
    cols: Vec<usize>,
    /// αc and Φ_q z of one column.
    ac: Vec<f64>,
    pz: Vec<f64>,
}

impl Batch {
    /// A batch for the factor left by `block_cholesky_inv` in `tmat` (strict lower triangle of
    /// L, 1/L_jj on the diagonal).
    fn new(tmat: &[f64], nq: usize, m: usize) -> Batch {
        let l = faer::Mat::from_fn(m, m, |i, j| match j.cmp(&i) {
            std::cmp::Ordering::Less => tmat[i * m + j],
            std::cmp::Ordering::Equal => 1.0 / tmat[i * m + i],
            std::cmp::Ordering::Greater => 0.0,
        });
        Batch {
            l,
            z: faer::Mat::zeros(nq, BATCH_COLUMNS),
            r: faer::Mat::zeros(m, BATCH_COLUMNS),
            cols: Vec::with_capacity(BATCH_COLUMNS),
            ac: vec![0.0; m],
            pz: vec![0.0; m],
        }
    }

    /// Adds column `j` with ∂f = `f`, ∂c = `c`; keeps ∂c in `r` until the flush.
    fn push(&mut self, j: usize, f: &[f64], c: &[f64]) {
        let k = self.cols.len();
        self.cols.push(j);
        self.z
            .col_mut(k)
            .iter_mut()
            .zip(f)
            .for_each(|(z, &v)| *z = v);
        self.r
            .col_mut(k)
            .iter_mut()
            .zip(c)
            .for_each(|(r, &v)| *r = v);
    }

    /// Solves the batch and writes its columns into the lower rows of `jac`.
    fn flush(
        &mut self,
        core: &AlCore,
        rows: &SparseRows,
        bmat: &[f64],
        alpha: f64,
        jac: &mut MatMut<'_, f64>,
    ) {
        let k = self.cols.len();
        if k == 0 {
            return;
        }
        let (nq, m) = (self.z.nrows(), self.r.nrows());
        let mut z = vec![0.0; nq];
        for b in 0..k {
            for (a, v) in self.ac.iter_mut().enumerate() {
                *v = alpha * self.r[(a, b)];
            }
            z.iter_mut()
                .zip(self.z.col(b).iter())
                .for_each(|(d, &s)| *d = s);
            rows.mul_t_add(&self.ac, &mut z);
            core.apply_inverse(&mut z);
            rows.mul(&z, &mut self.pz);
            for a in 0..m {
                self.r[(a, b)] = self.pz[a] - self.r[(a, b)];
            }
            self.z
                .col_mut(b)
                .iter_mut()
                .zip(&z)
                .for_each(|(d, &s)| *d = s);
        }
        let par = faer::Par::Seq;
        let mut r = self.r.as_mut().subcols_mut(0, k);
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(
            self.l.as_ref(),
            r.rb_mut(),
            par,
        );
        faer::linalg::triangular_solve::solve_upper_triangular_in_place(
            self.l.transpose(),
            r.rb_mut(),
            par,
        );
        let bref = faer::MatRef::from_column_major_slice(bmat, nq, m);
        let mut zk = self.z.as_mut().subcols_mut(0, k);
        faer::linalg::matmul::matmul(zk.rb_mut(), faer::Accum::Add, bref, r.rb(), -1.0, par);
        for (b, &j) in self.cols.iter().enumerate() {
            for i in 0..nq {
                jac[(nq + i, j)] = zk[(i, b)];
            }
        }
        self.cols.clear();
    }
}
