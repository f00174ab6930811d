//! Kinematics of a revolute clearance joint (docs/model.md §2), unit-testable on its own.
//!
//! ```text
//! e   = r_J^P − r_B^P               eccentricity (bearing centre → journal centre)
//! c   = R_B − R_J                   radial clearance
//! n   = e/|e|,  t = (−n_y, n_x)     normal and tangent (n = (1, 0) when |e| < 1e-12·c)
//! δ   = |e| − c                     penetration (contact iff δ > 0)
//! ė   = ṙ_J^P − ṙ_B^P
//! δ̇   = n·ė
//! v_T = t·ė + R_J φ̇_J − R_B φ̇_B     slip of the material contact points
//! ε   = |e|/c,  ε̇ = δ̇/c
//! γ̇   = (e_x ė_y − e_y ė_x)/|e|²    (0 when |e| < 1e-12·c)
//! Ω   = φ̇_J + φ̇_B − 2γ̇              (film wedge speed, docs/model.md §4)
//! ```

/// Everything the force laws need about one clearance joint at one instant.
///
/// ```text
/// e = r_J^P − r_B^P,  n = e/|e|,  t = (−n_y, n_x),  δ = |e| − c,  δ̇ = n·ė
/// v_T = t·ė + R_J φ̇_J − R_B φ̇_B,  ε = |e|/c,  ε̇ = δ̇/c,  Ω = φ̇_J + φ̇_B − 2γ̇
/// ```
/// docs/model.md §2 and §4 (Peng et al. 2025, Lubricants 13(3) 124, §2.1 and §2.3, with the
/// material-point slip of docs/model.md §2 in v_T).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClearanceState {
    /// Eccentricity vector e (m).
    pub e: [f64; 2],
    /// |e| (m).
    pub e_norm: f64,
    /// Unit normal n (journal pushed along −n by contact).
    pub n: [f64; 2],
    /// Unit tangent t = (−n_y, n_x).
    pub t: [f64; 2],
    /// Penetration δ = |e| − c (m).
    pub delta: f64,
    /// Normal relative velocity δ̇ (m/s).
    pub delta_dot: f64,
    /// Tangential slip of the material contact points v_T (m/s).
    pub v_t: f64,
    /// Relative eccentricity ε = |e|/c.
    pub eps: f64,
    /// ε̇ = δ̇/c (1/s).
    pub eps_dot: f64,
    /// Film wedge speed Ω = φ̇_J + φ̇_B − 2γ̇ (rad/s).
    pub omega: f64,
}

/// Journal and bearing data needed by [`ClearanceState::compute`].
///
/// ```text
/// r_k^P = r_k + A(φ_k) s'_k,   ṙ_k^P = ṙ_k + φ̇_k k × (A(φ_k) s'_k),   k = J, B
/// ```
/// The joint centres and their velocities, already transformed to the global frame
/// (docs/model.md §1; Peng et al. 2025 §3); radii satisfy R_B > R_J > 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClearanceInput {
    /// Global position of the journal centre P_J.
    pub r_j: [f64; 2],
    /// Global position of the bearing centre P_B.
    pub r_b: [f64; 2],
    /// Global velocity of P_J.
    pub v_j: [f64; 2],
    /// Global velocity of P_B.
    pub v_b: [f64; 2],
    /// Angular velocity of the journal body (0 for ground).
    pub phi_dot_j: f64,
    /// Angular velocity of the bearing body (0 for ground).
    pub phi_dot_b: f64,
    /// Journal radius R_J.
    pub radius_j: f64,
    /// Bearing radius R_B.
    pub radius_b: f64,
}

impl ClearanceState {
    /// |e|, whether the journal counts as centred (|e| < 1e-12·c, or 0), and the unit normal
    /// n = e/|e| ((1, 0) when centred) of the eccentricity e at clearance c: the start of
    /// [`ClearanceState::compute`], shared with the event functions' gap and rate.
    #[inline(always)]
    pub(crate) fn normal_of(e: [f64; 2], c: f64) -> (f64, bool, [f64; 2]) {
        let e_norm = (e[0] * e[0] + e[1] * e[1]).sqrt();
        // `e_norm == 0` also covers a degenerate c ≤ 0, where the relative test alone would
        // let 0/0 through.
        let centred = e_norm < 1e-12 * c || e_norm == 0.0;
        let n = if centred {
            [1.0, 0.0]
        } else {
            [e[0] / e_norm, e[1] / e_norm]
        };
        (e_norm, centred, n)
    }

    /// Evaluates the clearance kinematics of docs/model.md §2 (see the type's equations).
    ///
    /// Centred guard: when |e| < 1e-12·c (or |e| = 0) the normal is n = (1, 0) and γ̇ = 0, so
    /// Ω = φ̇_J + φ̇_B. The result is finite for finite input with R_B > R_J.
    #[inline]
    pub fn compute(inp: &ClearanceInput) -> ClearanceState {
        let c = inp.radius_b - inp.radius_j;
        let e = [inp.r_j[0] - inp.r_b[0], inp.r_j[1] - inp.r_b[1]];
        let ed = [inp.v_j[0] - inp.v_b[0], inp.v_j[1] - inp.v_b[1]];
        let (e_norm, centred, n) = ClearanceState::normal_of(e, c);
        let t = [-n[1], n[0]];
        let delta_dot = n[0] * ed[0] + n[1] * ed[1];
        let v_t = t[0] * ed[0] + t[1] * ed[1] + inp.radius_j * inp.phi_dot_j
            - inp.radius_b * inp.phi_dot_b;
        let gamma_dot = if centred {
            0.0
        } else {
            // (e_x ė_y − e_y ė_x)/|e|² written as (n × ė)/|e|: |e|² cannot underflow.
            (n[0] * ed[1] - n[1] * ed[0]) / e_norm
        };
        ClearanceState {
            e,
            e_norm,
            n,
            t,
            delta: e_norm - c,
            delta_dot,
            v_t,
            eps: e_norm / c,
            eps_dot: delta_dot / c,
            omega: inp.phi_dot_j + inp.phi_dot_b - 2.0 * gamma_dot,
        }
    }
}

/// The derivatives of a [`ClearanceState`] in u = (e_x, e_y, ė_x, ė_y, φ̇_J, φ̇_B), away from
/// the centred guard (|e| ≥ 1e-12·c):
///
/// ```text
/// ∂n/∂e = t tᵀ/|e|,  ∂t/∂e = −n tᵀ/|e|          (n, t do not depend on ė, φ̇)
/// ∂δ  = (nᵀ, 0, 0, 0)
/// ∂δ̇  = (γ̇ tᵀ, nᵀ, 0, 0)                        γ̇ = t·ė/|e|
/// ∂v_T = (−(δ̇/|e|) tᵀ, tᵀ, R_J, −R_B)
/// ∂γ̇  = (−(δ̇ tᵀ + (t·ė) nᵀ)/|e|², tᵀ/|e|, 0, 0),  ∂Ω = −2 ∂γ̇ + (0, 0, 1, 1)
/// ∂ε = ∂δ/c,  ∂ε̇ = ∂δ̇/c
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct StateDerivatives {
    /// ∂δ/∂u.
    pub delta: [f64; 6],
    /// ∂δ̇/∂u.
    pub delta_dot: [f64; 6],
    /// ∂v_T/∂u.
    pub v_t: [f64; 6],
    /// ∂Ω/∂u.
    pub omega: [f64; 6],
    /// ∂n_i/∂e_j.
    pub dn: [[f64; 2]; 2],
    /// ∂t_i/∂e_j.
    pub dt: [[f64; 2]; 2],
}

impl ClearanceState {
    /// The derivatives of the state in u (see [`StateDerivatives`]) given ė and the radii;
    /// `None` at the centred guard, where n is held at (1, 0) and has no derivative.
    pub(crate) fn derivatives(
        &self,
        ed: [f64; 2],
        radius_j: f64,
        radius_b: f64,
    ) -> Option<StateDerivatives> {
        let c = radius_b - radius_j;
        let r = self.e_norm;
        if r < 1e-12 * c || r == 0.0 {
            return None;
        }
        let (n, t) = (self.n, self.t);
        let te = t[0] * ed[0] + t[1] * ed[1];
        let gd = te / r;
        let dd = self.delta_dot;
        let r2 = r * r;
        let omega_e = |i: usize| 2.0 * (dd * t[i] + te * n[i]) / r2;
        Some(StateDerivatives {
            delta: [n[0], n[1], 0.0, 0.0, 0.0, 0.0],
            delta_dot: [gd * t[0], gd * t[1], n[0], n[1], 0.0, 0.0],
            v_t: [
                -dd / r * t[0],
                -dd / r * t[1],
                t[0],
                t[1],
                radius_j,
                -radius_b,
            ],
            omega: [
                omega_e(0),
                omega_e(1),
                -2.0 * t[0] / r,
                -2.0 * t[1] / r,
                1.0,
                1.0,
            ],
            dn: [
                [t[0] * t[0] / r, t[0] * t[1] / r],
                [t[1] * t[0] / r, t[1] * t[1] / r],
            ],
            dt: [
                [-n[0] * t[0] / r, -n[0] * t[1] / r],
                [-n[1] * t[0] / r, -n[1] * t[1] / r],
            ],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every derivative against central differences of `compute` in each of u's six entries
    /// (steps 1e-7 of each entry's scale; the differences err by ~1e-9 relative).
    #[test]
    fn state_derivatives_match_differences() {
        let (rj, rb) = (0.009, 0.010);
        let u0 = [3e-4, -6e-4, 0.02, 0.05, 3.0, -1.5];
        let state = |u: &[f64; 6]| {
            ClearanceState::compute(&ClearanceInput {
                r_j: [u[0], u[1]],
                r_b: [0.0, 0.0],
                v_j: [u[2], u[3]],
                v_b: [0.0, 0.0],
                phi_dot_j: u[4],
                phi_dot_b: u[5],
                radius_j: rj,
                radius_b: rb,
            })
        };
        let s0 = state(&u0);
        let d = s0.derivatives([u0[2], u0[3]], rj, rb).unwrap();
        let scales = [1e-3, 1e-3, 0.1, 0.1, 1.0, 1.0];
        for j in 0..6 {
            let h = 1e-7 * scales[j];
            let (mut up, mut um) = (u0, u0);
            up[j] += h;
            um[j] -= h;
            let (p, m) = (state(&up), state(&um));
            let diff = |a: f64, b: f64| (a - b) / (2.0 * h);
            let pairs = [
                (d.delta[j], diff(p.delta, m.delta), "δ"),
                (d.delta_dot[j], diff(p.delta_dot, m.delta_dot), "δ̇"),
                (d.v_t[j], diff(p.v_t, m.v_t), "v_T"),
                (d.omega[j], diff(p.omega, m.omega), "Ω"),
            ];
            for (a, b, what) in pairs {
                assert!(
                    (a - b).abs() <= 1e-6 * a.abs().max(b.abs()).max(1e-3 / scales[j]),
                    "∂{what}/∂u{j}: {a:e} vs {b:e}"
                );
            }
            for i in 0..2 {
                let (dn, dt) = if j < 2 {
                    (d.dn[i][j], d.dt[i][j])
                } else {
                    (0.0, 0.0)
                };
                assert!((dn - diff(p.n[i], m.n[i])).abs() <= 1e-6 / scales[0]);
                assert!((dt - diff(p.t[i], m.t[i])).abs() <= 1e-6 / scales[0]);
            }
        }
        // The centred guard has no derivative.
        assert!(state(&[0.0, 0.0, 0.1, 0.0, 1.0, 0.0])
            .derivatives([0.1, 0.0], rj, rb)
            .is_none());
    }
}
