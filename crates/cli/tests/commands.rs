//! End-to-end: every command of the built `lash` binary on small cases — exit codes, the files
//! written, and the contents of summary.json, trajectory.csv and the comparison tables
//! (docs/outputs.md: "`summary.json`", "`trajectory.csv`", "Files each command writes").

mod common;
use common::{json, lash, ok};
use std::path::{Path, PathBuf};

use lash_model::cases::{press_scene, PressJoint};

fn press_case(dir: &Path) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../../cases/press/{}", dir.display()))
}

/// A press scene cut short (t_end in s) in `dir/NAME.json`.
fn short_press(dir: &Path, name: &str, joint: PressJoint, c: f64, t_end: f64) -> PathBuf {
    let mut s = press_scene(joint, 150.0, c);
    s.revolutions = None;
    s.t_end = Some(t_end);
    let p = dir.join(format!("{name}.json"));
    std::fs::write(&p, s.to_json_pretty()).unwrap();
    p
}

// A mechanism run's: `formulation`, `kink_events`, `metrics_window` are absent for built-in
// test problems, `crank_revolutions` without a crank (docs/outputs.md).
const SUMMARY_KEYS: [&str; 19] = [
    "atol",
    "case",
    "controller",
    "crank_revolutions",
    "events",
    "final_state",
    "formulation",
    "kink_events",
    "method",
    "metrics",
    "metrics_window",
    "reference_error",
    "rtol",
    "scene_sha256",
    "stats",
    "step",
    "t_end",
    "version",
    "wall_time_s",
];

#[test]
fn run_writes_summary_trajectory_and_figures() {
    let d = tempfile::tempdir().unwrap();
    let case = short_press(d.path(), "ideal_short", PressJoint::Ideal, 0.0, 0.1);
    // lagrange_baumgarte named: the keys of its summary (auto would take the augmented
    // Lagrangian for this loop and add formulation_stats).
    let out = ok(
        &[
            "run",
            case.to_str().unwrap(),
            "--formulation",
            "lagrange_baumgarte",
            "--out",
            "o",
        ],
        d.path(),
    );
    assert!(out.contains("ideal_short: bdf rtol 1e-8"), "{out}");
    let o = d.path().join("o");
    let s = json(&o.join("summary.json"));
    let mut keys: Vec<&str> = s.as_object().unwrap().keys().map(|k| k.as_str()).collect();
    keys.sort();
    assert_eq!(keys, SUMMARY_KEYS);
    assert_eq!(s["formulation"], "lagrange_baumgarte");
    assert!(out.contains("  formulation: lagrange_baumgarte\n"), "{out}");
    // No clearance joint, so no kink events, and no line about them.
    assert_eq!(s["kink_events"], false);
    assert!(!out.contains("kink events"), "{out}");
    assert_eq!(s["case"], "ideal_short");
    assert_eq!(s["scene_sha256"].as_str().unwrap().len(), 64);
    assert_eq!(
        (s["method"].as_str(), s["rtol"].as_f64()),
        (Some("bdf"), Some(1e-8))
    );
    // bdf is diffsol's: no controller of ours; adaptive: no step; atol one per component.
    assert!(s["controller"].is_null() && s["step"].is_null());
    assert_eq!(s["atol"].as_array().unwrap().len(), 12);
    assert_eq!(s["t_end"], 0.1);
    // A quarter turn at 150 rpm, shorter than the revolution: the window is the whole run.
    assert!(
        (s["crank_revolutions"].as_f64().unwrap() - 0.25).abs() < 1e-12,
        "{s}"
    );
    assert_eq!(s["metrics_window"], serde_json::json!([0.0, 0.1]));
    let m = &s["metrics"];
    // The ideal mechanism is its closed form; it has no clearance joint.
    assert!(
        m["slider_acc_rms_dev_ideal"].as_f64().unwrap() < 1e-6,
        "{m}"
    );
    assert!(m["eps_max"].is_null() && m["contact_onsets"].is_null());
    // A quarter turn: the driver's work goes into T + V; the balance closes to the
    // integration error (bdf at rtol 1e-8: about 1e-7 of the work).
    let e = &m["energy"];
    let w = e["driver_work"].as_f64().unwrap();
    assert!(w > 100.0, "{e}");
    assert!(e["balance_error"].as_f64().unwrap().abs() < 1e-6 * w, "{e}");
    assert!(s["final_state"].is_null() && s["reference_error"].is_null());
    // trajectory.csv: the header of docs/outputs.md ("`trajectory.csv`"); 2000 rows per revolution
    // (T = 0.4 s) + 1.
    let csv = std::fs::read_to_string(o.join("trajectory.csv")).unwrap();
    let mut lines = csv.lines();
    // The fixed columns, then every body's, then the crank driver's torque.
    let header = lines.next().unwrap();
    assert!(header.starts_with(
        "t,crank_angle,slider_x,slider_v,slider_a,ex_over_c,ey_over_c,delta,contact_force,friction_force,film_force,constraint_violation,driver_torque,crank.x,crank.y,crank.theta,"
    ), "{header}");
    assert!(
        header.ends_with(",slider.ax,slider.ay,slider.alpha,crank_driver.torque"),
        "{header}"
    );
    assert_eq!(header.split(',').count(), 13 + 3 * 9 + 1);
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 501);
    let last: Vec<&str> = rows[500].split(',').collect();
    assert_eq!(last[0], "0.1");
    assert!((last[1].parse::<f64>().unwrap() - 0.5 * std::f64::consts::PI).abs() < 1e-12);
    assert_eq!(last[5], "", "no clearance joint: empty e/c");
    for f in ["slider_x", "slider_v", "slider_a"] {
        assert!(o.join(format!("{f}.png")).is_file() && o.join(format!("{f}.svg")).is_file());
    }
    assert!(!o.join("orbit.png").exists());
}

#[test]
fn run_lubricated_and_dry_cases() {
    let d = tempfile::tempdir().unwrap();
    let lub = press_case(Path::new("lubricated_150rpm_c0.1.json"));
    ok(&["run", lub.to_str().unwrap(), "--out", "lub"], d.path());
    let m = &json(&d.path().join("lub/summary.json"))["metrics"];
    // docs/model.md §9: the film keeps the journal off the bearing.
    assert!(m["eps_max"].as_f64().unwrap() < 1.0);
    assert_eq!(m["contact_onsets"], 0);
    assert!(m["film_thickness_min"].as_f64().unwrap() > 0.0);
    for f in ["orbit.png", "joint_forces.svg", "slider_a.png"] {
        assert!(d.path().join("lub").join(f).is_file(), "{f}");
    }
    // The paper's RK4 on the dry case, a quarter revolution: crossings counted, none located.
    let dry = short_press(d.path(), "dry_short", PressJoint::Dry, 1e-4, 0.1);
    ok(
        &[
            "run",
            dry.to_str().unwrap(),
            "--method",
            "rk4",
            "--step",
            "2e-4",
            "--out",
            "dry",
        ],
        d.path(),
    );
    let s = json(&d.path().join("dry/summary.json"));
    assert_eq!(
        (s["method"].as_str(), s["step"].as_f64()),
        (Some("rk4"), Some(2e-4))
    );
    assert!(s["rtol"].is_null() && s["atol"].is_null() && s["controller"].is_null());
    assert_eq!(s["events"], 0);
    assert!(s["metrics"]["contact_onsets"].as_u64().unwrap() >= 1);
    // The paper's RK4 runs without the dry joint's default kink events (docs/model.md §7).
    assert_eq!(s["kink_events"], false);
    // tsit54 on it restarts at the kinks of its laws by default, and says so.
    let out = ok(
        &[
            "run",
            dry.to_str().unwrap(),
            "--method",
            "tsit54",
            "--out",
            "dry_tsit54",
        ],
        d.path(),
    );
    assert!(
        out.contains(
            "  kink events: on (a restart at each, with exact event steps; docs/model.md §7)\n"
        ),
        "{out}"
    );
    assert_eq!(
        json(&d.path().join("dry_tsit54/summary.json"))["kink_events"],
        true
    );
    // Four stages per step and the initial evaluation.
    let acc = s["stats"]["accepted"].as_u64().unwrap();
    assert!(acc == 500 || acc == 501, "{acc}");
    assert_eq!(s["stats"]["rhs_evals"].as_u64().unwrap(), 4 * acc + 1);
}

#[test]
fn run_testset_reports_the_reference_error() {
    let d = tempfile::tempdir().unwrap();
    ok(
        &[
            "run",
            "testset:hires",
            "--method",
            "rodas5p",
            "--rtol",
            "1e-8",
            "--out",
            "h",
        ],
        d.path(),
    );
    let s = json(&d.path().join("h/summary.json"));
    assert_eq!(s["case"], "testset:hires");
    assert!(s["scene_sha256"].is_null() && s["metrics"].is_null());
    assert!(s["reference_error"].as_f64().unwrap() < 1e-5);
    assert_eq!(s["final_state"].as_array().unwrap().len(), 8);
    assert_eq!(s["controller"], "gustafsson");
    let csv = std::fs::read_to_string(d.path().join("h/trajectory.csv")).unwrap();
    assert!(csv
        .lines()
        .next()
        .unwrap()
        .ends_with(",driver_torque,y0,y1,y2,y3,y4,y5,y6,y7"));
    // A built-in problem's reference holds at its own end time.
    let o = lash(&["run", "testset:hires", "--t-end", "1"], d.path());
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--t-end does not apply"));
}

#[test]
fn solver_failure_exits_3_and_keeps_what_it_can() {
    let d = tempfile::tempdir().unwrap();
    let lub = press_case(Path::new("lubricated_150rpm_c0.1.json"));
    let rk4 = |step: &str, out: &str| {
        lash(
            &[
                "run",
                lub.to_str().unwrap(),
                "--method",
                "rk4",
                "--step",
                step,
                "--out",
                out,
            ],
            d.path(),
        )
    };
    // A directory holding a file that is not a run's is refused and kept as it was: a run
    // replaces its directory as a whole.
    let out = d.path().join("o");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("keep.txt"), b"x").unwrap();
    let o = rk4("1e-5", "o");
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(
            "is not a lash run directory (no .lash-run marker) and holds files (keep.txt)"
        ),
        "{err}"
    );
    let names: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("keep.txt")]);
    // RK4 at 1e-5 s, beyond the film's stability limit (between 3 and 10 µs,
    // crates/model/tests/rk4_stability.rs): its stability
    // stop, with the step and the estimated limit; failure.json and the rows up to it.
    let o = rk4("1e-5", "f");
    assert_eq!(o.status.code(), Some(3));
    let err = String::from_utf8_lossy(&o.stderr);
    let lines: Vec<&str> = err.lines().collect();
    assert!(
        lines[0].starts_with("wrote failure.json and partial_trajectory.csv ("),
        "{err}"
    );
    assert!(
        lines[1].starts_with("error: solver failed: RK4 beyond its stability limit at t = ")
            && lines[1].contains("step 1e-5 s, estimated limit "),
        "{err}"
    );
    assert!(lines[2].starts_with("  at t = ") && lines[2].contains("state = ["));
    let f = d.path().join("f");
    let mut names: Vec<String> = std::fs::read_dir(&f)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [".lash-run", "failure.json", "partial_trajectory.csv"]
    );
    let j = json(&f.join("failure.json"));
    assert_eq!(j["error"]["kind"], "rk4_unstable");
    let h_limit = j["error"]["h_limit"].as_f64().unwrap();
    assert!(h_limit > 3e-6 && h_limit < 1e-5, "{j}");
    let t = j["t"].as_f64().unwrap();
    // The state by component name: the rod and the slider are integrated (the crank is
    // driven), each x, y, θ and their rates.
    let state = j["state"].as_object().unwrap();
    assert_eq!(state.len(), 12);
    // The slider where the ideal slider-crank puts it at t (r = 0.015 m, l = 0.35 m,
    // 150 rpm), within the clearance c = 0.1 mm: the state is the run's, not a diverged one.
    let th = 150.0 * std::f64::consts::TAU / 60.0 * t;
    let ideal = 0.015 * th.cos() + (0.35f64.powi(2) - (0.015 * th.sin()).powi(2)).sqrt();
    assert!(
        (state["slider.x"].as_f64().unwrap() - ideal).abs() < 1e-4,
        "{j}"
    );
    let csv = std::fs::read_to_string(f.join("partial_trajectory.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len() as u64, j["rows"].as_u64().unwrap());
    let last_t: f64 = rows
        .last()
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(last_t <= t, "{last_t} {t}");
    // A scene that fails validation is bad input, one line.
    std::fs::write(d.path().join("empty.json"), b"{\"bodies\": []}").unwrap();
    let o = lash(&["run", "empty.json"], d.path());
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("error: case empty.json: bodies"), "{err}");
    // An atol array of the wrong length is a usage error, not a solver failure (the press's
    // state under the default formulation, auto = minimal: rod angle and slider position and
    // their rates).
    let o = lash(
        &["run", lub.to_str().unwrap(), "--atol", "1e-9,1e-9"],
        d.path(),
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("atol has 2 entries, the system 4"));
}

#[test]
fn compare_lists_every_method_against_the_reference() {
    let d = tempfile::tempdir().unwrap();
    let case = short_press(d.path(), "ideal_rev", PressJoint::Ideal, 0.0, 0.4);
    let out = ok(
        &[
            "compare",
            case.to_str().unwrap(),
            "--steps",
            "1e-3,5e-4",
            "--tolerances",
            "1e-8",
            "--out",
            "c",
        ],
        d.path(),
    );
    assert!(out.contains("Reference: dop853 at rtol 1e-12"), "{out}");
    let c = json(&d.path().join("c/compare.json"));
    let runs = c["runs"].as_array().unwrap();
    // 2 RK4 steps + 4 explicit pairs + 4 stiff methods.
    assert_eq!(runs.len(), 10);
    let err = |i: usize| runs[i]["error"].as_f64().unwrap();
    // RK4 is order 4: halving the step divides the error by about 16.
    let ratio = err(0) / err(1);
    assert!((12.0..20.0).contains(&ratio), "{ratio}");
    for r in runs {
        assert!(r["failure"].is_null(), "{r}");
        assert!(r["error"].as_f64().unwrap() < 1e-5, "{r}");
        assert!(r["rhs_evals"].as_u64().unwrap() > 0);
        assert!(r["norms"]["orbit_max"].is_null(), "no clearance joint");
    }
    assert_eq!(c["window"]["label"], "last revolution");
    assert!(d.path().join("c/compare.md").is_file());
    // A built-in problem: no RK4 by default, errors are reference errors.
    ok(
        &[
            "compare",
            "testset:hires",
            "--tolerances",
            "1e-6",
            "--out",
            "h",
        ],
        d.path(),
    );
    let h = json(&d.path().join("h/compare.json"));
    let runs = h["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 8);
    let rodas = runs.iter().find(|r| r["method"] == "rodas5p").unwrap();
    assert!(rodas["error"].as_f64().unwrap() < 1e-5);
}

#[test]
fn work_precision_tables_and_the_cheapest_runs() {
    let d = tempfile::tempdir().unwrap();
    ok(
        &[
            "work-precision",
            "testset:hires",
            "--methods",
            "rodas5p,bdf,dopri54",
            "--tolerances",
            "1e-4,1e-6,1e-8",
            "--controllers",
            "pi,h211",
            "--out",
            "w",
        ],
        d.path(),
    );
    let w = json(&d.path().join("w/work_precision.json"));
    let runs = w["runs"].as_array().unwrap();
    // rodas5p × 3, bdf × 3, dopri54 × 2 controllers × 3.
    assert_eq!(runs.len(), 12);
    let errs: Vec<f64> = runs
        .iter()
        .filter(|r| r["method"] == "rodas5p")
        .map(|r| r["error"].as_f64().unwrap())
        .collect();
    // Tolerance proportionality: each 100× tighter rtol gives a smaller error.
    assert!(errs[0] > errs[1] && errs[1] > errs[2], "{errs:?}");
    assert!(runs.iter().any(|r| r["controller"] == "h211"));
    let cheapest = w["cheapest"].as_array().unwrap();
    assert_eq!(cheapest.len(), 5);
    // Somebody reaches 1e-4.
    assert!(!cheapest[1]["by_rhs_evals"].is_null());
    for f in ["work_precision.md", "wp_rhs.png", "wp_time.svg"] {
        assert!(d.path().join("w").join(f).is_file(), "{f}");
    }
    // rk4 on a test problem needs explicit steps.
    let o = lash(
        &["work-precision", "testset:hires", "--methods", "rk4"],
        d.path(),
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("rk4 needs --steps"));
}

#[test]
fn sweep_runs_real_points_resumes_and_merges() {
    let d = tempfile::tempdir().unwrap();
    short_press(d.path(), "lub_short", PressJoint::Lubricated, 1e-4, 0.1);
    std::fs::write(
        d.path().join("grid.json"),
        br#"{"case": "lub_short.json", "speed_rpm": [120, 150], "viscosity": [0.2, 0.4],
            "method": ["bdf"], "rtol": [1e-6]}"#,
    )
    .unwrap();
    // "Interrupted": only shard 0 of 2 runs first.
    ok(
        &["sweep", "grid.json", "--shard", "0/2", "--out", "s"],
        d.path(),
    );
    let dirs = |p: &Path| -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(p)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.is_dir())
            .collect();
        v.sort();
        v
    };
    let first = dirs(&d.path().join("s"));
    assert_eq!(first.len(), 2);
    let stamp: Vec<Vec<u8>> = first
        .iter()
        .map(|p| std::fs::read(p.join("result.json")).unwrap())
        .collect();
    // The rerun over the whole grid skips the two finished points.
    let o = lash(&["sweep", "grid.json", "--out", "s"], d.path());
    assert_eq!(o.status.code(), Some(0));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("2 ran, 0 solver failures, 2 already done"),
        "{err}"
    );
    for (p, s) in first.iter().zip(&stamp) {
        assert_eq!(
            &std::fs::read(p.join("result.json")).unwrap(),
            s,
            "rewritten"
        );
    }
    assert_eq!(dirs(&d.path().join("s")).len(), 4);
    ok(&["merge", "s"], d.path());
    let csv = std::fs::read_to_string(d.path().join("s/merged.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 5);
    let head: Vec<&str> = csv_row(lines[0]);
    let col = |n: &str| {
        head.iter()
            .position(|h| *h == n)
            .unwrap_or_else(|| panic!("{n}"))
    };
    let (eps, speed, visc) = (col("metrics.eps_max"), col("speed_rpm"), col("viscosity"));
    assert_eq!(head.iter().filter(|h| **h == "case").count(), 1);
    for l in &lines[1..] {
        let c: Vec<&str> = csv_row(l);
        let e: f64 = c[eps].parse().unwrap();
        assert!(e > 0.0 && e < 1.0, "{l}");
        assert!(["120.0", "150.0"].contains(&c[speed]) && ["0.2", "0.4"].contains(&c[visc]));
    }
    // Thinner oil lets the journal move further off centre (same speed).
    let eps_of = |s: &str, v: &str| -> f64 {
        lines[1..]
            .iter()
            .map(|l| csv_row(l))
            .find(|c| c[speed] == s && c[visc] == v)
            .unwrap()[eps]
            .parse()
            .unwrap()
    };
    assert!(eps_of("150.0", "0.2") > eps_of("150.0", "0.4"));
    // Each point wrote its summary with the point's speed.
    let s = json(&first[0].join("summary.json"));
    assert_eq!(s["case"], "lub_short");
}

/// `--max-wall-time` bounds every integration of the long commands (issue 22): a budget far
/// below one step's cost ends each sweep point as a recorded solver failure ("budget
/// exhausted"), and compare's reference as a solver failure (exit 3); a generous one changes
/// nothing.
#[test]
fn long_commands_stop_each_integration_at_the_wall_time_budget() {
    let d = tempfile::tempdir().unwrap();
    short_press(d.path(), "lub", PressJoint::Lubricated, 1e-4, 0.02);
    std::fs::write(
        d.path().join("grid.json"),
        r#"{"case": "lub.json", "method": ["bdf", "dopri54"]}"#,
    )
    .unwrap();
    let o = lash(
        &[
            "sweep",
            "grid.json",
            "--out",
            "s",
            "--max-wall-time",
            "1e-9",
        ],
        d.path(),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("2 solver failures"), "{err}");
    for e in std::fs::read_dir(d.path().join("s")).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            let r = json(&p.join("result.json"));
            assert_eq!(r["status"], "solver_failed", "{r}");
            assert!(
                r["error"].as_str().unwrap().contains("budget exhausted"),
                "{r}"
            );
        }
    }
    ok(
        &["sweep", "grid.json", "--out", "t", "--max-wall-time", "600"],
        d.path(),
    );
    let o = lash(
        &[
            "compare",
            "lub.json",
            "--out",
            "c",
            "--max-wall-time",
            "1e-9",
        ],
        d.path(),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(err.contains("budget exhausted"), "{err}");
    let o = lash(
        &[
            "work-precision",
            "lub.json",
            "--out",
            "w",
            "--max-wall-time",
            "1e-9",
        ],
        d.path(),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(err.contains("budget exhausted"), "{err}");
}

/// Sweeps of any scene field (issue 22): `set` by index and by element name; every path a
/// column of merged.csv named as written and a key of the point's params; the values reach the
/// scene (the heavier rocker and the larger friction change the run).
#[test]
fn sweep_sets_any_scene_field_by_path() {
    let d = tempfile::tempdir().unwrap();
    let case = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/examples/fourbar_clearance.json");
    let mut j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(case).unwrap()).unwrap();
    j.as_object_mut().unwrap().remove("revolutions");
    j["t_end"] = serde_json::json!(0.3);
    std::fs::write(d.path().join("fourbar.json"), j.to_string()).unwrap();
    std::fs::write(
        d.path().join("grid.json"),
        r#"{"case": "fourbar.json", "method": ["bdf"], "rtol": [1e-6],
            "set": {"joints[coupler_rocker].friction.mu": [0.05, 0.3],
                    "bodies[2].mass": [0.8, 2.0]}}"#,
    )
    .unwrap();
    let o = lash(&["sweep", "grid.json", "--out", "s"], d.path());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains("4 points to run"), "{err}");
    ok(&["merge", "s"], d.path());
    let csv = std::fs::read_to_string(d.path().join("s/merged.csv")).unwrap();
    let head: Vec<&str> = csv_row(csv.lines().next().unwrap());
    let col = |n: &str| head.iter().position(|c| *c == n).expect(n);
    let (mu, mass) = (
        col("joints[coupler_rocker].friction.mu"),
        col("bodies[2].mass"),
    );
    let fric = col("metrics.energy.dissipated_friction");
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| csv_row(l)).collect();
    assert_eq!(rows.len(), 4);
    let mut seen: Vec<(String, String)> = rows
        .iter()
        .map(|r| (r[mu].to_string(), r[mass].to_string()))
        .collect();
    seen.sort();
    assert_eq!(
        seen,
        [
            ("0.05", "0.8"),
            ("0.05", "2.0"),
            ("0.3", "0.8"),
            ("0.3", "2.0")
        ]
        .map(|(a, b)| (a.to_string(), b.to_string()))
    );
    // Distinct values give distinct runs: friction dissipation differs between the rows.
    let mut f: Vec<&str> = rows.iter().map(|r| r[fric]).collect();
    f.sort();
    f.dedup();
    assert_eq!(f.len(), 4, "{csv}");
    // The point's params name the path as written.
    let dirs: Vec<_> = std::fs::read_dir(d.path().join("s"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    let r = json(&dirs[0].join("result.json"));
    assert!(
        r["params"]["joints[coupler_rocker].friction.mu"].is_number(),
        "{r}"
    );
    assert!(r["params"]["bodies[2].mass"].is_number(), "{r}");
}

/// Bad sweep files end in one line naming the key, with nothing run (no output directory):
/// an unknown path, a value of the wrong type, a value the scene rejects, an empty list, and
/// speed_rpm on a scene a motor turns.
#[test]
fn bad_set_sweeps_fail_before_any_point_runs() {
    let d = tempfile::tempdir().unwrap();
    let case = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/examples/fourbar_clearance.json");
    std::fs::copy(&case, d.path().join("fourbar.json")).unwrap();
    let punch = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/press/punch_motor_150rpm_c0.1.json");
    std::fs::copy(&punch, d.path().join("punch.json")).unwrap();
    for (i, (body, expect)) in [
        (
            r#""set": {"joints[coupler_rocker].friction.nu": [0.1]}"#,
            "set['joints[coupler_rocker].friction.nu'] (point 0 (",
        ),
        (
            r#""set": {"joints[nope].friction.mu": [0.1]}"#,
            "joints has no element named 'nope'",
        ),
        (r#""set": {"bodies[2].mass": ["heavy"]}"#, "bodies[2].mass"),
        (r#""set": {"bodies[2].mass": [-1.0]}"#, "bodies[2].mass"),
        (
            r#""set": {"bodies[2].mass": []}"#,
            "set['bodies[2].mass'] is an empty list",
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let f = format!("bad{i}.json");
        std::fs::write(
            d.path().join(&f),
            format!(r#"{{"case": "fourbar.json", {body}}}"#),
        )
        .unwrap();
        let out = format!("o{i}");
        let o = lash(&["sweep", &f, "--out", &out], d.path());
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{body}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{body}: {err}");
        assert!(err.contains(expect), "{body}: {err}");
        assert!(!d.path().join(&out).exists(), "{body}: ran something");
    }
    std::fs::write(
        d.path().join("motor.json"),
        r#"{"case": "punch.json", "speed_rpm": [120, 150]}"#,
    )
    .unwrap();
    let o = lash(&["sweep", "motor.json", "--out", "m"], d.path());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("speed_rpm needs the scene's crank_driver role") && err.contains("point 0"),
        "{err}"
    );
    assert!(!d.path().join("m").exists());
}

/// `--window` on sweep and run: a window the scene cannot have (last-revolution without a
/// crank, a span outside the run) is one line, exit 2, before any point runs; a span is every
/// point's metrics window; the motor-driven punch press measures its last turn.
#[test]
fn the_metrics_window_is_chosen_on_run_and_sweep() {
    let d = tempfile::tempdir().unwrap();
    let cases = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases");
    std::fs::copy(
        cases.join("examples/pendulum.json"),
        d.path().join("pendulum.json"),
    )
    .unwrap();
    std::fs::write(
        d.path().join("sw.json"),
        r#"{"case": "pendulum.json", "set": {"bodies[0].mass": [1.0, 2.0]}}"#,
    )
    .unwrap();
    for (i, (w, expect)) in [
        ("last-revolution", "last-revolution needs a crank"),
        ("0.1:99", "is not inside the run"),
    ]
    .into_iter()
    .enumerate()
    {
        let out = format!("bad{i}");
        let o = lash(
            &["sweep", "sw.json", "--window", w, "--out", &out],
            d.path(),
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{w}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{w}: {err}");
        assert!(
            err.contains("--window") && err.contains(expect),
            "{w}: {err}"
        );
        assert!(!d.path().join(&out).exists(), "{w}: ran something");
    }
    ok(
        &["sweep", "sw.json", "--window", "0.1:0.5", "--out", "s"],
        d.path(),
    );
    let mut n = 0;
    for e in std::fs::read_dir(d.path().join("s")).unwrap() {
        let p = e.unwrap().path().join("summary.json");
        if p.exists() {
            let w = json(&p)["metrics_window"].clone();
            let (a, b) = (w[0].as_f64().unwrap(), w[1].as_f64().unwrap());
            assert!((a - 0.1).abs() < 1e-12 && b == 0.5, "{w}");
            n += 1;
        }
    }
    assert_eq!(n, 2);
    let o = lash(
        &["run", "pendulum.json", "--window", "0.5:0.1", "--out", "r"],
        d.path(),
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("T0 must be before T1"));
    // The punch press: its crank pivot is the crank; the last turn ends at t_end and is about
    // 60/152 s long (152 rpm mean, README), the crank turned about 2.03 times.
    let punch = cases.join("press/punch_motor_150rpm_c0.1.json");
    ok(&["run", punch.to_str().unwrap(), "--out", "p"], d.path());
    let s = json(&d.path().join("p/summary.json"));
    let (a, b) = (
        s["metrics_window"][0].as_f64().unwrap(),
        s["metrics_window"][1].as_f64().unwrap(),
    );
    assert_eq!(b, 0.8);
    assert!((b - a - 60.0 / 152.0).abs() < 0.01, "{a}");
    let turns = s["crank_revolutions"].as_f64().unwrap();
    assert!((turns - 2.03).abs() < 0.01, "{turns}");
    let csv = std::fs::read_to_string(d.path().join("p/trajectory.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let k = header.iter().position(|h| *h == "crank_angle").unwrap();
    let last = csv.lines().last().unwrap().split(',').nth(k).unwrap();
    let phi: f64 = last.parse().unwrap();
    assert!((phi / std::f64::consts::TAU - turns).abs() < 1e-9, "{phi}");
}

/// `lash compare --window`: a span is where the errors are measured (compare.json's window),
/// `all` the whole run; a span outside the run and any window on a test problem (compared at
/// its end point) are usage errors, exit 2, before the reference runs.
#[test]
fn compare_measures_errors_on_the_chosen_window() {
    let d = tempfile::tempdir().unwrap();
    let case = short_press(d.path(), "ideal_rev", PressJoint::Ideal, 0.0, 0.4);
    let c = case.to_str().unwrap();
    for (w, dir, start, end, label) in [
        ("0.1:0.3", "s", 0.1, 0.3, "chosen span 0.1:0.3"),
        ("all", "a", 0.0, 0.4, "whole run"),
    ] {
        ok(
            &[
                "compare",
                c,
                "--steps",
                "1e-3",
                "--tolerances",
                "1e-6",
                "--window",
                w,
                "--out",
                dir,
            ],
            d.path(),
        );
        let j = json(&d.path().join(dir).join("compare.json"));
        assert_eq!(j["window"]["start"].as_f64().unwrap(), start, "{w}");
        assert_eq!(j["window"]["end"].as_f64().unwrap(), end, "{w}");
        assert_eq!(j["window"]["label"], label);
        let md = std::fs::read_to_string(d.path().join(dir).join("compare.md")).unwrap();
        assert!(md.contains(&format!("[{start}, {end}]")), "{md}");
    }
    for (args, needle) in [
        (
            vec!["compare", c, "--window", "0.5:0.9"],
            "is not inside the run",
        ),
        (
            vec!["compare", "testset:hires", "--window", "all"],
            "applies to scene cases",
        ),
    ] {
        let o = lash(&args, d.path());
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(needle), "{err}");
    }
}

/// The dry four-bar of cases/examples cut to `t_end` s, as `dir/fourbar.json`.
fn short_fourbar(dir: &Path, t_end: f64) {
    let case = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/examples/fourbar_clearance.json");
    let mut j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(case).unwrap()).unwrap();
    j.as_object_mut().unwrap().remove("revolutions");
    j["t_end"] = serde_json::json!(t_end);
    std::fs::write(dir.join("fourbar.json"), j.to_string()).unwrap();
}

/// A sampled sweep end to end (issue 22): a Latin hypercube of 4 points over the journal's
/// radius and the friction coefficient; each sampled path is a column of merged.csv named as
/// written, its values inside the distribution's range, one per stratum, and they reach the
/// scene (four distinct friction dissipations); a rerun runs nothing.
#[test]
fn sampled_sweep_runs_merges_and_resumes() {
    let d = tempfile::tempdir().unwrap();
    short_fourbar(d.path(), 0.1);
    std::fs::write(
        d.path().join("lhs.json"),
        r#"{"case": "fourbar.json", "method": ["bdf"], "rtol": [1e-6],
            "sample": {"count": 4, "seed": 5, "method": "latin_hypercube",
                       "vary": {"joints[coupler_rocker].journal.radius": {"uniform": [0.0094, 0.0096]},
                                "joints[coupler_rocker].friction.mu": {"lognormal": [-2.3, 0.3]}}}}"#,
    )
    .unwrap();
    let o = lash(&["sweep", "lhs.json", "--out", "s"], d.path());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains("4 points to run"), "{err}");
    ok(&["merge", "s"], d.path());
    let csv = std::fs::read_to_string(d.path().join("s/merged.csv")).unwrap();
    let head: Vec<&str> = csv_row(csv.lines().next().unwrap());
    let col = |n: &str| head.iter().position(|c| *c == n).expect(n);
    let (r, mu, fric) = (
        col("joints[coupler_rocker].journal.radius"),
        col("joints[coupler_rocker].friction.mu"),
        col("metrics.energy.dissipated_friction"),
    );
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| csv_row(l)).collect();
    assert_eq!(rows.len(), 4);
    let mut strata: Vec<usize> = rows
        .iter()
        .map(|row| {
            let x: f64 = row[r].parse().unwrap();
            assert!((0.0094..0.0096).contains(&x), "{x}");
            ((x - 0.0094) / 0.0002 * 4.0) as usize
        })
        .collect();
    strata.sort_unstable();
    assert_eq!(strata, [0, 1, 2, 3]);
    assert!(rows.iter().all(|row| row[mu].parse::<f64>().unwrap() > 0.0));
    let mut f: Vec<&str> = rows.iter().map(|row| row[fric]).collect();
    f.sort_unstable();
    f.dedup();
    assert_eq!(f.len(), 4, "{csv}");
    let o = lash(&["sweep", "lhs.json", "--out", "s"], d.path());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains("4 of 4 points already done"), "{err}");
    // merged.md: a readable table by default (no solver statistics beyond the step count),
    // the quantiles of every metric; --columns chooses the table; an unknown column is exit 2.
    let md = std::fs::read_to_string(d.path().join("s/merged.md")).unwrap();
    let header = md.lines().find(|l| l.starts_with("| id |")).unwrap();
    assert!(
        header.contains("| joints[coupler_rocker].friction.mu |"),
        "{header}"
    );
    assert!(header.contains("| metrics.eps_max |"), "{header}");
    assert!(!header.contains("stats.h_min_used") && !header.contains("scene_sha256"));
    let fr: Vec<f64> = rows.iter().map(|row| row[fric].parse().unwrap()).collect();
    let mut sorted = fr.clone();
    sorted.sort_by(f64::total_cmp);
    // Type 7 over 4 numbers: Q(0.5) = (x1 + x2)/2, 6 significant digits in merged.md.
    let q = md
        .lines()
        .find(|l| l.starts_with("| metrics.energy.dissipated_friction |"))
        .expect(&md);
    let cells: Vec<&str> = q.split('|').map(str::trim).collect();
    assert_eq!(cells[2], "4");
    let median: f64 = cells[4].parse().unwrap();
    let want = 0.5 * (sorted[1] + sorted[2]);
    assert!(
        (median - want).abs() <= 1e-5 * want.abs(),
        "{median} vs {want}"
    );
    ok(
        &[
            "merge",
            "s",
            "--columns",
            "index,metrics.energy.dissipated_friction",
        ],
        d.path(),
    );
    let md = std::fs::read_to_string(d.path().join("s/merged.md")).unwrap();
    assert!(
        md.contains("| index | metrics.energy.dissipated_friction |\n|---|---|\n| 0 |"),
        "{md}"
    );
    let o = lash(&["merge", "s", "--columns", "index,nope"], d.path());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("no column 'nope'") && err.contains("--columns"),
        "{err}"
    );
}

/// Bad sampled sweep files (issue 22): each ends in one line naming the key, exit 2, with
/// nothing run (no output directory).
#[test]
fn bad_sample_sweeps_fail_before_any_point_runs() {
    let d = tempfile::tempdir().unwrap();
    short_fourbar(d.path(), 0.1);
    let mass = r#""vary": {"bodies[2].mass": {"uniform": [0.5, 1.5]}}"#;
    let cases: Vec<(String, &str)> = vec![
        (
            format!(r#""sample": {{"count": 0, "seed": 1, {mass}}}"#),
            "sample.count must be in 1 ..= 1000000, got 0",
        ),
        (
            format!(r#""sample": {{"count": [3], "seed": 1, {mass}}}"#),
            "sample.count: invalid type",
        ),
        (
            r#""sample": {"count": 3, "seed": 1, "vary": {"bodies[2].mass": {"uniform": [2, 1]}}}"#.into(),
            "sample.vary['bodies[2].mass'].uniform: needs lo < hi",
        ),
        (
            r#""sample": {"count": 3, "seed": 1, "vary": {"bodies[2].mass": {"normal": [1, 0]}}}"#.into(),
            "sample.vary['bodies[2].mass'].normal: needs sd > 0",
        ),
        (
            r#""sample": {"count": 3, "seed": 1, "vary": {"bodies[2].mass": {"lognormal": [0, -0.1]}}}"#.into(),
            "sample.vary['bodies[2].mass'].lognormal: needs sigma > 0",
        ),
        (
            format!(r#""set": {{"bodies[2].mass": [1.0, 2.0]}}, "sample": {{"count": 3, "seed": 1, {mass}}}"#),
            "sample.vary['bodies[2].mass'] is also in set",
        ),
        (
            r#""sample": {"count": 3, "seed": 1, "vary": {"bodies[2].weight": {"uniform": [1, 2]}}}"#.into(),
            "sample.vary['bodies[2].weight'] (point 0 (",
        ),
        (
            r#""sample": {"count": 3, "seed": 1, "vary": {"bodies[2].name": {"uniform": [1, 2]}}}"#.into(),
            "bodies[2].name",
        ),
        (
            // A normal of mean 0: about half the masses drawn are negative, which the scene refuses.
            r#""sample": {"count": 8, "seed": 1, "vary": {"bodies[2].mass": {"normal": [0, 1]}}}"#.into(),
            "bodies[2].mass",
        ),
    ];
    for (i, (body, expect)) in cases.into_iter().enumerate() {
        let f = format!("bad{i}.json");
        std::fs::write(
            d.path().join(&f),
            format!(r#"{{"case": "fourbar.json", {body}}}"#),
        )
        .unwrap();
        let out = format!("o{i}");
        let o = lash(&["sweep", &f, "--out", &out], d.path());
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{body}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{body}: {err}");
        assert!(err.contains(expect), "{body}: {err}");
        assert!(!d.path().join(&out).exists(), "{body}: ran something");
    }
}

/// The fields of one line of merged.csv (RFC 4180: a field in double quotes may hold commas,
/// as the JSON of `metrics_window` does); quoted fields keep their quotes.
fn csv_row(line: &str) -> Vec<&str> {
    let (mut fields, mut start, mut quoted) = (Vec::new(), 0, false);
    for (i, c) in line.char_indices() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => {
                fields.push(&line[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    fields.push(&line[start..]);
    fields
}
