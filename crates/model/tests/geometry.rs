//! Clearance-joint kinematics (docs/model.md §2, §4) against finite differences along prescribed
//! motions and against motions with known rates.

use lash_model::geometry::{ClearanceInput, ClearanceState};

const R_B: f64 = 0.05;
const R_J: f64 = 0.0499;
/// c = R_B − R_J (1e-4 m up to the rounding of the subtraction).
const C: f64 = R_B - R_J;

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

fn rot(phi: f64, v: [f64; 2]) -> [f64; 2] {
    let (s, c) = phi.sin_cos();
    [c * v[0] - s * v[1], s * v[0] + c * v[1]]
}

/// A prescribed motion of both bodies: positions, angles and their exact time derivatives.
struct Motion {
    r_b: [f64; 2],
    v_b: [f64; 2],
    phi_b: f64,
    w_b: f64,
    r_j: [f64; 2],
    v_j: [f64; 2],
    phi_j: f64,
    w_j: f64,
}

/// Bearing centre wandering on a Lissajous path while the bearing body rocks; the eccentricity
/// sweeps from inside the clearance to penetration (|e| between ~0.4c and ~1.6c).
fn motion(t: f64) -> Motion {
    let r_b = [0.3 + 0.01 * (2.0 * t).sin(), -0.02 * (3.0 * t).cos()];
    let v_b = [0.02 * (2.0 * t).cos(), 0.06 * (3.0 * t).sin()];
    let e = [
        1.3e-4 * (5.0 * t).cos() + 2e-5 * t,
        0.9e-4 * (4.0 * t + 0.3).sin(),
    ];
    let e_dot = [
        -6.5e-4 * (5.0 * t).sin() + 2e-5,
        3.6e-4 * (4.0 * t + 0.3).cos(),
    ];
    Motion {
        r_b,
        v_b,
        phi_b: 0.5 * (1.7 * t).sin(),
        w_b: 0.85 * (1.7 * t).cos(),
        r_j: [r_b[0] + e[0], r_b[1] + e[1]],
        v_j: [v_b[0] + e_dot[0], v_b[1] + e_dot[1]],
        phi_j: 2.0 * t + 0.3 * t.cos(),
        w_j: 2.0 - 0.3 * t.sin(),
    }
}

fn input(m: &Motion) -> ClearanceInput {
    ClearanceInput {
        r_j: m.r_j,
        r_b: m.r_b,
        v_j: m.v_j,
        v_b: m.v_b,
        phi_dot_j: m.w_j,
        phi_dot_b: m.w_b,
        radius_j: R_J,
        radius_b: R_B,
    }
}

fn state(t: f64) -> ClearanceState {
    ClearanceState::compute(&input(&motion(t)))
}

const TIMES: [f64; 6] = [0.0, 0.17, 0.5, 1.1, 2.3, 4.05];

#[test]
fn normal_and_tangent_are_orthonormal_and_right_handed() {
    for t in TIMES {
        let s = state(t);
        assert!((dot(s.n, s.n) - 1.0).abs() < 1e-15);
        assert!((dot(s.t, s.t) - 1.0).abs() < 1e-15);
        assert!(dot(s.n, s.t).abs() < 1e-15);
        // t is n turned by +90°: n × t = +1.
        assert!((s.n[0] * s.t[1] - s.n[1] * s.t[0] - 1.0).abs() < 1e-15);
        // n points from the bearing centre to the journal centre: e = |e| n.
        assert!((s.e[0] - s.e_norm * s.n[0]).abs() < 1e-20);
        assert!((s.e[1] - s.e_norm * s.n[1]).abs() < 1e-20);
        assert!((dot(s.n, s.e) - s.e_norm).abs() < 1e-19);
        // δ, ε, ε̇ by their definitions.
        assert_eq!(s.delta, s.e_norm - C);
        assert_eq!(s.eps, s.e_norm / C);
        assert_eq!(s.eps_dot, s.delta_dot / C);
    }
}

/// The motion reaches both sides of contact, so the FD checks below cover δ < 0 and δ > 0.
#[test]
fn prescribed_motion_crosses_contact() {
    let deltas: Vec<f64> = (0..400).map(|i| state(i as f64 * 0.01).delta).collect();
    assert!(deltas.iter().any(|&d| d > 0.3 * C));
    assert!(deltas.iter().any(|&d| d < -0.3 * C));
}

/// δ̇ = d|e|/dt and ε̇ = dε/dt: central differences of the computed δ along the motion, step
/// 1e-5 s (truncation ~h²·|e'''| ≈ 1e-12 m/s, rounding ~1e-17/1e-5 = 1e-12 m/s against
/// |ė| ~ 5e-4 m/s: 1e-6 relative leaves a wide margin but catches any sign or factor slip).
#[test]
fn delta_dot_is_the_derivative_of_penetration() {
    let h = 1e-5;
    for t in TIMES {
        let s = state(t);
        let fd = (state(t + h).delta - state(t - h).delta) / (2.0 * h);
        let scale = 6.5e-4;
        assert!(
            (s.delta_dot - fd).abs() < 1e-6 * scale,
            "t = {t}: δ̇ = {:e}, FD {fd:e}",
            s.delta_dot
        );
        let fd_eps = (state(t + h).eps - state(t - h).eps) / (2.0 * h);
        assert!((s.eps_dot - fd_eps).abs() < 1e-6 * scale / C);
    }
}

/// γ̇ = dγ/dt with γ = atan2(e_y, e_x), read back from Ω = φ̇_J + φ̇_B − 2γ̇.
#[test]
fn omega_carries_the_rate_of_the_line_of_centres() {
    let h = 1e-5;
    for t in TIMES {
        let s = state(t);
        let m = motion(t);
        let gamma = |t: f64| {
            let e = state(t).e;
            e[1].atan2(e[0])
        };
        let mut dg = gamma(t + h) - gamma(t - h);
        if dg > std::f64::consts::PI {
            dg -= 2.0 * std::f64::consts::PI;
        } else if dg < -std::f64::consts::PI {
            dg += 2.0 * std::f64::consts::PI;
        }
        let fd = dg / (2.0 * h);
        let gamma_dot = (m.w_j + m.w_b - s.omega) / 2.0;
        assert!(
            (gamma_dot - fd).abs() < 1e-6 * fd.abs().max(1.0),
            "t = {t}: γ̇ = {gamma_dot}, FD {fd}"
        );
    }
}

/// v_T is the tangential slip of the material contact points: the point of the journal body
/// and the point of the bearing body that sit at Q_J = r_J + R_J n and Q_B = r_B + R_B n at time
/// t, followed as material points (rigid rotation with each body) by central differences.
/// With the body rates ~1–2 rad/s, the rotation terms (~0.1 m/s) dominate v_T here.
#[test]
fn slip_is_the_relative_velocity_of_material_contact_points() {
    let h = 1e-6;
    for t in TIMES {
        let s = state(t);
        let m = motion(t);
        let s_j = [R_J * s.n[0], R_J * s.n[1]];
        let s_b = [R_B * s.n[0], R_B * s.n[1]];
        let point = |tau: f64| {
            let mm = motion(tau);
            let qj = rot(mm.phi_j - m.phi_j, s_j);
            let qb = rot(mm.phi_b - m.phi_b, s_b);
            [
                mm.r_j[0] + qj[0] - mm.r_b[0] - qb[0],
                mm.r_j[1] + qj[1] - mm.r_b[1] - qb[1],
            ]
        };
        let (p1, p0) = (point(t + h), point(t - h));
        let rel_v = [(p1[0] - p0[0]) / (2.0 * h), (p1[1] - p0[1]) / (2.0 * h)];
        let fd = dot(s.t, rel_v);
        assert!(
            (s.v_t - fd).abs() < 1e-7 * fd.abs().max(1e-3),
            "t = {t}: v_T = {}, FD {fd}",
            s.v_t
        );
        // The normal part of that relative velocity is δ̇ plus the normal velocity the rigid
        // rotations add at the contact points: k × (R n) has no normal part, so it is δ̇.
        assert!((dot(s.n, rel_v) - s.delta_dot).abs() < 1e-6 * 6.5e-4);
        // Without the rotation terms (as the paper writes it) the slip would be off by
        // R_J φ̇_J − R_B φ̇_B, which is not small here.
        assert!((m.w_j * R_J - m.w_b * R_B).abs() > 1e-2);
    }
}

/// A journal spinning in place (centres fixed) slips at R_J φ̇_J; a spinning bearing at
/// −R_B φ̇_B. No normal velocity, and Ω = φ̇_J + φ̇_B (no line-of-centres rotation).
#[test]
fn spinning_in_place_slips_at_radius_times_rate() {
    let base = ClearanceInput {
        r_j: [1.0 + 3e-5, 2.0 - 4e-5],
        r_b: [1.0, 2.0],
        v_j: [0.0, 0.0],
        v_b: [0.0, 0.0],
        phi_dot_j: 0.0,
        phi_dot_b: 0.0,
        radius_j: R_J,
        radius_b: R_B,
    };
    let j = ClearanceState::compute(&ClearanceInput {
        phi_dot_j: 7.0,
        ..base
    });
    assert_eq!(j.v_t, R_J * 7.0);
    assert_eq!(j.delta_dot, 0.0);
    assert_eq!(j.omega, 7.0);
    let b = ClearanceState::compute(&ClearanceInput {
        phi_dot_b: 7.0,
        ..base
    });
    assert_eq!(b.v_t, -R_B * 7.0);
    assert_eq!(b.omega, 7.0);
    // |e| = 5e-5 = c/2: δ = −c/2, ε = 1/2, n = (3, −4)/5.
    assert!((j.delta + 0.5 * C).abs() < 1e-16);
    assert!((j.eps - 0.5).abs() < 1e-11);
    assert!((j.n[0] - 0.6).abs() < 1e-11 && (j.n[1] + 0.8).abs() < 1e-11);
}

/// Journal centre on a circle of radius ρ about the bearing centre at angular speed w:
/// γ̇ = w, so Ω = φ̇_J + φ̇_B − 2w; δ̇ = 0; t·ė = ρ w. A common translation of both centres
/// changes nothing (only relative motion counts).
#[test]
fn circular_whirl_has_gamma_dot_equal_to_whirl_speed() {
    for &(rho, w) in &[(0.5 * C, 3.0), (2.0 * C, -5.0), (0.999 * C, 1e3)] {
        for &theta in &[0.0, 1.0, 2.5, -2.0, std::f64::consts::PI] {
            for &(w_j, w_b) in &[(0.0, 0.0), (3.0, 2.0), (-1.0, 4.0)] {
                for &v_common in &[[0.0, 0.0], [0.7, -1.3]] {
                    let (s, c) = f64::sin_cos(theta);
                    let inp = ClearanceInput {
                        r_j: [0.2 + rho * c, -0.1 + rho * s],
                        r_b: [0.2, -0.1],
                        v_j: [v_common[0] - rho * w * s, v_common[1] + rho * w * c],
                        v_b: v_common,
                        phi_dot_j: w_j,
                        phi_dot_b: w_b,
                        radius_j: R_J,
                        radius_b: R_B,
                    };
                    let st = ClearanceState::compute(&inp);
                    let gamma_dot = (w_j + w_b - st.omega) / 2.0;
                    assert!(
                        (gamma_dot - w).abs() < 1e-9 * w.abs(),
                        "ρ = {rho}, w = {w}, θ = {theta}: γ̇ = {gamma_dot}"
                    );
                    assert!(st.delta_dot.abs() < 1e-12 * rho * w.abs() / C);
                    let want_vt = rho * w + R_J * w_j - R_B * w_b;
                    assert!((st.v_t - want_vt).abs() < 1e-12 * want_vt.abs().max(1.0));
                }
            }
        }
    }
}

/// docs/model.md §2 guard: |e| < 1e-12·c uses n = (1, 0) and γ̇ = 0 (so Ω = φ̇_J + φ̇_B), whatever
/// ė; everything stays finite. Just above the threshold the true direction is used.
#[test]
fn centred_journal_guard() {
    let ed = [1e-3, 2e-3];
    for e in [[0.0, 0.0], [0.0, -0.5e-12 * C], [-0.7e-12 * C, 0.0]] {
        let st = ClearanceState::compute(&ClearanceInput {
            r_j: [0.4 + e[0], 0.1 + e[1]],
            r_b: [0.4, 0.1],
            v_j: [0.5 + ed[0], ed[1]],
            v_b: [0.5, 0.0],
            phi_dot_j: 3.0,
            phi_dot_b: -1.0,
            radius_j: R_J,
            radius_b: R_B,
        });
        // r_j − r_b is not exactly e in binary; still far below the threshold.
        assert!(st.e_norm < 1e-12 * C, "{:e}", st.e_norm);
        assert_eq!(st.n, [1.0, 0.0]);
        assert_eq!(st.t, [0.0, 1.0]);
        assert_eq!(st.omega, 2.0);
        assert!((st.delta_dot - ed[0]).abs() < 1e-15);
        assert!((st.v_t - (ed[1] + R_J * 3.0 + R_B * 1.0)).abs() < 1e-15);
        assert!((st.delta + C).abs() < 1e-12 * C);
        for v in [st.delta, st.delta_dot, st.v_t, st.eps, st.eps_dot, st.omega] {
            assert!(v.is_finite());
        }
    }
    // |e| = 3e-12·c along −y (bearing at the origin, so e is exact): the real normal.
    let st = ClearanceState::compute(&ClearanceInput {
        r_j: [0.0, -3e-12 * C],
        r_b: [0.0, 0.0],
        v_j: ed,
        v_b: [0.0, 0.0],
        phi_dot_j: 3.0,
        phi_dot_b: -1.0,
        radius_j: R_J,
        radius_b: R_B,
    });
    assert_eq!(st.n, [0.0, -1.0]);
    assert_eq!(st.t, [1.0, 0.0]);
    // γ̇ = (e_x ė_y − e_y ė_x)/|e|² = ė_x/|e| (finite, large).
    let gamma_dot = ed[0] / (3e-12 * C);
    assert!(((2.0 - st.omega) / 2.0 - gamma_dot).abs() < 1e-12 * gamma_dot);
}
