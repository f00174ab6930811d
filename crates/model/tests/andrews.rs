//! Andrews' squeezing mechanism (cases/andrews/andrews.json) against the published reference
//! solution at t = 0.03 s.
//!
//! ```text
//! β = φ_K1, Θ = φ_K2 − φ_K1, γ = φ_K3, Φ = φ_K4 − φ_K5, δ = φ_K5, Ω = φ_K6 − φ_K7, ε = φ_K7
//! |lash − reference| ≤ 1e-6 |reference|   for the seven angles and their seven rates
//! ```
//! Reference: Mazzia and Magherini, Test Set for IVP Solvers, problem "andrews" (Hairer and
//! Wanner, Solving Ordinary Differential Equations II, §VII.7), the solution at t = 0.03
//! computed with PSIDE at tolerances 1e-14 (its subroutine `solut`). lash integrates the same
//! mechanism in absolute coordinates (seven bodies, ten revolute joints, docs/model.md §1) with
//! the spring and the driving torque of docs/model.md §10.

use lash_model::{Mechanism, Scene};
use lash_solver::{solve, Atol, Method, SolverOptions};

/// β, Θ, γ, Φ, δ, Ω, ε at t = 0.03 (rad), then their rates (rad/s): the test set's reference.
const REFERENCE: [f64; 14] = [
    0.1581077119629904e+2,
    -0.1575637105984298e+2,
    0.4082224013073101e-1,
    -0.5347301163226948e+0,
    0.5244099658805304e+0,
    0.5347301163226948e+0,
    0.1048080741042263e+1,
    0.1139920302151208e+4,
    -0.1424379294994111e+4,
    0.1103291221937134e+2,
    0.1929337464421385e+2,
    0.5735699284790808e+0,
    -0.1929337464421385e+2,
    0.3231791658026955e+0,
];

const NAMES: [&str; 7] = ["beta", "Theta", "gamma", "Phi", "delta", "Omega", "epsilon"];

fn scene() -> Scene {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../cases/andrews/andrews.json"
    );
    Scene::from_path(path).unwrap()
}

/// The seven joint angles and rates of the test set from lash's absolute coordinates.
fn joint_coordinates(m: &Mechanism, t: f64, y: &[f64]) -> [f64; 14] {
    let o = m.outputs(t, y);
    let b = &o.bodies;
    let rel = |i: usize, j: Option<usize>| {
        (
            b[i].theta - j.map_or(0.0, |j| b[j].theta),
            b[i].omega - j.map_or(0.0, |j| b[j].omega),
        )
    };
    let pairs = [
        rel(0, None),
        rel(1, Some(0)),
        rel(2, None),
        rel(3, Some(4)),
        rel(4, None),
        rel(5, Some(6)),
        rel(6, None),
    ];
    let mut out = [0.0; 14];
    for (k, (a, r)) in pairs.into_iter().enumerate() {
        out[k] = a;
        out[7 + k] = r;
    }
    out
}

/// DOP853 at rtol = atol = 1e-12: the mechanism's fast scales (the spring against the light
/// links, rates above 1000 rad/s) are resolved by an explicit method; the run is the
/// reference's check, not a benchmark.
#[test]
fn andrews_matches_the_test_set_reference_at_0_03_s() {
    let s = scene();
    let m = Mechanism::from_scene(&s).unwrap();
    let y0 = m.initial_state();
    // The scene starts at the test set's initial angles, at rest.
    let c0 = joint_coordinates(&m, 0.0, &y0);
    // The test set's initial angles, with its digits.
    #[allow(clippy::excessive_precision)]
    let init = [
        -0.0617138900142764496358948458001,
        0.0,
        0.455279819163070380255912382449,
        0.222668390165885884674473185609,
        0.487364979543842550225598953530,
        -0.222668390165885884674473185609,
        1.23054744454982119249735015568,
    ];
    for k in 0..7 {
        assert!((c0[k] - init[k]).abs() < 1e-12, "{}: {}", NAMES[k], c0[k]);
        assert_eq!(c0[7 + k], 0.0);
    }
    let opts = SolverOptions {
        method: Method::Dop853,
        rtol: 1e-12,
        atol: Atol::Scalar(1e-12),
        ..Default::default()
    };
    let sol = solve(&m, (0.0, 0.03), &y0, &opts).unwrap();
    let k = sol.len() - 1;
    assert_eq!(sol.t[k], 0.03);
    let c = joint_coordinates(&m, sol.t[k], sol.state(k));
    let mut worst = 0.0f64;
    for i in 0..14 {
        let rel = (c[i] - REFERENCE[i]).abs() / REFERENCE[i].abs();
        let what = if i < 7 { "" } else { " rate" };
        eprintln!(
            "{}{what}: lash {:.15e}, reference {:.15e}, relative error {rel:.2e}",
            NAMES[i % 7],
            c[i],
            REFERENCE[i]
        );
        worst = worst.max(rel);
    }
    assert!(worst <= 1e-6, "largest relative error {worst:.2e}");
}
