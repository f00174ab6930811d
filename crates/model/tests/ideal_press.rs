//! The ideal press (no clearance) against the closed form of docs/model.md §5, and the consistency
//! of the outputs (slider acceleration = right-hand side; driver torque = power balance).
mod common;
use common::*;
use lash_model::cases::{press_scene, PressJoint};
use lash_model::Mechanism;
use lash_solver::{OdeSystem, Output};

const R: f64 = 0.015;
const L: f64 = 0.35;

fn omega(rpm: f64) -> f64 {
    rpm * std::f64::consts::PI / 30.0
}

/// The exact state (rod, slider) of the ideal slider-crank at crank angle θ = ω t.
fn exact_state(theta: f64, w: f64) -> Vec<f64> {
    let (s, c) = theta.sin_cos();
    let big_s = (L * L - R * R * s * s).sqrt();
    let a = [R * c, R * s];
    let ad = [-R * w * s, R * w * c];
    let x = R * c + big_s;
    let xd = -R * w * s * (1.0 + R * c / big_s);
    let b = [x, 0.0];
    let bd = [xd, 0.0];
    let d = [b[0] - a[0], b[1] - a[1]];
    let dd = [bd[0] - ad[0], bd[1] - ad[1]];
    let psi = d[1].atan2(d[0]);
    let psid = (d[0] * dd[1] - d[1] * dd[0]) / (L * L);
    vec![
        0.5 * (a[0] + b[0]),
        0.5 * (a[1] + b[1]),
        psi,
        x,
        0.0,
        0.0,
        0.5 * (ad[0] + bd[0]),
        0.5 * (ad[1] + bd[1]),
        psid,
        xd,
        0.0,
        0.0,
    ]
}

fn ideal(rpm: f64) -> Mechanism {
    let m = Mechanism::from_scene(&press_scene(PressJoint::Ideal, rpm, 0.0)).unwrap();
    assert_eq!(m.integrated_bodies(), vec!["rod", "slider"]);
    assert_eq!(m.prescribed_bodies(), vec!["crank"]);
    m
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn geometry_of_the_closed_form_is_derived_from_the_scene() {
    let m = ideal(150.0);
    let i = m.ideal_slider_crank().expect("an in-line slider-crank");
    assert!((i.r - R).abs() < 1e-15 && (i.l - L).abs() < 1e-15, "{i:?}");
    assert!((i.omega - omega(150.0)).abs() < 1e-14);
    assert_eq!((i.theta0, i.offset), (0.0, 0.0));
    assert_eq!(m.crank_speed(), Some(omega(150.0)));
    // Two revolutions at 150 rpm.
    assert!((m.t_end() - 0.8).abs() < 1e-15);
}

#[test]
fn assembly_reaches_the_exact_initial_state() {
    for rpm in [120.0, 150.0, 180.0, 200.0] {
        let m = ideal(rpm);
        let y0 = m.initial_state();
        let ex = exact_state(0.0, omega(rpm));
        for (a, b) in y0.iter().zip(&ex) {
            assert!((a - b).abs() < 1e-12, "rpm {rpm}: {y0:?} vs {ex:?}");
        }
    }
}

#[test]
fn slider_acceleration_at_dead_centres_from_exact_states() {
    // docs/model.md §5: ẍ(θ=0) = −rω²(1 + r/l), ẍ(θ=π) = rω²(1 − r/l); printed values at θ = 0.
    let printed = [
        (120.0, -2.47022),
        (150.0, -3.85972),
        (180.0, -5.55800),
        (200.0, -6.86172),
    ];
    for (rpm, a0_printed) in printed {
        let w = omega(rpm);
        let m = ideal(rpm);
        let a0 = -R * w * w * (1.0 + R / L);
        let api = R * w * w * (1.0 - R / L);
        assert!(
            (a0 - a0_printed).abs() < 5e-6,
            "closed form {a0} vs docs/model.md §5 {a0_printed}"
        );
        let o0 = m.outputs(0.0, &exact_state(0.0, w));
        let t_pi = std::f64::consts::PI / w;
        let opi = m.outputs(t_pi, &exact_state(std::f64::consts::PI, w));
        let e0 = rel(o0.slider_a.unwrap(), a0);
        let epi = rel(opi.slider_a.unwrap(), api);
        println!("rpm {rpm}: rel. error at θ=0 {e0:.2e}, at θ=π {epi:.2e}");
        assert!(e0 < 1e-6 && epi < 1e-6);
        // And at a generic angle, against the full closed form.
        let i = m.ideal_slider_crank().unwrap();
        for th in [0.3, 1.1, 2.0, 4.0, 5.5] {
            let o = m.outputs(th / w, &exact_state(th, w));
            assert!(rel(o.slider_a.unwrap(), i.a_at(th)) < 1e-6, "θ = {th}");
            assert!((o.slider_x.unwrap() - i.x_at(th)).abs() < 1e-15);
            assert!(o.constraint_violation < 1e-15);
        }
    }
}

#[test]
fn slider_acceleration_at_dead_centres_along_an_rk4_run() {
    // RK4 with 2000 steps per revolution; outputs at every dead centre of two revolutions.
    for rpm in [120.0, 150.0, 180.0, 200.0] {
        let w = omega(rpm);
        let m = ideal(rpm);
        let period = 2.0 * std::f64::consts::PI / w;
        let h = period / 2000.0;
        let times: Vec<f64> = (0..=4)
            .map(|k| k as f64 * std::f64::consts::PI / w)
            .collect();
        let sol = run(&m, &rk4(h, false, Output::Times(times.clone())));
        let mut worst: f64 = 0.0;
        for (k, &t) in times.iter().enumerate() {
            let expect = if k % 2 == 0 {
                -R * w * w * (1.0 + R / L)
            } else {
                R * w * w * (1.0 - R / L)
            };
            let o = m.outputs(t, sol.state(k));
            worst = worst.max(rel(o.slider_a.unwrap(), expect));
        }
        println!("rpm {rpm}: h = {h:.3e} s, worst relative error of ẍ at dead centres {worst:.2e}");
        assert!(worst < 1e-6);
    }
}

#[test]
fn slider_acceleration_output_is_the_right_hand_side() {
    let m = ideal(150.0);
    let y = exact_state(0.7, omega(150.0));
    let mut dy = vec![0.0; m.dim()];
    m.rhs(0.7 / omega(150.0), &y, &mut dy);
    let o = m.outputs(0.7 / omega(150.0), &y);
    // Slider is the second integrated body: q̈ index 6 + 3.
    assert_eq!(o.slider_a.unwrap(), dy[9]);
    assert_eq!(o.slider_v.unwrap(), y[9]);
    let pk = m
        .point_kinematics("slider", "B", 0.7 / omega(150.0), &y)
        .unwrap();
    assert_eq!(pk.acc[0], dy[9]);
    // The crank tip: r ω² towards the pivot (prescribed body).
    let pk = m
        .point_kinematics("crank", "A", 0.7 / omega(150.0), &y)
        .unwrap();
    let w = omega(150.0);
    assert!((pk.acc[0] + R * w * w * 0.7f64.cos()).abs() < 1e-13);
    assert!((pk.acc[1] + R * w * w * 0.7f64.sin()).abs() < 1e-13);
}

#[test]
fn driver_power_equals_the_rate_of_mechanical_energy() {
    // Ideal joints, no dissipation: P_driver = d(T + V)/dt along the exact motion. The driver
    // torque of the prescribed crank comes from its Newton–Euler balance.
    for rpm in [120.0, 200.0] {
        let w = omega(rpm);
        let m = ideal(rpm);
        for th in [0.4, 1.7, 3.0, 4.4, 6.0] {
            let t = th / w;
            let dt = 1e-5;
            let e = |t: f64| {
                let o = m.outputs(t, &exact_state(w * t, w));
                o.kinetic_energy + o.potential_energy
            };
            let de_dt = (e(t + dt) - e(t - dt)) / (2.0 * dt);
            let p = m.power(t, &exact_state(th, w));
            let tau = m.outputs(t, &exact_state(th, w)).driver_torques[0];
            assert!((p.driver - tau * w).abs() < 1e-12 * p.driver.abs().max(1.0));
            let scale = p.driver.abs().max(1.0);
            assert!(
                (p.driver - de_dt).abs() < 1e-6 * scale,
                "rpm {rpm} θ {th}: P = {} vs dE/dt = {de_dt}",
                p.driver
            );
            assert_eq!((p.contact_damping, p.friction, p.film), (0.0, 0.0, 0.0));
        }
    }
}

/// Every body in the outputs: at the exact state of the ideal press at θ = 1 rad, the
/// per-element columns carry the crank's closed-form motion (centre at r/2 (cos θ, sin θ),
/// turning at ω with θ̈ = 0), the rod's and slider's exact positions and velocities, the
/// slider's closed-form acceleration, and the driver's torque; one value per column name.
#[test]
fn every_body_and_driver_has_its_named_columns() {
    let rpm = 150.0;
    let (w, theta) = (omega(rpm), 1.0);
    let m = ideal(rpm);
    let names = m.output_columns();
    let y = exact_state(theta, w);
    let o = m.outputs(theta / w, &y);
    let mut v = Vec::new();
    o.column_values(&mut v);
    assert_eq!(names.len(), v.len());
    assert_eq!(
        names.len(),
        3 * 9 + 1,
        "three bodies, one driver, no clearance joint"
    );
    let col = |n: &str| {
        v[names
            .iter()
            .position(|x| x == n)
            .unwrap_or_else(|| panic!("{n}"))]
    };
    let (s, c) = theta.sin_cos();
    assert!((col("crank.x") - 0.5 * R * c).abs() < 1e-15);
    assert!((col("crank.y") - 0.5 * R * s).abs() < 1e-15);
    assert!((col("crank.omega") - w).abs() < 1e-12 * w);
    assert!(col("crank.alpha").abs() < 1e-9);
    for (k, name) in ["rod.x", "rod.y", "rod.theta", "slider.x", "slider.y"]
        .iter()
        .enumerate()
    {
        assert!((col(name) - y[k]).abs() < 1e-15, "{name}");
    }
    assert!((col("rod.vx") - y[6]).abs() < 1e-12 && (col("slider.vx") - y[9]).abs() < 1e-12);
    let a_exact = m.ideal_slider_crank().unwrap().a(theta / w);
    assert!(
        rel(col("slider.ax"), a_exact) < 1e-9,
        "{} vs {a_exact}",
        col("slider.ax")
    );
    assert_eq!(col("slider.ax"), o.slider_a.unwrap());
    assert_eq!(col("crank_driver.torque"), o.driver_torques[0]);
}
