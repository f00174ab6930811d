//! The core runner on the paper's press and a built-in test problem: closed forms, physical
//! expectations of docs/model.md §5–§9, the energy balance, and contact onsets against a tight
//! reference (skipped impacts).

use std::path::PathBuf;

use crate::error::{Error, ErrorKind};
use crate::report::metrics::EventQuantity;
use crate::report::trajectory::{Columns, CsvFile, Header, TrajectorySink};
use crate::run::case::Case;
use crate::run::plan::RunRequest;
use crate::run::prepare::Prepared;
use crate::run::result::RunResult;
use crate::run::simulate::{simulate, simulate_into};
use lash_model::cases::{press_scene, PressJoint};
use lash_model::Mechanism;
use lash_solver::Method;

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
    // Lagrange–Baumgarte, as before `auto`: at BDF rtol 1e-8 its energy balance closes to
    // 5.6e-6 J of the film's 0.93 J (1.2e-5 J with Boole's rule on the dense output); `auto` (minimal) closes it to 2.2e-4 J at 1e-8 and 1.5e-6
    // J at 1e-10 (the balance converges with rtol, the error is the integration's, not the
    // formulation's: tests/minimal.rs in lash-model), over this test's 1e-4 bound.
    let p = case("lubricated_150rpm_c0.1")
        .with_formulation(lash_model::FormulationName::LagrangeBaumgarte)
        .unwrap();
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
    // BDF integrates the power at its own steps; its quadrature error is the difference
    // with Boole's rule on its dense output (docs/outputs.md, `energy`): 3.2e-5 J, which
    // bounds the balance (5.6e-6 J; 1.2e-5 J when the integrals were Boole's on the dense
    // output, whose own estimate was below 1e-6 of the film's).
    assert!(e.balance_error.abs() <= e.quadrature_error, "{e:?}");
    assert!(e.quadrature_error < 1e-4 * e.dissipated_film, "{e:?}");
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
    let r = run(&p, crate::run::prepare::DEFAULT_METHOD, 1e-10, Some(t_rev));
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
    // One row per accepted step and the start, the state in columns y0..y7.
    let h = r.trajectory.header().unwrap();
    assert_eq!(
        h.names()[13..],
        ["y0", "y1", "y2", "y3", "y4", "y5", "y6", "y7"]
    );
    assert_eq!(r.trajectory.len(), s.stats.accepted + 1);
    assert_eq!(r.trajectory_rows, r.trajectory.len());
    let y7 = r.trajectory.column("y7").unwrap();
    assert_eq!(y7.last(), s.final_state.as_ref().unwrap().last());
    assert!(p.t_span(Some(1.0)).is_err());
}

#[test]
fn press_case_prepares_the_scene_of_its_file() {
    // Case::press builds the scene in code; the file in cases/press/ was written from the
    // same generator, so both prepare to the same scene and mechanism facts.
    use crate::run::case::Case;
    use crate::run::press::PressCase;
    let name = "lubricated_150rpm_c0.2";
    let from_code = Prepared::load(Case::press(PressCase::lubricated(150, 200))).unwrap();
    let from_file = case(name);
    assert_eq!(from_code.scene(), from_file.scene());
    assert_eq!(from_code.info, from_file.info);
    assert_eq!(from_code.case.name, from_file.case.name);
    assert_eq!(from_code.case.sha256(), None);
}

/// The two-link pendulum of README.md ("Writing a scene"), read from the README itself.
fn readme_pendulum() -> String {
    let readme =
        std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../README.md"))
            .unwrap();
    let from = readme.find("A two-link pendulum").unwrap();
    let rest = &readme[from..];
    let start = rest.find("```json\n").unwrap() + "```json\n".len();
    let end = start + rest[start..].find("```").unwrap();
    rest[start..end].to_string()
}

fn prepared(name: &str, json: &str) -> Prepared {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join(format!("{name}.json"));
    std::fs::write(&p, json).unwrap();
    Prepared::load(Case::load(p.to_str().unwrap(), None).unwrap()).unwrap()
}

/// Keeps the largest value of one column over a trajectory's rows: a sink that sees a
/// million rows in constant memory.
struct MaxOf {
    name: &'static str,
    col: usize,
    max: f64,
    rows: usize,
}

impl TrajectorySink for MaxOf {
    fn start(&mut self, h: &Header) -> Result<(), Error> {
        self.col = h.index(self.name).unwrap();
        Ok(())
    }
    fn row(&mut self, v: &[f64]) -> Result<(), Error> {
        self.max = self.max.max(v[self.col]);
        self.rows += 1;
        Ok(())
    }
}

/// docs/outputs.md (`metrics`): the maxima are taken over every accepted step's dense output,
/// not over the output grid. The README's pendulum hits its elbow in impacts shorter than the
/// 2001-point grid's spacing (0.5 ms): the grid sees a fraction of the peak force. The true
/// peak comes from a tight run (dop853, rtol 1e-11) sampled every 5 µs (its error there is
/// (5 µs / 0.3 ms)² ≈ 3e-4 of the peak; the impact's time scale is about 0.3 ms).
#[test]
fn the_pendulums_peak_contact_force_is_the_true_peak() {
    let p = prepared("pendulum", &readme_pendulum());
    let r = run(&p, crate::run::prepare::DEFAULT_METHOD, 1e-8, None);
    let m = r.summary.metrics.as_ref().unwrap();
    let peak = m.contact_force_max.unwrap();
    let mut req = RunRequest::new(
        p.options_for(Method::Dop853, Some(1e-11), None, None)
            .unwrap(),
    );
    req.trajectory_points = Some(200_001);
    req.energy = false;
    let mut fine = MaxOf {
        name: "contact_force",
        col: 0,
        max: 0.0,
        rows: 0,
    };
    let tight = simulate_into(&p, &req, &mut fine).unwrap();
    assert_eq!((fine.rows, tight.trajectory_rows), (200_001, 200_001));
    assert!(tight.trajectory.is_empty(), "a sink run keeps no rows");
    assert!(
        (peak - fine.max).abs() < 2e-3 * fine.max,
        "metrics {peak} N, true peak {} N",
        fine.max
    );
    // The tight run's own dense maximum agrees with its 5 µs grid.
    let tight_peak = tight.summary.metrics.unwrap().contact_force_max.unwrap();
    assert!((tight_peak - fine.max).abs() < 1e-3 * fine.max);
    // The 2001-point grid (the definition before) misses most of it.
    let grid = r
        .window
        .iter()
        .filter_map(|s| s.contact_force)
        .fold(0.0, f64::max);
    assert!(grid < 0.9 * fine.max, "grid {grid} N vs {} N", fine.max);
    // The peak is found where the force peaks: penetration and ε agree with it.
    let j = &m.clearance_joints["elbow"];
    assert_eq!(j.contact_force_max, peak);
    // δ = c (ε − 1), c = 1 mm.
    let from_eps = (m.eps_max.unwrap() - 1.0) * 1e-3;
    assert!(
        j.penetration_max > 0.0 && (from_eps - j.penetration_max).abs() < 1e-6 * j.penetration_max
    );
}

/// docs/outputs.md (`trajectory.csv`): every body, every clearance joint, every driver by name
/// after the fixed columns; the second clearance joint of a mechanism has its columns and its
/// metrics. A two-link pendulum hanging from a clearance pivot with a clearance elbow.
#[test]
fn every_element_has_its_columns_and_every_clearance_joint_its_metrics() {
    let mut scene: serde_json::Value = serde_json::from_str(&readme_pendulum()).unwrap();
    scene["joints"][0] = serde_json::json!({"type": "clearance", "name": "pivot",
        "bearing": {"body": "ground", "at": [0.0, 0.0], "radius": 0.010},
        "journal": {"body": "link1", "point": "O", "radius": 0.0095},
        "normal": {"law": "impact", "k": 1e9, "c_max": 2000.0, "d_max": 1e-5}});
    scene["t_end"] = serde_json::json!(0.3);
    let p = prepared("two_clearances", &scene.to_string());
    let r = run(&p, Method::Dop853, 1e-8, None);
    let h = r.trajectory.header().unwrap();
    let names = h.names();
    for b in ["link1", "link2"] {
        for c in ["x", "y", "theta", "vx", "vy", "omega", "ax", "ay", "alpha"] {
            assert!(names.contains(&format!("{b}.{c}")), "{b}.{c}");
        }
    }
    for j in ["pivot", "elbow"] {
        for c in [
            "ex_over_c",
            "ey_over_c",
            "delta",
            "contact_force",
            "friction_force",
            "film_force",
        ] {
            assert!(names.contains(&format!("{j}.{c}")), "{j}.{c}");
        }
    }
    // The role's columns are the elbow's; the pivot's are its own.
    assert_eq!(
        r.trajectory.column("delta"),
        r.trajectory.column("elbow.delta")
    );
    assert_ne!(
        r.trajectory.column("delta"),
        r.trajectory.column("pivot.delta")
    );
    // No slider, no crank: those fixed columns are absent (empty in the CSV).
    assert_eq!(r.trajectory.column("slider_x"), None);
    // Gravity pulls the pivot's journal into its bearing: the pivot touches (δ ≥ 0 somewhere)
    // and its contact force carries the pendulum's weight, about 2 × 9.81 N.
    let m = r.summary.metrics.unwrap();
    let piv = &m.clearance_joints["pivot"];
    let max_delta = r
        .trajectory
        .column("pivot.delta")
        .unwrap()
        .iter()
        .fold(f64::NEG_INFINITY, |a, b| a.max(*b));
    assert!(
        max_delta > 0.0 && piv.penetration_max >= max_delta,
        "{piv:?}"
    );
    assert!(piv.contact_force_max > 2.0 * 9.81, "{piv:?}");
    assert!(piv.contact_onsets >= 1);
    assert!(m.clearance_joints["elbow"].contact_onsets >= 1);
    assert_eq!(
        m.contact_onsets,
        Some(m.clearance_joints["elbow"].contact_onsets)
    );
}

/// trajectory.csv streamed to a file is byte for byte the rows a run collects in memory
/// (module trajectory: every sink gets the same rows).
#[test]
fn streamed_and_collected_trajectories_are_identical() {
    let p = case("dry_150rpm_c0.1");
    let mut req = RunRequest::new(
        p.options_for(Method::Tsit54, Some(1e-6), None, None)
            .unwrap(),
    );
    req.t_end = Some(0.1);
    let mem = simulate(&p, &req).unwrap();
    let d = tempfile::tempdir().unwrap();
    let path = d.path().join("trajectory.csv");
    let mut f = CsvFile::create(&path).unwrap();
    let streamed = simulate_into(&p, &req, &mut f).unwrap();
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        mem.trajectory.to_csv()
    );
    assert_eq!((f.rows(), mem.trajectory.len()), (501, 501));
    assert_eq!(streamed.summary.metrics, mem.summary.metrics);
    // Thinned: 20 rows per revolution, or one every 10 ms; both ends exact.
    for (spr, every, rows) in [
        (Some(20), None, 6),
        (None, Some(0.01), 11),
        (None, Some(0.03), 5),
    ] {
        req.samples_per_revolution = spr;
        req.output_every = every;
        let r = simulate(&p, &req).unwrap();
        let t = r.trajectory.column("t").unwrap();
        assert_eq!(t.len(), rows, "{spr:?} {every:?}");
        assert_eq!((t[0], t[rows - 1]), (0.0, 0.1));
        if let Some(dt) = every {
            assert!((t[1] - dt).abs() < 1e-15);
        }
    }
}

fn expect_error(p: &Prepared, req: &RunRequest, kind: ErrorKind, needle: &str) {
    let mut sink = Columns::new();
    match simulate_into(p, req, &mut sink) {
        Err(e) => {
            assert_eq!(e.kind(), kind, "{e}");
            let m = e.to_string();
            assert!(m.contains(needle) && !m.contains('\n'), "{m}");
        }
        Ok(_) => panic!("{needle}: the run succeeded"),
    }
}

/// docs/outputs.md ("Exit codes of `lash`"): requests f64 or the budgets cannot carry are input
/// errors naming the field, before anything runs; RK4 past its stability limit has its own
/// error.
#[test]
fn runs_that_cannot_be_done_right_are_refused_by_name() {
    let p = case("ideal_150rpm");
    let req = |method: Method, step: Option<f64>| {
        let rtol = (!method.is_fixed_step()).then_some(1e-8);
        RunRequest::new(p.options_for(method, rtol, step, None).unwrap())
    };
    // A time span far from 0: the output spacing 2e-4 s is below f64's resolution there.
    let mut far: serde_json::Value =
        serde_json::from_slice(&std::fs::read(press_path("ideal_150rpm")).unwrap()).unwrap();
    far["t_start"] = serde_json::json!(1e15);
    let pf = prepared("far", &far.to_string());
    let r = RunRequest::new(pf.options_for(Method::Bdf, Some(1e-8), None, None).unwrap());
    expect_error(
        &pf,
        &r,
        ErrorKind::BadInput,
        "t_start = 1.000000e15 s is too far from 0",
    );
    // At 1e6 s the same spacing still resolves; at 1e11 s it does not (the end time).
    far["t_start"] = serde_json::json!(1e6);
    let pf = prepared("far", &far.to_string());
    let mut r = RunRequest::new(pf.options_for(Method::Bdf, Some(1e-8), None, None).unwrap());
    r.t_end = Some(1e6 + 0.05);
    simulate(&pf, &r).unwrap();
    r.t_end = Some(1e11);
    r.output_every = Some(1e4);
    expect_error(
        &pf,
        &r,
        ErrorKind::BadInput,
        "t_end = 1.000000e11 s is too far from 0",
    );
    // RK4's step longer than the run.
    expect_error(
        &p,
        &req(Method::Rk4, Some(1.0)),
        ErrorKind::BadInput,
        "step 1 s is longer than the run (0.8 s",
    );
    // A driver's angle far from 0 (issue 23: θ₀ = 1e17 rad froze the crank at exit 0): the
    // 0.2 ms output spacing turns the 150 rpm crank 3.1e-3 rad, which f64 angles resolve to
    // TIME_RESOLUTION up to |θ| ≈ 3.1e-6 / (16 ε) ≈ 8.8e8 rad: 1e8 runs, 1e10 is refused.
    let mut turned: serde_json::Value =
        serde_json::from_slice(&std::fs::read(press_path("ideal_150rpm")).unwrap()).unwrap();
    let driver = turned["joints"]
        .as_array()
        .unwrap()
        .iter()
        .position(|j| j["type"] == "driver")
        .unwrap();
    turned["joints"][driver]["theta0"] = serde_json::json!(1e8);
    let pt = prepared("turned", &turned.to_string());
    let mut r = RunRequest::new(pt.options_for(Method::Bdf, Some(1e-8), None, None).unwrap());
    r.t_end = Some(0.05);
    simulate(&pt, &r).unwrap();
    turned["joints"][driver]["theta0"] = serde_json::json!(1e10);
    let pt = prepared("turned", &turned.to_string());
    let r = RunRequest::new(pt.options_for(Method::Bdf, Some(1e-8), None, None).unwrap());
    expect_error(
        &pt,
        &r,
        ErrorKind::BadInput,
        &format!("joints[{driver}].theta0 = 1.000000e10 rad: the driver's angle reaches"),
    );
    // A trajectory of 5e9 rows.
    let mut r = req(Method::Bdf, None);
    r.t_end = Some(1e6);
    expect_error(&p, &r, ErrorKind::BadInput, "5e9 rows, more than the 1e8 lash writes: thin it with samples_per_revolution or output_every");
    // Rows per revolution of a scene without a crank.
    let pend = prepared("pendulum", &readme_pendulum());
    let mut r = RunRequest::new(
        pend.options_for(Method::Bdf, Some(1e-6), None, None)
            .unwrap(),
    );
    r.samples_per_revolution = Some(10);
    expect_error(
        &pend,
        &r,
        ErrorKind::BadInput,
        "samples_per_revolution needs a crank driver",
    );
    // RK4 beyond the film's stability limit (between 3 and 10 µs,
    // crates/model/tests/rk4_stability.rs): its own error, with the step and the estimated
    // limit.
    let lub = case("lubricated_150rpm_c0.1");
    let r = RunRequest::new(
        lub.options_for(Method::Rk4, None, Some(1e-5), None)
            .unwrap(),
    );
    let mut rows = Columns::new();
    match simulate_into(&lub, &r, &mut rows) {
        Err(Error::Solver(lash_solver::SolveError::Rk4Unstable {
            t,
            h,
            h_limit,
            steps,
            ..
        })) => {
            assert_eq!((h, steps), (1e-5, 15));
            assert!(h_limit > 3e-6 && h_limit < h, "{h_limit}");
            // 15 flagged steps in a row come within the first revolution (0.4 s).
            assert!(t > 0.0 && t < 0.4, "{t}");
            // The rows up to the failure reached the sink.
            let last = *rows.column("t").unwrap().last().unwrap();
            assert!(last <= t && t - last <= 0.4 / 2000.0 + 1e-12, "{last} {t}");
        }
        other => panic!("{other:?}"),
    }
}

fn press_path(stem: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/press")
        .join(format!("{stem}.json"))
}

/// The issue's four-bar (cases/examples/fourbar_clearance.json) with its crank driver replaced
/// by a motor, a torsional spring-damper on the rocker and a constant torque on the coupler:
/// every element term enters the balance (docs/model.md §1.8, §10). Leaving out any one of
/// them would shift the balance by that term, each orders of magnitude above the tolerance.
#[test]
fn every_force_element_enters_the_energy_balance() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/examples/fourbar_clearance.json");
    let mut j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let joints = j["joints"].as_array_mut().unwrap();
    joints.retain(|x| x["type"] != "driver");
    let o = j.as_object_mut().unwrap();
    o.remove("revolutions");
    o.insert("t_end".into(), serde_json::json!(1.5));
    o["roles"].as_object_mut().unwrap().remove("crank_driver");
    o.insert(
        "forces".into(),
        serde_json::json!([
            {"type": "motor", "name": "motor", "rotor": "crank",
             "stall_torque": 2.0, "no_load_rpm": 90.0},
            {"type": "rotational_spring_damper", "name": "rocker_spring", "a": "rocker",
             "stiffness": 5.0, "damping": 0.05},
            {"type": "torque", "name": "coupler_torque", "body": "coupler", "value": -0.3}
        ]),
    );
    let scene = lash_model::Scene::from_json_str(&j.to_string()).unwrap();
    let p = Prepared::with_scene(Case::load(path.to_str().unwrap(), None).unwrap(), scene).unwrap();
    let r = run(&p, Method::Bdf, 1e-8, None);
    let e = r.summary.metrics.as_ref().unwrap().energy.unwrap();
    assert_eq!(e.driver_work, 0.0, "{e:?}");
    // Each element term is far above the balance's tolerance.
    assert!(e.motor_work > 0.1, "{e:?}");
    assert!(e.load_work.abs() > 1e-3, "{e:?}");
    assert!(e.dissipated_damper > 0.01, "{e:?}");
    assert!(e.element_potential_change.abs() > 1e-3, "{e:?}");
    assert!(e.dissipated_damping + e.dissipated_friction > 0.0, "{e:?}");
    assert!(
        e.balance_error.abs() < 1e-6 + 10.0 * e.quadrature_error,
        "{e:?}"
    );
    let smallest = [
        e.motor_work,
        e.load_work,
        e.dissipated_damper,
        e.element_potential_change,
    ]
    .iter()
    .fold(f64::INFINITY, |m, x| m.min(x.abs()));
    assert!(smallest > 10.0 * e.balance_error.abs(), "{e:?}");
}

/// cases/press/punch_motor_150rpm_c0.1.json: a motor turns the crank against a punch; the
/// balance closes with the motor's work in and the punch's out (5.7 J off without them).
#[test]
fn motor_press_energy_balance_closes() {
    let p = case("punch_motor_150rpm_c0.1");
    let r = run(&p, Method::Bdf, 1e-8, None);
    let e = r.summary.metrics.as_ref().unwrap().energy.unwrap();
    assert!(e.motor_work > 100.0 && e.load_work < -100.0, "{e:?}");
    assert!(e.balance_error.abs() < 1e-4, "{e:?}");
}
