//! Lagrange multipliers with Baumgarte stabilisation: the paper's formulation (docs/model.md
//! §1.3–§1.5), today's only one.
//!
//! ```text
//! y = (q, q̇),  q = (x_i, y_i, φ_i) of every integrated body (scene order)
//!
//! [ M    Φ_qᵀ ] [ q̈ ]   [ g                 ]        M = diag(m_i, m_i, I_i)
//! [ Φ_q  0    ] [ λ  ] = [ γ − 2αΦ̇ − β²Φ    ]        Φ̈ = Φ_q q̈ − γ
//!
//! solved by the range-space (Schur complement) reduction, exactly equivalent for M > 0 and
//! Φ_q of full row rank (checked at the initial state):
//!   S = Φ_q M⁻¹ Φ_qᵀ  (SPD),   S λ = Φ_q M⁻¹ g − (γ − 2αΦ̇ − β²Φ)   (Cholesky),
//!   q̈ = M⁻¹ (g − Φ_qᵀ λ)
//! ```
//! S has a fixed structure (which rows share a body) built once, and is block diagonal up to
//! the order of its rows; it is stored and factored in its envelope (linalg.rs, `Envelope`:
//! a chain's S is banded, so the solve costs O(m), with the numbers of the dense factor).
//! Φ_q itself is formed densely only for the Jacobian (m × n_q, on demand). The Jacobian of this
//! formulation is in jacobian.rs, its checks at the initial state in check.rs.
//!
//! Sources: docs/model.md §1 (Nikravesh, Computer-Aided Analysis of Mechanical Systems, 1988;
//! Baumgarte 1972), Peng et al. 2025 §3.

mod check;
mod jacobian;

use std::cell::RefCell;

use crate::linalg::Envelope;
use crate::mechanism::bodies::{Bodies, BodyInfo};
use crate::mechanism::constraints::{eval_row, Constraints};
use crate::mechanism::formulation::column_terms::ColumnTerms;
use crate::mechanism::scratch::Scratch;
use crate::scene::format::Baumgarte;

/// One block product of the Schur complement S = Φ_q M⁻¹ Φ_qᵀ: term `ta` of row `a` and term
/// `tb` of row `b` (a ≥ b) act on the same integrated body `i`, and add
/// J_{a,ta} M_i⁻¹ J_{b,tb}ᵀ (3-vectors, M_i⁻¹ = diag(1/m, 1/m, 1/I)) to S_ab, stored at `at`
/// in the envelope of S. Built once per scene: the rows of bodies that share no term give
/// S_ab = 0 and cost nothing.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SchurTerm {
    pub a: usize,
    pub b: usize,
    pub ta: usize,
    pub tb: usize,
    pub i: usize,
    pub at: usize,
}

/// The buffers of one evaluation of the constraint side (m equations, n_q coordinates).
#[derive(Clone, Debug, Default)]
pub(crate) struct Work {
    /// Φ_q, m × n_q row-major (the Jacobian and the tests only: empty until
    /// `dense_constraint_jacobian` forms it).
    pub jac: Vec<f64>,
    pub phi: Vec<f64>,
    pub phid: Vec<f64>,
    /// r = γ − 2αΦ̇ − β²Φ.
    pub rc: Vec<f64>,
    /// S, then its factor (its envelope, 1/L_jj on the diagonal).
    pub smat: Vec<f64>,
    pub lam: Vec<f64>,
    /// Jacobian blocks of every row with respect to each of its terms' bodies.
    pub term_jac: Vec<[[f64; 3]; 2]>,
}

impl Work {
    fn new(m: usize, envelope: usize) -> Work {
        Work {
            jac: Vec::new(),
            phi: vec![0.0; m],
            phid: vec![0.0; m],
            rc: vec![0.0; m],
            smat: vec![0.0; envelope],
            lam: vec![0.0; m],
            term_jac: vec![[[0.0; 3]; 2]; m],
        }
    }
}

/// The formulation (module doc).
/// The buffers of [`LagrangeBaumgarte::jacobian`], kept with the formulation so that a
/// Jacobian allocates nothing after the first (each is resized on use).
#[derive(Debug, Default)]
pub(crate) struct JacWork {
    /// W = S⁻¹ Φ_q M⁻¹, m × nq row-major.
    w: Vec<f64>,
    /// N = M⁻¹ − M⁻¹Φ_qᵀ W, nq × nq (symmetric).
    nmat: Vec<f64>,
    /// One column of ∂q̈ (nq).
    low: Vec<f64>,
    /// Φ_q, m × nq column-major.
    phiq: Vec<f64>,
    /// The right-hand sides of one column (built on the first Jacobian).
    terms: Option<ColumnTerms>,
}

#[derive(Debug)]
pub(crate) struct LagrangeBaumgarte {
    nq: usize,
    /// M⁻¹ of the integrated coordinates.
    minv: Vec<f64>,
    alpha: f64,
    beta: f64,
    /// The nonzero block products of S (fixed structure, built once).
    schur: Vec<SchurTerm>,
    /// The rows acting on each integrated body, increasing: the nonzero rows of Φ_q's three
    /// columns of that body (the Jacobian's sparse products).
    rows_of_body: Vec<Vec<usize>>,
    /// The envelope of S in its diagonal blocks (rows that share no body, directly or
    /// through other rows, are in different blocks).
    env: Envelope,
    work: RefCell<Work>,
    jac_work: RefCell<JacWork>,
    /// S of the accepted-state check (mechanism/accepted.rs), kept apart from `work`, which
    /// holds the last evaluation's multipliers.
    check_s: RefCell<Vec<f64>>,
}

impl LagrangeBaumgarte {
    /// The structure of S for the constraint equations `cons` on `bodies`.
    pub(crate) fn new(cons: &Constraints, bodies: &Bodies, baumgarte: Baumgarte) -> Self {
        let (rows, row_int) = (&cons.rows, &cons.row_int);
        // The terms on each integrated body, then every pair of them: O(Σ_i deg_i²), in the
        // order (a, b, ta, tb) of the products' sums.
        let mut on_body: Vec<Vec<(usize, usize)>> = vec![Vec::new(); bodies.nq() / 3];
        for (a, ints) in row_int.iter().enumerate() {
            for (ta, bi) in ints.iter().enumerate() {
                if let Some(i) = *bi {
                    on_body[i].push((a, ta));
                }
            }
        }
        let mut schur = Vec::new();
        for (i, terms) in on_body.iter().enumerate() {
            for &(a, ta) in terms {
                for &(b, tb) in terms {
                    if b <= a {
                        schur.push(SchurTerm {
                            a,
                            b,
                            ta,
                            tb,
                            i,
                            at: 0,
                        });
                    }
                }
            }
        }
        schur.sort_unstable_by_key(|p| (p.a, p.b, p.ta, p.tb));
        let rows_of_body: Vec<Vec<usize>> = on_body
            .iter()
            .map(|terms| {
                let mut r: Vec<usize> = terms.iter().map(|t| t.0).collect();
                r.dedup();
                r
            })
            .collect();
        // Diagonal blocks of S: connected components of the rows under "share a body".
        let mut comp: Vec<usize> = (0..rows.len()).collect();
        fn root(c: &mut [usize], mut a: usize) -> usize {
            while c[a] != a {
                c[a] = c[c[a]];
                a = c[a];
            }
            a
        }
        for p in &schur {
            let (ra, rb) = (root(&mut comp, p.a), root(&mut comp, p.b));
            comp[ra.max(rb)] = ra.min(rb);
        }
        let mut kkt_blocks: Vec<Vec<usize>> = Vec::new();
        let mut block_of = vec![usize::MAX; rows.len()];
        for r in 0..rows.len() {
            let c = root(&mut comp, r);
            if block_of[c] == usize::MAX {
                block_of[c] = kkt_blocks.len();
                kkt_blocks.push(Vec::new());
            }
            kkt_blocks[block_of[c]].push(r);
        }
        let m = rows.len();
        let diagonal = (0..m).map(|a| (a, a));
        let env = Envelope::new(
            m,
            kkt_blocks,
            schur.iter().map(|p| (p.a, p.b)).chain(diagonal),
        );
        for p in &mut schur {
            p.at = env.at(p.a, p.b);
        }
        let nq = bodies.nq();
        LagrangeBaumgarte {
            nq,
            minv: bodies.inverse_masses(),
            alpha: baumgarte.alpha,
            beta: baumgarte.beta,
            work: RefCell::new(Work::new(m, env.len())),
            jac_work: RefCell::default(),
            check_s: RefCell::new(vec![0.0; env.len()]),
            schur,
            rows_of_body,
            env,
        }
    }

    /// (2α, β²): r = γ − 2αΦ̇ − β²Φ (crate::kkt).
    pub(crate) fn stabilisation(&self) -> (f64, f64) {
        (2.0 * self.alpha, self.beta * self.beta)
    }

    /// q̈ into `sc.qdd` from the applied forces `sc.g` (after the kinematics): the constraint
    /// rows, then the KKT system by its Schur complement. False if S is not positive definite.
    /// A full evaluation (`_full`) needs nothing more of this formulation (the reactions come
    /// from the term blocks).
    pub(crate) fn accelerations(
        &self,
        t: f64,
        cons: &Constraints,
        info: &[BodyInfo],
        sc: &mut Scratch,
        _full: bool,
    ) -> bool {
        let mut w = self.work.borrow_mut();
        self.constraint_rows(t, cons, info, sc, &mut w);
        self.solve_kkt(cons, sc, &mut w)
    }

    /// Constraint values, Φ̇, the Baumgarte right-hand side and the Jacobian blocks of every
    /// term (for the Schur complement and the reactions on any body).
    pub(crate) fn constraint_rows(
        &self,
        t: f64,
        cons: &Constraints,
        info: &[BodyInfo],
        sc: &Scratch,
        w: &mut Work,
    ) {
        let (a2, b2) = (2.0 * self.alpha, self.beta * self.beta);
        for (r, row) in cons.rows.iter().enumerate() {
            let ev = eval_row(row, info, t, sc);
            w.term_jac[r] = ev.jrows;
            w.phi[r] = ev.phi;
            w.phid[r] = ev.phid;
            w.rc[r] = ev.gamma - a2 * ev.phid - b2 * ev.phi;
        }
    }

    /// Φ_q (m × n_q, row-major) into `w.jac` from the term blocks (after `constraint_rows`).
    pub(crate) fn dense_constraint_jacobian(&self, cons: &Constraints, w: &mut Work) {
        let nq = self.nq;
        w.jac.clear();
        w.jac.resize(cons.rows.len() * nq, 0.0);
        for (r, (row, jr)) in cons.row_int.iter().zip(&w.term_jac).enumerate() {
            for (ti, bi) in row.iter().enumerate() {
                if let Some(i) = *bi {
                    let base = r * nq + 3 * i;
                    w.jac[base] += jr[ti][0];
                    w.jac[base + 1] += jr[ti][1];
                    w.jac[base + 2] += jr[ti][2];
                }
            }
        }
    }

    /// Solves the KKT system by its Schur complement; false if S is not positive definite.
    ///
    /// ```text
    /// S = Φ_q M⁻¹ Φ_qᵀ,  S λ = Φ_q M⁻¹ g − r,  q̈ = M⁻¹ (g − Φ_qᵀ λ)
    /// ```
    /// Φ_q is used through its term blocks (`term_jac`, three columns of one body each) and S
    /// through its fixed structure (`schur`): no product with a zero block is formed.
    pub(crate) fn solve_kkt(&self, cons: &Constraints, sc: &mut Scratch, w: &mut Work) -> bool {
        let nq = self.nq;
        let m = cons.rows.len();
        let Work {
            term_jac,
            smat,
            lam,
            rc,
            ..
        } = w;
        let Scratch { qdd, g, .. } = sc;
        let minv = &self.minv[..nq];
        let g = &g[..nq];
        let qdd = &mut qdd[..nq];
        if m == 0 {
            for j in 0..nq {
                qdd[j] = minv[j] * g[j];
            }
            return true;
        }
        // q̈ first holds M⁻¹ g, the right-hand side Φ_q M⁻¹ g − r of λ is read from it.
        for j in 0..nq {
            qdd[j] = minv[j] * g[j];
        }
        let term_jac = &term_jac[..m];
        for (a, (row, jr)) in cons.row_int.iter().zip(term_jac).enumerate() {
            let mut ba = -rc[a];
            for (ti, bi) in row.iter().enumerate() {
                if let Some(i) = *bi {
                    let x = &qdd[3 * i..3 * i + 3];
                    let j = &jr[ti];
                    ba += j[0] * x[0] + j[1] * x[1] + j[2] * x[2];
                }
            }
            lam[a] = ba;
        }
        self.assemble_schur(term_jac, smat);
        // S in its envelope (block diagonal up to the order of the rows, banded for a chain):
        // the factor, stored in place, holds the numbers of the dense factor of S.
        if self.env.factor::<true>(smat).is_err() {
            return false;
        }
        self.env.solve(smat, lam);
        // q̈ = M⁻¹ g − M⁻¹ Φ_qᵀ λ.
        for (a, (row, jr)) in cons.row_int.iter().zip(term_jac).enumerate() {
            let la = lam[a];
            for (ti, bi) in row.iter().enumerate() {
                if let Some(i) = *bi {
                    let j = &jr[ti];
                    let w = &minv[3 * i..3 * i + 3];
                    let x = &mut qdd[3 * i..3 * i + 3];
                    x[0] -= w[0] * j[0] * la;
                    x[1] -= w[1] * j[1] * la;
                    x[2] -= w[2] * j[2] * la;
                }
            }
        }
        true
    }

    /// The smallest relative pivot ρ_j = d_j / S_jj of the Cholesky factorisation of
    /// S = Φ_q M⁻¹ Φ_qᵀ from the term blocks of every row (the blocks and order of the
    /// acceleration solve), and its row; ρ ≤ 0 when a pivot is not positive (mechanism/
    /// accepted.rs).
    /// (The first non-positive pivot in row order when there are several.)
    pub(crate) fn smallest_relative_pivot(
        &self,
        cons: &Constraints,
        term_jac: &[[[f64; 3]; 2]],
    ) -> (f64, usize) {
        let m = cons.rows.len();
        let mut smat = self.check_s.borrow_mut();
        self.assemble_schur(term_jac, &mut smat);
        let env = &self.env;
        let diag: Vec<f64> = (0..m).map(|j| smat[env.diag(j)]).collect();
        if let Err(j) = env.factor::<true>(&mut smat) {
            return (smat[env.diag(j)] / diag[j], j);
        }
        let mut best = (f64::INFINITY, 0);
        for blk in env.blocks() {
            for &j in blk {
                // The factor holds 1/√d_j on its diagonal.
                let r = smat[env.diag(j)];
                let d = 1.0 / (r * r);
                let rho = d / diag[j];
                if rho < best.0 {
                    best = (rho, j);
                }
            }
        }
        best
    }

    /// S = Φ_q M⁻¹ Φ_qᵀ into its envelope `smat` from the term blocks of every row (the
    /// products in `schur`'s order, each entry's from 0).
    fn assemble_schur(&self, term_jac: &[[[f64; 3]; 2]], smat: &mut [f64]) {
        smat.fill(0.0);
        for p in &self.schur {
            let (ja, jb) = (&term_jac[p.a][p.ta], &term_jac[p.b][p.tb]);
            let w = &self.minv[3 * p.i..3 * p.i + 3];
            smat[p.at] += ja[0] * w[0] * jb[0] + ja[1] * w[1] * jb[1] + ja[2] * w[2] * jb[2];
        }
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
}

#[cfg(test)]
mod tests {
    //! The Schur-complement solve equals faer's LU solve of the full KKT matrix.
    use crate::cases::{press_scene, PressJoint};
    use crate::mechanism::formulation::Formulation;
    use crate::Mechanism;
    use faer::Mat;

    #[test]
    fn schur_complement_equals_the_full_kkt_solve() {
        let mut scene = press_scene(PressJoint::Dry, 150.0, 1e-4);
        scene.formulation = crate::FormulationName::LagrangeBaumgarte;
        let m = Mechanism::from_scene(&scene).unwrap();
        let Formulation::LagrangeBaumgarte(f) = m.formulation() else {
            unreachable!("chosen above")
        };
        let nq = m.nq();
        let nc = m.constraints().len();
        // A perturbed state: off the constraint manifold, in contact, moving.
        let mut y = m.initial_state();
        let pert = [
            3e-5, -1.2e-4, 2e-3, 1e-4, 2e-5, -1e-3, 0.02, -0.01, 0.3, -0.05, 0.01, 0.002,
        ];
        for (v, p) in y.iter_mut().zip(pert) {
            *v += p;
        }
        let t = 0.123;
        let sc = m.evaluated(t, &y).unwrap();
        let mut w = f.work.borrow_mut();
        f.dense_constraint_jacobian(m.constraints(), &mut w);
        assert!(sc.revolute[0].f_n > 0.0, "the test state is in contact");
        let n = nq + nc;
        let mut kkt = Mat::<f64>::zeros(n, n);
        let mut rhs = Mat::<f64>::zeros(n, 1);
        for j in 0..nq {
            kkt[(j, j)] = 1.0 / f.minv[j];
            rhs[(j, 0)] = sc.g[j];
        }
        for a in 0..nc {
            for j in 0..nq {
                kkt[(nq + a, j)] = w.jac[a * nq + j];
                kkt[(j, nq + a)] = w.jac[a * nq + j];
            }
            rhs[(nq + a, 0)] = w.rc[a];
        }
        use faer::linalg::solvers::Solve;
        let sol = kkt.partial_piv_lu().solve(&rhs);
        for j in 0..nq {
            let d = (sol[(j, 0)] - sc.qdd[j]).abs();
            assert!(
                d <= 1e-9 * sol[(j, 0)].abs().max(1.0),
                "q̈[{j}]: {} vs {}",
                sol[(j, 0)],
                sc.qdd[j]
            );
        }
        for a in 0..nc {
            let d = (sol[(nq + a, 0)] - w.lam[a]).abs();
            assert!(d <= 1e-9 * sol[(nq + a, 0)].abs().max(1.0), "λ[{a}]");
        }
    }
}
