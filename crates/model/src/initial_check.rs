//! The equations of motion checked once when a mechanism is built, so that a scene whose
//! numbers are each finite but whose dynamics f64 cannot compute (an inertia of 1e-182 beside
//! masses of 1e3, ω² or β² beyond 1e308) is rejected with the body or joint to blame, instead
//! of failing as a non-finite state at the first right-hand side of a run.
//!
//! ```text
//! 1. the formulation's own check before any evaluation (Lagrange–Baumgarte: the point
//!    mobility of every constrained point of an integrated body      → bodies[k].inertia)
//! 2. at (t_start, y0), the first failure in this order:
//!    prescribed motion   pose, velocity, acceleration of every driven body finite → joints[driver]
//!    clearance forces    δ, δ̇, v_T, F_N, F_T, film F_r, F_t finite              → joints[k]
//!    applied forces      (F_x, F_y, M) of every integrated body finite            → bodies[k]
//!    the formulation's equations (Lagrange–Baumgarte: Φ, Φ̇, r and Φ_q finite,
//!                        then every Cholesky pivot of S = Φ_q M⁻¹ Φ_qᵀ above
//!                        PIVOT_TOL · S_jj)                                       → joints[k]
//!    accelerations       q̈ = f(t, y)[n_q..] finite                               → bodies[k]
//!    Jacobian            ∂f/∂y finite (the Newton matrix of the implicit methods) → bodies[k]
//!                        (when its n² f64, twice over with the Jacobian's work buffers,
//!                        fit the memory budget of lash_solver::memory;
//!                        beyond, an implicit method refuses the run itself, and an
//!                        explicit one needs no Jacobian); from
//!                        lash_solver::linear_algebra::SPARSE_FROM unknowns, a mechanism of
//!                        several clusters (crate::jacobian) instead checks the coloured
//!                        differences of its sparse pattern, the Jacobian that diffsol's
//!                        sparse path computes (O(nnz), no n² matrix); one cluster
//!                        from lash_solver::linear_algebra::KKT_FROM unknowns under an
//!                        absolute formulation checks its KKT linearisation instead
//!                        (crate::kkt: K regular, ∂ρ/∂y finite); any other mechanism of
//!                        one cluster from that size (a dense ∂f/∂y, O(n³) to form) is
//!                        not checked at set-up
//! ```
//! The formulation's checks, with the reasons for their bounds, are in
//! mechanism/formulation/lagrange_baumgarte/check.rs.
//!
//! Source: docs/model.md §1 (the KKT system and its Schur complement); docs/scene-format.md,
//! "Errors".

use lash_solver::OdeSystem;

use crate::mechanism::formulation::Formulation;
use crate::mechanism::scratch::Scratch;
use crate::mechanism::Mechanism;
use crate::scene::error::SceneError;

fn fail(path: String, reason: String) -> SceneError {
    SceneError::Dynamics { path, reason }
}

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Scene body and name of state component `i` of q (`x`, `y`, `φ`) or, with `dot`, of its
/// time derivative order 1 or 2.
fn component(mech: &Mechanism, i: usize, names: [&str; 3]) -> (usize, String) {
    if let Formulation::Minimal(f) = mech.formulation() {
        let (k, name) = f.coordinate(i);
        let order = match names[0] {
            "ẋ" => "rate of ",
            "ẍ" => "acceleration of ",
            _ => "",
        };
        return (
            k,
            format!(
                "{order}joint coordinate {name} of body '{}'",
                mech.body_info()[k].name
            ),
        );
    }
    let k = mech.bodies().int_bodies[i / 3];
    (
        k,
        format!("{} of body '{}'", names[i % 3], mech.body_info()[k].name),
    )
}

/// Runs the checks of the module doc on `mech` (assembled: `y0` set).
pub(crate) fn check(mech: &Mechanism) -> Result<(), SceneError> {
    mech.formulation()
        .check_point_mobility(mech.scene(), mech.constraints(), mech.body_info())?;
    let t = mech.t_start();
    let y = mech.initial_state();
    // The first half of y: q (n_q) or the minimal formulation's θ.
    let nq = y.len() / 2;
    check_evaluation(mech, t, &y, &mut mech.scratch())?;
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
                mech.body_info()[k].describe()
            ),
        ));
    }
    // The Jacobian of the implicit methods (lower half: the upper half is [0 I]). Skipped
    // when its n² f64 and the n² of the Jacobian's own work buffers (jacobian.rs: ∂g/∂y and
    // the lower blocks, nq × n each) do not fit the memory budget (lash_solver::memory), or
    // when the allocator refuses the matrix: an explicit method needs no Jacobian, and an
    // implicit one refuses the run itself with its typed OutOfMemory error before allocating
    // its own.
    let n = y.len();
    crate::scene::error::checkpoint("the initial checks", t)?;
    // A large mechanism of several clusters: diffsol's sparse path (lash_solver::
    // linear_algebra) takes the Jacobian by coloured differences on its pattern, never the
    // dense closed form; those differences are checked instead, in O(nnz) memory.
    if n >= lash_solver::linear_algebra::SPARSE_FROM {
        if let Some(pattern) = mech.jacobian_sparsity() {
            return check_sparse_jacobian(mech, t, &y, &dy, pattern);
        }
        // One large cluster under an absolute formulation: the `kkt` path
        // (lash_solver::kkt) never forms ∂f/∂y; its linearisation is checked instead
        // (crate::kkt).
        if lash_solver::linear_algebra::uses_kkt(mech, lash_solver::LinearAlgebra::Auto, false) {
            return check_kkt(mech, t, &y);
        }
        // Any other cluster of that size: its ∂f/∂y is dense and forming it costs O(n²)
        // memory and O(n³) work — a 1 500-link chain's took a minute and 1.3 GB, every other
        // step of set-up being O(n). Not checked here: an implicit method forms it at its
        // first step, where a non-finite entry fails the Newton iteration (a typed solver
        // error), and an explicit one never does.
        return Ok(());
    }
    let fits =
        lash_solver::memory::check(lash_solver::memory::dense_bytes(n, 2), String::new, None);
    let Ok(mut jac) = fits.and_then(|()| lash_solver::memory::try_zeros(n, n)) else {
        return Ok(());
    };
    mech.jacobian(t, &y, jac.as_mut());
    crate::scene::error::checkpoint("the initial Jacobian", t)?;
    for j in 0..n {
        for i in nq..n {
            let v = jac[(i, j)];
            if !v.is_finite() {
                return Err(jacobian_entry_error(mech, i, j, v));
            }
        }
    }
    Ok(())
}

/// The error of a non-finite entry `v` = ∂f_i/∂y_j of the Jacobian's lower half (i ≥ n_q):
/// the body and the components named, for the dense and the sparse checks alike.
pub(crate) fn jacobian_entry_error(mech: &Mechanism, i: usize, j: usize, v: f64) -> SceneError {
    let nq = mech.dim() / 2;
    let (k, what) = component(mech, i - nq, ["ẍ", "ÿ", "φ̈"]);
    let by = if j < nq {
        ["x", "y", "φ"]
    } else {
        ["ẋ", "ẏ", "φ̇"]
    };
    let (_, by) = component(mech, j % nq, by);
    fail(
        format!("bodies[{k}]"),
        format!(
            "the Jacobian entry ∂({what})/∂({by}) that the implicit methods need is {v} ({})",
            mech.body_info()[k].describe()
        ),
    )
}

/// The Jacobian as the sparse path computes it (coloured forward differences on `pattern`,
/// lash_solver::jacobian) at (t, y) with f(t, y) = `dy`: a non-finite entry of the lower
/// half is the same error as the dense check's.
fn check_sparse_jacobian(
    mech: &Mechanism,
    t: f64,
    y: &[f64],
    dy: &[f64],
    pattern: Vec<Vec<usize>>,
) -> Result<(), SceneError> {
    let n = y.len();
    let nq = n / 2;
    let Some(colouring) = lash_solver::jacobian::Colouring::new(pattern) else {
        return Ok(());
    };
    let mut col_ptr = vec![0];
    let mut row_idx = Vec::new();
    for rows in colouring.pattern() {
        row_idx.extend_from_slice(rows);
        col_ptr.push(row_idx.len());
    }
    let mut values = vec![0.0; row_idx.len()];
    let mut stats = lash_solver::Stats::default();
    lash_solver::jacobian::JacobianEvaluator::new(vec![1.0; n]).sparse_difference(
        mech,
        t,
        y,
        dy,
        &colouring,
        (&col_ptr, &row_idx),
        &mut values,
        &mut stats,
    );
    crate::scene::error::checkpoint("the initial Jacobian", t)?;
    for j in 0..n {
        for k in col_ptr[j]..col_ptr[j + 1] {
            let (i, v) = (row_idx[k], values[k]);
            if i >= nq && !v.is_finite() {
                return Err(jacobian_entry_error(mech, i, j, v));
            }
        }
    }
    Ok(())
}

/// Check 2 of the module doc, up to the formulation's checks of its equations.
fn check_evaluation(
    mech: &Mechanism,
    t: f64,
    y: &[f64],
    sc: &mut Scratch,
) -> Result<(), SceneError> {
    mech.kinematics(t, y, sc);
    for p in &mech.bodies().pres {
        let k = p.body;
        if !(finite(&sc.pose[k]) && finite(&sc.vel[k]) && finite(&sc.acc[k])) {
            return Err(fail(
                format!("joints[{}]", p.driver_joint),
                format!(
                    "the motion it prescribes to body '{}' is not finite at t = {t} \
                     (θ₀ = {:e} rad, ω = {:e} rad/s): pose {:?}, velocity {:?}, \
                     acceleration {:?}",
                    mech.body_info()[k].name,
                    p.theta0,
                    p.omega,
                    sc.pose[k],
                    sc.vel[k],
                    sc.acc[k]
                ),
            ));
        }
    }
    mech.forces().applied(mech.bodies(), t, sc, false);
    for (k, c) in mech.forces().revolute.iter().enumerate() {
        let (ev, st) = (sc.revolute[k], sc.revolute[k].st);
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
                    mech.scene().joints[c.joint],
                    listed.join(", ")
                ),
            ));
        }
    }
    for (i, &k) in mech.bodies().int_bodies.iter().enumerate() {
        let g = &sc.g[3 * i..3 * i + 3];
        if !finite(g) {
            return Err(fail(
                format!("bodies[{k}]"),
                format!(
                    "the applied force and moment (F_x, F_y, M) = {g:?} on {} are not finite \
                     (gravity {:?} m/s²)",
                    mech.body_info()[k].describe(),
                    mech.forces().gravity.unwrap_or([0.0; 2])
                ),
            ));
        }
    }
    mech.formulation()
        .check_equations(t, mech.scene(), mech.constraints(), mech.body_info(), sc)
}

/// The initial check of the `kkt` path (below): at (t, y), every entry of
/// ∂ρ/∂y finite; a non-finite entry is the dense check's error on the acceleration of the
/// coordinate its row acts on (a constraint row: its column's body). A K that cannot be
/// factored (redundant constraints under the augmented Lagrangian) is not refused here: an
/// explicit method needs no Newton matrix, and an implicit one on this path ends in its typed
/// Newton failure (BENCHMARKS.md, "The sparse Newton of one cluster").
fn check_kkt(mech: &Mechanism, t: f64, y: &[f64]) -> Result<(), SceneError> {
    let nq = mech.nq();
    let Ok(entries) = lash_solver::kkt::residual_jacobian(mech, t, y, &vec![1.0; y.len()]) else {
        return Ok(());
    };
    crate::scene::error::checkpoint("the initial Jacobian", t)?;
    match entries.into_iter().find(|e| !e.2.is_finite()) {
        None => Ok(()),
        Some((i, j, v)) => {
            let row = if i < nq { i } else { j % nq };
            Err(jacobian_entry_error(mech, nq + row, j, v))
        }
    }
}
