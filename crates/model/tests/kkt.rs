//! The `kkt` linear algebra of diffsol's implicit methods (lash_solver::kkt, the mechanism's
//! KKT form in crates/model/src/kkt.rs) on chains of pendulum links, one cluster whose
//! state-space Jacobian is dense.
use faer::prelude::Solve;
use lash_model::{Mechanism, Scene};
use lash_solver::{LinearAlgebra, Method, OdeSystem, Problem, SolverOptions, WithQuadrature};
use serde_json::{json, Value};

/// A chain of `n` links of 0.1 m and 1 kg pinned end to end, the first to the ground, laid
/// out horizontally (gravity swings it down), as /scratch's gen.py writes it.
fn chain(n: usize, formulation: &str) -> Value {
    let l = 0.1;
    let mut bodies = Vec::new();
    let mut joints = vec![json!({"type": "revolute", "name": "j0",
        "a": {"body": "l0", "point": "A"}, "b": {"body": "ground", "at": [0.0, 0.0]}})];
    for i in 0..n {
        bodies.push(
            json!({"name": format!("l{i}"), "mass": 1.0, "inertia": l * l / 12.0,
            "position": [l * i as f64 + l / 2.0, 0.0],
            "points": {"A": [-l / 2.0, 0.0], "B": [l / 2.0, 0.0]}}),
        );
        if i > 0 {
            joints.push(json!({"type": "revolute", "name": format!("j{i}"),
                "a": {"body": format!("l{}", i - 1), "point": "B"},
                "b": {"body": format!("l{i}"), "point": "A"}}));
        }
    }
    json!({"bodies": bodies, "joints": joints, "gravity": [0.0, -9.81], "t_end": 1.0,
           "formulation": formulation})
}

fn mech(v: &Value) -> Mechanism {
    Mechanism::from_scene(&Scene::from_json_str(&v.to_string()).unwrap()).unwrap()
}

/// The chain's state after `t` s of bdf on the dense path (a swinging chain: every link
/// moving, the constraint forces nonzero).
fn swinging(m: &Mechanism, t: f64) -> Vec<f64> {
    let mut o = SolverOptions::with_method(Method::Bdf);
    o.output = lash_solver::Output::Final;
    o.linear_algebra = LinearAlgebra::Dense;
    Problem::new(m, &o)
        .unwrap()
        .solve((0.0, t), &m.initial_state())
        .unwrap()
        .y_final
}

/// One Newton solve (I − cJ) x = r through the KKT form (lash_solver::kkt::newton_solve)
/// against the dense Newton matrix of the model's closed-form Jacobian, on a 40-link chain
/// after 0.05 s of swinging, under both absolute formulations, for c from 1e-5 to 1e-2 (bdf's
/// hγ over its steps here), with the increments' floor of the `kkt` path (1: increments of
/// at least √ε ≈ 1.5e-8 m, rad, m/s). The two differ by the forward differences of ∂ρ/∂y
/// (relative error ~√ε of each entry, times the conditioning of I − cJ, a few here) and,
/// under the augmented Lagrangian, by its iteration's tolerance in the closed form: bound
/// 1e-7 of ‖x‖∞ (measured: 7e-9 and 2.2e-8 at c = 1e-2). A wrong block (a missing term of ∂ρ/∂y, D's c² on the wrong side) is O(1)
/// of the c-dependent part of x and fails it: the check below that x differs from r by far
/// more than the bound makes sure that part is not negligible.
#[test]
fn the_kkt_newton_solve_matches_the_dense_newton_matrix() {
    for formulation in ["lagrange_baumgarte", "augmented_lagrangian"] {
        let m = mech(&chain(40, formulation));
        let y = swinging(&m, 0.05);
        let n = y.len();
        let t = 0.05;
        let mut jac = faer::Mat::<f64>::zeros(n, n);
        m.jacobian(t, &y, jac.as_mut());
        let r: Vec<f64> = (0..n).map(|i| ((i * 7) % 13) as f64 - 6.0).collect();
        for c in [1e-5, 1e-3, 1e-2] {
            let a = faer::Mat::<f64>::from_fn(n, n, |i, j| {
                f64::from(u8::from(i == j)) - c * jac[(i, j)]
            });
            let rhs = faer::Mat::<f64>::from_fn(n, 1, |i, _| r[i]);
            let x_dense = a.partial_piv_lu().solve(&rhs);
            let mut x = r.clone();
            let scale = vec![1e-3; n];
            let kkt = m.kkt().expect("an absolute formulation has the KKT form");
            lash_solver::kkt::newton_solve(kkt, t, &y, c, &scale, &mut x).unwrap();
            let xmax = x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let diff = (0..n).fold(0.0f64, |a, i| a.max((x[i] - x_dense[(i, 0)]).abs()));
            let moved = (0..n).fold(0.0f64, |a, i| a.max((x[i] - r[i]).abs()));
            eprintln!("{formulation} c = {c:e}: |x| {xmax:e}, |x − r| {moved:e}, diff {diff:e}");
            assert!(diff <= 1e-7 * xmax, "{formulation} c = {c}: {diff:e}");
            assert!(
                moved >= 1e3 * 1e-7 * xmax,
                "{formulation} c = {c}: x − r = {moved:e}"
            );
        }
    }
}

/// bdf on the `kkt` path against the dense path on a 110-link chain (n = 660: `auto` takes
/// the `kkt` path), both formulations, 0.05 s of swinging at the default tolerances: the same
/// ODE and, up to the Newton matrix, the same iteration, so the same accepted steps and
/// factorisations, Newton iterations within 10 % (a wrong Newton matrix costs iterations and
/// failed steps long before it moves the answer), and final states within 1e-3 of the
/// tolerance's scale rtol · ‖y‖∞ (both converge Newton to a small fraction of the local
/// tolerance at the same steps).
/// `auto`'s crossover for one cluster (lash_solver::linear_algebra::KKT_ONE_CLUSTER_FROM =
/// 300 unknowns): a chain of 50 links (n = 300) takes the `kkt` path, one of 49 links
/// (n = 294) the dense one; 50 free bodies (n = 300, no KKT cluster: a sparse pattern)
/// stay dense below SPARSE_FROM.
#[test]
fn auto_takes_the_kkt_path_for_one_cluster_from_300_unknowns() {
    let o = SolverOptions::with_method(Method::Bdf);
    for (links, kkt) in [(50usize, true), (49, false)] {
        let m = mech(&chain(links, "augmented_lagrangian"));
        let p = Problem::new(&m, &o).unwrap();
        assert_eq!(p.diffsol().unwrap().is_kkt(), kkt, "{links} links");
    }
    let bodies: Vec<Value> = (0..50)
        .map(|i| {
            json!({"name": format!("f{i}"), "mass": 1.0, "inertia": 0.1,
                        "position": [i as f64, 0.0]})
        })
        .collect();
    let free = json!({"bodies": bodies, "joints": [], "gravity": [0.0, -9.81], "t_end": 1.0,
                      "formulation": "augmented_lagrangian"});
    let m = mech(&free);
    assert_eq!(m.dim(), 300);
    assert!(!Problem::new(&m, &o).unwrap().diffsol().unwrap().is_kkt());
}

#[test]
fn the_kkt_path_follows_the_dense_path_on_a_chain() {
    for formulation in ["lagrange_baumgarte", "augmented_lagrangian"] {
        let m = mech(&chain(110, formulation));
        let y0 = m.initial_state();
        let mut runs = Vec::new();
        for la in [LinearAlgebra::Dense, LinearAlgebra::Auto] {
            let mut o = SolverOptions::with_method(Method::Bdf);
            o.output = lash_solver::Output::Final;
            o.linear_algebra = la;
            let p = Problem::new(&m, &o).unwrap();
            assert_eq!(p.diffsol().unwrap().is_kkt(), la == LinearAlgebra::Auto);
            let sol = p.solve((0.0, 0.05), &y0).unwrap();
            assert_eq!(sol.t_final, 0.05);
            runs.push((sol.y_final, sol.stats));
        }
        let ((yd, sd), (yk, sk)) = (&runs[0], &runs[1]);
        eprintln!("{formulation}: dense {sd:?}\n kkt {sk:?}");
        assert_eq!(sd.accepted, sk.accepted, "{formulation}");
        assert_eq!(sd.lu_factorizations, sk.lu_factorizations, "{formulation}");
        assert!(
            (sk.newton_iters as f64) <= 1.1 * sd.newton_iters as f64,
            "{formulation}: {} vs {}",
            sk.newton_iters,
            sd.newton_iters
        );
        let ymax = yd.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let diff = yd
            .iter()
            .zip(yk)
            .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()));
        eprintln!("{formulation}: max |Δy| {diff:e} of ‖y‖ {ymax:e}");
        assert!(diff <= 1e-3 * 1e-3 * ymax, "{formulation}: {diff:e}");
    }
}

/// Mechanical energy of a chain of 1 kg links of 0.1 m (kinetic, and potential in gravity
/// 9.81 down) from y.
fn energy(y: &[f64]) -> f64 {
    let nq = y.len() / 2;
    let inertia = 0.1 * 0.1 / 12.0;
    (0..nq / 3)
        .map(|i| {
            let (vx, vy, w) = (y[nq + 3 * i], y[nq + 3 * i + 1], y[nq + 3 * i + 2]);
            0.5 * (vx * vx + vy * vy) + 0.5 * inertia * w * w + 9.81 * y[3 * i + 1]
        })
        .sum()
}

/// Energy on the `kkt` path: a 100-link chain (n = 600) falling from the horizontal for 0.2 s
/// (it turns 186 J of potential energy into kinetic) by bdf at rtol 1e-10, atol 1e-12: ideal
/// joints and gravity conserve the mechanical energy, so its drift is the integration's (and
/// Baumgarte's) error, which the local error control keeps at the order of rtol times the
/// energy exchanged: bound rtol · E_kin (1.9e-8 J; measured 2.7e-10 J). The same run at rtol
/// 1e-6 drifts 1.2e-6 J, over that bound (so it can fail).
#[test]
fn a_chain_keeps_its_energy_on_the_kkt_path() {
    let m = mech(&chain(100, "lagrange_baumgarte"));
    let y0 = m.initial_state();
    let e0 = energy(&y0);
    let mut drifts = Vec::new();
    for rtol in [1e-10, 1e-6] {
        let mut o = SolverOptions::with_method(Method::Bdf);
        o.output = lash_solver::Output::Final;
        o.linear_algebra = LinearAlgebra::Kkt;
        o.rtol = rtol;
        o.atol = lash_solver::Atol::Scalar(rtol * 1e-2);
        let p = Problem::new(&m, &o).unwrap();
        assert!(p.diffsol().unwrap().is_kkt());
        let sol = p.solve((0.0, 0.2), &y0).unwrap();
        let mut at_rest = sol.y_final.clone();
        let nq = at_rest.len() / 2;
        at_rest[nq..].fill(0.0);
        let kinetic = energy(&sol.y_final) - energy(&at_rest);
        let drift = (energy(&sol.y_final) - e0).abs();
        eprintln!(
            "rtol {rtol:e}: kinetic {kinetic} J, drift {drift:e} J, {:?}",
            sol.stats
        );
        drifts.push((drift, kinetic));
    }
    let (drift, kinetic) = drifts[0];
    assert!(kinetic > 100.0, "{kinetic}");
    assert!(drift <= 1e-10 * kinetic, "{drift:e} of {kinetic}");
    assert!(drifts[1].0 > 1e-10 * kinetic, "{:?}", drifts[1]);
}

/// The memory check counts the `kkt` path's entries (lash_solver::memory::kkt_bytes): a
/// chain of N links has n_q = 3N, 2N constraint rows (the first on one body, the others on
/// two: K has 3N + 2 · 3 · (4N − 2) = 27N − 12 triplets) and ∂ρ/∂y has 78N − 48 entries
/// (columns of an inner link: its and its neighbours' 9 force rows and its 4 constraint rows,
/// 6 columns; the first link 10, the last 8), so 80 · (2 (27N − 12) + 2 (78N − 48) + 12N) =
/// 80 · (222N − 120) bytes: 1 766 400 for N = 100, linear in N. That budget admits the `kkt`
/// path, one byte less refuses it, and the dense path (4 · 8 · 600² = 11.52 MB) is refused.
#[test]
fn the_memory_budget_of_the_kkt_path_counts_entries() {
    use lash_solver::SolveError;
    for n_links in [100usize, 200] {
        let m = mech(&chain(n_links, "lagrange_baumgarte"));
        let shape = lash_solver::kkt::KktSystem::kkt_shape(&m);
        let want = 80 * (222 * n_links as u64 - 120);
        assert_eq!(
            lash_solver::memory::kkt_bytes(&shape),
            want,
            "N = {n_links}"
        );
    }
    let m = mech(&chain(100, "lagrange_baumgarte"));
    let mut o = SolverOptions::with_method(Method::Bdf);
    o.max_memory = Some(1_766_400);
    assert!(Problem::new(&m, &o).unwrap().diffsol().unwrap().is_kkt());
    o.max_memory = Some(1_766_399);
    match Problem::new(&m, &o) {
        Err(SolveError::OutOfMemory(e)) => {
            assert_eq!((e.needed, e.budget), (1_766_400, 1_766_399));
            assert!(e.to_string().contains("KKT"), "{e}");
        }
        other => panic!("kkt path over budget admitted: {:?}", other.err()),
    }
    o.max_memory = Some(1_766_400);
    o.linear_algebra = LinearAlgebra::Dense;
    match Problem::new(&m, &o) {
        Err(SolveError::OutOfMemory(e)) => assert_eq!(e.needed, 11_520_000),
        other => panic!("dense path admitted: {:?}", other.err()),
    }
}

/// A 4-link chain whose last link is tied by a spring to free body f0, f0 and f1 joined by a
/// dry clearance joint, f1 and f2 by a rotational spring, f3 pushed by a force read from the
/// spring's length (a reference through an element), f4 alone.
fn mixed(formulation: &str) -> Value {
    let mut v = chain(4, formulation);
    let bodies = v["bodies"].as_array_mut().unwrap();
    for i in 0..5 {
        bodies.push(
            json!({"name": format!("f{i}"), "mass": 1.0 + 0.1 * i as f64,
            "inertia": 0.1, "position": [i as f64, 1.0 + 0.1 * i as f64],
            "velocity": [0.3, -0.2 * i as f64], "angular_velocity": 0.5,
            "points": {"p": [0.05, 0.02], "c": [0.0, 0.0]}}),
        );
    }
    v["joints"]
        .as_array_mut()
        .unwrap()
        .push(json!({"type": "clearance", "name": "cl",
        "bearing": {"body": "f0", "point": "c", "radius": 0.01},
        "journal": {"body": "f1", "point": "c", "radius": 0.009},
        "normal": {"law": "impact", "k": 1e9, "c_max": 2000.0, "d_max": 1e-5},
        "friction": {"law": "coulomb", "mu": 0.1, "v0": 1e-4, "v1": 2e-4}}));
    v["forces"] = json!([
        {"type": "spring_damper", "name": "s", "a": {"body": "l3", "point": "B"},
         "b": {"body": "f0", "point": "p"}, "stiffness": 1e3, "damping": 2.0,
         "free_length": 0.5},
        {"type": "rotational_spring_damper", "name": "r", "a": "f1", "b": "f2",
         "stiffness": 10.0, "damping": 0.1, "free_angle": 0.2},
        {"type": "force", "name": "f", "body": "f3", "direction": [0.0, 1.0],
         "table": {"input": {"of": "length", "element": "s"},
                   "points": [[0.0, 0.0], [10.0, 5.0]]}}
    ]);
    v
}

/// The pattern of ∂ρ/∂y (crates/model/src/kkt.rs, `residual_pattern`) covers every entry:
/// ρ = b − K z at an arbitrary z, each coordinate of y perturbed alone, every change outside
/// the pattern exactly 0 (a body outside an element's or a row's reach takes no part in
/// those rows' arithmetic); and the couplings it guards are seen (a change inside the
/// pattern off the body's own rows: the spring, the clearance joint, the rows).
#[test]
fn the_residual_pattern_covers_every_entry() {
    use lash_solver::kkt::KktSystem;
    for formulation in ["lagrange_baumgarte", "augmented_lagrangian"] {
        let m = mech(&mixed(formulation));
        let shape = m.kkt_shape();
        let (n, nk) = (2 * shape.nq, shape.nq + shape.m);
        // Contact in the clearance joint (c = 1 mm): the journal 1.5 mm off the bearing's centre.
        let mut y = m.initial_state();
        let f1 = 3 * 5;
        y[f1] += 0.0015;
        let z: Vec<f64> = (0..nk).map(|i| 0.3 + ((i * 5) % 7) as f64).collect();
        let rho = |y: &[f64]| {
            let (mut k, mut b) = (Vec::new(), vec![0.0; nk]);
            assert!(m.kkt_assemble(0.0, y, &mut k, &mut b));
            for (i, j, v) in k {
                b[i] -= v * z[j];
            }
            b
        };
        let r0 = rho(&y);
        let mut coupled = 0;
        for j in 0..n {
            let mut yp = y.clone();
            yp[j] += 1e-4 * (1.0 + y[j].abs());
            let r1 = rho(&yp);
            let rows = &shape.residual_pattern[j];
            let body = (j % shape.nq) / 3;
            for i in 0..nk {
                let changed = r1[i] != r0[i];
                if !rows.contains(&i) {
                    assert!(!changed, "{formulation}: ∂ρ_{i}/∂y_{j} outside the pattern");
                } else if changed && (i >= shape.nq || i / 3 != body) {
                    coupled += 1;
                }
            }
        }
        eprintln!("{formulation}: {coupled} coupling entries seen");
        assert!(coupled > 50, "{formulation}: {coupled}");
    }
}

/// TR-BDF2 and ESDIRK3(4) on the `kkt` path (their Newton matrix I − hγJ reaches it the same
/// way) against the dense path on a 110-link chain for 0.02 s: Newton iterations within 10 %
/// and final states within 1e-3 of rtol · ‖y‖∞, as for bdf.
#[test]
fn the_sdirk_methods_take_the_kkt_path_too() {
    let m = mech(&chain(110, "augmented_lagrangian"));
    let y0 = m.initial_state();
    for method in [Method::Trbdf2, Method::Esdirk34] {
        let mut runs = Vec::new();
        for la in [LinearAlgebra::Dense, LinearAlgebra::Auto] {
            let mut o = SolverOptions::with_method(method);
            o.output = lash_solver::Output::Final;
            o.linear_algebra = la;
            let p = Problem::new(&m, &o).unwrap();
            assert_eq!(p.diffsol().unwrap().is_kkt(), la == LinearAlgebra::Auto);
            runs.push(p.solve((0.0, 0.02), &y0).unwrap());
        }
        let (d, k) = (&runs[0], &runs[1]);
        eprintln!("{method}: dense {:?}\n kkt {:?}", d.stats, k.stats);
        assert!(
            (k.stats.newton_iters as f64) <= 1.1 * d.stats.newton_iters as f64,
            "{method}"
        );
        let ymax = d.y_final.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let diff =
            (d.y_final.iter().zip(&k.y_final)).fold(0.0f64, |a, (p, q)| a.max((p - q).abs()));
        assert!(diff <= 1e-3 * 1e-3 * ymax, "{method}: {diff:e}");
    }
}

#[test]
fn a_chain_with_quadratures_keeps_the_kkt_path() {
    // The engine integrates a run's energy terms as quadratures of the mechanism
    // (`WithQuadrature`): the wrapper must hand the KKT form on, or a long chain falls back to
    // the dense n × n path (a 1 000-link chain: 1.4 GB and 19 s instead of 32 MB and 0.6 s).
    let m = mech(&chain(110, "augmented_lagrangian"));
    let q = |_: f64, _: &[f64], out: &mut [f64]| out[0] = 0.0;
    let sys = WithQuadrature {
        sys: &m,
        m: 1,
        q: &q,
    };
    assert!(sys.kkt().is_some());
    let o = SolverOptions::with_method(Method::Bdf);
    assert!(Problem::new(&sys, &o).unwrap().diffsol().unwrap().is_kkt());
}

/// The `kkt` path where K = [[M, Φ_qᵀ], [Φ_q, 0]] is singular: redundant constraints (the
/// parallel cranks, rank 11 of 12) and the singular positions of the N-four-bar (A02, N = 2,
/// through its first horizontal position at t ≈ 0.71 s), under the augmented Lagrangian, which
/// tolerates both. Its right-hand side is the formulation's own on every path; only the Newton
/// matrix is the `kkt` path's, so bdf at rtol 1e-10 must meet the references of
/// tests/iftomm.rs there as on the dense path: the first body's angle within 1e-6 rad
/// (measured 2.6e-9 and 4.6e-9). With K itself factored (no K_ε, lash_solver::kkt "A singular
/// K") the cranks ended in a Newton failure at t = 0.688 s.
#[test]
fn the_kkt_path_runs_redundant_and_singular_mechanisms() {
    use lash_model::iftomm::{n_four_bar, parallel_cranks};
    let (cranks, crank_ref) = parallel_cranks(2.0);
    let (a02, a02_ref) = n_four_bar(2, 2.0);
    for (name, scene, reference) in [
        ("parallel cranks", cranks, crank_ref),
        ("A02 N = 2", a02, a02_ref),
    ] {
        let mut scene = scene;
        scene.formulation = lash_model::FormulationName::AugmentedLagrangian;
        let m = Mechanism::from_scene(&scene).unwrap();
        let mut o = SolverOptions::with_method(Method::Bdf);
        o.output = lash_solver::Output::Final;
        o.linear_algebra = LinearAlgebra::Kkt;
        o.rtol = 1e-10;
        o.atol = lash_solver::Atol::Scalar(1e-10);
        let p = Problem::new(&m, &o).unwrap();
        assert!(p.diffsol().unwrap().is_kkt(), "{name}");
        let sol = p.solve((0.0, 2.0), &m.initial_state());
        let sol = sol.unwrap_or_else(|e| panic!("{name}: {e}"));
        let th = reference.solve(&[2.0])[0][0];
        let err = (sol.y_final[2] - th).sin().abs();
        eprintln!(
            "{name}: first body's angle error {err:e} rad, {:?}",
            sol.stats
        );
        assert!(err < 1e-6, "{name}: {err:e}");
    }
}

/// R = ∂ρ/∂y at fixed z (ρ = b − K z) by the model's closed form
/// (`KktSystem::kkt_residual_jacobian`) and central differences of ρ with steps h and h/2,
/// h = 6e-6 (1 + |y_j|) ≈ ε^(1/3), the pattern's entries in its order, and max |ρ|; None
/// where the model has no closed form.
#[allow(clippy::type_complexity)]
fn closed_and_differenced(
    m: &Mechanism,
    t: f64,
    y: &[f64],
) -> Option<(Vec<f64>, [Vec<f64>; 2], f64)> {
    use lash_solver::kkt::KktSystem;
    let shape = m.kkt_shape();
    let nk = shape.nq + shape.m;
    // z of a typical size, not the solution: R is linear in z and its closed form holds at
    // any z.
    let z: Vec<f64> = (0..nk).map(|i| 0.3 + ((i * 5) % 7) as f64).collect();
    let nnz: usize = shape.residual_pattern.iter().map(Vec::len).sum();
    let mut closed = vec![f64::NAN; nnz];
    let mut k = Vec::new();
    let mut b = vec![0.0; nk];
    assert!(m.kkt_assemble(t, y, &mut k, &mut b));
    if !m.kkt_residual_jacobian(t, y, &z, &shape.residual_pattern, &mut closed) {
        return None;
    }
    let rho = |y: &[f64]| {
        let (mut k, mut b) = (Vec::new(), vec![0.0; nk]);
        assert!(m.kkt_assemble(t, y, &mut k, &mut b));
        for (i, j, v) in k {
            b[i] -= v * z[j];
        }
        b
    };
    let mut diff = [Vec::with_capacity(nnz), Vec::with_capacity(nnz)];
    for (j, rows) in shape.residual_pattern.iter().enumerate() {
        for (d, h) in diff.iter_mut().zip([6e-6, 3e-6]) {
            let h = h * (1.0 + y[j].abs());
            let (mut yp, mut ym) = (y.to_vec(), y.to_vec());
            yp[j] += h;
            ym[j] -= h;
            let (rp, rm) = (rho(&yp), rho(&ym));
            let hh = yp[j] - ym[j];
            d.extend(rows.iter().map(|&i| (rp[i] - rm[i]) / hh));
        }
    }
    let rho_max = rho(y).iter().fold(0.0f64, |a, v| a.max(v.abs()));
    Some((closed, diff, rho_max))
}

/// The closed-form R equals the central differences of ρ to the differences' own error, on
/// A02 N = 2 and N = 40 (gravity only: ∂g = 0) under both absolute formulations, and on a
/// chain with a dry clearance joint in contact and a linear spring-damper (every force's ∂g
/// a closed form); the mixed scene, whose rotational spring and force read from a length
/// have none, returns none (the `kkt` path then differences ρ). The states are moved off
/// the initial one, with every velocity nonzero (the velocity terms of ∂c). The error of the
/// difference with step h/2 is its truncation, O(h²): a third of its distance to the step
/// h's (Richardson), bounded here by that whole distance; plus its rounding, ε max|ρ| / h
/// (four times, and 1e-9 of the column's largest |entry|, or of 1). A wrong sign or a
/// dropped term is O(1) of an entry of the column and fails it.
#[test]
fn the_closed_form_residual_jacobian_equals_central_differences() {
    use lash_solver::kkt::KktSystem;
    let case = |name: &str, formulation: &str| {
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../cases/iftomm")
            .join(name);
        let mut s: Value = serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
        s["formulation"] = json!(formulation);
        s
    };
    for formulation in ["lagrange_baumgarte", "augmented_lagrangian"] {
        // The mixed scene without its rotational spring and its force read from a length
        // (differenced elements): the clearance joint and the linear spring-damper.
        let mut clearance = mixed(formulation);
        clearance["forces"].as_array_mut().unwrap().truncate(1);
        let scenes = [
            ("A02 N = 2", case("a02_n2.json", formulation), false),
            ("A02 N = 40", case("a02_n40.json", formulation), false),
            ("chain with a clearance joint", clearance, true),
        ];
        for (what, v, contact) in scenes {
            let m = mech(&v);
            let mut y = m.initial_state();
            let nq = y.len() / 2;
            for (i, v) in y.iter_mut().enumerate() {
                *v += if i < nq { 1e-3 } else { 0.5 } * ((i as f64) * 1.3 + 0.2).sin();
            }
            if contact {
                // The journal (f1) 1.5 mm off the bearing's centre (c = 1 mm): in contact.
                y[3 * 5] += 0.0015;
            }
            let (closed, [coarse, fine], rho_max) =
                closed_and_differenced(&m, 0.01, &y).expect(what);
            let shape = m.kkt_shape();
            let (mut e, mut worst, mut big) = (0, 0.0f64, 0usize);
            for (j, rows) in shape.residual_pattern.iter().enumerate() {
                let span = e..e + rows.len();
                // The rounding of the difference with step h/2: ε max|ρ| / h.
                let rounding = f64::EPSILON * rho_max / (3e-6 * (1.0 + y[j].abs()));
                let scale = fine[span.clone()]
                    .iter()
                    .fold(1.0f64, |a, v| a.max(v.abs()));
                for ((c, d), d2) in closed[span.clone()]
                    .iter()
                    .zip(&fine[span.clone()])
                    .zip(&coarse[span])
                {
                    let err = (c - d).abs();
                    worst = worst.max(err / scale);
                    assert!(
                        err <= (d - d2).abs() + 1e-9 * scale + 4.0 * rounding,
                        "{formulation} {what}: {c:e} against {d:e} (step h: {d2:e})"
                    );
                    big += usize::from(d.abs() > 1e-3 * scale);
                }
                e += rows.len();
            }
            eprintln!("{formulation} {what}: {e} entries, {big} large, worst {worst:e}");
            // A fifth of the pattern at least is live (measured 24–35 %).
            assert!(big > e / 5, "{formulation} {what}: {big} of {e}");
        }
        assert!(
            closed_and_differenced(
                &mech(&mixed(formulation)),
                0.01,
                &mech(&mixed(formulation)).initial_state()
            )
            .is_none(),
            "{formulation}: a force read from a length has no closed form"
        );
    }
}
