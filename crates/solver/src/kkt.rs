//! The Newton solve of diffsol's implicit methods through a second-order system's sparse KKT
//! matrix (the `kkt` linear algebra of crate::linear_algebra): the state-space ODE and its
//! steps are kept, no n × n Jacobian is formed.
//!
//! ```text
//! y = (q, v), n = 2 n_q:   q' = v,   v' = a(t, q, v),   K(t, q) z = b(t, q, v),  z = (a, λ)
//!                          K = [[M, Φ_qᵀ], [Φ_q, 0]]  ((n_q + m) square, sparse)
//! ρ(y; z) = b(t, y) − K(t, y) z,   R = ∂ρ/∂y at fixed z = [R_q  R_v]  ((n_q + m) × n, sparse)
//!   ⇒  ∂z/∂y = K⁻¹ R,   J = ∂f/∂y = [[0, I], [S K⁻¹ R_q, S K⁻¹ R_v]]   (S: the first n_q rows)
//!
//! Newton matrix I − cJ (c = hγ) on (x₁, x₂) = (r₁, r₂):
//!   x₁ = r₁ + c x₂,   x₂ − S K⁻¹ D x₂ = r₂ + c S K⁻¹ R_q r₁,   D = c R_v + c² R_q
//!   with w = K⁻¹ (D x₂ + c R_q r₁):   [ I   −S ] [x₂]   [ r₂        ]
//!                                      [ −D   K ] [w ] = [ c R_q r₁  ]      (2 n_q + m, sparse)
//! ```
//! At each Jacobian evaluation (diffsol's `jacobian_inplace`) the system assembles K and b at
//! (t, y) ([`KktSystem::kkt_assemble`]); z = K⁻¹ b by a sparse LU; R in the system's closed
//! form where it has one ([`KktSystem::kkt_residual_jacobian`]), else by forward differences
//! of ρ at fixed z over structurally orthogonal columns ([`KktShape::residual_pattern`],
//! coloured as crate::jacobian colours ∂f/∂y: one assembly per colour, 19 for a chain of
//! pendulum links whatever its length, each counted as a right-hand side in the solver's
//! statistics; the closed form counts none). At each factorisation diffsol asks for (a new c, the
//! same linearisation) the augmented matrix above is factored by faer's sparse LU, its
//! symbolic analysis done once. The matrix diffsol itself holds is the exact part of J, the
//! identity block q' = v (`upper_pattern`): its Newton matrix gives c exactly (the entry
//! (0, n_q) is −c). Everything is O(nnz) for a banded K and R: memory and time linear in the
//! length of a chain (BENCHMARKS.md, "The sparse Newton of one cluster").
//!
//! The Jacobian J this linearises is that of the KKT solution with the system's b; a
//! formulation that reaches the same accelerations another way (the augmented Lagrangian's
//! iteration, to its tolerance) gets a Newton matrix as exact as its dense Jacobian.
//!
//! Why this design and not the descriptor (index-1 DAE) form with a singular mass matrix: it
//! integrates the same ODE with the same step sequence as the dense path (measured: the same
//! steps, factorisations and Newton iterations on a 110-link chain, final states within
//! 1e-12 of each other), so observers, the error norm, events, dense output and restarts are
//! untouched, and nothing needs a consistent (a, λ) or weights for algebraic unknowns; the
//! price is ∂ρ/∂y, the system's closed form or differences (one assembly of K and b per
//! colour, cheaper than a right-hand side: no solve) and a system of 2 n_q + m unknowns per factorisation instead
//! of the descriptor form's 2 n_q + m with the same banded structure: the same order of
//! work. Limits: the transposed solve (adjoints) is not provided.
//!
//! **A singular K.** Redundant constraints and singular configurations make K singular (Φ_q
//! loses row rank) while the accelerations stay unique: the augmented Lagrangian integrates
//! through both. For such a system ([`KktShape::regularisation`] = ε, its 1/α) the path
//! factors K_ε = [[M, Φ_qᵀ], [Φ_q, −εI]] instead, which is quasi-definite (M positive
//! definite) and so nonsingular, with a stable LU, whatever the rank of Φ_q; z = K⁻¹b is
//! then reached by z ← z + K_ε⁻¹ (b − K z), the augmented Lagrangian's iteration of the
//! multipliers, to a relative 1e-12 of the accelerations (at most 20 refinements), and the
//! augmented matrix holds K_ε. Its Newton matrix is that of the penalty form, within
//! O(ε σ⁻¹) of the exact one where Φ_q has full rank (σ the smallest singular value of
//! Φ_q M⁻¹ Φ_qᵀ), which Newton's iteration absorbs; the ODE, its right-hand side and the
//! accepted states are the formulation's own. Without ε a singular K fails the
//! linearisation, and the step then ends in diffsol's Newton failure (typed, with the
//! state), as a singular dense Newton matrix does.

use std::cell::RefCell;
use std::rc::Rc;

use diffsol_la::{
    FaerContext, FaerSparseMat, FaerVec, LaError, LinearOp, LinearSolver, Matrix, MatrixCommon,
    Vector,
};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::reborrow::Reborrow;
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use faer::{Conj, Par};

use crate::jacobian::Colouring;
use crate::stats::Stats;

pub use crate::system::{KktShape, KktSystem};

/// Most refinements of K z = b with K_ε (module doc); each reduces the multipliers' error by
/// about 1/(1 + σ/ε), σ the smallest nonzero singular value of Φ_q M⁻¹ Φ_qᵀ (as the augmented
/// Lagrangian's own iteration).
const REFINEMENTS: usize = 20;

/// The refinement stops when its last correction of the accelerations is below this share of
/// their largest (as the augmented Lagrangian's default tolerance).
const REFINE_TOL: f64 = 1e-12;

/// The pattern of the exact part of J diffsol holds on the `kkt` path: (i, n_q + i) for
/// i < n_q (q' = v), as columns.
pub(crate) fn upper_pattern(nq: usize) -> Vec<Vec<usize>> {
    (0..2 * nq)
        .map(|j| if j >= nq { vec![j - nq] } else { Vec::new() })
        .collect()
}

/// The floors of the `kkt` path's difference increments from the solver's (atol_i / rtol):
/// at least 1, so that an increment is never below √ε ≈ 1.5e-8 in the SI units of a
/// mechanism's coordinates (m, rad, m/s). With atol/rtol = 1e-3 (the defaults) a coordinate
/// near 0 got increments of 1.5e-11, whose rounding error (ε |Φ_qᵀλ| / δ, tensions of
/// 10³ N in a 100-link chain) made ∂ρ/∂y wrong in its fourth digit: the Newton solve then
/// differed from the dense Newton matrix's by 6e-6 of ‖x‖ at c = 1e-2, against 7e-9 with
/// this floor (crates/model/tests/kkt.rs).
pub fn increment_floors(mut scale: Vec<f64>) -> Vec<f64> {
    for s in &mut scale {
        *s = s.max(1.0);
    }
    scale
}

/// A sparse matrix of fixed pattern whose values are refilled: faer's symbolic structure,
/// the order of the triplets in it, and its LU's symbolic analysis (done once).
struct Fixed {
    idx: Vec<(usize, usize)>,
    symbolic: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    lu: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    scratch: MemBuffer,
    solve_scratch: RefCell<MemBuffer>,
    /// The numeric factorisation succeeded.
    ok: bool,
}

impl Fixed {
    fn new(n: usize, idx: Vec<(usize, usize)>) -> Result<Self, String> {
        let pairs: Vec<Pair<usize, usize>> =
            idx.iter().map(|&(row, col)| Pair { row, col }).collect();
        let (symbolic, argsort) = SymbolicSparseColMat::try_new_from_indices(n, n, &pairs)
            .map_err(|e| format!("KKT matrix: {e:?}"))?;
        let lu = factorize_symbolic_lu(symbolic.rb(), Default::default())
            .map_err(|e| format!("KKT matrix: symbolic LU failed: {e:?}"))?;
        let scratch =
            MemBuffer::new(lu.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()));
        let solve_scratch = RefCell::new(MemBuffer::new(
            lu.solve_in_place_scratch::<f64>(1, Par::Seq),
        ));
        Ok(Fixed {
            idx,
            symbolic,
            argsort,
            lu,
            numeric: NumericLu::new(),
            scratch,
            solve_scratch,
            ok: false,
        })
    }

    /// Factors the matrix with `values` (in the order of `idx`).
    fn factor(&mut self, values: &[f64]) -> Result<(), String> {
        self.ok = false;
        let a = SparseColMat::new_from_argsort(self.symbolic.clone(), &self.argsort, values)
            .map_err(|e| format!("KKT matrix: {e:?}"))?;
        self.lu
            .factorize_numeric_lu(
                &mut self.numeric,
                a.rb(),
                Par::Seq,
                MemStack::new(&mut self.scratch),
                Default::default(),
            )
            .map_err(|e| format!("sparse LU failed: {e:?}"))?;
        self.ok = true;
        Ok(())
    }

    /// Solves in place of `x` with the last factorisation (which must have succeeded).
    fn solve(&self, x: &mut [f64]) {
        let n = x.len();
        let lu = LuRef::new_unchecked(&self.lu, &self.numeric);
        let rhs = faer::MatMut::from_column_major_slice_mut(x, n, 1);
        let mut scratch = self.solve_scratch.borrow_mut();
        lu.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, MemStack::new(&mut scratch));
    }
}

/// The linearisation shared by the operator (which computes it at each Jacobian) and the
/// linear solver (which factors and solves with it): module doc.
pub struct KktNewton {
    nq: usize,
    m: usize,
    colouring: Colouring,
    /// Floors of the difference increments (atol/rtol of each component, as crate::jacobian).
    scale: Vec<f64>,
    k: Vec<(usize, usize, f64)>,
    /// K's values at the linearisation point (`k` holds the last assembly, perturbed).
    kvals: Vec<f64>,
    b: Vec<f64>,
    z: Vec<f64>,
    rho0: Vec<f64>,
    rho1: Vec<f64>,
    ytmp: Vec<f64>,
    deltas: Vec<f64>,
    /// R's values, column by column in the pattern's order; `r_factored` those the last
    /// factorisation used.
    r: Vec<f64>,
    r_factored: Vec<f64>,
    kmat: Option<Fixed>,
    aug: Option<Fixed>,
    aug_values: Vec<f64>,
    /// c of the last factorisation.
    c: f64,
    /// ε of K_ε (KktShape::regularisation).
    eps: Option<f64>,
    /// Why the last linearisation or factorisation failed.
    failed: Option<String>,
    work: RefCell<Vec<f64>>,
}

impl KktNewton {
    /// The shared state for a system of shape `shape` whose components have difference
    /// floors `scale`; None when the pattern is out of range.
    pub(crate) fn new(shape: KktShape, scale: Vec<f64>) -> Option<Self> {
        let KktShape {
            nq,
            m,
            residual_pattern,
            regularisation,
            ..
        } = shape;
        if residual_pattern.len() != 2 * nq || scale.len() != 2 * nq {
            return None;
        }
        let colouring = Colouring::rectangular(residual_pattern, nq + m)?;
        let nnz_r = colouring.pattern().iter().map(Vec::len).sum();
        Some(KktNewton {
            nq,
            m,
            colouring,
            scale,
            k: Vec::new(),
            kvals: Vec::new(),
            b: vec![0.0; nq + m],
            z: vec![0.0; nq + m],
            rho0: vec![0.0; nq + m],
            rho1: vec![0.0; nq + m],
            ytmp: vec![0.0; 2 * nq],
            deltas: vec![0.0; 2 * nq],
            r: vec![0.0; nnz_r],
            r_factored: vec![0.0; nnz_r],
            kmat: None,
            aug: None,
            aug_values: Vec::new(),
            c: 0.0,
            eps: regularisation.filter(|e| e.is_finite() && *e > 0.0),
            failed: Some("KKT Newton: no linearisation yet".into()),
            work: RefCell::new(vec![0.0; 2 * nq + m]),
        })
    }

    /// Colours of R: assemblies per linearisation beyond the first.
    pub fn colours(&self) -> usize {
        self.colouring.colours()
    }

    /// ρ = b − K z into `out` from the triplets `k`.
    fn residual(k: &[(usize, usize, f64)], b: &[f64], z: &[f64], out: &mut [f64]) {
        out.copy_from_slice(b);
        for &(i, j, v) in k {
            out[i] -= v * z[j];
        }
    }

    /// Linearises at (t, y): K, b, z = K⁻¹ b and R (module doc). A failure (the system cannot
    /// assemble, K singular) is kept and returned by the next factorisation.
    pub(crate) fn linearise(&mut self, sys: &dyn KktSystem, t: f64, y: &[f64], stats: &mut Stats) {
        self.failed = self.try_linearise(sys, t, y, stats).err();
    }

    fn try_linearise(
        &mut self,
        sys: &dyn KktSystem,
        t: f64,
        y: &[f64],
        stats: &mut Stats,
    ) -> Result<(), String> {
        let nk = self.nq + self.m;
        stats.rhs_evals += 1;
        stats.jac_evals += 1;
        if !sys.kkt_assemble(t, y, &mut self.k, &mut self.b) {
            return Err(format!("KKT matrix: the system cannot evaluate at t = {t}"));
        }
        // K's triplets, then K_ε's −εI block when the system regularises (module doc).
        let n_exact = self.k.len();
        let reg = self.eps.map(|e| (self.nq..nk).map(move |i| (i, i, -e)));
        let same = self.kmat.as_ref().is_some_and(|f| {
            f.idx.len() == n_exact + reg.clone().map_or(0, |r| r.len())
                && f.idx
                    .iter()
                    .zip(&self.k)
                    .all(|(a, b)| a.0 == b.0 && a.1 == b.1)
        });
        if !same {
            let mut idx: Vec<(usize, usize)> = self.k.iter().map(|&(i, j, _)| (i, j)).collect();
            idx.extend(reg.clone().into_iter().flatten().map(|(i, j, _)| (i, j)));
            self.kmat = Some(Fixed::new(nk, idx)?);
            self.aug = None;
        }
        self.kvals.clear();
        self.kvals.extend(self.k.iter().map(|e| e.2));
        self.kvals.extend(reg.into_iter().flatten().map(|e| e.2));
        let kmat = self.kmat.as_mut().expect("set above");
        kmat.factor(&self.kvals)?;
        self.z.copy_from_slice(&self.b);
        kmat.solve(&mut self.z);
        if self.eps.is_some() {
            // z of K z = b by the augmented Lagrangian's own iteration: z += K_ε⁻¹ (b − K z),
            // the multipliers' update with penalty 1/ε, which converges to the accelerations
            // of K z = b where those are unique (also for a singular, consistent K).
            // ρ₁ as the residual's buffer: the coloured differences below overwrite it.
            let r = &mut self.rho1;
            for _ in 0..REFINEMENTS {
                Self::residual(&self.k, &self.b, &self.z, r);
                kmat.solve(r);
                let (mut dz, mut zmax) = (0.0f64, 0.0f64);
                for (zi, ri) in self.z[..self.nq].iter_mut().zip(&r[..self.nq]) {
                    *zi += ri;
                    dz = dz.max(ri.abs());
                    zmax = zmax.max(zi.abs());
                }
                for (zi, ri) in self.z[self.nq..].iter_mut().zip(&r[self.nq..]) {
                    *zi += ri;
                }
                if !(dz > REFINE_TOL * zmax) {
                    break;
                }
            }
        }
        if self.z.iter().any(|v| !v.is_finite()) {
            return Err(format!("KKT matrix: singular at t = {t}"));
        }
        let pattern = self.colouring.pattern();
        if sys.kkt_residual_jacobian(t, y, &self.z, pattern, &mut self.r) {
            return Ok(());
        }
        stats.rhs_evals += self.colouring.colours();
        Self::residual(&self.k, &self.b, &self.z, &mut self.rho0);
        self.ytmp.copy_from_slice(y);
        let mut start = vec![0usize; pattern.len() + 1];
        for (j, rows) in pattern.iter().enumerate() {
            start[j + 1] = start[j] + rows.len();
        }
        for group in self.colouring.groups() {
            for &j in group {
                self.deltas[j] = crate::jacobian::increment(y[j], self.scale[j]);
                self.ytmp[j] = y[j] + self.deltas[j];
            }
            if !sys.kkt_assemble(t, &self.ytmp, &mut self.k, &mut self.b) {
                return Err(format!(
                    "KKT matrix: the system cannot evaluate near t = {t}"
                ));
            }
            Self::residual(&self.k, &self.b, &self.z, &mut self.rho1);
            for &j in group {
                self.ytmp[j] = y[j];
                let inv = 1.0 / self.deltas[j];
                for (e, &i) in pattern[j].iter().enumerate() {
                    self.r[start[j] + e] = (self.rho1[i] - self.rho0[i]) * inv;
                }
            }
        }
        Ok(())
    }

    /// Factors the augmented matrix (module doc) for `c` with the last linearisation.
    pub(crate) fn factor(&mut self, c: f64) -> Result<(), String> {
        if let Some(why) = &self.failed {
            return Err(why.clone());
        }
        let (nq, m) = (self.nq, self.m);
        let pattern = self.colouring.pattern();
        // Triplets: I, −S, −D (−c R_v then −c² R_q, summed), K.
        if self.aug.is_none() {
            let mut idx = Vec::new();
            idx.extend((0..nq).map(|i| (i, i)));
            idx.extend((0..nq).map(|i| (i, nq + i)));
            for (j, rows) in pattern.iter().enumerate() {
                let col = if j >= nq { j - nq } else { j };
                idx.extend(rows.iter().map(|&i| (nq + i, col)));
            }
            let kmat = self
                .kmat
                .as_ref()
                .ok_or("KKT Newton: no linearisation yet")?;
            idx.extend(kmat.idx.iter().map(|&(i, j)| (nq + i, nq + j)));
            self.aug = Some(Fixed::new(2 * nq + m, idx)?);
        }
        let aug = self.aug.as_mut().expect("set above");
        let v = &mut self.aug_values;
        v.clear();
        v.extend((0..nq).map(|_| 1.0));
        v.extend((0..nq).map(|_| -1.0));
        let mut e = 0;
        for (j, rows) in pattern.iter().enumerate() {
            let s = if j >= nq { -c } else { -c * c };
            for _ in rows {
                v.push(s * self.r[e]);
                e += 1;
            }
        }
        v.extend_from_slice(&self.kvals);
        self.r_factored.copy_from_slice(&self.r);
        self.c = c;
        aug.factor(&self.aug_values)
    }

    /// Solves (I − cJ) x = r in place of `r` (length 2 n_q) with the last factorisation.
    pub(crate) fn solve(&self, r: &mut [f64]) -> Result<(), String> {
        let (nq, m, c) = (self.nq, self.m, self.c);
        let aug = match (&self.failed, &self.aug) {
            (None, Some(a)) if a.ok => a,
            (Some(why), _) => return Err(why.clone()),
            _ => return Err("KKT Newton: no factorisation".into()),
        };
        let mut w = self.work.borrow_mut();
        let w = &mut w[..2 * nq + m];
        let (r1, r2) = r.split_at_mut(nq);
        w[..nq].copy_from_slice(r2);
        w[nq..].fill(0.0);
        let pattern = self.colouring.pattern();
        let mut e = 0;
        for (j, rows) in pattern.iter().enumerate() {
            if j >= nq {
                break;
            }
            let x = c * r1[j];
            for &i in rows {
                w[nq + i] += self.r_factored[e] * x;
                e += 1;
            }
        }
        aug.solve(w);
        r2.copy_from_slice(&w[..nq]);
        for (x1, x2) in r1.iter_mut().zip(r2.iter()) {
            *x1 += c * x2;
        }
        Ok(())
    }
}

type Ms = FaerSparseMat<f64>;
type Vs = FaerVec<f64>;

/// The linear solver of the `kkt` path (module doc): reads c from diffsol's Newton matrix
/// (its entry (0, n_q) is −c exactly) and factors the shared linearisation's augmented matrix.
#[derive(Default)]
pub struct KktLu {
    shared: Option<Rc<RefCell<KktNewton>>>,
    /// diffsol's Newton matrix (only its identity block and c are read).
    a: Option<Ms>,
    failed: Option<String>,
}

impl KktLu {
    /// The solver of the linearisation `shared`.
    pub(crate) fn new(shared: Rc<RefCell<KktNewton>>) -> Self {
        KktLu {
            shared: Some(shared),
            a: None,
            failed: None,
        }
    }

    /// c of diffsol's Newton matrix I − cJ_upper, checked to have that structure.
    fn c_of(a: &Ms, nq: usize) -> Result<f64, String> {
        let m = &a.inner()[0];
        let (col_ptr, row_idx, values) = (m.symbolic().col_ptr(), m.symbolic().row_idx(), m.val());
        let entry = |i: usize, j: usize| -> f64 {
            (col_ptr[j]..col_ptr[j + 1])
                .find(|&e| row_idx[e] == i)
                .map_or(0.0, |e| values[e])
        };
        if nq == 0 {
            return Ok(0.0);
        }
        let c = -entry(0, nq);
        let exact = (0..nq).all(|i| entry(i, nq + i) == -c && entry(i, i) == 1.0);
        if exact && c.is_finite() {
            Ok(c)
        } else {
            Err("KKT Newton: the Newton matrix is not I − cJ of y = (q, v)".into())
        }
    }
}

impl LinearSolver<Ms> for KktLu {
    fn set_linearisation<C: LinearOp<V = Vs, T = f64, M = Ms, C = FaerContext>>(&mut self, op: &C) {
        let (Some(shared), Some(a)) = (&self.shared, self.a.as_mut()) else {
            self.failed = Some("KKT Newton: no linearisation set".into());
            return;
        };
        op.matrix_inplace(a);
        let mut sh = shared.borrow_mut();
        self.failed = Self::c_of(a, sh.nq).and_then(|c| sh.factor(c)).err();
    }

    fn set_sparsity<C: LinearOp<V = Vs, T = f64, M = Ms, C = FaerContext>>(&mut self, op: &C) {
        self.a = Some(Ms::new_from_sparsity(
            op.nrows(),
            op.ncols(),
            op.sparsity(),
            *op.context(),
        ));
    }

    fn solve_in_place(&self, b: &mut Vs) -> Result<(), LaError> {
        if let Some(why) = &self.failed {
            return Err(LaError::Other(why.clone()));
        }
        let shared = self
            .shared
            .as_ref()
            .ok_or_else(|| LaError::Other("KKT Newton: no linearisation set".into()))?;
        let sh = shared.borrow();
        if b.len() != 2 * sh.nq {
            return Err(LaError::Other("KKT Newton: wrong length".into()));
        }
        sh.solve(b.inner_mut().col_as_slice_mut(0))
            .map_err(LaError::Other)
    }

    fn solve_transpose_in_place(&self, _b: &mut Vs) -> Result<(), LaError> {
        Err(LaError::Other(
            "KKT Newton: no transposed solve (adjoint problems use the dense or sparse path)"
                .into(),
        ))
    }
}

/// One Newton solve (I − cJ) x = r in place of `r` through `sys`'s KKT form at (t, y), with
/// difference floors `scale` (module doc): what the `kkt` path does at one linearisation and
/// factorisation (the floors `scale` raised as the path raises them, [`increment_floors`]),
/// for tests and checks against a dense Newton matrix. Errors: a system
/// without that form, a pattern out of range, a singular K or augmented matrix.
pub fn newton_solve(
    sys: &dyn KktSystem,
    t: f64,
    y: &[f64],
    c: f64,
    scale: &[f64],
    r: &mut [f64],
) -> Result<(), String> {
    let mut newton = KktNewton::new(sys.kkt_shape(), increment_floors(scale.to_vec()))
        .ok_or("KKT Newton: the shape does not match the state")?;
    if y.len() != 2 * newton.nq || r.len() != y.len() {
        return Err("KKT Newton: wrong length".into());
    }
    newton.linearise(sys, t, y, &mut Stats::default());
    newton.factor(c)?;
    newton.solve(r)
}

/// The entries (row of ρ, column of y, value) of R = ∂ρ/∂y at (t, y) as the `kkt` path
/// computes them (module doc), with difference floors `scale` (raised as
/// [`newton_solve`]'s): for a system's initial checks
/// (a non-finite entry would make every Newton matrix unusable). Errors as
/// [`newton_solve`]'s.
pub fn residual_jacobian(
    sys: &dyn KktSystem,
    t: f64,
    y: &[f64],
    scale: &[f64],
) -> Result<Vec<(usize, usize, f64)>, String> {
    let mut newton = KktNewton::new(sys.kkt_shape(), increment_floors(scale.to_vec()))
        .ok_or("KKT Newton: the shape does not match the state")?;
    if y.len() != 2 * newton.nq {
        return Err("KKT Newton: wrong length".into());
    }
    newton.linearise(sys, t, y, &mut Stats::default());
    if let Some(why) = newton.failed {
        return Err(why);
    }
    let mut out = Vec::with_capacity(newton.r.len());
    let mut e = 0;
    for (j, rows) in newton.colouring.pattern().iter().enumerate() {
        for &i in rows {
            out.push((i, j, newton.r[e]));
            e += 1;
        }
    }
    Ok(out)
}
