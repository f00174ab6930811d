//! Driver torque of a driver on an integrated body is −λ of its equation: a free disk turned
//! at constant speed against the friction of a ground bearing needs τ = −R_J F_T (moment
//! balance about its centre, φ̈ = 0).
use lash_model::{Mechanism, Scene};
use lash_solver::OdeSystem;
use serde_json::json;

#[test]
fn driver_lambda_balances_the_friction_moment() {
    let v = json!({
        "bodies": [{"name": "disk", "mass": 3.0, "inertia": 0.02, "points": {"c": [0.0, 0.0]}}],
        "joints": [
            {"type": "driver", "name": "motor", "body": "disk", "omega": 5.0},
            {"type": "clearance", "name": "j",
             "bearing": {"body": "ground", "at": [0.0, 0.0], "radius": 0.010},
             "journal": {"body": "disk", "point": "c", "radius": 0.009},
             "normal": {"law": "impact", "k": 1e9, "c_max": 100.0, "d_max": 1e-5},
             "friction": {"law": "coulomb", "mu": 0.3, "v0": 1e-4, "v1": 2e-4},
             "initial_eccentricity": [0.0, -0.00102], "allow_initial_penetration": true}
        ],
        "gravity": [0.0, -9.81],
        "t_end": 1.0
    });
    let m = Mechanism::from_scene(&Scene::from_json_str(&v.to_string()).unwrap()).unwrap();
    assert_eq!(m.integrated_bodies(), vec!["disk"]);
    assert!(m.prescribed_bodies().is_empty());
    let y0 = m.initial_state();
    // Assembly turned the disk at the driver's speed and left it 20 µm into the bearing.
    assert!((y0[5] - 5.0).abs() < 1e-12 && (y0[1] + 0.00102).abs() < 1e-12);
    let o = m.outputs(0.0, &y0);
    let c = &o.clearance[0];
    assert!(c.contact_force > 0.0 && c.friction_force != 0.0);
    let tau = o.driver_torques[0];
    let expect = -0.009 * c.friction_force;
    assert!(
        (tau - expect).abs() < 1e-12 * expect.abs(),
        "τ = {tau}, −R_J F_T = {expect}"
    );
    let mut dy = vec![0.0; 6];
    m.rhs(0.0, &y0, &mut dy);
    assert!(dy[5].abs() < 1e-12);
    // Power: the driver feeds exactly what friction dissipates at this instant (ė = 0).
    let p = m.power(0.0, &y0);
    assert!((p.driver - p.friction).abs() < 1e-12 * p.friction);
}
