//! Helpers shared by the integration tests.
#![allow(dead_code)]

use faer::Mat;
use lash_model::cases::{press_scene, PressJoint};
use lash_model::{Mechanism, Scene, SceneError};
use lash_solver::{solve, Method, OdeSystem, Output, Solution, SolverOptions};

/// The dry press at 150 rpm, c = 0.1 mm, as a JSON value to mutate.
pub fn dry_press_value() -> serde_json::Value {
    serde_json::from_str(&press_scene(PressJoint::Dry, 150.0, 1e-4).to_json_pretty()).unwrap()
}

/// Parses a JSON value and builds the mechanism. A scene that names no formulation is built
/// with `lagrange_baumgarte`: the tests that use this are about elements, laws, scene errors
/// and the absolute state y = (q, q̇), which was the default before `auto` (docs/model.md
/// §12); the formulations' own tests (minimal.rs, iftomm.rs) choose theirs.
pub fn build(v: &serde_json::Value) -> Result<Mechanism, SceneError> {
    let mut scene = Scene::from_json_str(&v.to_string())?;
    if v.get("formulation").is_none() {
        scene.formulation = lash_model::FormulationName::LagrangeBaumgarte;
    }
    Mechanism::from_scene(&scene)
}

/// RK4 options with a fixed step, outputs at the given times.
pub fn rk4(step: f64, events: bool, output: Output) -> SolverOptions {
    SolverOptions {
        method: Method::Rk4,
        step: Some(step),
        events,
        output,
        ..Default::default()
    }
}

/// Runs a mechanism from its initial state to its end time.
pub fn run(m: &Mechanism, opts: &SolverOptions) -> Solution {
    solve(m, (m.t_start(), m.t_end()), &m.initial_state(), opts).expect("integration succeeds")
}

/// The folder of the press scenes (cases/press).
#[allow(dead_code)]
pub fn cases_dir() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/press")
}

/// The RK4 step these tests run a press case of the catalogue at (its file stem), s: the
/// largest step found stable that keeps ‖Φ‖ below 1e-8 over the case (the `rk4_scan`
/// example). The model chooses no integrator settings; the engine keeps the same steps for
/// its runs (`lash_validation::PressCase::rk4_step`).
///
/// ```text
/// ideal 1e-3 s;  dry 2e-4 s;  lubricated: c = 0.1, 0.5 mm 2e-6 s, c = 0.3 mm 5e-7 s,
/// c = 0.2 mm 2e-7 s (the film's radial damping grows as (1 − ε²)^{−3/2} up to
/// ε_cap = 0.99, which bounds the RK4 step)
/// ```
pub fn rk4_step(stem: &str) -> f64 {
    assert!(
        lash_model::cases::press_catalogue()
            .iter()
            .any(|(n, _)| n == stem),
        "{stem} is not a press case of the catalogue"
    );
    if stem.starts_with("ideal") {
        1e-3
    } else if stem.starts_with("dry") {
        2e-4
    } else if stem.ends_with("c0.2") {
        2e-7
    } else if stem.ends_with("c0.3") {
        5e-7
    } else {
        2e-6
    }
}

/// The file stems of cases/press/*.json, sorted.
/// Scenes of cases/press written by hand, not by the paper's generator: the press with a
/// punching load and a motor (docs/model.md §10; crates/model/tests/example_cases.rs runs it).
pub const HAND_WRITTEN: [&str; 1] = ["punch_motor_150rpm_c0.1"];

pub fn case_stems() -> Vec<String> {
    let mut stems: Vec<String> = std::fs::read_dir(cases_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .filter(|s| !HAND_WRITTEN.contains(&s.as_str()))
        .collect();
    stems.sort();
    stems
}

/// Central differences of f in y, Richardson-extrapolated: (4 D(h/2) − D(h)) / 3, truncation
/// O(h⁴). Valid where f is smooth on the scale h.
pub fn richardson(m: &Mechanism, t: f64, y: &[f64], h_of: impl Fn(usize) -> f64) -> Mat<f64> {
    let n = y.len();
    let mut out = Mat::<f64>::zeros(n, n);
    let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
    let mut yp = y.to_vec();
    let mut d = |j: usize, h: f64, yp: &mut Vec<f64>| -> Vec<f64> {
        yp[j] = y[j] + h;
        m.rhs(t, yp, &mut fp);
        yp[j] = y[j] - h;
        m.rhs(t, yp, &mut fm);
        yp[j] = y[j];
        (0..n).map(|i| (fp[i] - fm[i]) / (2.0 * h)).collect()
    };
    for j in 0..n {
        let h = h_of(j);
        let d1 = d(j, h, &mut yp);
        let d2 = d(j, 0.5 * h, &mut yp);
        for i in 0..n {
            out[(i, j)] = (4.0 * d2[i] - d1[i]) / 3.0;
        }
    }
    out
}

/// Largest |J − R| over the lower block, relative to the largest |R| of the same row.
pub fn worst_row_error(jac: &Mat<f64>, reference: &Mat<f64>) -> f64 {
    let n = jac.nrows();
    let mut worst: f64 = 0.0;
    for i in n / 2..n {
        let scale = (0..n).fold(0.0f64, |a, j| a.max(reference[(i, j)].abs()));
        for j in 0..n {
            worst = worst.max((jac[(i, j)] - reference[(i, j)]).abs() / scale);
        }
    }
    worst
}

/// Two 0.5 m links of 1 kg, the first pinned to the ground, the second hanging from the first
/// through a clearance joint (c = 1 mm) with the given normal and friction laws, released from
/// the horizontal under gravity, t_end 1 s: the conservative scene of energy.rs and minimal.rs.
pub fn clearance_double_pendulum(
    normal: serde_json::Value,
    friction: serde_json::Value,
) -> serde_json::Value {
    let i = 1.0 * 0.5 * 0.5 / 12.0;
    serde_json::json!({
        "bodies": [
            {"name": "link1", "mass": 1.0, "inertia": i, "position": [0.25, 0.0],
             "points": {"O": [-0.25, 0.0], "P": [0.25, 0.0]}},
            {"name": "link2", "mass": 1.0, "inertia": i, "position": [0.75, 0.0],
             "points": {"P": [-0.25, 0.0], "E": [0.25, 0.0]}}
        ],
        "joints": [
            {"type": "revolute", "name": "pivot", "a": {"body": "link1", "point": "O"},
             "b": {"body": "ground", "at": [0.0, 0.0]}},
            {"type": "clearance", "name": "elbow",
             "bearing": {"body": "link1", "point": "P", "radius": 0.010},
             "journal": {"body": "link2", "point": "P", "radius": 0.009},
             "normal": normal, "friction": friction,
             "initial_eccentricity": [0.0, -0.0005]}
        ],
        "gravity": [0.0, -9.81],
        "t_end": 1.0
    })
}
