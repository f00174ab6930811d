//! Energy: a conservative scene (double pendulum, one elastic clearance joint, gravity, no
//! driver, damping, friction or film) keeps T + V (contact potential 2/5 K δ^{5/2} included);
//! with contact damping and friction the energy never grows and the dissipated power closes
//! the balance.
mod common;
use common::*;
use lash_model::{Mechanism, Scene};
use lash_solver::{OdeSystem, Output};
use serde_json::json;

/// Two 0.5 m links of 1 kg, the first pinned to the ground, the second hanging from the first
/// through a clearance joint (c = 1 mm, K = 1e9 N/m^1.5). Released from the horizontal.
fn pendulum(normal: serde_json::Value, friction: serde_json::Value) -> Mechanism {
    let v = clearance_double_pendulum(normal, friction);
    Mechanism::from_scene(&Scene::from_json_str(&v.to_string()).unwrap()).unwrap()
}

fn energy(m: &Mechanism, t: f64, y: &[f64]) -> (f64, f64) {
    let o = m.outputs(t, y);
    (o.kinetic_energy + o.potential_energy, o.kinetic_energy)
}

#[test]
fn conservative_double_pendulum_with_clearance_keeps_its_energy() {
    let m = pendulum(
        json!({"law": "impact", "k": 1e9, "c_max": 0.0, "d_max": 1e-5}),
        json!({"law": "none"}),
    );
    let h = 2e-6;
    let mut opts = rk4(h, true, Output::Steps);
    opts.max_steps = 10_000_000;
    let t0 = std::time::Instant::now();
    let sol = run(&m, &opts);
    let wall = t0.elapsed().as_secs_f64();
    let (e0, _) = energy(&m, 0.0, sol.state(0));
    let mut t_max: f64 = 0.0;
    let mut drift: f64 = 0.0;
    let mut contact_steps = 0;
    for k in (0..sol.len()).step_by(10) {
        let (e, kin) = energy(&m, sol.t[k], sol.state(k));
        t_max = t_max.max(kin);
        drift = drift.max((e - e0).abs());
        if m.outputs(sol.t[k], sol.state(k)).clearance[0].delta > 0.0 {
            contact_steps += 1;
        }
    }
    let onsets = sol
        .events
        .iter()
        .filter(|e| e.index == 0 && e.rising)
        .count();
    println!(
        "h = {h:e}: {} steps, {onsets} contact onsets, {contact_steps} sampled states in contact, \
         max |E − E0| = {drift:.3e} J, max T = {t_max:.3} J, relative {:.3e}, wall {wall:.2} s",
        sol.len(),
        drift / t_max
    );
    assert!(onsets >= 3, "the journal must hit the bearing repeatedly");
    assert!(drift <= 1e-6 * t_max);
}

#[test]
fn damping_and_friction_never_add_energy_and_close_the_balance() {
    let m = pendulum(
        json!({"law": "impact", "k": 1e9, "c_max": 2000.0, "d_max": 1e-5}),
        json!({"law": "coulomb", "mu": 0.3, "v0": 1e-4, "v1": 2e-4}),
    );
    let h = 2e-6;
    let mut opts = rk4(h, true, Output::Steps);
    opts.max_steps = 10_000_000;
    let sol = run(&m, &opts);
    let mut scale: f64 = 0.0;
    let mut prev = energy(&m, 0.0, sol.state(0)).0;
    let e0 = prev;
    let mut worst_rise: f64 = f64::NEG_INFINITY;
    // Dissipated energy by the trapezoidal rule on the step outputs.
    let diss = |k: usize| {
        let p = m.power(sol.t[k], sol.state(k));
        assert_eq!(p.driver, 0.0);
        assert!(p.contact_damping >= 0.0 && p.friction >= 0.0, "{p:?}");
        p.contact_damping + p.friction
    };
    let mut dissipated = 0.0;
    let mut d_prev = diss(0);
    let mut balance: f64 = 0.0;
    let mut total_friction = 0.0;
    for k in 1..sol.len() {
        let (e, kin) = energy(&m, sol.t[k], sol.state(k));
        scale = scale.max(kin);
        worst_rise = worst_rise.max(e - prev);
        prev = e;
        let d = diss(k);
        dissipated += 0.5 * (d + d_prev) * (sol.t[k] - sol.t[k - 1]);
        total_friction += m.power(sol.t[k], sol.state(k)).friction * (sol.t[k] - sol.t[k - 1]);
        d_prev = d;
        balance = balance.max((e0 - e - dissipated).abs());
    }
    println!(
        "largest energy rise between steps {worst_rise:.3e} J (scale {scale:.3} J), energy lost \
         {:.4} J, dissipated {dissipated:.4} J (friction {total_friction:.4} J), balance error {balance:.3e} J",
        e0 - prev
    );
    assert!(worst_rise <= 1e-9 * scale);
    assert!(
        e0 - prev > 1e-3 * scale,
        "damping and friction must remove energy"
    );
    assert!(total_friction > 0.0);
    assert!(balance <= 1e-5 * scale);
}

#[test]
fn restitution_laws_store_the_impact_velocity_at_contact_onset() {
    let m = pendulum(
        json!({"law": "lankarani_nikravesh", "k": 1e9, "restitution": 0.5}),
        json!({"law": "none"}),
    );
    let mut opts = rk4(2e-6, true, Output::Final);
    opts.max_steps = 10_000_000;
    let sol = lash_solver::solve(&m, (0.0, 0.2), &m.initial_state(), &opts).unwrap();
    let first = sol
        .events
        .iter()
        .find(|e| e.index == 0 && e.rising)
        .expect("an impact within 0.2 s");
    assert!(first.t > 0.0);
    let v = m.impact_velocities()[0];
    assert!(v > 0.0, "δ̇⁻ = {v}");
    // c_r = 0.5 dissipates: the energy after 0.2 s is below the start.
    let (e0, _) = energy(&m, 0.0, &m.initial_state());
    let (e1, _) = energy(&m, 0.2, &sol.y_final);
    assert!(e1 < e0);
    // δ, and the clip of F_N: a dry joint whose restitution law (c_r < 1) can clip gets that
    // kink event by default (docs/model.md §7, "The default"); the law adds no other.
    assert_eq!(m.n_events(), 2);
    assert_eq!(m.event_name(1).unwrap().0, "kink_force_clip");
}
