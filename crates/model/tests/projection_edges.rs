//! The velocity projection that meets exact initial velocities (docs/model.md §1.6): its
//! conditioning and the kinetic energy it adds are reported, and an ill-conditioned one is a
//! scene error naming the exact velocities (issue 23).

use std::path::PathBuf;

use lash_model::{Mechanism, Scene, SceneError};
use serde_json::{json, Value};

fn pendulum() -> Value {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/examples/pendulum.json");
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}

fn build(v: &Value) -> Result<Mechanism, SceneError> {
    // Lagrange–Baumgarte: the tests read the absolute initial state y = (q, q̇).
    let mut s = Scene::from_json_str(&v.to_string()).unwrap();
    s.formulation = lash_model::FormulationName::LagrangeBaumgarte;
    Mechanism::from_scene(&s)
}

#[test]
fn an_exact_velocity_met_through_a_nearly_singular_projection_is_refused() {
    // Issue 23: the README pendulum with its journal at e = (0, −c/2) and link2's exact
    // vx = −3 m/s. Link1 is horizontal, so its tip moves vertically; only link2's tilt
    // (c/2 over 0.25 m, 2e-3 rad) turns its spin into vx: ω₂ ≈ 3 / 5e-4 = 6000 rad/s, and the
    // projection started link1 at 41 000 rad/s (17 MJ in 1 kg links), against the 4.5 J the
    // exact value carries.
    let mut s = pendulum();
    s["joints"][1]["initial_eccentricity"] = json!([0.0, -0.0005]);
    s["bodies"][1]["initial_velocity"] = json!({"vx": -3.0});
    match build(&s) {
        Err(SceneError::Assembly { path, reason }) => {
            assert_eq!(path, "bodies[1].initial_velocity.vx");
            assert!(reason.contains("ill-conditioned"), "{reason}");
            assert!(reason.contains("carry 4.500e0 J"), "{reason}");
        }
        Err(e) => panic!("expected an assembly error, got {e}"),
        Ok(m) => panic!("built: {}", m.projection_report()),
    }
    // With the journal centred the same request cannot be met at all: refused as before.
    s["joints"][1]["initial_eccentricity"] = json!([0.0, 0.0]);
    let e = build(&s).unwrap_err().to_string();
    assert!(e.contains("bodies[1].initial_velocity.vx"), "{e}");
    // Without the exact velocity the scene builds, and reports no exact energy.
    let m = build(&pendulum()).unwrap();
    assert_eq!(m.projection_report().kinetic_energy_exact, 0.0);
}

#[test]
fn a_pinned_rod_given_its_centres_speed_reports_the_energies_in_closed_form() {
    // A uniform rod (m = 1 kg, l = 0.5 m, I = m l²/12) pinned at one end, its centre given
    // vy = v exactly: ω = v/(l/2), so T = ½ m v² (1 + I/(m (l/2)²)) = ½ m v² · 4/3, while the
    // exact value alone carries ½ m v².
    let v = 2.0;
    let s = json!({
        "bodies": [{"name": "rod", "mass": 1.0, "inertia": 0.5 * 0.5 / 12.0,
                    "position": [0.25, 0.0], "points": {"O": [-0.25, 0.0]},
                    "initial_velocity": {"vy": v}}],
        "joints": [{"type": "revolute", "name": "pivot", "a": {"body": "rod", "point": "O"},
                    "b": {"body": "ground", "at": [0.0, 0.0]}}],
        "gravity": [0.0, -9.81],
        "t_end": 1.0
    });
    let m = build(&s).unwrap();
    let r = m.projection_report();
    assert!(
        (r.kinetic_energy_exact - 0.5 * v * v).abs() < 1e-12,
        "{r:?}"
    );
    assert!(
        (r.kinetic_energy_assembled - 0.5 * v * v * 4.0 / 3.0).abs() < 1e-12,
        "{r:?}"
    );
    assert!(r.condition.is_finite() && r.condition >= 1.0, "{r:?}");
    let y0 = m.initial_state();
    assert!((y0[5] - v / 0.25).abs() < 1e-12, "{y0:?}");
}

#[test]
fn every_scene_in_cases_still_builds() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases");
    let mut n = 0;
    for dir in std::fs::read_dir(&root).unwrap() {
        for f in std::fs::read_dir(dir.unwrap().path()).unwrap() {
            let p = f.unwrap().path();
            if p.extension().is_some_and(|e| e == "json") {
                let text = std::fs::read_to_string(&p).unwrap();
                let m = Mechanism::from_scene(&Scene::from_json_str(&text).unwrap());
                let m = m.unwrap_or_else(|e| panic!("{}: {e}", p.display()));
                let r = m.projection_report();
                // The augmented Lagrangian takes redundant constraints (parallel_cranks):
                // its projection matrix has lost rank, and that is not refused.
                let redundant_allowed = m.formulation_name() == "augmented_lagrangian";
                assert!(
                    r.condition < 1e8 || redundant_allowed,
                    "{}: {r:?}",
                    p.display()
                );
                n += 1;
            }
        }
    }
    assert!(n >= 40, "{n}");
}
