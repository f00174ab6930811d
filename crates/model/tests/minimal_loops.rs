//! The minimal formulation with loop closures (docs/model.md §12, minimal/loops.rs): joint
//! coordinates on the spanning tree of the ideal joints, the joints that close a loop kept as
//! constraints on the reduced system by the augmented Lagrangian. The IFToMM targets (A02
//! N = 1, 2, the parallel cranks, contradictory closures) are in tests/iftomm.rs; here a
//! general four-bar's energy, Andrews' mechanism against the augmented Lagrangian and the
//! test set's reference, and the Jacobian against differences of f.
mod common;
use common::{richardson, worst_row_error};
use faer::Mat;
use lash_model::{FormulationName, Mechanism, Outputs, Scene};
use lash_solver::{solve, Atol, Method, OdeSystem, Output, SolverOptions};
use serde_json::json;

fn scene_at(rel: &str) -> Scene {
    Scene::from_path(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)).unwrap()
}

fn with(mut s: Scene, f: FormulationName) -> Mechanism {
    s.formulation = f;
    Mechanism::from_scene(&s).unwrap()
}

fn tight(rtol: f64, atol: f64, output: Output) -> SolverOptions {
    SolverOptions {
        rtol,
        atol: Atol::Scalar(atol),
        output,
        max_steps: 10_000_000,
        ..SolverOptions::with_method(Method::Dop853)
    }
}

/// The crank-rocker of cases/examples/fourbar_clearance.json with its clearance joint made an
/// ideal revolute joint and without its driver: a free Grashof four-bar (crank 0.1 m,
/// coupler 0.35 m, rocker 0.3 m, ground 0.4 m) released at rest under gravity, 2 s. It is
/// conservative, and no configuration on its way is singular.
fn closed_four_bar() -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/examples/fourbar_clearance.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let joints = v["joints"].as_array_mut().unwrap();
    joints[4] = json!({
        "type": "revolute",
        "name": "coupler_rocker",
        "a": {"body": "coupler", "point": "B"},
        "b": {"body": "rocker", "point": "B"}
    });
    joints.remove(1);
    let o = v.as_object_mut().unwrap();
    o.remove("roles");
    o.remove("revolutions");
    o.insert("t_end".into(), json!(2.0));
    Scene::from_json_str(&v.to_string()).unwrap()
}

#[test]
fn a_closed_four_bar_keeps_its_energy() {
    // T + V of a conservative mechanism is constant; at rtol 1e-10 its drift stays below
    // 1e-8 of the total energy (V from y = 0: the target for the conservative
    // benchmarks). The tree: crank and rocker from the ground, the coupler from the crank;
    // the coupler–rocker pin closes the loop (2 rows on 3 angles).
    let m = with(closed_four_bar(), FormulationName::Minimal);
    assert_eq!(m.formulation_name(), "minimal");
    assert_eq!(m.dim(), 2 * 3);
    let sol = solve(
        &m,
        (m.t_start(), m.t_end()),
        &m.initial_state(),
        &tight(1e-10, 1e-12, Output::Steps),
    )
    .unwrap();
    let energy = |k: usize| {
        let o = m.outputs(sol.t[k], sol.state(k));
        (
            o.kinetic_energy + o.potential_energy,
            o.kinetic_energy,
            o.constraint_violation,
        )
    };
    let (e0, _, _) = energy(0);
    let (mut drift, mut t_max, mut viol): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for k in 0..sol.len() {
        let (e, kin, v) = energy(k);
        drift = drift.max((e - e0).abs());
        t_max = t_max.max(kin);
        viol = viol.max(v);
    }
    eprintln!(
        "closed four-bar: E = {e0:.4} J, drift {:.2e} of it, T_max {t_max:.3} J, violation \
         {viol:.2e} m, {} steps",
        drift / e0.abs(),
        sol.len()
    );
    // It moves: the energy is exchanged, not sitting still.
    assert!(t_max > 0.1 * e0.abs(), "{t_max} of {e0}");
    assert!(drift < 1e-8 * e0.abs(), "drift {drift:e} of {e0}");
    // The closure is held (the augmented Lagrangian's bound in tests/iftomm.rs).
    assert!(viol < 1e-6, "{viol:e}");
}

/// The bodies' x, y, θ and rates of two outputs: the largest difference relative to the
/// largest value of its kind (positions, angles, rates).
fn relative_difference(a: &Outputs, b: &Outputs) -> f64 {
    let mut worst: f64 = 0.0;
    let mut scale = [0.0f64; 3];
    for b in &b.bodies {
        scale[0] = scale[0].max(b.x.abs()).max(b.y.abs());
        scale[1] = scale[1].max(b.theta.abs());
        scale[2] = scale[2].max(b.vx.abs()).max(b.vy.abs()).max(b.omega.abs());
    }
    for (a, b) in a.bodies.iter().zip(&b.bodies) {
        for (d, k) in [
            (a.x - b.x, 0),
            (a.y - b.y, 0),
            (a.theta - b.theta, 1),
            (a.vx - b.vx, 2),
            (a.vy - b.vy, 2),
            (a.omega - b.omega, 2),
        ] {
            worst = worst.max(d.abs() / scale[k]);
        }
    }
    worst
}

#[test]
fn andrews_under_minimal_matches_the_augmented_lagrangian() {
    // Andrews' squeezing mechanism (seven bodies, ten revolute joints: a tree of 7 angles and
    // three closing joints, 6 rows) at t = 0.03 s, both formulations under DOP853 at
    // rtol = atol = 1e-12 as tests/andrews.rs runs it (where the augmented Lagrangian meets
    // the test set's reference to 1e-6 relative). The two solve the same ODE on the
    // constraint manifold in different coordinates; their difference is the two runs' global
    // errors, which at this tolerance are far below the reference's 1e-6 bar: 1e-8 of each
    // quantity's scale leaves a margin over the measured 3e-11.
    let s = scene_at("../../cases/andrews/andrews.json");
    let mi = with(s.clone(), FormulationName::Minimal);
    let al = with(s, FormulationName::AugmentedLagrangian);
    assert_eq!(mi.dim(), 2 * 7);
    assert_eq!(al.dim(), 2 * 21);
    let opts = tight(1e-12, 1e-12, Output::Final);
    let y_mi = solve(&mi, (0.0, 0.03), &mi.initial_state(), &opts)
        .unwrap()
        .y_final;
    let y_al = solve(&al, (0.0, 0.03), &al.initial_state(), &opts)
        .unwrap()
        .y_final;
    let (o_mi, o_al) = (mi.outputs(0.03, &y_mi), al.outputs(0.03, &y_al));
    let d = relative_difference(&o_mi, &o_al);
    eprintln!(
        "andrews: minimal vs augmented Lagrangian {d:.2e}, violation {:.2e} m",
        o_mi.constraint_violation
    );
    assert!(d < 1e-8, "{d:e}");
    assert!(o_mi.constraint_violation < 1e-6);
}

/// The Jacobian (the tree's closed forms chained through R, the tree's geometry and the
/// closing rows' ρ and σ by central differences, each column the differentiated KKT system:
/// minimal/jacobian.rs, minimal/loops.rs) against Richardson differences of f, mid-run on the
/// closed four-bar, A02 N = 1 and Andrews: agreement to 1e-6 of each row's scale, as
/// tests/jacobian.rs asks of Lagrange–Baumgarte. The steps of the differences are smooth-scale
/// (1e-4: these mechanisms have no contact) and leave f's rounding (the iteration's floor,
/// ~1e-11 relative at penalty 1e4; A02's scene sets 1e7: ~1e-9, h = 1e-3 there) below 1e-7.
#[test]
fn loop_closure_jacobian_matches_differences_of_f() {
    let (a02, _) = lash_model::iftomm::n_four_bar(1, 20.0);
    for (what, scene, t1, h) in [
        ("closed four-bar", closed_four_bar(), 0.4, 1e-4),
        ("A02 N = 1", a02, 0.3, 1e-3),
        (
            "andrews",
            scene_at("../../cases/andrews/andrews.json"),
            0.01,
            1e-4,
        ),
    ] {
        let m = with(scene, FormulationName::Minimal);
        let y = solve(
            &m,
            (m.t_start(), t1),
            &m.initial_state(),
            &tight(1e-10, 1e-12, Output::Final),
        )
        .unwrap()
        .y_final;
        let n = m.dim();
        let mut jac = Mat::<f64>::zeros(n, n);
        m.jacobian(t1, &y, jac.as_mut());
        let reference = richardson(&m, t1, &y, |j| h * (1.0 + y[j].abs()));
        let err = worst_row_error(&jac, &reference);
        eprintln!("{what}: worst relative error {err:.2e}");
        assert!(err < 1e-6, "{what}: worst relative error {err:e}");
    }
}

/// The ideal press (no clearance: crank prescribed, rod, slider on its line) is a loop: the
/// slider hangs from the rod in the tree, and its translational joint closes the loop (2 rows
/// on 2 angles: no degree of freedom left). At the assembled initial state Φ and Φ̇ vanish to
/// rounding, so both formulations solve the same KKT system; the iteration and its
/// refinement reach its solution where Φ_θ has full rank, so the accelerations and the driver
/// torque (the crank's Newton–Euler balance, from the tree rows' multipliers after the
/// closing rows' λ*) equal Lagrange–Baumgarte's to 1e-8 of their scale, as
/// tests/minimal.rs asks on trees.
#[test]
fn the_ideal_press_under_minimal_has_lagrange_baumgartes_accelerations_and_torque() {
    use lash_model::cases::{press_scene, PressJoint};
    for rpm in [150.0, 2000.0] {
        let scene = press_scene(PressJoint::Ideal, rpm, 1e-4);
        let lb = with(scene.clone(), FormulationName::LagrangeBaumgarte);
        let mi = with(scene, FormulationName::Minimal);
        assert_eq!(mi.dim(), 2 * 2);
        let t0 = lb.t_start();
        let (o_lb, o_mi) = (
            lb.outputs(t0, &lb.initial_state()),
            mi.outputs(t0, &mi.initial_state()),
        );
        for (a, b) in o_lb.bodies.iter().zip(&o_mi.bodies) {
            let da = [a.ax - b.ax, a.ay - b.ay, a.alpha - b.alpha];
            let scale = 1.0 + a.ax.abs().max(a.ay.abs()).max(a.alpha.abs());
            assert!(da.iter().all(|v| v.abs() < 1e-8 * scale), "{rpm}: {da:?}");
        }
        assert!(!o_lb.driver_torques.is_empty());
        for (a, b) in o_lb.driver_torques.iter().zip(&o_mi.driver_torques) {
            eprintln!("ideal press {rpm} rpm: driver torque {a} (LB) vs {b} (minimal)");
            assert!((a - b).abs() < 1e-8 * (1.0 + a.abs()), "{rpm}: {a} vs {b}");
        }
    }
}
