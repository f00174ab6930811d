//! The Jacobian ∂f/∂y of the Lagrange–Baumgarte formulation (docs/model.md §1.7), given the
//! applied forces' ∂g/∂(q, q̇) (the clearance joints and force elements give it).
//!
//! ```text
//! f = (q̇, q̈(t, q, q̇)),   ∂f/∂y = [ 0        I       ]
//!                                 [ ∂q̈/∂q   ∂q̈/∂q̇  ]
//! q̈ = K(t, q, q̇; g),  g = g(q, q̇) the applied forces,
//!   K the KKT solution, linear in g:  ∂K/∂g = A = M⁻¹ − M⁻¹Φ_qᵀ S⁻¹ Φ_q M⁻¹
//! ∂q̈/∂y = ∂K/∂y |_{g fixed} + A ∂g/∂y
//!   ∂K/∂q  |_g : closed form (the derivatives of Φ_q, γ and Φ̇ in the angles; see
//!                `constraint_position_jacobian`)
//!   ∂K/∂q̇  |_g = M⁻¹Φ_qᵀ S⁻¹ ∂r/∂q̇,  r = γ − 2αΦ̇ − β²Φ,
//!                ∂r/∂q̇ = ∂γ/∂q̇ − 2α Φ_q   (closed form; γ ∋ ω² (w·A s))
//! ```
//! docs/model.md §1 (1.7) allows finite differences for the constraint part; the closed forms
//! are exact, and cost no KKT solve beyond one back substitution per column.
//!
//! Φ_q is sparse (a row acts on at most two bodies) and so are ∂r/∂q̇, ∂g/∂y (a force couples
//! few bodies) and the right-hand sides of ∂λ: every product with them runs over the rows
//! that act on the bodies involved (`rows_of_body`), in increasing order, so that the
//! Jacobian costs O(n²) (its size; P and the result are dense) instead of O(n² m), with the
//! numbers of the dense products (only products with an exact zero are skipped; a column of
//! ∂g/∂y that is not finite takes the dense products, which spread its NaN as before).

use faer::MatMut;

use crate::linalg::{first_order_jacobian_frame, zeroed};
use crate::mechanism::constraints::{Constraints, TermKind};
use crate::mechanism::formulation::lagrange_baumgarte::{JacWork, LagrangeBaumgarte, Work};
use crate::mechanism::scratch::Scratch;
use crate::planar::{perp, rot};

impl LagrangeBaumgarte {
    /// The lower blocks of ∂f/∂y (y = (q, q̇), f = (q̇, q̈)) into `jac` (n × n, its upper
    /// blocks [0 I] set too), after an evaluation at (t, y) (the kinematics and q̈ in `sc`, λ
    /// and the factor of S in the work), given `dg` = ∂g/∂(q, q̇) of the applied forces
    /// (n_q × n, column-major); `dg` = None: the evaluation failed, the lower rows are NaN.
    ///
    /// ```text
    /// q̈ = K(t, q, q̇; g),  K linear in g:  ∂K/∂g = A = M⁻¹ − M⁻¹Φ_qᵀ S⁻¹ Φ_q M⁻¹
    /// ∂q̈/∂y = ∂K/∂y |_{g fixed} + A ∂g/∂y
    ///   ∂K/∂q  |_g : closed form (`constraint_position_jacobian`)
    ///   ∂K/∂q̇  |_g = M⁻¹Φ_qᵀ S⁻¹ ∂r/∂q̇,  r = γ − 2αΦ̇ − β²Φ,
    ///                ∂r/∂q̇ = ∂γ/∂q̇ − 2α Φ_q   (closed form; γ ∋ ω² (w·A s))
    /// ```
    pub(crate) fn jacobian(
        &self,
        cons: &Constraints,
        sc: &Scratch,
        dg: Option<&[f64]>,
        mut jac: MatMut<'_, f64>,
    ) {
        let nq = self.nq;
        let n = 2 * nq;
        let m = cons.len();
        first_order_jacobian_frame(&mut jac, nq, dg.is_some());
        let Some(dg) = dg else {
            return;
        };
        let mut w0 = self.work.borrow_mut();
        self.dense_constraint_jacobian(cons, &mut w0);
        let mut work = self.jac_work.borrow_mut();
        let JacWork {
            pmat,
            sinv,
            drdv,
            low,
            w,
            w2,
        } = &mut *work;
        // P = M⁻¹ Φ_qᵀ S⁻¹ (nq × m, column-major), from m solves with the factor of S: every later
        // product with S⁻¹ is a product with P.
        let pmat = zeroed(pmat, nq * m);
        self.kkt_projector(m, &w0, zeroed(sinv, m * m), pmat);
        // The lower blocks (nq × n, column-major) are built in `low`, then copied into `jac`.
        let low = zeroed(low, nq * n);
        // A ∂g/∂y with A = M⁻¹ − P Φ_q M⁻¹, column by column: w = Φ_q M⁻¹ ∂g/∂y_j, then
        // M⁻¹ ∂g/∂y_j − P w. (Forming A first is 15 % faster but rounds differently; on the 1 µm
        // film, where ∂g/∂y reaches 1e18 near the centred start, that was enough to change BDF's
        // path from 76 000 steps to more than 300 000 over the first 20 µs.)
        let w = zeroed(w, m);
        let mut rows: Vec<usize> = Vec::new();
        for j in 0..n {
            let dgj = &dg[j * nq..(j + 1) * nq];
            if dgj.iter().all(|&v| v == 0.0) {
                continue;
            }
            let lj = &mut low[j * nq..(j + 1) * nq];
            if dgj.iter().all(|v| v.is_finite()) {
                // w is nonzero only on the rows acting on the bodies ∂g/∂y_j moves.
                rows.clear();
                for (b, rb) in self.rows_of_body.iter().enumerate() {
                    if dgj[3 * b..3 * b + 3].iter().any(|&v| v != 0.0) {
                        rows.extend_from_slice(rb);
                    }
                }
                rows.sort_unstable();
                rows.dedup();
                for &a in &rows {
                    let mut s = 0.0;
                    for c in self.row_columns(cons, a) {
                        s += w0.jac[a * nq + c] * self.minv[c] * dgj[c];
                    }
                    w[a] = s;
                }
                for (i, x) in lj.iter_mut().enumerate() {
                    *x = self.minv[i] * dgj[i];
                }
                for &a in &rows {
                    let (wa, pa) = (w[a], &pmat[a * nq..(a + 1) * nq]);
                    for (x, p) in lj.iter_mut().zip(pa) {
                        *x -= p * wa;
                    }
                }
                continue;
            }
            for (a, wa) in w.iter_mut().enumerate() {
                let ja = &w0.jac[a * nq..(a + 1) * nq];
                let mut s = 0.0;
                for ((x, mi), v) in ja.iter().zip(&self.minv[..nq]).zip(dgj) {
                    s += x * mi * v;
                }
                *wa = s;
            }
            for (i, x) in lj.iter_mut().enumerate() {
                let mut s = self.minv[i] * dgj[i];
                for (a, wa) in w.iter().enumerate() {
                    s -= pmat[a * nq + i] * wa;
                }
                *x = s;
            }
        }
        // ∂K/∂q̇ at fixed g: P ∂r/∂q̇, column by column.
        let drdv = zeroed(drdv, m * nq);
        self.constraint_rhs_velocity_jacobian(cons, sc, drdv);
        let acc = zeroed(w2, nq);
        for j in 0..nq {
            // ∂r/∂q̇_j is nonzero only on the rows acting on body j/3.
            acc.fill(0.0);
            for &a in &self.rows_of_body[j / 3] {
                let (d, pa) = (drdv[a * nq + j], &pmat[a * nq..(a + 1) * nq]);
                for (s, p) in acc.iter_mut().zip(pa) {
                    *s += p * d;
                }
            }
            let lj = &mut low[(nq + j) * nq..(nq + j + 1) * nq];
            for (x, s) in lj.iter_mut().zip(acc.iter()) {
                *x += s;
            }
        }
        // ∂K/∂q at fixed g, in closed form (module doc).
        self.constraint_position_jacobian(cons, sc, &w0, pmat, w, zeroed(w2, m), low);
        for j in 0..n {
            let src = &low[j * nq..(j + 1) * nq];
            let col = jac.as_mut().col_mut(j).subrows_mut(nq, nq);
            match col.try_as_col_major_mut() {
                Some(c) => c.as_slice_mut().copy_from_slice(src),
                None => {
                    let mut c = jac.as_mut().col_mut(j);
                    for i in 0..nq {
                        c[nq + i] = src[i];
                    }
                }
            }
        }
    }

    /// P = M⁻¹ Φ_qᵀ S⁻¹ (nq × m, column-major) after an evaluation (Φ_q in `w0.jac`, the factor of
    /// S in `w0.smat`): S⁻¹ column by column from the factor, then the product.
    /// `sinv` (m × m) is scratch; `p` receives P.
    fn kkt_projector(&self, m: usize, w0: &Work, sinv: &mut [f64], p: &mut [f64]) {
        let nq = self.nq;
        for a in 0..m {
            // S⁻¹ is symmetric: row a = column a, the solve of S x = e_a in place.
            let e = &mut sinv[a * m..(a + 1) * m];
            e[a] = 1.0;
            self.env.solve(&w0.smat, e);
        }
        // Column i of Φ_q is nonzero only on the rows acting on body i/3.
        for i in 0..nq {
            let rows = &self.rows_of_body[i / 3];
            for a in 0..m {
                let mut s = 0.0;
                for &b in rows {
                    s += w0.jac[b * nq + i] * sinv[b * m + a];
                }
                p[a * nq + i] = self.minv[i] * s;
            }
        }
    }

    /// The columns of row `a` of Φ_q on integrated bodies, increasing (three per body).
    fn row_columns(&self, cons: &Constraints, a: usize) -> impl Iterator<Item = usize> {
        let mut b = cons.row_int[a];
        if let [Some(x), Some(y)] = b {
            if x == y {
                b[1] = None;
            } else if y < x {
                b = [Some(y), Some(x)];
            }
        }
        b.into_iter().flatten().flat_map(|i| 3 * i..3 * i + 3)
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
    /// `dphiq` and `rhs` (length m) are scratch.
    #[allow(clippy::too_many_arguments)]
    fn constraint_position_jacobian(
        &self,
        cons: &Constraints,
        sc: &Scratch,
        w0: &Work,
        pmat: &[f64],
        dphiq: &mut [f64],
        rhs: &mut [f64],
        low: &mut [f64],
    ) {
        let nq = self.nq;
        let m = cons.len();
        if m == 0 {
            return;
        }
        let (a2, b2) = (2.0 * self.alpha, self.beta * self.beta);
        let mut v = vec![0.0; nq];
        // dphiq: ∂Φ_q[:, j]/∂q_j (the only nonzero column). Both it and ∂r/∂q_j are nonzero
        // only on the rows acting on body j/3.
        for j in 0..nq {
            let (body_i, comp) = (j / 3, j % 3);
            let rows = &self.rows_of_body[body_i];
            for &a in rows {
                dphiq[a] = 0.0;
            }
            // ∂r/∂q_j, with the sign of −∂r in `rhs`.
            for &a in rows {
                rhs[a] = b2 * w0.jac[a * nq + j];
            }
            if comp == 2 {
                cons.for_point_terms_in(rows.iter().copied(), sc, body_i, |a, wa, wb, om| {
                    dphiq[a] -= wa;
                    // −∂γ/∂φ + 2α ∂Φ̇/∂φ = −φ̇² (w · b) − 2α (w · A s) φ̇.
                    rhs[a] -= om * om * wb + a2 * wa * om;
                });
            }
            // u = (∂Φ_q/∂q_j)ᵀ λ has the single entry u_j.
            let u: f64 = rows.iter().map(|&a| dphiq[a] * w0.lam[a]).sum();
            let mj = self.minv[j];
            for &a in rows {
                rhs[a] += dphiq[a] * sc.qdd[j] - w0.jac[a * nq + j] * mj * u;
            }
            // ∂q̈/∂q_j = −M⁻¹ u e_j − P (S ∂λ).
            v.fill(0.0);
            v[j] = self.minv[j] * u;
            for &a in rows {
                let (ra, pa) = (rhs[a], &pmat[a * nq..(a + 1) * nq]);
                for (x, p) in v.iter_mut().zip(pa) {
                    *x += p * ra;
                }
            }
            let lj = &mut low[j * nq..(j + 1) * nq];
            for (x, vi) in lj.iter_mut().zip(&v) {
                *x -= vi;
            }
        }
    }

    /// ∂r/∂q̇ (m × nq, row-major, into the zeroed `out`) of the constraint right-hand side
    /// r = γ − 2αΦ̇ − β²Φ.
    fn constraint_rhs_velocity_jacobian(&self, cons: &Constraints, sc: &Scratch, out: &mut [f64]) {
        let nq = self.nq;
        let a2 = 2.0 * self.alpha;
        for (r, (row, ints)) in cons.rows.iter().zip(&cons.row_int).enumerate() {
            for (ti, term) in row.terms[..row.n_terms].iter().enumerate() {
                let Some(i) = ints[ti] else {
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
    }
}
