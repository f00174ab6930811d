//! Kink events through the runner (docs/model.md §7, "The default"): a dry scene that leaves
//! `kink_events` out runs its adaptive methods with them and with exact event steps, and says
//! so in summary.json; the paper's RK4 runs without them, and would compute the same numbers
//! with them (RK4 locates no event: the kink functions only add crossings to its list).

use std::path::PathBuf;

use crate::report::metrics::EventQuantity;
use crate::run::case::Case;
use crate::run::plan::RunRequest;
use crate::run::prepare::Prepared;
use crate::run::result::RunResult;
use crate::run::simulate::simulate;
use lash_solver::Method;

/// The press case `stem` of the catalogue with `kink_events` as given (None: left out, as the
/// catalogue has it).
fn case(stem: &str, kinks: Option<bool>) -> Prepared {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/press")
        .join(format!("{stem}.json"));
    let mut scene = lash_model::Scene::from_path(&path).unwrap();
    assert_eq!(
        scene.kink_events, None,
        "the catalogue leaves the field out"
    );
    scene.kink_events = kinks;
    Prepared::with_scene(Case::load(path.to_str().unwrap(), None).unwrap(), scene).unwrap()
}

fn run(p: &Prepared, method: Method, tol: f64, t_end: f64) -> RunResult {
    let (rtol, step) = if method.is_fixed_step() {
        (None, Some(tol))
    } else {
        (Some(tol), None)
    };
    let mut req = RunRequest::new(p.options_for(method, rtol, step, None).unwrap());
    req.t_end = Some(t_end);
    simulate(p, &req).unwrap()
}

/// (kink crossings, contact onsets) among the events of a run.
fn counts(r: &RunResult) -> (usize, usize) {
    let kinks = r
        .events
        .iter()
        .filter(|e| r.event_names[e.index].0.starts_with("kink_"))
        .count();
    let onsets = r
        .events
        .iter()
        .filter(|e| e.quantity == EventQuantity::Penetration && e.rising)
        .count();
    (kinks, onsets)
}

#[test]
fn a_dry_scene_runs_its_adaptive_methods_with_kink_events_and_exact_event_steps() {
    let dry = case("dry_150rpm_c0.1", None);
    assert!(dry.info.as_ref().unwrap().kink_events);
    let o = dry
        .options_for(Method::Tsit54, Some(1e-8), None, None)
        .unwrap();
    assert!(o.exact_event_steps && o.events);
    // The paper's RK4 locates no event, so it takes no exact event steps either.
    let rk4 = dry
        .options_for(Method::Rk4, None, Some(2e-4), None)
        .unwrap();
    assert!(!rk4.exact_event_steps && !rk4.events);
    // Off where the scene says so, and for the lubricated press (its film: docs/model.md §7).
    let off = case("dry_150rpm_c0.1", Some(false));
    assert!(
        !off.options_for(Method::Tsit54, Some(1e-8), None, None)
            .unwrap()
            .exact_event_steps
    );
    let lub = case("lubricated_150rpm_c0.1", None);
    assert!(!lub.info.as_ref().unwrap().kink_events);
    assert!(!lub.default_options().exact_event_steps);

    // The first 0.1 s hold the first contact phases (onset at 3.6 ms, docs/model.md §7):
    // the default run restarts at the kinks of IMPACT and of the friction law, the run with
    // `false` only at δ's zeros, and both see the same contact onsets.
    let t_end = 0.1;
    let with = run(&dry, Method::Tsit54, 1e-8, t_end);
    let without = run(&off, Method::Tsit54, 1e-8, t_end);
    assert_eq!(with.summary.kink_events, Some(true));
    assert_eq!(without.summary.kink_events, Some(false));
    let (k_with, on_with) = counts(&with);
    let (k_without, on_without) = counts(&without);
    println!("kinks {k_with} / {k_without}, onsets {on_with} / {on_without}");
    assert_eq!(k_without, 0);
    assert!(k_with > 0 && with.summary.events == without.summary.events + k_with);
    assert_eq!(on_with, on_without);
    assert!(on_with >= 1);
}

#[test]
fn the_papers_rk4_computes_the_same_numbers_with_or_without_kink_events() {
    // The default (the field left out) runs RK4 without kink events; `true` in the scene wins
    // and adds their functions, whose crossings RK4 counts at its step ends. Nothing else
    // changes: RK4 locates no event, so no step is cut and no hook runs.
    let t_end = 0.1;
    let auto = run(&case("dry_150rpm_c0.1", None), Method::Rk4, 2e-4, t_end);
    let on = run(
        &case("dry_150rpm_c0.1", Some(true)),
        Method::Rk4,
        2e-4,
        t_end,
    );
    assert_eq!(auto.summary.kink_events, Some(false));
    assert_eq!(on.summary.kink_events, Some(true));
    assert_eq!(auto.summary.stats, on.summary.stats);
    assert_eq!(auto.summary.events, 0);
    assert_eq!(on.summary.events, 0);
    assert_eq!(auto.summary.metrics, on.summary.metrics);
    let names = auto.trajectory.header().unwrap().names().to_vec();
    assert_eq!(names, on.trajectory.header().unwrap().names());
    for name in &names {
        // Bit for bit (a column may hold NaN where a quantity does not apply).
        let bits = |r: &RunResult| {
            let c = r.trajectory.column(name).unwrap();
            c.iter().map(|x| x.to_bits()).collect::<Vec<u64>>()
        };
        assert_eq!(bits(&auto), bits(&on), "column {name}");
    }
    let (k_auto, onsets_auto) = counts(&auto);
    let (k_on, onsets_on) = counts(&on);
    assert_eq!(k_auto, 0);
    assert!(k_on > 0, "RK4 counts the kink crossings at its step ends");
    assert_eq!(onsets_auto, onsets_on);
}
