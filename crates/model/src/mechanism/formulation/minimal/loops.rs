//! The joints that close a loop, kept as constraints on the reduced system of the minimal
//! formulation by the augmented Lagrangian (docs/model.md §12).
//!
//! ```text
//! Φ(q(θ), t) = 0           the rows of the joints outside the tree (closing joints, and
//!                          drivers of integrated bodies), m of them
//! Φ_θ = Φ_q R(θ)           (m × n)
//! Φ̈ = Φ_q q̈ − γ = Φ_θ θ̈ + Φ_q a_c − γ          (q̈ = R θ̈ + a_c: mod.rs)
//! c̄ = γ − Φ_q a_c − 2ξω Φ̇ − ω² Φ               (Φ_θ θ̈ = c̄: Φ̈ + 2ξωΦ̇ + ω²Φ = 0)
//! (M̄ + Φ_θᵀ α Φ_θ) θ̈ = Q̄ − Φ_θᵀ λ* + Φ_θᵀ α c̄,   M̄ = Rᵀ M R,  Q̄ = Rᵀ (Q − M a_c)
//! λ* ← λ* + α (Φ_θ θ̈ − c̄)   from λ* = 0, until max|Δθ̈| ≤ tol · max|θ̈|
//! ```
//! The iteration, α, ξ, ω and their defaults are the augmented Lagrangian's
//! (augmented_lagrangian/core.rs and [`penalty_alpha`]: the scene's `augmented_lagrangian`
//! object); its statistics are counted as that formulation counts them. The leading matrix is
//! positive definite for any Φ_θ (M̄ is), so singular configurations (the N-four-bar passing
//! the horizontal) and redundant closures (parallel cranks) are run as the augmented
//! Lagrangian runs them; the tree's own joints hold by construction.
//!
//! The Jacobian (minimal/jacobian.rs) differentiates the KKT system at the converged (θ̈, λ*):
//! ```text
//! M̄ ∂θ̈ + Φ_θᵀ ∂λ = Rᵀ ∂Q/∂y_j + ∂_j ρ,   ρ = Rᵀ (Q − M q̈(θ, θ̇; θ̈) − Φ_qᵀ λ*)
//! Φ_θ ∂θ̈        = ∂_j σ,                σ = γ − Φ_q q̈(θ, θ̇; θ̈) − 2ξωΦ̇ − ω²Φ
//! ```
//! with Q, θ̈ and λ* held: ρ and σ are the tree's smooth geometry and the closing rows, taken
//! by the same central differences of the recursive kinematics as the tree's ρ (no force is
//! evaluated), and the columns solved as the augmented Lagrangian's are
//! (augmented_lagrangian/columns.rs). ∂f/∂t is left to the integrator's difference in t
//! (as for the augmented Lagrangian: a driver's rows enter through t).

use std::cell::{Cell, RefCell};

use crate::mechanism::bodies::{Bodies, BodyInfo};
use crate::mechanism::constraints::{eval_row, Constraints};
use crate::mechanism::formulation::augmented_lagrangian::columns::KktColumns;
use crate::mechanism::formulation::augmented_lagrangian::core::{
    AlCore, Iterations, Mass, SparseRows,
};
use crate::mechanism::formulation::augmented_lagrangian::{penalty_alpha, FormulationStats};
use crate::mechanism::scratch::Scratch;
use crate::scene::format::AugmentedLagrangianParams;

/// The closing rows evaluated at one state.
#[derive(Clone, Debug, Default)]
pub(crate) struct RowsAt {
    pub phi: Vec<f64>,
    pub phid: Vec<f64>,
    /// γ − Φ_q acc − 2ξωΦ̇ − ω²Φ for the given absolute accelerations acc (a_c: c̄; q̈: σ).
    pub c: Vec<f64>,
    /// Jacobian blocks of every term.
    pub term_jac: Vec<[[f64; 3]; 2]>,
}

/// The buffers of one evaluation.
#[derive(Clone, Debug, Default)]
pub(crate) struct LoopWork {
    /// The rows at the evaluation (c: c̄).
    pub at: RowsAt,
    /// λ* of the closing rows.
    pub lam: Vec<f64>,
    /// Φ_θ (dense rows over the n coordinates).
    pub theta_rows: SparseRows,
    /// Q̄ (the right-hand side of the iteration).
    pub f: Vec<f64>,
    /// M̄ + Φ_θᵀαΦ_θ and the iteration.
    pub core: AlCore,
    /// The Jacobian's: the rows at a perturbed state, Φ_qᵀλ* there, ∂σ, ∂λ, ∂θ̈.
    pub pert: RowsAt,
    pub force: Vec<f64>,
    pub dsig: Vec<f64>,
    pub dl: Vec<f64>,
    pub dx: Vec<f64>,
    pub kkt: Option<KktColumns>,
}

/// The closing joints' constraints on the reduced system (module doc).
#[derive(Debug)]
pub(crate) struct Loops {
    /// The closing rows (and their integrated bodies), in the order of the mechanism's rows.
    pub cons: Constraints,
    /// Index in the mechanism's rows of each closing row.
    pub index: Vec<usize>,
    info: Vec<BodyInfo>,
    nq: usize,
    n: usize,
    /// 2ξω and ω².
    a2: f64,
    b2: f64,
    work: RefCell<LoopWork>,
    stats: Cell<FormulationStats>,
}

impl Loops {
    /// The rows of the joints `closing` (scene indices) of `cons`, on a tree of n
    /// coordinates; None when there are none.
    pub(crate) fn new(
        closing: &[usize],
        cons: &Constraints,
        bodies: &Bodies,
        n: usize,
        params: &AugmentedLagrangianParams,
    ) -> Option<Loops> {
        let index: Vec<usize> = (0..cons.len())
            .filter(|&r| closing.contains(&cons.rows[r].joint))
            .collect();
        if index.is_empty() {
            return None;
        }
        let m = index.len();
        let sub = Constraints {
            rows: index.iter().map(|&r| cons.rows[r].clone()).collect(),
            row_int: index.iter().map(|&r| cons.row_int[r]).collect(),
        };
        let theta_rows = SparseRows {
            start: (0..=m).map(|a| a * n).collect(),
            col: (0..m).flat_map(|_| 0..n).collect(),
            val: vec![0.0; m * n],
        };
        let core = AlCore::new(
            n,
            true,
            &theta_rows,
            penalty_alpha(bodies, params),
            params.tol,
            params.max_iterations,
        );
        let at = RowsAt {
            phi: vec![0.0; m],
            phid: vec![0.0; m],
            c: vec![0.0; m],
            term_jac: vec![[[0.0; 3]; 2]; m],
        };
        Some(Loops {
            cons: sub,
            index,
            info: bodies.info.clone(),
            nq: bodies.nq(),
            n,
            a2: 2.0 * params.xi * params.omega,
            b2: params.omega * params.omega,
            work: RefCell::new(LoopWork {
                pert: at.clone(),
                at,
                lam: vec![0.0; m],
                theta_rows,
                f: vec![0.0; n],
                core,
                force: vec![0.0; bodies.nq()],
                dsig: vec![0.0; m],
                dl: vec![0.0; m],
                dx: vec![0.0; n],
                kkt: None,
            }),
            stats: Cell::new(FormulationStats::default()),
        })
    }

    /// Number of closing rows.
    pub(crate) fn len(&self) -> usize {
        self.index.len()
    }

    /// The closing rows at the kinematics of `sc` (time t), with c = γ − Φ_q acc − 2ξωΦ̇ −
    /// ω²Φ for the absolute accelerations `acc` (n_q) of the integrated bodies.
    fn rows_at(&self, t: f64, sc: &Scratch, acc: &[f64], out: &mut RowsAt) {
        for (a, (row, ints)) in self.cons.rows.iter().zip(&self.cons.row_int).enumerate() {
            let ev = eval_row(row, &self.info, t, sc);
            let mut ja = 0.0;
            for (ti, bi) in ints.iter().enumerate() {
                if let Some(i) = *bi {
                    for c in 0..3 {
                        ja += ev.jrows[ti][c] * acc[3 * i + c];
                    }
                }
            }
            out.phi[a] = ev.phi;
            out.phid[a] = ev.phid;
            out.c[a] = ev.gamma - ja - self.a2 * ev.phid - self.b2 * ev.phi;
            out.term_jac[a] = ev.jrows;
        }
    }

    /// Φ_θ = Φ_q R (dense rows, n columns) from the term blocks and R (n_q × n, column-major).
    fn theta_rows(&self, term_jac: &[[[f64; 3]; 2]], r: &[f64], out: &mut SparseRows) {
        let (nq, n) = (self.nq, self.n);
        for (a, ints) in self.cons.row_int.iter().enumerate() {
            let vals = &mut out.val[a * n..(a + 1) * n];
            for (j, v) in vals.iter_mut().enumerate() {
                let rj = &r[j * nq..(j + 1) * nq];
                let mut s = 0.0;
                for (ti, bi) in ints.iter().enumerate() {
                    if let Some(i) = *bi {
                        for c in 0..3 {
                            s += term_jac[a][ti][c] * rj[3 * i + c];
                        }
                    }
                }
                *v = s;
            }
        }
    }

    /// θ̈ into `thdd` by the iteration (module doc), given R, a_c and M̄ (n × n row-major,
    /// lower triangle) at the kinematics of `sc` and Q̄ in `thdd`. False if
    /// M̄ + Φ_θᵀαΦ_θ is not positive definite in f64.
    pub(crate) fn solve(
        &self,
        t: f64,
        sc: &Scratch,
        r: &[f64],
        ac: &[f64],
        mbar: &[f64],
        thdd: &mut [f64],
    ) -> bool {
        let mut guard = self.work.borrow_mut();
        let w = &mut *guard;
        self.rows_at(t, sc, ac, &mut w.at);
        self.theta_rows(&w.at.term_jac, r, &mut w.theta_rows);
        w.core.assemble(Mass::Dense(mbar), &w.theta_rows);
        if w.core.factor().is_err() {
            return false;
        }
        w.f.copy_from_slice(thdd);
        w.lam.iter_mut().for_each(|v| *v = 0.0);
        let it = w.core.solve(&w.theta_rows, &w.f, &w.at.c, &mut w.lam, thdd);
        let fix = w.core.refine(
            Mass::Dense(mbar),
            &w.theta_rows,
            &w.f,
            &w.at.c,
            &mut w.lam,
            thdd,
        );
        let mut s = self.stats.get();
        s.record(Iterations {
            count: it.count + fix.count,
            converged: it.converged && fix.converged,
        });
        self.stats.set(s);
        true
    }

    /// Adds the closing rows' Φ_qᵀλ* of the last evaluation to `fc` (n_q, absolute), and
    /// writes their Φ, term blocks and λ* into the mechanism-wide `phi`, `term_jac`, `lam`
    /// (full evaluations: constraint violation and reactions).
    pub(crate) fn closing_forces(
        &self,
        fc: &mut [f64],
        phi: &mut [f64],
        term_jac: &mut [[[f64; 3]; 2]],
        lam: &mut [f64],
    ) {
        let w = self.work.borrow();
        for (a, &r) in self.index.iter().enumerate() {
            phi[r] = w.at.phi[a];
            term_jac[r] = w.at.term_jac[a];
            lam[r] = w.lam[a];
            for (ti, bi) in self.cons.row_int[a].iter().enumerate() {
                if let Some(i) = *bi {
                    for c in 0..3 {
                        fc[3 * i + c] += w.at.term_jac[a][ti][c] * w.lam[a];
                    }
                }
            }
        }
    }

    /// The Jacobian's set-up after an evaluation: B and T of the columns' solve.
    pub(crate) fn start_jacobian(&self) {
        let mut guard = self.work.borrow_mut();
        let w = &mut *guard;
        w.kkt = Some(KktColumns::new(&w.core, &w.theta_rows, self.n));
    }

    /// At a perturbed state (kinematics in `sc`, R there `r`, q̈(θ, θ̇; θ̈) there `qdd`):
    /// subtracts Φ_θᵀλ* from `rho` (n) and writes σ (m) into `sigma` (module doc).
    pub(crate) fn perturbed(
        &self,
        t: f64,
        sc: &Scratch,
        r: &[f64],
        qdd: &[f64],
        rho: &mut [f64],
        sigma: &mut [f64],
    ) {
        let (nq, n) = (self.nq, self.n);
        let mut guard = self.work.borrow_mut();
        let w = &mut *guard;
        self.rows_at(t, sc, qdd, &mut w.pert);
        sigma.copy_from_slice(&w.pert.c);
        w.force.iter_mut().for_each(|v| *v = 0.0);
        for (a, ints) in self.cons.row_int.iter().enumerate() {
            for (ti, bi) in ints.iter().enumerate() {
                if let Some(i) = *bi {
                    for c in 0..3 {
                        w.force[3 * i + c] += w.pert.term_jac[a][ti][c] * w.lam[a];
                    }
                }
            }
        }
        for (j, o) in rho.iter_mut().enumerate().take(n) {
            let rj = &r[j * nq..(j + 1) * nq];
            *o -= rj.iter().zip(&w.force).map(|(x, y)| x * y).sum::<f64>();
        }
    }

    /// One column of ∂θ̈/∂y: `col` (n) holds Rᵀ ∂Q/∂y_j + ∂_j ρ and gets ∂θ̈; `dsig` (m) is
    /// ∂_j σ (after [`Loops::start_jacobian`]).
    pub(crate) fn column(&self, col: &mut [f64], dsig: &[f64]) {
        let mut guard = self.work.borrow_mut();
        let w = &mut *guard;
        let kkt = w.kkt.as_mut().expect("start_jacobian first");
        w.dsig.copy_from_slice(dsig);
        kkt.solve(
            &mut w.core,
            &w.theta_rows,
            col,
            &w.dsig,
            &mut w.dl,
            &mut w.dx,
        );
        col.copy_from_slice(&w.dx);
    }

    /// The statistics so far.
    pub(crate) fn stats(&self) -> FormulationStats {
        self.stats.get()
    }

    /// Sets the statistics back to zero.
    pub(crate) fn reset_stats(&self) {
        self.stats.set(FormulationStats::default());
    }
}
