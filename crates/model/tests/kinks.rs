//! Kink events of the revolute clearance joints' force laws (docs/model.md §7, scene field
//! `kink_events`) on the dry press (150 rpm, c = 0.1 mm):
//!
//! - every kink event sits on its kink (its event function is zero there to the location
//!   tolerance) and each kind the press's laws have fires;
//! - they leave the contact onsets and losses where they were;
//! - they give the fixed-step RK4 its order back through a contact: a C⁰ kink of the force
//!   stepped across costs a local error O(h²) (global order 2), a restart at it nothing;
//! - a scene without the field gets them exactly when a revolute clearance joint is dry and
//!   its laws have a kink (docs/model.md §7, "The default"); `true`/`false` win, and the
//!   field round-trips through the scene's JSON.

mod common;

use lash_model::Mechanism;
use lash_solver::{Atol, Method, OdeSystem, Output, Problem, SolverOptions, StepOutcome};

/// The dry press from t = 0 to `t_end`, with or without kink events.
fn dry(kinks: bool, t_end: f64) -> Mechanism {
    let mut v = common::dry_press_value();
    v["kink_events"] = serde_json::json!(kinks);
    v["revolutions"] = serde_json::Value::Null;
    v["t_end"] = serde_json::json!(t_end);
    common::build(&v).unwrap()
}

fn tight(method: Method) -> SolverOptions {
    SolverOptions {
        method,
        rtol: 1e-12,
        atol: Atol::Scalar(1e-16),
        output: Output::Final,
        ..Default::default()
    }
}

/// (t, kind) of every event of a run of `m` with `opts`, and the largest |g| of a triggering
/// function at its event state, each divided by its scale (d_max for δ − d_max, 1 for the
/// clip ratio, v₁² = 4e-8 m²/s² for the slip functions, c for δ).
fn events_and_residual(m: &Mechanism, opts: &SolverOptions) -> (Vec<(f64, &'static str)>, f64) {
    let p = Problem::new(m, opts).unwrap();
    let mut it = p
        .integrator(m.t_start(), m.t_end(), &m.initial_state())
        .unwrap();
    let mut g = vec![0.0; m.n_events()];
    let mut out = Vec::new();
    let mut worst = 0.0f64;
    loop {
        match it.step().unwrap() {
            StepOutcome::Event { t, hits, .. } => {
                m.events(t, it.y(), &mut g);
                for h in hits {
                    let kind = m.event_name(h.index).unwrap().0;
                    let scale = match kind {
                        "kink_full_damping" => 1e-5,
                        "kink_force_clip" => 1.0,
                        "kink_slip_v0" | "kink_slip_v1" => 4e-8,
                        _ => 1e-4,
                    };
                    worst = worst.max(g[h.index].abs() / scale);
                    out.push((t, kind));
                }
            }
            StepOutcome::StopTime { .. } => break,
            _ => {}
        }
    }
    (out, worst)
}

#[test]
fn kink_events_sit_on_their_kinks_and_leave_the_contacts_alone() {
    let t_end = 0.1;
    let (with, residual) = events_and_residual(&dry(true, t_end), &tight(Method::Dop853));
    let (without, _) = events_and_residual(&dry(false, t_end), &tight(Method::Dop853));
    assert!(residual < 1e-6, "|g|/scale at a kink event: {residual:.2e}");
    for kind in ["kink_full_damping", "kink_slip_v0", "kink_slip_v1"] {
        let n = with.iter().filter(|e| e.1 == kind).count();
        assert!(n >= 2, "{kind} fired {n} times");
    }
    // The same contact onsets and losses, at the same times: over these 0.1 s (seven contact
    // phases) the two runs differ only by integration error.
    let contacts = |ev: &[(f64, &str)]| -> Vec<f64> {
        ev.iter()
            .filter(|e| e.1 == "contact")
            .map(|e| e.0)
            .collect()
    };
    let (a, b) = (contacts(&with), contacts(&without));
    assert_eq!(a.len(), b.len(), "contact events {a:?} against {b:?}");
    assert_eq!(a.len(), 15);
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() < 1e-8, "contact event at {x} against {y}");
    }
}

/// Least-squares slope of log err against log h.
fn slope(h: &[f64], err: &[f64]) -> f64 {
    let n = h.len() as f64;
    let xs: Vec<f64> = h.iter().map(|v| v.ln()).collect();
    let ys: Vec<f64> = err.iter().map(|v| v.ln()).collect();
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

#[test]
fn rk4_keeps_its_order_through_a_contact_with_kink_events() {
    // The first contact phase (onset at 3.6 ms, full damping from 3.8 ms, four slip
    // reversals, loss at 22.1 ms) and a little free flight after it.
    let t_end = 0.0235;
    let steps = [4e-5, 2e-5, 1e-5, 5e-6];
    let mut orders = Vec::new();
    for kinks in [false, true] {
        let m = dry(kinks, t_end);
        let reference = common::run(&m, &tight(Method::Dop853)).y_final;
        let nq = reference.len() / 2;
        let err: Vec<f64> = steps
            .iter()
            .map(|&h| {
                let s = common::run(&m, &common::rk4(h, true, Output::Final));
                (0..nq)
                    .map(|i| (s.y_final[i] - reference[i]).abs())
                    .fold(0.0, f64::max)
            })
            .collect();
        let p = slope(&steps, &err);
        println!("kink events {kinks}: position errors {err:?}, order {p:.2}");
        orders.push(p);
    }
    // Theory: 2 across the C⁰ kinks, 4 with restarts at them. Measured: 0.9 and 3.2 (the
    // fit's points scatter by a factor of two around the line: the contact amplifies each
    // step's error by an amount that depends on where the steps fall).
    assert!(
        orders[0] < 2.0,
        "without kink events: order {:.2}",
        orders[0]
    );
    assert!(orders[1] > 2.7, "with kink events: order {:.2}", orders[1]);
}

/// The mechanism of the dry press with its clearance joint's laws and film replaced as given
/// (`None`: left as the press has them) and `kink_events` absent.
fn press_with(
    normal: Option<serde_json::Value>,
    friction: Option<serde_json::Value>,
    film: Option<serde_json::Value>,
) -> Mechanism {
    let mut v = common::dry_press_value();
    assert!(
        v.get("kink_events").is_none(),
        "the catalogue leaves it out"
    );
    let joint = v["joints"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find(|j| j["type"] == "clearance")
        .unwrap();
    for (key, value) in [("normal", normal), ("friction", friction), ("film", film)] {
        if let Some(value) = value {
            joint[key] = value;
        }
    }
    common::build(&v).unwrap()
}

#[test]
fn kink_events_are_on_by_default_exactly_for_a_dry_joint_whose_laws_have_a_kink() {
    use serde_json::json;
    let on = |m: &Mechanism| {
        let kinds: Vec<&str> = (0..m.n_events())
            .map(|i| m.event_name(i).unwrap().0)
            .collect();
        // The flag and the event list agree: with it, the kinks follow δ.
        assert_eq!(
            m.kink_events(),
            kinds.iter().any(|k| k.starts_with("kink_"))
        );
        m.kink_events()
    };
    // The dry press: IMPACT with c_max > 0 and Coulomb with v0 > 0, v1 > v0: on, all four.
    let dry = press_with(None, None, None);
    assert!(on(&dry));
    assert_eq!(dry.n_events(), 5);
    // Each kinked law alone turns them on; an elastic law without friction has no kink.
    let elastic = json!({"law": "lankarani_nikravesh", "k": 2.34e10, "restitution": 1.0});
    let no_friction = json!({"law": "none"});
    let coulomb = json!({"law": "coulomb", "mu": 0.01, "v0": 1e-4, "v1": 2e-4});
    let damped = json!({"law": "lankarani_nikravesh", "k": 2.34e10, "restitution": 0.8});
    for (normal, friction, expected) in [
        (elastic.clone(), no_friction.clone(), false),
        (elastic.clone(), coulomb.clone(), true),
        (damped.clone(), no_friction.clone(), true),
        (
            json!({"law": "impact", "k": 2.34e10, "c_max": 0.0, "d_max": 1e-5}),
            no_friction.clone(),
            false,
        ),
    ] {
        let m = press_with(Some(normal.clone()), Some(friction.clone()), None);
        assert_eq!(on(&m), expected, "{normal} {friction}");
    }
    // A film: off, whatever the laws (the lubricated press has all four kinks).
    let film = json!({"viscosity": 0.4, "length": 0.1});
    assert!(!on(&press_with(None, None, Some(film))));
    // The scene's word wins both ways.
    let mut v = common::dry_press_value();
    v["kink_events"] = json!(false);
    assert!(!on(&common::build(&v).unwrap()));
    let mut v = common::dry_press_value();
    assert_eq!(v["joints"][4]["type"], "clearance");
    v["joints"][4]["film"] = json!({"viscosity": 0.4, "length": 0.1});
    v["kink_events"] = json!(true);
    let lubricated = common::build(&v).unwrap();
    assert!(
        on(&lubricated) && lubricated.n_events() == 6,
        "δ, ε − ε_cap, four kinks"
    );
}

#[test]
fn kink_events_round_trip_through_the_scene_json() {
    // Absent stays absent (the automatic choice), and an explicit false is kept: it no longer
    // means the same as the field's absence.
    for given in [None, Some(false), Some(true)] {
        let mut v = common::dry_press_value();
        if let Some(b) = given {
            v["kink_events"] = serde_json::json!(b);
        }
        let scene = lash_model::Scene::from_json_str(&v.to_string()).unwrap();
        assert_eq!(scene.kink_events, given);
        let back: serde_json::Value = serde_json::from_str(&scene.to_json_pretty()).unwrap();
        assert_eq!(back.get("kink_events").and_then(|b| b.as_bool()), given);
        assert_eq!(
            lash_model::Scene::from_json_str(&back.to_string()).unwrap(),
            scene
        );
    }
}
