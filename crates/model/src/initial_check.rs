//! The equations of motion checked once when a mechanism is built, so that a scene whose
//! numbers are each finite but whose dynamics f64 cannot compute (an inertia of 1e-182 beside
//! masses of 1e3, ω² or β² beyond 1e308) is rejected with the body or joint to blame, instead
//! of failing as a non-finite state at the first right-hand side of a run.
//!
//! ```text
//! 1. point mobility   every point P (offset s') of an integrated body k held by a constraint:
//!                     the inverse mass matrix seen at P, W_P = I₂/m + (A s')⊥(A s')⊥ᵀ/I, has
//!                     eigenvalues 1/m and 1/m + |s'|²/I at every angle; its condition
//!                     1 + m|s'|²/I must stay below 1/PIVOT_TOL                → bodies[k].inertia
//! 2. at (t_start, y0), the first failure in this order:
//!    prescribed motion   pose, velocity, acceleration of every driven body finite → joints[driver]
//!    clearance forces    δ, δ̇, v_T, F_N, F_T, film F_r, F_t finite              → joints[k]
//!    applied forces      (F_x, F_y, M) of every integrated body finite            → bodies[k]
//!    constraints         Φ, Φ̇, r = γ − 2αΦ̇ − β²Φ and the row of Φ_q finite       → joints[k]
//!    KKT                 S = Φ_q M⁻¹ Φ_qᵀ = L Lᵀ with every pivot d_j = L_jj² above
//!                        PIVOT_TOL · S_jj                                         → joints[k]
//!    accelerations       q̈ = f(t, y)[n_q..] finite                               → bodies[k]
//!    Jacobian            ∂f/∂y finite (the Newton matrix of the implicit methods) → bodies[k]
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

use lash_solver::OdeSystem;

use crate::linalg::cholesky_in_place;
use crate::mechanism::constraints::{Row, TermKind};
use crate::mechanism::{Mechanism, Owner, Scratch};
use crate::scene::SceneError;

/// Relative Cholesky pivot d_j / S_jj at or below which Φ_q M⁻¹ Φ_qᵀ is singular in f64.
pub(crate) const PIVOT_TOL: f64 = 1e-14;

fn fail(path: String, reason: String) -> SceneError {
    SceneError::Dynamics { path, reason }
}

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// `body 'rod' (mass … kg, inertia … kg·m²)` of scene body k.
fn body_desc(mech: &Mechanism, k: usize) -> String {
    let b = &mech.bodies[k];
    format!(
        "body '{}' (mass {:e} kg, inertia {:e} kg·m²)",
        b.name, b.mass, b.inertia
    )
}

fn row_desc(mech: &Mechanism, row: &Row) -> String {
    format!(
        "equation '{}' of {}",
        row.label, mech.scene.joints[row.joint]
    )
}

/// Scene body and name of state component `i` of q (`x`, `y`, `φ`) or, with `dot`, of its
/// time derivative order 1 or 2.
fn component(mech: &Mechanism, i: usize, names: [&str; 3]) -> (usize, String) {
    let k = mech.int_bodies[i / 3];
    (
        k,
        format!("{} of body '{}'", names[i % 3], mech.bodies[k].name),
    )
}

/// Runs the checks of the module doc on `mech` (assembled: `y0` set).
pub(crate) fn check(mech: &Mechanism) -> Result<(), SceneError> {
    check_point_mobility(mech)?;
    let t = mech.t_start;
    let y = mech.y0.clone();
    let nq = mech.nq();
    check_evaluation(mech, t, &y, &mut mech.scratch.borrow_mut())?;
    // The right-hand side itself, as the solvers call it.
    let mut dy = vec![0.0; y.len()];
    mech.rhs(t, &y, &mut dy);
    if let Some(i) = dy[nq..].iter().position(|v| !v.is_finite()) {
        let (k, what) = component(mech, i, ["ẍ", "ÿ", "φ̈"]);
        return Err(fail(
            format!("bodies[{k}]"),
            format!(
                "the acceleration {what} is {} ({})",
                dy[nq + i],
                body_desc(mech, k)
            ),
        ));
    }
    // The Jacobian of the implicit methods (lower half: the upper half is [0 I]).
    let n = y.len();
    let mut jac = faer::Mat::<f64>::zeros(n, n);
    mech.jacobian(t, &y, jac.as_mut());
    for j in 0..n {
        for i in nq..n {
            let v = jac[(i, j)];
            if !v.is_finite() {
                let (k, what) = component(mech, i - nq, ["ẍ", "ÿ", "φ̈"]);
                let by = if j < nq {
                    ["x", "y", "φ"]
                } else {
                    ["ẋ", "ẏ", "φ̇"]
                };
                let (_, by) = component(mech, j % nq, by);
                return Err(fail(
                    format!("bodies[{k}]"),
                    format!(
                        "the Jacobian entry ∂({what})/∂({by}) that the implicit methods need \
                         is {v} ({})",
                        body_desc(mech, k)
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Check 1 of the module doc.
fn check_point_mobility(mech: &Mechanism) -> Result<(), SceneError> {
    for row in &mech.rows {
        for term in &row.terms[..row.n_terms] {
            let (TermKind::Point { s, .. }, Owner::Int(_)) =
                (term.kind, mech.bodies[term.body].owner)
            else {
                continue;
            };
            let b = &mech.bodies[term.body];
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
                        body_desc(mech, term.body),
                        s[0].hypot(s[1]),
                        mech.scene.joints[row.joint],
                        1.0 / PIVOT_TOL
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Check 2 of the module doc, up to the KKT factorisation.
fn check_evaluation(
    mech: &Mechanism,
    t: f64,
    y: &[f64],
    sc: &mut Scratch,
) -> Result<(), SceneError> {
    mech.kinematics(t, y, sc);
    for p in &mech.pres {
        let k = p.body;
        if !(finite(&sc.pose[k]) && finite(&sc.vel[k]) && finite(&sc.acc[k])) {
            return Err(fail(
                format!("joints[{}]", p.driver_joint),
                format!(
                    "the motion it prescribes to body '{}' is not finite at t = {t} \
                     (θ₀ = {:e} rad, ω = {:e} rad/s): pose {:?}, velocity {:?}, \
                     acceleration {:?}",
                    mech.bodies[k].name, p.theta0, p.omega, sc.pose[k], sc.vel[k], sc.acc[k]
                ),
            ));
        }
    }
    mech.applied_forces(t, sc, false);
    for (k, c) in mech.clr.iter().enumerate() {
        let (ev, st) = (sc.clr[k], sc.clr[k].st);
        let quantities = [
            ("δ", st.delta, "m"),
            ("δ̇", st.delta_dot, "m/s"),
            ("v_T", st.v_t, "m/s"),
            ("F_N", ev.f_n, "N"),
            ("F_T", ev.f_t, "N"),
            ("film F_r", ev.f_r, "N"),
            ("film F_t", ev.f_tf, "N"),
        ];
        if quantities.iter().any(|(_, v, _)| !v.is_finite()) {
            let listed: Vec<String> = quantities
                .iter()
                .map(|(name, v, unit)| format!("{name} = {v:e} {unit}"))
                .collect();
            return Err(fail(
                format!("joints[{}]", c.joint),
                format!(
                    "the forces of {} are not finite: {}",
                    mech.scene.joints[c.joint],
                    listed.join(", ")
                ),
            ));
        }
    }
    for (i, &k) in mech.int_bodies.iter().enumerate() {
        let g = &sc.g[3 * i..3 * i + 3];
        if !finite(g) {
            return Err(fail(
                format!("bodies[{k}]"),
                format!(
                    "the applied force and moment (F_x, F_y, M) = {g:?} on {} are not finite \
                     (gravity {:?} m/s²)",
                    body_desc(mech, k),
                    mech.gravity.unwrap_or([0.0; 2])
                ),
            ));
        }
    }
    mech.constraint_rows(t, sc, true);
    let nq = mech.nq();
    for (r, row) in mech.rows.iter().enumerate() {
        let jr = &sc.jac[r * nq..(r + 1) * nq];
        if !(finite(&[sc.phi[r], sc.phid[r], sc.rc[r]]) && finite(jr)) {
            return Err(fail(
                format!("joints[{}]", row.joint),
                format!(
                    "{}: Φ = {:e}, Φ̇ = {:e}, γ − 2αΦ̇ − β²Φ = {:e} (α = {:e}, β = {:e} 1/s), \
                     row of Φ_q {jr:?}: not finite",
                    row_desc(mech, row),
                    sc.phi[r],
                    sc.phid[r],
                    sc.rc[r],
                    mech.alpha,
                    mech.beta
                ),
            ));
        }
    }
    if let Some((r, ratio)) = weak_pivot(mech, sc) {
        let row = &mech.rows[r];
        let bodies: Vec<String> = row.terms[..row.n_terms]
            .iter()
            .filter(|t| matches!(mech.bodies[t.body].owner, Owner::Int(_)))
            .map(|t| body_desc(mech, t.body))
            .collect();
        return Err(fail(
            format!("joints[{}]", row.joint),
            format!(
                "Φ_q M⁻¹ Φ_qᵀ is singular in f64: {}, weighted by the inverse masses and \
                 inertias, is a combination of the equations before it (Cholesky pivot \
                 d/S_jj = {ratio:.3e}, at most {PIVOT_TOL:e}); it acts on {}: masses and \
                 inertias too far apart to be solved together",
                row_desc(mech, row),
                bodies.join(" and ")
            ),
        ));
    }
    Ok(())
}

/// The first equation j whose Cholesky pivot of S = Φ_q M⁻¹ Φ_qᵀ is at most PIVOT_TOL · S_jj
/// (or not a number), with d_j / S_jj; None when every pivot is above it. Needs Φ_q in
/// `sc.jac` (after `constraint_rows`).
fn weak_pivot(mech: &Mechanism, sc: &Scratch) -> Option<(usize, f64)> {
    let ratios = pivot_ratios(mech, sc);
    let j = ratios.iter().position(|r| !(*r > PIVOT_TOL))?;
    Some((j, ratios[j]))
}

/// d_j / S_jj of the Cholesky factorisation S = Φ_q M⁻¹ Φ_qᵀ = L Lᵀ, d_j = L_jj², up to and
/// including the first that is not a positive number (the factorisation stops there).
fn pivot_ratios(mech: &Mechanism, sc: &Scratch) -> Vec<f64> {
    let nq = mech.nq();
    let m = mech.rows.len();
    let minv = &mech.minv;
    let mut l = vec![0.0; m * m];
    for a in 0..m {
        let ja = &sc.jac[a * nq..(a + 1) * nq];
        for b in 0..=a {
            let jb = &sc.jac[b * nq..(b + 1) * nq];
            l[a * m + b] = (0..nq).map(|j| ja[j] * minv[j] * jb[j]).sum();
        }
    }
    let diag: Vec<f64> = (0..m).map(|j| l[j * m + j]).collect();
    match cholesky_in_place(&mut l, m) {
        Ok(()) => (0..m).map(|j| l[j * m + j].powi(2) / diag[j]).collect(),
        Err(k) => (0..=k)
            .map(|j| {
                let d = if j == k {
                    l[j * m + j]
                } else {
                    l[j * m + j].powi(2)
                };
                d / diag[j]
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Scene;

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
        Mechanism::from_scene(&Scene::from_json_str(&text).unwrap()).unwrap()
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
            let mut sc = mech.scratch.borrow_mut();
            mech.kinematics(0.0, &mech.y0, &mut sc);
            mech.constraint_rows(0.0, &mut sc, true);
            let r = pivot_ratios(&mech, &sc);
            let (s, c) = phi.sin_cos();
            let (s11, s22) = (1.0 / m + s * s / inertia, 1.0 / m + c * c / inertia);
            let want = (1.0 / m) * (1.0 / m + 1.0 / inertia) / (s11 * s22);
            assert_eq!(r.len(), 2);
            // d₁/S₁₁ = 1 (as L₁₁², up to the rounding of √ and its square).
            assert!((r[0] - 1.0).abs() <= 2.0 * f64::EPSILON, "{r:?}");
            assert!((r[1] - want).abs() < 4.0 * f64::EPSILON, "{r:?} {want}");
            assert_eq!(weak_pivot(&mech, &sc), None);
        }
        let mech = pendulum(1.0, 1e-6, 0.0);
        let mut sc = mech.scratch.borrow_mut();
        mech.kinematics(0.0, &mech.y0, &mut sc);
        mech.constraint_rows(0.0, &mut sc, true);
        let r = pivot_ratios(&mech, &sc);
        assert!(
            r.len() == 2 && r.iter().all(|x| (x - 1.0).abs() <= 2.0 * f64::EPSILON),
            "{r:?}"
        );
    }
}
