//! The augmented Lagrangian formulation in absolute coordinates (docs/model.md §12).
//!
//! ```text
//! y = (q, q̇),  q = (x_i, y_i, φ_i) of every integrated body (scene order), as Lagrange–Baumgarte
//!
//! (M + Φ_qᵀ α Φ_q) q̈ = Q − Φ_qᵀ λ* + Φ_qᵀ α c,   c = γ − 2ξω Φ̇ − ω² Φ
//! λ* ← λ* + α (Φ_q q̈ − c)   from λ* = 0, until max|Δq̈| ≤ tol · max|q̈|   (core.rs)
//! α = penalty · (mean mass of the integrated bodies)
//! ```
//! (Φ̈ = Φ_q q̈ − γ: c = −(Φ̇_q q̇ + 2ξωΦ̇ + ω²Φ) of Bayo & Ledesma's notation.) The leading
//! matrix is positive definite for any Φ_q: through singular configurations (the N-four-bar
//! passing the horizontal) and with redundant constraints (parallel cranks), where the
//! Schur complement of Lagrange–Baumgarte is singular. The constraint violation obeys
//! Φ̈ + 2ξωΦ̇ + ω²Φ = 0 where Φ_q has full row rank.
//!
//! Every right-hand side starts the multipliers from zero, so that q̈ is a function of (t, y)
//! (a warm start from the previous evaluation would save about one iteration but make the
//! right-hand side depend on the history of the integrator's stages). Its statistics — the
//! evaluations, iterations, the most iterations of one evaluation and the evaluations that
//! did not converge in `max_iterations` (their last iterate is used) — are kept in
//! [`crate::FormulationStats`].
//!
//! No projection after accepted steps: lash-solver's integrators have no post-step hook
//! (their dense output and error control assume the state they stepped), and the violation
//! stays at the integrator's tolerance in the tests (docs/model.md §12).
//!
//! Sources: Bayo & Ledesma, Nonlinear Dynamics 9 (1996) 113–130; García de Jalón & Bayo,
//! Kinematic and Dynamic Simulation of Multibody Systems (1994), §5.3.

pub(crate) mod columns;
pub(crate) mod core;
pub(crate) mod jacobian;

use std::cell::{Cell, RefCell};

use crate::mechanism::bodies::{Bodies, BodyInfo, Owner};
use crate::mechanism::constraints::{describe, eval_row, Constraints, TermKind};
use crate::mechanism::scratch::Scratch;
use crate::scene::error::SceneError;
use crate::scene::format::{AugmentedLagrangianParams, Scene};

use self::core::{AlCore, Iterations, Mass, SparseRows};

/// Iteration statistics of a formulation that iterates (the augmented Lagrangian), summed
/// over every evaluation since the mechanism was built (or [`crate::Mechanism::reset_formulation_stats`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct FormulationStats {
    /// Acceleration solves (right-hand sides and Jacobians' evaluations).
    pub evaluations: u64,
    /// Multiplier iterations over all of them (one solve with the factor of M + Φ_qᵀαΦ_q
    /// each).
    pub iterations: u64,
    /// The most iterations one evaluation took.
    pub max_iterations: u64,
    /// Evaluations that stopped at `max_iterations` before the tolerance.
    pub unconverged: u64,
}

impl FormulationStats {
    /// Counts one acceleration solve that took `it`.
    pub(crate) fn record(&mut self, it: Iterations) {
        self.evaluations += 1;
        self.iterations += it.count as u64;
        self.max_iterations = self.max_iterations.max(it.count as u64);
        self.unconverged += u64::from(!it.converged);
    }
}

/// α = penalty · (mean mass of the integrated bodies): the scale that makes αΦ_qᵀΦ_q
/// comparable with M (the reasons for the default penalty: `AugmentedLagrangianParams`). A
/// reduced system's loop closures (minimal/loops.rs) use the same α: there a row of Φ_θ
/// has the units of Φ_q times a length, and so has M̄ = RᵀMR against M, which leaves the
/// ratio of αΦ_θᵀΦ_θ to M̄ that of αΦ_qᵀΦ_q to M.
pub(crate) fn penalty_alpha(bodies: &Bodies, params: &AugmentedLagrangianParams) -> f64 {
    let nb = bodies.int_bodies.len().max(1);
    let mean_mass = bodies
        .int_bodies
        .iter()
        .map(|&k| bodies.info[k].mass)
        .sum::<f64>()
        / nb as f64;
    params.penalty * mean_mass
}

/// The buffers of one evaluation.
#[derive(Clone, Debug, Default)]
pub(crate) struct Work {
    pub phi: Vec<f64>,
    pub phid: Vec<f64>,
    /// c = γ − 2ξωΦ̇ − ω²Φ.
    pub c: Vec<f64>,
    pub lam: Vec<f64>,
    /// Jacobian blocks of every row with respect to each of its terms' bodies.
    pub term_jac: Vec<[[f64; 3]; 2]>,
    /// Φ_q of the integrated coordinates (values in the fixed pattern).
    pub rows: SparseRows,
    pub core: AlCore,
}

/// The formulation (module doc).
#[derive(Debug)]
pub(crate) struct AugmentedLagrangian {
    nq: usize,
    mass: Vec<f64>,
    /// 2ξω and ω².
    a2: f64,
    b2: f64,
    work: RefCell<Work>,
    stats: Cell<FormulationStats>,
}

/// The fixed pattern of Φ_q: 3 entries (x, y, φ) for a point term on an integrated body, 1
/// (φ) for an angle term; none on prescribed bodies.
fn pattern(cons: &Constraints) -> SparseRows {
    let mut s = SparseRows {
        start: vec![0],
        ..Default::default()
    };
    for (row, ints) in cons.rows.iter().zip(&cons.row_int) {
        for (ti, term) in row.terms[..row.n_terms].iter().enumerate() {
            let Some(i) = ints[ti] else { continue };
            match term.kind {
                TermKind::Point { .. } => s.col.extend([3 * i, 3 * i + 1, 3 * i + 2]),
                TermKind::Angle { .. } => s.col.push(3 * i + 2),
            }
        }
        s.start.push(s.col.len());
    }
    s.val = vec![0.0; s.col.len()];
    s
}

impl AugmentedLagrangian {
    /// The structure for the constraint equations `cons` on `bodies`.
    pub(crate) fn new(
        cons: &Constraints,
        bodies: &Bodies,
        params: AugmentedLagrangianParams,
    ) -> Self {
        let nq = bodies.nq();
        let mass: Vec<f64> = bodies.inverse_masses().iter().map(|v| 1.0 / v).collect();
        let rows = pattern(cons);
        let m = cons.len();
        let core = AlCore::new(
            nq,
            false,
            &rows,
            penalty_alpha(bodies, &params),
            params.tol,
            params.max_iterations,
        );
        AugmentedLagrangian {
            nq,
            mass,
            a2: 2.0 * params.xi * params.omega,
            b2: params.omega * params.omega,
            work: RefCell::new(Work {
                phi: vec![0.0; m],
                phid: vec![0.0; m],
                c: vec![0.0; m],
                lam: vec![0.0; m],
                term_jac: vec![[[0.0; 3]; 2]; m],
                rows,
                core,
            }),
            stats: Cell::new(FormulationStats::default()),
        }
    }

    /// (2ξω, ω²): c = γ − 2ξωΦ̇ − ω²Φ (crate::kkt).
    pub(crate) fn stabilisation(&self) -> (f64, f64) {
        (self.a2, self.b2)
    }

    /// The penalty α of its leading matrix M + Φ_qᵀαΦ_q (crate::kkt: 1/α regularises K).
    pub(crate) fn penalty(&self) -> f64 {
        self.work.borrow().core.alpha
    }

    /// The constraint rows at the kinematics of `sc`: Φ, Φ̇, c and the values of Φ_q.
    fn constraint_rows(&self, t: f64, cons: &Constraints, info: &[BodyInfo], sc: &Scratch) {
        let mut w = self.work.borrow_mut();
        let w = &mut *w;
        let mut e = 0;
        for (r, (row, ints)) in cons.rows.iter().zip(&cons.row_int).enumerate() {
            let ev = eval_row(row, info, t, sc);
            w.term_jac[r] = ev.jrows;
            w.phi[r] = ev.phi;
            w.phid[r] = ev.phid;
            w.c[r] = ev.gamma - self.a2 * ev.phid - self.b2 * ev.phi;
            for (ti, term) in row.terms[..row.n_terms].iter().enumerate() {
                if ints[ti].is_none() {
                    continue;
                }
                let j = ev.jrows[ti];
                match term.kind {
                    TermKind::Point { .. } => {
                        w.rows.val[e..e + 3].copy_from_slice(&j);
                        e += 3;
                    }
                    TermKind::Angle { .. } => {
                        w.rows.val[e] = j[2];
                        e += 1;
                    }
                }
            }
        }
    }

    /// Assembles and factors M + Φ_qᵀαΦ_q; Err(j): pivot j not positive.
    fn factor(&self) -> Result<(), usize> {
        let mut w = self.work.borrow_mut();
        let Work { rows, core, .. } = &mut *w;
        core.assemble(Mass::Diagonal(&self.mass), rows);
        core.factor()
    }

    /// q̈ into `sc.qdd` from the applied forces `sc.g` (after the kinematics). False if the
    /// leading matrix is not positive definite in f64 or q̈ is not finite.
    pub(crate) fn accelerations(
        &self,
        t: f64,
        cons: &Constraints,
        info: &[BodyInfo],
        sc: &mut Scratch,
    ) -> bool {
        self.constraint_rows(t, cons, info, sc);
        if self.factor().is_err() {
            return false;
        }
        let mut w = self.work.borrow_mut();
        let Work {
            c, lam, rows, core, ..
        } = &mut *w;
        lam.iter_mut().for_each(|v| *v = 0.0);
        let it = core.solve(rows, &sc.g[..self.nq], c, lam, &mut sc.qdd[..self.nq]);
        let mut s = self.stats.get();
        s.record(it);
        self.stats.set(s);
        sc.qdd[..self.nq].iter().all(|v| v.is_finite())
    }

    /// The statistics so far.
    pub(crate) fn stats(&self) -> FormulationStats {
        self.stats.get()
    }

    /// Sets the statistics back to zero.
    pub(crate) fn reset_stats(&self) {
        self.stats.set(FormulationStats::default());
    }

    /// The constraint forces −Σ J_r,kᵀ λ_r of the last evaluation on every body, added to `cf`
    /// in row order, and the torques −λ of the driver rows: (joint index, τ).
    pub(crate) fn reactions(
        &self,
        cons: &Constraints,
        cf: &mut [[f64; 3]],
        torques: &mut Vec<(usize, f64)>,
    ) {
        let w = self.work.borrow();
        cons.reactions(&w.term_jac, &w.lam, cf, torques);
    }

    /// ‖Φ(q, t)‖₂ of the last evaluation.
    pub(crate) fn constraint_violation(&self) -> f64 {
        let w = self.work.borrow();
        // From +0: an empty sum (no constraint rows) is +0, not `Sum`'s −0 (printed "-0").
        w.phi.iter().fold(0.0, |a, v| a + v * v).sqrt()
    }

    /// The checks at the initial state (after the kinematics and applied forces in `sc`):
    /// every constraint row finite (→ the joint), then M + Φ_qᵀαΦ_q positive definite in f64
    /// (→ the body of the first failing pivot). There is no rank condition on Φ_q.
    pub(crate) fn check_equations(
        &self,
        t: f64,
        scene: &Scene,
        cons: &Constraints,
        info: &[BodyInfo],
        sc: &Scratch,
    ) -> Result<(), SceneError> {
        self.constraint_rows(t, cons, info, sc);
        {
            let w = self.work.borrow();
            for (r, row) in cons.rows.iter().enumerate() {
                let vals = [w.phi[r], w.phid[r], w.c[r]];
                let jr = w.term_jac[r];
                if !(vals.iter().all(|v| v.is_finite())
                    && jr.iter().flatten().all(|v| v.is_finite()))
                {
                    return Err(SceneError::Dynamics {
                        path: format!("joints[{}]", row.joint),
                        reason: format!(
                            "{}: Φ = {:e}, Φ̇ = {:e}, γ − 2ξωΦ̇ − ω²Φ = {:e}, Jacobian blocks \
                             {jr:?}: not finite",
                            describe(row, scene),
                            vals[0],
                            vals[1],
                            vals[2]
                        ),
                    });
                }
            }
        }
        if let Err(j) = self.factor() {
            let k = info
                .iter()
                .position(|b| b.owner == Owner::Int(j / 3))
                .unwrap_or(0);
            return Err(SceneError::Dynamics {
                path: format!("bodies[{k}]"),
                reason: format!(
                    "M + Φ_qᵀαΦ_q (α = {:e}) is not positive definite in f64 at coordinate {} \
                     of {}: the penalty times the constraint Jacobian overflows or swamps \
                     the mass",
                    self.work.borrow().core.alpha,
                    ["x", "y", "φ"][j % 3],
                    info[k].describe()
                ),
            });
        }
        Ok(())
    }
}
