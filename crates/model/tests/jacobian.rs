//! The Jacobian ∂f/∂y that implicit methods use (central finite differences of the KKT
//! solution) against analytic derivatives of the contact, friction and film laws
//! (docs/model.md §3–§4) on a free journal in a ground bearing, where q̈ = force / mass.
mod common;
use common::{richardson, worst_row_error};
use faer::Mat;
use lash_model::{Mechanism, Scene};
use lash_solver::OdeSystem;
use serde_json::json;

const MASS: f64 = 2.0;
const INERTIA: f64 = 0.1;
const RB: f64 = 0.010;
const RJ: f64 = 0.009;
const C: f64 = RB - RJ;

fn journal(
    normal: serde_json::Value,
    friction: serde_json::Value,
    film: Option<serde_json::Value>,
) -> Mechanism {
    let mut joint = json!({"type": "clearance", "name": "j",
        "bearing": {"body": "ground", "at": [0.0, 0.0], "radius": RB},
        "journal": {"body": "pin", "point": "c", "radius": RJ},
        "normal": normal, "friction": friction});
    if let Some(f) = film {
        joint["film"] = f;
    }
    let v = json!({
        "bodies": [{"name": "pin", "mass": MASS, "inertia": INERTIA, "points": {"c": [0.0, 0.0]}}],
        "joints": [joint],
        "t_end": 1.0
    });
    Mechanism::from_scene(&Scene::from_json_str(&v.to_string()).unwrap()).unwrap()
}

fn jac(m: &Mechanism, y: &[f64]) -> Mat<f64> {
    let mut j = Mat::<f64>::zeros(6, 6);
    assert!(m.has_jacobian());
    m.jacobian(0.0, y, j.as_mut());
    // Upper blocks: ∂q̇/∂q = 0, ∂q̇/∂q̇ = I exactly.
    for r in 0..3 {
        for c in 0..6 {
            assert_eq!(j[(r, c)], if c == r + 3 { 1.0 } else { 0.0 });
        }
    }
    j
}

/// Compares the lower block with the expected rows (q̈ over y), relative to the row scale
/// (a row that is zero is compared with 1e-9 of the largest entry: rounding of the KKT solve).
fn check(j: &Mat<f64>, expect: [[f64; 6]; 3], tol: f64) {
    let global = expect.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    for r in 0..3 {
        let scale = expect[r]
            .iter()
            .fold(0.0f64, |a, v| a.max(v.abs()))
            .max(1e-9 * global);
        for c in 0..6 {
            let d = (j[(r + 3, c)] - expect[r][c]).abs();
            assert!(
                d <= tol * scale,
                "∂q̈{r}/∂y{c}: FD {} vs analytic {} (row scale {scale:e})",
                j[(r + 3, c)],
                expect[r][c]
            );
        }
    }
}

#[test]
fn impact_law_derivatives() {
    let (k, cmax, dmax) = (1e10, 1e3, 1e-4);
    let m = journal(
        json!({"law": "impact", "k": k, "c_max": cmax, "d_max": dmax}),
        json!({"law": "none"}),
        None,
    );
    let delta = 5e-5;
    let e = C + delta;
    let vx = 0.1;
    let y = [e, 0.0, 0.3, vx, 0.0, 0.0];
    let s = delta / dmax;
    let cd = cmax * s * s * (3.0 - 2.0 * s);
    let cd_p = cmax * 6.0 * s * (1.0 - s) / dmax;
    let f_n = k * delta.powf(1.5) + cd * vx;
    let mut expect = [[0.0; 6]; 3];
    expect[0][0] = -(1.5 * k * delta.sqrt() + cd_p * vx) / MASS;
    expect[0][3] = -cd / MASS;
    expect[1][1] = -f_n / (MASS * e);
    check(&jac(&m, &y), expect, 1e-6);
}

#[test]
fn coulomb_friction_derivatives() {
    let (k, cmax, dmax, mu) = (1e10, 1e3, 1e-4, 0.2);
    let m = journal(
        json!({"law": "impact", "k": k, "c_max": cmax, "d_max": dmax}),
        json!({"law": "coulomb", "mu": mu, "v0": 1e-4, "v1": 2e-4}),
        None,
    );
    let delta = 5e-5;
    let e = C + delta;
    let (vx, vy) = (0.1, 0.05); // slip v_T = vy > v1: full friction, F_T = −μ F_N
    let y = [e, 0.0, 0.0, vx, vy, 0.0];
    let s = delta / dmax;
    let cd = cmax * s * s * (3.0 - 2.0 * s);
    let cd_p = cmax * 6.0 * s * (1.0 - s) / dmax;
    let f_n = k * delta.powf(1.5) + cd * vx;
    let f_t = -mu * f_n;
    let dfn_dx = 1.5 * k * delta.sqrt() + cd_p * vx;
    let dfn_dy = cd * vy / e; // through δ̇ = n·ė, ∂n_y/∂e_y = 1/|e|
    let mut expect = [[0.0; 6]; 3];
    // ẍ = (−F_N n_x + F_T t_x)/m, t_x = −n_y
    expect[0][0] = -dfn_dx / MASS;
    expect[0][1] = (-dfn_dy - f_t / e) / MASS;
    expect[0][3] = -cd / MASS;
    // ÿ = (−F_N n_y + F_T t_y)/m, t_y = n_x
    expect[1][0] = -mu * dfn_dx / MASS;
    expect[1][1] = (-f_n / e - mu * dfn_dy) / MASS;
    expect[1][3] = -mu * cd / MASS;
    // φ̈ = R_J F_T / I (arm R_J n)
    expect[2][0] = -RJ * mu * dfn_dx / INERTIA;
    expect[2][1] = -RJ * mu * dfn_dy / INERTIA;
    expect[2][3] = -RJ * mu * cd / INERTIA;
    check(&jac(&m, &y), expect, 1e-6);
}

#[test]
fn sommerfeld_film_derivatives() {
    let (mu, len) = (0.4, 0.02);
    let m = journal(
        json!({"law": "impact", "k": 1e10, "c_max": 0.0, "d_max": 1e-5}),
        json!({"law": "none"}),
        Some(json!({"model": "long_sommerfeld", "viscosity": mu, "length": len})),
    );
    let eps = 0.5;
    let e = eps * C;
    let vx = 0.01;
    let y = [e, 0.0, 0.0, vx, 0.0, 0.0];
    let s = 12.0 * std::f64::consts::PI * mu * len * RJ.powi(3) / (C * C);
    let one = 1.0 - eps * eps;
    let eps_dot = vx / C;
    let f_r = -s * eps_dot / one.powf(1.5);
    let dft_domega = s * eps / ((2.0 + eps * eps) * one.sqrt());
    let mut expect = [[0.0; 6]; 3];
    // ẍ = F_r/m: ∂/∂x through ε (∂ε/∂x = 1/c), ∂/∂ẋ through ε̇ (1/c).
    expect[0][0] = f_r * 3.0 * eps / one / C / MASS;
    expect[0][3] = -s / one.powf(1.5) / C / MASS;
    // ÿ = (F_r n_y + F_t t_y)/m with F_t = dF_t/dΩ · Ω, Ω = φ̇ − 2γ̇, γ̇ = ė_y/|e|.
    // ∂γ̇/∂e_y = −ė_x/|e|², so ∂Ω/∂y = 2 ẋ/|e|².
    expect[1][1] = (f_r / e + dft_domega * 2.0 * vx / (e * e)) / MASS;
    expect[1][4] = -2.0 / e * dft_domega / MASS;
    expect[1][5] = dft_domega / MASS;
    check(&jac(&m, &y), expect, 1e-6);
}

/// The press (150 rpm, c = 0.1 mm): constraints, a moving bearing (slider) and journal (rod),
/// the crank prescribed. States off the centred start: dry in contact (δ = 2e-5 m), lubricated
/// at ε = 0.5; the rod moved by (dx, dy) against the slider, all velocities perturbed. There f
/// is smooth on the scale 1e-5 m, and Richardson-extrapolated differences with h = 1e-7 m are
/// accurate to ~1e-8 relative; the Jacobian (differences in e, ė and closed forms) must agree
/// to 1e-6 of each row's scale.
#[test]
fn press_jacobian_matches_differences_of_f() {
    use lash_model::cases::{press_scene, PressJoint};
    for (joint, dx, dy) in [
        (PressJoint::Dry, 9.0e-5, -8.0e-5),
        (PressJoint::Lubricated, 3.0e-5, -4.0e-5),
    ] {
        // Lagrange–Baumgarte's Jacobian, in the absolute coordinates perturbed below
        // (minimal's: tests/minimal.rs).
        let mut scene = press_scene(joint, 150.0, 1e-4);
        scene.formulation = lash_model::FormulationName::LagrangeBaumgarte;
        let m = Mechanism::from_scene(&scene).unwrap();
        let mut y = m.initial_state();
        let pert = [
            dx, dy, 0.0, 0.0, 0.0, 0.0, 0.02, -0.01, 0.3, -0.05, 0.0, 0.0,
        ];
        for (v, p) in y.iter_mut().zip(pert) {
            *v += p;
        }
        let t = 0.05;
        let o = m.outputs(t, &y);
        let cl = &o.clearance[0];
        match joint {
            PressJoint::Dry => assert!(cl.delta > 1e-5 && cl.contact_force > 0.0, "{cl:?}"),
            _ => assert!((cl.eps - 0.5).abs() < 1e-9, "{cl:?}"),
        }
        let n = m.dim();
        let mut jac = Mat::<f64>::zeros(n, n);
        m.jacobian(t, &y, jac.as_mut());
        let reference = richardson(&m, t, &y, |_| 1e-7);
        let err = worst_row_error(&jac, &reference);
        assert!(err < 1e-6, "{joint:?}: worst relative error {err:e}");
    }
}

/// A lubricated journal almost centred in a ground bearing, |e| = 1e-6 c = 1e-9 m, moving
/// obliquely: the film force turns with n = e/|e|, so f varies on the scale |e|. The
/// Jacobian must match differences of f with steps 1e-4 |e| (possible here because y holds e
/// itself); an increment of 1e-8 in y, as plain differences of f take, would straddle e = 0.
#[test]
fn jacobian_near_the_centred_journal() {
    let m = journal(
        json!({"law": "impact", "k": 1e10, "c_max": 0.0, "d_max": 1e-5}),
        json!({"law": "none"}),
        Some(json!({"model": "long_gumbel", "viscosity": 0.4, "length": 0.02})),
    );
    let e = 1e-6 * C;
    let y = [0.6 * e, 0.8 * e, 0.0, 0.01, -0.02, 3.0];
    let mut jac = Mat::<f64>::zeros(6, 6);
    m.jacobian(0.0, &y, jac.as_mut());
    let reference = richardson(&m, 0.0, &y, |j| if j < 2 { 1e-4 * e } else { 1e-6 });
    let err = worst_row_error(&jac, &reference);
    assert!(err < 1e-6, "worst relative error {err:e}");
}

/// The clearance four-bar of cases/examples (a revolute joint between two integrated bodies,
/// rows with terms on two bodies, a moving clearance joint), mid-run: the closed-form
/// ∂q̈/∂q at fixed applied forces (the derivatives of Φ_q, γ and Φ̇ in the angles) and the
/// rest of the Jacobian agree with Richardson-extrapolated differences of f to 1e-6 of each
/// row's scale, and so do the velocity columns.
#[test]
fn jacobian_of_a_mechanism_with_two_body_joints_matches_differences_of_f() {
    use lash_solver::{solve, Output, SolverOptions};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/examples/fourbar_clearance.json");
    let m = Mechanism::from_scene(&lash_model::Scene::from_path(&path).unwrap()).unwrap();
    let t1 = m.t_start() + 0.3 * (m.t_end() - m.t_start());
    let o = SolverOptions {
        rtol: 1e-10,
        atol: lash_solver::Atol::Scalar(1e-13),
        output: Output::Final,
        ..SolverOptions::with_method(lash_solver::Method::Dop853)
    };
    let y = solve(&m, (m.t_start(), t1), &m.initial_state(), &o)
        .unwrap()
        .y_final;
    assert!(
        m.n_constraints() > 0 && m.integrated_bodies().len() >= 2,
        "a mechanism with joints between integrated bodies"
    );
    let n = m.dim();
    let mut jac = Mat::<f64>::zeros(n, n);
    m.jacobian(t1, &y, jac.as_mut());
    let reference = richardson(&m, t1, &y, |j| if j < n / 2 { 1e-7 } else { 1e-5 });
    let err = worst_row_error(&jac, &reference);
    assert!(err < 1e-6, "worst relative error {err:e}");
}

/// The augmented Lagrangian's Jacobian (docs/model.md §12: the direct KKT solve where Φ_q has
/// full row rank, the multiplier iteration where it has not) against Richardson differences
/// of f. The right-hand side iterates its multipliers to `tol`, so f is smooth only to about
/// tol · |q̈|: with tol = 1e-14 the differences carry about 1e-14 / h of each row's scale.
/// - the dry press in contact (the state of `press_jacobian_matches_differences_of_f`,
///   h = 1e-7 m: noise 1e-7) to 1e-5 of each row's scale;
/// - A02 N = 1, cranks at 1 rad, moving (smooth on the scale of its 1 m links, h = 1e-5:
///   noise 1e-9) to 1e-7 (the direct solve);
/// - the parallel cranks (three cranks on one bar: 12 equations of rank 11, the iteration's
///   path) at a moving state, likewise to 1e-7.
#[test]
fn augmented_lagrangian_jacobian_matches_differences_of_f() {
    use lash_model::cases::{press_scene, PressJoint};
    use lash_model::iftomm::{n_four_bar, parallel_cranks};
    use lash_model::FormulationName;
    let al = |mut s: Scene| {
        s.formulation = FormulationName::AugmentedLagrangian;
        s.augmented_lagrangian.tol = 1e-14;
        Mechanism::from_scene(&s).unwrap()
    };
    let check = |m: &Mechanism, t: f64, y: &[f64], h: f64, tol: f64, what: &str| {
        let n = m.dim();
        let mut jac = Mat::<f64>::zeros(n, n);
        m.jacobian(t, y, jac.as_mut());
        let reference = richardson(m, t, y, |_| h);
        let err = worst_row_error(&jac, &reference);
        eprintln!("{what}: worst relative error {err:.2e}");
        assert!(err < tol, "{what}: worst relative error {err:e}");
    };
    // The press in contact.
    let m = al(press_scene(PressJoint::Dry, 150.0, 1e-4));
    let mut y = m.initial_state();
    let pert = [
        9.0e-5, -8.0e-5, 0.0, 0.0, 0.0, 0.0, 0.02, -0.01, 0.3, -0.05, 0.0, 0.0,
    ];
    for (v, p) in y.iter_mut().zip(pert) {
        *v += p;
    }
    let o = m.outputs(0.05, &y);
    assert!(o.clearance[0].contact_force > 0.0);
    check(&m, 0.05, &y, 1e-7, 1e-5, "press, dry, in contact");
    // A02 N = 1 at θ = 1 rad (bodies: crank, coupler, crank), θ̇ = −2 rad/s.
    let m = al(n_four_bar(1, 1.0).0);
    let (th, w) = (1.0f64, -2.0);
    let (c, s) = (th.cos(), th.sin());
    let mut y = vec![0.0; m.dim()];
    y[..9].copy_from_slice(&[
        0.5 * c,
        0.5 * s,
        th,
        c + 0.5,
        s,
        0.0,
        1.0 + 0.5 * c,
        0.5 * s,
        th,
    ]);
    y[9..].copy_from_slice(&[
        -0.5 * s * w,
        0.5 * c * w,
        w,
        -s * w,
        c * w,
        0.0,
        -0.5 * s * w,
        0.5 * c * w,
        w,
    ]);
    check(&m, 0.0, &y, 1e-5, 1e-7, "A02 N = 1");
    // The parallel cranks from their initial state, moving.
    let m = al(parallel_cranks(1.0).0);
    let y = m.initial_state();
    assert!(y[y.len() / 2..].iter().any(|v| v.abs() > 0.1));
    check(&m, 0.0, &y, 1e-5, 1e-7, "parallel cranks (redundant)");
}

/// The augmented Lagrangian's Jacobian on a chain long enough for its batched direct solve
/// (130 pendulum links: m = 260 constraint rows, at least
/// `BATCHED_MIN_CONSTRAINTS` = 256; the columns go through faer's triangular solves and
/// matrix product 64 at a time) against Richardson differences of f, to the bound of the
/// smaller mechanisms above (1e-7 of each row: the differences' own error at h = 1e-5). The
/// chain turns rigidly about its pivot at ω = 1.5 rad/s (a consistent velocity: v = ω × r,
/// θ̇ = ω), so the velocity terms of ∂c are not zero.
#[test]
fn augmented_lagrangian_jacobian_of_a_long_chain_matches_differences_of_f() {
    let (links, l, omega) = (130usize, 0.1, 1.5);
    let bodies: Vec<_> = (0..links)
        .map(|i| {
            json!({"name": format!("l{i}"), "mass": 1.0, "inertia": l * l / 12.0,
                   "position": [l * i as f64 + l / 2.0, 0.0],
                   "points": {"A": [-l / 2.0, 0.0], "B": [l / 2.0, 0.0]}})
        })
        .collect();
    let mut joints = vec![json!({"type": "revolute", "name": "j0",
        "a": {"body": "l0", "point": "A"}, "b": {"body": "ground", "at": [0.0, 0.0]}})];
    for i in 1..links {
        joints.push(json!({"type": "revolute", "name": format!("j{i}"),
            "a": {"body": format!("l{}", i - 1), "point": "B"},
            "b": {"body": format!("l{i}"), "point": "A"}}));
    }
    let v = json!({"bodies": bodies, "joints": joints, "gravity": [0.0, -9.81], "t_end": 1.0,
                   "formulation": "augmented_lagrangian"});
    let mut s = Scene::from_json_str(&v.to_string()).unwrap();
    s.augmented_lagrangian.tol = 1e-14;
    let m = Mechanism::from_scene(&s).unwrap();
    let n = m.dim();
    let nq = n / 2;
    assert_eq!(nq, 3 * links);
    let mut y = m.initial_state();
    for i in 0..links {
        let x = y[3 * i];
        y[nq + 3 * i] = -omega * y[3 * i + 1];
        y[nq + 3 * i + 1] = omega * x;
        y[nq + 3 * i + 2] = omega;
    }
    let mut jac = Mat::<f64>::zeros(n, n);
    m.jacobian(0.0, &y, jac.as_mut());
    let reference = richardson(&m, 0.0, &y, |_| 1e-5);
    let err = worst_row_error(&jac, &reference);
    eprintln!("chain of {links}: worst relative error {err:.2e}");
    assert!(err < 1e-7, "worst relative error {err:e}");
}
