//! Every scene of cases/press/ loads, matches its generator, declares its roles, and runs to
//! its end time with RK4 at a stable step, keeping ‖Φ‖ below 1e-8 (docs/model.md §5–§6).
//!
//! Steps (largest tried that is stable *and* keeps ‖Φ‖ < 1e-8; `rk4_scan` example):
//! ideal 1e-3 s; dry 2e-4 s (dry runs stay bounded up to 1e-3–2e-3 s but ‖Φ‖ reaches 1e-7);
//! lubricated c = 0.1 and 0.5 mm 2e-6 s; c = 0.3 mm 5e-7 s; c = 0.2 mm 2e-7 s (the film's
//! radial damping grows as (1 − ε²)^{−3/2} up to ε_cap = 0.99, which bounds the RK4 step).
mod common;
use common::*;
use lash_model::cases::press_catalogue;
use lash_model::{Mechanism, Scene};
use lash_solver::Output;

struct RunStats {
    phi_max: f64,
    eps_max: f64,
    f_n_max: f64,
    rms_dev_ideal: f64,
    wall: f64,
}

fn run_case(stem: &str) -> RunStats {
    let scene = Scene::from_path(cases_dir().join(format!("{stem}.json"))).unwrap();
    let m = Mechanism::from_scene(&scene).unwrap();
    let t_end = m.t_end();
    let period = 2.0 * std::f64::consts::PI / m.crank_speed().unwrap();
    // Whole run on a coarse grid for ‖Φ‖, last revolution on the 2001-point grid of
    // docs/outputs.md ("`metrics`").
    let mut times: Vec<f64> = (0..400).map(|i| t_end * i as f64 / 400.0).collect();
    let last: Vec<f64> = (0..=2000)
        .map(|i| t_end - period + period * i as f64 / 2000.0)
        .collect();
    times.retain(|&t| t < last[0]);
    times.extend_from_slice(&last);
    let mut opts = rk4(rk4_step(stem), false, Output::Times(times.clone()));
    opts.max_steps = 100_000_000;
    let t0 = std::time::Instant::now();
    let sol = run(&m, &opts);
    let wall = t0.elapsed().as_secs_f64();
    assert_eq!(sol.t_final, t_end, "{stem} reaches its end time");
    assert_eq!(sol.len(), times.len());
    let ideal = m.ideal_slider_crank().expect("in-line slider-crank");
    let mut s = RunStats {
        phi_max: 0.0,
        eps_max: 0.0,
        f_n_max: 0.0,
        rms_dev_ideal: 0.0,
        wall,
    };
    let mut n_last = 0;
    for k in 0..sol.len() {
        let y = sol.state(k);
        assert!(y.iter().all(|v| v.is_finite()));
        let o = m.outputs(sol.t[k], y);
        s.phi_max = s.phi_max.max(o.constraint_violation);
        if sol.t[k] >= last[0] {
            if let Some(c) = o.clearance.first() {
                s.eps_max = s.eps_max.max(c.eps);
                s.f_n_max = s.f_n_max.max(c.contact_force);
            }
            let th = ideal.theta_of_crank_angle(o.crank_angle.unwrap());
            s.rms_dev_ideal += (o.slider_a.unwrap() - ideal.a_at(th)).powi(2);
            n_last += 1;
        }
    }
    s.rms_dev_ideal = (s.rms_dev_ideal / n_last as f64).sqrt();
    println!(
        "{stem:26} h = {:.0e} s: wall {:.3} s, max ‖Φ‖ {:.2e}, last revolution: ε_max {:.3}, \
         F_N max {:.0} N, RMS(ẍ − ẍ_ideal) {:.3e} m/s²",
        rk4_step(stem),
        s.wall,
        s.phi_max,
        s.eps_max,
        s.f_n_max,
        s.rms_dev_ideal
    );
    assert!(s.phi_max < 1e-8, "{stem}: max ‖Φ‖ = {}", s.phi_max);
    s
}

#[test]
fn case_files_match_their_generator_and_declare_their_roles() {
    let stems = case_stems();
    let mut catalogue = press_catalogue();
    catalogue.sort_by(|a, b| a.0.cmp(&b.0));
    assert_eq!(
        stems,
        catalogue.iter().map(|c| c.0.clone()).collect::<Vec<_>>()
    );
    assert_eq!(stems.len(), 18);
    for (stem, generated) in &catalogue {
        let scene = Scene::from_path(cases_dir().join(format!("{stem}.json"))).unwrap();
        assert_eq!(
            &scene, generated,
            "{stem}.json is stale: rerun the write_press_cases example"
        );
        let m = Mechanism::from_scene(&scene).unwrap();
        let roles = m.roles();
        assert!(roles.slider.is_some() && roles.crank_driver.is_some());
        assert_eq!(roles.clearance_joint.is_some(), !stem.starts_with("ideal"));
        assert_eq!(m.prescribed_bodies(), vec!["crank"]);
        assert_eq!(m.integrated_bodies(), vec!["rod", "slider"]);
        let rpm: f64 = stem
            .split('_')
            .nth(1)
            .unwrap()
            .trim_end_matches("rpm")
            .parse()
            .unwrap();
        assert!((m.t_end() - 2.0 * 60.0 / rpm).abs() < 1e-12);
        if stem.starts_with("lubricated") {
            assert!(
                scene.notes.iter().any(|n| n.contains("L/D = 1")),
                "{stem}: L/D caveat"
            );
            assert_eq!(m.n_constraints(), 4);
        }
    }
}

#[test]
fn ideal_and_dry_cases_run_to_the_end_with_rk4() {
    for (stem, _) in press_catalogue() {
        if stem.starts_with("lubricated") {
            continue;
        }
        let s = run_case(&stem);
        if stem.starts_with("ideal") {
            // RK4 at 1e-3 s: the state error is O(h⁴) ≈ 1e-9 relative.
            assert!(s.rms_dev_ideal < 1e-8, "{stem}: {}", s.rms_dev_ideal);
        }
        if stem == "dry_150rpm_c0.1" {
            // docs/model.md §9: the soft contact penetrates deeper than the clearance (|e|/c > 2)
            // and the contact force exceeds 30 kN.
            assert!(
                s.eps_max > 2.0 && s.f_n_max > 3e4,
                "ε_max {} F_N {}",
                s.eps_max,
                s.f_n_max
            );
        }
    }
}

#[test]
fn lubricated_c01_cases_run_to_the_end_with_rk4() {
    for rpm in [120, 150, 180, 200] {
        let s = run_case(&format!("lubricated_{rpm}rpm_c0.1"));
        // The film carries the load: no contact at 0.1 mm.
        assert!(s.eps_max < 1.0);
        if rpm == 150 {
            // docs/model.md §9: within about 1e-3 m/s² RMS of the ideal mechanism.
            assert!(s.rms_dev_ideal < 1.5e-3, "{}", s.rms_dev_ideal);
        }
    }
}

#[test]
fn lubricated_c05_case_runs_to_the_end_with_rk4() {
    let s = run_case("lubricated_150rpm_c0.5");
    assert!(s.eps_max > 1.0, "at 0.5 mm the journal reaches the bearing");
}

/// Slow (BENCHMARKS.md, "Test-suite run times"): RK4 needs 2e-7 s and 5e-7 s steps for these
/// two cases.
#[test]
fn lubricated_c02_c03_cases_run_to_the_end_with_rk4() {
    run_case("lubricated_150rpm_c0.2");
    run_case("lubricated_150rpm_c0.3");
}
