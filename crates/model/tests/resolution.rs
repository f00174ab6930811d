//! Inputs f64 cannot resolve are scene errors naming the field (docs/model.md §1.6,
//! "Resolution"; issue 23): a body angle whose f64 spacing 16 ε |θ| exceeds 1e-9 rad, and a
//! clearance joint whose ends lie so far out that ε |r| exceeds a millionth of its clearance.

use lash_model::{Mechanism, Scene, SceneError};
use serde_json::{json, Value};

fn invalid_path(v: &Value) -> Option<(String, String)> {
    match Scene::from_json_str(&v.to_string()) {
        Err(SceneError::Invalid { path, reason }) => Some((path, reason)),
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => None,
    }
}

/// A body in a bearing on the ground at `at` (clearance 0.1 mm).
fn journal_at(at: f64, angle: f64) -> Value {
    json!({
        "bodies": [{"name": "body", "mass": 1.0, "inertia": 0.01, "position": [at, 0.0],
                    "angle": angle, "points": {"J": [0.0, 0.0]}}],
        "joints": [{"type": "clearance", "name": "loose",
                    "bearing": {"body": "ground", "at": [at, 0.0], "radius": 0.0101},
                    "journal": {"body": "body", "point": "J", "radius": 0.01},
                    "normal": {"law": "impact", "k": 1e9, "c_max": 0.0, "d_max": 1e-5},
                    "friction": {"law": "none"}}],
        "gravity": [0.0, -9.81],
        "t_end": 0.1
    })
}

#[test]
fn a_body_angle_f64_cannot_resolve_is_refused_by_name() {
    // 16 ε |θ| = 1e-9 rad at |θ| = 1e-9 / (16 · 2.22e-16) = 2.815e5 rad.
    let limit = 1e-9 / (16.0 * f64::EPSILON);
    assert!(invalid_path(&journal_at(0.0, 0.99 * limit)).is_none());
    let (path, reason) = invalid_path(&journal_at(0.0, 1.01 * limit)).unwrap();
    assert_eq!(path, "bodies[0].angle");
    assert!(reason.contains("modulo 2π"), "{reason}");
    let (path, _) = invalid_path(&journal_at(0.0, -1e17)).unwrap();
    assert_eq!(path, "bodies[0].angle");
}

#[test]
fn a_clearance_joint_too_far_out_for_its_clearance_is_refused_by_name() {
    // ε |r| = 1e-6 c = 1e-10 m at |r| = 1e-10 / 2.22e-16 = 4.5e5 m.
    let limit = 1e-6 * 1e-4 / f64::EPSILON;
    let m =
        Mechanism::from_scene(&Scene::from_json_str(&journal_at(1e3, 0.0).to_string()).unwrap());
    assert!(m.is_ok());
    assert!(invalid_path(&journal_at(0.99 * limit, 0.0)).is_none());
    let (path, reason) = invalid_path(&journal_at(1.01 * limit, 0.0)).unwrap();
    assert_eq!(path, "joints[0].bearing.at");
    assert!(
        reason.contains("'loose'") && reason.contains("of its clearance 9.99"),
        "{reason}"
    );
    // A body end: the journal's body far out, the bearing at the origin.
    let mut v = journal_at(0.0, 0.0);
    v["bodies"][0]["position"] = json!([1e6, 0.0]);
    let (path, _) = invalid_path(&v).unwrap();
    assert_eq!(path, "bodies[0].position");
}
