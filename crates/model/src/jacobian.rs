//! The Jacobian ∂f/∂y of the mechanism ODE for implicit methods.
//!
//! ```text
//! f = (q̇, q̈(t, q, q̇)),   ∂f/∂y = [ 0        I       ]
//!                                 [ ∂q̈/∂q   ∂q̈/∂q̇  ]
//! q̈ = K(t, q, q̇; g),  g = g(q, q̇) the applied forces (gravity and clearance joints),
//!   K the KKT solution, linear in g:  ∂K/∂g = A = M⁻¹ − M⁻¹Φ_qᵀ S⁻¹ Φ_q M⁻¹
//! ∂q̈/∂y = ∂K/∂y |_{g fixed} + A ∂g/∂y
//!   ∂K/∂q  |_g : closed form (the derivatives of Φ_q, γ and Φ̇ in the angles; see
//!                `constraint_position_jacobian`)
//!   ∂K/∂q̇  |_g = M⁻¹Φ_qᵀ S⁻¹ ∂r/∂q̇,  r = γ − 2αΦ̇ − β²Φ,
//!                ∂r/∂q̇ = ∂γ/∂q̇ − 2α Φ_q   (closed form; γ ∋ ω² (w·A s))
//!   ∂g/∂y = ∂g/∂u · ∂u/∂y + ∂g/∂φ |_u,  u = (e, ė, φ̇_J, φ̇_B) of each clearance joint,
//!           ∂u/∂y closed form (e = r_J + A_J s_J − r_B − A_B s_B, ė its time derivative),
//!           ∂(F, T)/∂u by central differences in u, with steps scaled to the joint:
//!           h_e = 1e-6 · min(|e|, |δ|) (floor 1e-10 c), h_ė = 1e-6 · max(|ė|, |v_T|, 1e-9);
//!           a mirrored film caps them so that Ω moves by at most 1e-3 Ω₀ (h_φ̇ ≤ 1e-3 Ω₀,
//!           h_ė ≤ 1e-3 Ω₀ |e|/2, h_e ≤ 1e-3 Ω₀ |e|²/(2|ė|))
//! ```
//! The force elements and prismatic clearance joints of docs/model.md §10–§11 (when the scene
//! has any) add ∂g/∂y by central differences of their generalized forces alone, with steps
//! h_j = 1e-8 · max(|y_j|, 1e-2) (positions) and 1e-8 · max(|y_j|, 1e-3) (velocities).
//!
//! F is the total force of the joint on its journal (contact, friction, film), T the friction
//! force (its moment arm R_J or R_B about the pin centres); the journal body receives
//! (F, (A_J s_J) × F + R_J T), the bearing body the opposite with R_B.
//!
//! Why not plain differences of f: the clearance forces vary on the scale of the clearance
//! (c = 0.1 mm) and, through the normal n = e/|e|, on the scale |e| itself, which is 0 at the
//! centred start of the press and grows through 10⁻¹²…10⁻⁸ m; an increment of 10⁻⁸ m in the
//! body coordinates straddles that and gives a Jacobian with O(1) errors, which costs a
//! Rosenbrock method (it needs the exact Jacobian for its order) thousands of tiny steps.
//! Differencing in e, ė directly with increments relative to |e| and |δ| has no such limit and
//! no cancellation (e is not recomputed from positions of size 0.35 m). docs/model.md §1 (1.7)
//! allows finite differences for the constraint part; the closed forms above are exact, and
//! cost no KKT solve beyond one back substitution per column.

use faer::MatMut;

use crate::geometry::{ClearanceInput, ClearanceState};
use crate::mechanism::{cholesky_solve, perp, rot, Mechanism, Owner, Scratch, TermKind};

/// Relative step of the differences in the clearance variables u = (e, ė, φ̇_J, φ̇_B).
const LOCAL_STEP: f64 = 1e-6;

/// Largest change of the film's Ω in one difference of a mirrored film, in units of its
/// sign width Ω₀ (central differences of tanh(Ω/Ω₀) then err by about 3e-7 relative).
const OMEGA_STEP: f64 = 1e-3;

/// Fills `jac` (n × n) with ∂f/∂y at (t, y).
pub(crate) fn jacobian(mech: &Mechanism, t: f64, y: &[f64], mut jac: MatMut<'_, f64>) {
    let n = y.len();
    let nq = n / 2;
    let m = mech.rows.len();
    for j in 0..n {
        for i in 0..n {
            jac[(i, j)] = 0.0;
        }
    }
    for i in 0..nq {
        jac[(i, nq + i)] = 1.0;
    }
    let mut sc = mech.scratch.borrow_mut();
    if !mech.evaluate(t, y, &mut sc, false) {
        for j in 0..n {
            for i in nq..n {
                jac[(i, j)] = f64::NAN;
            }
        }
        return;
    }
    mech.dense_constraint_jacobian(&mut sc);
    // ∂g/∂y (nq × n, column-major) through the clearance joints.
    let mut dg = vec![0.0; nq * n];
    for k in 0..mech.clr.len() {
        clearance_force_jacobian(mech, k, &sc, n, &mut dg);
    }
    if !(mech.elements.is_empty() && mech.prismatic.is_empty()) {
        element_force_jacobian(mech, t, y, &sc, &mut dg);
    }
    // P = M⁻¹ Φ_qᵀ S⁻¹ (nq × m, row-major), from m solves with the factor of S: every later
    // product with S⁻¹ is a product with P.
    let pmat = kkt_projector(mech, &sc);
    // Lower-left and lower-right blocks: A ∂g/∂y, A = M⁻¹ − P Φ_q M⁻¹, column by column.
    let mut col = vec![0.0; nq];
    let mut w = vec![0.0; m];
    for j in 0..n {
        let dgj = &dg[j * nq..(j + 1) * nq];
        if dgj.iter().all(|&v| v == 0.0) {
            continue;
        }
        project(mech, &sc, &pmat, dgj, &mut w, &mut col);
        for i in 0..nq {
            jac[(nq + i, j)] = col[i];
        }
    }
    // ∂K/∂q̇ at fixed g: P ∂r/∂q̇, column by column.
    let drdv = constraint_rhs_velocity_jacobian(mech, &sc);
    for j in 0..nq {
        for i in 0..nq {
            let mut s = 0.0;
            for a in 0..m {
                s += pmat[i * m + a] * drdv[a * nq + j];
            }
            jac[(nq + i, nq + j)] += s;
        }
    }
    // ∂K/∂q at fixed g, in closed form (module doc).
    constraint_position_jacobian(mech, &sc, &pmat, &mut jac);
}

/// P = M⁻¹ Φ_qᵀ S⁻¹ (nq × m, row-major) after an evaluation (Φ_q in `sc.jac`, the factor of
/// S in `sc.smat`): S⁻¹ column by column from the factor, then the product.
fn kkt_projector(mech: &Mechanism, sc: &Scratch) -> Vec<f64> {
    let nq = mech.nq();
    let m = mech.rows.len();
    let mut sinv = vec![0.0; m * m];
    let mut e = vec![0.0; m];
    for a in 0..m {
        e.iter_mut().for_each(|v| *v = 0.0);
        e[a] = 1.0;
        cholesky_solve(&sc.smat, m, &mut e);
        sinv[a * m..(a + 1) * m].copy_from_slice(&e); // S⁻¹ is symmetric: row a = column a
    }
    let mut p = vec![0.0; nq * m];
    for i in 0..nq {
        for a in 0..m {
            let mut s = 0.0;
            for b in 0..m {
                s += sc.jac[b * nq + i] * sinv[b * m + a];
            }
            p[i * m + a] = mech.minv[i] * s;
        }
    }
    p
}

/// Adds ∂K/∂q at fixed g to the lower-left block of `jac` (after an evaluation: q̈, λ, Φ_q,
/// the factor of S in the scratch).
///
/// ```text
/// S λ = Φ_q M⁻¹ g − r,  q̈ = M⁻¹ (g − Φ_qᵀ λ)  ⇒  for each coordinate q_j:
///   u = (∂Φ_q/∂q_j)ᵀ λ,   S ∂λ = (∂Φ_q/∂q_j) q̈ − Φ_q M⁻¹ u − ∂r/∂q_j,
///   ∂q̈/∂q_j = −M⁻¹ (u + Φ_qᵀ ∂λ)
/// Φ_q depends on q only through the angles: a point term (w · r^P, r^P = r + A(φ) s) has
/// the row (w_x, w_y, w · b), b = ∂(A s)/∂φ, and ∂(w · b)/∂φ = −w · A s; so ∂Φ_q/∂q_j is
/// zero for x and y and has one nonzero column (j itself) for φ.
/// r = γ − 2αΦ̇ − β²Φ:  ∂Φ/∂q_j = Φ_q[:, j];  for a point term on body i,
///   ∂Φ̇/∂φ_i = −(w · A s) φ̇_i,   ∂γ/∂φ_i = φ̇_i² (w · b)   (γ ∋ φ̇_i² (w · A s))
/// ```
/// Before, central differences of 12 KKT solves (BENCHMARKS.md, "What was optimised").
fn constraint_position_jacobian(
    mech: &Mechanism,
    sc: &Scratch,
    pmat: &[f64],
    jac: &mut MatMut<'_, f64>,
) {
    let nq = mech.nq();
    let m = mech.rows.len();
    if m == 0 {
        return;
    }
    let (a2, b2) = (2.0 * mech.alpha, mech.beta * mech.beta);
    let mut dphiq = vec![0.0; m]; // ∂Φ_q[:, j]/∂q_j (the only nonzero column)
    let mut rhs = vec![0.0; m];
    for j in 0..nq {
        let (body_i, comp) = (j / 3, j % 3);
        dphiq.iter_mut().for_each(|v| *v = 0.0);
        // ∂r/∂q_j, with the sign of −∂r in `rhs`.
        for a in 0..m {
            rhs[a] = b2 * sc.jac[a * nq + j];
        }
        if comp == 2 {
            for (a, (row, ints)) in mech.rows.iter().zip(&mech.row_int).enumerate() {
                for (ti, term) in row.terms[..row.n_terms].iter().enumerate() {
                    if ints[ti] != Some(body_i) {
                        continue;
                    }
                    if let TermKind::Point { s, w: wv } = term.kind {
                        let av = rot(sc.cs[term.body], s);
                        let bv = perp(av);
                        let wa = wv[0] * av[0] + wv[1] * av[1];
                        let wb = wv[0] * bv[0] + wv[1] * bv[1];
                        let om = sc.vel[term.body][2];
                        dphiq[a] -= wa;
                        // −∂γ/∂φ + 2α ∂Φ̇/∂φ = −φ̇² (w · b) − 2α (w · A s) φ̇.
                        rhs[a] -= om * om * wb + a2 * wa * om;
                    }
                }
            }
        }
        // u = (∂Φ_q/∂q_j)ᵀ λ has the single entry u_j.
        let u: f64 = (0..m).map(|a| dphiq[a] * sc.lam[a]).sum();
        let mj = mech.minv[j];
        for a in 0..m {
            rhs[a] += dphiq[a] * sc.qdd[j] - sc.jac[a * nq + j] * mj * u;
        }
        // ∂q̈/∂q_j = −M⁻¹ u e_j − P (S ∂λ).
        for i in 0..nq {
            let mut v = if i == j { mech.minv[i] * u } else { 0.0 };
            for a in 0..m {
                v += pmat[i * m + a] * rhs[a];
            }
            jac[(nq + i, j)] -= v;
        }
    }
}

/// Adds ∂g/∂y of the force elements and prismatic clearance joints (nq × n, column-major)
/// by central differences of their generalized forces.
fn element_force_jacobian(mech: &Mechanism, t: f64, y: &[f64], sc: &Scratch, dg: &mut [f64]) {
    let n = y.len();
    let nq = n / 2;
    let mut s2 = sc.clone();
    let mut yp = y.to_vec();
    let mut gp = vec![0.0; nq];
    let mut gm = vec![0.0; nq];
    let g_of = |yp: &[f64], s2: &mut Scratch, out: &mut [f64]| {
        mech.kinematics(t, yp, s2);
        s2.g.iter_mut().for_each(|v| *v = 0.0);
        mech.element_forces(t, s2, false);
        out.copy_from_slice(&s2.g);
    };
    for j in 0..n {
        let floor = if j < nq { 1e-2 } else { 1e-3 };
        let h = 1e-8 * y[j].abs().max(floor);
        yp[j] = y[j] + h;
        let hp = yp[j] - y[j];
        g_of(&yp, &mut s2, &mut gp);
        yp[j] = y[j] - h;
        let hm = y[j] - yp[j];
        g_of(&yp, &mut s2, &mut gm);
        yp[j] = y[j];
        let col = &mut dg[j * nq..(j + 1) * nq];
        for ((c, p), m) in col.iter_mut().zip(&gp).zip(&gm) {
            *c += (p - m) / (hp + hm);
        }
    }
}

/// out = A v = M⁻¹ v − P Φ_q M⁻¹ v (after an evaluation: Φ_q in `sc.jac`; P from
/// [`kkt_projector`]); `w` is scratch of length m.
fn project(
    mech: &Mechanism,
    sc: &Scratch,
    pmat: &[f64],
    v: &[f64],
    w: &mut [f64],
    out: &mut [f64],
) {
    let nq = v.len();
    let m = w.len();
    let minv = &mech.minv;
    for a in 0..m {
        let ja = &sc.jac[a * nq..(a + 1) * nq];
        let mut s = 0.0;
        for j in 0..nq {
            s += ja[j] * minv[j] * v[j];
        }
        w[a] = s;
    }
    for i in 0..nq {
        let mut s = minv[i] * v[i];
        for a in 0..m {
            s -= pmat[i * m + a] * w[a];
        }
        out[i] = s;
    }
}

/// ∂r/∂q̇ (m × nq, row-major) of the constraint right-hand side r = γ − 2αΦ̇ − β²Φ.
fn constraint_rhs_velocity_jacobian(mech: &Mechanism, sc: &Scratch) -> Vec<f64> {
    let nq = mech.nq();
    let a2 = 2.0 * mech.alpha;
    let mut out = vec![0.0; mech.rows.len() * nq];
    for (r, row) in mech.rows.iter().enumerate() {
        for term in &row.terms[..row.n_terms] {
            let Owner::Int(i) = mech.bodies[term.body].owner else {
                continue;
            };
            let base = r * nq + 3 * i;
            match term.kind {
                TermKind::Point { s, w: wv } => {
                    let a = rot(sc.cs[term.body], s);
                    let b = perp(a);
                    let w = sc.vel[term.body][2];
                    out[base] -= a2 * wv[0];
                    out[base + 1] -= a2 * wv[1];
                    out[base + 2] += 2.0 * w * (wv[0] * a[0] + wv[1] * a[1])
                        - a2 * (wv[0] * b[0] + wv[1] * b[1]);
                }
                TermKind::Angle { c } => out[base + 2] -= a2 * c,
            }
        }
    }
    out
}

/// The joint's force on its journal F and its friction force T as functions of
/// u = (e_x, e_y, ė_x, ė_y, φ̇_J, φ̇_B).
fn local_forces(mech: &Mechanism, k: usize, u: &[f64; 6]) -> [f64; 3] {
    let c = &mech.clr[k];
    let st = ClearanceState::compute(&ClearanceInput {
        r_j: [u[0], u[1]],
        r_b: [0.0, 0.0],
        v_j: [u[2], u[3]],
        v_b: [0.0, 0.0],
        phi_dot_j: u[4],
        phi_dot_b: u[5],
        radius_j: c.rj,
        radius_b: c.rb,
    });
    let ev = mech.clearance_forces(k, st);
    let fn_ = -ev.f_n + ev.f_r;
    let ft = ev.f_t + ev.f_tf;
    [
        fn_ * st.n[0] + ft * st.t[0],
        fn_ * st.n[1] + ft * st.t[1],
        ev.f_t,
    ]
}

/// Adds the contribution of clearance joint k to ∂g/∂y (nq × n, column-major in `dg`).
fn clearance_force_jacobian(mech: &Mechanism, k: usize, sc: &Scratch, n: usize, dg: &mut [f64]) {
    let nq = n / 2;
    let c = &mech.clr[k];
    let st = sc.clr[k].st;
    let w_j = c.journal.body.map_or(0.0, |b| sc.vel[b][2]);
    let w_b = c.bearing.body.map_or(0.0, |b| sc.vel[b][2]);
    let edot = ed(mech, k, sc);
    let u0 = [st.e[0], st.e[1], edot[0], edot[1], w_j, w_b];
    // Steps scaled to the joint (see the module documentation).
    let mut he = (LOCAL_STEP * st.e_norm.min(st.delta.abs())).max(1e-10 * c.c);
    let vscale = u0[2].abs().max(u0[3].abs()).max(st.v_t.abs()).max(1e-9);
    let mut hv = LOCAL_STEP * vscale;
    let mut hw = hv / c.rj.max(c.rb);
    // A mirrored film turns its sign over the width Ω₀ of tanh(Ω/Ω₀) (docs/model.md §4): each
    // difference may move Ω = φ̇_J + φ̇_B − 2 (n × ė)/|e| by at most OMEGA_STEP · Ω₀, so that
    // it resolves the turn. Floors keep every step representable against u0 (1e-12 relative).
    if let Some(film) = c.film.filter(|f| f.is_mirrored()) {
        let dom = OMEGA_STEP * film.mirror_width;
        hw = hw.min(dom).max(1e-12 * u0[4].abs().max(u0[5].abs()));
        if st.e_norm > 0.0 {
            hv = hv.min(0.5 * dom * st.e_norm).max(1e-12 * vscale);
            let edot = u0[2].hypot(u0[3]);
            if edot > 0.0 {
                he = he
                    .min(0.5 * dom * st.e_norm * st.e_norm / edot)
                    .max(1e-12 * st.e_norm);
            }
        }
    }
    let steps = [he, he, hv, hv, hw, hw];
    // ∂(F_x, F_y, T)/∂u, 3 × 6.
    let mut lu = [[0.0; 6]; 3];
    let f0 = local_forces(mech, k, &u0);
    let mut u = u0;
    for j in 0..6 {
        let h = steps[j];
        u[j] = u0[j] + h;
        let hp = u[j] - u0[j];
        let fp = local_forces(mech, k, &u);
        u[j] = u0[j] - h;
        let hm = u0[j] - u[j];
        let fm = local_forces(mech, k, &u);
        u[j] = u0[j];
        for i in 0..3 {
            lu[i][j] = (fp[i] - fm[i]) / (hp + hm);
        }
    }
    // ∂u/∂y for each integrated end: e = ±(r + A s), ė = ±(v + ω perp(A s)), φ̇ of the body.
    // Column index of (x, y, φ) of body i: 3i..3i+2; of (ẋ, ẏ, ω): nq + 3i..nq + 3i+2.
    let mut du = vec![[0.0; 6]; n];
    let ends = [(c.journal, 1.0, 4usize), (c.bearing, -1.0, 5usize)];
    for (end, sign, wslot) in ends {
        let Some(kb) = end.body else { continue };
        let Owner::Int(i) = mech.bodies[kb].owner else {
            continue;
        };
        let a = rot(sc.cs[kb], end.s);
        let b = perp(a);
        let w = sc.vel[kb][2];
        let (px, py, pp, vx, vy, vw) = (
            3 * i,
            3 * i + 1,
            3 * i + 2,
            nq + 3 * i,
            nq + 3 * i + 1,
            nq + 3 * i + 2,
        );
        du[px][0] += sign;
        du[py][1] += sign;
        du[pp][0] += sign * b[0];
        du[pp][1] += sign * b[1];
        // ∂(ω perp(A s))/∂φ = −ω A s.
        du[pp][2] -= sign * w * a[0];
        du[pp][3] -= sign * w * a[1];
        du[vx][2] += sign;
        du[vy][3] += sign;
        du[vw][2] += sign * b[0];
        du[vw][3] += sign * b[1];
        du[vw][wslot] += 1.0;
    }
    // dF/dy, dT/dy, then the generalized forces of both ends.
    let f = [f0[0], f0[1]];
    for j in 0..n {
        let dj = &du[j];
        if dj.iter().all(|&v| v == 0.0) {
            continue;
        }
        let mut d = [0.0; 3];
        for (i, di) in d.iter_mut().enumerate() {
            *di = (0..6).map(|l| lu[i][l] * dj[l]).sum();
        }
        let col = &mut dg[j * nq..(j + 1) * nq];
        for (end, sign, radius) in [(c.journal, 1.0, c.rj), (c.bearing, -1.0, c.rb)] {
            let Some(kb) = end.body else { continue };
            let Owner::Int(i) = mech.bodies[kb].owner else {
                continue;
            };
            let a = rot(sc.cs[kb], end.s);
            col[3 * i] += sign * d[0];
            col[3 * i + 1] += sign * d[1];
            col[3 * i + 2] += sign * (a[0] * d[1] - a[1] * d[0] + radius * d[2]);
        }
    }
    // The moment arms A s turn with their own bodies: ∂((A s) × F)/∂φ = perp(A s) × F = −(A s)·F.
    for (end, sign) in [(c.journal, 1.0), (c.bearing, -1.0)] {
        let Some(kb) = end.body else { continue };
        let Owner::Int(i) = mech.bodies[kb].owner else {
            continue;
        };
        let a = rot(sc.cs[kb], end.s);
        dg[(3 * i + 2) * nq + 3 * i + 2] -= sign * (a[0] * f[0] + a[1] * f[1]);
    }
}

/// ė of clearance joint k (after `kinematics`).
fn ed(mech: &Mechanism, k: usize, sc: &Scratch) -> [f64; 2] {
    let c = &mech.clr[k];
    let vel = |end: &crate::mechanism::End| match end.body {
        None => [0.0; 2],
        Some(kb) => {
            let a = rot(sc.cs[kb], end.s);
            let [vx, vy, w] = sc.vel[kb];
            [vx - w * a[1], vy + w * a[0]]
        }
    };
    let (vj, vb) = (vel(&c.journal), vel(&c.bearing));
    [vj[0] - vb[0], vj[1] - vb[1]]
}
