//! The hand-written minimal-coordinate press (`lash_benches::handwritten`) against the general
//! model: the same slider and rod accelerations at every step of a two-revolution trajectory.
//!
//! ```text
//! |Δẍ| ≤ 1e-12 · max(|ẍ|, r ω²) + 4 κ |f| / m_slider,    κ = ε_mach · |B| / min(|e|, |δ|)
//! |Δψ̈| ≤ 1e-12 · max(|ψ̈|, r ω²/l) + 4 κ |f| (l + R_J) / I_A,  f the clearance force
//! ```
//! Both compute the eccentricity e = B − P as the difference of two points about 0.36 m from
//! the crank pivot, so any two implementations may disagree by ε_mach·|B| in e: a relative
//! error κ in the direction of e (which the film's Ω and the force directions use) and in the
//! penetration δ (which the contact law uses). Near the centred start |e| → 0 and κ → 1; in
//! the second revolution of the lubricated press (ε ≈ 0.25) κ ≈ 2e-12. A formula that
//! differs (a wrong arm, sign, inertia or film term) shows up at 1e-4 and above.

use lash_benches::handwritten::HandPress;
use lash_model::cases::{press_scene, PressJoint};
use lash_model::{FormulationName, Mechanism, Scene};
use lash_solver::{solve, Atol, Method, Output, SolverOptions};

/// The scene in the paper's absolute coordinates (12 states: the hand-written press maps to
/// and from them), whatever the default formulation.
fn lb(mut scene: Scene) -> Scene {
    scene.formulation = FormulationName::LagrangeBaumgarte;
    scene
}

/// Largest |Δẍ| / bound and largest relative |Δẍ| / max(|ẍ|, r ω²) over the second revolution.
fn check(joint: PressJoint, c: f64) -> (f64, f64) {
    let lubricated = joint == PressJoint::Lubricated;
    let hand = HandPress::paper(150.0, c, lubricated);
    let m = Mechanism::from_scene(&lb(press_scene(joint, 150.0, c))).unwrap();
    let o = SolverOptions {
        method: Method::Dop853,
        rtol: 1e-8,
        atol: Atol::Scalar(1e-11),
        output: Output::Steps,
        ..Default::default()
    };
    let sol = solve(&m, (m.t_start(), m.t_end()), &m.initial_state(), &o).unwrap();
    let scale = hand.r * hand.omega * hand.omega;
    let (mut worst, mut worst_rel_rev2, mut in_contact) = (0.0f64, 0.0f64, 0);
    let period = 2.0 * std::f64::consts::PI / hand.omega;
    for k in 0..sol.len() {
        let t = sol.t[k];
        let y = HandPress::minimal_state(sol.state(k));
        let full = hand.full_state(t, &y);
        let out = m.outputs(t, &full);
        let cl = &out.clearance[0];
        let [psidd, xdd] = hand.accelerations(t, &y);
        let b_norm = full[3].abs().max(hand.l);
        let e_norm = cl.eps * hand.clearance();
        let kappa = (f64::EPSILON * b_norm / e_norm.min(cl.delta.abs())).min(1.0);
        // What a relative error κ in e can move: the clearance force, whose size (not only
        // its x component) matters, since an error in the direction of e turns it.
        let force = cl.contact_force.hypot(cl.friction_force) + cl.film_force;
        let bound = 1e-12 * xdd.abs().max(scale) + 4.0 * kappa * force / hand.m_slider;
        let dx = (xdd - out.slider_a.unwrap()).abs();
        worst = worst.max(dx / bound);
        // The rod: its angular acceleration has gravity and the pin's motion besides.
        let dpsi = (psidd - out.bodies[1].alpha).abs();
        let i_a = hand.i_rod + 0.25 * hand.m_rod * hand.l * hand.l;
        let bound_psi = 1e-12 * psidd.abs().max(scale / hand.l)
            + 4.0 * kappa * force * (hand.l + hand.rj) / i_a;
        worst = worst.max(dpsi / bound_psi);
        if t > period {
            worst_rel_rev2 = worst_rel_rev2.max(dx / xdd.abs().max(scale));
        }
        if cl.delta > 0.0 {
            in_contact += 1;
        }
    }
    assert!(sol.len() > 100);
    if !lubricated {
        assert!(
            in_contact > 50,
            "the dry run must test the contact forces: {in_contact}"
        );
    }
    (worst, worst_rel_rev2)
}

#[test]
fn the_hand_written_lubricated_press_equals_the_general_model() {
    let (worst, rel) = check(PressJoint::Lubricated, 1e-4);
    assert!(worst <= 1.0, "{worst} × the bound");
    // The journal at ε ≈ 0.25: κ ≈ 2e-12 allows about 1e-11 relative; measured 3e-12.
    assert!(rel < 1e-11, "second revolution: {rel:e} relative");
}

#[test]
fn the_hand_written_dry_press_equals_the_general_model() {
    let (worst, rel) = check(PressJoint::Dry, 1e-4);
    assert!(worst <= 1.0, "{worst} × the bound");
    assert!(rel < 1e-11, "second revolution: {rel:e} relative");
}

/// Stacked copies of the press run diffsol's BDF with the same steps, Newton iterations and
/// results as one copy (identical blocks see identical arithmetic, and the RMS error norm over
/// identical blocks is that of one up to its rounding), so that their wall time measures the
/// dimension alone: over the first 40 % of two revolutions at rtol 1e-8, the same accepted
/// steps and slider accelerations equal bit for bit. (Over whole runs the rounding of the norm
/// may flip a rare step decision: 1148 steps against 1146 at rtol 3.2e-10.)
#[test]
fn stacked_copies_take_the_same_steps_as_one_press() {
    use lash_benches::handwritten::{diffsol_bdf, diffsol_bdf_copies};
    let hand = HandPress::paper(150.0, 1e-4, true);
    let m = Mechanism::from_scene(&lb(press_scene(PressJoint::Lubricated, 150.0, 1e-4))).unwrap();
    let y0 = HandPress::minimal_state(&m.initial_state());
    let t_end = m.t_start() + 0.4 * (m.t_end() - m.t_start());
    let times: Vec<f64> = (0..=200)
        .map(|k| m.t_start() + (t_end - m.t_start()) * k as f64 / 200.0)
        .collect();
    let rtol = 1e-8;
    let one = diffsol_bdf(&hand, m.t_start(), y0, rtol, [rtol * 1e-3; 4], &times).unwrap();
    for copies in [1, 3] {
        let c =
            diffsol_bdf_copies(&hand, m.t_start(), y0, rtol, rtol * 1e-3, &times, copies).unwrap();
        assert_eq!(c.steps, one.steps, "{copies} copies");
        assert_eq!(c.slider_a, one.slider_a, "{copies} copies");
    }
    assert!(diffsol_bdf_copies(&hand, m.t_start(), y0, rtol, 1e-11, &times, 4).is_err());
}
