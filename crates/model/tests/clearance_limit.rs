//! Clearance → 0 with stiff contact converges to the ideal mechanism (docs/model.md §5): a dry
//! press with c = 1e-7 m and K = 1e14 N/m^1.5 keeps the slider within 1e-6 m of the closed
//! form over the second revolution.
mod common;
use common::*;
use lash_model::cases::{press_scene, PressJoint};
use lash_model::scene::{JointSpec, NormalSpec};
use lash_model::Mechanism;
use lash_solver::Output;

#[test]
fn tiny_clearance_and_stiff_contact_follow_the_closed_form() {
    let mut scene = press_scene(PressJoint::Dry, 150.0, 1e-7);
    for j in scene.joints.iter_mut() {
        if let JointSpec::Clearance(c) = j {
            c.journal.radius = c.bearing.radius - 1e-7;
            if let NormalSpec::Impact(s) = &mut c.normal {
                s.k = Some(1e14);
            }
        }
    }
    let m = Mechanism::from_scene(&scene).unwrap();
    let ideal = m.ideal_slider_crank().unwrap();
    let t_end = m.t_end();
    let half = 0.5 * t_end;
    let times: Vec<f64> = (0..=2000)
        .map(|i| half + (t_end - half) * i as f64 / 2000.0)
        .collect();
    let h = 1e-5;
    let t0 = std::time::Instant::now();
    let sol = run(&m, &rk4(h, false, Output::Times(times.clone())));
    let wall = t0.elapsed().as_secs_f64();
    let mut worst: f64 = 0.0;
    let mut eps_max: f64 = 0.0;
    for (k, &t) in times.iter().enumerate() {
        let o = m.outputs(t, sol.state(k));
        let th = ideal.theta_of_crank_angle(o.crank_angle.unwrap());
        worst = worst.max((o.slider_x.unwrap() - ideal.x_at(th)).abs());
        eps_max = eps_max.max(o.clearance[0].eps);
    }
    println!(
        "c = 1e-7 m, K = 1e14: RK4 h = {h:e} s, wall {wall:.3} s, max |x − x_ideal| over the \
         second revolution {worst:.3e} m, ε_max {eps_max:.2}"
    );
    assert!(worst < 1e-6);
}
