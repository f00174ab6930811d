//! Helpers shared by the integration tests.
#![allow(dead_code)]

use lash_model::cases::{press_scene, PressJoint};
use lash_model::{Mechanism, Scene, SceneError};
use lash_solver::{solve, Method, Output, Solution, SolverOptions};

/// The dry press at 150 rpm, c = 0.1 mm, as a JSON value to mutate.
pub fn dry_press_value() -> serde_json::Value {
    serde_json::from_str(&press_scene(PressJoint::Dry, 150.0, 1e-4).to_json_pretty()).unwrap()
}

/// Parses a JSON value and builds the mechanism.
pub fn build(v: &serde_json::Value) -> Result<Mechanism, SceneError> {
    let scene = Scene::from_json_str(&v.to_string())?;
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

/// The RK4 step of a press case (`lash_model::cases::rk4_step`; the stems here are the
/// catalogue's).
pub fn rk4_step(stem: &str) -> f64 {
    lash_model::cases::rk4_step(stem).unwrap_or_else(|| panic!("{stem} is not a press case"))
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
