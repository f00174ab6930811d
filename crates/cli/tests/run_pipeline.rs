//! End-to-end: `lash run` over long runs, interruptions and bad conditions — peak memory that
//! does not grow with the simulated time, standard output closed or full, reruns that fail or
//! are killed while writing, budgets that cover the set-up, and the runs f64 cannot do right
//! (docs/outputs.md: "Exit codes of `lash`", "General rules", "`failure.json`").

mod common;
use common::{lash, ok};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn press(stem: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join(format!("../../cases/press/{stem}.json"))
        .to_string_lossy()
        .into_owned()
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lash"))
}

/// Every file of a directory and its bytes.
fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

/// Names in `dir` other than `keep`.
fn others(dir: &Path, keep: &str) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != keep)
        .collect()
}

/// The peak resident set (VmHWM, KiB) of a child, polled from /proc until it exits: VmHWM
/// only grows, so the last value read before the exit is the peak (within the 5 ms between
/// polls). None without /proc.
fn peak_rss_kib(mut cmd: Command) -> Option<(u64, bool)> {
    if !Path::new("/proc/self/status").exists() {
        return None;
    }
    let mut child = cmd
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let status = format!("/proc/{}/status", child.id());
    let mut peak = 0;
    loop {
        if let Ok(s) = std::fs::read_to_string(&status) {
            if let Some(kb) = s
                .lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse::<u64>().ok())
            {
                peak = peak.max(kb);
            }
        }
        if let Some(st) = child.try_wait().unwrap() {
            return Some((peak, st.success()));
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// simulate.rs ("memory"): the trajectory is streamed and the metrics accumulated on the fly,
/// so the peak memory of a run does not grow with its length. The ideal press with RK4 at
/// 1 ms, 2000 rows per revolution, for 5 and 50 revolutions (10 001 and 100 001 rows of 41
/// columns). Before streaming (every row held, then the whole CSV as one string) the peak
/// grew by about 0.9 MB per revolution: 21 MB at 10 revolutions, 105 MB at 100
/// (BENCHMARKS.md, "Streamed output: peak memory of long runs"); streamed, both peaks are
/// about 11 MB.
#[test]
fn peak_memory_does_not_grow_with_the_simulated_time() {
    let d = tempfile::tempdir().unwrap();
    let run = |revs: f64, out: &str| {
        let mut c = bin();
        c.args([
            "run",
            &press("ideal_150rpm"),
            "--method",
            "rk4",
            "--step",
            "1e-3",
            "--t-end",
            &format!("{}", revs * 0.4),
            "--out",
            out,
        ])
        .current_dir(d.path());
        peak_rss_kib(c)
    };
    let Some((short, ok_short)) = run(5.0, "short") else {
        return;
    };
    let (long, ok_long) = run(50.0, "long").unwrap();
    assert!(ok_short && ok_long);
    let rows = std::fs::read_to_string(d.path().join("long/trajectory.csv"))
        .unwrap()
        .lines()
        .count();
    assert_eq!(rows, 1 + 100_001);
    assert!(
        long < short + 8 * 1024,
        "peak grew from {short} KiB to {long} KiB"
    );
    assert!(long < 40 * 1024, "peak {long} KiB");
}

/// app.rs, out.rs: standard output closed by its reader ends quietly (no panic, the run's own
/// exit code, its files written); standard output that cannot be written (a full device) is
/// one line on standard error and exit 2, after the files were written.
#[test]
fn closed_or_full_standard_output_never_panics() {
    let d = tempfile::tempdir().unwrap();
    let args = ["run", &press("ideal_150rpm"), "--t-end", "0.05", "--out"];
    // The reader is gone before lash writes a byte.
    let mut child = bin()
        .args(args)
        .arg("a")
        .current_dir(d.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.is_empty(), "{err}");
    assert!(d.path().join("a/summary.json").is_file());
    if let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") {
        let o = bin()
            .args(args)
            .arg("b")
            .current_dir(d.path())
            .stdout(full)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.starts_with("error: writing standard output: "), "{err}");
        assert!(!err.contains("panicked"));
        assert!(d.path().join("b/summary.json").is_file());
    }
    // Help into a closed pipe too.
    let mut child = bin()
        .arg("--help")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0));
    assert!(o.stderr.is_empty());
}

/// io.rs (OutDir): a rerun that cannot write its files (the file size limit stands in for a
/// full disk: SIGXFSZ ignored, so writes fail with EFBIG) is an I/O error (exit 2) and leaves
/// the earlier run exactly as it was, with no temporary beside it.
#[test]
fn a_rerun_that_fails_to_write_leaves_the_old_run_intact() {
    if Command::new("sh").arg("-c").arg("true").status().is_err() {
        return;
    }
    let d = tempfile::tempdir().unwrap();
    ok(
        &[
            "run",
            &press("ideal_150rpm"),
            "--t-end",
            "0.05",
            "--out",
            "o",
        ],
        d.path(),
    );
    let before = snapshot(&d.path().join("o"));
    // 2 revolutions write about 3 MB of trajectory; the limit is 256 KiB.
    let o = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "trap '' XFSZ; ulimit -f 512; exec \"$0\" run '{}' --out o",
            press("ideal_150rpm")
        ))
        .arg(env!("CARGO_BIN_EXE_lash"))
        .current_dir(d.path())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("trajectory.csv") && err.contains("too large"),
        "{err}"
    );
    assert_eq!(snapshot(&d.path().join("o")), before);
    assert!(
        others(d.path(), "o").is_empty(),
        "{:?}",
        others(d.path(), "o")
    );
}

/// io.rs (OutDir): a rerun stopped while it writes leaves the earlier run exactly as it was.
/// SIGINT (Ctrl-C) is a stop request: exit 130 and the run's temporary directory removed on
/// the way out. SIGKILL leaves the temporary behind; the next run into the same place removes
/// it and replaces the old run whole.
#[test]
fn a_rerun_interrupted_while_writing_leaves_the_old_run_intact() {
    if !Path::new("/proc/self").exists() || Command::new("kill").arg("-l").output().is_err() {
        return;
    }
    for (signal, code, temporaries) in [("-INT", Some(130), 0), ("-KILL", None, 1)] {
        rerun_stopped_while_writing(signal, code, temporaries);
    }
}

fn rerun_stopped_while_writing(signal: &str, code: Option<i32>, temporaries: usize) {
    let d = tempfile::tempdir().unwrap();
    ok(
        &[
            "run",
            &press("ideal_150rpm"),
            "--t-end",
            "0.05",
            "--out",
            "o",
        ],
        d.path(),
    );
    let before = snapshot(&d.path().join("o"));
    // 100 revolutions of RK4 at 1 ms: several seconds of streaming.
    let mut child = bin()
        .args([
            "run",
            &press("ideal_150rpm"),
            "--method",
            "rk4",
            "--step",
            "1e-3",
            "--t-end",
            "40",
            "--out",
            "o",
        ])
        .current_dir(d.path())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Wait until its trajectory is being written.
    let started = Instant::now();
    let writing = loop {
        let tmp: Vec<PathBuf> = std::fs::read_dir(d.path())
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| {
                p.file_name()
                    .unwrap()
                    .to_string_lossy()
                    .starts_with(".o.tmp-")
            })
            .collect();
        let size = tmp
            .first()
            .and_then(|t| std::fs::metadata(t.join("trajectory.csv")).ok())
            .map_or(0, |m| m.len());
        if size > 100_000 || started.elapsed() > Duration::from_secs(60) {
            break size > 100_000;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let killed = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    let st = child.wait().unwrap();
    assert!(writing && killed.success(), "{signal}: {st:?}");
    assert_eq!(st.code(), code, "{signal}: {st:?}");
    assert_eq!(snapshot(&d.path().join("o")), before, "{signal}");
    assert_eq!(
        others(d.path(), "o").len(),
        temporaries,
        "{signal}: the stopped run's temporary"
    );
    // The next run cleans it and replaces the old run.
    ok(
        &[
            "run",
            &press("ideal_150rpm"),
            "--t-end",
            "0.1",
            "--out",
            "o",
        ],
        d.path(),
    );
    assert!(
        others(d.path(), "o").is_empty(),
        "{:?}",
        others(d.path(), "o")
    );
    let after = snapshot(&d.path().join("o"));
    assert_eq!(
        after.keys().collect::<Vec<_>>(),
        before.keys().collect::<Vec<_>>()
    );
    assert_ne!(after["trajectory.csv"], before["trajectory.csv"]);
}

/// commands.rs (run): `--max-wall-time` is the budget of the whole run. The press plus 3 000
/// free bodies spends tens of milliseconds in reading, checking and assembling the scene (since
/// the sparse path its initial Jacobian check is no longer dense: with 1 000 bodies set-up now
/// ends within 0.05 s); a budget of 0.01 s ends the run there, at set-up's next check
/// (lash_model's build phases), with exit 3 naming set-up, whatever the step budget.
#[test]
fn the_wall_clock_budget_covers_the_set_up() {
    let d = tempfile::tempdir().unwrap();
    let mut scene: serde_json::Value =
        serde_json::from_slice(&std::fs::read(press("ideal_150rpm")).unwrap()).unwrap();
    for i in 0..3000 {
        scene["bodies"]
            .as_array_mut()
            .unwrap()
            .push(serde_json::json!({
                "name": format!("b{i}"), "mass": 1.0, "inertia": 0.1, "position": [i as f64, 5.0]
            }));
    }
    std::fs::write(d.path().join("free.json"), scene.to_string()).unwrap();
    let started = Instant::now();
    let o = lash(
        &[
            "run",
            "free.json",
            "--max-wall-time",
            "0.01",
            "--max-steps",
            "10",
            "--out",
            "o",
        ],
        d.path(),
    );
    let took = started.elapsed().as_secs_f64();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains("error: solver failed: budget exhausted"),
        "{err}"
    );
    assert!(
        err.contains("wall-clock budget of 0.01 s used during set-up ("),
        "{err}"
    );
    assert!(
        err.contains("(no state yet: the run stopped during its set-up)"),
        "{err}"
    );
    assert!(took < 3.0, "{took} s");
    assert!(!d.path().join("o/summary.json").exists());
}

/// Asserts exit code 2 and one line on standard error containing `needle`; nothing written.
fn refused(args: &[&str], cwd: &Path, needle: &str) {
    let o = lash(args, cwd);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains(needle), "'{needle}' not in {err}");
    assert!(!cwd.join("o").exists());
}

/// simulate.rs ("Checks before a run"): what f64 or the output cannot carry is refused with
/// exit 2 naming the field, never an abort or a silent wrong answer.
#[test]
fn runs_that_cannot_be_done_right_exit_2_naming_the_field() {
    let d = tempfile::tempdir().unwrap();
    let mut scene: serde_json::Value =
        serde_json::from_slice(&std::fs::read(press("ideal_150rpm")).unwrap()).unwrap();
    scene["t_start"] = serde_json::json!(1e15);
    std::fs::write(d.path().join("far.json"), scene.to_string()).unwrap();
    refused(
        &["run", "far.json", "--out", "o"],
        d.path(),
        "case far: t_start = 1.000000e15 s is too far from 0 for f64 time",
    );
    // A driver's θ₀ of 1e17 rad, where f64 angles are 16 rad apart (issue 23: the crank froze
    // and the run exited 0).
    let mut scene: serde_json::Value =
        serde_json::from_slice(&std::fs::read(press("ideal_150rpm")).unwrap()).unwrap();
    for j in scene["joints"].as_array_mut().unwrap() {
        if j["type"] == "driver" {
            j["theta0"] = serde_json::json!(1e17);
        }
    }
    std::fs::write(d.path().join("frozen.json"), scene.to_string()).unwrap();
    refused(
        &["run", "frozen.json", "--out", "o"],
        d.path(),
        ".theta0 = 1.000000e17 rad: the driver's angle reaches 1.000e17 rad, where f64 angles \
         are at least 3.55e2 rad apart",
    );
    let ideal = press("ideal_150rpm");
    refused(
        &["run", &ideal, "--t-end", "1e6", "--out", "o"],
        d.path(),
        "5e9 rows, more than the 1e8 lash writes: thin it with --samples-per-revolution or \
         --output-every, or shorten --t-end",
    );
    refused(
        &[
            "run", &ideal, "--method", "rk4", "--step", "1", "--out", "o",
        ],
        d.path(),
        "--step 1 s is longer than the run (0.8 s",
    );
    refused(
        &[
            "run",
            &ideal,
            "--samples-per-revolution",
            "10",
            "--output-every",
            "0.1",
            "--out",
            "o",
        ],
        d.path(),
        "cannot be used with",
    );
    // Thinned, a long run is fine: 250 revolutions at 2 rows each.
    ok(
        &[
            "run",
            &ideal,
            "--t-end",
            "100",
            "--samples-per-revolution",
            "2",
            "--out",
            "thin",
        ],
        d.path(),
    );
    let csv = std::fs::read_to_string(d.path().join("thin/trajectory.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 501);
}
