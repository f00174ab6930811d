//! `lash run --until-periodic` (crate::run::steady): the run ends at the first revolution K ≥ 2 whose
//! section change is below the tolerance, reports K, and its metrics are those of revolution K.

use std::path::PathBuf;

use crate::commands::run::{self as commands, RunOptions};
use crate::error::ErrorKind;
use crate::progress::NoProgress;
use crate::run::prepare::Prepared;
use crate::run::steady::{settle, UntilPeriodic};

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
