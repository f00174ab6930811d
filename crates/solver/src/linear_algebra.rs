//! Dense or sparse linear algebra for diffsol's implicit methods (BDF, TR-BDF2, ESDIRK3(4)),
//! chosen per problem; Rodas5P chooses the same way (its sparse W: crate::sparse_lu::
//! ShiftedSparse).
//!
//! ```text
//! dense   nalgebra vectors and n × n matrices: ∂f/∂y the system's own (or forward
//!         differences), the Newton matrix I − hγJ factored by crate::auto_lu
//!         memory 4 · 8n² bytes (crate::memory)
//! sparse  faer vectors and compressed-column matrices on the system's sparsity pattern
//!         (OdeSystem::jacobian_sparsity): ∂f/∂y by forward differences over structurally
//!         orthogonal column groups (crate::jacobian, one RHS evaluation per colour), I − hγJ
//!         factored by faer's sparse LU (crate::sparse_lu)
//!         memory O(nnz): crate::memory::sparse_bytes
//! kkt     a second-order system whose accelerations solve a sparse KKT system
//!         (OdeSystem::kkt): diffsol holds only J's exact identity block; the Newton solve
//!         goes through K's sparse LU and an augmented sparse system (crate::kkt)
//!         memory O(nnz(K) + nnz(∂ρ/∂y)) and the LU's fill: crate::memory::kkt_bytes
//! auto    sparse when n ≥ SPARSE_FROM and the pattern has at most n²/SPARSE_DENSITY
//!         entries; else kkt when the system has the KKT form and n ≥ KKT_FROM, or
//!         n ≥ KKT_ONE_CLUSTER_FROM and its Jacobian is dense (no sparsity pattern: one
//!         cluster, as a chain or A02); dense otherwise
//! ```
//! On the sparse path the system's own dense Jacobian is not used (it is n × n): a mechanism's
//! closed-form blocks are replaced by differences, whose error (√ε relative) is far below what
//! Newton's convergence needs. Measured crossover: BENCHMARKS.md, "Scaling with the number of
//! bodies".

use diffsol_la::{
    Context, DefaultDenseMatrix, FaerContext, FaerSparseMat, FaerVec, LinearSolver, Matrix,
    MatrixSparsity, NalgebraContext, NalgebraMat, NalgebraVec, Vector,
};
use faer::MatMut;

use std::cell::RefCell;
use std::rc::Rc;

use crate::kkt::KktNewton;
use crate::system::OdeSystem;

/// Which linear algebra diffsol's implicit methods and Rodas5P use (module doc). The other
/// methods ignore it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LinearAlgebra {
    /// Sparse from [`SPARSE_FROM`] unknowns when the system gives a pattern with at most
    /// n²/[`SPARSE_DENSITY`] entries, dense otherwise.
    #[default]
    Auto,
    /// Dense matrices (n² memory).
    Dense,
    /// Sparse matrices on the system's pattern (a full pattern when it gives none).
    Sparse,
    /// The Newton solve through the system's sparse KKT form (crate::kkt); dense when the
    /// system has none.
    Kkt,
}

impl LinearAlgebra {
    /// Whether it is the default (`Auto`).
    pub fn is_auto(&self) -> bool {
        *self == LinearAlgebra::Auto
    }
}

/// The number of unknowns from which `Auto` takes the sparse path (module doc).
pub const SPARSE_FROM: usize = 600;

/// The number of unknowns from which `Auto` takes the `kkt` path (module doc; measured:
/// BENCHMARKS.md, "The sparse Newton of one cluster").
pub const KKT_FROM: usize = 600;

/// The number of unknowns from which `Auto` takes the `kkt` path for a system whose Jacobian
/// is dense ([`OdeSystem::jacobian_sparsity`] None: one cluster of constraints, as a chain
/// or IFToMM A02), whose dense Newton matrix costs n² entries to form and n³ to factor
/// against the KKT matrix's O(n). Measured (BENCHMARKS.md, "Minimal with loop closures"): bdf on a chain
/// breaks even near n = 150 and is 5× faster on the kkt path at n = 300; A02 N = 40
/// (n = 486, 20 s at rtol 1e-10) 9.1 s against 55 s, with 11 036 steps against 11 098.
pub const KKT_ONE_CLUSTER_FROM: usize = 300;

/// Whether `choice` puts `sys` on the `kkt` path (module doc), given whether the pattern
/// path was chosen.
pub fn uses_kkt<S: OdeSystem + ?Sized>(sys: &S, choice: LinearAlgebra, sparse: bool) -> bool {
    let has = sys.kkt().is_some();
    let n = sys.dim();
    match choice {
        LinearAlgebra::Kkt => has,
        LinearAlgebra::Auto => {
            has && !sparse
                && (n >= KKT_FROM
                    || (n >= KKT_ONE_CLUSTER_FROM && sys.jacobian_sparsity().is_none()))
        }
        LinearAlgebra::Dense | LinearAlgebra::Sparse => false,
    }
}

/// `Auto` takes the sparse path only for a pattern with at most n²/SPARSE_DENSITY entries.
pub const SPARSE_DENSITY: usize = 8;

/// The pattern (for each column, its rows ascending and distinct) of the sparse path for
/// `sys` under `choice`, None for the dense path (module doc). A pattern of the wrong length
/// or with a row out of range counts as none.
pub fn sparse_pattern<S: OdeSystem + ?Sized>(
    sys: &S,
    choice: LinearAlgebra,
) -> Option<Vec<Vec<usize>>> {
    let n = sys.dim();
    let pattern = || {
        let mut p = sys.jacobian_sparsity()?;
        if p.len() != n || p.iter().flatten().any(|&i| i >= n) {
            return None;
        }
        for rows in &mut p {
            rows.sort_unstable();
            rows.dedup();
        }
        Some(p)
    };
    match choice {
        LinearAlgebra::Dense | LinearAlgebra::Kkt => None,
        LinearAlgebra::Sparse => {
            Some(pattern().unwrap_or_else(|| (0..n).map(|_| (0..n).collect()).collect()))
        }
        LinearAlgebra::Auto if n < SPARSE_FROM => None,
        LinearAlgebra::Auto => {
            let p = pattern()?;
            let nnz: usize = p.iter().map(Vec::len).sum();
            (nnz.saturating_mul(SPARSE_DENSITY) <= n.saturating_mul(n)).then_some(p)
        }
    }
}

/// A Jacobian matrix of either path, as its entries are written.
pub(crate) enum JacView<'a> {
    /// Column-major n × n.
    Dense(MatMut<'a, f64>),
    /// Compressed columns: column j's rows are `row_idx[col_ptr[j]..col_ptr[j + 1]]`, its
    /// values the same range of `values`.
    Sparse {
        col_ptr: &'a [usize],
        row_idx: &'a [usize],
        values: &'a mut [f64],
    },
}

/// The types of one path (module doc).
pub(crate) trait La: 'static {
    /// Vectors.
    type V: Vector<T = f64, C = Self::C> + DefaultDenseMatrix;
    /// Matrices (∂f/∂y and the Newton matrix).
    type M: Matrix<T = f64, V = Self::V, C = Self::C>;
    /// diffsol's context.
    type C: Context + Copy + Default;
    /// The Newton matrix's solver.
    type Lu: LinearSolver<Self::M>;
    /// Whether products J v may use the system's own dense Jacobian (the sparse path takes a
    /// directional difference instead: no n × n matrix).
    const SYSTEM_PRODUCTS: bool;
    /// The entries of a vector.
    fn slice(v: &Self::V) -> &[f64];
    /// The entries of a vector, mutably.
    fn slice_mut(v: &mut Self::V) -> &mut [f64];
    /// diffsol's sparsity of ∂f/∂y from a pattern (None on the dense path).
    fn sparsity(n: usize, pattern: &[Vec<usize>]) -> Option<<Self::M as Matrix>::Sparsity>;
    /// The matrix's entries to write.
    fn view(m: &mut Self::M) -> JacView<'_>;
    /// The Newton matrix's solver, on the `kkt` path with its shared linearisation.
    fn lu(kkt: Option<&Rc<RefCell<KktNewton>>>) -> Self::Lu {
        let _ = kkt;
        Self::Lu::default()
    }
}

/// The dense path: nalgebra, crate::auto_lu.
pub(crate) struct Dense;

impl La for Dense {
    type V = NalgebraVec<f64>;
    type M = NalgebraMat<f64>;
    type C = NalgebraContext;
    type Lu = crate::auto_lu::AutoLu;
    const SYSTEM_PRODUCTS: bool = true;
    fn slice(v: &Self::V) -> &[f64] {
        diffsol_la::VectorCommon::inner(v).as_slice()
    }
    fn slice_mut(v: &mut Self::V) -> &mut [f64] {
        v.inner_mut().as_mut_slice()
    }
    fn sparsity(_n: usize, _pattern: &[Vec<usize>]) -> Option<<Self::M as Matrix>::Sparsity> {
        None
    }
    fn view(m: &mut Self::M) -> JacView<'_> {
        let (r, c) = (
            diffsol_la::MatrixCommon::nrows(m),
            diffsol_la::MatrixCommon::ncols(m),
        );
        JacView::Dense(MatMut::from_column_major_slice_mut(
            m.inner_mut().as_mut_slice(),
            r,
            c,
        ))
    }
}

/// The sparse path: faer, crate::sparse_lu.
pub(crate) struct Sparse;

impl La for Sparse {
    type V = FaerVec<f64>;
    type M = FaerSparseMat<f64>;
    type C = FaerContext;
    type Lu = crate::sparse_lu::SparseLu;
    const SYSTEM_PRODUCTS: bool = false;
    fn slice(v: &Self::V) -> &[f64] {
        diffsol_la::VectorCommon::inner(v).col_as_slice(0)
    }
    fn slice_mut(v: &mut Self::V) -> &mut [f64] {
        v.inner_mut().col_as_slice_mut(0)
    }
    fn sparsity(n: usize, pattern: &[Vec<usize>]) -> Option<<Self::M as Matrix>::Sparsity> {
        let indices = pattern
            .iter()
            .enumerate()
            .flat_map(|(j, rows)| rows.iter().map(move |&i| (i, j)))
            .collect();
        <<Self::M as Matrix>::Sparsity as MatrixSparsity<Self::M>>::try_from_indices(n, n, indices)
            .ok()
    }
    fn view(m: &mut Self::M) -> JacView<'_> {
        let (symbolic, values) = m.inner_mut()[0].parts_mut();
        JacView::Sparse {
            col_ptr: symbolic.col_ptr(),
            row_idx: symbolic.row_idx(),
            values,
        }
    }
}

/// The `kkt` path: faer's vectors and compressed columns for J's identity block, crate::kkt.
pub(crate) struct Kkt;

impl La for Kkt {
    type V = FaerVec<f64>;
    type M = FaerSparseMat<f64>;
    type C = FaerContext;
    type Lu = crate::kkt::KktLu;
    const SYSTEM_PRODUCTS: bool = false;
    fn slice(v: &Self::V) -> &[f64] {
        Sparse::slice(v)
    }
    fn slice_mut(v: &mut Self::V) -> &mut [f64] {
        Sparse::slice_mut(v)
    }
    fn sparsity(n: usize, pattern: &[Vec<usize>]) -> Option<<Self::M as Matrix>::Sparsity> {
        Sparse::sparsity(n, pattern)
    }
    fn view(m: &mut Self::M) -> JacView<'_> {
        Sparse::view(m)
    }
    fn lu(kkt: Option<&Rc<RefCell<KktNewton>>>) -> Self::Lu {
        kkt.map(|k| crate::kkt::KktLu::new(k.clone()))
            .unwrap_or_default()
    }
}
