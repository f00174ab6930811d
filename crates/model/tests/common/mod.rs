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
