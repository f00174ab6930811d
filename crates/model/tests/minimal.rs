//! The minimal (joint-coordinate) formulation (docs/model.md §12): the same motion as
//! Lagrange–Baumgarte on the trees of the examples, the energy of a conservative scene kept,
//! and the Jacobian against differences of f (loop closures: tests/minimal_loops.rs).
mod common;
use common::{richardson, worst_row_error};
use faer::Mat;
use lash_model::cases::{press_scene, PressJoint};
use lash_model::{FormulationName, Mechanism, Scene};
use lash_solver::{solve, Atol, Method, OdeSystem, Output, SolverOptions};
use serde_json::json;

fn example(name: &str) -> Scene {
    Scene::from_path(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../cases/examples")
            .join(name),
    )
    .unwrap()
}

fn with(mut s: Scene, f: FormulationName) -> Mechanism {
    s.formulation = f;
    Mechanism::from_scene(&s).unwrap()
}

fn tight() -> SolverOptions {
    SolverOptions {
        rtol: 1e-10,
        atol: Atol::Scalar(1e-12),
        output: Output::Final,
        max_steps: 10_000_000,
        ..SolverOptions::with_method(Method::Dop853)
    }
}

/// The largest difference of the bodies' x, y, θ and rates between two outputs.
fn differ(a: &lash_model::Outputs, b: &lash_model::Outputs) -> f64 {
    let mut worst: f64 = 0.0;
    for (a, b) in a.bodies.iter().zip(&b.bodies) {
        for d in [
            a.x - b.x,
            a.y - b.y,
            a.theta - b.theta,
            a.vx - b.vx,
            a.vy - b.vy,
            a.omega - b.omega,
        ] {
            worst = worst.max(d.abs());
        }
    }
    worst
}

/// The scenes of the comparison: (what, scene, its degrees of freedom, time span).
fn trees() -> Vec<(&'static str, Scene, usize, f64)> {
    vec![
        // Rod angle and slider position: the crank is prescribed, the clearance joint a force.
        (
            "press, dry",
            press_scene(PressJoint::Dry, 150.0, 1e-4),
            2,
            0.2,
        ),
        (
            "press, lubricated",
            press_scene(PressJoint::Lubricated, 150.0, 1e-4),
            2,
            0.2,
        ),
        // link1's angle, and link2 free (only the clearance joint holds it).
        ("pendulum", example("pendulum.json"), 4, 0.5),
        // The coupler's angle (pinned to the prescribed crank) and the rocker's.
        ("four-bar", example("fourbar_clearance.json"), 2, 0.5),
    ]
}

/// On the trees of the examples, minimal's state holds the degrees of freedom only, its
/// initial state is the same mechanism as the assembled absolute one (every body's pose and
/// velocity to rounding), and integrated at rtol 1e-10 both formulations give the same motion:
/// every body's x, y, θ and rates at the end of the span, both at rtol 1e-12, differ by less
/// than Lagrange–Baumgarte's own error at rtol 1e-10 (its difference from itself at 1e-12):
/// the formulations give the same motion to the integration's tolerance (the dry press's
/// impacts amplify an error of the integration to ~1e-5 over 0.2 s; a wrong R or a_c would
/// differ by 1e-3 and more). At the initial state the accelerations and the driver torque
/// (Newton–Euler of the prescribed crank, from minimal's multipliers) agree to rounding; the
/// tree's constraint violation stays at rounding along the run.
#[test]
fn minimal_follows_lagrange_baumgarte_on_trees() {
    for (what, scene, dof, span) in trees() {
        let lb = with(scene.clone(), FormulationName::LagrangeBaumgarte);
        let mi = with(scene, FormulationName::Minimal);
        assert_eq!(mi.formulation_name(), "minimal");
        assert_eq!(mi.dim(), 2 * dof, "{what}");
        let t0 = lb.t_start();
        let (y_lb, y_mi) = (lb.initial_state(), mi.initial_state());
        let (o_lb, o_mi) = (lb.outputs(t0, &y_lb), mi.outputs(t0, &y_mi));
        for (a, b) in o_lb.bodies.iter().zip(&o_mi.bodies) {
            let d = [
                a.x - b.x,
                a.y - b.y,
                a.theta - b.theta,
                a.vx - b.vx,
                a.vy - b.vy,
            ];
            assert!(d.iter().all(|v| v.abs() < 1e-12), "{what} at t0: {d:?}");
            // The accelerations of the two formulations at the same state.
            let da = [a.ax - b.ax, a.ay - b.ay, a.alpha - b.alpha];
            let scale = 1.0 + a.ax.abs().max(a.ay.abs()).max(a.alpha.abs());
            assert!(
                da.iter().all(|v| v.abs() < 1e-8 * scale),
                "{what} at t0: {da:?}"
            );
        }
        for (a, b) in o_lb.driver_torques.iter().zip(&o_mi.driver_torques) {
            assert!(
                (a - b).abs() < 1e-8 * (1.0 + a.abs()),
                "{what}: torque {a} vs {b}"
            );
        }
        let t1 = t0 + span;
        let fine = SolverOptions {
            rtol: 1e-12,
            atol: Atol::Scalar(1e-14),
            ..tight()
        };
        let lb_coarse = solve(&lb, (t0, t1), &y_lb, &tight()).unwrap().y_final;
        let lb_fine = solve(&lb, (t0, t1), &y_lb, &fine).unwrap().y_final;
        let mi_fine = solve(&mi, (t0, t1), &y_mi, &fine).unwrap().y_final;
        let o_ref = lb.outputs(t1, &lb_fine);
        let o_mi = mi.outputs(t1, &mi_fine);
        let err_lb = differ(&lb.outputs(t1, &lb_coarse), &o_ref);
        let worst = differ(&o_mi, &o_ref);
        eprintln!(
            "{what}: minimal − lagrange_baumgarte at rtol 1e-12: {worst:.2e}; \
             lagrange_baumgarte's own error at rtol 1e-10: {err_lb:.2e}"
        );
        assert!(worst <= err_lb.max(1e-9), "{what}: {worst:e} > {err_lb:e}");
        assert!(
            o_mi.constraint_violation < 1e-12,
            "{what}: {}",
            o_mi.constraint_violation
        );
    }
}

/// Two 0.5 m links of 1 kg, the first pinned to the ground, the second hanging from the first
/// through an elastic clearance joint (no damping, friction or film): T + V (contact potential
/// included) is conserved. Chosen by the scene field `"formulation": "minimal"`; at rtol 1e-10
/// the energy drifts by less than 1e-7 of the largest kinetic energy over 1 s, through the
/// contacts (the same bar as energy.rs's conservative pendulum under RK4).
#[test]
fn a_conservative_scene_keeps_its_energy_in_joint_coordinates() {
    let mut v = common::clearance_double_pendulum(
        json!({"law": "impact", "k": 1e9, "c_max": 0.0, "d_max": 1e-5}),
        json!({"law": "none"}),
    );
    v["formulation"] = json!("minimal");
    let m = Mechanism::from_scene(&Scene::from_json_str(&v.to_string()).unwrap()).unwrap();
    assert_eq!(m.formulation_name(), "minimal");
    assert_eq!(m.dim(), 8);
    let opts = SolverOptions {
        output: Output::Steps,
        ..tight()
    };
    let sol = solve(&m, (0.0, 1.0), &m.initial_state(), &opts).unwrap();
    let energy = |k: usize| {
        let o = m.outputs(sol.t[k], sol.state(k));
        (o.kinetic_energy + o.potential_energy, o.kinetic_energy)
    };
    let (e0, _) = energy(0);
    let (mut drift, mut t_max, mut contact): (f64, f64, usize) = (0.0, 0.0, 0);
    for k in 0..sol.len() {
        let (e, kin) = energy(k);
        drift = drift.max((e - e0).abs());
        t_max = t_max.max(kin);
        let o = m.outputs(sol.t[k], sol.state(k));
        contact += usize::from(o.clearance[0].contact_force > 0.0);
    }
    eprintln!("drift {drift:.2e} of T_max {t_max:.3}, {contact} states in contact");
    assert!(t_max > 1.0 && contact > 0, "{t_max} {contact}");
    assert!(drift < 1e-7 * t_max, "drift {drift:e} of T_max {t_max}");
}

/// The Jacobian (forces' closed forms chained through R, the tree's geometry by central
/// differences: module doc of minimal/jacobian.rs) against Richardson differences of f:
/// - the press with the slider moved 1.2e-4 m off the centred journal (dry: in contact, δ =
///   2e-5 m; lubricated: 0.3e-4 m, ε = 0.3), at t_start, rates perturbed: f is smooth on
///   the scale 1e-5 m,
///   differences with h = 1e-7 are accurate to ~1e-8 of each row's scale;
/// - the pendulum and the four-bar mid-run (h = 1e-7: their contacts make f vary on the
///   scale 1e-5, where h = 1e-6 leaves a truncation of 1e-6; at 1e-7 the two agree to 1e-9).
///
/// Agreement to 1e-6 of each row's scale, as tests/jacobian.rs asks of Lagrange–Baumgarte
/// (measured: 4e-9 to 7e-10).
#[test]
fn minimal_jacobian_matches_differences_of_f() {
    let check = |m: &Mechanism, t: f64, y: &[f64], h: f64, what: &str| {
        let n = m.dim();
        let mut jac = Mat::<f64>::zeros(n, n);
        m.jacobian(t, y, jac.as_mut());
        let reference = richardson(m, t, y, |_| h);
        let err = worst_row_error(&jac, &reference);
        eprintln!("{what}: worst relative error {err:.2e}");
        assert!(err < 1e-6, "{what}: worst relative error {err:e}");
    };
    for (joint, shift) in [(PressJoint::Dry, 1.2e-4), (PressJoint::Lubricated, 0.3e-4)] {
        let m = with(press_scene(joint, 150.0, 1e-4), FormulationName::Minimal);
        let mut y = m.initial_state();
        // y = (φ_rod, σ_slider, φ̇_rod, σ̇_slider) in tree order: find σ by the slider's x.
        let t = m.t_start();
        let o0 = m.outputs(t, &y);
        let slider = m
            .scene()
            .bodies
            .iter()
            .position(|b| b.name == "slider")
            .unwrap();
        let mut k = 0;
        for j in 0..2 {
            let mut yp = y.clone();
            yp[j] += 1e-3;
            if (m.outputs(t, &yp).bodies[slider].x - o0.bodies[slider].x).abs() > 1e-4 {
                k = j;
            }
        }
        y[k] += shift;
        y[2] += 0.3;
        y[3] -= 0.05;
        let o = m.outputs(t, &y);
        let cl = &o.clearance[0];
        match joint {
            PressJoint::Dry => assert!(cl.delta > 1e-5 && cl.contact_force > 0.0, "{cl:?}"),
            _ => assert!(cl.eps > 0.2 && cl.eps < 0.9, "{cl:?}"),
        }
        check(&m, t, &y, 1e-7, &format!("press {joint:?}"));
    }
    for name in ["pendulum.json", "fourbar_clearance.json"] {
        let m = with(example(name), FormulationName::Minimal);
        let t1 = m.t_start() + 0.3 * (m.t_end() - m.t_start());
        let y = solve(&m, (m.t_start(), t1), &m.initial_state(), &tight())
            .unwrap()
            .y_final;
        check(&m, t1, &y, 1e-7, name);
    }
}

/// The state of `scene` under `f` at t (bdf, rtol 1e-10).
fn state_at(m: &Mechanism, t: f64) -> Vec<f64> {
    let opts = SolverOptions {
        rtol: 1e-10,
        atol: Atol::Scalar(1e-12),
        output: Output::Final,
        max_steps: 10_000_000,
        ..SolverOptions::with_method(Method::Bdf)
    };
    solve(m, (m.t_start(), t), &m.initial_state(), &opts)
        .unwrap()
        .y_final
}

/// ∂f/∂t in joint coordinates (minimal/jacobian.rs): time moves the prescribed crank and,
/// at fixed (θ, θ̇), the rod with it across the slider's film, so f_t ≈ 1e6 on the
/// lubricated press where Lagrange–Baumgarte's is ≈ 1e2. Mid-run (t = 0.05, 0.31, 0.55 s,
/// the film loaded; not t_start, where the journal sits at e = 0) the mechanism's own f_t
/// matches the Richardson extrapolation of central differences of f in t (steps 1e-7 and
/// 5e-8, error ≈ 1e-9 of the row) to 1e-8 of each row (measured 5e-10), and the dry press's
/// likewise. The difference Rodas5P took before (central, δ_t = ε^(1/3)·√t ≈ 1e-6 … 4e-6 s)
/// is off by more than 1e-4 of the row there (measured 3e-4, 1.6e-2, 1.1e-3): what cost it
/// 370× the steps of Lagrange–Baumgarte (`rodas5p_takes_the_steps_of_lagrange_baumgarte_under_minimal`).
#[test]
fn minimal_time_derivative_matches_differences_of_f() {
    for joint in [PressJoint::Lubricated, PressJoint::Dry] {
        // Without kink events (the dry press's default since docs/model.md §7, "The
        // default"): the states are those of the BDF path the bound was measured on (δ = 2.6e-6
        // and 1.4e-5 m at 0.31 and 0.55 s). With them the path reaches δ = 3.5e-5 m at 0.55 s,
        // where the extrapolated differences are themselves off by 4.4e-8 of the row: they
        // still converge to f_t as the step falls (1.8e-4 at 1e-7 s, 1.0e-5 at 1e-8 s).
        let mut scene = press_scene(joint, 150.0, 1e-4);
        scene.kink_events = Some(false);
        let m = with(scene, FormulationName::Minimal);
        assert!(m.has_time_derivative());
        for t in [0.05, 0.31, 0.55] {
            let y = state_at(&m, t);
            let n = y.len();
            let cd = |d: f64| {
                let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
                m.rhs(t + d, &y, &mut fp);
                m.rhs(t - d, &y, &mut fm);
                (0..n)
                    .map(|i| (fp[i] - fm[i]) / (2.0 * d))
                    .collect::<Vec<_>>()
            };
            let (a, b) = (cd(1e-7), cd(5e-8));
            let reference: Vec<f64> = (0..n).map(|i| (4.0 * b[i] - a[i]) / 3.0).collect();
            let mut ft = vec![0.0; n];
            m.time_derivative(t, &y, &mut ft);
            for i in 0..n {
                let scale = reference[i].abs().max(1.0);
                assert!(
                    (ft[i] - reference[i]).abs() < 1e-8 * scale,
                    "{joint:?} t = {t}: f_t[{i}] = {:e}, differences {:e}",
                    ft[i],
                    reference[i]
                );
            }
            if joint == PressJoint::Lubricated {
                let old = cd(f64::EPSILON.cbrt() * t.sqrt());
                let worst = (n / 2..n)
                    .map(|i| (old[i] - reference[i]).abs() / reference[i].abs())
                    .fold(0.0, f64::max);
                assert!(worst > 1e-4, "t = {t}: {worst:e}");
            }
        }
    }
}

/// Rodas5P under minimal takes the steps it takes under Lagrange–Baumgarte, up to what the
/// coordinates change: the same motion, over [t_start, 0.4] at rtol 1e-8, atol 1e-10 (bdf
/// takes 393 steps under minimal against 380 on the lubricated press). Measured with the
/// mechanism's ∂f/∂t: dry 3 534 against 3 380 (asserted ≤ 1.25×), lubricated 1 387 against
/// 339 (≤ 5×: the residue is not the derivatives — J f + f_t matches a directional
/// difference of f to 1e-11 of |f_t|, and five-point differences of the geometry take the
/// same steps — but the Rosenbrock's error in coordinates where the film's stiff direction
/// turns with t and θ). With the difference in t it was 124 833 against 339 (368×).
#[test]
fn rodas5p_takes_the_steps_of_lagrange_baumgarte_under_minimal() {
    for (joint, bound) in [(PressJoint::Dry, 1.25), (PressJoint::Lubricated, 5.0)] {
        let steps = |f: FormulationName| {
            let m = with(press_scene(joint, 150.0, 1e-4), f);
            let opts = SolverOptions {
                rtol: 1e-8,
                atol: Atol::Scalar(1e-10),
                output: Output::Final,
                max_steps: 10_000_000,
                ..SolverOptions::with_method(Method::Rodas5p)
            };
            solve(&m, (m.t_start(), 0.4), &m.initial_state(), &opts)
                .unwrap()
                .stats
                .accepted
        };
        let (mi, lb) = (
            steps(FormulationName::Minimal),
            steps(FormulationName::LagrangeBaumgarte),
        );
        assert!(
            (mi as f64) <= bound * lb as f64,
            "{joint:?}: {mi} steps under minimal, {lb} under lagrange_baumgarte"
        );
    }
}

/// The prescribed bodies' kinematics are kept between evaluations at the same t
/// (`Scratch::pres_t`): whatever came before — a right-hand side at another t, the events, the
/// Jacobian and ∂f/∂t (which move the prescribed bodies of their own copy to other times) —
/// a right-hand side, the events and the Jacobian at (t, y) give the bits of a mechanism built
/// afresh and evaluated there first (they are functions of (t, y) alone).
#[test]
fn kept_prescribed_kinematics_change_no_result() {
    let scene = press_scene(PressJoint::Lubricated, 150.0, 1e-4);
    let used = with(scene.clone(), FormulationName::Minimal);
    let y0 = used.initial_state();
    let n = y0.len();
    let at = |k: f64| -> Vec<f64> {
        y0.iter()
            .enumerate()
            .map(|(i, v)| v + 1e-5 * k * (1.0 + i as f64))
            .collect()
    };
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let eval = |m: &Mechanism, t: f64, y: &[f64]| {
        let mut dy = vec![0.0; n];
        m.rhs(t, y, &mut dy);
        let mut g = vec![0.0; m.n_events()];
        m.events(t, y, &mut g);
        let mut jac = Mat::<f64>::zeros(n, n);
        m.jacobian(t, y, jac.as_mut());
        let jac: Vec<f64> = (0..n * n).map(|k| jac[(k / n, k % n)]).collect();
        (bits(&dy), bits(&g), bits(&jac))
    };
    let mut scratch = vec![0.0; n];
    for (k, t) in [0.013, 0.05, 0.05, 0.0131, 0.013].into_iter().enumerate() {
        let y = at(k as f64);
        // Before: a right-hand side at another t and the same state, ∂f/∂t at t (its own
        // copy at t ± h), a right-hand side at t and another state.
        used.rhs(t + 1e-3, &y, &mut scratch);
        used.time_derivative(t, &at(7.0), &mut scratch);
        used.rhs(t, &at(9.0), &mut scratch);
        let fresh = with(scene.clone(), FormulationName::Minimal);
        assert_eq!(eval(&used, t, &y), eval(&fresh, t, &y), "t = {t}");
    }
}
