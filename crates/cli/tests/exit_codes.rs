//! End-to-end: the built `lash` binary turns bad input into exit code 2 and one line on
//! standard error (docs/outputs.md, "Exit codes of `lash`").

mod common;
use common::lash;
use std::path::Path;

/// Asserts exit code 2, nothing on stdout, and exactly one line `error: ...` containing `needle`.
fn usage_error(args: &[&str], cwd: &Path, needle: &str) {
    let o = lash(args, cwd);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert!(o.stdout.is_empty(), "{args:?} wrote to stdout");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "{args:?}: not one line: {err:?}");
    assert!(lines[0].starts_with("error: "), "{args:?}: {err}");
    assert!(
        lines[0].contains(needle),
        "{args:?}: '{needle}' not in {err}"
    );
}

#[test]
fn bad_input_exits_2_with_one_line() {
    let d = tempfile::tempdir().unwrap();
    let cwd = d.path();
    std::fs::write(cwd.join("case.json"), b"{\"bodies\": []}").unwrap();
    std::fs::write(cwd.join("broken.json"), b"{\"bodies\": [").unwrap();
    usage_error(&["run"], cwd, "<CASE>");
    usage_error(
        &["run", "missing.json"],
        cwd,
        "case file missing.json not found",
    );
    usage_error(
        &["run", "broken.json"],
        cwd,
        "case file broken.json is not valid JSON",
    );
    usage_error(&["run", "testset:nosuch"], cwd, "unknown built-in case");
    usage_error(
        &["run", "case.json", "--method", "euler"],
        cwd,
        "unknown method 'euler'",
    );
    usage_error(
        &["run", "case.json", "--controller", "p"],
        cwd,
        "unknown controller 'p'",
    );
    usage_error(
        &["run", "case.json", "--rtol", "0"],
        cwd,
        "rtol must be in [1e-14, 1)",
    );
    usage_error(
        &["run", "case.json", "--step", "-1e-4"],
        cwd,
        "step must be > 0",
    );
    usage_error(
        &["run", "case.json", "--method", "dopri54", "--step", "1e-4"],
        cwd,
        "--step is only for fixed-step methods",
    );
    usage_error(
        &[
            "run",
            "case.json",
            "--method",
            "rk4",
            "--step",
            "1e-4",
            "--rtol",
            "1e-6",
        ],
        cwd,
        "--rtol is only for adaptive methods",
    );
    usage_error(
        &["run", "case.json", "--method", "rk4"],
        cwd,
        "needs --step",
    );
    usage_error(
        &[
            "work-precision",
            "case.json",
            "--methods",
            "rk4",
            "--tolerances",
            "1e-6",
        ],
        cwd,
        "--tolerances is only for adaptive methods",
    );
    usage_error(
        &["sweep", "none.json"],
        cwd,
        "sweep file none.json not found",
    );
    usage_error(
        &["sweep", "case.json", "--shard", "3/3"],
        cwd,
        "shard must be I/N",
    );
    usage_error(&["merge", "nodir"], cwd, "merge: nodir is not a directory");
    usage_error(&["frobnicate"], cwd, "unrecognized subcommand 'frobnicate'");
    usage_error(&["study", "other"], cwd, "invalid value 'other'");
}

#[test]
fn help_exits_0() {
    let d = tempfile::tempdir().unwrap();
    let o = lash(&["--help"], d.path());
    assert_eq!(o.status.code(), Some(0));
    let out = String::from_utf8_lossy(&o.stdout);
    for sub in [
        "run",
        "study",
        "compare",
        "work-precision",
        "sweep",
        "merge",
        "extremes",
        "stiffness",
        "poincare",
    ] {
        assert!(out.contains(sub), "help lacks {sub}: {out}");
    }
}

#[test]
fn merge_of_an_empty_sweep_writes_a_header_only_table() {
    let d = tempfile::tempdir().unwrap();
    std::fs::create_dir(d.path().join("sweep")).unwrap();
    let o = lash(&["merge", "sweep"], d.path());
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let csv = std::fs::read_to_string(d.path().join("sweep/merged.csv")).unwrap();
    assert_eq!(csv, "id,index,status,error\n");
}

/// Asserts exit code 3, a note naming what was written to `out` (failure.json, and the rows
/// before the failure), then a two-line report: the solver's typed error containing `needle`,
/// then the time and the state (docs/outputs.md, "Exit codes of `lash`"). Never summary.json.
fn budget_error(args: &[&str], cwd: &Path, out: &str, needle: &str) {
    let o = lash(args, cwd);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{args:?}: {err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 3, "{args:?}: {err}");
    assert!(lines[0].starts_with("wrote failure.json"), "{err}");
    assert!(lines[1].starts_with("error: solver failed: "), "{err}");
    assert!(lines[1].contains(needle), "'{needle}' not in {err}");
    assert!(lines[2].starts_with("  at t = "), "{err}");
    let dir = cwd.join(out);
    assert!(dir.join("failure.json").is_file(), "{args:?}");
    assert!(
        !dir.join("summary.json").exists(),
        "{args:?} wrote a summary"
    );
    assert!(!dir.join("trajectory.csv").exists(), "{args:?}");
}

#[test]
fn exhausted_budgets_exit_3_and_name_the_budget() {
    let d = tempfile::tempdir().unwrap();
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases/press/dry_150rpm_c0.1.json");
    let case = case.to_str().unwrap();
    // 10 steps cannot cover two revolutions (the dry journal is at its wall, where the step
    // limit near contact, T/100, alone needs 200).
    budget_error(
        &["run", case, "--max-steps", "10", "--out", "a"],
        d.path(),
        "a",
        "too many steps: ",
    );
    budget_error(
        &[
            "run",
            case,
            "--method",
            "rk4",
            "--step",
            "2e-4",
            "--max-steps",
            "10",
            "--out",
            "b",
        ],
        d.path(),
        "b",
        "too many steps: 10 steps taken, reached t = 2",
    );
    // One microsecond of wall time runs out before set-up's first check (after the scene's
    // validation): exit 3 naming set-up's phase, no state, and nothing written: no output
    // directory, since the run never started.
    let o = lash(
        &["run", case, "--max-wall-time", "1e-6", "--out", "c"],
        d.path(),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert_eq!(
        err.lines().collect::<Vec<_>>(),
        [
            "error: solver failed: budget exhausted at t = 0e0: wall-clock budget of 0.000001 s \
             used during set-up (checking the scene)",
            "  at t = 0e0 (no state yet: the run stopped during its set-up)"
        ]
    );
    assert!(!d.path().join("c").exists());
}

/// A run whose energy balance is off by more than its accuracy allows exits 3 with
/// `energy_balance` (docs/outputs.md, "The energy check of a run"): the fuzzed 2 µm film of
/// crates/validation/tests/data/fuzz_2082.json under ESDIRK3(4) at the default rtol 1e-8;
/// failure.json names the kind and the end time, partial_trajectory.csv holds the whole run
/// (0.01 s at 2.5 µs spacing: 4 001 rows). `--no-energy-check` keeps the run, and its
/// summary.json shows the balance the check refused (below −10 J of its 128 J of flows).
#[test]
fn a_broken_energy_balance_exits_3_unless_the_check_is_left_out() {
    let d = tempfile::tempdir().unwrap();
    let case =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../validation/tests/data/fuzz_2082.json");
    let case = case.to_str().unwrap();
    budget_error(
        &["run", case, "--method", "esdirk34", "--out", "a"],
        d.path(),
        "a",
        "energy balance off at t = 1e-2: balance error ",
    );
    let f = common::json(&d.path().join("a/failure.json"));
    assert_eq!(f["error"]["kind"], "energy_balance", "{f}");
    assert_eq!(f["t"], 0.01, "{f}");
    assert_eq!(f["rows"], 4001, "{f}");
    common::ok(
        &[
            "run",
            case,
            "--method",
            "esdirk34",
            "--no-energy-check",
            "--out",
            "b",
        ],
        d.path(),
    );
    let s = common::json(&d.path().join("b/summary.json"));
    let balance = s["metrics"]["energy"]["balance_error"].as_f64().unwrap();
    assert!(balance < -10.0, "{balance}");
}

/// A wall-clock budget longer than the clock holds (`--max-wall-time 1e300`: finite and > 0,
/// so the rule accepts it) is no budget: the run ends with exit 0 and writes its summary,
/// where the watchdog's and the engine's deadlines used to panic (exit 101).
#[test]
fn a_wall_time_budget_beyond_the_clock_is_no_budget() {
    let d = tempfile::tempdir().unwrap();
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases/press/dry_150rpm_c0.1.json");
    let case = case.to_str().unwrap();
    let args = [
        "run",
        case,
        "--t-end",
        "0.01",
        "--max-wall-time",
        "1e300",
        "--out",
        "far",
    ];
    common::ok(&args, d.path());
    assert!(d.path().join("far/summary.json").is_file());
}
