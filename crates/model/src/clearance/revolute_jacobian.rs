//! The revolute clearance joint's part of the Jacobian ∂g/∂y (docs/model.md §1.7): its force
//! on the journal and its friction force as functions of the joint's own variables
//! u = (e, ė, φ̇_J, φ̇_B), differentiated in closed form (or by differences scaled to the joint
//! near the centre and contact onset), then chained through ∂u/∂y.
//!
//! ```text
//! ∂g/∂y = ∂g/∂u · ∂u/∂y + ∂g/∂φ |_u,  u = (e, ė, φ̇_J, φ̇_B),
//!         ∂u/∂y closed form (e = r_J + A_J s_J − r_B − A_B s_B, ė its time derivative),
//!         ∂(F, T)/∂u in closed form: the chain rule through ∂(δ, δ̇, v_T, ε, ε̇, Ω, n, t)/∂u
//!         (`ClearanceState::derivatives`) and the laws' own partial derivatives
//!         (`force_derivatives` of the normal, friction and film laws; one-sided at their
//!         kinks). Where |e| or |δ| < 1e-4 c (the centred start, contact onset and loss;
//!         the differences' step below would be floored) central differences in u, which
//!         average the 1/|e| and 1/|e|² of n and γ̇ over the floor step, with steps scaled
//!         to the joint:
//!         h_e = 1e-6 · min(|e|, |δ|) (floor 1e-10 c), h_ė = 1e-6 · max(|ė|, |v_T|, 1e-9);
//!         a mirrored film caps them so that Ω moves by at most 1e-3 Ω₀ (h_φ̇ ≤ 1e-3 Ω₀,
//!         h_ė ≤ 1e-3 Ω₀ |e|/2, h_e ≤ 1e-3 Ω₀ |e|²/(2|ė|))
//! ```
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
//! no cancellation (e is not recomputed from positions of size 0.35 m).

use crate::clearance::geometry::{ClearanceInput, ClearanceState};
use crate::clearance::revolute::{Revolute, RevoluteEval};
use crate::elements::input::Kin;
use crate::planar::{perp, rot};

/// Relative step of the differences in the clearance variables u = (e, ė, φ̇_J, φ̇_B).
const LOCAL_STEP: f64 = 1e-6;

/// Floor of the differences' step in e, in units of the clearance c.
const DIFF_FLOOR: f64 = 1e-10;

/// Largest change of the film's Ω in one difference of a mirrored film, in units of its
/// sign width Ω₀ (central differences of tanh(Ω/Ω₀) then err by about 3e-7 relative).
const OMEGA_STEP: f64 = 1e-3;

impl Revolute {
    /// The joint's force on its journal F and its friction force T as functions of
    /// u = (e_x, e_y, ė_x, ė_y, φ̇_J, φ̇_B).
    fn local_forces(&self, u: &[f64; 6]) -> [f64; 3] {
        let c = self;
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
        let ev = self.forces(st);
        let fn_ = -ev.f_n + ev.f_r;
        let ft = ev.f_t + ev.f_tf;
        [
            fn_ * st.n[0] + ft * st.t[0],
            fn_ * st.n[1] + ft * st.t[1],
            ev.f_t,
        ]
    }

    /// ∂(F_x, F_y, T)/∂u of clearance joint k at the evaluated state, in closed form: the chain
    /// rule through the state's derivatives ([`ClearanceState::derivatives`]) and those of the
    /// laws (`force_derivatives` of the normal, friction and film laws). `None` where |e| or |δ|
    /// is below 1e-4 c (and at the centred guard, n undefined), where
    /// [`differenced_local_jacobian`] serves.
    fn analytic_local_jacobian(&self, ev: &RevoluteEval, edot: [f64; 2]) -> Option<[[f64; 6]; 3]> {
        let c = self;
        let st = ev.st;
        // Where the differences' steps would be floored (|e| or |δ| below 1e-4 c), the closed form
        // would carry the 1/|e| and 1/|e|² of n and γ̇ at full strength near the centre or the
        // contact onset; there the differences, which average them over the floor step, serve
        // (module documentation).
        if LOCAL_STEP * st.e_norm.min(st.delta.abs()) < DIFF_FLOOR * c.c {
            return None;
        }
        let d = st.derivatives(edot, c.rj, c.rb)?;
        // ∂F_N/∂u and ∂F_T/∂u (contact and friction act only for δ > 0, as in the evaluation).
        let (mut dfn, mut dft) = ([0.0; 6], [0.0; 6]);
        if st.delta > 0.0 {
            let [nd, nv] =
                c.normal
                    .force_derivatives(st.delta, st.delta_dot, c.impact_velocity.get());
            for j in 0..6 {
                dfn[j] = nd * d.delta[j] + nv * d.delta_dot[j];
            }
            if let Some(fr) = &c.friction {
                let [fv, ff] = fr.force_derivatives(st.v_t, ev.f_n);
                for j in 0..6 {
                    dft[j] = fv * d.v_t[j] + ff * dfn[j];
                }
            }
        }
        // ∂(F_r, F_t)/∂u of the film through ε = |e|/c, ε̇ = δ̇/c and Ω.
        let (mut dfr, mut dftf) = ([0.0; 6], [0.0; 6]);
        if let Some(film) = &c.film {
            let fd = film.force_derivatives(st.eps, st.eps_dot, st.omega);
            for j in 0..6 {
                let (de, dv, dw) = (d.delta[j] / c.c, d.delta_dot[j] / c.c, d.omega[j]);
                dfr[j] = fd[0][0] * de + fd[0][1] * dv + fd[0][2] * dw;
                dftf[j] = fd[1][0] * de + fd[1][1] * dv + fd[1][2] * dw;
            }
        }
        // F = (−F_N + F_r) n + (F_T + F_t) t, T = F_T.
        let (normal, tangential) = (-ev.f_n + ev.f_r, ev.f_t + ev.f_tf);
        let mut lu = [[0.0; 6]; 3];
        for j in 0..6 {
            let (dnorm, dtan) = (-dfn[j] + dfr[j], dft[j] + dftf[j]);
            for i in 0..2 {
                let (dn, dt) = if j < 2 {
                    (d.dn[i][j], d.dt[i][j])
                } else {
                    (0.0, 0.0)
                };
                lu[i][j] = dnorm * st.n[i] + normal * dn + dtan * st.t[i] + tangential * dt;
            }
            lu[2][j] = dft[j];
        }
        Some(lu)
    }

    /// ∂(F_x, F_y, T)/∂u of clearance joint k by central differences of the laws in u, with steps
    /// scaled to the joint (see the module documentation): the path near the centre and near
    /// contact onset, and the tests' reference for [`analytic_local_jacobian`].
    fn differenced_local_jacobian(
        &self,
        ev: &RevoluteEval,
        kin: &Kin<'_>,
        edot: [f64; 2],
    ) -> [[f64; 6]; 3] {
        let c = self;
        let st = ev.st;
        let w_j = c.journal.omega(kin);
        let w_b = c.bearing.omega(kin);
        let u0 = [st.e[0], st.e[1], edot[0], edot[1], w_j, w_b];
        let mut he = (LOCAL_STEP * st.e_norm.min(st.delta.abs())).max(DIFF_FLOOR * c.c);
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
        let mut lu = [[0.0; 6]; 3];
        let mut u = u0;
        for j in 0..6 {
            let h = steps[j];
            u[j] = u0[j] + h;
            let hp = u[j] - u0[j];
            let fp = self.local_forces(&u);
            u[j] = u0[j] - h;
            let hm = u0[j] - u[j];
            let fm = self.local_forces(&u);
            u[j] = u0[j];
            for i in 0..3 {
                lu[i][j] = (fp[i] - fm[i]) / (hp + hm);
            }
        }
        lu
    }

    /// Adds the joint's contribution to ∂g/∂y (nq × n, column-major in `dg`); `int_of` maps
    /// a scene body to its integrated index.
    ///
    /// ```text
    /// ∂u/∂y of an integrated end (sign s = +1 journal, −1 bearing; a = A s_end, b = perp(a)):
    ///   column x, y:    ∂e/∂(x, y) = s (1, 0), s (0, 1)
    ///   column φ:       ∂e/∂φ = s b,  ∂ė/∂φ = −s ω a
    ///   column ẋ, ẏ:    ∂ė/∂(ẋ, ẏ) = s (1, 0), s (0, 1)
    ///   column ω:       ∂ė/∂ω = s b,  ∂φ̇_end/∂ω = 1
    /// ```
    /// Each column's (∂F, ∂T) = ∂(F, T)/∂u · ∂u/∂y_j is summed over the entries of ∂u/∂y_j
    /// that can be nonzero, in ascending order of u: the dense product over all six entries
    /// adds products with exact zeros besides, which change no nonzero sum, and a zero's sign
    /// does not reach ∂g (its entries are sums from +0, where a ±0 term changes nothing).
    /// The ends are on different bodies (`check_ends` in clearance/revolute.rs refuses a
    /// scene where they are not), so a column is one end's; were they not, the two ends'
    /// parts of a column would be added one after the other (the same derivative, rounded
    /// differently).
    pub(crate) fn force_jacobian(
        &self,
        ev: &RevoluteEval,
        kin: &Kin<'_>,
        int_of: &[Option<usize>],
        n: usize,
        dg: &mut [f64],
    ) {
        let nq = n / 2;
        let c = self;
        let edot = self.edot(kin);
        // ∂(F_x, F_y, T)/∂u, 3 × 6.
        let lu = self
            .analytic_local_jacobian(ev, edot)
            .unwrap_or_else(|| self.differenced_local_jacobian(ev, kin, edot));
        let (normal, tangential) = (-ev.f_n + ev.f_r, ev.f_t + ev.f_tf);
        let f = [
            normal * ev.st.n[0] + tangential * ev.st.t[0],
            normal * ev.st.n[1] + tangential * ev.st.t[1],
        ];
        // Each integrated end: (integrated index, sign, radius, A s, φ̇ slot of u, its body's
        // ω), found once.
        let mut on = [(0usize, 0.0, 0.0, [0.0; 2], 0usize, 0.0); 2];
        let mut n_on = 0;
        for (end, sign, radius, wslot) in [(c.journal, 1.0, c.rj, 4), (c.bearing, -1.0, c.rb, 5)] {
            let Some(kb) = end.body else { continue };
            let Some(i) = int_of[kb] else {
                continue;
            };
            on[n_on] = (
                i,
                sign,
                radius,
                rot(kin.cs[kb], end.s),
                wslot,
                kin.vel[kb][2],
            );
            n_on += 1;
        }
        let on = &on[..n_on];
        // dF/dy_j, dT/dy_j = `d` into the generalized forces of both ends.
        let mut add = |j: usize, d: [f64; 3]| {
            let col = &mut dg[j * nq..(j + 1) * nq];
            for &(i, sign, radius, a, _, _) in on {
                let g = &mut col[3 * i..3 * i + 3];
                g[0] += sign * d[0];
                g[1] += sign * d[1];
                g[2] += sign * (a[0] * d[1] - a[1] * d[0] + radius * d[2]);
            }
        };
        for &(i, sign, _, a, wslot, w) in on {
            let b = perp(a);
            // The entries of ∂u/∂y_j as the dense rows had them (sums from 0).
            let (sb, sw) = ([0.0 + sign * b[0], 0.0 + sign * b[1]], sign * w);
            let (swa0, swa1) = (0.0 - sw * a[0], 0.0 - sw * a[1]);
            let one = |l: usize| [lu[0][l] * sign, lu[1][l] * sign, lu[2][l] * sign];
            add(3 * i, one(0));
            add(3 * i + 1, one(1));
            add(
                3 * i + 2,
                [0, 1, 2].map(|r| {
                    let x = &lu[r];
                    x[0] * sb[0] + x[1] * sb[1] + x[2] * swa0 + x[3] * swa1
                }),
            );
            add(nq + 3 * i, one(2));
            add(nq + 3 * i + 1, one(3));
            add(
                nq + 3 * i + 2,
                [0, 1, 2].map(|r| {
                    let x = &lu[r];
                    x[2] * sb[0] + x[3] * sb[1] + x[wslot]
                }),
            );
        }
        // The moment arms A s turn with their own bodies: ∂((A s) × F)/∂φ = perp(A s) × F = −(A s)·F.
        for &(i, sign, _, a, _, _) in on {
            dg[(3 * i + 2) * nq + 3 * i + 2] -= sign * (a[0] * f[0] + a[1] * f[1]);
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::Mechanism;
    use crate::Scene;
    use serde_json::json;

    const RB: f64 = 0.010;
    const RJ: f64 = 0.009;
    const C: f64 = RB - RJ;

    /// A free pin (journal) in a ground bearing with the given laws.
    fn journal(
        normal: serde_json::Value,
        friction: serde_json::Value,
        film: Option<serde_json::Value>,
    ) -> Mechanism {
        let mut joint = json!({"type": "clearance", "name": "j",
            "bearing": {"body": "ground", "at": [0.0, 0.0], "radius": RB},
            "journal": {"body": "pin", "point": "c", "radius": RJ},
            "normal": normal, "friction": friction});
        if let Some(f) = film {
            joint["film"] = f;
        }
        let v = json!({
            "bodies": [{"name": "pin", "mass": 2.0, "inertia": 0.1, "points": {"c": [0.0, 0.0]}}],
            "joints": [joint],
            "t_end": 1.0
        });
        Mechanism::from_scene(&Scene::from_json_str(&v.to_string()).unwrap()).unwrap()
    }

    /// The closed-form ∂(F_x, F_y, T)/∂u against central differences of the laws, for every
    /// normal law, friction in each regime and every film model, capped and not, at states in
    /// contact and in the film (oblique e, so that n and t turn). The differences (steps 1e-6
    /// of the joint's scales) err by ~1e-9 of a row's scale; 1e-6 leaves room for that and
    /// catches any wrong or missing term (each is at least 1e-3 of its row here).
    #[test]
    fn closed_form_law_jacobian_matches_differences() {
        let k = 1e10;
        let normals = [
            json!({"law": "impact", "k": k, "c_max": 2e3, "d_max": 1e-5}),
            json!({"law": "lankarani_nikravesh", "k": k, "restitution": 0.7}),
            json!({"law": "flores", "k": k, "restitution": 0.8}),
            json!({"law": "hunt_crossley", "k": k, "restitution": 0.9}),
        ];
        let frictions = [
            json!({"law": "none"}),
            json!({"law": "coulomb", "mu": 0.2, "v0": 1e-3, "v1": 0.5}),
            json!({"law": "coulomb", "mu": 0.2, "v0": 1e-4, "v1": 1e-3}),
        ];
        let films = [
            None,
            Some(json!({"model": "long_gumbel", "viscosity": 0.4, "length": 0.02})),
            Some(
                json!({"model": "long_gumbel_mirrored", "viscosity": 0.4, "length": 0.02,
                "omega0": 5.0}),
            ),
            Some(
                json!({"model": "long_sommerfeld", "viscosity": 0.4, "length": 0.02,
                "eps_cap": null}),
            ),
            Some(json!({"model": "short_ocvirk", "viscosity": 0.4, "length": 0.02})),
            Some(
                json!({"model": "short_ocvirk_mirrored", "viscosity": 0.4, "length": 0.02,
                "eps_cap": null, "omega0": 5.0}),
            ),
        ];
        let (ca, sa) = (0.6f64.cos(), 0.6f64.sin());
        // (|e|, ė along n, ė along t, ω): in contact (δ = 4e-6 below d_max, approach; δ = 2e-5
        // beyond it, separation with slip in the ramp of c_d) and in the film (ε = 0.6, 0.95).
        let states = [
            (C + 4e-6, 0.02, 0.3, 4.0),
            (C + 2e-5, -0.01, 0.0, 0.05),
            (0.6 * C, 0.01, -0.02, 3.0),
            (0.95 * C, -0.003, 0.01, -1.0),
        ];
        let mut checked = 0;
        for normal in &normals {
            for friction in &frictions {
                for film in &films {
                    let m = journal(normal.clone(), friction.clone(), film.clone());
                    m.set_impact_velocity(0, 0.4);
                    for &(r, vn, vt, w) in &states {
                        let y = [r * ca, r * sa, 0.0, vn * ca - vt * sa, vn * sa + vt * ca, w];
                        let sc = m.evaluated(0.0, &y).unwrap();
                        let (j, ev) = (&m.forces().revolute[0], &sc.revolute[0]);
                        let edot = j.edot(&sc.kin());
                        let a = j.analytic_local_jacobian(ev, edot).unwrap();
                        let d = j.differenced_local_jacobian(ev, &sc.kin(), edot);
                        for i in 0..3 {
                            // Row scale: the largest |∂F/∂u_j| times the scale of u_j.
                            let us = [r, r, 0.1, 0.1, 1.0, 1.0];
                            let scale = (0..6)
                                .map(|j| a[i][j].abs().max(d[i][j].abs()) * us[j])
                                .fold(0.0f64, f64::max);
                            for j in 0..6 {
                                let err = (a[i][j] - d[i][j]).abs() * us[j];
                                assert!(
                                    err <= 1e-6 * scale,
                                    "{normal} {friction} {film:?} |e| {r:e}: ∂F{i}/∂u{j} \
                                     closed form {:e}, differences {:e}",
                                    a[i][j],
                                    d[i][j]
                                );
                            }
                        }
                        checked += 1;
                    }
                }
            }
        }
        assert_eq!(checked, 4 * 3 * 6 * 4);
    }

    /// At the centred start (e = 0) n has no derivative, and within 1e-4 c of the centre the
    /// floored differences serve (module documentation); beyond, the closed form.
    #[test]
    fn the_centred_journal_falls_back_to_differences() {
        let m = journal(
            json!({"law": "impact", "k": 1e10, "c_max": 1e3, "d_max": 1e-5}),
            json!({"law": "none"}),
            Some(json!({"model": "long_gumbel", "viscosity": 0.4, "length": 0.02})),
        );
        let j = &m.forces().revolute[0];
        let local = |y: &[f64]| {
            let sc = m.evaluated(0.0, y).unwrap();
            j.analytic_local_jacobian(&sc.revolute[0], j.edot(&sc.kin()))
        };
        assert!(local(&[0.0, 0.0, 0.0, 0.01, 0.0, 2.0]).is_none());
        for (r, closed) in [(1e-6 * C, false), (0.9e-4 * C, false), (1.1e-4 * C, true)] {
            let a = local(&[r, 0.0, 0.0, 0.01, 0.0, 2.0]);
            assert_eq!(a.is_some(), closed, "|e| = {r:e}");
        }
    }
}
