//! The Jacobian ∂f/∂y and the time derivative ∂f/∂t of the minimal formulation, given the
//! applied forces' ∂g/∂(q, q̇).
//!
//! ```text
//! θ̈ solves  F(y, θ̈) = Rᵀ(θ) [Q(q, q̇) − M (R θ̈ + a_c(θ, θ̇))] = 0,   ∂F/∂θ̈ = −Rᵀ M R
//! ∂θ̈/∂y_j = (Rᵀ M R)⁻¹ [ Rᵀ ∂Q/∂(q, q̇) · ∂(q, q̇)/∂y_j  +  ∂_j ρ ]
//! ρ(y) = Rᵀ(θ) [Q − M q̈(θ, θ̇; θ̈)]   with Q and θ̈ held at the evaluation's values
//! ```
//! The force part chains the closed-form ∂g/∂(q, q̇) of the clearance joints and elements
//! (mechanism/forces.rs) through ∂q/∂θ = R, ∂q̇/∂θ̇ = R, ∂q/∂θ̇ = 0 and ∂q̇/∂θ; the
//! geometric part (∂q̇/∂θ and ∂ρ) is smooth and cheap — the tree's kinematics, no force — and
//! is taken by central differences of the recursive kinematics (tree.rs), step
//! h = 6e-6 (1 + |y_j|) ≈ ε^(1/3) scale, error O(h²) ≈ 1e-10 relative. One Jacobian costs the
//! forces' ∂g plus, per column of θ and side, a pass of the tree's kinematics over the bodies
//! the column's coordinate moves (Tree::moved_by: its body and the descendants), and n + n
//! solves with the factor of Rᵀ M R; the other bodies keep the unperturbed kinematics, so the
//! numbers are those of full passes (the test below keeps the full-pass implementation as the
//! reference). A column of θ̇ moves no body and R is held: on a tree it is the closed form
//! ∂_j ρ = −Rᵀ M ∂a_c/∂θ̇_j (a_c is quadratic in the bodies' angular rates:
//! `Tree::rate_derivative_of`), exact where the difference was exact but for its rounding.
//! With loop closures (loops.rs) ρ also carries −Φ_θᵀλ*, the closing rows' σ is differenced
//! alongside (velocities only for a column of θ̇), and each column solves the differentiated
//! KKT system instead.
//!
//! ∂f/∂t ([`Minimal::time_derivative`]) is given too, for Rosenbrock methods: time moves the
//! prescribed bodies and, at fixed (θ, θ̇), everything that hangs from them, so f_t carries
//! the film's and the contact's stiffness (≈ 1e6 on the lubricated press, where
//! Lagrange–Baumgarte's is ≈ 1e2) and cancels J f along the motion; a difference of f in t
//! is not accurate enough for that (module doc of `time_derivative`). Its force part is the
//! same closed-form ∂g/∂(q, q̇) times ∂(q, q̇)/∂t in closed form; the smooth rest by the
//! five-point central difference (2/3 (φ(t+h) − φ(t−h)) − 1/12 (φ(t+2h) − φ(t−2h)))/h,
//! h = ε^(1/5)/max(1, |ω|max). Cost: the forces' ∂g, four force evaluations, five passes of
//! the kinematics and one solve; Rodas5P calls it once per step instead of two RHS.

use faer::reborrow::ReborrowMut;
use faer::MatMut;

use crate::linalg::{cholesky_solve, first_order_jacobian_frame, zeroed};
use crate::mechanism::bodies::Bodies;
use crate::mechanism::forces::Forces;
use crate::mechanism::formulation::minimal::{solve_unrolled, JacWork, Minimal};
use crate::mechanism::scratch::Scratch;

/// `v` at length `len`, its entries as they are (resized, with zeros, only when it is not).
#[inline]
fn sized(v: &mut Vec<f64>, len: usize) -> &mut [f64] {
    if v.len() != len {
        v.resize(len, 0.0);
    }
    &mut v[..len]
}

/// Column `j` of ∂f/∂y (2n rows, n = `lower.len()`): the upper rows [0 I]'s entries and
/// `lower` below them, through the column's slice when its rows are contiguous (faer's
/// indexed writes check every entry), else entry by entry.
#[inline]
fn write_column(jac: &mut MatMut<'_, f64>, j: usize, n: usize, lower: &[f64]) {
    let upper = |i: usize| if j == n + i { 1.0 } else { 0.0 };
    match jac.rb_mut().col_mut(j).try_as_col_major_mut() {
        Some(c) => {
            let c = &mut c.as_slice_mut()[..2 * n];
            for (i, v) in c[..n].iter_mut().enumerate() {
                *v = upper(i);
            }
            c[n..].copy_from_slice(lower);
        }
        None => {
            for i in 0..n {
                jac[(i, j)] = upper(i);
            }
            for (a, &v) in lower.iter().enumerate() {
                jac[(n + a, j)] = v;
            }
        }
    }
}

/// The five-point central difference (module doc): (offset in steps, weight); the derivative
/// is Σ weight · φ(x + offset · h) / h.
const STENCIL: [(f64, f64); 4] = [
    (1.0, 2.0 / 3.0),
    (-1.0, -2.0 / 3.0),
    (2.0, -1.0 / 12.0),
    (-2.0, 1.0 / 12.0),
];

/// ε^(1/5), the step of [`STENCIL`] at unit scale.
fn step_scale() -> f64 {
    f64::EPSILON.powf(0.2)
}

impl Minimal {
    /// ∂f/∂y (module doc) into `jac` (2n × 2n) after an evaluation; `dg` = None: the
    /// evaluation failed, the lower rows are NaN.
    pub(crate) fn jacobian(&self, sc: &Scratch, dg: Option<&[f64]>, mut jac: MatMut<'_, f64>) {
        let (nq, n) = (self.nq, self.tree.n);
        let Some(dg) = dg else {
            first_order_jacobian_frame(&mut jac, n, false);
            return;
        };
        // Each column below writes its entries of the upper rows [0 I]
        // (first_order_jacobian_frame's) and of the lower rows (`write_column`).
        let w = self.work.borrow();
        let mut jw = self.jac_work.borrow_mut();
        let JacWork {
            sc: s2,
            yp,
            rp,
            qddp,
            qdd0,
            rho,
            qd,
            dgq,
            dac,
            col,
            ..
        } = &mut *jw;
        // The kinematics as the evaluation left them (the prescribed bodies' functions of t,
        // the integrated bodies' those of Tree::positions at y): a column recomputes the
        // bodies it moves (Tree::moved_by) and puts them back, so that every other body's
        // kinematics, R rows and q̈ are the unperturbed ones, the bits a pass over every body
        // would give.
        match s2 {
            Some(s2) => s2.copy_kinematics_from(sc),
            None => *s2 = Some(sc.clone()),
        }
        let s2 = s2.as_mut().expect("set above");
        let y = &w.y;
        // Sized once (no zeroing: every entry read is written first, at the call or in its
        // column).
        sized(yp, 2 * n).copy_from_slice(y);
        sized(rp, nq * n).copy_from_slice(&w.r[..nq * n]);
        self.tree.accelerations(s2, Some(&w.thdd), sized(qdd0, nq));
        sized(qddp, nq).copy_from_slice(qdd0);
        let [rho0, rho1] = rho;
        for v in [rho0, rho1, col] {
            sized(v, n);
        }
        let [qd0, qd1] = qd;
        for v in [qd0, qd1, dgq, dac] {
            sized(v, nq);
        }
        // Loop closures (loops.rs): σ at the perturbed states, and the columns' KKT solve.
        let (mut sig, mut dsig): ([Vec<f64>; 2], Vec<f64>) = Default::default();
        if let Some(l) = &self.loops {
            let ml = l.len();
            sig = [vec![0.0; ml], vec![0.0; ml]];
            dsig = vec![0.0; ml];
            l.start_jacobian();
        }
        for j in 0..2 * n {
            let moved = self.tree.moved_by(j % n);
            if j >= n && self.loops.is_none() {
                // A rate's column in closed form (module doc).
                self.rate_column(j - n, moved, sc, dg, dac, dgq, col);
                solve_unrolled(&w.mr, n, col);
                write_column(&mut jac, j, n, col);
                continue;
            }
            let h = 6e-6 * (1.0 + y[j].abs());
            let mut hs = [0.0; 2];
            for (side, sign) in [(0usize, 1.0), (1, -1.0)] {
                yp[j] = y[j] + sign * h;
                hs[side] = (yp[j] - y[j]).abs();
                let r = if j < n {
                    self.tree.positions_of(moved, &yp[..n], &yp[n..], s2);
                    self.tree.velocity_matrix_of(moved, s2, nq, rp);
                    for tb in moved.iter().map(|&b| &self.tree.bodies[b]) {
                        let ii = 3 * tb.int;
                        qd[side][ii..ii + 3].copy_from_slice(&s2.vel[tb.body]);
                    }
                    &rp[..]
                } else {
                    // A rate moves no body: velocities only.
                    self.tree.velocities_of(moved, &yp[n..], s2);
                    &w.r[..]
                };
                self.tree.accelerations_of(moved, s2, Some(&w.thdd), qddp);
                self.reduced_residual(r, &sc.g, qddp, &mut rho[side]);
                if let Some(l) = &self.loops {
                    l.perturbed(w.t, s2, r, qddp, &mut rho[side], &mut sig[side]);
                }
            }
            yp[j] = y[j];
            // The moved bodies back to the unperturbed state.
            for tb in moved.iter().map(|&b| &self.tree.bodies[b]) {
                let (k, ii) = (tb.body, 3 * tb.int);
                s2.pose[k] = sc.pose[k];
                s2.vel[k] = sc.vel[k];
                s2.cs[k] = sc.cs[k];
                qddp[ii..ii + 3].copy_from_slice(&qdd0[ii..ii + 3]);
                if j < n {
                    for (cp, c0) in rp.chunks_exact_mut(nq).zip(w.r.chunks_exact(nq)) {
                        cp[ii..ii + 3].copy_from_slice(&c0[ii..ii + 3]);
                    }
                }
            }
            let hh = hs[0] + hs[1];
            // ρ' + Rᵀ ∂Q/∂(q, q̇) ∂(q, q̇)/∂y_j, with ∂(q, q̇)/∂y_j = (R_j, (q̇₊ − q̇₋)/hh)
            // (θ_j) or (0, R_j) (θ̇_j, loop closures).
            // Over the moved bodies' rows of q and of q̇, ascending: ∂(q, q̇)/∂y_j is +0 in
            // the others (R_j's rows, and (q̇ − q̇)/hh of a body not moved), which the sum
            // over every row skipped too.
            dgq.fill(0.0);
            let rows = self.tree.rows_moved_by(j % n);
            let rj = &w.r[(j % n) * nq..(j % n + 1) * nq];
            let mut add = |c: usize, d: f64| {
                if d != 0.0 {
                    for (o, &v) in dgq.iter_mut().zip(&dg[c * nq..(c + 1) * nq]) {
                        *o += v * d;
                    }
                }
            };
            if j < n {
                for &i in rows {
                    add(i, rj[i]);
                }
                for &i in rows {
                    add(nq + i, (qd[0][i] - qd[1][i]) / hh);
                }
            } else {
                for &i in rows {
                    add(nq + i, rj[i]);
                }
            }
            self.reduced_product(&w.r, dgq, col);
            for (out, (p, m)) in col.iter_mut().zip(rho[0].iter().zip(&rho[1])) {
                *out += (p - m) / hh;
            }
            match &self.loops {
                None => solve_unrolled(&w.mr, n, col),
                Some(l) => {
                    for (d, (p, m)) in dsig.iter_mut().zip(sig[0].iter().zip(&sig[1])) {
                        *d = (p - m) / hh;
                    }
                    l.column(col, &dsig);
                }
            }
            write_column(&mut jac, j, n, col);
        }
    }

    /// The column of θ̇_`c` before the solve, Rᵀ [∂g/∂q̇ · R_c − M ∂a_c/∂θ̇_c], into `col`
    /// (n), in closed form (module doc): ∂q/∂θ̇ = 0, ∂q̇/∂θ̇_c = R_c (nonzero in the rows of
    /// the bodies `moved` = `Tree::moved_by(c)` only), and q̈ = R θ̈ + a_c with R and θ̈
    /// held moves by ∂a_c/∂θ̇_c (`Tree::rate_derivative_of`), in the same rows. `dgq` and
    /// `dac` (n_q) are buffers.
    #[allow(clippy::too_many_arguments)]
    fn rate_column(
        &self,
        c: usize,
        moved: &[usize],
        sc: &Scratch,
        dg: &[f64],
        dac: &mut [f64],
        dgq: &mut [f64],
        col: &mut [f64],
    ) {
        let nq = self.nq;
        let w = self.work.borrow();
        let rc = &w.r[c * nq..(c + 1) * nq];
        let rows = self.tree.rows_moved_by(c);
        dgq.fill(0.0);
        for &i in rows {
            let d = rc[i];
            if d != 0.0 {
                let dgc = &dg[(nq + i) * nq..(nq + i + 1) * nq];
                for (o, &v) in dgq.iter_mut().zip(dgc) {
                    *o += v * d;
                }
            }
        }
        self.tree.rate_derivative_of(c, moved, sc, dac);
        for &i in rows {
            dgq[i] -= self.mass[i] * dac[i];
        }
        self.reduced_product(&w.r, dgq, col);
    }

    /// ρ = Rᵀ (g − M q̈) into `out` (n), body by body over the columns of R that reach each
    /// body (`force_terms`, as the right-hand side sums Rᵀ (Q − M a_c)): the bits of the sum
    /// over every row from +0, whose skipped terms are +0 · finite = ±0.
    fn reduced_residual(&self, r: &[f64], g: &[f64], qdd: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for t in &self.force_terms {
            let (rj, g) = (&r[t.rj..t.rj + 3], &g[t.q..t.q + 3]);
            let (m, a) = (&self.mass[t.q..t.q + 3], &qdd[t.q..t.q + 3]);
            let mut s = out[t.entry];
            s += rj[0] * (g[0] - m[0] * a[0]);
            s += rj[1] * (g[1] - m[1] * a[1]);
            s += rj[2] * (g[2] - m[2] * a[2]);
            out[t.entry] = s;
        }
    }

    /// Rᵀ v into `out` (n), over the reached columns as [`Minimal::reduced_residual`]; from
    /// −0, the start of f64's `Sum` that the dense loop used (an entry can differ from that
    /// loop's only in the sign of a zero, when every reached term is −0).
    fn reduced_product(&self, r: &[f64], v: &[f64], out: &mut [f64]) {
        out.fill(-0.0);
        for t in &self.force_terms {
            let (rj, v) = (&r[t.rj..t.rj + 3], &v[t.q..t.q + 3]);
            let mut s = out[t.entry];
            s += rj[0] * v[0];
            s += rj[1] * v[1];
            s += rj[2] * v[2];
            out[t.entry] = s;
        }
    }

    /// ∂f/∂t at fixed y = (θ, θ̇) into `out` (both halves) after an evaluation at (t, y),
    /// given the applied forces' ∂g/∂(q, q̇) `dg`:
    ///
    /// ```text
    /// ∂θ̈/∂t = (Rᵀ M R)⁻¹ [ Rᵀ (∂g/∂(q, q̇) · ∂(q, q̇)/∂t + ∂g/∂t|_(q, q̇)) + ∂ρ/∂t ]
    /// ```
    /// Time moves the prescribed bodies, and with them, at fixed joint coordinates, every
    /// body that hangs from one (the press's rod from its crank). The stiff part — the film or
    /// contact force as the journal is carried across the clearance — is the closed-form
    /// ∂g/∂(q, q̇) times ∂(q, q̇)/∂t, itself in closed form (below); the smooth rest — ∂ρ/∂t
    /// with Q and θ̈ held, and the forces' own dependence on the prescribed bodies and on t at
    /// fixed (q, q̇), ∂g/∂t|_(q, q̇) (zero on the press; what Lagrange–Baumgarte differences
    /// too) — by the module's five-point difference in t, step h_t = ε^(1/5)/max(1, |ω|max)
    /// (a crank angle of ≈ 7e-4 rad). A central difference of f itself in t moves the journal
    /// by ω r δ_t across a film whose length scale is its gap: on the lubricated press its
    /// error is up to 2 % at Rodas5P's δ_t (tests/minimal.rs).
    pub(crate) fn time_derivative(
        &self,
        bodies: &Bodies,
        forces: &Forces,
        t: f64,
        sc: &Scratch,
        dg: &[f64],
        out: &mut [f64],
    ) {
        let (nq, n) = (self.nq, self.tree.n);
        out[..n].fill(0.0);
        let w = self.work.borrow();
        let mut jw = self.jac_work.borrow_mut();
        let JacWork {
            sc: s2,
            yp,
            qddp,
            rho,
            dq,
            dgq,
            col,
            ..
        } = &mut *jw;
        let s2 = s2.get_or_insert_with(|| sc.clone());
        zeroed(qddp, nq);
        zeroed(&mut rho[0], n);
        zeroed(dq, 2 * nq);
        zeroed(dgq, nq);
        zeroed(col, n);
        let omega = bodies
            .pres
            .iter()
            .map(|p| p.omega.abs())
            .fold(1.0, f64::max);
        let h = step_scale() / omega;
        for (off, wt) in STENCIL {
            let ts = t + off * h;
            // ∂g/∂t at fixed (q, q̇) of the integrated bodies, into dgq.
            s2.copy_kinematics_from(sc);
            bodies.prescribed_kinematics(ts, s2);
            forces.applied(bodies, ts, s2, false);
            for (o, g) in dgq.iter_mut().zip(&s2.g) {
                *o += wt * g;
            }
            // ρ with Q and θ̈ held, at fixed (θ, θ̇).
            self.tree.positions(&w.y[..n], &w.y[n..2 * n], s2);
            self.tree.accelerations(s2, Some(&w.thdd), qddp);
            for (a, o) in rho[0].iter_mut().enumerate() {
                let ra = &w.r[a * nq..(a + 1) * nq];
                let mut s = 0.0;
                for i in 0..nq {
                    s += ra[i] * (sc.g[i] - self.mass[i] * qddp[i]);
                }
                *o += wt * s;
            }
        }
        // ∂(q, q̇)/∂t at fixed (θ, θ̇), in closed form: R does not depend on t (a prescribed
        // body's parents are prescribed too), so ∂q/∂t = b(t, θ) and ∂q̇/∂t = ∂b/∂t, the
        // velocity and acceleration of the tree moved by its prescribed bodies alone (θ̇ = 0,
        // θ̈ = 0). Exact, because on a stiff film the force part below must cancel J f to
        // many digits.
        s2.copy_kinematics_from(sc);
        zeroed(yp, n);
        self.tree.positions(&w.y[..n], yp, s2);
        self.tree.accelerations(s2, None, qddp);
        for tb in &self.tree.bodies {
            let ii = 3 * tb.int;
            dq[ii..ii + 3].copy_from_slice(&s2.vel[tb.body]);
            dq[nq + ii..nq + ii + 3].copy_from_slice(&qddp[ii..ii + 3]);
        }
        dgq.iter_mut().for_each(|v| *v /= h);
        // ∂g/∂(q, q̇) · ∂(q, q̇)/∂t, added to dgq.
        for (c, &d) in dq.iter().enumerate() {
            if d != 0.0 {
                for (o, &v) in dgq.iter_mut().zip(&dg[c * nq..(c + 1) * nq]) {
                    *o += v * d;
                }
            }
        }
        for (a, o) in col.iter_mut().enumerate() {
            let ra = &w.r[a * nq..(a + 1) * nq];
            let s: f64 = ra.iter().zip(dgq.iter()).map(|(x, y)| x * y).sum();
            *o = s + rho[0][a] / h;
        }
        cholesky_solve(&w.mr, n, col);
        out[n..2 * n].copy_from_slice(col);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanism::formulation::Formulation;
    use crate::{Mechanism, Scene};
    use faer::Mat;
    use lash_solver::OdeSystem;

    impl Minimal {
        /// The Jacobian as it was before the columns recomputed only the bodies they move
        /// (every body's kinematics at each side, dense sums over every row of R): the
        /// reference whose numbers the faster one must keep.
        fn jacobian_every_body(&self, sc: &Scratch, dg: Option<&[f64]>, mut jac: MatMut<'_, f64>) {
            let (nq, n) = (self.nq, self.tree.n);
            first_order_jacobian_frame(&mut jac, n, dg.is_some());
            let Some(dg) = dg else {
                return;
            };
            let w = self.work.borrow();
            let mut jw = self.jac_work.borrow_mut();
            let JacWork {
                sc: s2,
                yp,
                rp,
                qddp,
                rho,
                qd,
                dq,
                dgq,
                col,
                ..
            } = &mut *jw;
            // The prescribed bodies' kinematics (functions of t) as the evaluation left them.
            match s2 {
                Some(s2) => s2.copy_kinematics_from(sc),
                None => *s2 = Some(sc.clone()),
            }
            let s2 = s2.as_mut().expect("set above");
            let y = &w.y;
            zeroed(yp, 2 * n).copy_from_slice(y);
            zeroed(rp, nq * n);
            zeroed(qddp, nq);
            zeroed(&mut rho[0], n);
            zeroed(&mut rho[1], n);
            zeroed(&mut qd[0], nq);
            zeroed(&mut qd[1], nq);
            zeroed(dq, 2 * nq);
            zeroed(dgq, nq);
            zeroed(col, n);
            // Loop closures (loops.rs): σ at the perturbed states, and the columns' KKT solve.
            let ml = self.loops.as_ref().map_or(0, |l| l.len());
            let mut sig = [vec![0.0; ml], vec![0.0; ml]];
            let mut dsig = vec![0.0; ml];
            if let Some(l) = &self.loops {
                l.start_jacobian();
            }
            for j in 0..2 * n {
                let h = 6e-6 * (1.0 + y[j].abs());
                let mut hs = [0.0; 2];
                for (side, sign) in [(0usize, 1.0), (1, -1.0)] {
                    yp[j] = y[j] + sign * h;
                    hs[side] = (yp[j] - y[j]).abs();
                    self.tree.positions(&yp[..n], &yp[n..], s2);
                    let r = if j < n {
                        self.tree.velocity_matrix(s2, nq, rp);
                        &rp[..]
                    } else {
                        &w.r[..]
                    };
                    self.tree.accelerations(s2, Some(&w.thdd), qddp);
                    for tb in &self.tree.bodies {
                        let ii = 3 * tb.int;
                        qd[side][ii..ii + 3].copy_from_slice(&s2.vel[tb.body]);
                    }
                    for (a, out) in rho[side].iter_mut().enumerate() {
                        let ra = &r[a * nq..(a + 1) * nq];
                        let mut s = 0.0;
                        for i in 0..nq {
                            s += ra[i] * (sc.g[i] - self.mass[i] * qddp[i]);
                        }
                        *out = s;
                    }
                    if let Some(l) = &self.loops {
                        l.perturbed(w.t, s2, r, qddp, &mut rho[side], &mut sig[side]);
                    }
                }
                yp[j] = y[j];
                let hh = hs[0] + hs[1];
                // ∂(q, q̇)/∂y_j.
                if j < n {
                    dq[..nq].copy_from_slice(&w.r[j * nq..(j + 1) * nq]);
                    for i in 0..nq {
                        dq[nq + i] = (qd[0][i] - qd[1][i]) / hh;
                    }
                } else {
                    dq[..nq].fill(0.0);
                    dq[nq..].copy_from_slice(&w.r[(j - n) * nq..(j - n + 1) * nq]);
                }
                // ρ' + Rᵀ ∂Q/∂(q, q̇) ∂(q, q̇)/∂y_j.
                dgq.fill(0.0);
                for (c, &d) in dq.iter().enumerate() {
                    if d != 0.0 {
                        for (o, &v) in dgq.iter_mut().zip(&dg[c * nq..(c + 1) * nq]) {
                            *o += v * d;
                        }
                    }
                }
                for (a, out) in col.iter_mut().enumerate() {
                    let ra = &w.r[a * nq..(a + 1) * nq];
                    let s: f64 = ra.iter().zip(dgq.iter()).map(|(x, y)| x * y).sum();
                    *out = s + (rho[0][a] - rho[1][a]) / hh;
                }
                match &self.loops {
                    None => cholesky_solve(&w.mr, n, col),
                    Some(l) => {
                        for (d, (p, m)) in dsig.iter_mut().zip(sig[0].iter().zip(&sig[1])) {
                            *d = (p - m) / hh;
                        }
                        l.column(col, &dsig);
                    }
                }
                for (a, &v) in col.iter().enumerate() {
                    jac[(n + a, j)] = v;
                }
            }
        }
    }

    /// The old and the new Jacobian of `m` at (t, y), through the mechanism's evaluation.
    fn both(m: &Mechanism, t: f64, y: &[f64]) -> (Mat<f64>, Mat<f64>) {
        let Formulation::Minimal(f) = m.formulation() else {
            panic!("minimal")
        };
        let nd = m.dim();
        let (mut new, mut old) = (Mat::<f64>::zeros(nd, nd), Mat::<f64>::zeros(nd, nd));
        m.jacobian(t, y, new.as_mut());
        let mut sc = m.scratch();
        assert!(m.evaluate(t, y, &mut sc, false));
        let mut fw = m.force_jac_work();
        m.forces().jacobian(m.bodies(), t, &sc, &mut fw);
        f.jacobian_every_body(&sc, Some(&fw.dg), old.as_mut());
        (new, old)
    }

    fn scene(path: &str) -> Scene {
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../..")
            .join(path);
        Scene::from_path(p).unwrap()
    }

    /// The branching tree of the reduced sums' test whose free body hangs from the second
    /// link's end through a dry clearance joint: bodies that each coordinate moves and bodies
    /// it does not, in every kind of link.
    fn tree_with_free_body_and_slider() -> Scene {
        let clearance = serde_json::json!({"type": "clearance", "name": "j",
             "bearing": {"body": "l2", "point": "E", "radius": 0.01},
             "journal": {"body": "f", "point": "O", "radius": 0.009},
             "normal": {"law": "impact", "k": 1e9, "c_max": 1e3, "d_max": 1e-4},
             "friction": {"law": "none"}});
        super::super::sparse_tests::branching_scene([2.5, 0.0], &[clearance])
    }

    /// The Jacobian that recomputes only the bodies each column moves (velocities only for a
    /// rate's column under loop closures, sums over the reached columns of R) gives the old
    /// one's numbers — equal as f64 in every entry of the angles' columns, and of every
    /// column with loop closures (== lets a zero differ in sign, the one difference
    /// reduced_product admits) — on the clearance presses, the free pendulum, the clearance
    /// four-bar, Andrews (loop closures) and a tree of every link kind, at states moved off
    /// the initial one so that every column and the contact are live. On a tree a rate's
    /// column is a closed form (`Minimal::rate_column`) and the old one a central difference
    /// of a quadratic, exact but for its rounding: equal to 1e-9 of the column's largest
    /// entry and |θ̈| (the rounding's scale, below; a wrong or missing term of the closed
    /// form is O(1) of an entry).
    #[test]
    fn recomputing_the_moved_bodies_only_keeps_the_numbers() {
        let mut scenes: Vec<(String, Scene)> = [
            "cases/press/lubricated_150rpm_c0.1.json",
            "cases/press/dry_150rpm_c0.1.json",
            "cases/examples/pendulum.json",
            "cases/examples/fourbar_clearance.json",
            "cases/andrews/andrews.json",
        ]
        .iter()
        .map(|p| (p.to_string(), scene(p)))
        .collect();
        scenes.push(("tree".into(), tree_with_free_body_and_slider()));
        // Rates of about 3e-4 and of about 1 rad/s (m/s): a_c is quadratic in them, the
        // rates' closed-form columns linear.
        for ((what, mut s), rates) in scenes
            .into_iter()
            .flat_map(|w| [(w.clone(), 30.0), (w, 1e5)])
        {
            s.formulation = crate::FormulationName::Minimal;
            let m = Mechanism::from_scene(&s).unwrap();
            let mut y = m.initial_state();
            let nd = y.len();
            for (i, v) in y.iter_mut().enumerate() {
                *v += 1e-5 * (1.0 + i as f64) * if i < nd / 2 { 1.0 } else { rates };
            }
            if what == "tree" {
                // The free body (θ 4..7, after the four links' coordinates) 2e-5 m into the
                // bearing's wall (radial clearance 1e-3 m): the contact force is live.
                y[4] += 1.02e-3;
            }
            let t = m.t_start() + 1e-3;
            let (new, old) = both(&m, t, &y);
            let Formulation::Minimal(f) = m.formulation() else {
                panic!("minimal")
            };
            let tree = f.closes_no_loop();
            // The size of θ̈ (1/s²), that of the terms of ρ after the solve: the differences'
            // rounding is ε |ρ| / (2h) ≈ 2e-11 of it (grown by the sums and the solve with
            // Rᵀ M R; measured at most 2e-12 of the column's largest entry and |θ̈| here).
            let mut dy = vec![0.0; nd];
            m.rhs(t, &y, &mut dy);
            let acc = dy[nd / 2..].iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let mut live = 0;
            let mut worst = 0.0f64;
            for c in 0..nd {
                let scale = (nd / 2..nd).map(|r| old[(r, c)].abs()).fold(0.0, f64::max);
                for r in 0..nd {
                    if c >= nd / 2 && tree {
                        // A rate's column in closed form (a tree): the difference's rounding.
                        let err = (new[(r, c)] - old[(r, c)]).abs();
                        worst = worst.max(err / (scale + acc));
                        assert!(
                            err <= 1e-9 * (scale + acc),
                            "{what}: ({r}, {c}) {:e} against {:e}",
                            new[(r, c)],
                            old[(r, c)]
                        );
                        live += usize::from(r >= nd / 2 && new[(r, c)] != 0.0);
                        continue;
                    }
                    assert!(
                        new[(r, c)] == old[(r, c)],
                        "{what}: ({r}, {c}) {:e} against {:e}",
                        new[(r, c)],
                        old[(r, c)]
                    );
                    live += usize::from(r >= nd / 2 && new[(r, c)] != 0.0);
                }
            }
            // The free pendulum's journal flies: only the pinned link's gravity torque in its
            // angle (its ω² A s is radial, orthogonal to its column of R: the rate's column
            // is 0, which the differences gave as a rounding of 1e-10).
            let want = match what.as_str() {
                "tree" => nd * nd / 4,
                "cases/examples/pendulum.json" => 1,
                _ => 2,
            };
            eprintln!(
                "{what} (rates × {rates}): {live} nonzero entries of {} in the lower rows, rate \
                 columns within {worst:e} of the differences",
                nd * nd / 2
            );
            assert!(
                live >= want,
                "{what}: {live} nonzero entries in the lower rows"
            );
        }
    }
}
