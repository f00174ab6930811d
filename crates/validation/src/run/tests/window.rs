//! The metrics window (crate::run::window) on a crank a motor turns (closed form of the
//! motor's line) and on a span of the dry press (event counts).

use std::f64::consts::TAU;

use crate::report::metrics::EventQuantity;
use crate::run::case::Case;
use crate::run::plan::RunRequest;
use crate::run::prepare::Prepared;
use crate::run::simulate::simulate;
use lash_model::MetricsWindow;

/// A flywheel (I = 0.1 kg m², centre on its pivot) that a motor with the line
/// T = T_s (1 − ω/ω₀), T_s = 10 N m, ω₀ = 20 rad/s, spins up from ω_i:
///
/// ```text
/// I ω̇ = T_s (1 − ω/ω₀)  ⇒  ω(t) = ω₀ − (ω₀ − ω_i) e^{−t/τ},  τ = I ω₀ / T_s = 0.2 s
/// φ(t) = ω₀ t − (ω₀ − ω_i) τ (1 − e^{−t/τ})
/// ```
fn flywheel(omega_i: f64, t_end: f64) -> Prepared {
    let json = format!(
        r#"{{
  "bodies": [{{"name": "wheel", "mass": 10.0, "inertia": 0.1, "points": {{"O": [0.0, 0.0]}},
              "position": [0.0, 0.0], "angle": 0.0, "velocity": [0.0, 0.0],
              "angular_velocity": {omega_i}}}],
  "joints": [{{"type": "revolute", "name": "pivot", "a": {{"body": "wheel", "point": "O"}},
               "b": {{"body": "ground", "at": [0.0, 0.0]}}, "initial_rate": {omega_i}}}],
  "forces": [{{"type": "motor", "name": "motor", "rotor": "wheel", "stall_torque": 10.0,
               "no_load_speed": 20.0}}],
  "gravity": [0.0, -9.81],
  "t_start": 0.0,
  "t_end": {t_end},
  "roles": {{"crank": "pivot"}}
}}"#
    );
    Prepared::load(Case::from_json_bytes("flywheel", json.into_bytes()).unwrap()).unwrap()
}

fn phi(omega_i: f64, t: f64) -> f64 {
    let (w0, tau) = (20.0, 0.2);
    w0 * t - (w0 - omega_i) * tau * (1.0 - (-t / tau).exp())
}

fn omega(omega_i: f64, t: f64) -> f64 {
    20.0 - (20.0 - omega_i) * (-t / 0.2_f64).exp()
}

/// The last revolution of a crank a motor turns: starts where φ is one turn behind φ(t_end),
/// from rest (after the start-up, 10 τ) and from the no-load speed (constant speed: the turn
/// takes 2π/ω₀); the revolutions counted are φ(t_end)/2π. rtol 1e-8 on φ ≈ 36 rad is about
/// 4e-7 rad, 2e-8 s at ω₀: the times agree to 1e-6 s.
#[test]
fn a_motor_driven_cranks_last_revolution_follows_the_motors_line() {
    for omega_i in [0.0, 20.0] {
        let t_end = 2.0;
        let p = flywheel(omega_i, t_end);
        let req = RunRequest::new(p.options(&Default::default()).unwrap());
        let r = simulate(&p, &req).unwrap();
        let s = &r.summary;
        // Newton on the closed form for the turn's start.
        let target = phi(omega_i, t_end) - TAU;
        let mut t = t_end - TAU / 20.0;
        for _ in 0..50 {
            t -= (phi(omega_i, t) - target) / omega(omega_i, t);
        }
        let [from, to] = s.metrics_window.unwrap();
        assert_eq!(to, t_end);
        assert!((from - t).abs() < 1e-6, "ω_i {omega_i}: {from} vs {t}");
        if omega_i == 20.0 {
            assert!((from - (t_end - TAU / 20.0)).abs() < 1e-6, "{from}");
        }
        let turns = s.crank_revolutions.unwrap();
        assert!(
            (turns - phi(omega_i, t_end) / TAU).abs() < 1e-6,
            "{turns} vs {}",
            phi(omega_i, t_end) / TAU
        );
        // The window's samples: 2001 from the turn's start to t_end, the crank angle one turn
        // apart at its ends.
        assert_eq!(r.window.len(), 2001);
        let (a, b) = (
            r.window[0].crank_angle.unwrap(),
            r.window[2000].crank_angle.unwrap(),
        );
        assert!(((b - a) - TAU).abs() < 1e-6, "{}", b - a);
        // The whole run on request; the motor's work is the kinetic energy gained.
        let mut all = req.clone();
        all.window = Some(MetricsWindow::All);
        let r = simulate(&p, &all).unwrap();
        assert_eq!(r.summary.metrics_window, Some([0.0, t_end]));
        let e = r.summary.metrics.unwrap().energy.unwrap();
        let gained = 0.5 * 0.1 * (omega(omega_i, t_end).powi(2) - omega_i * omega_i);
        assert!(
            (e.kinetic_change - gained).abs() < 1e-6 * gained.max(1.0),
            "{e:?}"
        );
        assert!(
            e.balance_error.abs() <= 1e-6 * e.motor_work.abs().max(1e-3),
            "{e:?}"
        );
    }
}

/// A crank that turns less than once: the whole run; `revolutions` with a motor-driven crank
/// is an input error naming why.
#[test]
fn a_short_run_is_its_own_window_and_revolutions_need_a_driver() {
    let p = flywheel(0.0, 0.1);
    let req = RunRequest::new(p.options(&Default::default()).unwrap());
    let r = simulate(&p, &req).unwrap();
    assert_eq!(r.summary.metrics_window, Some([0.0, 0.1]));
    let json = String::from_utf8(match &p.case.source {
        crate::run::case::CaseSource::File { bytes, .. } => bytes.clone(),
        _ => unreachable!(),
    })
    .unwrap()
    .replace("\"t_end\": 0.1", "\"revolutions\": 3");
    let e = Prepared::load(Case::from_json_bytes("flywheel", json.into_bytes()).unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(
            "revolutions: needs roles.crank_driver (a driver at a prescribed speed): the time \
             the crank 'pivot' takes to turn is not known before the run; give t_end"
        ),
        "{e}"
    );
}

/// `--window T0:T1` on the dry press: the metrics cover [T0, T1]; its contact onsets are the
/// rising penetration events located in it, and slider_x_end is x at T1.
#[test]
fn a_span_window_counts_the_onsets_inside_it() {
    let p = Prepared::load_spec(
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../cases/press/dry_150rpm_c0.1.json")
            .to_str()
            .unwrap(),
        None,
    )
    .unwrap();
    let mut req = RunRequest::new(p.options(&Default::default()).unwrap());
    req.window = Some(MetricsWindow::Span { from: 0.1, to: 0.3 });
    req.extra_times = vec![0.3];
    let r = simulate(&p, &req).unwrap();
    assert_eq!(r.summary.metrics_window, Some([0.1, 0.3]));
    let m = r.summary.metrics.as_ref().unwrap();
    let located = r
        .events
        .iter()
        .filter(|e| e.quantity == EventQuantity::Penetration && e.rising)
        .filter(|e| (0.1..=0.3).contains(&e.t))
        .count();
    assert!(located > 0);
    assert_eq!(m.contact_onsets, Some(located));
    assert_eq!(m.slider_x_end, r.extra[0].slider_x);
    // Outside the run: an option error naming the window.
    req.window = Some(MetricsWindow::Span { from: 0.1, to: 0.9 });
    let e = simulate(&p, &req).unwrap_err().to_string();
    assert!(
        e.contains("window") && e.contains("not inside the run"),
        "{e}"
    );
}
