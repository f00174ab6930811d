//! The checks of an accepted state (`OdeSystem::check_accepted`, run by the integrator at the
//! end of every step): a run never ends with a wrong mechanism and exit 0 (issue 26).
//!
//! ```text
//! every formulation   |Φ_r(q, t)| ≤ VIOLATION_REL · L   (rows of positions, m)
//!                     |Φ_r(q, t)| ≤ VIOLATION_ANGLE      (rows of angles, rad)
//!                     L = the largest attachment offset |s| of the constraint rows (the
//!                     mechanism's size as its joints see it; 1 m when there is none)
//!   → "constraint_violation"
//! lagrange_baumgarte  S = Φ_q M⁻¹ Φ_qᵀ factored as in the acceleration solve; the relative
//!                     pivot of row j, ρ_j = d_j / S_jj (d_j the Cholesky pivot), is sin² of
//!                     the angle between row j of Φ_q M^{-1/2} and the span of the rows before
//!                     it; min_j ρ_j < PIVOT_MIN (or S not positive definite)
//!                     or the step crossed a singular configuration (below)
//!   → "singular_configuration": the rank of Φ_q drops
//! minimal on a tree   nothing: its positions are built from θ through the tree's joints, so
//!                     Φ of every row is rounding by construction (a non-finite state is the
//!                     integrator's NonFiniteState before this check); the scan cost 10 % of
//!                     the lubricated press's bdf run (BENCHMARKS.md, "The press targets
//!                     through `lash run`")
//! ```
//! Why these bounds:
//! - PIVOT_MIN = 1e-8: cond(S) ≥ 1/min ρ, so the multipliers of the Schur-complement solve
//!   carry a relative rounding error of about ε / min ρ; at 1e-8 that is 2e-8, the size of
//!   the default rtol of a scene run (1e-8): past it, the solve's own error is larger than
//!   what the run promises, and at the singular configuration itself the equations of
//!   Lagrange–Baumgarte do not determine the motion (IFToMM A02: the parallelogram turns into
//!   an anti-parallelogram, or the method stalls). The augmented Lagrangian's matrix
//!   M + Φ_qᵀαΦ_q stays positive definite there: it is not checked.
//! - VIOLATION_REL = 1e-2 of the mechanism's size, VIOLATION_ANGLE = 1e-2 rad: above every
//!   run the tests accept (the largest seen: a 1 cm pendulum's reference run in `lash
//!   stiffness`, 3.3e-3 of its size under Baumgarte's drift; the press stays below 1e-6), far
//!   below a mechanism that came apart (an RK4 run beyond its stability limit: 0.8 of it).
//!
//! - A crossing: a step can pass a singular configuration with no accepted state near it.
//!   Every maximal minor of Φ_q vanishes there, so under Lagrange–Baumgarte the determinant of
//!   the best-conditioned m × m minor at the step's start (its columns D by complete pivoting)
//!   changes sign across it: sign det Φ_q(q_b)[:, D] ≠ sign det Φ_q(q_a)[:, D] is a crossing.
//!   (A minor chosen as the best at the start does not degenerate within a step otherwise,
//!   unless the step turns the mechanism that far.) Not looked for when the ideal joints
//!   form a tree (no joint closes a loop: minimal/tree.rs's spanning tree takes every
//!   equation): each integrated body then has one parent link whose rows are invertible in
//!   the body's own coordinates (a pin: the identity in x, y; a slider: the unit direction and
//!   the angle), so Φ_q ordered parents before children is block triangular with invertible
//!   diagonal blocks and has full row rank in every configuration. That is every open chain:
//!   the pivoting's fill-in along a chain made the search O(m²) per step (a 3 000-link chain:
//!   41 % of a one-step run).
//!
//! It costs one kinematic evaluation and the constraint rows per step (two, a factorisation of
//! S, a complete pivoting of Φ_q and two m × m determinants under Lagrange–Baumgarte); it is
//! not counted as a right-hand side. The pivoting and the determinants run on Φ_q's rows
//! stored sparse (each row's entries that are not 0): the dense eliminations' pivots, ties and
//! updates on those entries only, so the same columns and signs in O(m · nnz) while the rows
//! stay sparse (a chain's: 6 entries a row, little fill-in) instead of O(m² n_q) — at a
//! 300-link chain (m = 600, n_q = 900) it was 65 % of the run.

use lash_solver::Rejection;

use crate::mechanism::constraints::{eval_row, RowEval, TermKind};
use crate::mechanism::formulation::Formulation;
use crate::mechanism::Mechanism;

/// Smallest allowed relative pivot of S under Lagrange–Baumgarte (module doc).
pub(crate) const PIVOT_MIN: f64 = 1e-8;
/// Largest allowed |Φ_r| of a row of positions, relative to the mechanism's size (module doc).
pub(crate) const VIOLATION_REL: f64 = 1e-2;
/// Largest allowed |Φ_r| of a row of angles, rad (module doc).
pub(crate) const VIOLATION_ANGLE: f64 = 1e-2;

impl Mechanism {
    /// The mechanism's size L for the violation bound: the largest attachment offset |s| of a
    /// point term of the constraint rows; 1 m when there is none.
    pub(crate) fn constraint_size(&self) -> f64 {
        let l = self
            .constraints
            .rows
            .iter()
            .flat_map(|r| r.terms[..r.n_terms].iter())
            .filter_map(|t| match t.kind {
                TermKind::Point { s, .. } => Some(s[0].hypot(s[1])),
                TermKind::Angle { .. } => None,
            })
            .fold(0.0, f64::max);
        if l > 0.0 {
            l
        } else {
            1.0
        }
    }

    /// The constraint rows evaluated at (t, y) (after the kinematics).
    fn rows_at(&self, t: f64, y: &[f64]) -> Vec<RowEval> {
        let mut sc = self.scratch.borrow_mut();
        self.kinematics(t, y, &mut sc);
        let info = &self.bodies.info;
        self.constraints
            .rows
            .iter()
            .map(|r| eval_row(r, info, t, &sc))
            .collect()
    }

    /// Φ_q of the integrated coordinates from evaluated rows, by rows: (column, value) of
    /// the entries that are not 0 (each the sum over the row's terms in term order from 0, as
    /// a dense m × n_q matrix would hold it).
    fn sparse_jacobian(&self, evals: &[RowEval]) -> Vec<Vec<(usize, f64)>> {
        self.constraints
            .row_int
            .iter()
            .zip(evals)
            .map(|(row, e)| {
                let mut out: Vec<(usize, f64)> = Vec::with_capacity(6);
                for (ti, bi) in row.iter().enumerate() {
                    if let Some(i) = *bi {
                        for c in 0..3 {
                            let j = 3 * i + c;
                            match out.iter_mut().find(|(k, _)| *k == j) {
                                Some((_, v)) => *v += e.jrows[ti][c],
                                None => out.push((j, 0.0 + e.jrows[ti][c])),
                            }
                        }
                    }
                }
                out.retain(|&(_, v)| v != 0.0);
                out
            })
            .collect()
    }

    /// A singular-configuration rejection (module doc) with what was seen.
    fn singular(&self, t: f64, what: String) -> Rejection {
        Rejection {
            kind: "singular_configuration",
            reason: format!(
                "singular configuration at t = {t:e} (rank of Φ_q drops: {what}): \
                 lagrange_baumgarte cannot pass it; use augmented_lagrangian"
            ),
        }
    }

    /// Whether an accepted step has anything to check (module doc): constraint rows, and a
    /// formulation other than minimal on a tree.
    #[inline]
    pub(crate) fn checks_accepted_steps(&self) -> bool {
        !self.constraints.rows.is_empty()
            && !matches!(&self.formulation, Formulation::Minimal(f) if f.closes_no_loop())
    }

    /// The checks of the module doc on the accepted step (t_a, y_a) → (t_b, y_b).
    #[inline(never)]
    pub(crate) fn check_accepted_state(
        &self,
        t_a: f64,
        y_a: &[f64],
        t_b: f64,
        y_b: &[f64],
    ) -> Result<(), Rejection> {
        let cons = &self.constraints;
        if !self.checks_accepted_steps() {
            return Ok(());
        }
        let evals = self.rows_at(t_b, y_b);
        if let Formulation::LagrangeBaumgarte(f) = &self.formulation {
            let term_jac: Vec<_> = evals.iter().map(|e| e.jrows).collect();
            let (rho, row) = f.smallest_relative_pivot(cons, &term_jac);
            if !(rho >= PIVOT_MIN) {
                let r = &cons.rows[row];
                return Err(self.singular(
                    t_b,
                    format!(
                        "equation \"{}\" of joint '{}' depends on the others, relative pivot \
                         {rho:.1e} < {PIVOT_MIN:e}",
                        r.label,
                        self.scene.joints[r.joint].name()
                    ),
                ));
            }
            // Crossed inside the step: the best-conditioned m × m minor of Φ_q at the start
            // changes the sign of its determinant. Not on a tree: its rank holds (module doc).
            if self.rank_holds {
                return self.check_violation(t_b, &evals);
            }
            let (m, nq) = (cons.rows.len(), self.nq());
            let jac_a = self.sparse_jacobian(&self.rows_at(t_a, y_a));
            let jac_b = self.sparse_jacobian(&evals);
            let cols = best_minor(jac_a.clone(), nq);
            let (da, db) = (minor_det(&jac_a, nq, &cols), minor_det(&jac_b, nq, &cols));
            if !(da * db > 0.0) {
                return Err(self.singular(
                    t_b,
                    format!(
                        "the determinant of its best-conditioned {m} × {m} minor at t = \
                         {t_a:e} changed sign inside the step to t = {t_b:e}"
                    ),
                ));
            }
        }
        self.check_violation(t_b, &evals)
    }

    /// The violation bounds of the module doc on the rows' evaluations at t_b.
    fn check_violation(&self, t_b: f64, evals: &[RowEval]) -> Result<(), Rejection> {
        let cons = &self.constraints;
        let size = self.constraint_size();
        for (r, e) in cons.rows.iter().zip(evals) {
            let angle = r.terms[..r.n_terms]
                .iter()
                .all(|t| matches!(t.kind, TermKind::Angle { .. }));
            let (tol, unit) = if angle {
                (VIOLATION_ANGLE, "rad")
            } else {
                (VIOLATION_REL * size, "m")
            };
            if !(e.phi.abs() <= tol) {
                return Err(Rejection {
                    kind: "constraint_violation",
                    reason: format!(
                        "constraint violation at t = {t_b:e}: equation \"{}\" of joint '{}' \
                         is off by {:.3e} {unit}, over its tolerance {tol:.1e} {unit} (the \
                         mechanism came apart; {} cannot hold it at these options)",
                        r.label,
                        self.scene.joints[r.joint].name(),
                        e.phi.abs(),
                        self.formulation.name()
                    ),
                });
            }
        }
        Ok(())
    }
}

/// A sparse matrix by rows: the (column, value) pairs of each row, in no particular order.
type Rows = Vec<Vec<(usize, f64)>>;

/// Row `i`'s entry in column `j` (0 when it holds none).
fn entry(row: &[(usize, f64)], j: usize) -> f64 {
    row.iter().find(|e| e.0 == j).map_or(0.0, |e| e.1)
}

/// `row[j] −= f · v` for every (j, v) of `pivot` that `keep` admits, inserting the entries
/// that fill in (0 − f·v, as a dense row would hold them).
fn eliminate(
    row: &mut Vec<(usize, f64)>,
    f: f64,
    pivot: &[(usize, f64)],
    keep: impl Fn(usize) -> bool,
) {
    for &(j, v) in pivot {
        if !keep(j) {
            continue;
        }
        match row.iter_mut().find(|e| e.0 == j) {
            Some(e) => e.1 -= f * v,
            None => row.push((j, 0.0 - f * v)),
        }
    }
}

/// The m columns of the best-conditioned m × m minor of `a` (m sparse rows over n columns,
/// full row rank): the pivot columns of Gaussian elimination with complete pivoting, in
/// increasing order.
///
/// The elimination of the dense m × n matrix (its pivots, ties broken by the first position
/// in the permuted row-then-column order, and its updates) run on the entries that are not 0
/// only: the same columns in O(m · nnz) instead of O(m² n) when the rows stay sparse (a
/// chain's Φ_q: 6 entries a row, little fill-in).
fn best_minor(mut a: Rows, n: usize) -> Vec<usize> {
    let m = a.len();
    let mut cols: Vec<usize> = (0..n).collect();
    let mut rows: Vec<usize> = (0..m).collect();
    // pos[j]: the position of column j in `cols`.
    let mut pos: Vec<usize> = (0..n).collect();
    for k in 0..m {
        let (mut bi, mut bj, mut best) = (k, k, -1.0);
        for (ii, &i) in rows.iter().enumerate().skip(k) {
            for &(j, v) in &a[i] {
                let (jj, v) = (pos[j], v.abs());
                if jj >= k && (v > best || (v == best && (ii, jj) < (bi, bj))) {
                    (bi, bj, best) = (ii, jj, v);
                }
            }
        }
        if !(best > 0.0) {
            // Only zeros (or NaN) left: the dense scan stops at the first position, (k, k).
            (bi, bj) = (k, k);
        }
        rows.swap(k, bi);
        cols.swap(k, bj);
        pos[cols[k]] = k;
        pos[cols[bj]] = bj;
        let (p, pc) = (rows[k], cols[k]);
        let piv = entry(&a[p], pc);
        if piv == 0.0 {
            break;
        }
        let pivot = std::mem::take(&mut a[p]);
        for &i in &rows[k + 1..] {
            let f = entry(&a[i], pc) / piv;
            if f != 0.0 {
                eliminate(&mut a[i], f, &pivot, |j| pos[j] > k);
            }
        }
        a[p] = pivot;
    }
    let mut d = cols[..m].to_vec();
    d.sort_unstable();
    d
}

/// The sign of det of the square minor of `a` (sparse rows over n columns) on the columns
/// `cols` (all rows): ±1, 0 for a zero pivot (NaN passes through), by Gaussian elimination
/// with partial pivoting (the last row of largest |entry| in the column) on the entries that
/// are not 0 only, as the dense elimination of the minor would run it.
fn minor_det(a: &[Vec<(usize, f64)>], n: usize, cols: &[usize]) -> f64 {
    let m = cols.len();
    let mut local = vec![usize::MAX; n];
    for (k, &j) in cols.iter().enumerate() {
        local[j] = k;
    }
    let mut w: Rows = a
        .iter()
        .map(|r| {
            r.iter()
                .filter(|e| local[e.0] != usize::MAX)
                .map(|&(j, v)| (local[j], v))
                .collect()
        })
        .collect();
    let mut det = 1.0;
    for k in 0..m {
        let mut p = k;
        let mut best = entry(&w[k], k).abs();
        for (x, row) in w.iter().enumerate().skip(k + 1) {
            let v = entry(row, k).abs();
            if v.total_cmp(&best).is_ge() {
                (p, best) = (x, v);
            }
        }
        if entry(&w[p], k) == 0.0 {
            return 0.0;
        }
        if p != k {
            w.swap(k, p);
            det = -det;
        }
        let piv = entry(&w[k], k);
        det *= piv.signum();
        let pivot = std::mem::take(&mut w[k]);
        for row in &mut w[k + 1..] {
            let f = entry(row, k) / piv;
            if f != 0.0 {
                eliminate(row, f, &pivot, |j| j >= k);
            }
        }
        w[k] = pivot;
    }
    det
}

#[cfg(test)]
mod tests {
    //! A02's parallelogram (N = 1) is regular with its cranks vertical and singular with them
    //! horizontal (every link on one line: Φ_q loses a rank); a pin pulled apart by 4× its
    //! tolerance is a violation, by 0.4× it is not.
    use super::*;
    use crate::iftomm::n_four_bar;
    use crate::scene::format::FormulationName;
    use lash_solver::OdeSystem;

    fn al_accepts(scene: &crate::Scene, ya: &[f64], yb: &[f64]) -> bool {
        let mut scene = scene.clone();
        scene.formulation = FormulationName::AugmentedLagrangian;
        let al = Mechanism::from_scene(&scene).unwrap();
        al.check_accepted(0.0, ya, 0.1, yb).is_ok()
    }

    /// The tree shortcut (module doc, "Not looked for when the ideal joints form a tree"):
    /// set for an open chain with a slider under Lagrange–Baumgarte, not for A02's loop; and
    /// its premise, Φ_q of full row rank in every configuration, holds for that tree at
    /// random poses, the aligned one (every link on one line, where a loop would lose rank)
    /// included: the smallest singular value of Φ_q stays above 0.1 (measured ≥ 0.24 over
    /// these 20 poses; its rows' entries are ±1 and lever arms of 0.2 m), where a loop at its
    /// singular configuration has one at rounding (A02 horizontal, the test below).
    #[test]
    fn a_tree_keeps_its_rank_so_no_crossing_is_looked_for() {
        let l = 0.4;
        let mut bodies = vec![
            serde_json::json!({"name": "slider", "mass": 1.0, "inertia": 0.01,
            "position": [0.0, 0.0], "points": {"P": [0.0, 0.0]}}),
        ];
        let mut joints = vec![serde_json::json!({"type": "translational", "name": "guide",
            "body": "slider", "point": "P", "origin": [0.0, 0.0], "direction": [1.0, 0.0]})];
        let mut parent = "slider".to_string();
        let mut parent_point = "P";
        for i in 0..5 {
            let name = format!("link{i}");
            bodies.push(
                serde_json::json!({"name": name, "mass": 1.0, "inertia": 0.02,
                "position": [l * i as f64 + l / 2.0, 0.0],
                "points": {"A": [-l / 2.0, 0.0], "B": [l / 2.0, 0.0]}}),
            );
            joints.push(
                serde_json::json!({"type": "revolute", "name": format!("pin{i}"),
                "a": {"body": parent, "point": parent_point}, "b": {"body": name, "point": "A"}}),
            );
            parent = name;
            parent_point = "B";
        }
        let scene = serde_json::json!({"bodies": bodies, "joints": joints,
            "gravity": [0.0, -9.81], "t_end": 1.0, "formulation": "lagrange_baumgarte"});
        let scene = crate::Scene::from_json_str(&scene.to_string()).unwrap();
        let m = Mechanism::from_scene(&scene).unwrap();
        assert!(m.rank_holds);
        let (mut a02, _) = n_four_bar(1, 1.0);
        a02.formulation = FormulationName::LagrangeBaumgarte;
        assert!(!Mechanism::from_scene(&a02).unwrap().rank_holds);
        let (nq, mrows) = (m.nq(), m.constraints.rows.len());
        let mut x = 0.3_f64;
        for round in 0..20 {
            let mut y = m.initial_state();
            if round > 0 {
                for v in &mut y[..nq] {
                    x = (x * 7.13 + 0.29).fract();
                    *v += 4.0 * (x - 0.5);
                }
            }
            let rows = m.sparse_jacobian(&m.rows_at(0.0, &y));
            let mut dense = faer::Mat::<f64>::zeros(mrows, nq);
            for (i, row) in rows.iter().enumerate() {
                for &(j, v) in row {
                    dense[(i, j)] = v;
                }
            }
            let sv = dense.singular_values().unwrap();
            let smallest = sv.iter().fold(f64::INFINITY, |a, &v| a.min(v));
            eprintln!("round {round}: {smallest}");
            assert!(smallest > 0.1, "round {round}: {smallest}");
        }
    }

    #[test]
    fn a_parallelogram_is_singular_only_when_horizontal() {
        let (mut scene, _) = n_four_bar(1, 1.0);
        scene.formulation = FormulationName::LagrangeBaumgarte;
        let m = Mechanism::from_scene(&scene).unwrap();
        let y0 = m.initial_state();
        let nq = m.nq();
        // Vertical cranks: a regular configuration.
        assert!(m.check_accepted(0.0, &y0, 0.0, &y0).is_ok());
        // The cranks turned to horizontal along +x (θ = 0), the coupler translated onto the
        // line y = 0 — a consistent configuration where Φ_q loses a rank.
        let mut y = y0.clone();
        for (i, p) in [[0.5, 0.0, 0.0], [1.5, 0.0, 0.0], [1.5, 0.0, 0.0]]
            .iter()
            .enumerate()
        {
            y[3 * i..3 * i + 3].copy_from_slice(p);
        }
        y[nq..].iter_mut().for_each(|v| *v = 0.0);
        let e = m.check_accepted(0.0, &y0, 0.0, &y).unwrap_err();
        assert_eq!(e.kind, "singular_configuration", "{}", e.reason);
        assert!(
            e.reason.contains("use augmented_lagrangian"),
            "{}",
            e.reason
        );
        // A step across the horizontal on the parallelogram branch (θ = 0.05 → −0.05 rad, both
        // ends regular: ρ ≈ θ² ≫ PIVOT_MIN) is a crossing; a step from 0.3 to 0.05 rad is not.
        let at = |th: f64| {
            let (c, s) = (th.cos(), th.sin());
            let mut y = vec![0.0; 2 * nq];
            y[..9].copy_from_slice(&[
                0.5 * c,
                0.5 * s,
                th,
                c + 0.5,
                s,
                0.0,
                1.0 + 0.5 * c,
                0.5 * s,
                th,
            ]);
            y
        };
        assert!(m.check_accepted(0.0, &at(0.3), 0.1, &at(0.05)).is_ok());
        let e = m
            .check_accepted(0.1, &at(0.05), 0.2, &at(-0.05))
            .unwrap_err();
        assert_eq!(e.kind, "singular_configuration", "{}", e.reason);
        assert!(e.reason.contains("changed sign"), "{}", e.reason);
        // The same states are consistent: the augmented Lagrangian accepts them.
        assert!(al_accepts(&scene, &at(0.05), &at(-0.05)));
        scene.formulation = FormulationName::AugmentedLagrangian;
        let al = Mechanism::from_scene(&scene).unwrap();
        assert!(al.check_accepted(0.0, &y0, 0.0, &y).is_ok());
        // A pin pulled apart by 2 cm on a 0.5 m offset (bound 5 mm) is a violation.
        let mut bad = y0.clone();
        bad[1] += 2e-2;
        let e = al.check_accepted(0.0, &y0, 0.0, &bad).unwrap_err();
        assert_eq!(e.kind, "constraint_violation", "{}", e.reason);
        // …and 2 mm is not.
        let mut ok = y0.clone();
        ok[1] += 2e-3;
        assert!(al.check_accepted(0.0, &y0, 0.0, &ok).is_ok());
    }

    #[test]
    fn a_tree_under_minimal_meets_its_joints_by_construction() {
        // The press (crank prescribed, rod on its crank pin, slider on its guide) at states
        // far from any motion it makes: every joint holds to rounding, nothing is rejected.
        let scene = crate::cases::press_scene(crate::cases::PressJoint::Dry, 150.0, 1e-4);
        let m = Mechanism::from_scene(&scene).unwrap();
        assert_eq!(m.formulation_name(), "minimal");
        let y0 = m.initial_state();
        for (k, dy) in [(0, 2.5), (1, 0.3), (2, -40.0), (3, 7.0)] {
            let mut y = y0.clone();
            y[k] += dy;
            assert!(m.check_accepted(0.0, &y0, 0.01, &y).is_ok());
            let phi = m.outputs(0.01, &y).constraint_violation;
            assert!(phi <= 1e-14, "‖Φ‖ = {phi:e} at {y:?}");
        }
    }

    // The dense eliminations the sparse ones replace: the reference they must equal.

    /// The m columns of the best-conditioned m × m minor of a (m × n, row-major, full row rank):
    /// the pivot columns of Gaussian elimination with complete pivoting, in increasing order.
    fn dense_best_minor(a: &[f64], m: usize, n: usize) -> Vec<usize> {
        let mut w = a.to_vec();
        let mut cols: Vec<usize> = (0..n).collect();
        let mut rows: Vec<usize> = (0..m).collect();
        for k in 0..m {
            let (mut bi, mut bj, mut best) = (k, k, -1.0);
            for (ii, &i) in rows.iter().enumerate().skip(k) {
                for (jj, &j) in cols.iter().enumerate().skip(k) {
                    let v = w[i * n + j].abs();
                    if v > best {
                        (bi, bj, best) = (ii, jj, v);
                    }
                }
            }
            rows.swap(k, bi);
            cols.swap(k, bj);
            let (p, pc) = (rows[k], cols[k]);
            let piv = w[p * n + pc];
            if piv == 0.0 {
                break;
            }
            for &i in &rows[k + 1..] {
                let f = w[i * n + pc] / piv;
                if f != 0.0 {
                    for &j in &cols[k..] {
                        w[i * n + j] -= f * w[p * n + j];
                    }
                }
            }
        }
        let mut d = cols[..m].to_vec();
        d.sort_unstable();
        d
    }

    /// det of the square minor of a (row-major, n columns) on the columns `cols` (all rows), by
    /// Gaussian elimination with partial pivoting.
    fn dense_minor_det(a: &[f64], n: usize, cols: &[usize]) -> f64 {
        let m = cols.len();
        let mut w: Vec<f64> = (0..m)
            .flat_map(|i| cols.iter().map(move |&j| a[i * n + j]))
            .collect();
        let mut det = 1.0;
        for k in 0..m {
            let p = (k..m)
                .max_by(|&x, &y| w[x * m + k].abs().total_cmp(&w[y * m + k].abs()))
                .unwrap_or(k);
            if w[p * m + k] == 0.0 {
                return 0.0;
            }
            if p != k {
                for j in 0..m {
                    w.swap(k * m + j, p * m + j);
                }
                det = -det;
            }
            let piv = w[k * m + k];
            det *= piv.signum();
            for i in k + 1..m {
                let f = w[i * m + k] / piv;
                for j in k..m {
                    w[i * m + j] -= f * w[k * m + j];
                }
            }
        }
        det
    }

    /// The sparse rows of a dense row-major m × n matrix.
    fn to_rows(a: &[f64], m: usize, n: usize) -> Rows {
        (0..m)
            .map(|i| {
                (0..n)
                    .filter(|&j| a[i * n + j] != 0.0)
                    .map(|j| (j, a[i * n + j]))
                    .collect()
            })
            .collect()
    }

    #[test]
    fn sparse_pivoting_picks_the_dense_columns_and_signs() {
        // Matrices of small integers (many ties and exact cancellations, the hardest case for
        // equal tie-breaking) and of a chain's pattern with real entries: the sparse complete
        // pivoting chooses the dense one's columns, and the determinants' signs agree on
        // those and on other column sets.
        let mut x = 0.37_f64;
        let mut next = || {
            x = (x * 7.13 + 0.29).fract();
            x
        };
        for (m, n, density) in [(4, 6, 0.6), (12, 18, 0.3), (30, 45, 0.15), (20, 20, 0.5)] {
            for round in 0..20 {
                let a: Vec<f64> = (0..m * n)
                    .map(|_| {
                        if next() < density {
                            if round % 2 == 0 {
                                (next() * 5.0).floor() - 2.0
                            } else {
                                next() - 0.5
                            }
                        } else {
                            0.0
                        }
                    })
                    .collect();
                let rows = to_rows(&a, m, n);
                let d = dense_best_minor(&a, m, n);
                assert_eq!(best_minor(rows.clone(), n), d, "{m} × {n}, round {round}");
                let other: Vec<usize> = (0..m).map(|i| (i * 7 + round) % n).collect();
                let mut other = other;
                other.sort_unstable();
                other.dedup();
                for cols in [&d, &other] {
                    let (s, r) = (minor_det(&rows, n, cols), dense_minor_det(&a, n, cols));
                    assert!(s == r, "{m} × {n}, round {round}: {s} vs {r}");
                }
            }
        }
        // A 40-link chain's Φ_q at an arbitrary pose (6 entries a row).
        let (links, l) = (40, 0.1);
        let (m, n) = (2 * links, 3 * links);
        let mut a = vec![0.0; m * n];
        for k in 0..links {
            let th = 0.3 * k as f64;
            let (s, c) = (th.sin() * l / 2.0, th.cos() * l / 2.0);
            for (r, sign) in [(0, 1.0), (1, 1.0)] {
                let row = 2 * k + r;
                a[row * n + 3 * k + r] = sign;
                a[row * n + 3 * k + 2] = if r == 0 { s } else { -c };
                if k > 0 {
                    a[row * n + 3 * (k - 1) + r] = -1.0;
                    a[row * n + 3 * (k - 1) + 2] = if r == 0 { s } else { -c };
                }
            }
        }
        let rows = to_rows(&a, m, n);
        let d = dense_best_minor(&a, m, n);
        assert_eq!(best_minor(rows.clone(), n), d);
        assert_eq!(minor_det(&rows, n, &d), dense_minor_det(&a, n, &d));
    }
}
