//! Long work and bad conditions, end to end on the built `lash` binary: progress lines off a
//! terminal, SIGINT (exit 130, the point in flight abandoned, finished points kept, a rerun
//! resumes), two processes on one sweep, merge of an incomplete or corrupt sweep, `--jobs`
//! above the cores (docs/outputs.md: "Sweeps", "Progress and interrupting a command", "Exit codes of
//! `lash`").

mod common;
use common::{lash, ok};

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use lash_model::cases::{press_scene, PressJoint};

/// A lubricated press cut to `t_end` s, and a sweep of `speeds` × 2 viscosities over it
/// (bdf, rtol 1e-6) in `dir/grid.json`.
fn grid(dir: &Path, t_end: f64, speeds: &[f64]) -> PathBuf {
    let mut s = press_scene(PressJoint::Lubricated, 150.0, 1e-4);
    s.revolutions = None;
    s.t_end = Some(t_end);
    std::fs::write(dir.join("lub.json"), s.to_json_pretty()).unwrap();
    let speeds: Vec<String> = speeds.iter().map(|v| format!("{v:?}")).collect();
    let g = dir.join("grid.json");
    std::fs::write(
        &g,
        format!(
            r#"{{"case": "lub.json", "speed_rpm": [{}], "viscosity": [0.2, 0.4],
                "method": ["bdf"], "rtol": [1e-6]}}"#,
            speeds.join(", ")
        ),
    )
    .unwrap();
    g
}

/// The point directories of a sweep output directory.
fn point_dirs(out: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    v.sort();
    v
}

/// Every file under `dir` whose name says it is a claim or a temporary file.
fn leftovers(dir: &Path) -> Vec<PathBuf> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            v.extend(leftovers(&p));
        } else {
            let n = p.file_name().unwrap().to_string_lossy().into_owned();
            if n == "claim.json" || n.contains(".tmp-") || n.starts_with(".claim") {
                v.push(p);
            }
        }
    }
    v
}

#[test]
fn off_a_terminal_each_point_is_a_log_line_and_jobs_are_capped() {
    let d = tempfile::tempdir().unwrap();
    grid(d.path(), 0.02, &[120.0, 150.0]);
    let o = lash(
        &["sweep", "grid.json", "--out", "s", "--jobs", "100000"],
        d.path(),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let cores = std::thread::available_parallelism().unwrap().get();
    assert!(
        err.contains(&format!(
            "--jobs 100000 is more than the {cores} cores available: using {cores}"
        )),
        "{err}"
    );
    assert!(err.contains("lash: 4 points to run"), "{err}");
    // One line per finished point: which, how it ended, how long, how many are left.
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with('[')).collect();
    assert_eq!(lines.len(), 4, "{err}");
    for (k, l) in lines.iter().enumerate() {
        assert!(l.starts_with(&format!("[{}/4] point ", k + 1)), "{l}");
        assert!(l.contains("): ok (") && l.contains(" s); "), "{l}");
    }
    assert!(lines[0].contains("3 points left, ~") && lines[3].ends_with("all points done"));
    // Standard output stays for results: the sweep prints nothing there.
    assert!(o.stdout.is_empty());
    assert!(leftovers(&d.path().join("s")).is_empty());
}

#[test]
fn two_processes_on_one_sweep_compute_each_point_once() {
    let d = tempfile::tempdir().unwrap();
    grid(d.path(), 0.05, &[120.0, 135.0, 150.0, 165.0, 180.0]);
    let spawn = || {
        Command::new(env!("CARGO_BIN_EXE_lash"))
            .args(["sweep", "grid.json", "--out", "s", "--jobs", "1"])
            .current_dir(d.path())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (spawn(), spawn());
    let outs = [a.wait_with_output().unwrap(), b.wait_with_output().unwrap()];
    let mut ran = Vec::new();
    for o in &outs {
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(0), "{err}");
        for l in err.lines().filter(|l| l.contains("): ok (")) {
            ran.push(
                l.split(" point ")
                    .nth(1)
                    .unwrap()
                    .split(':')
                    .next()
                    .unwrap()
                    .to_string(),
            );
        }
    }
    ran.sort();
    let n = ran.len();
    ran.dedup();
    // Ten points, each computed by exactly one of the two processes.
    assert_eq!((n, ran.len()), (10, 10), "{ran:?}");
    assert_eq!(point_dirs(&d.path().join("s")).len(), 10);
    assert!(leftovers(&d.path().join("s")).is_empty());
    ok(&["merge", "s"], d.path());
}

/// Issue 23: two processes on one sweep, the first killed (SIGKILL: no clean-up) while it
/// holds a claim the second has already skipped. The second, once its own points are done,
/// finds the holder dead, takes the point over and exits 0 with every point finished (it used
/// to exit 0 with that point unfinished).
#[test]
fn a_survivor_takes_over_the_claims_of_a_killed_peer() {
    let d = tempfile::tempdir().unwrap();
    // Points of most of a second each (0.6 s of motion take about 0.06 s), one at a time per
    // process, so the first still holds its claim when the second has passed it.
    grid(d.path(), 6.0, &[120.0, 150.0, 180.0]);
    let spawn = || {
        Command::new(env!("CARGO_BIN_EXE_lash"))
            .args(["sweep", "grid.json", "--out", "s", "--jobs", "1"])
            .current_dir(d.path())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let mut a = spawn();
    // Wait until the first process holds a claim.
    let s = d.path().join("s");
    let t0 = std::time::Instant::now();
    while !(s.is_dir()
        && point_dirs(&s)
            .iter()
            .any(|p| p.join("claim.json").is_file()))
    {
        assert!(t0.elapsed().as_secs() < 60, "no claim appeared");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let mut b = spawn();
    let mut err = BufReader::new(b.stderr.take().unwrap());
    let mut seen = String::new();
    // The second process skips the point the first holds ...
    loop {
        let mut l = String::new();
        assert!(err.read_line(&mut l).unwrap() > 0, "ended early: {seen}");
        seen.push_str(&l);
        if l.contains("left to it") {
            break;
        }
    }
    // ... and then the first dies holding it (reaped, as a shell or a scheduler would).
    a.kill().unwrap();
    a.wait().unwrap();
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut err, &mut rest).unwrap();
    seen.push_str(&rest);
    let status = b.wait().unwrap();
    assert_eq!(status.code(), Some(0), "{seen}");
    assert!(
        seen.contains("left it unfinished; taken over here: ok"),
        "{seen}"
    );
    // Every point finished, no claim or temporary file left; merge finds nothing missing.
    let finished = point_dirs(&s)
        .iter()
        .filter(|p| p.join("result.json").is_file())
        .count();
    assert_eq!(finished, 6, "{seen}");
    assert!(leftovers(&s).is_empty(), "{:?}", leftovers(&s));
    ok(&["merge", "s"], d.path());
}

#[test]
fn sigint_abandons_the_point_in_flight_and_a_rerun_resumes() {
    let d = tempfile::tempdir().unwrap();
    // Points of a few tenths of a second each, one at a time.
    grid(d.path(), 0.4, &[100.0, 120.0, 140.0, 160.0, 180.0, 200.0]);
    let mut child = Command::new(env!("CARGO_BIN_EXE_lash"))
        .args(["sweep", "grid.json", "--out", "s", "--jobs", "1"])
        .current_dir(d.path())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut seen = String::new();
    // Wait for the first finished point, then interrupt.
    loop {
        let mut l = String::new();
        assert!(err.read_line(&mut l).unwrap() > 0, "ended early: {seen}");
        seen.push_str(&l);
        if l.starts_with("[1/") {
            break;
        }
    }
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut err, &mut rest).unwrap();
    let status = child.wait().unwrap();
    seen.push_str(&rest);
    assert_eq!(status.code(), Some(130), "{seen}");
    let last = seen.lines().last().unwrap();
    assert!(
        last.starts_with("error: interrupted: sweep: ") && last.contains("rerun the same command"),
        "{seen}"
    );
    assert!(seen.contains("lash: stopping"), "{seen}");
    // Finished points stay, the one in flight left nothing, no claim or temporary file.
    let s = d.path().join("s");
    let finished: Vec<PathBuf> = point_dirs(&s)
        .into_iter()
        .filter(|p| p.join("result.json").is_file())
        .collect();
    assert!(!finished.is_empty() && finished.len() < 12, "{seen}");
    assert_eq!(
        point_dirs(&s).len(),
        finished.len(),
        "a partial point directory stayed"
    );
    assert!(leftovers(&s).is_empty(), "{:?}", leftovers(&s));
    // merge names the unfinished points and refuses, unless --allow-partial.
    let o = lash(&["merge", "s"], d.path());
    let m = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{m}");
    let missing = 12 - finished.len();
    assert!(
        m.starts_with(&format!(
            "error: merge: the sweep is incomplete ({} finished): {missing} point(s) unfinished: #",
            finished.len()
        )) && m.contains("--allow-partial to merge what finished"),
        "{m}"
    );
    assert!(!s.join("merged.csv").exists());
    let o = lash(&["merge", "s", "--allow-partial"], d.path());
    assert_eq!(o.status.code(), Some(0));
    let csv = std::fs::read_to_string(s.join("merged.csv")).unwrap();
    assert_eq!(csv.lines().count(), 13);
    assert_eq!(
        csv.matches(",unfinished,unfinished,").count(),
        missing,
        "{csv}"
    );
    // The rerun does the rest only.
    let o = lash(&["sweep", "grid.json", "--out", "s"], d.path());
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{e}");
    assert!(
        e.contains(&format!(
            "{missing} ran, 0 solver failures, {} already done",
            finished.len()
        )),
        "{e}"
    );
    ok(&["merge", "s"], d.path());
}

#[test]
fn merge_names_a_corrupt_point() {
    let d = tempfile::tempdir().unwrap();
    grid(d.path(), 0.02, &[120.0]);
    ok(&["sweep", "grid.json", "--out", "s"], d.path());
    let dirs = point_dirs(&d.path().join("s"));
    std::fs::write(dirs[1].join("result.json"), b"{\"id\": ").unwrap();
    let o = lash(&["merge", "s"], d.path());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    let id = dirs[1].file_name().unwrap().to_string_lossy().into_owned();
    assert!(
        err.contains("1 point(s) with a corrupt result.json: #") && err.contains(&id),
        "{err}"
    );
    // A rerun of the sweep says so and computes the point again.
    let o = lash(&["sweep", "grid.json", "--out", "s"], d.path());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains(&format!("({id}) runs again: ")), "{e}");
    assert!(
        e.contains("1 ran, 0 solver failures, 1 already done"),
        "{e}"
    );
    ok(&["merge", "s"], d.path());
}
