//! Assembly on sparse matrices, for large mechanisms (from [`SPARSE_FROM_COORDINATES`]
//! coordinates): the dense path's answers in O(nnz) memory and near-linear time, or `None`
//! (the dense path decides) wherever the answer or a refusal could depend on the rounding of
//! the method.
//!
//! ```text
//! J (m × n_q, full row rank), D = I (positions) or M⁻¹ (velocities), S = J D Jᵀ = L Lᵀ
//!   (faer's sparse Cholesky, a fill-reducing ordering: a chain's S is banded)
//! minimum-norm step      J⁺ φ = Jᵀ S⁻¹ φ                      (D = I)
//! velocity projection    M^{-1/2}(J M^{-1/2})⁺ Φ̇ = M⁻¹ Jᵀ S⁻¹ Φ̇   (D = M⁻¹)
//! σ_max² = λ_max(S),  σ_min² = 1/λ_max(S⁻¹)   (Lanczos, the Ritz value to 1e-10)
//! exact energy           ½ rᵀ (A M⁻¹ Aᵀ)⁻¹ r  = ½ ‖(A M^{-1/2})⁺ r‖²
//! ```
//! With J of full row rank the pseudo-inverse is Jᵀ(J Jᵀ)⁻¹ exactly, so both paths compute the
//! same vectors; they differ in rounding only (the dense path's SVD against this Cholesky
//! factor). The sparse path accepts only when every check passes with a margin: a Cholesky
//! that fails (S singular in f64: redundant equations), a σ_min/σ_max below
//! [`MARGIN_RANK`] (the rank check's threshold is 1e-9), a projection condition number above
//! [`MARGIN_CONDITION`] (the refusal's bound is 1e8), a Lanczos iteration that does not
//! converge, a Newton iteration that fails, a velocity the projection cannot meet or an
//! energy beyond the bound: each returns `None` and the dense path runs from the start, so
//! every refusal and its message are the dense path's. S squares J's condition number; at
//! κ(J) ≤ 1e6 its Cholesky keeps about 4 digits of S⁻¹ — the solves are verified by their
//! residuals (a Newton step's, the projected velocities').

use faer::linalg::solvers::SolveCore;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, Side};

use super::common::{
    report, velocity_rows, worst, Polish, MAX_ITER, MAX_PROJECTION_CONDITION,
    MAX_PROJECTION_ENERGY_RATIO, POS_TOL, VEL_TOL,
};
use crate::mechanism::bodies::Owner;
use crate::mechanism::constraints::{eval_row, Row};
use crate::mechanism::Mechanism;
use crate::projection::ProjectionReport;
use crate::scene::error::SceneError;

/// Mechanisms with at least this many coordinates n_q of integrated bodies (100 bodies) are
/// assembled on sparse matrices; below, every case keeps the dense path's numbers.
pub(crate) const SPARSE_FROM_COORDINATES: usize = 300;
/// Smallest σ_min/σ_max of the ideal rows the sparse path accepts (the rank check refuses
/// below 1e-9: a margin of 1 000 for the estimate's error).
const MARGIN_RANK: f64 = 1e-6;
/// Largest condition number of the projection the sparse path accepts (the refusal's bound
/// is 1e8: a margin of 100).
const MARGIN_CONDITION: f64 = 1e6;
/// Relative change of the Lanczos estimate between checks (every 10 iterations) that ends
/// the iteration.
const LANCZOS_TOL: f64 = 1e-10;
/// Lanczos iterations before the estimate counts as unconverged.
const LANCZOS_MAX: usize = 3000;

/// A constraint Jacobian in compressed rows (a column may repeat within a row: its values add).
pub(crate) struct SparseRows {
    /// Row r's entries are `col[ptr[r]..ptr[r + 1]]`, `val[…]`.
    ptr: Vec<usize>,
    col: Vec<usize>,
    val: Vec<f64>,
    ncols: usize,
}

impl SparseRows {
    fn nrows(&self) -> usize {
        self.ptr.len() - 1
    }

    /// out = J x.
    fn mul(&self, x: &[f64], out: &mut [f64]) {
        for (r, o) in out.iter_mut().enumerate() {
            let mut s = 0.0;
            for k in self.ptr[r]..self.ptr[r + 1] {
                s += self.val[k] * x[self.col[k]];
            }
            *o = s;
        }
    }

    /// out = Jᵀ z.
    fn mul_t(&self, z: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for (r, &zr) in z.iter().enumerate() {
            for k in self.ptr[r]..self.ptr[r + 1] {
                out[self.col[k]] += self.val[k] * zr;
            }
        }
    }

    /// S = J diag(d) Jᵀ, its lower triangle (m × m, compressed columns).
    fn gram(&self, d: &[f64]) -> Option<SparseColMat<usize, f64>> {
        let mut by_col: Vec<Vec<(usize, f64)>> = vec![Vec::new(); self.ncols];
        for r in 0..self.nrows() {
            for k in self.ptr[r]..self.ptr[r + 1] {
                by_col[self.col[k]].push((r, self.val[k]));
            }
        }
        let mut t = Vec::new();
        for (c, entries) in by_col.iter().enumerate() {
            for &(a, va) in entries {
                for &(b, vb) in entries {
                    if a >= b {
                        t.push(Triplet::new(a, b, va * d[c] * vb));
                    }
                }
            }
        }
        SparseColMat::try_new_from_triplets(self.nrows(), self.nrows(), &t).ok()
    }
}

/// The factor of S = J D Jᵀ and its solves.
struct Gram {
    llt: faer::sparse::linalg::solvers::Llt<usize, f64>,
    m: usize,
}

impl Gram {
    /// None when S is not positive definite in f64 (J has dependent rows) or the
    /// factorisation fails.
    fn new(jac: &SparseRows, d: &[f64]) -> Option<Gram> {
        let s = jac.gram(d)?;
        let llt = s.sp_cholesky(Side::Lower).ok()?;
        Some(Gram {
            llt,
            m: jac.nrows(),
        })
    }

    /// b ← S⁻¹ b.
    fn solve(&self, b: &mut [f64]) {
        let mut col = faer::Mat::<f64>::from_fn(self.m, 1, |i, _| b[i]);
        self.llt.solve_in_place_with_conj(Conj::No, col.as_mut());
        for (i, v) in b.iter_mut().enumerate() {
            *v = col[(i, 0)];
        }
    }
}

/// The largest eigenvalue of the symmetric positive (semi)definite operator `apply` on R^m by
/// Lanczos' iteration (no reorthogonalisation: the extreme Ritz value converges regardless,
/// Paige 1980), from a fixed start vector; None when it has not converged to `LANCZOS_TOL`
/// after `LANCZOS_MAX` iterations or a value is not finite.
fn largest_eigenvalue(m: usize, mut apply: impl FnMut(&[f64], &mut [f64])) -> Option<f64> {
    if m == 0 {
        return Some(0.0);
    }
    // A start vector with no structure (a Weyl sequence): not orthogonal to the top
    // eigenvector of any of the matrices met here.
    let mut v: Vec<f64> = (0..m)
        .map(|i| 0.5 + ((i as f64 + 1.0) * 0.618_033_988_749_895).fract())
        .collect();
    let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    v.iter_mut().for_each(|x| *x /= norm);
    let mut v_prev = vec![0.0; m];
    let mut w = vec![0.0; m];
    let (mut alpha, mut beta) = (Vec::new(), Vec::new());
    let mut last = f64::NAN;
    for it in 1..=LANCZOS_MAX.min(m + 1) {
        apply(&v, &mut w);
        let a: f64 = w.iter().zip(&v).map(|(x, y)| x * y).sum();
        let b_prev = beta.last().copied().unwrap_or(0.0);
        for i in 0..m {
            w[i] -= a * v[i] + b_prev * v_prev[i];
        }
        alpha.push(a);
        let b = w.iter().map(|x| x * x).sum::<f64>().sqrt();
        // An invariant subspace (exact after m steps): the Ritz values are eigenvalues.
        let invariant = !(b > 1e-14 * a.abs().max(f64::MIN_POSITIVE)) || it == m;
        if it % 10 == 0 || invariant {
            let est = tridiagonal_max(&alpha, &beta);
            if !est.is_finite() {
                return None;
            }
            if invariant || (est - last).abs() <= LANCZOS_TOL * est.abs() {
                return Some(est);
            }
            last = est;
        }
        beta.push(b);
        for i in 0..m {
            v_prev[i] = v[i];
            v[i] = w[i] / b;
        }
    }
    None
}

/// The largest eigenvalue of the symmetric tridiagonal matrix with diagonal `a` and
/// off-diagonal `b` (|b| = |a| − 1 or more; the extra are ignored), by bisection on the
/// Sturm sequence's count of eigenvalues below x.
fn tridiagonal_max(a: &[f64], b: &[f64]) -> f64 {
    let k = a.len();
    let off = |i: usize| if i < k - 1 { b[i].abs() } else { 0.0 };
    // Gershgorin's interval.
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..k {
        let r = off(i) + if i > 0 { off(i - 1) } else { 0.0 };
        lo = lo.min(a[i] - r);
        hi = hi.max(a[i] + r);
    }
    // Eigenvalues below x (Sturm count of T − x I's LDLᵀ pivots).
    let below = |x: f64| {
        let mut count = 0;
        let mut d = 1.0;
        for i in 0..k {
            let bb = if i > 0 { off(i - 1) * off(i - 1) } else { 0.0 };
            d = a[i] - x - if i > 0 { bb / d } else { 0.0 };
            if d == 0.0 {
                d = -f64::EPSILON * (x.abs() + 1.0);
            }
            if d < 0.0 {
                count += 1;
            }
        }
        count
    };
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if !(mid > lo && mid < hi) {
            break;
        }
        if below(mid) == k {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// σ_max / σ_min of J diag(d)^{1/2} (J of full row rank, m ≤ n_q), with the factor of
/// J diag(d) Jᵀ; None when the estimates do not converge.
fn condition(jac: &SparseRows, d: &[f64], gram: &Gram) -> Option<f64> {
    let (m, n) = (jac.nrows(), jac.ncols);
    let mut tmp = vec![0.0; n];
    let hi = largest_eigenvalue(m, |x, out| {
        jac.mul_t(x, &mut tmp);
        tmp.iter_mut().zip(d).for_each(|(t, di)| *t *= di);
        jac.mul(&tmp, out);
    })?;
    let inv_lo = largest_eigenvalue(m, |x, out| {
        out.copy_from_slice(x);
        gram.solve(out);
    })?;
    let c = (hi * inv_lo).sqrt();
    c.is_finite().then_some(c)
}

/// Rows evaluated at (t, y): values, rates and the Jacobian on the integrated columns.
fn eval(mech: &Mechanism, rows: &[Row], t: f64, y: &[f64]) -> (Vec<f64>, Vec<f64>, SparseRows) {
    let nq = mech.nq();
    let mut sc = mech.scratch();
    mech.bodies().kinematics(t, y, &mut sc);
    let (mut phi, mut phid) = (vec![0.0; rows.len()], vec![0.0; rows.len()]);
    let mut jac = SparseRows {
        ptr: vec![0],
        col: Vec::new(),
        val: Vec::new(),
        ncols: nq,
    };
    for (r, row) in rows.iter().enumerate() {
        let ev = eval_row(row, mech.body_info(), t, &sc);
        phi[r] = ev.phi;
        phid[r] = ev.phid;
        for (ti, term) in row.terms[..row.n_terms].iter().enumerate() {
            if let Owner::Int(i) = mech.body_info()[term.body].owner {
                for c in 0..3 {
                    jac.col.push(3 * i + c);
                    jac.val.push(ev.jrows[ti][c]);
                }
            }
        }
        jac.ptr.push(jac.col.len());
    }
    (phi, phid, jac)
}

/// x = D Jᵀ S⁻¹ b: the minimum-norm solution (in the D⁻¹ norm) of J x = b.
fn min_norm(jac: &SparseRows, d: &[f64], gram: &Gram, b: &[f64]) -> Vec<f64> {
    let mut z = b.to_vec();
    gram.solve(&mut z);
    let mut x = vec![0.0; jac.ncols];
    jac.mul_t(&z, &mut x);
    x.iter_mut().zip(d).for_each(|(v, di)| *v *= di);
    x
}

/// The assembly of the module doc from the scene's state `given`: Some((y0, report)) when
/// every check passes with its margin, None for the dense path to decide; an error only for
/// the call's deadline or a stop request.
pub(crate) fn assemble(
    mech: &Mechanism,
    rows: &[Row],
    given: &[f64],
) -> Result<Option<(Vec<f64>, ProjectionReport)>, SceneError> {
    let nq = mech.nq();
    let t0 = mech.t_start();
    let vrows = velocity_rows(mech);
    let mut y = given.to_vec();
    let ones = vec![1.0; nq];
    // Past POS_TOL, Newton polishes the positions to rounding (common.rs, `Polish`).
    let mut polish = Polish::default();
    let mut converged = false;
    for it in 0..=MAX_ITER {
        if rows.is_empty() {
            break;
        }
        crate::scene::error::checkpoint("assembly", t0)?;
        let (phi, _, jac) = eval(mech, rows, t0, &y);
        let (_, err) = worst(&phi);
        if err <= POS_TOL || converged {
            converged = true;
            if !polish.another(err, &mut y, nq) || it == MAX_ITER {
                break;
            }
        } else if it == MAX_ITER || !err.is_finite() || rows.len() > nq {
            return Ok(None);
        }
        let Some(gram) = Gram::new(&jac, &ones) else {
            if converged {
                break;
            }
            return Ok(None);
        };
        let dq = min_norm(&jac, &ones, &gram, &phi);
        // The step must solve J dq = φ (S⁻¹ lost to rounding otherwise).
        let mut res = vec![0.0; phi.len()];
        jac.mul(&dq, &mut res);
        let scale = phi.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if !res
            .iter()
            .zip(&phi)
            .all(|(r, p)| (r - p).abs() <= 1e-6 * scale)
        {
            if converged {
                break;
            }
            return Ok(None);
        }
        for j in 0..nq {
            y[j] -= dq[j];
        }
    }
    // Velocities: the mass-weighted projection on the constraints and the exact velocities.
    let mut all = rows.to_vec();
    all.extend(vrows.iter().map(|v| v.0.clone()));
    let minv = mech.bodies().inverse_masses();
    let mut condition_number = 1.0;
    if !all.is_empty() {
        if all.len() > nq {
            return Ok(None);
        }
        let (_, phid, jac) = eval(mech, &all, t0, &y);
        let Some(gram) = Gram::new(&jac, &minv) else {
            return Ok(None);
        };
        let dv = min_norm(&jac, &minv, &gram, &phid);
        for j in 0..nq {
            y[nq + j] -= dv[j];
        }
        let (_, phid, jac) = eval(mech, &all, t0, &y);
        let (_, verr) = worst(&phid);
        let vmax = y[nq..].iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if !(vmax.is_finite() && verr <= VEL_TOL * (1.0 + vmax)) {
            return Ok(None);
        }
        let Some(gram) = Gram::new(&jac, &minv) else {
            return Ok(None);
        };
        match condition(&jac, &minv, &gram) {
            Some(c) if c <= MARGIN_CONDITION => condition_number = c,
            _ => return Ok(None),
        }
    }
    // The kinetic energy the exact velocities carry: at q̇ = 0 their rows read −r.
    let mut exact = 0.0;
    if !vrows.is_empty() {
        let mut y0 = y.clone();
        y0[nq..].fill(0.0);
        let vr: Vec<Row> = vrows.iter().map(|v| v.0.clone()).collect();
        let (_, phid, a) = eval(mech, &vr, t0, &y0);
        let r: Vec<f64> = phid.iter().map(|v| -v).collect();
        let Some(gram) = Gram::new(&a, &minv) else {
            return Ok(None);
        };
        // x = (A M^{-1/2})⁺ r = M^{-1/2} Aᵀ S⁻¹ r, so ½‖x‖² = ½ Σ (Aᵀz)_j² / m_j.
        let mut z = r.clone();
        gram.solve(&mut z);
        let mut x = vec![0.0; nq];
        a.mul_t(&z, &mut x);
        exact = 0.5 * x.iter().zip(&minv).map(|(v, mi)| v * v * mi).sum::<f64>();
        if !exact.is_finite() {
            return Ok(None);
        }
    }
    // The rank of the ideal equations at the assembled state.
    if mech.formulation().needs_full_rank() {
        let ideal = &mech.constraints().rows;
        if ideal.len() > nq {
            return Ok(None);
        }
        if !ideal.is_empty() {
            let (_, _, jac) = eval(mech, ideal, t0, &y);
            let Some(gram) = Gram::new(&jac, &ones) else {
                return Ok(None);
            };
            match condition(&jac, &ones, &gram) {
                Some(c) if 1.0 / c >= MARGIN_RANK => {}
                _ => return Ok(None),
            }
        }
    }
    let mut rep = report(mech, given, &y);
    rep.kinetic_energy_exact = exact;
    rep.condition = condition_number;
    if !vrows.is_empty() {
        let added = rep.kinetic_energy_assembled - rep.kinetic_energy_given;
        let ill =
            mech.formulation().needs_full_rank() && !(condition_number <= MAX_PROJECTION_CONDITION);
        if ill || !(added <= MAX_PROJECTION_ENERGY_RATIO * exact) {
            return Ok(None);
        }
    }
    Ok(Some((y, rep)))
}

#[cfg(test)]
mod tests {
    //! The sparse path against the dense one (assembly.rs) on mechanisms of more than
    //! [`SPARSE_FROM_COORDINATES`] coordinates: chains and ladders (closed loops) from
    //! perturbed guesses, with exact initial velocities; and the cases it must leave to the
    //! dense path (redundant equations, a nearly singular projection), whose refusals stay
    //! the dense path's.
    use serde_json::{json, Value};

    use super::super::common::velocity_rows;
    use super::super::{assembly_rows, dense, guess};
    use super::*;
    use crate::scene::format::{FormulationName, Scene};

    /// A link of length 0.1 m along x at (x, y), its guess moved by `k`'s perturbation.
    fn link(name: &str, x: f64, y: f64, k: usize) -> Value {
        let s = k as f64;
        json!({"name": name, "mass": 1.0, "inertia": 0.01 / 12.0,
               "position": [x + 2e-3 * (0.7 * s).sin(), y + 1e-3 * (1.3 * s).cos()],
               "angle": 5e-3 * (2.1 * s).sin(),
               "points": {"A": [-0.05, 0.0], "B": [0.05, 0.0]}})
    }

    fn pin(name: &str, a: &str, pa: &str, b: &str, pb: &str) -> Value {
        json!({"type": "revolute", "name": name, "a": {"body": a, "point": pa},
               "b": {"body": b, "point": pb}})
    }

    /// `n` links pinned end to end from the ground at `(0, y)`, named `{p}0…`.
    fn chain(p: &str, n: usize, y: f64, bodies: &mut Vec<Value>, joints: &mut Vec<Value>) {
        joints.push(json!({"type": "revolute", "name": format!("{p}j0"),
                           "a": {"body": format!("{p}0"), "point": "A"},
                           "b": {"body": "ground", "at": [0.0, y]}}));
        for i in 0..n {
            bodies.push(link(
                &format!("{p}{i}"),
                0.1 * i as f64 + 0.05,
                y,
                i + bodies.len(),
            ));
            if i > 0 {
                joints.push(pin(
                    &format!("{p}j{i}"),
                    &format!("{p}{}", i - 1),
                    "B",
                    &format!("{p}{i}"),
                    "A",
                ));
            }
        }
    }

    /// Two chains of `n` links 0.1 m apart joined by a vertical rung every `every` links:
    /// n / every closed loops. Exact velocities: the first chain's tip vy and a joint rate.
    fn ladder(n: usize, every: usize) -> Value {
        let (mut bodies, mut joints) = (Vec::new(), Vec::new());
        chain("a", n, 0.0, &mut bodies, &mut joints);
        chain("b", n, 0.1, &mut bodies, &mut joints);
        for k in (every - 1..n).step_by(every) {
            let x = 0.1 * k as f64 + 0.1;
            let mut r = link(&format!("r{k}"), x, 0.05, k);
            r["angle"] = json!(std::f64::consts::FRAC_PI_2 + 3e-3);
            bodies.push(r);
            joints.push(pin(
                &format!("ra{k}"),
                &format!("a{k}"),
                "B",
                &format!("r{k}"),
                "A",
            ));
            joints.push(pin(
                &format!("rb{k}"),
                &format!("b{k}"),
                "B",
                &format!("r{k}"),
                "B",
            ));
        }
        bodies[n - 1]["initial_velocity"] = json!({"vy": 0.5});
        joints[3]["initial_rate"] = json!(0.3);
        json!({"bodies": bodies, "joints": joints, "gravity": [0.0, -9.81], "t_end": 1.0})
    }

    fn mechanism(v: &Value, f: FormulationName) -> Result<Mechanism, SceneError> {
        let mut s = Scene::from_json_str(&v.to_string()).unwrap();
        s.formulation = f;
        Mechanism::from_scene(&s)
    }

    /// Both paths from the scene's guesses.
    type Both = (
        Option<(Vec<f64>, ProjectionReport)>,
        Result<(Vec<f64>, ProjectionReport), SceneError>,
    );

    fn both(mech: &Mechanism) -> Both {
        let rows = assembly_rows(mech);
        let sparse = assemble(mech, &rows, &guess(mech)).unwrap();
        (sparse, dense(mech, rows, velocity_rows(mech), guess(mech)))
    }

    /// The two answers agree: positions within 10 × the assembly tolerance (both Newton
    /// sequences are one sequence in exact arithmetic, each stopped within 1e-12 of the
    /// constraints), velocities within the projection's rounding (1e-9 of the largest, far
    /// above κ ε with κ ≤ 1e6), the condition number within the Lanczos tolerance (1e-10,
    /// and the SVD's own rounding), the energies within 1e-10 relative.
    fn agree(mech: &Mechanism, s: &(Vec<f64>, ProjectionReport), d: &(Vec<f64>, ProjectionReport)) {
        let nq = mech.nq();
        let vmax = d.0[nq..].iter().fold(1.0f64, |a, v| a.max(v.abs()));
        for j in 0..2 * nq {
            let tol = if j < nq { 10.0 * POS_TOL } else { 1e-9 * vmax };
            assert!(
                (s.0[j] - d.0[j]).abs() <= tol,
                "y[{j}]: {} vs {}",
                s.0[j],
                d.0[j]
            );
        }
        let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(f64::MIN_POSITIVE);
        assert!(
            rel(s.1.condition, d.1.condition) < 1e-8,
            "{} {}",
            s.1.condition,
            d.1.condition
        );
        assert!(rel(s.1.kinetic_energy_exact, d.1.kinetic_energy_exact) < 1e-10);
        assert!(rel(s.1.kinetic_energy_assembled, d.1.kinetic_energy_assembled) < 1e-10);
        let names = |r: &ProjectionReport| -> Vec<(String, &str)> {
            r.changes
                .iter()
                .map(|c| (c.body.clone(), c.coordinate))
                .collect()
        };
        assert_eq!(names(&s.1), names(&d.1));
    }

    #[test]
    fn chains_and_loops_assemble_to_the_dense_answer() {
        for (scene, f) in [
            (ladder(120, 1_000), FormulationName::LagrangeBaumgarte), // two chains, no loop
            (ladder(60, 10), FormulationName::LagrangeBaumgarte),     // 6 loops
            (ladder(60, 3), FormulationName::AugmentedLagrangian),    // 20 loops
        ] {
            let mech = mechanism(&scene, f).unwrap();
            assert!(mech.nq() >= SPARSE_FROM_COORDINATES, "{}", mech.nq());
            let (s, d) = both(&mech);
            let (s, d) = (s.expect("the sparse path answers"), d.unwrap());
            // The guesses were off: Newton and the projection did move them.
            assert!(
                d.1.max_position_change > 1e-3 && d.1.max_velocity_change > 0.1,
                "{:?}",
                d.1
            );
            agree(&mech, &s, &d);
            // The mechanism holds the sparse path's answer.
            assert_eq!(mech.projection_report(), &s.1);
        }
    }

    #[test]
    fn redundant_equations_are_left_to_the_dense_path() {
        // A ladder whose first rung is pinned twice (the same joint again): two equations
        // depend on the others. The augmented Lagrangian takes them (the dense path's
        // pseudo-inverse), Lagrange multipliers refuse them — in the dense path's words.
        let mut scene = ladder(60, 10);
        let rung = scene["joints"]
            .as_array()
            .unwrap()
            .iter()
            .find(|j| j["name"] == "ra9")
            .unwrap()
            .clone();
        let mut again = rung;
        again["name"] = json!("ra9 again");
        scene["joints"].as_array_mut().unwrap().push(again);
        let mech = mechanism(&scene, FormulationName::AugmentedLagrangian).unwrap();
        let (s, d) = both(&mech);
        assert!(s.is_none());
        assert_eq!(mech.projection_report(), &d.unwrap().1);
        let e = mechanism(&scene, FormulationName::LagrangeBaumgarte).unwrap_err();
        match &e {
            SceneError::Redundant { path, reason } => {
                assert_eq!(
                    path,
                    &format!("joints[{}]", scene["joints"].as_array().unwrap().len() - 1)
                );
                assert!(
                    reason.contains("depends on the equations before it"),
                    "{reason}"
                );
            }
            e => panic!("{e}"),
        }
    }

    #[test]
    fn a_nearly_singular_projection_is_refused_as_before() {
        // Issue 23's pendulum (journal at e = (0, −c/2), link2's exact vx = −3 m/s) beside a
        // chain of 110 links: large enough for the sparse path, which must leave it to the
        // dense path's refusal (condition number ~1e9, over its 1e6 margin).
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../cases/examples/pendulum.json");
        let mut scene: Value = serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap();
        scene["joints"][1]["initial_eccentricity"] = json!([0.0, -0.0005]);
        scene["bodies"][1]["initial_velocity"] = json!({"vx": -3.0});
        let (mut bodies, mut joints) = (Vec::new(), Vec::new());
        chain("c", 110, 5.0, &mut bodies, &mut joints);
        scene["bodies"].as_array_mut().unwrap().extend(bodies);
        scene["joints"].as_array_mut().unwrap().extend(joints);
        let small = Scene::from_json_str(&scene.to_string()).unwrap();
        let mut s = small.clone();
        s.formulation = FormulationName::LagrangeBaumgarte;
        match Mechanism::from_scene(&s) {
            Err(SceneError::Assembly { path, reason }) => {
                assert_eq!(path, "bodies[1].initial_velocity.vx");
                assert!(reason.contains("ill-conditioned"), "{reason}");
                assert!(reason.contains("carry 4.500e0 J"), "{reason}");
            }
            Err(e) => panic!("expected an assembly error, got {e}"),
            Ok(m) => panic!("built: {}", m.projection_report()),
        }
        // The same mechanism without the exact velocity builds; on the sparse path its
        // projection's condition number (the clearance joint's rows) stays under the margin.
        scene["bodies"][1]
            .as_object_mut()
            .unwrap()
            .remove("initial_velocity");
        let mech = mechanism(&scene, FormulationName::LagrangeBaumgarte).unwrap();
        let (s, d) = both(&mech);
        agree(&mech, &s.expect("the sparse path answers"), &d.unwrap());
    }

    #[test]
    fn lanczos_finds_the_extreme_eigenvalues_of_a_laplacian() {
        // The path graph's Laplacian-like matrix tridiag(−1, 2, −1) of order m has the
        // eigenvalues 2 − 2 cos(kπ/(m+1)), k = 1…m (closed form), the top ones clustered as a
        // chain's Gram matrix's are.
        for m in [1, 7, 400] {
            let apply = |x: &[f64], out: &mut [f64]| {
                for i in 0..m {
                    let left = if i > 0 { x[i - 1] } else { 0.0 };
                    let right = if i + 1 < m { x[i + 1] } else { 0.0 };
                    out[i] = 2.0 * x[i] - left - right;
                }
            };
            let top = largest_eigenvalue(m, apply).unwrap();
            let exact = 2.0 - 2.0 * (m as f64 * std::f64::consts::PI / (m as f64 + 1.0)).cos();
            assert!(
                (top - exact).abs() < 1e-9 * exact,
                "m = {m}: {top} vs {exact}"
            );
        }
    }
}
