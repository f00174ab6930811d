//! The mechanism's KKT form for the `kkt` linear algebra of diffsol's implicit methods
//! (lash_solver::kkt): K, b and the pattern of ∂ρ/∂y, under the absolute formulations.
//!
//! ```text
//! y = (q, q̇),  K = [[M, Φ_qᵀ], [Φ_q, 0]],  b = (g, c),   K (q̈, λ) = b
//! c = γ − p Φ̇ − s Φ    (Lagrange–Baumgarte: p = 2α, s = β²; augmented Lagrangian: 2ξω, ω²)
//! ρ(y; z) = b(t, y) − K(t, y) z
//! ```
//! The ODE this linearises is Lagrange–Baumgarte's exactly (its Schur-complement solve is
//! the same system) and the augmented Lagrangian's to its iteration's tolerance (its
//! multipliers converge to λ: mechanism/formulation/augmented_lagrangian). The minimal
//! formulation has no KKT form here (its mass matrix is dense over a tree).
//!
//! ∂ρ/∂y at fixed z = (q̈, λ) in closed form (`kkt_residual_jacobian`), the column of y_j:
//!
//! ```text
//! rows of g:  ∂g/∂y_j − (∂Φ_q/∂y_j)ᵀ λ      rows of c:  ∂c/∂y_j − (∂Φ_q/∂y_j) q̈
//! ```
//! the augmented Lagrangian's and Lagrange–Baumgarte's closed forms (formulation/
//! column_terms.rs, there with their own q̈ and λ) over the pattern's rows, with the forces'
//! closed-form ∂g/∂y (zero with gravity alone, which needs none). Where a force element or a
//! prismatic clearance joint has no closed form, the `kkt` path differences ρ over the
//! pattern's colours (lash_solver::kkt).
//!
//! ∂ρ/∂y's pattern ([`residual_pattern`]): the column of a coordinate of body j (q or q̇)
//! has the rows of g of every body that shares a force element with j or a constraint row
//! (Φ_qᵀλ), j's own, and the constraint rows that act on j. Why it covers ρ: g of body b
//! reads the bodies of the elements that act on b (crate::jacobian's reach of each force
//! node) and b's own state; a row's c and Φ_q read the bodies of its terms only; M is
//! constant.

use lash_solver::kkt::{KktShape, KktSystem};

use crate::mechanism::constraints::eval_row;
use crate::mechanism::Mechanism;

impl KktSystem for Mechanism {
    fn kkt_shape(&self) -> KktShape {
        let cons = self.constraints();
        let k_entries = self.nq()
            + 2 * cons
                .row_int
                .iter()
                .zip(&cons.rows)
                .map(|(ints, row)| 3 * ints[..row.n_terms].iter().flatten().count())
                .sum::<usize>();
        KktShape {
            nq: self.nq(),
            m: cons.rows.len(),
            k_entries,
            residual_pattern: residual_pattern(self),
            regularisation: self.formulation().kkt_regularisation(),
        }
    }

    fn kkt_assemble(
        &self,
        t: f64,
        y: &[f64],
        k: &mut Vec<(usize, usize, f64)>,
        b: &mut [f64],
    ) -> bool {
        let Some((p, s)) = self.formulation().kkt_stabilisation() else {
            return false;
        };
        let nq = self.nq();
        let (bodies, cons) = (self.bodies(), self.constraints());
        if y.len() != 2 * nq || b.len() != nq + cons.rows.len() {
            return false;
        }
        let mut sc = self.scratch();
        self.kinematics(t, y, &mut sc);
        self.forces().applied(bodies, t, &mut sc, false);
        k.clear();
        for (i, &kb) in bodies.int_bodies.iter().enumerate() {
            let info = &bodies.info[kb];
            k.push((3 * i, 3 * i, info.mass));
            k.push((3 * i + 1, 3 * i + 1, info.mass));
            k.push((3 * i + 2, 3 * i + 2, info.inertia));
        }
        b[..nq].copy_from_slice(&sc.g[..nq]);
        for (r, (row, ints)) in cons.rows.iter().zip(&cons.row_int).enumerate() {
            let ev = eval_row(row, &bodies.info, t, &sc);
            b[nq + r] = ev.gamma - p * ev.phid - s * ev.phi;
            for (ti, bi) in ints[..row.n_terms].iter().enumerate() {
                if let Some(i) = *bi {
                    for c in 0..3 {
                        let v = ev.jrows[ti][c];
                        k.push((nq + r, 3 * i + c, v));
                        k.push((3 * i + c, nq + r, v));
                    }
                }
            }
        }
        b.iter().all(|v| v.is_finite()) && k.iter().all(|e| e.2.is_finite())
    }

    /// R = ∂ρ/∂y at fixed z = (q̈, λ) in closed form (module doc) where the forces' ∂g/∂y
    /// has one (none, gravity only; or every clearance joint's and element's own): false
    /// otherwise, and the `kkt` path differences ρ.
    fn kkt_residual_jacobian(
        &self,
        t: f64,
        y: &[f64],
        z: &[f64],
        pattern: &[Vec<usize>],
        r: &mut [f64],
    ) -> bool {
        let Some((p, s)) = self.formulation().kkt_stabilisation() else {
            return false;
        };
        let nq = self.nq();
        let (bodies, cons, forces) = (self.bodies(), self.constraints(), self.forces());
        let m = cons.rows.len();
        if y.len() != 2 * nq || z.len() != nq + m || pattern.len() != 2 * nq {
            return false;
        }
        let mut sc = self.scratch();
        self.kinematics(t, y, &mut sc);
        let mut fw = self.force_jac_work();
        let with_dg = forces.has_jacobian();
        if with_dg {
            forces.applied(bodies, t, &mut sc, false);
            if !forces.closed_jacobian(bodies, t, &sc, &mut fw) {
                return false;
            }
        }
        // Φ_q's block of each term of every row.
        let jr: Vec<[[f64; 3]; 2]> = cons
            .rows
            .iter()
            .map(|row| eval_row(row, &bodies.info, t, &sc).jrows)
            .collect();
        let (qdd, lam) = z.split_at(nq);
        let (mut dphiq, mut dcdq, mut dcdv) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
        let mut e = 0;
        for (j, rows) in pattern.iter().enumerate() {
            let (qj, vel) = (j % nq, j >= nq);
            let (body, comp) = (qj / 3, qj % 3);
            let (grows, crows) = rows.split_at(rows.partition_point(|&i| i < nq));
            for &i in crows {
                (dphiq[i - nq], dcdq[i - nq], dcdv[i - nq]) = (0.0, 0.0, 0.0);
            }
            // An angle's column: ∂Φ_q/∂φ and the velocity parts of ∂c (point terms).
            if comp == 2 {
                let on = crows.iter().map(|&i| i - nq);
                cons.for_point_terms_in(on, &sc, body, |a, wa, wb, om| {
                    dphiq[a] -= wa;
                    dcdq[a] += om * om * wb + p * wa * om;
                    dcdv[a] += 2.0 * om * wa;
                });
            }
            // (∂Φ_q/∂φ)ᵀ λ: nonzero in the angle's own row only.
            let u: f64 = if vel {
                0.0
            } else {
                crows.iter().map(|&i| dphiq[i - nq] * lam[i - nq]).sum()
            };
            for &i in grows {
                let dg = if with_dg { fw.dg[j * nq + i] } else { 0.0 };
                r[e] = if i == qj && !vel { dg - u } else { dg };
                e += 1;
            }
            for &i in crows {
                let a = i - nq;
                let (row, ints) = (&cons.rows[a], &cons.row_int[a]);
                let phiq: f64 = (0..row.n_terms)
                    .filter(|&ti| ints[ti] == Some(body))
                    .map(|ti| jr[a][ti][comp])
                    .sum();
                r[e] = if vel {
                    dcdv[a] - p * phiq
                } else {
                    dcdq[a] - s * phiq - dphiq[a] * qdd[qj]
                };
                e += 1;
            }
        }
        true
    }
}

/// The pattern of ∂ρ/∂y (module doc): for each column of y = (q, q̇), its rows of ρ
/// (g's n_q, then the m constraint rows), ascending.
pub(crate) fn residual_pattern(mech: &Mechanism) -> Vec<Vec<usize>> {
    let nq = mech.nq();
    let nint = nq / 3;
    let cons = mech.constraints();
    // Bodies whose g may read body j: the reach of each force node, the rows' bodies.
    let mut nbr: Vec<Vec<usize>> = (0..nint).map(|j| vec![j]).collect();
    let mut rows_of: Vec<Vec<usize>> = vec![Vec::new(); nint];
    for reach in crate::jacobian::force_reach(mech) {
        for &a in &reach {
            nbr[a].extend(&reach);
        }
    }
    for (r, (row, ints)) in cons.rows.iter().zip(&cons.row_int).enumerate() {
        let on: Vec<usize> = ints[..row.n_terms].iter().flatten().copied().collect();
        for &a in &on {
            nbr[a].extend(&on);
            rows_of[a].push(r);
        }
    }
    let mut pattern = vec![Vec::new(); 2 * nq];
    for j in 0..nint {
        let mut bs = std::mem::take(&mut nbr[j]);
        bs.sort_unstable();
        bs.dedup();
        let mut rows: Vec<usize> = bs.iter().flat_map(|&b| 3 * b..3 * b + 3).collect();
        let mut cr: Vec<usize> = rows_of[j].iter().map(|r| nq + r).collect();
        cr.sort_unstable();
        cr.dedup();
        rows.extend(cr);
        for c in 0..3 {
            pattern[3 * j + c] = rows.clone();
            pattern[nq + 3 * j + c] = rows.clone();
        }
    }
    pattern
}
