//! The linear solver of diffsol's implicit methods: nalgebra's LU (diffsol's own) below
//! [`FAER_LU_FROM`] unknowns, faer's blocked LU with partial pivoting above.
//!
//! ```text
//! n < FAER_LU_FROM:  diffsol's NalgebraLU (unblocked Gaussian elimination; the numbers of
//!                    every run of the paper's systems, n ≤ 60, stay bit for bit)
//! n ≥ FAER_LU_FROM:  the matrix diffsol assembles (I − hγJ, dense, column-major) factored in
//!                    place by faer::linalg::lu::partial_pivoting (P A = L U, sequential),
//!                    solved by its permutation and two triangular solves
//! ```
//! Both factor in place in the one n × n matrix, so the memory budget of crate::memory holds
//! for either. nalgebra's elimination runs at about 1.7 Gflop/s here (2.3 s for n = 1 800, 66 %
//! of a 300-link chain's run and 74 % of a 50-clearance-joint chain's); faer's blocked
//! factorisation is several times faster from n ≈ 100 on (BENCHMARKS.md, "Scaling with the
//! number of bodies"). A zero pivot (a singular matrix) is the solve's `LuSolveFailed`, as
//! nalgebra's triangular solve reports a failure.

use diffsol::{LaError, NalgebraContext, NalgebraLU, NalgebraMat, NalgebraVec};
use diffsol_la::{LinearOp, LinearSolver, Matrix, MatrixCommon, Vector};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::{Conj, MatMut, MatRef, Par};

/// The number of unknowns from which faer's LU is used.
pub const FAER_LU_FROM: usize = 100;

type Md = NalgebraMat<f64>;
type Vd = NalgebraVec<f64>;

/// faer's factorisation in place in diffsol's matrix.
struct FaerLu {
    a: Md,
    fwd: Vec<usize>,
    bwd: Vec<usize>,
    /// A zero on the diagonal of U.
    singular: bool,
}

impl FaerLu {
    fn n(&self) -> usize {
        self.fwd.len()
    }

    fn lu(&self) -> MatRef<'_, f64> {
        let n = self.n();
        MatRef::from_column_major_slice(self.a.inner().as_slice(), n, n)
    }

    fn factor(&mut self) {
        let n = self.n();
        let lu = MatMut::from_column_major_slice_mut(self.a.inner_mut().as_mut_slice(), n, n);
        let par = Par::Seq;
        let mut buf = MemBuffer::new(factor::lu_in_place_scratch::<usize, f64>(
            n,
            n,
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
        self.singular = (0..n).any(|i| !(lu[(i, i)] != 0.0));
    }

    fn solve(&self, b: &mut Vd, transpose: bool) -> Result<(), LaError> {
        if self.singular {
            return Err(LaError::Other(
                "LU solve failed: a zero pivot (singular matrix)".to_string(),
            ));
        }
        let n = self.n();
        let rhs = MatMut::from_column_major_slice_mut(b.inner_mut().as_mut_slice(), n, 1);
        let perm = faer::perm::PermRef::new_checked(&self.fwd, &self.bwd, n);
        let par = Par::Seq;
        let mut buf = MemBuffer::new(solve::solve_in_place_scratch::<usize, f64>(n, 1, par));
        let stack = MemStack::new(&mut buf);
        if transpose {
            solve::solve_transpose_in_place_with_conj(
                self.lu(),
                self.lu(),
                perm,
                Conj::No,
                rhs,
                par,
                stack,
            );
        } else {
            solve::solve_in_place_with_conj(self.lu(), self.lu(), perm, Conj::No, rhs, par, stack);
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
            self.large = Some(FaerLu {
                a: Md::new_from_sparsity(n, n, op.sparsity(), *op.context()),
                fwd: vec![0; n],
                bwd: vec![0; n],
                singular: true,
            });
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
