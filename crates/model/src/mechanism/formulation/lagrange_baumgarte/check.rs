//! The checks of the Lagrange–Baumgarte equations when a mechanism is built
//! (crates/model/src/initial_check.rs runs them in its order; docs/scene-format.md, "Initial
//! check").
//!
//! ```text
//! 1. point mobility   every point P (offset s') of an integrated body k held by a constraint:
//!                     the inverse mass matrix seen at P, W_P = I₂/m + (A s')⊥(A s')⊥ᵀ/I, has
//!                     eigenvalues 1/m and 1/m + |s'|²/I at every angle; its condition
//!                     1 + m|s'|²/I must stay below 1/PIVOT_TOL                → bodies[k].inertia
//! 2. constraints      Φ, Φ̇, r = γ − 2αΦ̇ − β²Φ and the row of Φ_q finite       → joints[k]
//!    KKT              S = Φ_q M⁻¹ Φ_qᵀ = L Lᵀ with every pivot d_j = L_jj² above
//!                     PIVOT_TOL · S_jj                                         → joints[k]
//! ```
//!
//! d_j / S_jj = sin²θ_j, θ_j the angle between row j of Φ_q M^{-1/2} and the span of the rows
//! before it. The assembly's rank check (assembly.rs) looks at Φ_q alone; masses and inertias
//! far apart can still make S singular in f64. The Cholesky factorisation computes d_j with an
//! absolute error of about (j + 1)·ε·S_jj (Higham, Accuracy and Stability of Numerical
//! Algorithms, 2nd ed., Theorem 10.3): below PIVOT_TOL = 1e-14 ≈ 45 ε a pivot cannot be told
//! from zero in a system of up to about 40 equations, S is singular in f64 and the multipliers
//! λ solved with it are rounding noise. Check 1 is the same bound taken over every angle: a
//! point constraint on a body whose radius of gyration √(I/m) is tiny against |s'| is a
//! pivot 1/(1 + m|s'|²/I) at angles where the constraint directions mix the two eigenvectors
//! (at the start they may happen to be aligned with them, and check 2 would pass).
//!
//! Source: docs/model.md §1 (the KKT system and its Schur complement); docs/scene-format.md,
//! "Errors".

use crate::mechanism::bodies::{BodyInfo, Owner};
use crate::mechanism::constraints::{describe, Constraints, TermKind};
use crate::mechanism::formulation::lagrange_baumgarte::{LagrangeBaumgarte, Work};
use crate::mechanism::scratch::Scratch;
use crate::scene::error::SceneError;
use crate::scene::format::Scene;

/// Relative Cholesky pivot d_j / S_jj at or below which Φ_q M⁻¹ Φ_qᵀ is singular in f64.
pub(crate) const PIVOT_TOL: f64 = 1e-14;

fn fail(path: String, reason: String) -> SceneError {
    SceneError::Dynamics { path, reason }
}

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

impl LagrangeBaumgarte {
    /// Check 1 of the module doc: the point mobility of every point a constraint holds.
    pub(crate) fn check_point_mobility(
        &self,
        scene: &Scene,
        cons: &Constraints,
        info: &[BodyInfo],
    ) -> Result<(), SceneError> {
        for row in &cons.rows {
            for term in &row.terms[..row.n_terms] {
                let (TermKind::Point { s, .. }, Owner::Int(_)) = (term.kind, info[term.body].owner)
                else {
                    continue;
                };
                let b = &info[term.body];
                let cond = 1.0 + b.mass * (s[0] * s[0] + s[1] * s[1]) / b.inertia;
                if !(cond < 1.0 / PIVOT_TOL) {
                    let point = b
                        .points
                        .iter()
                        .find(|(_, p)| **p == s)
                        .map_or_else(|| format!("{s:?}"), |(n, _)| format!("'{n}'"));
                    return Err(fail(
                        format!("bodies[{}].inertia", term.body),
                        format!(
                            "the radius of gyration √(I/m) = {:e} m of {} is too small for its \
                         point {point} at {:e} m from the centre of mass that {} holds: the \
                         inverse mass seen at the point, 1/m + |s'|²/I, is {cond:.3e} times \
                         1/m, beyond the {:e} that f64 can resolve in Φ_q M⁻¹ Φ_qᵀ",
                            (b.inertia / b.mass).sqrt(),
                            b.describe(),
                            s[0].hypot(s[1]),
                            scene.joints[row.joint],
                            1.0 / PIVOT_TOL
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Check 2 of the module doc at (t, y), after the kinematics and the applied forces in
    /// `sc`: every constraint row finite, then every Cholesky pivot of S above PIVOT_TOL.
    pub(crate) fn check_equations(
        &self,
        t: f64,
        scene: &Scene,
        cons: &Constraints,
        info: &[BodyInfo],
        sc: &Scratch,
    ) -> Result<(), SceneError> {
        let mut w = self.work.borrow_mut();
        self.constraint_rows(t, cons, info, sc, &mut w);
        let nq = self.nq;
        for (r, row) in cons.rows.iter().enumerate() {
            // Row r of Φ_q: its terms' blocks, summed per integrated body.
            let mut jr: Vec<(usize, [f64; 3])> = Vec::with_capacity(2);
            for (ti, bi) in cons.row_int[r].iter().enumerate() {
                let Some(i) = *bi else { continue };
                let k = jr.iter().position(|e| e.0 == i).unwrap_or_else(|| {
                    jr.push((i, [0.0; 3]));
                    jr.len() - 1
                });
                for c in 0..3 {
                    jr[k].1[c] += w.term_jac[r][ti][c];
                }
            }
            if !(finite(&[w.phi[r], w.phid[r], w.rc[r]]) && jr.iter().all(|e| finite(&e.1))) {
                let mut dense = vec![0.0; nq];
                for (i, v) in &jr {
                    dense[3 * i..3 * i + 3].copy_from_slice(v);
                }
                let jr = dense;
                return Err(fail(
                    format!("joints[{}]", row.joint),
                    format!(
                        "{}: Φ = {:e}, Φ̇ = {:e}, γ − 2αΦ̇ − β²Φ = {:e} (α = {:e}, β = {:e} 1/s), \
                         row of Φ_q {jr:?}: not finite",
                        describe(row, scene),
                        w.phi[r],
                        w.phid[r],
                        w.rc[r],
                        self.alpha,
                        self.beta
                    ),
                ));
            }
        }
        if let Some((r, ratio)) = self.weak_pivot(&w) {
            let row = &cons.rows[r];
            let bodies: Vec<String> = row.terms[..row.n_terms]
                .iter()
                .filter(|t| matches!(info[t.body].owner, Owner::Int(_)))
                .map(|t| info[t.body].describe())
                .collect();
            return Err(fail(
                format!("joints[{}]", row.joint),
                format!(
                    "Φ_q M⁻¹ Φ_qᵀ is singular in f64: {}, weighted by the inverse masses and \
                     inertias, is a combination of the equations before it (Cholesky pivot \
                     d/S_jj = {ratio:.3e}, at most {PIVOT_TOL:e}); it acts on {}: masses and \
                     inertias too far apart to be solved together",
                    describe(row, scene),
                    bodies.join(" and ")
                ),
            ));
        }
        Ok(())
    }

    /// The first equation j whose Cholesky pivot of S = Φ_q M⁻¹ Φ_qᵀ is at most PIVOT_TOL · S_jj
    /// (or not a number), with d_j / S_jj; None when every pivot is above it. Needs the term
    /// blocks in `w` (after `constraint_rows`).
    fn weak_pivot(&self, w: &Work) -> Option<(usize, f64)> {
        let ratios = self.pivot_ratios(w);
        let j = ratios.iter().position(|r| !(*r > PIVOT_TOL))?;
        Some((j, ratios[j]))
    }

    /// d_j / S_jj of the Cholesky factorisation S = Φ_q M⁻¹ Φ_qᵀ = L Lᵀ, d_j = L_jj², up to and
    /// including the first that is not a positive number (the factorisation stops there). S
    /// is formed and factored in its envelope (linalg.rs, `Envelope`), in row order.
    fn pivot_ratios(&self, w: &Work) -> Vec<f64> {
        let m = w.phi.len();
        let env = &self.env;
        let mut l = vec![0.0; env.len()];
        self.assemble_schur(&w.term_jac[..m], &mut l);
        let diag: Vec<f64> = (0..m).map(|j| l[env.diag(j)]).collect();
        match env.factor::<false>(&mut l) {
            Ok(()) => (0..m).map(|j| l[env.diag(j)].powi(2) / diag[j]).collect(),
            Err(k) => (0..=k)
                .map(|j| {
                    let d = if j == k {
                        l[env.diag(j)]
                    } else {
                        l[env.diag(j)].powi(2)
                    };
                    d / diag[j]
                })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanism::formulation::Formulation;
    use crate::{Mechanism, Scene};

    /// The pivot ratios of S at the mechanism's initial state, and its first weak pivot.
    fn pivots(mech: &Mechanism) -> (Vec<f64>, Option<(usize, f64)>) {
        let Formulation::LagrangeBaumgarte(f) = mech.formulation() else {
            unreachable!("chosen by the scenes below")
        };
        let sc = mech.evaluated(0.0, &mech.initial_state()).unwrap();
        let mut w = Work::new(mech.constraints().len(), f.env.len());
        f.constraint_rows(0.0, mech.constraints(), mech.body_info(), &sc, &mut w);
        (f.pivot_ratios(&w), f.weak_pivot(&w))
    }

    /// A body of mass m, inertia I hanging from the ground by its point P at s' = (1, 0) m,
    /// at angle φ.
    fn pendulum(m: f64, inertia: f64, phi: f64) -> Mechanism {
        let text = format!(
            r#"{{"bodies": [{{"name": "bob", "mass": {m}, "inertia": {inertia},
                 "points": {{"P": [1.0, 0.0]}}, "angle": {phi},
                 "position": [{x}, {y}]}}],
               "joints": [{{"type": "revolute", "name": "pin",
                 "a": {{"body": "bob", "point": "P"}}, "b": {{"body": "ground", "at": [0.0, 0.0]}}}}],
               "t_end": 1.0}}"#,
            x = -phi.cos(),
            y = -phi.sin()
        );
        // Lagrange–Baumgarte's pivots (`auto` would take minimal).
        let mut scene = Scene::from_json_str(&text).unwrap();
        scene.formulation = crate::FormulationName::LagrangeBaumgarte;
        Mechanism::from_scene(&scene).unwrap()
    }

    #[test]
    fn pivots_of_a_pendulum_follow_the_point_mobility() {
        // S = W_P = I₂/m + b bᵀ/I, b = (A s')⊥ = (−sin φ, cos φ), |s'| = 1: the second pivot
        // is d₂/S₂₂ = det S/(S₁₁ S₂₂), det S = (1/m)(1/m + 1/I) (the eigenvalues),
        // S₁₁ = 1/m + sin²φ/I, S₂₂ = 1/m + cos²φ/I; the factorisation computes it with an
        // absolute error of a few ε (Higham, Theorem 10.3). At φ = 0 the rows are the
        // eigenvectors (ratio 1).
        for (m, inertia, phi) in [(2.0, 0.5, 0.7), (1.0, 1e-6, 0.3), (3.0, 1e3, 2.0)] {
            let mech = pendulum(m, inertia, phi);
            let (r, weak) = pivots(&mech);
            let (s, c) = phi.sin_cos();
            let (s11, s22) = (1.0 / m + s * s / inertia, 1.0 / m + c * c / inertia);
            let want = (1.0 / m) * (1.0 / m + 1.0 / inertia) / (s11 * s22);
            assert_eq!(r.len(), 2);
            // d₁/S₁₁ = 1 (as L₁₁², up to the rounding of √ and its square).
            assert!((r[0] - 1.0).abs() <= 2.0 * f64::EPSILON, "{r:?}");
            assert!((r[1] - want).abs() < 4.0 * f64::EPSILON, "{r:?} {want}");
            assert_eq!(weak, None);
        }
        let mech = pendulum(1.0, 1e-6, 0.0);
        let (r, _) = pivots(&mech);
        assert!(
            r.len() == 2 && r.iter().all(|x| (x - 1.0).abs() <= 2.0 * f64::EPSILON),
            "{r:?}"
        );
    }
}
