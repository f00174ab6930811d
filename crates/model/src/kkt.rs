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
