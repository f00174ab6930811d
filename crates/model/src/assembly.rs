//! Initial assembly: consistent initial conditions from the scene's guesses, and the rank check
//! of the constraint Jacobian.
//!
//! ```text
//! Φ_a = (Φ of the ideal joints and non-prescribing drivers,
//!        r_J^P − r_B^P − e₀ of every clearance joint,
//!        n·(r_C − o) − offset₀, φ − φ_guide − tilt₀ of every prismatic clearance joint)
//!                                                                   at t = t_start
//! positions:  q ← q − Φ_a,q⁺ Φ_a(q)      (Newton, minimum-norm step; until max|Φ_a| ≤ 1e-12,
//!             then to rounding: common.rs, `Polish`)
//! velocities: minimise ½ (q̇ − q̇₀)ᵀ M (q̇ − q̇₀)  subject to  Φ̇_a = target rates (ė₀, the
//!             prismatic joints' rates, 0 for the ideal joints) and the exact initial
//!             velocities of the scene (joint initial_rate, body initial_velocity):
//!             q̇ = q̇₀ − M^{-1/2} (J M^{-1/2})⁺ Φ̇(q̇₀)   (one exact step: Φ̇ is affine in q̇)
//! rank check: Φ_q of the ideal equations must have full row rank at the assembled state
//!             (when the formulation needs it: Lagrange multipliers do)
//! ```
//! Φ⁺ is the Moore–Penrose pseudo-inverse (faer's SVD). The minimum-norm position step keeps
//! the bodies as near their guessed pose as the constraints allow; the velocity projection is
//! the one of least kinetic energy of the change (weighted least squares, the KKT projection).
//! What both changed is kept in a [`ProjectionReport`]. Sources: Nikravesh, Computer-Aided
//! Analysis of Mechanical Systems (1988), §4 (Newton–Raphson position analysis); docs/model.md
//! §1 ("Initial conditions").

use faer::Mat;

mod common;
mod sparse;

use common::{
    report, velocity_rows, worst, Polish, MAX_ITER, MAX_PROJECTION_CONDITION,
    MAX_PROJECTION_ENERGY_RATIO, POS_TOL, RANK_TOL, VEL_TOL,
};

use crate::mechanism::bodies::Owner;
use crate::mechanism::constraints::{describe, eval_row, Row};
use crate::mechanism::Mechanism;
use crate::projection::ProjectionReport;
use crate::scene::error::SceneError;

/// The equations held during assembly: the mechanism's constraint equations, then each
/// clearance joint's own (its initial eccentricity, or its initial offset and tilt), with
/// their target rates.
fn assembly_rows(mech: &Mechanism) -> Vec<Row> {
    let t0 = mech.t_start();
    let info = mech.body_info();
    let integrated = |k: usize| matches!(info[k].owner, Owner::Int(_));
    let mut rows = mech.constraints().rows.clone();
    for c in &mech.forces().revolute {
        rows.extend(c.assembly_rows(&integrated, t0));
    }
    for p in &mech.forces().prismatic {
        rows.extend(p.assembly_rows(&integrated, t0));
    }
    rows
}

/// Evaluates rows at (t, y): values, rates, and the Jacobian on integrated columns.
fn eval(mech: &Mechanism, rows: &[Row], t: f64, y: &[f64]) -> (Vec<f64>, Vec<f64>, Mat<f64>) {
    let nq = mech.nq();
    let mut sc = mech.scratch();
    mech.bodies().kinematics(t, y, &mut sc);
    let mut phi = vec![0.0; rows.len()];
    let mut phid = vec![0.0; rows.len()];
    let mut jac = Mat::<f64>::zeros(rows.len(), nq);
    for (r, row) in rows.iter().enumerate() {
        let ev = eval_row(row, mech.body_info(), t, &sc);
        phi[r] = ev.phi;
        phid[r] = ev.phid;
        for (ti, term) in row.terms[..row.n_terms].iter().enumerate() {
            if let Owner::Int(i) = mech.body_info()[term.body].owner {
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
    (
        format!("joints[{}]", row.joint),
        describe(row, mech.scene()),
    )
}

/// Checks that the rows have full row rank; names the first row that depends on earlier ones.
pub(crate) fn check_rank(mech: &Mechanism, rows: &[Row], jac: &Mat<f64>) -> Result<(), SceneError> {
    let m = rows.len();
    let nq = jac.ncols();
    if m == 0 {
        return Ok(());
    }
    // Full row rank of the whole Jacobian implies it for every leading block of rows (the
    // smallest singular value of a subset of the rows is at least the whole's, Cauchy
    // interlacing on Φ_q Φ_qᵀ, and the largest at most the whole's): one SVD when the rows
    // are independent, the search for the first dependent row only when they are not.
    if m <= nq {
        let sv = jac.singular_values().unwrap_or_default();
        let tol = RANK_TOL * sv.first().copied().unwrap_or(0.0).max(f64::MIN_POSITIVE);
        if sv.iter().filter(|&&s| s > tol).count() == m {
            return Ok(());
        }
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

/// For a formulation that accepts redundant equations (the augmented Lagrangian), a failed
/// Newton iteration cannot be told from redundancy by the rank: the error names every joint
/// whose equation is left unmet (|Φ| > 1e3 · POS_TOL) at the last iterate, largest first —
/// the equations that contradict each other (or a guess too far from any assembly).
fn contradictory(mech: &Mechanism, rows: &[Row], phi: &[f64]) -> Result<(), SceneError> {
    let mut unmet: Vec<(usize, f64)> = phi
        .iter()
        .enumerate()
        .filter(|(_, v)| v.abs() > 1e3 * POS_TOL)
        .map(|(i, v)| (i, v.abs()))
        .collect();
    unmet.sort_by(|a, b| b.1.total_cmp(&a.1));
    let Some(&(first, _)) = unmet.first() else {
        return Ok(());
    };
    let mut joints: Vec<String> = Vec::new();
    for &(i, v) in &unmet {
        let name = format!("{} (residual {v:.3e})", describe(&rows[i], mech.scene()));
        if !joints.contains(&name) {
            joints.push(name);
        }
    }
    Err(SceneError::Assembly {
        path: format!("joints[{}]", rows[first].joint),
        reason: format!(
            "contradictory constraints: no pose meets all {} equations from the scene's \
             guesses; left unmet after the Newton iteration: {}",
            rows.len(),
            joints.join("; ")
        ),
    })
}

/// The scene's state y = (q, q̇) of the integrated bodies: positions and angles as given,
/// velocities the exact `initial_velocity` where there is one, else the guesses.
fn guess(mech: &Mechanism) -> Vec<f64> {
    let nq = mech.nq();
    let mut y = vec![0.0; 2 * nq];
    for (i, &k) in mech.bodies().int_bodies.iter().enumerate() {
        let b = &mech.scene().bodies[k];
        let iv = b.initial_velocity.clone().unwrap_or_default();
        y[3 * i] = b.position[0];
        y[3 * i + 1] = b.position[1];
        y[3 * i + 2] = b.angle;
        y[nq + 3 * i] = iv.vx.unwrap_or(b.velocity[0]);
        y[nq + 3 * i + 1] = iv.vy.unwrap_or(b.velocity[1]);
        y[nq + 3 * i + 2] = iv.omega.unwrap_or(b.angular_velocity);
    }
    y
}

/// Newton on positions, projection of velocities, rank check; returns y0 = (q, q̇) and what
/// the assembly changed. From `sparse::SPARSE_FROM_COORDINATES` coordinates on sparse
/// matrices when that path can answer (assembly/sparse.rs), else on dense ones.
pub(crate) fn assemble(mech: &Mechanism) -> Result<(Vec<f64>, ProjectionReport), SceneError> {
    let nq = mech.nq();
    let given = guess(mech);
    let rows = assembly_rows(mech);
    let vrows = velocity_rows(mech);
    if rows.is_empty() && vrows.is_empty() {
        return Ok((given, ProjectionReport::default()));
    }
    if nq >= sparse::SPARSE_FROM_COORDINATES {
        if let Some(done) = sparse::assemble(mech, &rows, &given)? {
            return Ok(done);
        }
    }
    dense(mech, rows, vrows, given)
}

/// The dense path of [`assemble`]: SVDs of the m × n_q Jacobians (the reference of the sparse
/// path, and the one that words every refusal).
fn dense(
    mech: &Mechanism,
    rows: Vec<Row>,
    vrows: Vec<(Row, String, String)>,
    given: Vec<f64>,
) -> Result<(Vec<f64>, ProjectionReport), SceneError> {
    let nq = mech.nq();
    let t0 = mech.t_start();
    let mut y = given.clone();
    let fail = |mech: &Mechanism, phi: &[f64], jac: &Mat<f64>, what: &str, iters: usize| {
        if mech.formulation().needs_full_rank() {
            check_rank(mech, &rows, jac)?;
        } else {
            contradictory(mech, &rows, phi)?;
        }
        let (i, v) = worst(phi);
        let (path, name) = row_name(mech, &rows[i]);
        Err(SceneError::Assembly {
            path,
            reason: format!("{what}: {name} has residual {v:.3e} after {iters} Newton iterations"),
        })
    };
    let mut converged = rows.is_empty();
    let mut iters = 0;
    // Past POS_TOL, Newton polishes the positions to rounding (common.rs, `Polish`).
    let mut polish = Polish::default();
    for it in 0..=MAX_ITER {
        if rows.is_empty() {
            break;
        }
        iters = it;
        crate::scene::error::checkpoint("assembly", t0)?;
        let (phi, _, jac) = eval(mech, &rows, t0, &y);
        let (_, err) = worst(&phi);
        if err <= POS_TOL || converged {
            // (A polish step that made it worse: `another` restores the best iterate.)
            converged = true;
            if !polish.another(err, &mut y, nq) || it == MAX_ITER {
                break;
            }
        } else if it == MAX_ITER || !err.is_finite() {
            return fail(mech, &phi, &jac, "positions", it);
        }
        let Some(dq) = pinv_apply(&jac, &phi) else {
            if converged {
                break;
            }
            return fail(mech, &phi, &jac, "positions", it);
        };
        for j in 0..nq {
            y[j] -= dq[j];
        }
    }
    debug_assert!(converged, "{iters}");
    // Velocities: one mass-weighted projection (Φ̇ is affine in q̇), then verify.
    let mut all = rows.clone();
    all.extend(vrows.iter().map(|v| v.0.clone()));
    // J M^{-1/2}: the projection of least kinetic energy (docs/model.md §1).
    let w: Vec<f64> = mech
        .bodies()
        .inverse_masses()
        .iter()
        .map(|v| v.sqrt())
        .collect();
    // The projected state and whether it meets the equations `eqs`.
    let project = |eqs: &[Row], y: &[f64]| -> (Vec<f64>, bool) {
        let mut y = y.to_vec();
        let (_, phid, jac) = eval(mech, eqs, t0, &y);
        let mut jw = jac.clone();
        for r in 0..jw.nrows() {
            for c in 0..nq {
                jw[(r, c)] *= w[c];
            }
        }
        let Some(dv) = pinv_apply(&jw, &phid) else {
            return (y, false);
        };
        for j in 0..nq {
            y[nq + j] -= w[j] * dv[j];
        }
        let (_, phid, _) = eval(mech, eqs, t0, &y);
        let (_, verr) = worst(&phid);
        let vmax = y[nq..].iter().fold(0.0f64, |a, v| a.max(v.abs()));
        // A huge velocity guess (1e308) overflows in the projection: never a non-finite y0.
        (
            y.clone(),
            vmax.is_finite() && verr <= VEL_TOL * (1.0 + vmax),
        )
    };
    let (yp, ok) = project(&all, &y);
    if !ok {
        // Blame the first exact initial velocity that the constraints (and the ones before it)
        // cannot meet; else the constraints themselves.
        for m in 1..=vrows.len() {
            let mut eqs = rows.clone();
            eqs.extend(vrows[..m].iter().map(|v| v.0.clone()));
            let (ym, okm) = project(&eqs, &y);
            if !okm {
                let (_, path, what) = &vrows[m - 1];
                let (_, phid, _) = eval(mech, &eqs, t0, &ym);
                return Err(SceneError::Assembly {
                    path: path.clone(),
                    reason: format!(
                        "velocities: {what} cannot be met together with the constraints and \
                         the initial velocities before it (residual {:.3e})",
                        worst(&phid).1
                    ),
                });
            }
        }
        let (_, phid, jac) = eval(mech, &all, t0, &yp);
        return fail(mech, &phid, &jac, "velocities", 1);
    }
    y = yp;
    let (condition, exact) = projection_conditioning(mech, &all, &vrows, t0, &y, &w);
    // Rank of the ideal equations at the assembled state, when the formulation needs it
    // (Lagrange multipliers: the KKT system).
    if mech.formulation().needs_full_rank() {
        let (_, _, jac) = eval(mech, &all, t0, &y);
        let rows = &mech.constraints().rows;
        let ideal = jac.subrows(0, rows.len()).to_owned();
        check_rank(mech, rows, &ideal)?;
    }
    let mut rep = report(mech, &given, &y);
    rep.kinetic_energy_exact = exact;
    rep.condition = condition;
    if !vrows.is_empty() {
        let added = rep.kinetic_energy_assembled - rep.kinetic_energy_given;
        let ill = mech.formulation().needs_full_rank() && !(condition <= MAX_PROJECTION_CONDITION);
        if ill || added > MAX_PROJECTION_ENERGY_RATIO * exact {
            let paths: Vec<&str> = vrows.iter().map(|v| v.1.as_str()).collect();
            return Err(SceneError::Assembly {
                path: paths[0].to_string(),
                reason: format!(
                    "velocities: meeting the exact initial velocities ({}) with the constraints \
                     is ill-conditioned: the projection's condition number is {condition:.3e} \
                     (at most {MAX_PROJECTION_CONDITION:e}) and it adds {added:.3e} J of kinetic \
                     energy where the exact values carry {exact:.3e} J (at most \
                     {MAX_PROJECTION_ENERGY_RATIO} times that); check them against the \
                     clearance joints' initial_eccentricity and the bodies' positions",
                    paths.join(", ")
                ),
            });
        }
    }
    Ok((y, rep))
}

/// The condition number of J M^{-1/2} over the rows `all` at y, and the kinetic energy the
/// exact initial velocities `vrows` carry: ½ ‖(A M^{-1/2})⁺ r‖² for their rows A q̇ = r, the
/// least kinetic energy of a motion that has them (docs/model.md §1.6).
fn projection_conditioning(
    mech: &Mechanism,
    all: &[Row],
    vrows: &[(Row, String, String)],
    t0: f64,
    y: &[f64],
    w: &[f64],
) -> (f64, f64) {
    let nq = mech.nq();
    let weighted = |rows: &[Row], y: &[f64]| {
        let (_, phid, mut jac) = eval(mech, rows, t0, y);
        for r in 0..jac.nrows() {
            for c in 0..nq {
                jac[(r, c)] *= w[c];
            }
        }
        (phid, jac)
    };
    let condition = if all.is_empty() {
        1.0
    } else {
        let (_, jw) = weighted(all, y);
        let sv = jw.singular_values().unwrap_or_default();
        let hi = sv.iter().fold(0.0f64, |a, &b| a.max(b));
        let lo = sv.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        if all.len() > nq || !(lo > 0.0) {
            f64::INFINITY
        } else {
            hi / lo
        }
    };
    if vrows.is_empty() {
        return (condition, 0.0);
    }
    // At q̇ = 0 the rows read −r.
    let mut y0 = y.to_vec();
    y0[nq..].fill(0.0);
    let rows: Vec<Row> = vrows.iter().map(|v| v.0.clone()).collect();
    let (phid, aw) = weighted(&rows, &y0);
    let r: Vec<f64> = phid.iter().map(|v| -v).collect();
    let exact = pinv_apply(&aw, &r).map_or(f64::INFINITY, |x| {
        0.5 * x.iter().map(|v| v * v).sum::<f64>()
    });
    (condition, exact)
}
