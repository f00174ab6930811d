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

/// W = d·I − J for Rodas5P's sparse path (crate::rosenbrock, crate::linear_algebra): J by
/// coloured forward differences on the system's pattern
/// ([`crate::jacobian::JacobianEvaluator::sparse_difference`]), W on that pattern and the
/// diagonal, factored by faer's sparse LU (its symbolic factorisation once, a numeric one
/// per step attempt, as [`SparseLu`] does for diffsol's methods).
///
/// ```text
/// memory  O(nnz(J) + nnz(L + U))   (crate::memory::check_sparse counts 80 bytes per entry)
/// work    colours + 1 RHS evaluations per Jacobian; per attempt one sparse LU
/// ```
pub(crate) struct ShiftedSparse {
    colouring: crate::jacobian::Colouring,
    /// J's compressed columns (the colouring's pattern) and values.
    j_ptr: Vec<usize>,
    j_idx: Vec<usize>,
    j_val: Vec<f64>,
    /// W on J's pattern and the diagonal; where each entry of J and each diagonal entry sits
    /// in its values.
    w: faer::sparse::SparseColMat<usize, f64>,
    j_to_w: Vec<usize>,
    diag: Vec<usize>,
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    scratch: MemBuffer,
    solve_scratch: MemBuffer,
}

impl ShiftedSparse {
    /// The structure for `colouring`'s pattern (n columns, rows < n); None when the symbolic
    /// factorisation fails.
    pub(crate) fn new(colouring: crate::jacobian::Colouring) -> Option<Self> {
        let n = colouring.pattern().len();
        let (mut j_ptr, mut j_idx) = (vec![0], Vec::new());
        let mut triplets = Vec::new();
        for (j, rows) in colouring.pattern().iter().enumerate() {
            j_idx.extend_from_slice(rows);
            j_ptr.push(j_idx.len());
            triplets.extend(rows.iter().map(|&i| faer::sparse::Triplet::new(i, j, 0.0)));
            triplets.push(faer::sparse::Triplet::new(j, j, 0.0));
        }
        let w = faer::sparse::SparseColMat::try_new_from_triplets(n, n, &triplets).ok()?;
        let (w_ptr, w_idx) = (w.symbolic().col_ptr(), w.symbolic().row_idx());
        let at = |i: usize, j: usize| {
            let rows = &w_idx[w_ptr[j]..w_ptr[j + 1]];
            w_ptr[j] + rows.binary_search(&i).expect("in W's pattern")
        };
        let mut j_to_w = Vec::with_capacity(j_idx.len());
        for j in 0..n {
            j_to_w.extend(j_idx[j_ptr[j]..j_ptr[j + 1]].iter().map(|&i| at(i, j)));
        }
        let diag = (0..n).map(|j| at(j, j)).collect();
        let symbolic = factorize_symbolic_lu(w.symbolic(), Default::default()).ok()?;
        let scratch = MemBuffer::new(
            symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()),
        );
        let solve_scratch = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        Some(ShiftedSparse {
            colouring,
            j_val: vec![0.0; j_idx.len()],
            j_ptr,
            j_idx,
            w,
            j_to_w,
            diag,
            symbolic,
            numeric: NumericLu::new(),
            scratch,
            solve_scratch,
        })
    }

    /// J at (t, y), f(t, y) = `f0`, by coloured differences with `eval`'s increments.
    pub(crate) fn jacobian<S: crate::system::OdeSystem + ?Sized>(
        &mut self,
        eval: &mut crate::jacobian::JacobianEvaluator,
        sys: &S,
        (t, y, f0): (f64, &[f64], &[f64]),
        stats: &mut crate::stats::Stats,
    ) {
        eval.sparse_difference(
            sys,
            t,
            y,
            f0,
            &self.colouring,
            (&self.j_ptr, &self.j_idx),
            &mut self.j_val,
            stats,
        );
    }

    /// Sets W = d·I − J and factors it; false when the factorisation fails (a column
    /// without a pivot) or a factor is not finite.
    pub(crate) fn factor(&mut self, d: f64) -> bool {
        let vals = self.w.val_mut();
        vals.fill(0.0);
        for (k, &p) in self.j_to_w.iter().enumerate() {
            vals[p] = -self.j_val[k];
        }
        for &p in &self.diag {
            vals[p] += d;
        }
        self.symbolic
            .factorize_numeric_lu(
                &mut self.numeric,
                self.w.rb(),
                Par::Seq,
                MemStack::new(&mut self.scratch),
                Default::default(),
            )
            .is_ok()
    }

    /// Solves W x = b in place (b in `x`) after [`ShiftedSparse::factor`].
    pub(crate) fn solve(&mut self, x: &mut [f64]) {
        let n = x.len();
        let lu = LuRef::new_unchecked(&self.symbolic, &self.numeric);
        lu.solve_in_place_with_conj(
            Conj::No,
            faer::MatMut::from_column_major_slice_mut(x, n, 1),
            Par::Seq,
            MemStack::new(&mut self.solve_scratch),
        );
    }
}
