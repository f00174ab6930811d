//! Rodas5P: a stiffly accurate Rosenbrock–Wanner method of order 5 with an embedded order-4
//! solution and an order-4 continuous extension (Steinebach 2023).
//!
//! ```text
//! W = I/(hγ) − J,   J = ∂f/∂y(t_n, y_n),   f_t = ∂f/∂t(t_n, y_n)
//! stage i = 1..8:
//!   U_i   = y_n + Σ_{j<i} a_ij k_j
//!   W k_i = f(t_n + c_i h, U_i) + d_i h f_t + Σ_{j<i} (C_ij / h) k_j
//! y_{n+1} = U_8 + k_8            (a_8j = a_7j + δ_j7 = a_6j + δ_j6 + δ_j7: stiffly accurate)
//! ŷ_{n+1} = U_8                  (embedded, order 4); error estimate ‖k_8‖
//! dense:  y(t_n + θh) = (1−θ) y_n + θ (y_{n+1} + (1−θ)(K_1 + θ (K_2 + θ K_3))),
//!         K_r = Σ_j H_rj k_j
//! ```
//!
//! quadrature (OdeSystem::quadrature, Q' = q(t, y), out of the error norm): the Q rows of
//! the same stage equations, for the augmented system (y, Q) whose Jacobian has the row
//! g = ∂q/∂y for Q (and a zero column, Q feeding nothing back):
//!   (1/(hγ)) k_i^Q − g·k_i = q(t_n + c_i h, U_i) + d_i h q_t + Σ_{j<i} (C_ij / h) k_j^Q
//!   Q_{n+1} = Q_n + Σ m_j k_j^Q,  estimate |k_8^Q|  (ŷ = U_8)
//! g·k_i (a forward difference of q along k_i) and q_t (a central difference in t) at
//! (t_n, y_n). The row g is needed: with a zero row instead, the untransformed form (HNW II
//! (7.4)) gives k_i^Q = h q_i and Q_{n+1} − Q_n = h Σ b_i q(U_i), and although the weights
//! meet Σ b_i c_i^k = 1/(k+1) for k ≤ 4, the stage states carry Γ's coupling
//! (U_i − y_n = h c_i f + h² Σ_j a_ij (c_j + γ_j) f'f + …), so the order-3 condition
//! Σ b_i a_ij (c_j + γ_j) = 1/6 fails and the integral of a y-dependent q is of order 2 only
//! (measured: tests/quadrature.rs). With g every tree of the augmented system is the
//! method's own: order 5. Cost per accepted step: 18 evaluations of q (8 stages, 8
//! directions, 2 for q_t), none of f. On a stiff component the stage states are poor (stage
//! order 1) and q may depend on it steeply (a lubricant film's force): the differences for
//! g·k_i are then unreliable, and lash-validation keeps Boole's rule on the dense output for
//! this method's runs (its `run/quadrature.rs`).
//!
//! This is the transformed form of HNW II, §IV.7, (7.25)–(7.26) (variables k_i = u_i there), in
//! which every stage needs one right-hand side and one solve with the same LU factors of W.
//! Coefficients: G. Steinebach, "Construction of Rosenbrock–Wanner method Rodas5P and
//! numerical benchmarks within the Julia Differential Equations package", BIT Numer. Math. 63,
//! 27 (2023), as tabulated in OrdinaryDiffEq.jl's `Rodas5PTableau` (γ, a, C, c, d and the dense
//! output matrix H). The test `tableau_is_consistent` checks their redundant data (c_i and d_i
//! recomputed from a and C) and the order conditions up to order 4.
//!
//! Derivatives: J is the system's Jacobian, or forward differences with increments floored
//! at atol_i/rtol ([`crate::jacobian`]). f_t is a central difference in t (~10⁻¹¹ relative; a
//! forward one, ~10⁻⁸, left the dense output with order 2 on forced problems), skipped
//! (f_t = 0) when [`OdeSystem::is_autonomous`] says so, and the system's own
//! ([`OdeSystem::time_derivative`]) when it has one: a difference in t is only as good as f is
//! smooth in t on the scale δ_t ≈ 6e-6 s, and a mechanism in joint coordinates is not (a
//! prescribed crank carries a journal across a lubricant film whose length scale is its gap;
//! the difference's 2 % error there cost Rodas5P 370× the steps on the lubricated press). The
//! order of the method needs the
//! exact J (a Rosenbrock method is not a W-method), so difference errors (~10⁻⁸ relative)
//! show up only below that level. W is factored in place by faer's LU with partial pivoting
//! (or the small LU below).
//!
//! Cost per step: one Jacobian (analytic, or n RHS evaluations by differences), one RHS for
//! f(t_n, y_n), two for ∂f/∂t by differences unless the system is autonomous or gives it
//! (not counted then, like an analytic Jacobian's work); per attempt one
//! LU factorisation of W, 7 RHS evaluations and 8 triangular solves. A rejected attempt reuses
//! J, f(t_n, y_n) and f_t (they belong to the step's start). Fixed steps (`adaptive = false`):
//! h0 on every step, the error estimate ignored.
//!
//! Large sparse systems (crate::linear_algebra's choice, as for diffsol's methods: `auto` from
//! 600 unknowns with a pattern of at most n²/8 entries): J by coloured differences on the
//! system's pattern (colours + 1 RHS evaluations) and W by faer's sparse LU
//! (crate::sparse_lu::ShiftedSparse), O(nnz) memory; the same tableau and step control.
//!
//! Step size: the loop of [`crate::onestep::OneStepDriver`] (default controller Gustafsson's
//! predictive one, [`Method::default_controller`]; any [`crate::ControllerKind`] accepted),
//! with error order p̂ = 4. A singular W (a zero or non-finite pivot) rejects the attempt (`rejected_newton`) and shrinks h by 4;
//! non-finite stages reject it as an error-test failure with ε = ∞. When h falls below
//! max(h_min, 16 ε |t|) the step fails with `NewtonFailure` (the last failure was a singular
//! W), `NonFiniteState` (non-finite stages) or `StepSizeTooSmall`. After a restart the first
//! step is chosen as at t0.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::perm::PermRef;
use faer::{Mat, MatMut, Par};

use crate::error::SolveError;
use crate::jacobian::JacobianEvaluator;
use crate::method::Method;
use crate::onestep::{Attempt, OneStepMethod};
use crate::options::{Atol, Tolerances};
use crate::stats::Stats;
use crate::stepper::{error_norm, StepQuadrature};
use crate::system::OdeSystem;

/// Number of stages.
const S: usize = 8;

/// γ, the diagonal of the Rosenbrock matrix Γ (Steinebach 2023; OrdinaryDiffEq.jl
/// `Rodas5PTableau`).
pub const GAMMA: f64 = 0.21193756319429014;

/// Stage coefficients a_ij of the transformed form, rows 7 and 8 written out
/// (a_7j = a_6j + δ_j6, a_8j = a_7j + δ_j7). Source: OrdinaryDiffEq.jl `Rodas5PTableau`
/// (a21 … a65), Steinebach 2023.
pub const A: [[f64; S]; S] = {
    const R6: [f64; 5] = [
        -7.502846399306121,
        2.561846144803919,
        -11.627539656261098,
        -0.18268767659942256,
        0.030198172008377946,
    ];
    [
        [0.0; S],
        [3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [
            2.849394379747939,
            0.45842242204463923,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
        ],
        [
            -6.954028509809101,
            2.489845061869568,
            -10.358996098473584,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
        ],
        [
            2.8029986275628964,
            0.5072464736228206,
            -0.3988312541770524,
            -0.04721187230404641,
            0.0,
            0.0,
            0.0,
            0.0,
        ],
        [R6[0], R6[1], R6[2], R6[3], R6[4], 0.0, 0.0, 0.0],
        [R6[0], R6[1], R6[2], R6[3], R6[4], 1.0, 0.0, 0.0],
        [R6[0], R6[1], R6[2], R6[3], R6[4], 1.0, 1.0, 0.0],
    ]
};

/// Weights m_j of the solution y_{n+1} = y_n + Σ m_j k_j (= row 8 of [`A`] plus δ_j8).
pub const M: [f64; S] = [A[7][0], A[7][1], A[7][2], A[7][3], A[7][4], 1.0, 1.0, 1.0];

/// Coupling coefficients C_ij of the transformed form (C = diag(1/γ) − Γ⁻¹). Source:
/// OrdinaryDiffEq.jl `Rodas5PTableau` (C21 … C87), Steinebach 2023.
pub const C: [[f64; S]; S] = [
    [0.0; S],
    [-14.155112264123755, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [
        -17.97296035885952,
        -2.859693295451294,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        147.12150275711716,
        -1.41221402718213,
        71.68940251302358,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        165.43517024871676,
        -0.4592823456491126,
        42.90938336958603,
        -5.961986721573306,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        24.854864614690072,
        -3.0009227002832186,
        47.4931110020768,
        5.5814197821558125,
        -0.6610691825249471,
        0.0,
        0.0,
        0.0,
    ],
    [
        30.91273214028599,
        -3.1208243349937974,
        77.79954646070892,
        34.28646028294783,
        -19.097331116725623,
        -28.087943162872662,
        0.0,
        0.0,
    ],
    [
        37.80277123390563,
        -3.2571969029072276,
        112.26918849496327,
        66.9347231244047,
        -40.06618937091002,
        -54.66780262877968,
        -9.48861652309627,
        0.0,
    ],
];

/// Stage times c_i (c_1 = 0; stages 6–8 at t_n + h). Source: OrdinaryDiffEq.jl
/// `Rodas5PTableau` (c2 … c5).
pub const C_TIME: [f64; S] = [
    0.0,
    0.6358126895828704,
    0.4095798393397535,
    0.9769306725060716,
    0.4288403609558664,
    1.0,
    1.0,
    1.0,
];

/// Time-derivative coefficients d_i = Σ_j γ_ij (zero for stages 6–8). Source:
/// OrdinaryDiffEq.jl `Rodas5PTableau` (d1 … d5).
pub const D: [f64; S] = [
    0.21193756319429014,
    -0.42387512638858027,
    -0.3384627126235924,
    1.8046452872882734,
    2.325825639765069,
    0.0,
    0.0,
    0.0,
];

/// Dense-output coefficients H_rj, K_r = Σ_j H_rj k_j (rows h2·, h3·, h4· of
/// OrdinaryDiffEq.jl `Rodas5PTableau`, Steinebach 2023).
pub const H: [[f64; S]; 3] = [
    [
        25.948786856663858,
        -2.5579724845846235,
        10.433815404888879,
        -2.3679251022685204,
        0.524948541321073,
        1.1241088310450404,
        0.4272876194431874,
        -0.17202221070155493,
    ],
    [
        -9.91568850695171,
        -0.9689944594115154,
        3.0438037242978453,
        -24.495224566215796,
        20.176138334709044,
        15.98066361424651,
        -6.789040303419874,
        -6.710236069923372,
    ],
    [
        11.419903575922262,
        2.8879645146136994,
        72.92137995996029,
        80.12511834622643,
        -52.072871366152654,
        -59.78993625266729,
        -0.15582684282751913,
        4.883087185713722,
    ],
];

/// Order of the embedded error estimate (the controller's p̂).
const P_HAT: usize = 4;

/// Systems up to this size are factored by [`SmallLu`]; larger ones by faer.
const SMALL: usize = 32;

/// Dense LU factors of W with partial pivoting, kept between steps (no allocation per step):
/// P W = L U in place. Up to [`SMALL`] unknowns by the unblocked algorithm of [`SmallLu`]
/// (faer's dispatch and workspace handling cost more than the arithmetic at n ≈ 10), above
/// by faer's LU.
struct DenseLu {
    n: usize,
    /// faer's factors (n > SMALL): the matrix in `lu`, permutations and scratch.
    lu: Mat<f64>,
    fwd: Vec<usize>,
    bwd: Vec<usize>,
    mem: MemBuffer,
    small: SmallLu,
}

impl DenseLu {
    fn new(n: usize) -> Self {
        let big = n > SMALL;
        let m = if big { n } else { 0 };
        let req = factor::lu_in_place_scratch::<usize, f64>(m, m, Par::Seq, Default::default())
            .or(solve::solve_in_place_scratch::<usize, f64>(m, 1, Par::Seq));
        DenseLu {
            n,
            lu: Mat::zeros(m, m),
            fwd: vec![0; m],
            bwd: vec![0; m],
            mem: MemBuffer::new(req),
            small: SmallLu::new(if big { 0 } else { n }),
        }
    }

    /// Sets the matrix to diag·I − J.
    fn set_shifted(&mut self, jac: &Mat<f64>, diag: f64) {
        let n = self.n;
        if n > SMALL {
            for j in 0..n {
                for i in 0..n {
                    self.lu[(i, j)] = -jac[(i, j)];
                }
                self.lu[(j, j)] += diag;
            }
        } else {
            for j in 0..n {
                let col = jac.col(j);
                for i in 0..n {
                    self.small.a[i * n + j] = -col[i];
                }
                self.small.a[j * n + j] += diag;
            }
        }
    }

    /// Factors the matrix; false when a pivot is zero or not finite.
    fn factor(&mut self) -> bool {
        if self.n <= SMALL {
            return self.small.factor();
        }
        factor::lu_in_place(
            self.lu.as_mut(),
            &mut self.fwd,
            &mut self.bwd,
            Par::Seq,
            MemStack::new(&mut self.mem),
            Default::default(),
        );
        (0..self.lu.nrows()).all(|i| {
            let p = self.lu[(i, i)];
            p != 0.0 && p.is_finite()
        })
    }

    /// Solves W x = b in place (b in `x`).
    fn solve(&mut self, x: &mut [f64]) {
        let n = x.len();
        if n <= SMALL {
            self.small.solve(x);
            return;
        }
        let perm = PermRef::new_checked(&self.fwd, &self.bwd, n);
        solve::solve_in_place(
            self.lu.as_ref(),
            self.lu.as_ref(),
            perm,
            MatMut::from_column_major_slice_mut(x, n, 1),
            Par::Seq,
            MemStack::new(&mut self.mem),
        );
    }
}

/// W = I/(hγ) − J and its factors: dense (n² f64) or sparse (crate::sparse_lu).
enum Linear {
    Dense { jac: Mat<f64>, w: Box<DenseLu> },
    Sparse(Box<crate::sparse_lu::ShiftedSparse>),
}

impl Linear {
    /// Sets W = d·I − J and factors it; false when it is singular.
    fn factor(&mut self, d: f64) -> bool {
        match self {
            Linear::Dense { jac, w } => {
                w.set_shifted(jac, d);
                w.factor()
            }
            Linear::Sparse(w) => w.factor(d),
        }
    }

    /// Solves W x = b in place.
    fn solve(&mut self, x: &mut [f64]) {
        match self {
            Linear::Dense { w, .. } => w.solve(x),
            Linear::Sparse(w) => w.solve(x),
        }
    }
}

/// LU factorisation with partial pivoting of a small dense matrix, row-major, in place.
///
/// ```text
/// for k = 0..n: p = argmax_{i ≥ k} |a_ik|, swap rows k and p, l_ik = a_ik / a_kk,
///               a_ij −= l_ik a_kj (i, j > k)          (P A = L U, L unit lower)
/// solve: b ← P b, L z = b (forward), U x = z (backward)
/// ```
/// Golub & Van Loan, *Matrix Computations*, 4th ed., Algorithm 3.4.1 (outer-product
/// Gaussian elimination with partial pivoting) and §3.1 (triangular solves).
struct SmallLu {
    n: usize,
    a: Vec<f64>,
    piv: Vec<usize>,
}

impl SmallLu {
    fn new(n: usize) -> Self {
        SmallLu {
            n,
            a: vec![0.0; n * n],
            piv: vec![0; n],
        }
    }

    /// Factors `a` in place; false when a pivot is zero or not finite (the factors are then
    /// not to be used).
    fn factor(&mut self) -> bool {
        let n = self.n;
        let a = &mut self.a;
        for k in 0..n {
            let mut p = k;
            let mut best = a[k * n + k].abs();
            for i in k + 1..n {
                let v = a[i * n + k].abs();
                if v > best {
                    best = v;
                    p = i;
                }
            }
            self.piv[k] = p;
            if p != k {
                for j in 0..n {
                    a.swap(k * n + j, p * n + j);
                }
            }
            let pivot = a[k * n + k];
            if pivot == 0.0 || !pivot.is_finite() {
                return false;
            }
            let (top, bottom) = a.split_at_mut((k + 1) * n);
            let row_k = &top[k * n + k + 1..(k + 1) * n];
            for row_i in bottom.chunks_exact_mut(n) {
                let l = row_i[k] / pivot;
                row_i[k] = l;
                if l != 0.0 {
                    for (x, &u) in row_i[k + 1..].iter_mut().zip(row_k) {
                        *x -= l * u;
                    }
                }
            }
        }
        true
    }

    /// Solves A x = b in place with the factors.
    fn solve(&self, x: &mut [f64]) {
        let n = self.n;
        let a = &self.a;
        for k in 0..n {
            let p = self.piv[k];
            if p != k {
                x.swap(k, p);
            }
        }
        for i in 1..n {
            let row = &a[i * n..i * n + i];
            let s: f64 = row.iter().zip(&x[..i]).map(|(l, v)| l * v).sum();
            x[i] -= s;
        }
        for i in (0..n).rev() {
            let row = &a[i * n + i + 1..(i + 1) * n];
            let s: f64 = row.iter().zip(&x[i + 1..]).map(|(u, v)| u * v).sum();
            x[i] = (x[i] - s) / a[i * n + i];
        }
    }
}

/// Rodas5P as a method of the [`crate::onestep::OneStepDriver`].
///
/// ```text
/// (I/(hγ) − J) k_i = f(t + c_i h, y + Σ a_ij k_j) + d_i h f_t + Σ (C_ij/h) k_j,  i = 1..8
/// y_{n+1} = y_n + Σ m_i k_i,  error ‖k_8‖,  order 5(4)
/// ```
/// Steinebach 2023 (BIT 63:27); see the module documentation for the tableau's source, the
/// dense output and the failure handling.
pub struct Rodas5pMethod {
    autonomous: bool,
    /// The system gives ∂f/∂t ([`OdeSystem::time_derivative`]).
    analytic_ft: bool,
    rtol: f64,
    atol: Atol,
    f0: Vec<f64>,
    dfdt: Vec<f64>,
    lin: Linear,
    jac_eval: JacobianEvaluator,
    k: Vec<Vec<f64>>,
    dense: [Vec<f64>; 3],
    u: Vec<f64>,
    fu: Vec<f64>,
    y_new: Vec<f64>,
    /// The accepted step's h (the quadrature's).
    h_acc: f64,
}

impl Rodas5pMethod {
    /// The method for `sys` with tolerances `tol` (the finite-difference increments of the
    /// Jacobian are floored at atol_i/rtol), on dense matrices. Nothing is evaluated before
    /// the first step.
    pub fn new<Sy: OdeSystem + ?Sized>(sys: &Sy, tol: &Tolerances) -> Self {
        let n = sys.dim();
        Self::with_linear(
            sys,
            tol,
            Linear::Dense {
                jac: Mat::zeros(n, n),
                w: Box::new(DenseLu::new(n)),
            },
        )
    }

    /// The method on sparse matrices (crate::linear_algebra's sparse path): ∂f/∂y by
    /// coloured differences on `colouring`'s pattern, W by faer's sparse LU
    /// (crate::sparse_lu); the dense method ([`Rodas5pMethod::new`]) when the pattern's
    /// symbolic factorisation fails.
    pub fn sparse<Sy: OdeSystem + ?Sized>(
        sys: &Sy,
        tol: &Tolerances,
        colouring: crate::jacobian::Colouring,
    ) -> Self {
        match crate::sparse_lu::ShiftedSparse::new(colouring) {
            Some(w) => Self::with_linear(sys, tol, Linear::Sparse(Box::new(w))),
            None => Self::new(sys, tol),
        }
    }

    /// Whether it runs on sparse matrices.
    pub fn is_sparse(&self) -> bool {
        matches!(self.lin, Linear::Sparse(_))
    }

    fn with_linear<Sy: OdeSystem + ?Sized>(sys: &Sy, tol: &Tolerances, lin: Linear) -> Self {
        let n = sys.dim();
        let (rtol, atol) = (tol.rtol(), tol.atol());
        let scale = (0..n).map(|i| atol.get(i) / rtol).collect();
        Rodas5pMethod {
            autonomous: sys.is_autonomous(),
            analytic_ft: sys.has_time_derivative(),
            rtol,
            atol: atol.clone(),
            f0: vec![0.0; n],
            dfdt: vec![0.0; n],
            lin,
            jac_eval: JacobianEvaluator::new(scale),
            k: vec![vec![0.0; n]; S],
            dense: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            u: vec![0.0; n],
            fu: vec![0.0; n],
            y_new: vec![0.0; n],
            h_acc: 0.0,
        }
    }
}

impl<Sy: OdeSystem + ?Sized> OneStepMethod<Sy> for Rodas5pMethod {
    fn method(&self) -> Method {
        Method::Rodas5p
    }
    fn error_order(&self) -> usize {
        P_HAT
    }

    /// Evaluates f(t, y), J and f_t at the step's start (reused by every attempt).
    fn start(&mut self, sys: &Sy, t: f64, y: &[f64], stats: &mut Stats) -> Result<(), SolveError> {
        sys.rhs(t, y, &mut self.f0);
        stats.rhs_evals += 1;
        if !self.f0.iter().all(|v| v.is_finite()) {
            return Err(SolveError::NonFiniteState { t, y: y.to_vec() });
        }
        match &mut self.lin {
            Linear::Dense { jac, .. } => {
                self.jac_eval
                    .jacobian(sys, t, y, &self.f0, jac.as_mut(), stats)
            }
            Linear::Sparse(w) => w.jacobian(&mut self.jac_eval, sys, (t, y, &self.f0), stats),
        }
        if self.autonomous {
            self.dfdt.fill(0.0);
        } else if self.analytic_ft {
            sys.time_derivative(t, y, &mut self.dfdt);
        } else {
            self.jac_eval
                .time_derivative(sys, t, y, &self.f0, &mut self.dfdt, stats);
        }
        Ok(())
    }

    fn f_start(&self) -> &[f64] {
        &self.f0
    }

    /// One attempt with step h: fills `k` and `y_new`; the error norm is ‖k_8‖.
    fn attempt(
        &mut self,
        sys: &Sy,
        t: f64,
        y: &[f64],
        h: f64,
        estimate: bool,
        stats: &mut Stats,
    ) -> Attempt {
        let n = y.len();
        // W = I/(hγ) − J
        let diag = 1.0 / (h * GAMMA);
        stats.lu_factorizations += 1;
        if !self.lin.factor(diag) {
            return Attempt::Singular;
        }
        for i in 0..S {
            // Stage value and its right-hand side.
            if i == 0 {
                self.fu.copy_from_slice(&self.f0);
            } else {
                self.u.copy_from_slice(y);
                for j in 0..i {
                    let a = A[i][j];
                    if a != 0.0 {
                        let kj = &self.k[j];
                        for (ul, kl) in self.u.iter_mut().zip(kj) {
                            *ul += a * kl;
                        }
                    }
                }
                sys.rhs(t + C_TIME[i] * h, &self.u, &mut self.fu);
                stats.rhs_evals += 1;
            }
            let (done, rest) = self.k.split_at_mut(i);
            let ki = &mut rest[0];
            let dh = D[i] * h;
            for l in 0..n {
                let mut v = self.fu[l] + dh * self.dfdt[l];
                for (j, kj) in done.iter().enumerate() {
                    v += C[i][j] / h * kj[l];
                }
                ki[l] = v;
            }
            self.lin.solve(ki);
            if !ki.iter().all(|v| v.is_finite()) {
                return Attempt::Error(f64::INFINITY);
            }
        }
        for l in 0..n {
            let mut v = y[l];
            for j in 0..S {
                v += M[j] * self.k[j][l];
            }
            self.y_new[l] = v;
        }
        if !self.y_new.iter().all(|v| v.is_finite()) {
            return Attempt::Error(f64::INFINITY);
        }
        Attempt::Error(if estimate {
            error_norm(&self.k[S - 1], y, &self.y_new, self.rtol, &self.atol)
        } else {
            0.0
        })
    }

    fn y_new(&self) -> &[f64] {
        &self.y_new
    }

    fn accept(&mut self, h: f64) {
        self.h_acc = h;
        for (r, dr) in self.dense.iter_mut().enumerate() {
            for l in 0..dr.len() {
                let mut v = 0.0;
                for j in 0..S {
                    v += H[r][j] * self.k[j][l];
                }
                dr[l] = v;
            }
        }
    }

    fn interpolate(
        &self,
        _sys: &Sy,
        _t_prev: f64,
        _h: f64,
        y_prev: &[f64],
        y: &[f64],
        th: f64,
        out: &mut [f64],
    ) {
        let th1 = 1.0 - th;
        let [k1, k2, k3] = &self.dense;
        for (i, o) in out.iter_mut().enumerate() {
            *o = th1 * y_prev[i] + th * (y[i] + th1 * (k1[i] + th * (k2[i] + th * k3[i])));
        }
    }

    /// The quadrature rows of the stages (module documentation): k_i^Q = hγ (q_i + g·k_i +
    /// d_i h q_t + Σ_{j<i} (C_ij/h) k_j^Q), Q increment Σ m_j k_j^Q, estimate |k_8^Q|, with
    /// q_i at the stage states U_i = y_n + Σ_{j<i} a_ij k_j rebuilt from the accepted step's
    /// stages, g·k_i = ∂q/∂y(t_n, y_n)·k_i a forward difference along k_i (no component moved
    /// by more than √ε (|y_l| + atol_l/rtol)) and q_t a central difference in t.
    fn quadrature(
        &self,
        sys: &Sy,
        t_prev: f64,
        y_prev: &[f64],
        value: &mut [f64],
        estimate: &mut [f64],
    ) -> StepQuadrature {
        let h = self.h_acc;
        let m = value.len();
        let n = y_prev.len();
        let mut u = y_prev.to_vec();
        let mut q0 = vec![0.0; m];
        let mut q = vec![0.0; m];
        sys.quadrature(t_prev, y_prev, &mut q0);
        // q_t by a central difference over a hundredth of the step (a difference in t is
        // only as good as q is smooth in t on its scale: the module documentation's f_t).
        let dt = (0.01 * h).max(1e-10 * t_prev.abs());
        let mut qt = vec![0.0; m];
        sys.quadrature(t_prev + dt, y_prev, &mut q);
        sys.quadrature(t_prev - dt, y_prev, &mut qt);
        for c in 0..m {
            qt[c] = (q[c] - qt[c]) / (2.0 * dt);
        }
        // Each component's scale: |y_l| + atol_l/rtol (the Jacobian's increments' floor).
        let scale: Vec<f64> = (0..n)
            .map(|l| y_prev[l].abs() + self.atol.get(l) / self.rtol)
            .collect();
        let mut gk = vec![0.0; m];
        let mut kq = [const { Vec::new() }; S];
        for i in 0..S {
            // g·k_i: forward difference of q along k_i, no component moved by more than
            // √ε of its scale.
            let k_norm = (0..n).fold(0.0_f64, |a, l| a.max(self.k[i][l].abs() / scale[l]));
            gk.fill(0.0);
            if k_norm > 0.0 && k_norm.is_finite() {
                let eps = f64::EPSILON.sqrt() / k_norm;
                for l in 0..n {
                    u[l] = y_prev[l] + eps * self.k[i][l];
                }
                sys.quadrature(t_prev, &u, &mut q);
                for c in 0..m {
                    gk[c] = (q[c] - q0[c]) / eps;
                }
            }
            u.copy_from_slice(y_prev);
            for (j, kj) in self.k.iter().enumerate().take(i) {
                let a = A[i][j];
                if a != 0.0 {
                    for (ul, kl) in u.iter_mut().zip(kj) {
                        *ul += a * kl;
                    }
                }
            }
            if i == 0 {
                q.copy_from_slice(&q0);
            } else {
                sys.quadrature(t_prev + C_TIME[i] * h, &u, &mut q);
            }
            kq[i] = (0..m)
                .map(|c| {
                    let coupling: f64 = (0..i).map(|j| C[i][j] / h * kq[j][c]).sum();
                    h * GAMMA * (q[c] + gk[c] + D[i] * h * qt[c] + coupling)
                })
                .collect();
        }
        for c in 0..m {
            value[c] = (0..S).map(|j| M[j] * kq[j][c]).sum();
            estimate[c] = kq[S - 1][c].abs();
        }
        StepQuadrature::ValueAndEstimate
    }

    fn reset(&mut self) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Γ from C = diag(1/γ) − Γ⁻¹ (lower triangular inverse), α = a Γ.
    fn gamma_alpha() -> ([[f64; S]; S], [[f64; S]; S]) {
        let mut gi = [[0.0; S]; S];
        for i in 0..S {
            for j in 0..S {
                gi[i][j] = if i == j { 1.0 / GAMMA } else { -C[i][j] };
            }
        }
        let mut g = [[0.0; S]; S];
        for j in 0..S {
            for i in j..S {
                let mut s = if i == j { 1.0 } else { 0.0 };
                for k in j..i {
                    s -= gi[i][k] * g[k][j];
                }
                g[i][j] = s / gi[i][i];
            }
        }
        let mut alpha = [[0.0; S]; S];
        for i in 0..S {
            for j in 0..S {
                alpha[i][j] = (0..S).map(|k| A[i][k] * g[k][j]).sum();
            }
        }
        (g, alpha)
    }

    /// The small LU solves A x = b to rounding (residual ≤ 1e-13 ‖A‖ ‖x‖) for matrices that
    /// need row exchanges (a zero leading entry, graded rows), and reports a singular matrix.
    #[test]
    fn small_lu_solves_and_detects_singularity() {
        for n in [1usize, 2, 5, 12, SMALL] {
            let mut lu = SmallLu::new(n);
            // Deterministic entries in [-1, 1); a_00 = 0 forces a pivot exchange; rows graded
            // by 10^(i mod 4).
            let entry = |i: usize, j: usize| {
                if i == 0 && j == 0 && n > 1 {
                    0.0
                } else {
                    let r = ((i * 37 + j * 91 + 13) % 101) as f64 / 50.5 - 1.0;
                    r * 10f64.powi((i % 4) as i32) + if i == j { 0.5 } else { 0.0 }
                }
            };
            for i in 0..n {
                for j in 0..n {
                    lu.a[i * n + j] = entry(i, j);
                }
            }
            assert!(lu.factor(), "n = {n}");
            let x_true: Vec<f64> = (0..n).map(|i| 1.0 + i as f64 * 0.25).collect();
            let mut x: Vec<f64> = (0..n)
                .map(|i| (0..n).map(|j| entry(i, j) * x_true[j]).sum())
                .collect();
            lu.solve(&mut x);
            let norm_a = (0..n)
                .map(|i| (0..n).map(|j| entry(i, j).abs()).sum::<f64>())
                .fold(0.0, f64::max);
            let norm_x = x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for i in 0..n {
                let r: f64 = (0..n).map(|j| entry(i, j) * x[j]).sum::<f64>()
                    - (0..n).map(|j| entry(i, j) * x_true[j]).sum::<f64>();
                assert!(
                    r.abs() <= 1e-13 * norm_a * norm_x,
                    "n = {n}, row {i}: {r:e}"
                );
            }
        }
        let mut lu = SmallLu::new(3);
        lu.a.copy_from_slice(&[1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 0.0, 1.0, 1.0]);
        assert!(!lu.factor(), "rows 0 and 1 are parallel");
        lu.a.copy_from_slice(&[1.0, 0.0, 0.0, 0.0, f64::NAN, 0.0, 0.0, 0.0, 1.0]);
        assert!(!lu.factor(), "a NaN pivot");
    }

    #[test]
    fn tableau_is_consistent() {
        let (g, alpha) = gamma_alpha();
        for i in 0..S {
            let ci: f64 = alpha[i].iter().sum();
            let di: f64 = g[i].iter().sum();
            assert!(
                (ci - C_TIME[i]).abs() < 1e-13,
                "c_{i}: {ci} vs {}",
                C_TIME[i]
            );
            assert!((di - D[i]).abs() < 1e-13, "d_{i}: {di} vs {}", D[i]);
        }
        // Weights of the original form: b = m Γ (solution), b̂ = m̂ Γ (embedded, k_8 dropped).
        let b: Vec<f64> = (0..S)
            .map(|j| (0..S).map(|k| M[k] * g[k][j]).sum())
            .collect();
        let mut m_hat = M;
        m_hat[S - 1] = 0.0;
        let bh: Vec<f64> = (0..S)
            .map(|j| (0..S).map(|k| m_hat[k] * g[k][j]).sum())
            .collect();
        let beta = |i: usize, j: usize| alpha[i][j] + g[i][j];
        let bp: Vec<f64> = (0..S).map(|i| (0..i).map(|j| beta(i, j)).sum()).collect();
        let al: Vec<f64> = (0..S).map(|i| alpha[i].iter().sum()).collect();
        let gm = GAMMA;
        // HNW II, Table IV.7.1: order conditions of Rosenbrock methods up to order 4 (first
        // three trees of order 4 shown with the bushy one).
        let dot = |w: &[f64], v: &dyn Fn(usize) -> f64| (0..S).map(|i| w[i] * v(i)).sum::<f64>();
        for (w, name) in [(&b, "b"), (&bh, "b̂")] {
            assert!(
                (w.iter().sum::<f64>() - 1.0).abs() < 1e-13,
                "{name}: order 1"
            );
            assert!(
                (dot(w, &|i| bp[i]) - (0.5 - gm)).abs() < 1e-13,
                "{name}: order 2"
            );
            assert!(
                (dot(w, &|i| al[i] * al[i]) - 1.0 / 3.0).abs() < 1e-12,
                "{name}: 3a"
            );
            let bb = dot(w, &|i| (0..i).map(|j| beta(i, j) * bp[j]).sum());
            assert!(
                (bb - (1.0 / 6.0 - gm + gm * gm)).abs() < 1e-12,
                "{name}: 3b"
            );
            assert!(
                (dot(w, &|i| al[i].powi(3)) - 0.25).abs() < 1e-12,
                "{name}: 4a"
            );
        }
    }
}
