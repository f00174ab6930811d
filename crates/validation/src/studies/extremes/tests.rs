//! The extremes matrix (`crate::studies::extremes`): the scene files, the scene that drives
//! the film to ε ≈ 0.999, the quick subset of the matrix (default run) and the full matrix
//! (ignored: `cargo test --release -p lash-validation --lib full_matrix -- --ignored`, or
//! `lash extremes`).

use std::path::PathBuf;

use crate::studies::extremes::catalogue::catalogue;
use crate::studies::extremes::outcome::{FailureKind, Matrix, Outcome};
use crate::studies::extremes::plan::{Plan, Setting};
use crate::studies::extremes::{plan, runner};
use lash_model::scene::JointSpec;
use lash_model::{Mechanism, Scene};

fn cases_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/extremes")
}

/// The committed files are the catalogue, byte for byte (regenerate them with
/// `cargo run --release -p lash-validation --example write_extreme_cases -- cases/extremes`).
#[test]
fn case_files_are_the_catalogue() {
    let mut on_disk: Vec<String> = std::fs::read_dir(cases_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".json"))
        .collect();
    on_disk.sort();
    let mut stems: Vec<String> = catalogue()
        .iter()
        .map(|s| format!("{}.json", s.stem))
        .collect();
    stems.sort();
    assert_eq!(on_disk, stems);
    for s in catalogue() {
        let text = std::fs::read_to_string(cases_dir().join(format!("{}.json", s.stem))).unwrap();
        assert!(text == s.json(), "{} differs from the catalogue", s.stem);
        let scene = Scene::from_json_str(&text).unwrap();
        Mechanism::from_scene(&scene).unwrap();
    }
}

/// The scenes reach the corners of the extremes matrix (module `extremes`; docs/outputs.md,
/// "`lash extremes`"): clearance 1e-9 … 1e-3 m, K 1e6 … 1e14, 1 … 2000 rpm, viscosity
/// 1e-4 … 10 Pa·s, friction 0 … 0.5.
#[test]
fn scenes_cover_the_corners() {
    let (mut c, mut k, mut rpm, mut visc, mut mu) = (vec![], vec![], vec![], vec![], vec![]);
    for s in catalogue() {
        for j in &s.scene.joints {
            match j {
                JointSpec::Clearance(cl) => {
                    c.push(cl.bearing.radius - cl.journal.radius);
                    if let lash_model::scene::NormalSpec::Impact(i) = &cl.normal {
                        k.push(i.k.unwrap());
                    }
                    if let lash_model::scene::FrictionSpec::Coulomb(f) = &cl.friction {
                        mu.push(f.mu);
                    }
                    if let Some(f) = &cl.film {
                        visc.push(f.viscosity);
                    }
                }
                JointSpec::Driver(d) => rpm.push(d.rpm.unwrap()),
                _ => {}
            }
        }
    }
    let range = |v: &[f64]| {
        (
            v.iter().copied().fold(f64::INFINITY, f64::min),
            v.iter().copied().fold(0.0, f64::max),
        )
    };
    let (c_lo, c_hi) = range(&c);
    assert!((c_lo - 1e-9).abs() < 1e-15 && (c_hi - 1e-3).abs() < 1e-12);
    assert!(c.iter().any(|x| (x - 1e-6).abs() < 1e-13));
    assert_eq!(range(&k), (1e6, 1e14));
    assert_eq!(range(&rpm), (1.0, 2000.0));
    assert_eq!(range(&visc), (1e-4, 10.0));
    assert_eq!(range(&mu), (0.0, 0.5));
}

/// The lubricated scene named for ε = 0.999 gets there: its reference (bdf against rodas5p)
/// reaches ε_max in [0.999, 0.9995) without touching the bearing (ε < 1).
#[test]
fn film_scene_reaches_eccentricity_0_999() {
    let s = catalogue()
        .into_iter()
        .find(|s| s.stem == "lubricated_eccentricity_0.999")
        .unwrap();
    let r = runner::prepare(s).unwrap();
    let eps = r.report.eps_max.unwrap();
    assert!((0.999..0.9995).contains(&eps), "ε_max = {eps}");
    assert!(r.report.agreement < 1e-8, "E_ref = {}", r.report.agreement);
}

/// Checks a finished matrix: no failure (every run agrees within its promise, ends in a typed
/// error, or is one of the documented KNOWN_FINDINGS), RK4 beyond its limit stopped inside
/// the run (its stability check, a non-finite state, or a mechanism that came apart:
/// "constraint_violation"), every reference converged.
fn check(m: &Matrix) {
    assert_eq!(m.failures, 0, "\n{}", m.failure_lines().join("\n"));
    let per_scene = 2 + plan::ADAPTIVE.len() * m.plan.tolerances.len();
    assert_eq!(m.cells.len(), m.scenes.len() * per_scene);
    for c in &m.cells {
        if let Setting::Rk4Beyond { .. } = c.setting {
            let r = m.scenes.iter().find(|r| r.stem == c.scene).unwrap();
            match &c.outcome {
                Outcome::Failed {
                    kind:
                        FailureKind::NonFiniteState
                        | FailureKind::Rk4Unstable
                        | FailureKind::StateRejected,
                    t,
                    ..
                } => assert!(*t < r.t_end, "{}: stopped at {t}", c.scene),
                o => panic!("{}: rk4 beyond its limit: {o:?}", c.scene),
            }
        }
    }
    for r in &m.scenes {
        // Converged references: two methods, and two tolerances, at rtol ≤ 1e-10 agree to
        // 2e-7 of the slider's scales.
        assert!(
            r.reference_rtol <= 1e-10 && r.agreement < 2e-7,
            "{}: reference at {} agrees to {}",
            r.stem,
            r.reference_rtol,
            r.agreement
        );
    }
}

#[test]
fn quick_matrix_ends_every_run_in_an_allowed_outcome() {
    let m = runner::run_cached(&Plan::quick(), None, &crate::NoProgress).unwrap();
    check(&m);
    // The known findings are not in the quick scenes: here every result meets its promise.
    assert!(m.known_lines().is_empty(), "{:?}", m.known_lines());
    // The promise is met by a result somewhere for every method but RK4 (whose inside step
    // on the film scene does not fit the budget): a method that only errors is a finding.
    for c in &m.counts {
        if c.label != "rk4 beyond" && c.label != "rk4" {
            assert!(c.agreed > 0, "{} never agreed: {c:?}", c.label);
        }
    }
}

#[test]
#[ignore = "the full matrix: 15 scenes × 50 runs, several minutes in release; `lash extremes` \
            runs the same and writes its report (BENCHMARKS.md, Extremes)"]
fn full_matrix_ends_every_run_in_an_allowed_outcome() {
    let m = runner::run_cached(&Plan::full(), None, &crate::NoProgress).unwrap();
    eprintln!("{}", m.to_markdown());
    check(&m);
}

/// The scenes whose solver section tightens the default run close their energy balance
/// (docs/model.md §1.8) to its quadrature error and to 1e-6 of the driver's work, at their
/// defaults (`lash run FILE`). At the press's default (bdf, rtol 1e-8) the same scenes are
/// 2.0e-3 J (dry 2000 rpm), 1.3e-2 J (lubricated 2000 rpm), 4.3e-4 J (viscosity 10) and
/// 4.2e-4 J (ε = 0.999) off, each above this bound (BENCHMARKS.md, "Energy balance of every
/// case"); the 1 µm film is 3.7e-3 J off with a quadrature error of 3.1e-3 J.
#[test]
fn scenes_with_a_solver_section_close_their_energy_balance_at_their_defaults() {
    let mut tightened = 0;
    for s in catalogue() {
        if s.scene.solver.is_empty() {
            continue;
        }
        tightened += 1;
        let p = s.prepared().unwrap();
        let o = p.default_options();
        assert_eq!(Some(o.rtol), s.scene.solver.rtol, "{}", s.stem);
        if let Some(m) = s.scene.solver.method {
            assert_eq!(o.method, m, "{}", s.stem);
        }
        let r = crate::run::simulate::simulate(&p, &crate::run::plan::RunRequest::new(o)).unwrap();
        let e = r.summary.metrics.as_ref().unwrap().energy.unwrap();
        // 1e-5 J: the floor the press cases keep at their own default (dry 150 rpm: 1.3e-5 J).
        let bound = 1e-5 + 1e-6 * e.driver_work.abs() + e.quadrature_error;
        assert!(
            e.balance_error.abs() <= bound,
            "{}: balance {:e} J, bound {bound:e} J ({e:?})",
            s.stem,
            e.balance_error
        );
    }
    assert_eq!(tightened, 5);
}
