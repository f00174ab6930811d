//! The Jacobian's sparsity pattern (`Mechanism::jacobian_pattern`, crates/model/src/jacobian.rs)
//! against the dense Jacobians: every entry outside the pattern is exactly 0 in the model's
//! closed-form ∂f/∂y and in forward differences of the right-hand side, on the press, a
//! chain, and free bodies coupled in pairs by springs, a rotational spring, a clearance joint
//! and a short chain, under each formulation. Exactly 0: a body outside a cluster takes no
//! part in its evaluation (its block of the constraint solve is its own), so perturbing it
//! leaves the cluster's f bit for bit; a coupling missing from the pattern fails here.
use faer::Mat;
use lash_model::cases::{press_scene, PressJoint};
use lash_model::{Mechanism, Scene};
use lash_solver::OdeSystem;
use serde_json::{json, Value};

fn mech(v: &Value) -> Mechanism {
    Mechanism::from_scene(&Scene::from_json_str(&v.to_string()).unwrap()).unwrap()
}

/// Free bodies b0…b9 and a two-link chain c0–c1 pinned to the ground: b0–b1 a spring, b2–b3
/// a rotational spring, b4–b5 a dry clearance joint, b6 a force whose magnitude is a table
/// of the spring's length (a reference through an element), b7 a spring to the ground,
/// b8, b9 alone. Clusters: {b0, b1, b6}, {b2, b3}, {b4, b5}, {b7}, {b8}, {b9}, {c0, c1}.
fn clusters(formulation: &str) -> Value {
    let mut bodies: Vec<Value> = (0..10)
        .map(|i| {
            json!({"name": format!("b{i}"), "mass": 1.0 + 0.1 * i as f64, "inertia": 0.1,
                   "position": [i as f64, 0.1 * i as f64], "velocity": [0.3, -0.2 * i as f64],
                   "angular_velocity": 0.5,
                   "points": {"p": [0.05, 0.02], "c": [0.0, 0.0]}})
        })
        .collect();
    for i in 0..2 {
        bodies.push(
            json!({"name": format!("c{i}"), "mass": 1.0, "inertia": 0.01,
            "position": [0.1 * i as f64 + 0.05, -5.0], "angular_velocity": 1.0,
            "points": {"A": [-0.05, 0.0], "B": [0.05, 0.0]}}),
        );
    }
    json!({
        "bodies": bodies,
        "joints": [
            {"type": "revolute", "name": "c0g", "a": {"body": "c0", "point": "A"},
             "b": {"body": "ground", "at": [0.0, -5.0]}},
            {"type": "revolute", "name": "c01", "a": {"body": "c0", "point": "B"},
             "b": {"body": "c1", "point": "A"}},
            {"type": "clearance", "name": "cl",
             "bearing": {"body": "b4", "point": "c", "radius": 0.01},
             "journal": {"body": "b5", "point": "c", "radius": 0.009},
             "normal": {"law": "impact", "k": 1e9, "c_max": 2000.0, "d_max": 1e-5},
             "friction": {"law": "coulomb", "mu": 0.1, "v0": 1e-4, "v1": 2e-4}}
        ],
        "forces": [
            {"type": "spring_damper", "name": "s01", "a": {"body": "b0", "point": "p"},
             "b": {"body": "b1", "point": "p"}, "stiffness": 1e3, "damping": 2.0,
             "free_length": 0.5},
            {"type": "rotational_spring_damper", "name": "r23", "a": "b2", "b": "b3",
             "stiffness": 10.0, "damping": 0.1, "free_angle": 0.2},
            {"type": "force", "name": "f6", "body": "b6", "direction": [0.0, 1.0],
             "table": {"input": {"of": "length", "element": "s01"},
                       "points": [[0.0, 0.0], [10.0, 5.0]]}},
            {"type": "spring_damper", "name": "s7", "a": {"body": "b7", "point": "p"},
             "b": {"body": "ground", "at": [7.0, 2.0]}, "stiffness": 50.0}
        ],
        "gravity": [0.0, -9.81],
        "formulation": formulation,
        "t_end": 1.0
    })
}

/// Checks that the closed-form Jacobian and forward differences vanish outside the pattern,
/// and that each is nonzero somewhere inside it off the q̇ = v identity (the test sees the
/// couplings it guards); returns the pattern's entry count.
fn check(m: &Mechanism, what: &str) -> usize {
    let n = m.dim();
    let y = m.initial_state();
    let pattern = m.jacobian_pattern();
    assert_eq!(pattern.len(), n, "{what}");
    let mut inside = vec![vec![false; n]; n];
    for (j, rows) in pattern.iter().enumerate() {
        assert!(
            rows.windows(2).all(|w| w[0] < w[1]),
            "{what}: rows ascending"
        );
        for &i in rows {
            inside[j][i] = true;
        }
    }
    let mut jac = Mat::<f64>::zeros(n, n);
    m.jacobian(0.0, &y, jac.as_mut());
    let mut f0 = vec![0.0; n];
    m.rhs(0.0, &y, &mut f0);
    let mut fd = Mat::<f64>::zeros(n, n);
    let mut yp = y.clone();
    let mut f1 = vec![0.0; n];
    for j in 0..n {
        let d = 1e-7 * y[j].abs().max(1e-2);
        yp[j] = y[j] + d;
        m.rhs(0.0, &yp, &mut f1);
        yp[j] = y[j];
        for i in 0..n {
            fd[(i, j)] = (f1[i] - f0[i]) / d;
        }
    }
    let mut seen_inside = 0;
    for j in 0..n {
        for i in 0..n {
            let (a, b) = (jac[(i, j)], fd[(i, j)]);
            assert!(
                a.is_finite() && b.is_finite(),
                "{what}: ({i}, {j}) not finite"
            );
            if !inside[j][i] {
                assert!(
                    a == 0.0 && b == 0.0,
                    "{what}: ∂f{i}/∂y{j} outside the pattern: closed form {a:e}, differences {b:e}"
                );
            } else if a != 0.0 && b != 0.0 && a != 1.0 {
                seen_inside += 1;
            }
        }
    }
    assert!(seen_inside > 0, "{what}: no coupling inside the pattern");
    pattern.iter().map(Vec::len).sum()
}

#[test]
fn the_pattern_covers_every_coupling_of_free_bodies_springs_and_joints() {
    // Cluster sizes in state components (6 per free body; the chain's 6 per body absolute,
    // 2 per link in minimal): {b0, b1, b6} 18, {b2, b3} 12, {b4, b5} 12, b7, b8, b9 6 each.
    let free: usize = [18usize, 12, 12, 6, 6, 6].iter().map(|s| s * s).sum();
    for (formulation, chain) in [
        ("lagrange_baumgarte", 12usize),
        ("augmented_lagrangian", 12),
        ("minimal", 4),
    ] {
        let m = mech(&clusters(formulation));
        let nnz = check(&m, formulation);
        assert_eq!(nnz, free + chain * chain, "{formulation}");
        assert!(m.jacobian_sparsity().is_some(), "{formulation}");
    }
}

#[test]
fn the_press_and_a_chain_are_one_cluster() {
    for joint in [PressJoint::Ideal, PressJoint::Dry, PressJoint::Lubricated] {
        let mut scene = press_scene(joint, 150.0, 1e-4);
        for f in ["lagrange_baumgarte", "auto"] {
            scene.formulation = serde_json::from_value(json!(f)).unwrap();
            let m = Mechanism::from_scene(&scene).unwrap();
            let n = m.dim();
            assert_eq!(check(&m, &format!("press {joint:?} {f}")), n * n);
            assert!(m.jacobian_sparsity().is_none(), "one cluster: dense");
        }
    }
    let chain = json!({
        "bodies": (0..4).map(|i| json!({"name": format!("l{i}"), "mass": 1.0,
            "inertia": 1e-3, "position": [0.1 * i as f64 + 0.05, 0.0],
            "points": {"A": [-0.05, 0.0], "B": [0.05, 0.0]}})).collect::<Vec<_>>(),
        "joints": (0..4).map(|i| if i == 0 {
            json!({"type": "revolute", "name": "j0", "a": {"body": "l0", "point": "A"},
                   "b": {"body": "ground", "at": [0.0, 0.0]}})
        } else {
            json!({"type": "revolute", "name": format!("j{i}"),
                   "a": {"body": format!("l{}", i - 1), "point": "B"},
                   "b": {"body": format!("l{i}"), "point": "A"}})
        }).collect::<Vec<_>>(),
        "gravity": [0.0, -9.81],
        "formulation": "lagrange_baumgarte",
        "t_end": 1.0
    });
    let m = mech(&chain);
    assert_eq!(check(&m, "chain"), 24 * 24);
}
