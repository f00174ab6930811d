//! Initial assembly: consistent initial conditions from the scene's guesses, and the rank check
//! of the constraint Jacobian.
//!
//! ```text
//! Φ_a = (Φ of the ideal joints and non-prescribing drivers,
//!        r_J^P − r_B^P − e₀ of every clearance joint)               at t = t_start
//! positions:  q ← q − Φ_a,q⁺ Φ_a(q)      (Newton, minimum-norm step; until max|Φ_a| ≤ 1e-12)
//! velocities: q̇ ← q̇ − Φ_a,q⁺ Φ̇_a(q, q̇)  (one exact projection: Φ̇ is linear in q̇; ė = 0)
//! rank check: Φ_q of the ideal equations must have full row rank at the assembled state
//! ```
//! Φ⁺ is the Moore–Penrose pseudo-inverse (faer's SVD). The minimum-norm step keeps the bodies
//! as near their guessed pose as the constraints allow. Source: Nikravesh, Computer-Aided
//! Analysis of Mechanical Systems (1988), §4 (Newton–Raphson position analysis).

use faer::Mat;

use crate::mechanism::{Mechanism, Owner, Row, Term, TermKind};
use crate::scene::SceneError;

/// Position tolerance of the assembly (m or rad).
const POS_TOL: f64 = 1e-12;
/// Velocity tolerance after the projection (m/s or rad/s).
const VEL_TOL: f64 = 1e-10;
/// Newton iterations before giving up.
const MAX_ITER: usize = 50;
/// Relative singular-value threshold of the rank check.
const RANK_TOL: f64 = 1e-9;

/// The equations held during assembly: the mechanism's rows, then two per clearance joint.
fn assembly_rows(mech: &Mechanism) -> Vec<Row> {
    let mut rows = mech.rows.clone();
    for c in &mech.clr {
        if !c
            .bearing
            .body
            .is_some_and(|k| matches!(mech.bodies[k].owner, Owner::Int(_)))
            && !c
                .journal
                .body
                .is_some_and(|k| matches!(mech.bodies[k].owner, Owner::Int(_)))
        {
            continue;
        }
        for (axis, label) in [(0usize, "eccentricity x"), (1, "eccentricity y")] {
            let mut w = [0.0; 2];
            w[axis] = 1.0;
            let mut row = Row::new(c.joint, label);
            row.konst = -c.e0[axis];
            for (end, sign) in [(&c.journal, 1.0), (&c.bearing, -1.0)] {
                let ws = [sign * w[0], sign * w[1]];
                match end.body {
                    None => row.konst += ws[0] * end.s[0] + ws[1] * end.s[1],
                    Some(k) => row.push(Term {
                        body: k,
                        kind: TermKind::Point { s: end.s, w: ws },
                    }),
                }
            }
            rows.push(row);
        }
    }
    rows
}

/// Evaluates rows at (t, y): values, rates, and the Jacobian on integrated columns.
fn eval(mech: &Mechanism, rows: &[Row], t: f64, y: &[f64]) -> (Vec<f64>, Vec<f64>, Mat<f64>) {
    let nq = mech.nq();
    let mut sc = mech.scratch.borrow_mut();
    mech.kinematics(t, y, &mut sc);
    let mut phi = vec![0.0; rows.len()];
    let mut phid = vec![0.0; rows.len()];
    let mut jac = Mat::<f64>::zeros(rows.len(), nq);
    for (r, row) in rows.iter().enumerate() {
        let ev = mech.eval_row(row, t, &sc);
        phi[r] = ev.phi;
        phid[r] = ev.phid;
        for (ti, term) in row.terms[..row.n_terms].iter().enumerate() {
            if let Owner::Int(i) = mech.bodies[term.body].owner {
                for c in 0..3 {
                    jac[(r, 3 * i + c)] += ev.jrows[ti][c];
                }
            }
        }
    }
    (phi, phid, jac)
}

fn pinv_apply(jac: &Mat<f64>, v: &[f64]) -> Option<Vec<f64>> {
    let svd = jac.thin_svd().ok()?;
    let p = svd.pseudoinverse();
    let n = p.nrows();
    let mut out = vec![0.0; n];
    for i in 0..n {
        for (j, vj) in v.iter().enumerate() {
            out[i] += p[(i, j)] * vj;
        }
    }
    Some(out)
}

fn row_name(mech: &Mechanism, row: &Row) -> (String, String) {
    let j = &mech.scene.joints[row.joint];
    (
        format!("joints[{}]", row.joint),
        format!("equation '{}' of {}", row.label, j),
    )
}

/// Checks that the rows have full row rank; names the first row that depends on earlier ones.
pub(crate) fn check_rank(mech: &Mechanism, rows: &[Row], jac: &Mat<f64>) -> Result<(), SceneError> {
    let m = rows.len();
    let nq = jac.ncols();
    if m == 0 {
        return Ok(());
    }
    let mut sigma_max: f64 = 0.0;
    for r in 1..=m {
        let sub = jac.subrows(0, r).to_owned();
        let sv = sub.singular_values().unwrap_or_default();
        sigma_max = sigma_max.max(sv.first().copied().unwrap_or(0.0));
        let tol = RANK_TOL * sigma_max.max(f64::MIN_POSITIVE);
        let rank = sv.iter().filter(|&&s| s > tol).count();
        if rank < r {
            let (path, what) = row_name(mech, &rows[r - 1]);
            let why = if r > nq {
                format!(
                    "{what} is one equation too many: {r} equations constrain only {nq} \
                     coordinates of the integrated bodies"
                )
            } else {
                format!(
                    "{what} depends on the equations before it (the constraint Jacobian of \
                     the first {r} equations has rank {rank}) at the initial state"
                )
            };
            return Err(SceneError::Redundant { path, reason: why });
        }
    }
    Ok(())
}

/// Newton on positions, projection of velocities, rank check; returns y0 = (q, q̇).
pub(crate) fn assemble(mech: &Mechanism) -> Result<Vec<f64>, SceneError> {
    let nq = mech.nq();
    let t0 = mech.t_start;
    let mut y = vec![0.0; 2 * nq];
    for (i, &k) in mech.int_bodies.iter().enumerate() {
        let b = &mech.scene.bodies[k];
        y[3 * i] = b.position[0];
        y[3 * i + 1] = b.position[1];
        y[3 * i + 2] = b.angle;
        y[nq + 3 * i] = b.velocity[0];
        y[nq + 3 * i + 1] = b.velocity[1];
        y[nq + 3 * i + 2] = b.angular_velocity;
    }
    let rows = assembly_rows(mech);
    if rows.is_empty() {
        return Ok(y);
    }
    let worst = |phi: &[f64]| -> (usize, f64) {
        phi.iter().enumerate().fold((0, 0.0), |(bi, bv), (i, v)| {
            if !(v.abs() <= bv) {
                (i, v.abs())
            } else {
                (bi, bv)
            }
        })
    };
    let fail = |mech: &Mechanism, phi: &[f64], jac: &Mat<f64>, what: &str, iters: usize| {
        check_rank(mech, &rows, jac)?;
        let (i, v) = worst(phi);
        let (path, name) = row_name(mech, &rows[i]);
        Err(SceneError::Assembly {
            path,
            reason: format!("{what}: {name} has residual {v:.3e} after {iters} Newton iterations"),
        })
    };
    let mut converged = false;
    let mut iters = 0;
    for it in 0..=MAX_ITER {
        iters = it;
        let (phi, _, jac) = eval(mech, &rows, t0, &y);
        let (_, err) = worst(&phi);
        if err <= POS_TOL {
            converged = true;
            break;
        }
        if it == MAX_ITER || !err.is_finite() {
            return fail(mech, &phi, &jac, "positions", it);
        }
        let Some(dq) = pinv_apply(&jac, &phi) else {
            return fail(mech, &phi, &jac, "positions", it);
        };
        for j in 0..nq {
            y[j] -= dq[j];
        }
    }
    debug_assert!(converged, "{iters}");
    // Velocities: one projection (Φ̇ is affine in q̇), then verify.
    let (_, phid, jac) = eval(mech, &rows, t0, &y);
    let Some(dv) = pinv_apply(&jac, &phid) else {
        return fail(mech, &phid, &jac, "velocities", 0);
    };
    for j in 0..nq {
        y[nq + j] -= dv[j];
    }
    let (_, phid, jac) = eval(mech, &rows, t0, &y);
    let (_, verr) = worst(&phid);
    let vmax = y[nq..].iter().fold(0.0f64, |a, v| a.max(v.abs()));
    // A huge velocity guess (1e308) overflows in the projection: never return a non-finite y0.
    if !(vmax.is_finite() && verr <= VEL_TOL * (1.0 + vmax)) {
        return fail(mech, &phid, &jac, "velocities", 1);
    }
    // Rank of the ideal equations (the KKT system) at the assembled state.
    let m = mech.rows.len();
    let ideal = jac.subrows(0, m).to_owned();
    check_rank(mech, &mech.rows, &ideal)?;
    Ok(y)
}
