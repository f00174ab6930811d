//! The benchmarks of cases/iftomm/ against their one-degree-of-freedom references
//! (lash_model::iftomm), with the augmented Lagrangian (docs/model.md §12).
//!
//! ```text
//! A02 N-four-bar   B0 = (cos θ, sin θ): x and y within 1e-6 m of the reference at rtol 1e-10
//!                  (the benchmark's own "high precision" bar is 1e-3); energy drift < 1e-8
//!                  of the total energy
//! A01 pendulum     the bob at (l cos θ, l sin θ) within 1e-6 m; energy drift < 1e-8
//! parallel cranks  every crank angle within 1e-6 rad of θ (redundant: rank 11 of 12)
//! ```
//! The same targets hold under the minimal formulation with its loop closures (joint
//! coordinates on the spanning tree, the closing joints enforced by the augmented Lagrangian
//! on the reduced system: minimal/loops.rs), whose state is the tree's coordinates only.

use lash_model::iftomm::{n_four_bar, parallel_cranks, simple_pendulum, OneDof};
use lash_model::{FormulationName, FormulationStats, Mechanism, Scene};
use lash_solver::{solve, Atol, Method, SolveError, SolverOptions};

struct Run {
    t: Vec<f64>,
    /// Per step: the outputs' body poses (x, y, θ) and the energy.
    poses: Vec<Vec<[f64; 3]>>,
    energy: Vec<f64>,
    violation: f64,
    /// Length of the state.
    dim: usize,
    /// The formulation's iteration statistics.
    stats: Option<FormulationStats>,
}

fn run(scene: &Scene, method: Method, rtol: f64) -> Result<Run, String> {
    run_as(scene, FormulationName::AugmentedLagrangian, method, rtol)
}

fn run_as(
    scene: &Scene,
    formulation: FormulationName,
    method: Method,
    rtol: f64,
) -> Result<Run, String> {
    let mut scene = scene.clone();
    scene.formulation = formulation;
    let m = Mechanism::from_scene(&scene).map_err(|e| e.to_string())?;
    let y0 = m.initial_state();
    let opts = SolverOptions {
        method,
        rtol,
        atol: Atol::Scalar(rtol * 1e-2),
        max_steps: 2_000_000,
        ..Default::default()
    };
    let sol = solve(&m, (m.t_start(), m.t_end()), &y0, &opts).map_err(|e| e.to_string())?;
    let mut out = Run {
        t: sol.t.clone(),
        poses: Vec::new(),
        energy: Vec::new(),
        violation: 0.0,
        dim: y0.len(),
        stats: None,
    };
    for k in 0..sol.len() {
        let o = m.outputs(sol.t[k], sol.state(k));
        out.poses
            .push(o.bodies.iter().map(|b| [b.x, b.y, b.theta]).collect());
        out.energy.push(o.kinetic_energy + o.potential_energy);
        out.violation = out.violation.max(o.constraint_violation);
    }
    out.stats = m.formulation_stats();
    Ok(out)
}

/// Largest |angle difference| wrapped to (−π, π].
fn angle_err(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(2.0 * std::f64::consts::PI);
    d.min(2.0 * std::f64::consts::PI - d)
}

/// Max |B0 − reference| over the steps (B0 = the tip of crank 0 = (cos θ, sin θ)), from the
/// pose of crank 0 (body 0, its centre at ½ (cos θ, sin θ)), and the relative energy drift.
fn check_crank_tip(r: &Run, reference: &OneDof, tip: f64) -> (f64, f64) {
    let refs = reference.solve(&r.t);
    let mut err = 0.0f64;
    for (p, th) in r.poses.iter().zip(&refs) {
        let [cx, cy, phi] = p[0];
        let (bx, by) = (cx + 0.5 * tip * phi.cos(), cy + 0.5 * tip * phi.sin());
        let (rx, ry) = (tip * th[0].cos(), tip * th[0].sin());
        err = err.max((bx - rx).abs()).max((by - ry).abs());
    }
    let e0 = reference.energy(reference.theta0, reference.omega0);
    let drift = r
        .energy
        .iter()
        .map(|e| (e - r.energy[0]).abs())
        .fold(0.0, f64::max)
        / e0.abs().max(r.energy[0].abs());
    (err, drift)
}

/// A02 over `t_end` at rtol 1e-10: B0 within 1e-6 m of the reference, energy drift below
/// 1e-8, no parallelogram flipped.
fn a02_meets_its_targets(n: usize, t_end: f64) {
    a02_meets_its_targets_as(FormulationName::AugmentedLagrangian, n, t_end);
}

fn a02_meets_its_targets_as(formulation: FormulationName, n: usize, t_end: f64) -> Run {
    let (scene, reference) = n_four_bar(n, t_end);
    let r = run_as(&scene, formulation, Method::Dop853, 1e-10).unwrap();
    let (err, drift) = check_crank_tip(&r, &reference, 1.0);
    eprintln!("A02 N = {n}, {t_end} s: B0 error {err:.3e} m, energy drift {drift:.3e}");
    assert!(err < 1e-6, "N = {n}: B0 error {err:e}");
    assert!(drift < 1e-8, "N = {n}: energy drift {drift:e}");
    assert!(r.violation < 1e-6, "N = {n}: violation {:e}", r.violation);
    // Every crank keeps the angle of crank 0 (to 1e-5 rad; a flip is π apart).
    for p in &r.poses {
        for i in 1..=n {
            assert!(angle_err(p[2 * i][2], p[0][2]) < 1e-5);
        }
    }
    r
}

#[test]
fn a02_n_four_bar_n1_and_n2_follow_the_one_dof_reference() {
    // 20 s as published: about 15 horizontal (singular) positions.
    a02_meets_its_targets(1, 20.0);
    a02_meets_its_targets(2, 20.0);
}

/// The published case, N = 40 over 20 s (about 200 s of wall time: run it with
/// `cargo test --release -p lash-model --test iftomm -- --ignored`).
#[test]
#[ignore]
fn a02_n_four_bar_n40_follows_the_one_dof_reference() {
    a02_meets_its_targets(40, 20.0);
}

/// The published case under bdf at rtol 1e-10, whose Newton matrix takes the `kkt` path
/// (`auto` from 300 unknowns on one cluster: n = 486) with ∂ρ/∂y in closed form
/// (crates/model/src/kkt.rs): B0 within 5e-5 m of the reference, energy drift below 2e-7,
/// no parallelogram flipped (ignored by default as the dop853 run above: about 10 s). bdf's
/// own error at this tolerance over 20 s is above dop853's 1e-6: measured 1.3e-5 m and drift
/// 5.6e-8 with ∂ρ/∂y by the coloured differences, 1.5e-5 m and 6.9e-8 with the closed form
/// (the Newton matrix moves the steps, not the accuracy); the benchmark's "high precision"
/// bar is 1e-3 m.
#[test]
#[ignore]
fn a02_n_four_bar_n40_under_bdf_on_the_kkt_path_follows_the_one_dof_reference() {
    let (scene, reference) = n_four_bar(40, 20.0);
    let m = Mechanism::from_scene(&scene).unwrap();
    let o = SolverOptions::with_method(Method::Bdf);
    let p = lash_solver::Problem::new(&m, &o).unwrap();
    assert!(p.diffsol().unwrap().is_kkt());
    let r = run_as(
        &scene,
        FormulationName::AugmentedLagrangian,
        Method::Bdf,
        1e-10,
    )
    .unwrap();
    let (err, drift) = check_crank_tip(&r, &reference, 1.0);
    eprintln!("A02 N = 40, bdf on the kkt path: B0 error {err:.3e} m, energy drift {drift:.3e}");
    assert!(err < 5e-5, "B0 error {err:e}");
    assert!(drift < 2e-7, "energy drift {drift:e}");
    for p in &r.poses {
        for i in 1..=40 {
            assert!(angle_err(p[2 * i][2], p[0][2]) < 1e-5);
        }
    }
}

#[test]
fn a02_n_four_bar_every_adaptive_method_keeps_the_branch() {
    // 20 s as published, through about 15 singular positions; Lagrange–Baumgarte ends at
    // the first in a typed error (lagrange_baumgarte_stops_at_the_first_singular_configuration;
    // before that check it stalled or, with bdf, flipped to the anti-parallelogram).
    every_adaptive_method_keeps_the_branch(FormulationName::AugmentedLagrangian);
}

/// A02 N = 1 over 20 s at rtol 1e-8 under `formulation` with every adaptive method: exit 0,
/// the cranks never π apart, B0 within 1e-2 m of the reference.
fn every_adaptive_method_keeps_the_branch(formulation: FormulationName) {
    let (scene, reference) = n_four_bar(1, 20.0);
    for method in [
        Method::Dop853,
        Method::Rodas5p,
        Method::Bdf,
        Method::Tsit54,
        Method::Dopri54,
        Method::Trbdf2,
        Method::Bs32,
        Method::Esdirk34,
    ] {
        let r = run_as(&scene, formulation, method, 1e-8)
            .unwrap_or_else(|e| panic!("{formulation:?} {method:?}: {e}"));
        let (err, _) = check_crank_tip(&r, &reference, 1.0);
        eprintln!("A02 N = 1, {formulation:?} {method:?}: B0 error {err:.3e} m");
        // No branch switch: the anti-parallelogram puts the cranks π apart.
        for p in &r.poses {
            assert!(
                angle_err(p[2][2], p[0][2]) < 1e-4,
                "{method:?}: cranks {} and {} rad",
                p[0][2],
                p[2][2]
            );
        }
        // A branch switch is about 1 m off; at rtol 1e-8 over 20 s the global error of the
        // methods is 2e-7 (dopri54) to 3.2e-3 (bs32, third order) under the augmented
        // Lagrangian, 1e-8 (tsit54) to 4.6e-3 (esdirk34) under minimal.
        assert!(err < 1e-2, "{method:?}: B0 error {err:e}");
    }
}

#[test]
fn lagrange_baumgarte_stops_at_the_first_singular_configuration() {
    // A02 N = 1 with Lagrange–Baumgarte and bdf used to exit 0 with the cranks π apart (the
    // parallelogram turned into an anti-parallelogram at the first horizontal position,
    // t ≈ 0.708 s, where Φ_q loses a rank). It now ends there in a typed error naming it.
    let (mut scene, reference) = n_four_bar(1, 20.0);
    scene.formulation = FormulationName::LagrangeBaumgarte;
    let m = Mechanism::from_scene(&scene).unwrap();
    // The first time the reference reaches θ = 0 (cranks horizontal): θ(t) from π/2 down.
    let ts: Vec<f64> = (0..=20_000).map(|k| k as f64 * 1e-4).collect();
    let th = reference.solve(&ts);
    let t_sing = ts[th.iter().position(|x| x[0] <= 0.0).unwrap()];
    for method in [Method::Bdf, Method::Dop853, Method::Rodas5p] {
        let opts = SolverOptions {
            method,
            rtol: 1e-8,
            atol: Atol::Scalar(1e-10),
            max_steps: 2_000_000,
            ..Default::default()
        };
        let e = solve(&m, (0.0, m.t_end()), &m.initial_state(), &opts).unwrap_err();
        let SolveError::StateRejected {
            t, kind, reason, ..
        } = &e
        else {
            panic!("{method:?}: expected a singular configuration, got {e}");
        };
        assert_eq!(*kind, "singular_configuration", "{method:?}: {reason}");
        assert!(
            reason.contains("lagrange_baumgarte cannot pass it; use augmented_lagrangian"),
            "{reason}"
        );
        // Stopped at the first horizontal position: at a state within 1e-4 rad of it (ρ ≈ θ²
        // < 1e-8; θ̇ ≈ −4.9 rad/s there) or at the end of the step that crossed it (these
        // steps are shorter than 0.05 s; the next singular position is 1.3 s later).
        assert!(
            *t > t_sing - 1e-3 && *t < t_sing + 0.05,
            "{method:?}: t = {t}, singular at {t_sing}"
        );
    }
}

#[test]
fn a01_simple_pendulum_follows_its_reference() {
    let (scene, reference) = simple_pendulum();
    let r = run(&scene, Method::Dop853, 1e-10).unwrap();
    let refs = reference.solve(&r.t);
    let mut err = 0.0f64;
    for (p, th) in r.poses.iter().zip(&refs) {
        err = err
            .max((p[0][0] - th[0].cos()).abs())
            .max((p[0][1] - th[0].sin()).abs());
    }
    let drift = r
        .energy
        .iter()
        .map(|e| (e - r.energy[0]).abs())
        .fold(0.0, f64::max)
        / (reference.k * lash_model::iftomm::G);
    eprintln!("A01: bob error {err:.3e} m, energy drift {drift:.3e} of m g l");
    assert!(err < 1e-6, "{err:e}");
    assert!(drift < 1e-8, "{drift:e}");
}

#[test]
fn redundant_parallel_cranks_follow_the_one_dof_reference() {
    let (scene, reference) = parallel_cranks(5.0);
    // Lagrange–Baumgarte refuses the redundant set; the augmented Lagrangian runs it.
    let mut lb = scene.clone();
    lb.formulation = FormulationName::LagrangeBaumgarte;
    let e = Mechanism::from_scene(&lb).unwrap_err().to_string();
    assert!(e.contains("rank 11"), "{e}");
    let r = run(&scene, Method::Dop853, 1e-10).unwrap();
    let refs = reference.solve(&r.t);
    let mut err = 0.0f64;
    for (p, th) in r.poses.iter().zip(&refs) {
        for crank in &p[..3] {
            err = err.max(angle_err(crank[2], th[0]));
        }
    }
    eprintln!("parallel cranks: crank angle error {err:.3e} rad");
    assert!(err < 1e-6, "{err:e}");
}

#[test]
fn the_scene_files_are_the_generators_scenes() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../cases/iftomm");
    for (name, want) in [
        ("a01_pendulum", simple_pendulum().0),
        ("a02_n1", n_four_bar(1, 20.0).0),
        ("a02_n2", n_four_bar(2, 20.0).0),
        ("a02_n40", n_four_bar(40, 20.0).0),
        ("parallel_cranks", parallel_cranks(10.0).0),
    ] {
        let got = Scene::from_path(format!("{dir}/{name}.json")).unwrap();
        assert_eq!(got, want, "cases/iftomm/{name}.json");
    }
}

#[test]
fn contradictory_constraints_are_refused_naming_the_joints() {
    // The third crank's ground pin at x = 5 m instead of 2 m: its tip is at least 2 m from
    // the first crank's tip (within 1 m of x = 0), the bar's end pins are 2 m apart — no pose
    // meets every equation. Redundant constraints are accepted (the test above);
    // contradictory ones are an error naming the joints.
    let (scene, _) = parallel_cranks(1.0);
    let mut text = serde_json::to_value(&scene).unwrap();
    text["joints"][2]["b"]["at"] = serde_json::json!([5.0, 0.0]);
    let bad = Scene::from_json_str(&text.to_string()).unwrap();
    let e = Mechanism::from_scene(&bad).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("contradictory"), "{msg}");
    assert!(msg.contains("joints["), "{msg}");
    // The equations left unmet are those of the loop through the moved pin.
    assert!(msg.contains("ground2") || msg.contains("bar2"), "{msg}");
}

#[test]
fn minimal_with_loop_closures_meets_the_a02_targets() {
    // The A02 targets above (B0 within 1e-6 m of the 1-DOF reference at rtol 1e-10, energy
    // drift below 1e-8, violation below 1e-6, no parallelogram flipped) under the minimal
    // formulation: the 2N + 1 rods are a tree of 2N + 1 angles from the ground pins, and the
    // N joints of the last crank's windows close the loops (2N rows on the reduced system).
    for n in [1, 2] {
        let r = a02_meets_its_targets_as(FormulationName::Minimal, n, 20.0);
        // The state holds the tree's coordinates only: 2N + 1 angles and their rates (the
        // augmented Lagrangian's holds 3 (2N + 1) coordinates and their rates).
        assert_eq!(r.dim, 2 * (2 * n + 1), "N = {n}");
        // The closures iterate as the augmented Lagrangian does and report it: every
        // evaluation runs the iteration and its refinement (core.rs, `AlCore::refine`), each
        // at least two iterates (its convergence test compares two).
        let s = r.stats.expect("minimal with loops reports its iterations");
        eprintln!("A02 N = {n} minimal: {s:?}");
        assert!(
            s.evaluations > 0 && s.iterations >= 4 * s.evaluations,
            "{s:?}"
        );
    }
}

#[test]
fn minimal_with_loop_closures_runs_the_redundant_parallel_cranks() {
    // Three cranks and a bar: a tree of 4 angles, and the bar's pins on cranks 2 and 3 close
    // two loops with 4 rows of rank 3 (redundant), which the augmented Lagrangian's
    // iteration takes on the reduced system as it does on the absolute one.
    let (scene, reference) = parallel_cranks(5.0);
    let r = run_as(&scene, FormulationName::Minimal, Method::Dop853, 1e-10).unwrap();
    assert_eq!(r.dim, 2 * 4);
    let refs = reference.solve(&r.t);
    let mut err = 0.0f64;
    for (p, th) in r.poses.iter().zip(&refs) {
        for crank in &p[..3] {
            err = err.max(angle_err(crank[2], th[0]));
        }
    }
    eprintln!("parallel cranks, minimal: crank angle error {err:.3e} rad");
    assert!(err < 1e-6, "{err:e}");
}

#[test]
fn minimal_refuses_contradictory_closures_naming_the_joints() {
    // The scene of contradictory_constraints_are_refused_naming_the_joints under minimal: the
    // closures are checked at assembly as the augmented Lagrangian's constraints are.
    let (scene, _) = parallel_cranks(1.0);
    let mut text = serde_json::to_value(&scene).unwrap();
    text["joints"][2]["b"]["at"] = serde_json::json!([5.0, 0.0]);
    text["formulation"] = serde_json::json!("minimal");
    let bad = Scene::from_json_str(&text.to_string()).unwrap();
    let msg = Mechanism::from_scene(&bad).unwrap_err().to_string();
    assert!(msg.contains("contradictory"), "{msg}");
    assert!(msg.contains("joints["), "{msg}");
    assert!(msg.contains("ground2") || msg.contains("bar2"), "{msg}");
}

#[test]
fn minimal_with_loop_closures_keeps_the_branch_with_every_adaptive_method() {
    // The test above under minimal: 20 s through about 15 singular positions at rtol 1e-8.
    every_adaptive_method_keeps_the_branch(FormulationName::Minimal);
}
