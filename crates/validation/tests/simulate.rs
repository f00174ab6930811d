//! The core runner on the paper's press and a built-in test problem: closed forms, physical
//! expectations of docs/model.md §5–§9, the energy balance, and contact onsets against a tight
//! reference (skipped impacts).

use std::path::PathBuf;

use lash_model::cases::{press_scene, PressJoint};
use lash_model::Mechanism;
use lash_solver::Method;
use lash_validation::metrics::EventQuantity;
use lash_validation::simulate::{simulate, Prepared, RunRequest, RunResult};

fn case(stem: &str) -> Prepared {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/press")
        .join(format!("{stem}.json"));
    Prepared::load_spec(p.to_str().unwrap(), None).unwrap()
}

fn run(p: &Prepared, method: Method, tol: f64, t_end: Option<f64>) -> RunResult {
    let (rtol, step) = if method.is_fixed_step() {
        (None, Some(tol))
    } else {
        (Some(tol), None)
    };
    let mut req = RunRequest::new(p.options_for(method, rtol, step, None).unwrap());
    req.t_end = t_end;
    simulate(p, &req).unwrap()
}

fn onsets(r: &RunResult, t0: f64, t1: f64) -> Vec<f64> {
    r.events
        .iter()
        .filter(|e| e.quantity == EventQuantity::Penetration && e.rising)
        .filter(|e| t0 <= e.t && e.t <= t1)
        .map(|e| e.t)
        .collect()
}

/// docs/model.md §5: ẍ(θ=0) = −r ω² (1 + r/l) for r = 15 mm, l = 350 mm; the closed form derived
/// from the press scenes (these checks moved here with the model's `IdealSliderCrank`).
#[test]
fn ideal_slider_crank_of_the_press_scenes_has_the_closed_form_values() {
    for (rpm, a0) in [
        (120.0, -2.47022),
        (150.0, -3.85972),
        (180.0, -5.55800),
        (200.0, -6.86172),
    ] {
        let m = Mechanism::from_scene(&press_scene(PressJoint::Ideal, rpm, 0.0)).unwrap();
        let i = m.ideal_slider_crank().unwrap();
        assert!((i.a_at(0.0) - a0).abs() < 5e-6, "{rpm}: {}", i.a_at(0.0));
        let w2 = i.omega * i.omega;
        let at_pi = i.a_at(std::f64::consts::PI);
        assert!((at_pi - 0.015 * w2 * (1.0 - 0.015 / 0.35)).abs() < 1e-12);
        assert!((i.x_at(0.0) - 0.365).abs() < 1e-15);
        // Central differences in θ: dx/dt = ω dx/dθ, truncation O(h²) ≈ 1e-10 relative.
        let h = 1e-5;
        for k in 0..24 {
            let th = 0.3 + k as f64 * 0.27;
            let dx = i.omega * (i.x_at(th + h) - i.x_at(th - h)) / (2.0 * h);
            let dv = i.omega * (i.v_at(th + h) - i.v_at(th - h)) / (2.0 * h);
            assert!((dx - i.v_at(th)).abs() < 1e-9, "θ = {th}");
            assert!((dv - i.a_at(th)).abs() < 1e-8 * w2, "θ = {th}");
        }
    }
    // A scene that is not a slider-crank has no closed form: a test problem has no mechanism.
    let p = Prepared::load_spec("testset:hires", None).unwrap();
    assert!(p.info.is_none());
}

#[test]
fn ideal_press_follows_the_closed_form_and_conserves_energy() {
    let p = case("ideal_150rpm");
    let r = run(&p, Method::Dop853, 1e-10, None);
    let m = r.summary.metrics.as_ref().unwrap();
    // The ideal mechanism is the closed form: only the integration error remains.
    assert!(m.slider_acc_rms_dev_ideal.unwrap() < 1e-9, "{m:?}");
    // Extremes at the dead centres (docs/model.md §5): θ = 0 → −3.85972, θ = π → rω²(1 − r/l).
    assert!((m.slider_acc_min.unwrap() + 3.85972).abs() < 1e-5);
    let w2 = (5.0 * std::f64::consts::PI).powi(2);
    assert!((m.slider_acc_max.unwrap() - 0.015 * w2 * (1.0 - 0.015 / 0.35)).abs() < 1e-6);
    // No clearance joint: its metrics are null.
    assert_eq!(
        (m.eps_max, m.contact_onsets, m.film_thickness_min),
        (None, None, None)
    );
    assert!((m.slider_x_end.unwrap() - 0.365).abs() < 1e-9);
    assert!(m.constraint_violation_max < 1e-10);
    // Two whole revolutions of a frictionless mechanism: the driver's net work is ΔT + ΔV = 0
    // (the crank returns to its start), and nothing dissipates.
    let e = m.energy.unwrap();
    assert_eq!(
        (
            e.dissipated_damping,
            e.dissipated_friction,
            e.dissipated_film
        ),
        (0.0, 0.0, 0.0)
    );
    assert!(
        e.kinetic_change.abs() < 1e-9 && e.driver_work.abs() < 1e-6,
        "{e:?}"
    );
    assert!(e.balance_error.abs() < 1e-9, "{e:?}");
    // The windows: 2001 samples on the last revolution, 4001 on the trajectory.
    assert_eq!((r.window.len(), r.trajectory.len()), (2001, 4001));
    assert_eq!(r.window[0].t, 0.4);
    assert_eq!(r.window[2000].t, 0.8);
}

#[test]
fn lubricated_press_film_carries_the_load() {
    let p = case("lubricated_150rpm_c0.1");
    let r = run(&p, Method::Bdf, 1e-8, None);
    let m = r.summary.metrics.as_ref().unwrap();
    // docs/model.md §9: the journal never touches the bearing; the slider stays within about
    // 1e-3 m/s² RMS of the ideal mechanism.
    let eps = m.eps_max.unwrap();
    assert!(eps > 0.3 && eps < 1.0, "{eps}");
    assert_eq!(m.contact_onsets, Some(0));
    assert_eq!(m.penetration_max, Some(0.0));
    assert_eq!(m.contact_force_max, Some(0.0));
    assert!((m.film_thickness_min.unwrap() - 1e-4 * (1.0 - eps)).abs() < 1e-15);
    assert!(m.film_force_max.unwrap() > 1e3);
    let dev = m.slider_acc_rms_dev_ideal.unwrap();
    assert!(dev > 1e-4 && dev < 1.5e-3, "{dev}");
    // Energy: the film dissipates what the driver puts in; the balance closes far below it.
    let e = m.energy.unwrap();
    assert!(e.dissipated_film > 0.1, "{e:?}");
    assert_eq!((e.dissipated_damping, e.dissipated_friction), (0.0, 0.0));
    assert!(e.balance_error.abs() < 1e-4 * e.dissipated_film, "{e:?}");
    assert!(e.quadrature_error < 1e-6 * e.dissipated_film, "{e:?}");
}

/// docs/model.md §7: missed events show up as skipped impacts. The dry press is chaotic (§9), so
/// runs are compared where trajectories still agree: the first revolution for the default
/// method at rtol 1e-10 (its other settings the defaults: event samples, h_max), the first
/// half for every adaptive method at rtol 1e-6.
#[test]
fn dry_press_contact_onsets_match_a_tight_reference() {
    let p = case("dry_150rpm_c0.1");
    let t_rev = p.period().unwrap();
    let reference = run(&p, Method::Dop853, 1e-12, Some(t_rev));
    let ref_on = onsets(&reference, 0.0, t_rev);
    assert!(ref_on.len() >= 20, "{}", ref_on.len());
    let r = run(
        &p,
        lash_validation::simulate::DEFAULT_METHOD,
        1e-10,
        Some(t_rev),
    );
    let on = onsets(&r, 0.0, t_rev);
    assert_eq!(on.len(), ref_on.len(), "{on:?}\n{ref_on:?}");
    for (a, b) in on.iter().zip(&ref_on).take(ref_on.len() / 2) {
        assert!((a - b).abs() < 1e-6, "{a} vs {b}");
    }
    let half = 0.5 * t_rev;
    let ref_half = onsets(&reference, 0.0, half).len();
    for m in Method::ALL.into_iter().filter(|m| !m.is_fixed_step()) {
        let r = run(&p, m, 1e-6, Some(half));
        assert_eq!(onsets(&r, 0.0, half).len(), ref_half, "{m}");
        assert_eq!(r.summary.events, r.events.len(), "{m}");
    }
}

#[test]
fn dry_press_energy_balance_and_rk4_crossings() {
    let p = case("dry_150rpm_c0.1");
    let r = run(&p, Method::Dop853, 1e-10, None);
    let m = r.summary.metrics.as_ref().unwrap();
    // docs/model.md §9: deeper than the clearance, contact force above 30 kN.
    assert!(
        m.eps_max.unwrap() > 2.0 && m.contact_force_max.unwrap() > 3e4,
        "{m:?}"
    );
    assert_eq!(m.film_force_max, Some(0.0));
    assert_eq!(m.film_thickness_min, None);
    let e = m.energy.unwrap();
    let dissipated = e.dissipated_damping + e.dissipated_friction;
    assert!(
        e.dissipated_damping > 0.0 && e.dissipated_friction > 0.0,
        "{e:?}"
    );
    assert!(
        e.balance_error.abs() < 1e-3 * dissipated + e.quadrature_error,
        "{e:?}"
    );
    // The paper's RK4 runs without event location: no located events, but its crossings of
    // δ at the step ends still count as contact onsets.
    let rk = run(&p, Method::Rk4, 2e-4, None);
    assert_eq!(rk.summary.events, 0);
    assert_eq!(rk.summary.stats.events, 0);
    let n = rk.summary.metrics.as_ref().unwrap().contact_onsets.unwrap();
    assert!(n >= 5, "{n}");
    // Four stages per step and the initial evaluation (the last of the 4001 steps is a
    // rounding sliver).
    let st = &rk.summary.stats;
    assert_eq!(st.rhs_evals, 4 * st.accepted + 1);
    assert!(st.accepted == 4000 || st.accepted == 4001);
}

#[test]
fn hires_reference_error_at_rtol_1e8() {
    let p = Prepared::load_spec("testset:hires", None).unwrap();
    let r = run(&p, Method::Rodas5p, 1e-8, None);
    let s = &r.summary;
    assert_eq!(s.case, "testset:hires");
    assert_eq!(s.scene_sha256, None);
    assert!(s.metrics.is_none());
    let err = s.reference_error.unwrap();
    // Rodas5P is order 5: rtol 1e-8 gives an error well below 1e-5 (measured 7e-10).
    assert!(err < 1e-5 && err > 0.0, "{err}");
    assert_eq!(s.final_state.as_ref().unwrap().len(), 8);
    assert_eq!(r.extra_columns().len(), 8);
    assert_eq!(r.trajectory.len(), s.stats.accepted + 1);
    assert!(p.t_span(Some(1.0)).is_err());
}

#[test]
fn catalogue_case_prepares_the_scene_of_its_file() {
    // Case::catalogue builds the scene in code; the file in cases/press/ was written from the
    // same generator, so both prepare to the same scene and mechanism facts.
    use lash_validation::case::Case;
    let name = "lubricated_150rpm_c0.2";
    let from_code = Prepared::load(Case::catalogue(name).unwrap()).unwrap();
    let from_file = case(name);
    assert_eq!(from_code.scene(), from_file.scene());
    assert_eq!(from_code.info, from_file.info);
    assert_eq!(from_code.case.name, from_file.case.name);
    assert_eq!(from_code.case.sha256(), None);
}
