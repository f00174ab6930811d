//! The mechanism: a validated scene turned into the index-1 ODE of docs/model.md §1.
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
//! A body whose motion is prescribed (a rotational driver plus a revolute joint to the ground
//! or to another prescribed body: the press's crank) is not integrated; its pose, velocity and
//! acceleration are closed-form functions of t, and the joints to it are rheonomic constraints
//! on the other body. The clearance joints add forces to g (docs/model.md §2–§4), and so do the
//! force elements and prismatic clearance joints (§10–§11); absent features (gravity, friction,
//! film, force elements) run no code.
//!
//! Sources: docs/model.md §1 (Nikravesh, Computer-Aided Analysis of Mechanical Systems, 1988;
//! Baumgarte 1972), Peng et al. 2025 §3.

mod bodies;
mod build;
pub(crate) mod constraints;
pub(crate) mod events;
mod ode;

use std::cell::RefCell;

use crate::clearance::geometry::{ClearanceInput, ClearanceState};
use crate::clearance::prismatic::{Prismatic, PrismaticEval};
use crate::clearance::revolute::{Clr, ClrEval, End};
use crate::elements::{Element, ElementEval};
use crate::linalg::{block_cholesky_inv, block_cholesky_solve};
use crate::mechanism::constraints::{Row, RowEval, TermKind};
use crate::mechanism::events::EventKind;
use crate::outputs::Roles;
use crate::planar::{cross, dot, perp, rot};
use crate::scene::{JointSpec, Scene};

pub(crate) use crate::mechanism::bodies::{BodyInfo, Owner, Prescription};

/// One block product of the Schur complement S = Φ_q M⁻¹ Φ_qᵀ: term `ta` of row `a` and term
/// `tb` of row `b` (a ≥ b) act on the same integrated body `i`, and add
/// J_{a,ta} M_i⁻¹ J_{b,tb}ᵀ (3-vectors, M_i⁻¹ = diag(1/m, 1/m, 1/I)) to S_ab. Built once per
/// scene: the rows of bodies that share no term give S_ab = 0 and cost nothing.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SchurTerm {
    pub a: usize,
    pub b: usize,
    pub ta: usize,
    pub tb: usize,
    pub i: usize,
}

/// Buffers of one evaluation (no allocation in `rhs`).
#[derive(Clone, Debug)]
pub(crate) struct Scratch {
    pub pose: Vec<[f64; 3]>,
    pub vel: Vec<[f64; 3]>,
    pub acc: Vec<[f64; 3]>,
    pub cs: Vec<[f64; 2]>,
    /// Applied generalized forces on integrated coordinates.
    pub g: Vec<f64>,
    /// Applied forces on every body (filled in full evaluations, for Newton–Euler and outputs).
    pub gb: Vec<[f64; 3]>,
    pub jac: Vec<f64>,
    pub phi: Vec<f64>,
    pub phid: Vec<f64>,
    pub rc: Vec<f64>,
    pub smat: Vec<f64>,
    pub lam: Vec<f64>,
    pub qdd: Vec<f64>,
    pub clr: Vec<ClrEval>,
    /// Every force element (docs/model.md §10).
    pub el: Vec<ElementEval>,
    /// Every prismatic clearance joint (docs/model.md §11).
    pub pr: Vec<PrismaticEval>,
    /// Jacobian blocks of every row with respect to each of its terms' bodies (full mode).
    pub term_jac: Vec<[[f64; 3]; 2]>,
}

/// A planar mechanism as an ODE: build it with [`Mechanism::from_scene`], integrate it with
/// `lash_solver::solve` from [`Mechanism::initial_state`], read it with
/// [`Mechanism::outputs`].
///
/// ```text
/// y' = f(t, y),  y = (q, q̇)  (docs/model.md §1);  events δ_k(q), ε_k − ε_cap and the
/// corner gaps δ_i of the prismatic clearance joints (§7, §11)
/// ```
#[derive(Debug)]
pub struct Mechanism {
    pub(crate) scene: Scene,
    pub(crate) bodies: Vec<BodyInfo>,
    /// Scene index of integrated body i.
    pub(crate) int_bodies: Vec<usize>,
    pub(crate) pres: Vec<Prescription>,
    pub(crate) rows: Vec<Row>,
    /// Integrated body index of each term of each row (None: a prescribed body).
    pub(crate) row_int: Vec<[Option<usize>; 2]>,
    /// The nonzero block products of S (fixed structure, built once).
    pub(crate) schur: Vec<SchurTerm>,
    /// The rows of each diagonal block of S (rows that share no body, directly or through
    /// other rows, are in different blocks), each in increasing order.
    pub(crate) kkt_blocks: Vec<Vec<usize>>,
    pub(crate) clr: Vec<Clr>,
    pub(crate) elements: Vec<Element>,
    pub(crate) prismatic: Vec<Prismatic>,
    pub(crate) projection: crate::assembly::ProjectionReport,
    pub(crate) events: Vec<EventKind>,
    pub(crate) minv: Vec<f64>,
    pub(crate) gravity: Option<[f64; 2]>,
    pub(crate) alpha: f64,
    pub(crate) beta: f64,
    pub(crate) t_start: f64,
    pub(crate) t_end: f64,
    pub(crate) y0: Vec<f64>,
    pub(crate) roles: Roles,
    pub(crate) scratch: RefCell<Scratch>,
    pub(crate) jac_work: RefCell<crate::jacobian::JacWork>,
}
impl Mechanism {
    /// What the projection onto the constraints changed in the scene's initial guesses
    /// (docs/model.md §1, "Initial conditions").
    pub fn projection_report(&self) -> &crate::assembly::ProjectionReport {
        &self.projection
    }

    /// Names of the force elements, in the order of [`crate::Outputs::elements`].
    pub fn element_names(&self) -> Vec<&str> {
        self.elements.iter().map(|e| e.name.as_str()).collect()
    }

    /// Names of the prismatic clearance joints, in the order of [`crate::Outputs::prismatic`].
    pub fn prismatic_names(&self) -> Vec<&str> {
        self.prismatic.iter().map(|p| p.name.as_str()).collect()
    }

    /// y0 after assembly: (q, q̇) of the integrated bodies.
    pub fn initial_state(&self) -> Vec<f64> {
        self.y0.clone()
    }

    /// Start time (s).
    pub fn t_start(&self) -> f64 {
        self.t_start
    }

    /// End time (s): `t_end`, or t_start + revolutions · 2π/|ω| of the crank driver.
    pub fn t_end(&self) -> f64 {
        self.t_end
    }

    /// The scene this mechanism was built from.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Resolved roles.
    pub fn roles(&self) -> &Roles {
        &self.roles
    }

    /// ω (rad/s) of the `crank_driver` role, if declared.
    pub fn crank_speed(&self) -> Option<f64> {
        let j = self.roles.crank_driver?;
        match &self.scene.joints[j] {
            JointSpec::Driver(d) => Some(d.omega_rad_s()),
            _ => None,
        }
    }

    /// Names of the integrated bodies, in the order of q.
    pub fn integrated_bodies(&self) -> Vec<&str> {
        self.int_bodies
            .iter()
            .map(|&k| self.bodies[k].name.as_str())
            .collect()
    }

    /// Names of the prescribed (not integrated) bodies.
    pub fn prescribed_bodies(&self) -> Vec<&str> {
        self.pres
            .iter()
            .map(|p| self.bodies[p.body].name.as_str())
            .collect()
    }

    /// Number of constraint equations in the KKT system.
    pub fn n_constraints(&self) -> usize {
        self.rows.len()
    }

    /// Names of the clearance joints, in the order of [`crate::Outputs::clearance`].
    pub fn clearance_names(&self) -> Vec<&str> {
        self.clr.iter().map(|c| c.name.as_str()).collect()
    }

    /// The stored impact velocity δ̇⁻ of every clearance joint (m/s; 0 before any onset).
    pub fn impact_velocities(&self) -> Vec<f64> {
        self.clr.iter().map(|c| c.impact_velocity.get()).collect()
    }

    /// Number of integrated coordinates (n_q = dim/2).
    pub(crate) fn nq(&self) -> usize {
        3 * self.int_bodies.len()
    }

    // -----------------------------------------------------------------------------------------
    // Evaluation core
    // -----------------------------------------------------------------------------------------

    /// Poses and velocities of every body at (t, y); accelerations of prescribed bodies.
    pub(crate) fn kinematics(&self, t: f64, y: &[f64], sc: &mut Scratch) {
        let nq = self.nq();
        for (i, &k) in self.int_bodies.iter().enumerate() {
            let q = &y[3 * i..3 * i + 3];
            let v = &y[nq + 3 * i..nq + 3 * i + 3];
            sc.pose[k] = [q[0], q[1], q[2]];
            sc.vel[k] = [v[0], v[1], v[2]];
            let (s, c) = q[2].sin_cos();
            sc.cs[k] = [c, s];
        }
        for p in &self.pres {
            let phi = p.theta0 + p.omega * t;
            let (s, c) = phi.sin_cos();
            let cs = [c, s];
            let as_ = rot(cs, p.s_own);
            let bs = perp(as_);
            let (pp, vp, ap) = match p.parent {
                None => (p.ground_at, [0.0; 2], [0.0; 2]),
                Some((kp, sp)) => {
                    let a = rot(sc.cs[kp], sp);
                    let b = perp(a);
                    let [x, y, _] = sc.pose[kp];
                    let [vx, vy, w] = sc.vel[kp];
                    let [ax, ay, al] = sc.acc[kp];
                    (
                        [x + a[0], y + a[1]],
                        [vx + w * b[0], vy + w * b[1]],
                        [ax + al * b[0] - w * w * a[0], ay + al * b[1] - w * w * a[1]],
                    )
                }
            };
            let w = p.omega;
            sc.cs[p.body] = cs;
            sc.pose[p.body] = [pp[0] - as_[0], pp[1] - as_[1], phi];
            sc.vel[p.body] = [vp[0] - w * bs[0], vp[1] - w * bs[1], w];
            sc.acc[p.body] = [ap[0] + w * w * as_[0], ap[1] + w * w * as_[1], 0.0];
        }
    }

    /// Global position and velocity of a clearance end, and the angular velocity of its body.
    #[inline]
    fn end_point(&self, e: &End, sc: &Scratch) -> ([f64; 2], [f64; 2], f64) {
        match e.body {
            None => (e.s, [0.0; 2], 0.0),
            Some(k) => {
                let a = rot(sc.cs[k], e.s);
                let [x, y, _] = sc.pose[k];
                let [vx, vy, w] = sc.vel[k];
                ([x + a[0], y + a[1]], [vx - w * a[1], vy + w * a[0]], w)
            }
        }
    }

    /// Clearance kinematics of joint k (after `kinematics`).
    #[inline]
    pub(crate) fn clearance_state(&self, k: usize, sc: &Scratch) -> ClearanceState {
        let c = &self.clr[k];
        let (r_b, v_b, w_b) = self.end_point(&c.bearing, sc);
        let (r_j, v_j, w_j) = self.end_point(&c.journal, sc);
        ClearanceState::compute(&ClearanceInput {
            r_j,
            r_b,
            v_j,
            v_b,
            phi_dot_j: w_j,
            phi_dot_b: w_b,
            radius_j: c.rj,
            radius_b: c.rb,
        })
    }

    /// Adds force f at global point (r_body + A s + arm_extra) to body k.
    #[inline]
    pub(crate) fn apply(&self, k: usize, arm: [f64; 2], f: [f64; 2], sc: &mut Scratch, full: bool) {
        let mz = cross(arm, f);
        match self.bodies[k].owner {
            Owner::Int(i) => {
                sc.g[3 * i] += f[0];
                sc.g[3 * i + 1] += f[1];
                sc.g[3 * i + 2] += mz;
            }
            Owner::Pres(_) => {}
        }
        if full {
            sc.gb[k][0] += f[0];
            sc.gb[k][1] += f[1];
            sc.gb[k][2] += mz;
        }
    }

    /// Applied forces: gravity and the clearance joints (docs/model.md §3–§4), then the force
    /// elements and prismatic clearance joints (§10–§11) when the scene has any.
    pub(crate) fn applied_forces(&self, t: f64, sc: &mut Scratch, full: bool) {
        sc.g.iter_mut().for_each(|v| *v = 0.0);
        if full {
            sc.gb.iter_mut().for_each(|v| *v = [0.0; 3]);
        }
        if let Some(gv) = self.gravity {
            for (i, &k) in self.int_bodies.iter().enumerate() {
                let m = self.bodies[k].mass;
                sc.g[3 * i] += m * gv[0];
                sc.g[3 * i + 1] += m * gv[1];
            }
            if full {
                for (k, b) in self.bodies.iter().enumerate() {
                    sc.gb[k][0] += b.mass * gv[0];
                    sc.gb[k][1] += b.mass * gv[1];
                }
            }
        }
        for k in 0..self.clr.len() {
            let st = self.clearance_state(k, sc);
            let c = &self.clr[k];
            let ev = self.clearance_forces(k, st);
            // Dry contact.
            if st.delta > 0.0 {
                let f_j = [
                    -ev.f_n * st.n[0] + ev.f_t * st.t[0],
                    -ev.f_n * st.n[1] + ev.f_t * st.t[1],
                ];
                if let Some(kj) = c.journal.body {
                    let a = rot(sc.cs[kj], c.journal.s);
                    let arm = [a[0] + c.rj * st.n[0], a[1] + c.rj * st.n[1]];
                    self.apply(kj, arm, f_j, sc, full);
                }
                if let Some(kb) = c.bearing.body {
                    let a = rot(sc.cs[kb], c.bearing.s);
                    let arm = [a[0] + c.rb * st.n[0], a[1] + c.rb * st.n[1]];
                    self.apply(kb, arm, [-f_j[0], -f_j[1]], sc, full);
                }
            }
            // Oil film.
            if c.film.is_some() {
                let (fr, ft) = (ev.f_r, ev.f_tf);
                let f_j = [fr * st.n[0] + ft * st.t[0], fr * st.n[1] + ft * st.t[1]];
                if let Some(kj) = c.journal.body {
                    let arm = rot(sc.cs[kj], c.journal.s);
                    self.apply(kj, arm, f_j, sc, full);
                }
                if let Some(kb) = c.bearing.body {
                    let arm = rot(sc.cs[kb], c.bearing.s);
                    self.apply(kb, arm, [-f_j[0], -f_j[1]], sc, full);
                }
            }
            sc.clr[k] = ev;
        }
        if !(self.elements.is_empty() && self.prismatic.is_empty()) {
            self.element_forces(t, sc, full);
        }
    }

    /// Adds a load (body, arm, force, torque) to the generalized forces.
    #[inline]
    fn apply_load(&self, l: crate::elements::Load, sc: &mut Scratch, full: bool) {
        let (k, arm, f, tau) = l;
        self.apply(k, arm, f, sc, full);
        if tau != 0.0 {
            match self.bodies[k].owner {
                Owner::Int(i) => sc.g[3 * i + 2] += tau,
                Owner::Pres(_) => {}
            }
            if full {
                sc.gb[k][2] += tau;
            }
        }
    }

    /// The force elements and prismatic clearance joints (docs/model.md §10–§11), after
    /// `kinematics`.
    pub(crate) fn element_forces(&self, t: f64, sc: &mut Scratch, full: bool) {
        let mut loads: [crate::elements::Load; 4] = [(0, [0.0; 2], [0.0; 2], 0.0); 4];
        for (i, e) in self.elements.iter().enumerate() {
            let mut n = 0;
            let ev = e.eval(t, &sc.pose, &sc.vel, &sc.cs, |l| {
                loads[n] = l;
                n += 1;
            });
            for l in &loads[..n] {
                self.apply_load(*l, sc, full);
            }
            sc.el[i] = ev;
        }
        for (i, p) in self.prismatic.iter().enumerate() {
            let mut n = 0;
            let ev = p.eval(&sc.pose, &sc.vel, &sc.cs, |l| {
                loads[n] = l;
                n += 1;
            });
            for l in &loads[..n] {
                self.apply_load(*l, sc, full);
            }
            sc.pr[i] = ev;
        }
    }

    /// The force laws of clearance joint k at the clearance state `st` (docs/model.md §3–§4):
    /// normal force, friction, elastic part (δ > 0 only) and film forces (when lubricated).
    #[inline]
    pub(crate) fn clearance_forces(&self, k: usize, st: ClearanceState) -> ClrEval {
        let c = &self.clr[k];
        let mut ev = ClrEval {
            st,
            ..ClrEval::default()
        };
        if st.delta > 0.0 {
            ev.f_n = c
                .normal
                .force(st.delta, st.delta_dot, c.impact_velocity.get());
            ev.elastic = c.normal.stiffness() * st.delta * st.delta.sqrt();
            if let Some(fr) = &c.friction {
                ev.f_t = fr.force(st.v_t, ev.f_n);
            }
        }
        if let Some(film) = &c.film {
            let (fr, ft) = film.force(st.eps, st.eps_dot, st.omega);
            ev.f_r = fr;
            ev.f_tf = ft;
        }
        ev
    }

    /// Value Φ, rate Φ̇, γ (Φ̈ = Φ_q q̈ − γ, prescribed accelerations folded in) and the
    /// Jacobian block of each term of one constraint row (after `kinematics`).
    #[inline]
    pub(crate) fn eval_row(&self, row: &Row, t: f64, sc: &Scratch) -> RowEval {
        let mut out = RowEval {
            phi: row.konst + row.rate * t,
            phid: row.rate,
            gamma: 0.0,
            jrows: [[0.0; 3]; 2],
        };
        for (ti, term) in row.terms[..row.n_terms].iter().enumerate() {
            let k = term.body;
            let [x, y, _] = sc.pose[k];
            let [vx, vy, w] = sc.vel[k];
            let owner = self.bodies[k].owner;
            out.jrows[ti] = match term.kind {
                TermKind::Point { s, w: wv } => {
                    let a = rot(sc.cs[k], s);
                    let b = perp(a);
                    out.phi += wv[0] * (x + a[0]) + wv[1] * (y + a[1]);
                    let jphi = dot(wv, b);
                    out.phid += wv[0] * vx + wv[1] * vy + jphi * w;
                    match owner {
                        Owner::Int(_) => out.gamma += w * w * dot(wv, a),
                        Owner::Pres(_) => {
                            let [ax, ay, al] = sc.acc[k];
                            out.gamma -= wv[0] * (ax + al * b[0] - w * w * a[0])
                                + wv[1] * (ay + al * b[1] - w * w * a[1]);
                        }
                    }
                    [wv[0], wv[1], jphi]
                }
                TermKind::Angle { c } => {
                    out.phi += c * sc.pose[k][2];
                    out.phid += c * w;
                    if let Owner::Pres(_) = owner {
                        out.gamma -= c * sc.acc[k][2];
                    }
                    [0.0, 0.0, c]
                }
            };
        }
        out
    }

    /// Constraint values, Φ̇, the Baumgarte right-hand side and the Jacobian blocks of every
    /// term (for the Schur complement and, in full mode, the reactions on any body); in full
    /// mode also the dense Φ_q of the integrated columns (`sc.jac`).
    pub(crate) fn constraint_rows(&self, t: f64, sc: &mut Scratch, full: bool) {
        let (a2, b2) = (2.0 * self.alpha, self.beta * self.beta);
        for (r, row) in self.rows.iter().enumerate() {
            let ev = self.eval_row(row, t, sc);
            sc.term_jac[r] = ev.jrows;
            sc.phi[r] = ev.phi;
            sc.phid[r] = ev.phid;
            sc.rc[r] = ev.gamma - a2 * ev.phid - b2 * ev.phi;
        }
        if full {
            self.dense_constraint_jacobian(sc);
        }
    }

    /// Φ_q (m × n_q, row-major) into `sc.jac` from the term blocks (after `constraint_rows`).
    pub(crate) fn dense_constraint_jacobian(&self, sc: &mut Scratch) {
        let nq = self.nq();
        sc.jac.iter_mut().for_each(|v| *v = 0.0);
        for (r, (row, jr)) in self.row_int.iter().zip(&sc.term_jac).enumerate() {
            for (ti, bi) in row.iter().enumerate() {
                if let Some(i) = *bi {
                    let base = r * nq + 3 * i;
                    sc.jac[base] += jr[ti][0];
                    sc.jac[base + 1] += jr[ti][1];
                    sc.jac[base + 2] += jr[ti][2];
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
    pub(crate) fn solve_kkt(&self, sc: &mut Scratch) -> bool {
        let nq = self.nq();
        let m = self.rows.len();
        let Scratch {
            term_jac,
            smat,
            lam,
            qdd,
            g,
            rc,
            ..
        } = sc;
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
        let smat = &mut smat[..m * m];
        for (a, (row, jr)) in self.row_int.iter().zip(term_jac).enumerate() {
            let mut ba = -rc[a];
            for (ti, bi) in row.iter().enumerate() {
                if let Some(i) = *bi {
                    let x = &qdd[3 * i..3 * i + 3];
                    let j = &jr[ti];
                    ba += j[0] * x[0] + j[1] * x[1] + j[2] * x[2];
                }
            }
            lam[a] = ba;
            smat[a * m..a * m + a + 1].fill(0.0);
        }
        for p in &self.schur {
            let (ja, jb) = (&term_jac[p.a][p.ta], &term_jac[p.b][p.tb]);
            let w = &minv[3 * p.i..3 * p.i + 3];
            smat[p.a * m + p.b] +=
                ja[0] * w[0] * jb[0] + ja[1] * w[1] * jb[1] + ja[2] * w[2] * jb[2];
        }
        // S is block diagonal (up to the order of the rows): each block is factored and solved
        // on its own, so the square roots and divisions of different blocks do not wait for
        // each other. The factor, stored in place, is the dense factor of S.
        for blk in &self.kkt_blocks {
            if block_cholesky_inv(smat, m, blk).is_err() {
                return false;
            }
            block_cholesky_solve(smat, m, blk, lam);
        }
        // q̈ = M⁻¹ g − M⁻¹ Φ_qᵀ λ.
        for (a, (row, jr)) in self.row_int.iter().zip(term_jac).enumerate() {
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

    /// One full evaluation at (t, y) into the scratch; false if the KKT matrix is singular.
    /// After it, `acc` holds every body's acceleration.
    pub(crate) fn evaluate(&self, t: f64, y: &[f64], sc: &mut Scratch, full: bool) -> bool {
        self.kinematics(t, y, sc);
        self.applied_forces(t, sc, full);
        self.constraint_rows(t, sc, full);
        let ok = self.solve_kkt(sc);
        for (i, &k) in self.int_bodies.iter().enumerate() {
            sc.acc[k] = [sc.qdd[3 * i], sc.qdd[3 * i + 1], sc.qdd[3 * i + 2]];
        }
        ok
    }
}
