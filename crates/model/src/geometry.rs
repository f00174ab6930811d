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
    /// Evaluates the clearance kinematics of docs/model.md §2 (see the type's equations).
    ///
    /// Centred guard: when |e| < 1e-12·c (or |e| = 0) the normal is n = (1, 0) and γ̇ = 0, so
    /// Ω = φ̇_J + φ̇_B. The result is finite for finite input with R_B > R_J.
    #[inline]
    pub fn compute(inp: &ClearanceInput) -> ClearanceState {
        let c = inp.radius_b - inp.radius_j;
        let e = [inp.r_j[0] - inp.r_b[0], inp.r_j[1] - inp.r_b[1]];
        let ed = [inp.v_j[0] - inp.v_b[0], inp.v_j[1] - inp.v_b[1]];
        let e_norm = (e[0] * e[0] + e[1] * e[1]).sqrt();
        // `e_norm == 0` also covers a degenerate c ≤ 0, where the relative test alone would
        // let 0/0 through.
        let centred = e_norm < 1e-12 * c || e_norm == 0.0;
        let n = if centred {
            [1.0, 0.0]
        } else {
            [e[0] / e_norm, e[1] / e_norm]
        };
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
