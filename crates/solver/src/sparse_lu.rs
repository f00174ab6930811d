//! The sparse LU of diffsol's Newton matrices on the sparse path (crate::linear_algebra):
//! faer's sparse LU with partial pivoting on diffsol's `FaerSparseMat`, with its failures
//! returned as errors.
//!
//! ```text
//! set_sparsity:      the pattern of I − hγJ (diffsol's union of the identity and ∂f/∂y's
//!                    pattern); its symbolic factorisation (a fill-reducing column ordering,
//!                    COLAMD, and the elimination structure) once per solver
//! set_linearisation: the values of I − hγJ, factored numerically (P A Q = L U)
//! solve:             the permutations and two sparse triangular solves
//! ```
//! diffsol's own `FaerSparseLU` does the same but panics (`expect`) when a factorisation
//! fails: a column without a pivot (a singular matrix) or an allocation refused. Here the
//! failure is kept and returned by the next solve as `LaError` (diffsol then counts a Newton
//! failure and shrinks the step, as for nalgebra's singular LU on the dense path: auto_lu.rs),
//! and a failed symbolic factorisation likewise. For a block-diagonal matrix (free bodies)
//! there is no fill: the factors have the matrix's own entries, and the work of a
//! factorisation is Σ over blocks of (block size)³.

use diffsol_la::{
    FaerContext, FaerSparseMat, FaerVec, LaError, LinearOp, LinearSolver, Matrix, MatrixCommon,
    Vector,
};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::reborrow::Reborrow;
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::{Conj, Par};

type Ms = FaerSparseMat<f64>;
type Vs = FaerVec<f64>;

/// The factorisation and its buffers.
struct Factor {
    a: Ms,
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    scratch: MemBuffer,
    solve_scratch: std::cell::RefCell<MemBuffer>,
    /// Why the last numeric factorisation failed (None: it succeeded).
    failed: Option<String>,
}

/// The sparse solver (module doc).
#[derive(Default)]
pub struct SparseLu {
    factor: Option<Factor>,
    /// Why the symbolic factorisation failed.
    failed: Option<String>,
}

impl LinearSolver<Ms> for SparseLu {
    fn set_linearisation<C: LinearOp<V = Vs, T = f64, M = Ms, C = FaerContext>>(&mut self, op: &C) {
        let Some(f) = self.factor.as_mut() else {
            return;
        };
        op.matrix_inplace(&mut f.a);
        let a = &f.a.inner()[0];
        f.failed = f
            .symbolic
            .factorize_numeric_lu(
                &mut f.numeric,
                a.rb(),
                Par::Seq,
                MemStack::new(&mut f.scratch),
                Default::default(),
            )
            .err()
            .map(|e| format!("sparse LU failed: {e:?}"));
    }

    fn set_sparsity<C: LinearOp<V = Vs, T = f64, M = Ms, C = FaerContext>>(&mut self, op: &C) {
        let a = Ms::new_from_sparsity(op.nrows(), op.ncols(), op.sparsity(), *op.context());
        self.factor = None;
        self.failed = None;
        match factorize_symbolic_lu(a.inner()[0].symbolic(), Default::default()) {
            Ok(symbolic) => {
                let scratch = MemBuffer::new(
                    symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()),
                );
                let solve_scratch = MemBuffer::new(
                    symbolic
                        .solve_in_place_scratch::<f64>(1, Par::Seq)
                        .or(symbolic.solve_transpose_in_place_scratch::<f64>(1, Par::Seq)),
                );
                self.factor = Some(Factor {
                    a,
                    symbolic,
                    numeric: NumericLu::new(),
                    scratch,
                    solve_scratch: std::cell::RefCell::new(solve_scratch),
                    failed: Some("sparse LU: no matrix factored yet".into()),
                });
            }
            Err(e) => {
                self.failed = Some(format!("sparse LU: symbolic factorisation failed: {e:?}"))
            }
        }
    }

    fn solve_in_place(&self, b: &mut Vs) -> Result<(), LaError> {
        self.solve(b, false)
    }

    fn solve_transpose_in_place(&self, b: &mut Vs) -> Result<(), LaError> {
        self.solve(b, true)
    }
}

impl SparseLu {
    fn solve(&self, b: &mut Vs, transpose: bool) -> Result<(), LaError> {
        let f = match (&self.factor, &self.failed) {
            (_, Some(why)) => return Err(LaError::Other(why.clone())),
            (None, None) => return Err(LaError::Other("sparse LU: no sparsity set".into())),
            (Some(f), None) => f,
        };
        if let Some(why) = &f.failed {
            return Err(LaError::Other(why.clone()));
        }
        let lu = LuRef::new_unchecked(&f.symbolic, &f.numeric);
        let mut scratch = f.solve_scratch.borrow_mut();
        let stack = MemStack::new(&mut scratch);
        let n = b.len();
        let rhs =
            faer::MatMut::from_column_major_slice_mut(b.inner_mut().col_as_slice_mut(0), n, 1);
        if transpose {
            lu.solve_transpose_in_place_with_conj(Conj::No, rhs, Par::Seq, stack);
        } else {
            lu.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, stack);
        }
        Ok(())
    }
}
