//! The minimal (joint-coordinate) formulation on a spanning tree of the ideal joints
//! (docs/model.md §12).
//!
//! ```text
//! y = (θ, θ̇), θ the coordinates of the tree's links (tree.rs): one angle per revolute link,
//!   one distance per translational link, (x, y, φ) per free body
//! q̇ = R(θ) θ̇ + b(t),   q̈ = R θ̈ + a_c(t, θ, θ̇)      (b, a_c: prescribed parents, Ṙθ̇)
//! (Rᵀ M R) θ̈ = Rᵀ (Q − M a_c)                         (the virtual work of the tree)
//! ```
//! Clearance joints and force elements are forces (Q), so the press, the pendulum and the
//! clearance four-bar are trees: their ideal joints are satisfied by construction (the
//! constraint violation is rounding), and the state holds the degrees of freedom only. The
//! joints that close a loop (and drivers of integrated bodies) are kept as constraints on the
//! reduced system, enforced by the augmented Lagrangian (loops.rs):
//! (M̄ + Φ_θᵀαΦ_θ) θ̈ = Q̄ − Φ_θᵀλ* + Φ_θᵀαc̄ with M̄ = RᵀMR, Q̄ = Rᵀ(Q − M a_c), Φ_θ = Φ_q R.
//!
//! The constraint forces (outputs: the driver torques of prescribed bodies) are the
//! multipliers of the ideal joints, Φ_qᵀ λ = Q − M q̈, solved by the normal equations in full
//! evaluations only (Φ_q has full row rank on a tree); with loops, the closing rows'
//! multipliers are the iteration's λ* and the tree's rows take Q − M q̈ − Φ_closingᵀλ*.
//!
//! R is stored dense (n_q × n); Rᵀ M R and Rᵀ (Q − M a_c) are summed only where R can be
//! nonzero (each body's rows in its own and its integrated ancestors' columns,
//! `Tree::columns_of`), and Rᵀ M R is factored densely: O(n³) per right-hand side, which is
//! why `auto` keeps large scenes on the augmented Lagrangian (docs/model.md §12). On a tree
//! of at most six coordinates the integrator's right-hand side takes small.rs instead: the
//! same sums and factorisation on the stack, θ̈ alone (no q̈), the same bits.

mod flat;
mod jacobian;
pub(crate) mod loops;
mod small;
pub(crate) mod tree;

use std::cell::RefCell;

use crate::linalg::{block_cholesky_inv, cholesky_solve};
use crate::mechanism::bodies::{Bodies, BodyInfo};
use crate::mechanism::constraints::{describe, eval_row, Constraints};
use crate::mechanism::scratch::Scratch;
use crate::scene::error::SceneError;
use crate::scene::format::{AugmentedLagrangianParams, Scene};

use self::flat::FlatPlan;
use self::loops::Loops;
use self::tree::{Link, Tree};

/// The buffers of one evaluation.
#[derive(Clone, Debug, Default)]
pub(crate) struct Work {
    /// (t, y) of the last kinematics.
    pub t: f64,
    pub y: Vec<f64>,
    /// R (n_q × n, column-major).
    pub r: Vec<f64>,
    /// a_c (n_q), then Q − M q̈.
    pub ac: Vec<f64>,
    /// Rᵀ M R, then its factor (n × n, row-major).
    pub mr: Vec<f64>,
    /// θ̈.
    pub thdd: Vec<f64>,
    /// 0..n (the blocks of the factorisation).
    pub all: Vec<usize>,
    /// Φ and the multipliers of every row (full evaluations).
    pub phi: Vec<f64>,
    pub lam: Vec<f64>,
    /// Jacobian blocks of every row (full evaluations).
    pub term_jac: Vec<[[f64; 3]; 2]>,
    /// Q − M a_c (n_q).
    pub f: Vec<f64>,
}

/// One body's part of an entry of Rᵀ M R or of Rᵀ (Q − M a_c): the offsets of the entry, of
/// the body's rows in the two columns of R, and of its rows in q (the sums' terms, in the
/// order one sum over all rows adds them: [`Minimal::reduced_mass`]).
#[derive(Clone, Copy, Debug)]
struct Term {
    entry: usize,
    ri: usize,
    rj: usize,
    q: usize,
}

/// The terms of Rᵀ M R (lower triangle, entry i n + j) and of Rᵀ (Q − M a_c) (entry j, `ri`
/// unused) of `tree`, body by body over [`Tree::columns_of`]: an entry's terms in the order of
/// the rows.
fn terms(tree: &Tree, nq: usize) -> (Vec<Term>, Vec<Term>) {
    let n = tree.n;
    let (mut mass, mut force) = (Vec::new(), Vec::new());
    for b in 0..nq / 3 {
        let q = 3 * b;
        let cols = tree.columns_of(b);
        for (ii, &i) in cols.iter().enumerate() {
            for &j in &cols[..=ii] {
                mass.push(Term {
                    entry: i * n + j,
                    ri: i * nq + q,
                    rj: j * nq + q,
                    q,
                });
            }
            force.push(Term {
                entry: i,
                ri: i * nq + q,
                rj: i * nq + q,
                q,
            });
        }
    }
    (mass, force)
}

/// The Jacobian's buffers (kept between calls: no allocation once sized).
#[derive(Clone, Debug, Default)]
pub(crate) struct JacWork {
    /// The kinematics at a perturbed state (the prescribed bodies' copied in).
    pub sc: Option<Scratch>,
    pub yp: Vec<f64>,
    pub rp: Vec<f64>,
    pub qddp: Vec<f64>,
    /// q̈ at the unperturbed state (the tree's recursion with the evaluation's θ̈).
    pub qdd0: Vec<f64>,
    pub rho: [Vec<f64>; 2],
    pub qd: [Vec<f64>; 2],
    pub dq: Vec<f64>,
    pub dgq: Vec<f64>,
    /// ∂a_c/∂θ̇_j of a rate's column (n_q, written in the moved bodies' rows).
    pub dac: Vec<f64>,
    pub col: Vec<f64>,
}

/// The formulation (module doc).
#[derive(Debug)]
pub(crate) struct Minimal {
    tree: Tree,
    nq: usize,
    /// m, m, I of every integrated body.
    mass: Vec<f64>,
    work: RefCell<Work>,
    jac_work: RefCell<JacWork>,
    /// The closing joints' constraints (None on a tree).
    loops: Option<Loops>,
    /// The terms of Rᵀ M R and of Rᵀ (Q − M a_c) (`terms`).
    mass_terms: Vec<Term>,
    force_terms: Vec<Term>,
    /// A flat tree's θ̈, planned coordinate by coordinate (flat.rs; empty if not flat, and
    /// then [`Minimal::small_flat`] is false).
    flat: FlatPlan,
}

impl Minimal {
    /// The tree of `scene`'s ideal joints, its closing joints kept as constraints (loops.rs).
    /// (Contradictory closures are refused at assembly, naming the joints.)
    pub(crate) fn new(
        scene: &Scene,
        cons: &Constraints,
        bodies: &Bodies,
    ) -> Result<Self, SceneError> {
        let tree = Tree::build(scene, bodies);
        Ok(Minimal::with_loops(
            tree,
            cons,
            bodies,
            &scene.augmented_lagrangian,
        ))
    }

    /// The formulation on `tree`, its closing joints (if any) kept as constraints enforced
    /// with the augmented Lagrangian's `params`.
    pub(crate) fn with_loops(
        tree: Tree,
        cons: &Constraints,
        bodies: &Bodies,
        params: &AugmentedLagrangianParams,
    ) -> Self {
        let loops = Loops::new(&tree.closing, cons, bodies, tree.n, params);
        Minimal {
            loops,
            ..Minimal::on_tree(tree, cons, bodies)
        }
    }

    /// The formulation on a tree without closing joints.
    pub(crate) fn on_tree(tree: Tree, cons: &Constraints, bodies: &Bodies) -> Self {
        let nq = bodies.nq();
        let n = tree.n;
        let m = cons.len();
        let mass: Vec<f64> = bodies.inverse_masses().iter().map(|v| 1.0 / v).collect();
        let (mass_terms, force_terms) = terms(&tree, nq);
        Minimal {
            mass_terms,
            force_terms,
            flat: FlatPlan::new(&tree, &mass),
            tree,
            nq,
            mass,
            work: RefCell::new(Work {
                t: 0.0,
                y: vec![0.0; 2 * n],
                r: vec![0.0; nq * n],
                ac: vec![0.0; nq],
                mr: vec![0.0; n * n],
                thdd: vec![0.0; n],
                all: (0..n).collect(),
                phi: vec![0.0; m],
                lam: vec![0.0; m],
                term_jac: vec![[[0.0; 3]; 2]; m],
                f: vec![0.0; nq],
            }),
            jac_work: RefCell::default(),
            loops: None,
        }
    }

    /// The spanning tree (its bodies' coordinates in θ).
    pub(crate) fn tree(&self) -> &Tree {
        &self.tree
    }

    /// Whether every ideal joint is a tree joint (no joint closes a loop): the positions then
    /// meet every constraint by construction.
    #[inline]
    pub(crate) fn closes_no_loop(&self) -> bool {
        self.tree.closing.is_empty()
    }

    /// The closing joints' constraints (None on a tree).
    pub(crate) fn loops(&self) -> Option<&Loops> {
        self.loops.as_ref()
    }

    /// Number of coordinates θ.
    pub(crate) fn n(&self) -> usize {
        self.tree.n
    }

    /// The scene body and name of coordinate `i` of θ (for messages).
    pub(crate) fn coordinate(&self, i: usize) -> (usize, &'static str) {
        let tb = self
            .tree
            .bodies
            .iter()
            .rev()
            .find(|b| b.col <= i)
            .expect("i < n");
        let name = match tb.link {
            Link::Free => ["x", "y", "φ"][i - tb.col],
            Link::Revolute { .. } => "φ",
            Link::Slider { .. } => "σ (along its translational joint)",
        };
        (tb.body, name)
    }

    /// The kinematics of every body at (t, y) into `sc`, and (t, y) kept for the Jacobian.
    #[inline]
    pub(crate) fn kinematics(&self, t: f64, y: &[f64], bodies: &Bodies, sc: &mut Scratch) {
        let n = self.tree.n;
        self.positions(t, y, bodies, sc);
        let mut w = self.work.borrow_mut();
        w.t = t;
        w.y.copy_from_slice(&y[..2 * n]);
    }

    /// The kinematics of every body at (t, y) into `sc` only (the event functions' need:
    /// the evaluation's buffers are left as they are).
    #[inline]
    pub(crate) fn positions(&self, t: f64, y: &[f64], bodies: &Bodies, sc: &mut Scratch) {
        let n = self.tree.n;
        bodies.prescribed_kinematics(t, sc);
        self.tree.positions(&y[..n], &y[n..2 * n], sc);
    }

    /// θ of an absolute (q, q̇).
    pub(crate) fn state_of(&self, y_abs: &[f64]) -> Vec<f64> {
        self.tree.state_of(y_abs)
    }

    /// R, a_c and Rᵀ M R (factored) at the kinematics of `sc`; Err(j): pivot j not positive.
    fn factor(&self, w: &mut Work, sc: &Scratch) -> Result<(), usize> {
        self.reduced_mass(w, sc);
        factor_unrolled(&mut w.mr, self.tree.n, &w.all)
    }

    /// R, a_c and Rᵀ M R (lower triangle, not factored) at the kinematics of `sc`.
    fn reduced_mass(&self, w: &mut Work, sc: &Scratch) {
        let (nq, n) = (self.nq, self.tree.n);
        self.tree
            .velocity_matrix_and_bias(sc, nq, &mut w.r, &mut w.ac);
        // (Rᵀ M R)_ij = Σ_rows R_ri m_r R_rj, body by body (rows ascending, as one sum over
        // the rows would add them), over the bodies where both columns can be nonzero
        // (Tree::columns_of: the skipped terms are +0 and change no bit).
        let (r, m, mr) = (&w.r[..nq * n], &self.mass[..nq], &mut w.mr[..n * n]);
        mr.fill(0.0);
        for t in &self.mass_terms {
            let (ri, rj, m) = (&r[t.ri..t.ri + 3], &r[t.rj..t.rj + 3], &m[t.q..t.q + 3]);
            let mut s = mr[t.entry];
            s += ri[0] * m[0] * rj[0];
            s += ri[1] * m[1] * rj[1];
            s += ri[2] * m[2] * rj[2];
            mr[t.entry] = s;
        }
    }

    /// θ̈ (kept) and q̈ = R θ̈ + a_c into `sc.qdd` from the applied forces `sc.g`; in full
    /// evaluations also Φ and the multipliers of every row. False if Rᵀ M R is not positive
    /// definite in f64 or θ̈ is not finite.
    #[inline]
    pub(crate) fn accelerations(
        &self,
        t: f64,
        cons: &Constraints,
        info: &[BodyInfo],
        sc: &mut Scratch,
        full: bool,
    ) -> bool {
        let (nq, n) = (self.nq, self.tree.n);
        let mut guard = self.work.borrow_mut();
        let w = &mut *guard;
        if self.loops.is_some() {
            self.reduced_mass(w, sc);
        } else if self.factor(w, sc).is_err() {
            return false;
        }
        // Rᵀ (Q − M a_c), body by body over the columns that can be nonzero in its rows (as
        // Rᵀ M R in reduced_mass: the same sums, bit for bit).
        {
            let (g, m, ac, f) = (&sc.g[..nq], &self.mass[..nq], &w.ac[..nq], &mut w.f[..nq]);
            for i in 0..nq {
                f[i] = g[i] - m[i] * ac[i];
            }
        }
        let (r, f, thdd) = (&w.r[..nq * n], &w.f[..nq], &mut w.thdd[..n]);
        thdd.fill(0.0);
        for t in &self.force_terms {
            let (rj, f) = (&r[t.rj..t.rj + 3], &f[t.q..t.q + 3]);
            let mut s = thdd[t.entry];
            s += rj[0] * f[0];
            s += rj[1] * f[1];
            s += rj[2] * f[2];
            thdd[t.entry] = s;
        }
        match &self.loops {
            None => solve_unrolled(&w.mr, n, &mut w.thdd),
            Some(l) => {
                if !l.solve(t, sc, &w.r, &w.ac, &w.mr, &mut w.thdd) {
                    return false;
                }
            }
        }
        add_columns(&w.r[..nq * n], &w.ac[..nq], &w.thdd[..n], &mut sc.qdd[..nq]);
        let ok = w.thdd.iter().all(|v| v.is_finite());
        if full {
            self.multipliers(w, t, cons, info, sc);
        }
        ok
    }

    /// Φ, the Jacobian blocks and the multipliers of every row: Φ_qᵀ λ = Q − M q̈ by the
    /// normal equations (Φ_q Φ_qᵀ) λ = Φ_q (Q − M q̈); NaN if they are singular.
    fn multipliers(
        &self,
        w: &mut Work,
        t: f64,
        cons: &Constraints,
        info: &[BodyInfo],
        sc: &Scratch,
    ) {
        let (nq, m) = (self.nq, cons.len());
        if m == 0 {
            return;
        }
        let mut jd = vec![0.0; m * nq];
        for (r, (row, ints)) in cons.rows.iter().zip(&cons.row_int).enumerate() {
            let ev = eval_row(row, info, t, sc);
            w.phi[r] = ev.phi;
            w.term_jac[r] = ev.jrows;
            for (ti, bi) in ints.iter().enumerate() {
                if let Some(i) = *bi {
                    for c in 0..3 {
                        jd[r * nq + 3 * i + c] += ev.jrows[ti][c];
                    }
                }
            }
        }
        let mut fc: Vec<f64> = (0..nq)
            .map(|i| sc.g[i] - self.mass[i] * sc.qdd[i])
            .collect();
        // With loops: the closing rows' multipliers are λ*, the tree's rows take the rest
        // (their rows of the normal equations decoupled from the closing rows').
        let mut closing = vec![false; m];
        if let Some(l) = &self.loops {
            let mut fl = vec![0.0; nq];
            l.closing_forces(&mut fl, &mut w.phi, &mut w.term_jac, &mut w.lam);
            for (f, v) in fc.iter_mut().zip(&fl) {
                *f -= v;
            }
            for &r in &l.index {
                closing[r] = true;
                jd[r * nq..(r + 1) * nq].fill(0.0);
            }
        }
        let lam_closing = w.lam.clone();
        let mut nm = vec![0.0; m * m];
        for a in 0..m {
            if closing[a] {
                nm[a * m + a] = 1.0;
                continue;
            }
            let ja = &jd[a * nq..(a + 1) * nq];
            w.lam[a] = ja.iter().zip(&fc).map(|(x, y)| x * y).sum();
            for b in 0..=a {
                let jb = &jd[b * nq..(b + 1) * nq];
                nm[a * m + b] = ja.iter().zip(jb).map(|(x, y)| x * y).sum();
            }
        }
        let all: Vec<usize> = (0..m).collect();
        if block_cholesky_inv(&mut nm, m, &all).is_ok() {
            cholesky_solve(&nm, m, &mut w.lam);
        } else {
            w.lam.iter_mut().for_each(|v| *v = f64::NAN);
        }
        for (a, l) in w.lam.iter_mut().enumerate() {
            if closing[a] {
                *l = lam_closing[a];
            }
        }
    }

    /// ẏ = (θ̇, θ̈) (NaN θ̈ when the solve failed).
    #[inline]
    pub(crate) fn derivative(&self, y: &[f64], ok: bool, dy: &mut [f64]) {
        let n = self.tree.n;
        dy[..n].copy_from_slice(&y[n..2 * n]);
        if ok {
            dy[n..2 * n].copy_from_slice(&self.work.borrow().thdd);
        } else {
            dy[n..2 * n].iter_mut().for_each(|v| *v = f64::NAN);
        }
    }

    /// The constraint forces −Σ J_r,kᵀ λ_r of the last full evaluation on every body, added
    /// to `cf`, and the torques −λ of the driver rows: (joint index, τ).
    pub(crate) fn reactions(
        &self,
        cons: &Constraints,
        cf: &mut [[f64; 3]],
        torques: &mut Vec<(usize, f64)>,
    ) {
        let w = self.work.borrow();
        cons.reactions(&w.term_jac, &w.lam, cf, torques);
    }

    /// ‖Φ(q, t)‖₂ of the last full evaluation (rounding on a tree).
    pub(crate) fn constraint_violation(&self) -> f64 {
        let w = self.work.borrow();
        // From +0: an empty sum (no constraint rows) is +0, not `Sum`'s −0 (printed "-0").
        w.phi.iter().fold(0.0, |a, v| a + v * v).sqrt()
    }

    /// The checks at the initial state (after the kinematics in `sc`): every constraint row
    /// finite (→ the joint), then Rᵀ M R positive definite in f64 (→ the body of the failing
    /// coordinate).
    pub(crate) fn check_equations(
        &self,
        t: f64,
        scene: &Scene,
        cons: &Constraints,
        info: &[BodyInfo],
        sc: &Scratch,
    ) -> Result<(), SceneError> {
        for row in &cons.rows {
            let ev = eval_row(row, info, t, sc);
            if !([ev.phi, ev.phid, ev.gamma].iter().all(|v| v.is_finite())
                && ev.jrows.iter().flatten().all(|v| v.is_finite()))
            {
                return Err(SceneError::Dynamics {
                    path: format!("joints[{}]", row.joint),
                    reason: format!(
                        "{}: Φ = {:e}, Φ̇ = {:e}, γ = {:e}: not finite",
                        describe(row, scene),
                        ev.phi,
                        ev.phid,
                        ev.gamma
                    ),
                });
            }
        }
        let mut w = self.work.borrow_mut();
        if let Err(j) = self.factor(&mut w, sc) {
            let (k, what) = self.coordinate(j);
            return Err(SceneError::Dynamics {
                path: format!("bodies[{k}]"),
                reason: format!(
                    "the reduced mass matrix Rᵀ M R of the minimal formulation is not positive \
                     definite in f64 at coordinate {what} of {}",
                    info[k].describe()
                ),
            });
        }
        Ok(())
    }
}

/// [`block_cholesky_inv`] of the whole n × n matrix (blocks `all` = 0..n), unrolled for
/// n ≤ 4: the same operations in the same order, so the same bits, without the index lists
/// and bounds checks of the general loops (a third of the reduced right-hand side of the
/// press, n = 2).
#[inline]
fn factor_unrolled(s: &mut [f64], n: usize, all: &[usize]) -> Result<(), usize> {
    match n {
        1 => factor_fixed::<1>(s),
        2 => factor_fixed::<2>(s),
        3 => factor_fixed::<3>(s),
        4 => factor_fixed::<4>(s),
        _ => block_cholesky_inv(s, n, all),
    }
}

/// [`block_cholesky_inv`] with m = N and every block in order.
#[inline(always)]
pub(super) fn factor_fixed<const N: usize>(s: &mut [f64]) -> Result<(), usize> {
    let s = &mut s[..N * N];
    for j in 0..N {
        let mut d = s[j * N + j];
        for k in 0..j {
            let v = s[j * N + k];
            d -= v * v;
        }
        if !(d > 0.0) {
            s[j * N + j] = d;
            return Err(j);
        }
        let r = 1.0 / d.sqrt();
        s[j * N + j] = r;
        for i in j + 1..N {
            let mut x = s[i * N + j];
            for k in 0..j {
                x -= s[i * N + k] * s[j * N + k];
            }
            s[i * N + j] = x * r;
        }
    }
    Ok(())
}

/// q̈ = a_c + Σ_j R_j θ̈_j (R: n_q × n column-major, n = `th.len()`), entry by entry with
/// the columns added in ascending order: the sums of adding R θ̈ to a_c column by column, bit
/// for bit; unrolled over the columns for n ≤ 4 (on the press, n = 2 and n_q = 6, the general
/// loops' iterator set-up cost more than their arithmetic).
#[inline]
fn add_columns(r: &[f64], ac: &[f64], th: &[f64], qdd: &mut [f64]) {
    match th.len() {
        1 => add_columns_fixed::<1>(r, ac, th, qdd),
        2 => add_columns_fixed::<2>(r, ac, th, qdd),
        3 => add_columns_fixed::<3>(r, ac, th, qdd),
        4 => add_columns_fixed::<4>(r, ac, th, qdd),
        _ => {
            let nq = qdd.len();
            qdd.copy_from_slice(ac);
            for (j, &a) in th.iter().enumerate() {
                for (q, r) in qdd.iter_mut().zip(&r[j * nq..(j + 1) * nq]) {
                    *q += r * a;
                }
            }
        }
    }
}

/// [`add_columns`] with n = N.
#[inline(always)]
fn add_columns_fixed<const N: usize>(r: &[f64], ac: &[f64], th: &[f64], qdd: &mut [f64]) {
    let nq = qdd.len();
    let (r, ac) = (&r[..N * nq], &ac[..nq]);
    let mut a = [0.0; N];
    a.copy_from_slice(&th[..N]);
    for q in 0..nq {
        let mut s = ac[q];
        for (j, a) in a.iter().enumerate() {
            s += r[j * nq + q] * a;
        }
        qdd[q] = s;
    }
}

/// [`cholesky_solve`] unrolled for n ≤ 4 (the same operations in the same order).
#[inline]
fn solve_unrolled(l: &[f64], n: usize, b: &mut [f64]) {
    match n {
        1 => solve_fixed::<1>(l, b),
        2 => solve_fixed::<2>(l, b),
        3 => solve_fixed::<3>(l, b),
        4 => solve_fixed::<4>(l, b),
        _ => cholesky_solve(l, n, b),
    }
}

/// [`cholesky_solve`] with m = N.
#[inline(always)]
pub(super) fn solve_fixed<const N: usize>(l: &[f64], b: &mut [f64]) {
    let l = &l[..N * N];
    let b = &mut b[..N];
    for i in 0..N {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i * N + k] * b[k];
        }
        b[i] = s * l[i * N + i];
    }
    for i in (0..N).rev() {
        let mut s = b[i];
        for k in i + 1..N {
            s -= l[k * N + i] * b[k];
        }
        b[i] = s * l[i * N + i];
    }
}

#[cfg(test)]
mod unrolled_tests {
    //! The unrolled factor and solve give the general ones' bits (n = 1…4 and a failing
    //! pivot), on symmetric positive definite matrices with entries of mixed magnitude.
    use super::*;

    fn spd(n: usize, seed: f64) -> Vec<f64> {
        // A Aᵀ + n I with A_ij = sin(seed (i + 1) (j + 2)) · 10^(i − j).
        let a: Vec<f64> = (0..n * n)
            .map(|k| {
                let (i, j) = (k / n, k % n);
                (seed * (i + 1) as f64 * (j + 2) as f64).sin() * 10f64.powi(i as i32 - j as i32)
            })
            .collect();
        let mut s = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                s[i * n + j] = (0..n).map(|k| a[i * n + k] * a[j * n + k]).sum::<f64>()
                    + if i == j { n as f64 } else { 0.0 };
            }
        }
        s
    }

    #[test]
    fn the_unrolled_cholesky_gives_the_general_bits() {
        for n in 1..=5 {
            for seed in [0.3, 1.7, 2.9] {
                let all: Vec<usize> = (0..n).collect();
                let (mut a, mut b) = (spd(n, seed), spd(n, seed));
                assert_eq!(block_cholesky_inv(&mut a, n, &all), Ok(()));
                assert_eq!(factor_unrolled(&mut b, n, &all), Ok(()));
                assert_eq!(bits(&a), bits(&b));
                let rhs: Vec<f64> = (0..n).map(|i| (i as f64 + seed).cos() * 1e3).collect();
                let (mut x, mut y) = (rhs.clone(), rhs);
                cholesky_solve(&a, n, &mut x);
                solve_unrolled(&b, n, &mut y);
                assert_eq!(bits(&x), bits(&y));
            }
            // Not positive definite: the same failing pivot, the same pivot left in place.
            let all: Vec<usize> = (0..n).collect();
            let mut a = spd(n, 0.3);
            a[(n - 1) * n + n - 1] = -1.0;
            let mut b = a.clone();
            let e = block_cholesky_inv(&mut a, n, &all);
            assert_eq!(e, Err(n - 1));
            assert_eq!(factor_unrolled(&mut b, n, &all), e);
            assert_eq!(bits(&a), bits(&b));
        }
    }

    #[test]
    fn the_unrolled_sum_of_columns_gives_the_bits_of_the_column_by_column_loop() {
        // n = 1…5 columns of n_q = 6 rows, entries of mixed magnitude and sign, with signed
        // zeros where a sum from a_c can keep or lose the sign of zero.
        let nq = 6;
        for n in 1..=5 {
            let r: Vec<f64> = (0..n * nq)
                .map(|k| match k % 7 {
                    0 => 0.0,
                    1 => -0.0,
                    _ => (k as f64 * 0.37).sin() * 10f64.powi(k as i32 % 5 - 2),
                })
                .collect();
            let ac: Vec<f64> = (0..nq)
                .map(|q| {
                    if q < 2 {
                        [-0.0, 0.0][q]
                    } else {
                        (q as f64).cos() * 1e-3
                    }
                })
                .collect();
            let th: Vec<f64> = (0..n).map(|j| (j as f64 + 0.5).tan() * 1e2).collect();
            let mut want = ac.clone();
            for (j, &a) in th.iter().enumerate() {
                for (q, r) in want.iter_mut().zip(&r[j * nq..(j + 1) * nq]) {
                    *q += r * a;
                }
            }
            let mut got = vec![f64::NAN; nq];
            add_columns(&r, &ac, &th, &mut got);
            assert_eq!(bits(&want), bits(&got), "n = {n}");
        }
        // A sum from a_c = −0 with a product +0 is +0, as in the loop: the sum starts from
        // a_c, not from +0.
        let mut got = [1.0];
        add_columns(&[0.0], &[-0.0], &[0.0], &mut got);
        assert_eq!(got[0].to_bits(), 0.0f64.to_bits());
        add_columns(&[0.0], &[-0.0], &[-0.0], &mut got);
        assert_eq!(got[0].to_bits(), (-0.0f64).to_bits());
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }
}

#[cfg(test)]
pub(super) mod sparse_tests {
    //! The reduced system summed body by body over `Tree::columns_of` gives the bits of the
    //! sums over every row of R (the formulas before the skip), on a tree with a chain, a branch
    //! from a slider and a free body, at states away from the assembled one.
    use super::*;
    use crate::mechanism::formulation::Formulation;
    use crate::Mechanism;
    use lash_solver::OdeSystem;

    /// Two links in a chain from the ground, a slider on an inclined line with a link pinned
    /// to it, and a free body `f` at `free_at`, with `joints` added (a clearance joint that
    /// holds `f`, for the Jacobian's test); gravity, under `minimal`: every kind of link, and
    /// bodies that each coordinate moves and bodies it does not.
    pub(super) fn branching_scene(free_at: [f64; 2], joints: &[serde_json::Value]) -> crate::Scene {
        let link = |name: &str, x: f64, y: f64, m: f64| {
            serde_json::json!({"name": name, "mass": m, "inertia": 0.1 * m,
                "points": {"O": [-0.5, 0.0], "E": [0.5, 0.0]},
                "position": [x, y], "angle": 0.0, "velocity": [0.0, 0.0],
                "angular_velocity": 0.0})
        };
        let mut all = vec![
            serde_json::json!({"type": "revolute", "name": "p1", "a": {"body": "l1", "point": "O"},
                 "b": {"body": "ground", "at": [0.0, 0.0]}}),
            serde_json::json!({"type": "revolute", "name": "p2", "a": {"body": "l1", "point": "E"},
                 "b": {"body": "l2", "point": "O"}}),
            serde_json::json!({"type": "translational", "name": "slide", "body": "s", "point": "O",
                 "origin": [-0.5, -1.0], "direction": [1.0, 0.3]}),
            serde_json::json!({"type": "revolute", "name": "p3", "a": {"body": "s", "point": "E"},
                 "b": {"body": "c", "point": "O"}}),
        ];
        all.extend_from_slice(joints);
        let scene = serde_json::json!({
            "bodies": [link("l1", 0.5, 0.0, 1.0), link("l2", 1.5, 0.0, 2.0),
                       link("s", 0.0, -1.0, 3.0), link("c", 0.5, -1.0, 0.5),
                       link("f", free_at[0], free_at[1], 1.5)],
            "joints": all,
            "gravity": [0.0, -9.81],
            "t_end": 1.0,
            "formulation": "minimal"
        });
        crate::Scene::from_json_str(&scene.to_string()).unwrap()
    }

    /// [`branching_scene`] with its free body at (3, 3), no clearance joint.
    fn branching() -> Mechanism {
        Mechanism::from_scene(&branching_scene([3.0, 3.0], &[])).unwrap()
    }

    #[test]
    fn r_and_a_c_in_one_pass_give_the_bits_of_the_two_passes() {
        // Every kind of link, states away from the assembled one (as below).
        let m = branching();
        let Formulation::Minimal(f) = m.formulation() else {
            panic!("minimal")
        };
        let (nq, n) = (f.nq, f.n());
        let y0 = m.initial_state();
        for k in 0..3 {
            let y: Vec<f64> = y0
                .iter()
                .enumerate()
                .map(|(i, v)| v + 0.4 * (k as f64 + 1.0) * ((i as f64) * 1.3 + 0.2).cos())
                .collect();
            let mut dy = vec![0.0; 2 * n];
            m.rhs(0.1 * k as f64, &y, &mut dy);
            let sc = m.scratch();
            let (mut r1, mut ac1) = (vec![f64::NAN; nq * n], vec![f64::NAN; nq]);
            let (mut r2, mut ac2) = (vec![f64::NAN; nq * n], vec![f64::NAN; nq]);
            f.tree.velocity_matrix(&sc, nq, &mut r1);
            f.tree.accelerations(&sc, None, &mut ac1);
            f.tree.velocity_matrix_and_bias(&sc, nq, &mut r2, &mut ac2);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&r1), bits(&r2));
            assert_eq!(bits(&ac1), bits(&ac2));
            // a_c is not zero on a moving tree (the check compares numbers, not zeros).
            assert!(ac2.iter().any(|v| v.abs() > 1e-3), "{ac2:?}");
        }
    }

    #[test]
    fn the_sums_over_the_reached_columns_give_the_bits_of_the_sums_over_every_row() {
        let m = branching();
        let Formulation::Minimal(f) = m.formulation() else {
            panic!("minimal")
        };
        let (nq, n) = (f.nq, f.n());
        // θ = (l1, l2, σ, c, x_f, y_f, φ_f): 7 coordinates of 5 bodies.
        assert_eq!((nq, n), (15, 7));
        let y0 = m.initial_state();
        let (mut zero, mut nonzero) = (0, 0);
        for k in 0..4 {
            // States away from the assembled one: every angle turned, every rate nonzero.
            let y: Vec<f64> = y0
                .iter()
                .enumerate()
                .map(|(i, v)| v + 0.3 * (k as f64 + 1.0) * ((i as f64) * 1.7 + 0.4).sin())
                .collect();
            let mut dy = vec![0.0; 2 * n];
            m.rhs(0.1 * k as f64, &y, &mut dy);
            let sc = m.scratch();
            let mut w = f.work.borrow_mut();
            // θ̈ by the sums over every row, factored and solved by the general loops.
            let rho: Vec<f64> = (0..n)
                .map(|j| {
                    let rj = &w.r[j * nq..(j + 1) * nq];
                    let mut s = 0.0;
                    for i in 0..nq {
                        s += rj[i] * (sc.g[i] - f.mass[i] * w.ac[i]);
                    }
                    s
                })
                .collect();
            f.reduced_mass(&mut w, &sc);
            let mut dense = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..=i {
                    let (ri, rj) = (&w.r[i * nq..(i + 1) * nq], &w.r[j * nq..(j + 1) * nq]);
                    let mut s = 0.0;
                    for ((a, b), mm) in ri.iter().zip(rj).zip(&f.mass) {
                        s += a * mm * b;
                    }
                    assert_eq!(s.to_bits(), w.mr[i * n + j].to_bits(), "({i}, {j})");
                    if s == 0.0 {
                        zero += 1;
                    } else {
                        nonzero += 1;
                    }
                    dense[i * n + j] = s;
                }
            }
            let all: Vec<usize> = (0..n).collect();
            assert_eq!(block_cholesky_inv(&mut dense, n, &all), Ok(()));
            let mut thdd = rho;
            cholesky_solve(&dense, n, &mut thdd);
            for (a, b) in thdd.iter().zip(&dy[n..]) {
                assert_eq!(a.to_bits(), b.to_bits());
            }
        }
        // The tree couples some columns (the chain, the branch on the slider) and not others
        // (chain × slider, anything × the free body): both kinds were compared.
        assert!(zero > 0 && nonzero > 0, "{zero} zero, {nonzero} nonzero");
    }
}
