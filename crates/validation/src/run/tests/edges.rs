//! Runs at the edges of the model (issue 23): states outside the range of the clearance
//! joints' laws end in a typed solver error naming the joint, the time and the depth;
//! milder excursions are counted in summary.json (docs/model.md §3.5).

use std::path::PathBuf;

use serde_json::{json, Value};

use crate::error::Error;
use crate::report::trajectory::Columns;
use crate::run::case::Case;
use crate::run::plan::RunRequest;
use crate::run::prepare::Prepared;
use crate::run::simulate::{simulate, simulate_into};
use lash_model::Mechanism;
use lash_solver::{Method, SolveError};

fn prepared(name: &str, scene: &Value) -> Prepared {
    Prepared::load(Case::from_json_bytes(name, scene.to_string().into_bytes()).unwrap()).unwrap()
}

fn press(stem: &str) -> Value {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/press")
        .join(format!("{stem}.json"));
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}

/// rtol 1e-8, or a step of 0.1 ms for a fixed-step method.
fn request(p: &Prepared, method: Method, t_end: f64) -> RunRequest {
    let (rtol, step) = if method.is_fixed_step() {
        (None, Some(1e-4))
    } else {
        (Some(1e-8), None)
    };
    let mut r = RunRequest::new(p.options_for(method, rtol, step, None).unwrap());
    r.t_end = Some(t_end);
    r
}

/// The failure of a run that must leave the range of a law: its time, state and reason.
fn law_failure(p: &Prepared, r: &RunRequest) -> (f64, Vec<f64>, String) {
    let mut rows = Columns::new();
    match simulate_into(p, r, &mut rows) {
        Err(Error::Solver(SolveError::LawOutOfRange { t, y, reason })) => (t, y, reason),
        Err(e) => panic!("expected LawOutOfRange, got {e}"),
        Ok(r) => panic!(
            "expected LawOutOfRange, the run ended: {:?}",
            r.summary.law_range
        ),
    }
}

/// The depth of the first clearance joint in `reason` ("penetration X m reached").
fn depth_in(reason: &str) -> f64 {
    let tail = reason.split("penetration ").nth(1).unwrap();
    tail.split(' ').next().unwrap().parse().unwrap()
}

/// A free body whose point J sits in a bearing on the ground (no gravity): the journal starts
/// centred and moves at `v` along x, so δ(t) = v t − c, less what the contact force
/// K δ^{3/2} (K = 1 N/m^{1.5}, 1.4e-3 N at 1.3 cm on 1 kg) takes: to first order in K,
/// n K v^{3/2} τ^{7/2} / (m · 5/2 · 7/2) with τ = t − c/v (n = 1 contact; 2 for the block,
/// whose two leading corners touch), 3e-8 m by τ = 0.013 s.
fn free_journal(v: f64) -> Value {
    json!({
        "bodies": [{"name": "body", "mass": 1.0, "inertia": 0.01, "points": {"J": [0.0, 0.0]}}],
        "joints": [{"type": "clearance", "name": "loose",
                    "bearing": {"body": "ground", "at": [0.0, 0.0], "radius": 0.0101},
                    "journal": {"body": "body", "point": "J", "radius": 0.01},
                    "normal": {"law": "impact", "k": 1.0, "c_max": 0.0, "d_max": 1e-5},
                    "friction": {"law": "none"},
                    "initial_eccentricity_rate": [v, 0.0]}],
        "gravity": [0.0, 0.0],
        "t_end": 0.1
    })
}

/// The same motion across a prismatic guide: a block 2 cm wide, 0.1 mm of clearance on each
/// side, crossing at `v`: its leading corners' gap is v t − c, and the limit half its width.
fn free_block(v: f64) -> Value {
    json!({
        "bodies": [{"name": "block", "mass": 1.0, "inertia": 0.01, "points": {"C": [0.0, 0.0]}}],
        "joints": [{"type": "prismatic_clearance", "name": "guide",
                    "guide": {"body": "ground", "at": [0.0, 0.0], "direction": [1.0, 0.0],
                              "width": 0.0202},
                    "block": {"body": "block", "point": "C", "length": 0.1, "width": 0.02},
                    "normal": {"law": "impact", "k": 1.0, "c_max": 0.0, "d_max": 1e-5},
                    "friction": {"law": "none"}, "initial_offset_rate": v}],
        "gravity": [0.0, 0.0],
        "t_end": 0.1
    })
}

#[test]
fn a_journal_through_its_bearing_ends_the_run_at_the_journal_radius() {
    // Free flight: the first accepted step end with δ = v t − c ≥ R_J (t ≥ 0.0101 s at
    // 1 m/s) ends the run, naming the joint; the depth is the free-flight one.
    let (v, c, rj) = (1.0, 1e-4, 0.01);
    for (name, scene) in [("journal", free_journal(v)), ("block", free_block(v))] {
        let p = prepared(name, &scene);
        for method in [Method::Dopri54, Method::Bdf, Method::Rk4] {
            let (t, y, reason) = law_failure(&p, &request(&p, method, 0.1));
            let depth = depth_in(&reason);
            assert!(reason.contains(if name == "journal" {
                "'loose'"
            } else {
                "'guide'"
            }));
            assert!(t >= (rj + c) / v, "{name} {method:?}: t = {t}");
            assert!(depth >= rj, "{name} {method:?}: {depth}");
            let (n, tau) = (if name == "journal" { 1.0 } else { 2.0 }, t - c / v);
            let free = v * t - c - n * v.powf(1.5) * tau.powf(3.5) / (2.5 * 3.5);
            assert!(
                (depth - free).abs() < 1e-9,
                "{name}: {depth} at {t}, {free}"
            );
            // The state is the one at t: its own depth.
            if name == "journal" {
                let m = Mechanism::from_scene(p.scene().unwrap()).unwrap();
                let o = m.outputs(t, &y);
                assert_eq!(o.clearance[0].delta, depth);
            }
        }
    }
}

#[test]
fn the_dry_press_with_a_soft_contact_ends_in_a_typed_error() {
    // Issue 23: K = 1 N/m^1.5 let the journal run 0.72 m deep (14.5 R_J) and exit 0.
    let mut s = press("dry_150rpm_c0.1");
    let j = s["joints"]
        .as_array()
        .unwrap()
        .iter()
        .position(|j| j["type"] == "clearance")
        .unwrap();
    s["joints"][j]["normal"]["k"] = json!(1.0);
    let p = prepared("soft", &s);
    let (t, _, reason) = law_failure(&p, &request(&p, Method::Bdf, 0.8));
    assert!(reason.contains("'rod_slider'"), "{reason}");
    assert!(depth_in(&reason) >= 0.0499, "{reason}");
    assert!(t > 0.0 && t < 0.8, "{t}");
}

#[test]
fn excursions_beyond_the_clearance_and_the_film_are_counted() {
    // The paper's dry press at c = 0.1 mm: its Hertz deflection under the contact forces of
    // the impacts, (F/K)^{2/3} with F ≈ 3e4–6e4 N and K = 2.34e10, is 0.1–0.2 mm: deeper
    // than 0.1 mm of clearance (the excursions are counted), within 0.5 mm.
    for (stem, beyond) in [("dry_150rpm_c0.1", true), ("dry_150rpm_c0.5", false)] {
        let p = prepared(stem, &press(stem));
        let r = simulate(&p, &request(&p, Method::Bdf, 0.8)).unwrap();
        let lr = r.summary.law_range.clone().unwrap();
        assert_eq!(lr.len(), 1);
        let l = &lr[0];
        assert_eq!(
            (l.joint.as_str(), l.film_beyond_range),
            ("rod_slider", None)
        );
        assert_eq!(l.depth_limit, 0.05 - l.clearance);
        assert_eq!(l.depth_max > l.clearance, beyond, "{l:?}");
        assert_eq!(l.beyond_clearance > 0, beyond, "{l:?}");
    }
    // A lubricated joint counts its film's excursions (ε ≥ 1 − η: the journal on the wall);
    // at c = 0.1 mm the film carries the load (ε < 1 throughout), at 0.5 mm it does not.
    for (stem, crushed) in [
        ("lubricated_150rpm_c0.1", false),
        ("lubricated_150rpm_c0.5", true),
    ] {
        let p = prepared(stem, &press(stem));
        let r = simulate(&p, &request(&p, Method::Bdf, 0.8)).unwrap();
        let l = &r.summary.law_range.as_ref().unwrap()[0];
        let n = l.film_beyond_range.unwrap();
        assert_eq!(n > 0, crushed, "{l:?}");
        assert_eq!(l.depth_max >= -1e-12 * 0.05, crushed, "{l:?}");
    }
    // No clearance joint, no record.
    let p = prepared("ideal", &press("ideal_150rpm"));
    let r = simulate(&p, &request(&p, Method::Bdf, 0.1)).unwrap();
    assert!(r.summary.law_range.is_none());
}

/// Two links of length 1 m between two ground pivots 1.41 m apart: a truss (no degree of
/// freedom) that assembles bent, with its elbow at (0.6, 0.8).
fn truss() -> Value {
    let (a1, a2) = (0.8f64.atan2(0.6), (-0.6f64).atan2(0.8));
    let link = |name: &str, at: [f64; 2], angle: f64| {
        json!({"name": name, "mass": 1.0, "inertia": 0.125, "position": at, "angle": angle,
               "points": {"L": [-0.5, 0.0], "R": [0.5, 0.0]}})
    };
    let pin =
        |name: &str, a: Value, b: Value| json!({"type": "revolute", "name": name, "a": a, "b": b});
    json!({
        "bodies": [link("link1", [0.3, 0.4], a1), link("link2", [1.0, 0.5], a2)],
        "joints": [
            pin("O", json!({"body": "link1", "point": "L"}), json!({"body": "ground", "at": [0.0, 0.0]})),
            pin("P", json!({"body": "link1", "point": "R"}), json!({"body": "link2", "point": "L"})),
            pin("Q", json!({"body": "link2", "point": "R"}), json!({"body": "ground", "at": [1.4, 0.2]}))
        ],
        "gravity": [0.0, -9.81],
        "t_end": 0.1
    })
}

#[test]
fn a_singular_configuration_inside_a_step_is_a_typed_error() {
    // Issue 23: a non-finite power inside an accepted step that jumped over a singular
    // configuration was "internal error" (exit 1). With both links stretched along x the
    // three x-equations of the pins read x1 − 0.5 = 0, (x1 + 0.5) − (x2 − 0.5) = 0,
    // x2 + 0.5 = 1.4: their rows e1, e1 − e4, e4 are dependent (row O − row P − row Q = 0,
    // exactly in f64), so Φ_q has lost rank and S = Φ_q M⁻¹ Φ_qᵀ is singular.
    // Lagrange–Baumgarte's singularity (`auto` gives this loop to the augmented Lagrangian,
    // which solves through it).
    let mut scene = truss();
    scene["formulation"] = json!("lagrange_baumgarte");
    let p = prepared("truss", &scene);
    let mech = Mechanism::from_scene(p.scene().unwrap()).unwrap();
    let y0 = mech.initial_state();
    assert_eq!(y0.len(), 12);
    assert!(mech.acceleration_solvable(0.0, &y0));
    let mut y = vec![0.0; 12];
    (y[0], y[3]) = (0.5, 1.5);
    assert!(!mech.acceleration_solvable(0.0, &y));
    let bug = || Error::Internal("energy: power terms [NaN, 0, 0, 0] not finite".into());
    match crate::run::mechanism::singular_or(&mech, bug(), 0.25, &y, (0.0, 0.5)) {
        Error::Solver(SolveError::StateRejected {
            t,
            y: ys,
            kind,
            reason,
        }) => {
            assert_eq!((t, ys, kind), (0.25, y.clone(), "singular_configuration"));
            assert!(
                reason.starts_with("singular configuration at t = "),
                "{reason}"
            );
            assert!(reason.contains("inside the accepted step"), "{reason}");
        }
        other => panic!("expected a singular configuration, got {other}"),
    }
    // A right-hand side that is not finite at such a state (the solver's NonFiniteState)
    // is the same typed error; at a state the model can evaluate it stays NonFiniteState.
    let nf = |y: &[f64]| {
        Error::Solver(SolveError::NonFiniteState {
            t: 0.25,
            y: y.to_vec(),
        })
    };
    match crate::run::mechanism::singular_rhs(&mech, nf(&y)) {
        Error::Solver(SolveError::StateRejected { kind, reason, .. }) => {
            assert_eq!(kind, "singular_configuration");
            assert!(reason.contains("rank of Φ_q drops"), "{reason}");
        }
        other => panic!("expected a singular configuration, got {other}"),
    }
    match crate::run::mechanism::singular_rhs(&mech, nf(&y0)) {
        Error::Solver(SolveError::NonFiniteState { .. }) => {}
        other => panic!("expected NonFiniteState, got {other}"),
    }
    // At a state the model can evaluate, a non-finite output stays what it is: a bug.
    let e = crate::run::mechanism::singular_or(&mech, bug(), 0.0, &y0, (0.0, 0.5));
    assert_eq!(e.kind(), crate::error::ErrorKind::Bug);
    // And the truss at rest runs (no degree of freedom: it stays where it is).
    let r = simulate(&p, &request(&p, Method::Bdf, 0.1)).unwrap();
    assert!(r.summary.law_range.is_none());
}

/// A wall-clock budget that runs out during set-up ends it at the next check
/// (lash_model's build phases, `lash_solver::interrupt::deadline_scope`): the solver's
/// BudgetExhausted at the scene's start time with no state, naming the phase and the budget,
/// not a scene error; without the scope the same scene sets up.
#[test]
fn a_budget_that_runs_out_in_set_up_stops_the_set_up() {
    let scene = press("dry_150rpm_c0.1");
    let case = || Case::from_json_bytes("press", scene.to_string().into_bytes()).unwrap();
    let passed = std::time::Instant::now();
    let err = {
        let _scope = lash_solver::interrupt::deadline_scope(Some((passed, 0.5)));
        match Prepared::load(case()) {
            Err(e) => e,
            Ok(_) => panic!("set-up past its deadline went on"),
        }
    };
    match err {
        Error::Solver(SolveError::BudgetExhausted { t, y, reason }) => {
            assert_eq!(t, 0.0);
            assert!(y.is_empty(), "{y:?}");
            assert_eq!(
                reason,
                "wall-clock budget of 0.5 s used during set-up (checking the scene)"
            );
        }
        e => panic!("{e}"),
    }
    // The scope ended with its block: the same case sets up.
    assert!(Prepared::load(case()).is_ok());
}
