//! `lash run --until-periodic` (crate::run::steady): the run ends at the first revolution K ≥ 2 whose
//! section change is below the tolerance, reports K, and its metrics are those of revolution K.

use std::path::PathBuf;

use crate::commands::run::{self as commands, RunOptions};
use crate::error::ErrorKind;
use crate::progress::NoProgress;
use crate::run::prepare::Prepared;
use std::f64::consts::PI;

use crate::diagnostics::poincare::{self, PoincareSettings};
use crate::run::steady::{settle, settle_until, UntilPeriodic};

fn press(stem: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join(format!("../../cases/press/{stem}.json"))
        .display()
        .to_string()
}

/// The lubricated 0.5 mm press settles (its journal reaches the bearing region within a
/// revolution); K is the first revolution from 2 on whose change is below 0.01 c, every
/// change is a distance in units of c (the journal stays within about 1.2 c of the centre, so
/// no change exceeds 2.4), and the run written ends at t₀ + K T with the same K in
/// summary.json.
#[test]
fn a_lubricated_press_runs_until_its_section_settles() {
    let p = Prepared::load_spec(&press("lubricated_150rpm_c0.5"), None).unwrap();
    let opts = p.default_options();
    let s = settle(&p, &opts, &UntilPeriodic::new(1e-2)).unwrap();
    let k = s.revolutions;
    assert!(s.settled && (2..=10).contains(&k), "{s:?}");
    assert_eq!(s.section_changes.len(), k);
    assert!(s.last_change() < 1e-2);
    assert!(
        s.section_changes[1..k - 1].iter().all(|&d| d >= 1e-2),
        "{s:?}"
    );
    assert!(
        s.section_changes.iter().all(|&d| d > 0.0 && d < 2.4),
        "{s:?}"
    );

    let d = tempfile::tempdir().unwrap();
    let w = commands::run(
        &RunOptions {
            case: press("lubricated_150rpm_c0.5"),
            out: Some(d.path().join("run")),
            until_periodic: Some(UntilPeriodic::new(1e-2)),
            ..Default::default()
        },
        &NoProgress,
    )
    .unwrap();
    let period = 60.0 / 150.0;
    let sum = &w.result.summary;
    assert!(
        (sum.t_end - k as f64 * period).abs() < 1e-12,
        "{}",
        sum.t_end
    );
    assert_eq!(sum.until_periodic.as_ref(), Some(&s));
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.path().join("run/summary.json")).unwrap()).unwrap();
    assert_eq!(json["until_periodic"]["revolutions"], k);
    assert_eq!(json["until_periodic"]["settled"], true);
    assert!(commands::describe_run(&w.result).contains(&format!("settled after {k} revolutions")));
}

/// A dry joint is chaotic: with a cap of 3 revolutions and a tolerance of 1e-6 c it does not
/// settle, runs to the cap and says so.
#[test]
fn a_dry_press_runs_to_the_cap() {
    let p = Prepared::load_spec(&press("dry_150rpm_c0.1"), None).unwrap();
    let s = settle(
        &p,
        &p.default_options(),
        &UntilPeriodic {
            tol: 1e-6,
            max_revolutions: 3,
        },
    )
    .unwrap();
    assert!(
        !s.settled && s.revolutions == 3 && s.section_changes.len() == 3,
        "{s:?}"
    );
    assert!(s.describe().contains("not settled within 3 revolutions"));
}

/// Usage errors: no clearance joint (the ideal press), a test problem, a zero tolerance, a cap
/// below 2, and --t-end together with --until-periodic.
#[test]
fn until_periodic_refuses_what_it_cannot_do() {
    let ideal = Prepared::load_spec(&press("ideal_150rpm"), None).unwrap();
    let e = settle(&ideal, &ideal.default_options(), &UntilPeriodic::new(1e-2)).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::BadInput, "{e}");
    assert!(e.to_string().contains("clearance joint"), "{e}");
    let rober = Prepared::load_spec("testset:rober", None).unwrap();
    let e = settle(&rober, &rober.default_options(), &UntilPeriodic::new(1e-2)).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::BadInput, "{e}");
    let lub = Prepared::load_spec(&press("lubricated_150rpm_c0.1"), None).unwrap();
    for bad in [
        UntilPeriodic::new(0.0),
        UntilPeriodic {
            tol: 1e-2,
            max_revolutions: 1,
        },
    ] {
        let e = settle(&lub, &lub.default_options(), &bad).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::BadInput, "{e}");
    }
    let d = tempfile::tempdir().unwrap();
    let e = commands::run(
        &RunOptions {
            case: press("lubricated_150rpm_c0.1"),
            t_end: Some(1.0),
            out: Some(d.path().join("run")),
            until_periodic: Some(UntilPeriodic::new(1e-2)),
            ..Default::default()
        },
        &NoProgress,
    )
    .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::BadInput, "{e}");
}

/// A motor turns a hub (I = 0.5 kg m², pivoted at its centre) from ω_s = 10 rad/s towards
/// its no-load speed ω_0 = 4π rad/s (120 rpm; stall torque T_s = 5 N m); a wheel sits on
/// the hub through a clearance joint, centred, with no gravity: no contact, so nothing loads
/// the hub and e/c stays 0. The crank angle is then φ(t) = ω_0 t + (ω_s − ω_0) τ (1 − e^{−t/τ}),
/// τ = I ω_0/T_s, and turn k is the root of φ(t_k) = 2πk. The section of `--until-periodic`
/// does not move (change 0 < tol) and the run ends at turn 2; `lash poincare`'s section is
/// taken at turns 0..3, each at φ = 2πk, with T the mean turn t_3/3. Tolerance: the default
/// rtol 1e-8 on φ ≈ 4π is an error of about 1e-7 rad, 1e-8 s at ω ≈ 11 rad/s; 1e-7 s and
/// 1e-6 rad leave a margin of 10.
#[test]
fn a_motor_driven_crank_is_sectioned_at_its_turns() {
    let d = tempfile::tempdir().unwrap();
    let scene = super::motor_hub_scene(5.0, 1.0);
    let path = d.path().join("flywheel.json");
    std::fs::write(&path, scene.to_string()).unwrap();
    let p = Prepared::load_spec(path.to_str().unwrap(), None).unwrap();
    let opts = p.default_options();
    let (w0, ws, tau) = (4.0 * PI, 10.0, 0.5 * 4.0 * PI / 5.0);
    let phi = |t: f64| w0 * t + (ws - w0) * tau * (1.0 - (-t / tau).exp());
    let turn = |k: f64| {
        let mut t = 2.0 * PI * k / ws;
        for _ in 0..50 {
            t -= (phi(t) - 2.0 * PI * k) / (w0 + (ws - w0) * (-t / tau).exp());
        }
        t
    };
    let (s, t_end) = settle_until(&p, &opts, &UntilPeriodic::new(1e-2)).unwrap();
    assert!(s.settled && s.revolutions == 2, "{s:?}");
    assert_eq!(s.section_changes, vec![0.0, 0.0]);
    assert!((t_end - turn(2.0)).abs() < 1e-7, "{t_end} vs {}", turn(2.0));
    let settings = PoincareSettings {
        revolutions: 3,
        ..Default::default()
    };
    let sec = poincare::section(&p, &opts, &settings).unwrap();
    assert_eq!(sec.points.len(), 4);
    for (k, q) in sec.points.iter().enumerate() {
        let tk = turn(k as f64);
        assert!((q.t - tk).abs() < 1e-7, "turn {k}: {} vs {tk}", q.t);
        let a = q.crank_angle.unwrap();
        assert!((a - 2.0 * PI * k as f64).abs() < 1e-6, "turn {k}: φ = {a}");
        assert_eq!((q.ex_over_c, q.eps), (0.0, 0.0));
    }
    assert!((sec.period - turn(3.0) / 3.0).abs() < 1e-7);
    assert!(sec.on_angle);
    // A crank at rest has no time scale for a turn: a usage error naming the start.
    let mut rest = scene.clone();
    rest["joints"][0]["initial_rate"] = serde_json::json!(0.0);
    std::fs::write(&path, rest.to_string()).unwrap();
    let p = Prepared::load_spec(path.to_str().unwrap(), None).unwrap();
    let e = settle(&p, &opts, &UntilPeriodic::new(1e-2)).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::BadInput, "{e}");
    assert!(e.to_string().contains("at rest"), "{e}");
}
