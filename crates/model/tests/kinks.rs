//! Kink events of the revolute clearance joints' force laws (docs/model.md §7, scene field
//! `kink_events`) on the dry press (150 rpm, c = 0.1 mm):
//!
//! - every kink event sits on its kink (its event function is zero there to the location
//!   tolerance) and each kind the press's laws have fires;
//! - they leave the contact onsets and losses where they were;
//! - they give the fixed-step RK4 its order back through a contact: a C⁰ kink of the force
//!   stepped across costs a local error O(h²) (global order 2), a restart at it nothing.

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
