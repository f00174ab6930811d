//! Tests of the runner on the paper's press and built-in problems (closed forms, physical
//! expectations, energy balance, event counts) and of runs until periodic.

mod edges;
mod energy;
mod kinks;
mod simulate;
mod steady;
mod window;

/// A hub on a pivot at its centre (m = 1 kg, I = 0.5 kg m²) turned from 10 rad/s by a motor
/// with the line T_s (1 − ω/ω₀), ω₀ = 4π rad/s (120 rpm), and a wheel on it through a
/// centred clearance joint, no gravity: no contact, so nothing but the motor loads the hub
/// (τ = I ω₀ / T_s). The crank is the hub's pivot.
pub(crate) fn motor_hub_scene(stall_torque: f64, t_end: f64) -> serde_json::Value {
    serde_json::json!({
        "bodies": [
            {"name": "hub", "mass": 1.0, "inertia": 0.5, "points": {"O": [0.0, 0.0]},
             "position": [0.0, 0.0], "angle": 0.0},
            {"name": "wheel", "mass": 1.0, "inertia": 0.1, "points": {"C": [0.0, 0.0]},
             "position": [0.0, 0.0], "angle": 0.0}
        ],
        "joints": [
            {"type": "revolute", "name": "hub_pivot", "a": {"body": "hub", "point": "O"},
             "b": {"body": "ground", "at": [0.0, 0.0]}, "initial_rate": 10.0},
            {"type": "clearance", "name": "hub_wheel",
             "bearing": {"body": "hub", "point": "O", "radius": 0.05},
             "journal": {"body": "wheel", "point": "C", "radius": 0.0499},
             "normal": {"law": "impact", "k": 2.34e10, "c_max": 100.0, "d_max": 1e-5}}
        ],
        "forces": [
            {"type": "motor", "name": "motor", "rotor": "hub", "stall_torque": stall_torque,
             "no_load_rpm": 120.0}
        ],
        "gravity": [0.0, 0.0],
        "t_start": 0.0,
        "t_end": t_end,
        "roles": {"clearance_joint": "hub_wheel", "crank": "hub_pivot"}
    })
}
