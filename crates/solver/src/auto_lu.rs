//! The linear solver of diffsol's implicit methods: nalgebra's LU (diffsol's own) below
//! [`FAER_LU_FROM`] unknowns, faer's blocked LU with partial pivoting above; above, a Newton
//! matrix of a second-order system is reduced to one system of half the size first.
//!
//! ```text
//! n < FAER_LU_FROM:  diffsol's NalgebraLU (unblocked Gaussian elimination; the numbers of
//!                    every run of the paper's systems, n ≤ 60, stay bit for bit)
//! n ≥ FAER_LU_FROM:  the matrix diffsol assembles (I − hγJ, dense, column-major) factored in
//!                    place by faer::linalg::lu::partial_pivoting (P A = L U, sequential),
//!                    solved by its permutation and two triangular solves
//!   second order:    y = (q, v), q' = v makes J = [[0, I], [A, B]] exactly, so the matrix is
//!                    [[I, tI], [P, Q]] (t = −hγ, P = −hγA, Q = I − hγB; checked entry by
//!                    entry, n/2 = k):
//!                      x + t v = r₁,  P x + Q v = r₂  ⇒  (Q − tP) v = r₂ − P r₁,  x = r₁ − t v
//!                      transposed:  (Q − tP)ᵀ v = r₂ − t r₁,  x = r₁ − Pᵀ v
//!                    S = Q − tP is formed in place of Q and factored by faer's LU: (n/2)³
//!                    instead of n³, an eighth of the work
//! ```
//! Both factor in place in the one n × n matrix, so the memory budget of crate::memory holds
//! for either. nalgebra's elimination runs at about 1.7 Gflop/s here (2.3 s for n = 1 800, 66 %
//! of a 300-link chain's run and 74 % of a 50-clearance-joint chain's); faer's blocked
//! factorisation is several times faster from n ≈ 100 on (BENCHMARKS.md, "Scaling with the
//! number of bodies"). A zero pivot (a singular matrix) is the solve's `LuSolveFailed`, as
//! nalgebra's triangular solve reports a failure. The reduction is the block elimination of
//! the first-order form of a second-order system (Hairer & Wanner, *Solving ODEs II*, §IV.8,
//! "the linear algebra of second-order problems"); a matrix without the exact structure (a
//! system with other states, or an approximate Jacobian whose upper blocks are not exactly 0
//! and I) is factored whole.

use diffsol::{LaError, NalgebraContext, NalgebraLU, NalgebraMat, NalgebraVec};
use diffsol_la::{LinearOp, LinearSolver, Matrix, MatrixCommon, Vector};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Conj, MatMut, MatRef, Par};

/// The number of unknowns from which faer's LU is used.
pub const FAER_LU_FROM: usize = 100;

type Md = NalgebraMat<f64>;
type Vd = NalgebraVec<f64>;

/// faer's factorisation in place in diffsol's matrix.
struct FaerLu {
    a: Md,
    /// Row permutation of the factored block (n, or n/2 when `half`).
    fwd: Vec<usize>,
    bwd: Vec<usize>,
    /// A zero on the diagonal of U.
    singular: bool,
    /// The matrix had the second-order structure: S = Q − tP is factored in place of Q
    /// (module doc), with t = `t`.
    half: bool,
    t: f64,
}

impl FaerLu {
    fn new(a: Md) -> Self {
        let n = a.nrows();
        Self {
            a,
            fwd: vec![0; n],
            bwd: vec![0; n],
            singular: true,
            half: false,
            t: 0.0,
        }
    }

    fn n(&self) -> usize {
        self.a.nrows()
    }

    fn full(&self) -> MatRef<'_, f64> {
        let n = self.n();
        MatRef::from_column_major_slice(self.a.inner().as_slice(), n, n)
    }

    /// The factored block: the whole matrix, or S in place of Q.
    fn lu(&self) -> MatRef<'_, f64> {
        let n = self.n();
        if self.half {
            let k = n / 2;
            self.full().submatrix(k, k, k, k)
        } else {
            self.full()
        }
    }

    /// t when the matrix is [[I, tI], [P, Q]] exactly (module doc), None otherwise.
    fn second_order(&self) -> Option<f64> {
        let n = self.n();
        if !n.is_multiple_of(2) || n == 0 {
            return None;
        }
        let (k, a) = (n / 2, self.full());
        let t = a[(0, k)];
        let upper = (0..k).all(|j| {
            (0..k).all(|i| a[(i, j)] == if i == j { 1.0 } else { 0.0 })
                && (0..k).all(|i| a[(i, k + j)] == if i == j { t } else { 0.0 })
        });
        upper.then_some(t)
    }

    fn factor(&mut self) {
        let n = self.n();
        let reduced = self.second_order();
        self.half = reduced.is_some();
        self.t = reduced.unwrap_or(0.0);
        let a = MatMut::from_column_major_slice_mut(self.a.inner_mut().as_mut_slice(), n, n);
        let lu = if self.half {
            let k = n / 2;
            let (_, _, p, mut s) = a.split_at_mut(k, k);
            let t = self.t;
            for j in 0..k {
                for i in 0..k {
                    s[(i, j)] -= t * p[(i, j)];
                }
            }
            s
        } else {
            a
        };
        let m = lu.nrows();
        self.fwd.truncate(m);
        self.bwd.truncate(m);
        self.fwd.resize(m, 0);
        self.bwd.resize(m, 0);
        let par = Par::Seq;
        let mut buf = MemBuffer::new(factor::lu_in_place_scratch::<usize, f64>(
            m,
            m,
            par,
            Default::default(),
        ));
        factor::lu_in_place(
            lu,
            &mut self.fwd,
            &mut self.bwd,
            par,
            MemStack::new(&mut buf),
            Default::default(),
        );
        let lu = self.lu();
        self.singular = (0..m).any(|i| !(lu[(i, i)] != 0.0));
    }

    /// Solves with the factored block in place of `rhs` (m × 1).
    fn block_solve(&self, rhs: MatMut<'_, f64>, transpose: bool) {
        let m = self.fwd.len();
        let perm = faer::perm::PermRef::new_checked(&self.fwd, &self.bwd, m);
        let par = Par::Seq;
        let mut buf = MemBuffer::new(solve::solve_in_place_scratch::<usize, f64>(m, 1, par));
        let stack = MemStack::new(&mut buf);
        let lu = self.lu();
        if transpose {
            solve::solve_transpose_in_place_with_conj(lu, lu, perm, Conj::No, rhs, par, stack);
        } else {
            solve::solve_in_place_with_conj(lu, lu, perm, Conj::No, rhs, par, stack);
        }
    }

    fn solve(&self, b: &mut Vd, transpose: bool) -> Result<(), LaError> {
        if self.singular {
            return Err(LaError::Other(
                "LU solve failed: a zero pivot (singular matrix)".to_string(),
            ));
        }
        let n = self.n();
        if !self.half {
            let rhs = MatMut::from_column_major_slice_mut(b.inner_mut().as_mut_slice(), n, 1);
            self.block_solve(rhs, transpose);
            return Ok(());
        }
        let (k, t) = (n / 2, self.t);
        let p = self.full().submatrix(k, 0, k, k);
        let (r1, r2) = b.inner_mut().as_mut_slice().split_at_mut(k);
        let mut r1 = MatMut::from_column_major_slice_mut(r1, k, 1);
        let mut r2 = MatMut::from_column_major_slice_mut(r2, k, 1);
        if transpose {
            // Sᵀ v = r₂ − t r₁,  x = r₁ − Pᵀ v
            for i in 0..k {
                r2[(i, 0)] -= t * r1[(i, 0)];
            }
            self.block_solve(r2.rb_mut(), true);
            faer::linalg::matmul::matmul(
                r1.rb_mut(),
                faer::Accum::Add,
                p.transpose(),
                r2.rb(),
                -1.0,
                Par::Seq,
            );
        } else {
            // S v = r₂ − P r₁,  x = r₁ − t v
            faer::linalg::matmul::matmul(r2.rb_mut(), faer::Accum::Add, p, r1.rb(), -1.0, Par::Seq);
            self.block_solve(r2.rb_mut(), false);
            for i in 0..k {
                r1[(i, 0)] -= t * r2[(i, 0)];
            }
        }
        Ok(())
    }
}

/// The solver (module doc): chosen by the size of the matrix at `set_sparsity`.
#[derive(Default)]
pub struct AutoLu {
    small: NalgebraLU<f64>,
    large: Option<FaerLu>,
}

impl LinearSolver<Md> for AutoLu {
    fn set_linearisation<C: LinearOp<V = Vd, T = f64, M = Md, C = NalgebraContext>>(
        &mut self,
        op: &C,
    ) {
        match self.large.as_mut() {
            Some(f) => {
                op.matrix_inplace(&mut f.a);
                f.factor();
            }
            None => self.small.set_linearisation(op),
        }
    }

    fn set_sparsity<C: LinearOp<V = Vd, T = f64, M = Md, C = NalgebraContext>>(&mut self, op: &C) {
        let n = op.nrows();
        if n >= FAER_LU_FROM && op.ncols() == n {
            self.small = NalgebraLU::default();
            self.large = Some(FaerLu::new(Md::new_from_sparsity(
                n,
                n,
                op.sparsity(),
                *op.context(),
            )));
        } else {
            self.large = None;
            self.small.set_sparsity(op);
        }
    }

    fn solve_in_place(&self, b: &mut Vd) -> Result<(), LaError> {
        match &self.large {
            Some(f) => f.solve(b, false),
            None => self.small.solve_in_place(b),
        }
    }

    fn solve_transpose_in_place(&self, b: &mut Vd) -> Result<(), LaError> {
        match &self.large {
            Some(f) => f.solve(b, true),
            None => self.small.solve_transpose_in_place(b),
        }
    }
}

#[cfg(test)]
mod tests {
    //! The reduced solve of a second-order Newton matrix against the whole matrix's LU: both
    //! are backward stable, so on a well-conditioned matrix (diagonally dominant lower blocks)
    //! their solutions agree to about a hundred ulps of the largest component, forward and transposed; a matrix that
    //! misses the structure by one entry is factored whole.
    use super::*;

    /// [[I, tI], [P, Q]] with k = n/2, P and Q from a fixed pseudo-random sequence, Q
    /// diagonally dominant (I − hγB of a stable system).
    fn newton(k: usize, t: f64) -> Md {
        let n = 2 * k;
        let mut a = Md::zeros(n, n, Default::default());
        let mut x = 0.5_f64;
        let mut next = || {
            x = (x * 3.7 + 0.13).fract();
            x - 0.5
        };
        let m = a.inner_mut();
        for i in 0..k {
            m[(i, i)] = 1.0;
            m[(i, k + i)] = t;
        }
        for j in 0..n {
            for i in k..n {
                m[(i, j)] = next() * 0.1;
            }
        }
        for i in k..n {
            m[(i, i)] += 2.0;
        }
        a
    }

    fn solve_both(f: &mut FaerLu, b: &[f64], transpose: bool) -> Vec<f64> {
        f.factor();
        let mut v = Vd::from_vec(b.to_vec(), Default::default());
        f.solve(&mut v, transpose).unwrap();
        diffsol_la::VectorCommon::inner(&v).as_slice().to_vec()
    }

    #[test]
    fn the_half_size_solve_agrees_with_the_whole_lu() {
        let k = 120;
        let t = -3e-3;
        let b: Vec<f64> = (0..2 * k).map(|i| ((i * 7) % 11) as f64 - 5.0).collect();
        for transpose in [false, true] {
            let mut reduced = FaerLu::new(newton(k, t));
            let x = solve_both(&mut reduced, &b, transpose);
            assert!(reduced.half && reduced.t == t);
            // The same matrix with one upper entry 2.2e-308 instead of 0 (far below its
            // rounding): no longer exactly of the structure, factored whole.
            let mut a = newton(k, t);
            a.inner_mut()[(3, 5)] = f64::MIN_POSITIVE;
            let mut whole = FaerLu::new(a);
            let y = solve_both(&mut whole, &b, transpose);
            assert!(!whole.half);
            let scale = y.iter().fold(0.0_f64, |s, v| s.max(v.abs()));
            for (xi, yi) in x.iter().zip(&y) {
                assert!((xi - yi).abs() <= 1e-13 * scale, "{xi} vs {yi}");
            }
        }
    }
}
