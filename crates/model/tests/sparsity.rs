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

/// `n` free bodies in pairs joined by a stiff spring–damper, under gravity (n/2 clusters of
/// 12 state components).
fn pairs(n: usize) -> Mechanism {
    let bodies: Vec<Value> = (0..n)
        .map(|i| {
            json!({"name": format!("b{i}"), "mass": 1.0 + 0.01 * i as f64, "inertia": 0.1,
                   "position": [i as f64, 0.0], "velocity": [0.0, 1.0 + 0.01 * i as f64],
                   "angular_velocity": 0.1 * (i % 7) as f64,
                   "points": {"p": [0.1, 0.05]}})
        })
        .collect();
    let forces: Vec<Value> = (0..n / 2)
        .map(|k| {
            json!({"type": "spring_damper", "name": format!("s{k}"),
                   "a": {"body": format!("b{}", 2 * k), "point": "p"},
                   "b": {"body": format!("b{}", 2 * k + 1), "point": "p"},
                   "stiffness": 1e4, "damping": 5.0, "free_length": 0.8})
        })
        .collect();
    mech(&json!({"bodies": bodies, "forces": forces, "gravity": [0.0, -9.81], "t_end": 0.1}))
}

/// The sparse path (crate lash_solver::linear_algebra) against the dense one on 100 free
/// bodies in pairs (n = 600, the size from which `auto` goes sparse), bdf, trbdf2,
/// esdirk34 and rodas5p at their default tolerances, to t = 0.1 s (about two periods of the springs'
/// stretch mode, ω = √(k/μ) ≈ 140 rad/s with μ ≈ 0.5 kg). Each path is compared with
/// dop853 at rtol 1e-12: both errors are controlled by the same tolerances, so the sparse
/// path's error must be of the dense path's size (within a factor 10, the spread of global errors between runs of one tolerance whose
/// step sequences differ). The Jacobians differ only by the sparse path's finite differences
/// (√ε relative), which leave Newton's iteration and the step-size sequence nearly the same:
/// the accepted steps agree within 10 %, and the two answers are closer to each other than
/// the dense one is to the reference (measured: 3.6× closer for bdf, 8× for esdirk34, 300×
/// for trbdf2, 11× for rodas5p, which takes the dense path's 58 steps and 63 LUs). A Jacobian with a coupling missing fails these (its Newton iterations
/// converge slowly, and the steps shrink).
#[test]
fn the_sparse_path_gives_the_dense_paths_answer() {
    use lash_solver::{LinearAlgebra, Method, Problem, SolverOptions};
    let m = pairs(100);
    let n = m.dim();
    assert_eq!(n, 600);
    let y0 = m.initial_state();
    let t_end = 0.1;
    let reference = {
        let mut o = SolverOptions::with_method(Method::Dop853);
        o.rtol = 1e-12;
        o.atol = lash_solver::Atol::Scalar(1e-14);
        o.output = lash_solver::Output::Final;
        Problem::new(&m, &o)
            .unwrap()
            .solve((0.0, t_end), &y0)
            .unwrap()
            .y_final
    };
    let err = |y: &[f64]| {
        y.iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    for method in [
        Method::Bdf,
        Method::Trbdf2,
        Method::Esdirk34,
        Method::Rodas5p,
    ] {
        let mut finals = Vec::new();
        for la in [
            LinearAlgebra::Dense,
            LinearAlgebra::Sparse,
            LinearAlgebra::Auto,
        ] {
            let mut o = SolverOptions::with_method(method);
            o.output = lash_solver::Output::Final;
            o.linear_algebra = la;
            let p = Problem::new(&m, &o).unwrap();
            let sparse = p.is_sparse();
            assert_eq!(sparse, la != LinearAlgebra::Dense, "{method} {la:?}");
            let sol = p.solve((0.0, t_end), &y0).unwrap();
            assert_eq!(sol.t_final, t_end);
            finals.push((sol.y_final, sol.stats));
        }
        let (dense, sparse) = (&finals[0], &finals[1]);
        assert_eq!(
            finals[1].0, finals[2].0,
            "{method}: auto is the sparse path here"
        );
        let (ed, es) = (err(&dense.0), err(&sparse.0));
        let diff = dense
            .0
            .iter()
            .zip(&sparse.0)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        eprintln!(
            "{method}: error dense {ed:e} sparse {es:e}, difference {diff:e}; steps {} vs {}, \
             rhs {} vs {}, LU {} vs {}",
            dense.1.accepted,
            sparse.1.accepted,
            dense.1.rhs_evals,
            sparse.1.rhs_evals,
            dense.1.lu_factorizations,
            sparse.1.lu_factorizations
        );
        assert!(
            es <= 10.0 * ed.max(1e-9),
            "{method}: sparse error {es:e}, dense {ed:e}"
        );
        assert!(
            diff <= 10.0 * ed.max(1e-9),
            "{method}: difference {diff:e}, dense error {ed:e}"
        );
    }
}

/// Below 600 unknowns `auto` keeps the dense path (its numbers unchanged), and a mechanism
/// that is one cluster stays dense at any size.
#[test]
fn auto_is_dense_below_the_threshold_and_for_one_cluster() {
    use lash_solver::{Method, Problem, SolverOptions};
    let o = SolverOptions::with_method(Method::Bdf);
    let small = pairs(98);
    assert_eq!(small.dim(), 588);
    assert!(!Problem::new(&small, &o)
        .unwrap()
        .diffsol()
        .unwrap()
        .is_sparse());
    let large = pairs(100);
    assert!(Problem::new(&large, &o)
        .unwrap()
        .diffsol()
        .unwrap()
        .is_sparse());
}

/// The memory check counts the sparse path's entries, not n²: 1 000 free bodies in pairs
/// (n = 6 000, 500 blocks of 12 × 12, nnz = 72 000) need 80 · (72 000 + 6 000) = 6.24 MB
/// sparse (lash_solver::memory::sparse_bytes), 4 · 8 · 6 000² = 1.152 GB dense: a budget of
/// 6.24 MB admits the sparse path and refuses the dense one, and one byte less refuses both.
#[test]
fn the_memory_budget_of_the_sparse_path_counts_entries() {
    use lash_solver::{LinearAlgebra, Method, Problem, SolveError, SolverOptions};
    let m = pairs(1000);
    assert_eq!(m.dim(), 6000);
    let mut o = SolverOptions::with_method(Method::Bdf);
    o.max_memory = Some(6_240_000);
    assert!(Problem::new(&m, &o).unwrap().diffsol().unwrap().is_sparse());
    o.linear_algebra = LinearAlgebra::Dense;
    match Problem::new(&m, &o) {
        Err(SolveError::OutOfMemory(e)) => assert_eq!(e.needed, 1_152_000_000),
        other => panic!("dense path admitted: {:?}", other.err()),
    }
    o.linear_algebra = LinearAlgebra::Auto;
    o.max_memory = Some(6_239_999);
    match Problem::new(&m, &o) {
        Err(SolveError::OutOfMemory(e)) => {
            assert_eq!((e.needed, e.budget), (6_240_000, 6_239_999));
            assert!(e.to_string().contains("72000 entries"), "{e}");
        }
        other => panic!("sparse path over budget admitted: {:?}", other.err()),
    }
}

/// A mechanism without constraint rows (free bodies) reports a constraint violation of +0 in
/// every formulation: ‖Φ‖₂ of no rows is the empty sum, which `Iterator::sum` starts from −0
/// (it printed "-0" in trajectory.csv and "max ‖Φ‖ -0.0e0" after `lash run`).
#[test]
fn no_constraint_rows_is_a_violation_of_plus_zero() {
    for formulation in ["lagrange_baumgarte", "augmented_lagrangian", "minimal"] {
        let v = json!({
            "bodies": [{"name": "b", "mass": 1.0, "inertia": 0.1, "position": [0.0, 0.0],
                        "velocity": [0.0, 1.0]}],
            "gravity": [0.0, -9.81], "t_end": 0.01, "formulation": formulation
        });
        let m = Mechanism::from_scene(&Scene::from_json_str(&v.to_string()).unwrap()).unwrap();
        let cv = m.outputs(0.0, &m.initial_state()).constraint_violation;
        assert!(cv == 0.0 && cv.is_sign_positive(), "{formulation}: {cv:?}");
    }
}

/// A chain of `n` links (0.1 m, 1 kg) whose first is pinned to the ground and whose n − 1
/// elbows are dry clearance joints (c = 1 mm), each journal 1.5 mm off its bearing's centre
/// (in contact: 0.5 mm deep), as benches/examples/scaling.rs's `clearance N` with contact.
fn clearance_chain(n: usize, formulation: &str) -> Value {
    let l = 0.1;
    let mut bodies = Vec::new();
    let mut joints = vec![json!({"type": "revolute", "name": "j0",
        "a": {"body": "l0", "point": "A"}, "b": {"body": "ground", "at": [0.0, 0.0]}})];
    for i in 0..n {
        bodies.push(
            json!({"name": format!("l{i}"), "mass": 1.0, "inertia": l * l / 12.0,
            "position": [l * i as f64 + l / 2.0 + 0.0015 * i as f64, 0.0],
            "angular_velocity": 0.3,
            "points": {"A": [-l / 2.0, 0.0], "B": [l / 2.0, 0.0]}}),
        );
        if i > 0 {
            joints.push(json!({"type": "clearance", "name": format!("j{i}"),
                "bearing": {"body": format!("l{}", i - 1), "point": "B", "radius": 0.01},
                "journal": {"body": format!("l{i}"), "point": "A", "radius": 0.009},
                "normal": {"law": "impact", "k": 1e9, "c_max": 2000.0, "d_max": 1e-5},
                "friction": {"law": "coulomb", "mu": 0.1, "v0": 1e-4, "v1": 2e-4}}));
        }
    }
    json!({"bodies": bodies, "joints": joints, "gravity": [0.0, -9.81], "t_end": 1.0,
           "formulation": formulation})
}

/// A chain of clearance joints is one cluster of bodies but N constraint clusters (each link
/// alone; the first with its ground pin): under the absolute formulations its pattern is
/// block tridiagonal, 36 (3N − 2) entries (each link's 6 × 6 block and its two neighbours'),
/// and covers every entry of the closed-form Jacobian and of the differences with every
/// elbow in contact (dropping the clearance joints' couplings fails `check`); under minimal
/// it stays one block (a link's force reaches its tree's root through the mass matrix).
#[test]
fn a_chain_of_clearance_joints_is_block_tridiagonal() {
    let n = 6;
    for formulation in ["lagrange_baumgarte", "augmented_lagrangian"] {
        let m = mech(&clearance_chain(n, formulation));
        assert_eq!(m.dim(), 6 * n);
        assert_eq!(check(&m, formulation), 36 * (3 * n - 2), "{formulation}");
        assert!(m.jacobian_sparsity().is_some(), "{formulation}");
    }
    let m = mech(&clearance_chain(n, "minimal"));
    let nnz: usize = m.jacobian_pattern().iter().map(Vec::len).sum();
    assert_eq!(nnz, m.dim() * m.dim());
    assert!(m.jacobian_sparsity().is_none());
}

/// From 100 links (n = 600, lash_solver::linear_algebra::SPARSE_FROM) `auto` runs a chain of
/// clearance joints on the sparse path; 99 links stay dense (their numbers unchanged).
#[test]
fn a_long_chain_of_clearance_joints_takes_the_sparse_path() {
    use lash_solver::{Method, Problem, SolverOptions};
    let o = SolverOptions::with_method(Method::Bdf);
    for (links, sparse) in [(99, false), (100, true)] {
        let m = mech(&clearance_chain(links, "lagrange_baumgarte"));
        let p = Problem::new(&m, &o).unwrap();
        assert_eq!(p.diffsol().unwrap().is_sparse(), sparse, "{links} links");
    }
}
