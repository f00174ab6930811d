//! Interruption and resuming (docs/outputs.md, "Progress and interrupting a command"): a stop request
//! (`lash_solver::interrupt`, raised by SIGINT or SIGTERM in `lash`) ends the run in flight at
//! its next step, starts no new item, keeps what had finished; a rerun redoes nothing that
//! finished.
//!
//! The stop request is one flag for the whole process, so every check lives in this one test
//! binary and runs in one test, in sequence, through the engine's public API (the commands
//! with their options, as a front end calls them).

use std::collections::BTreeSet;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use lash_solver::interrupt::{clear_stop, request_stop, stop_requested};
use lash_solver::{solve, Method, OdeSystem, SolveError, SolverOptions};
use lash_validation::study::Plan as StudyPlan;
use lash_validation::{
    Error, ErrorKind, ExtremesOptions, Message, NoProgress, PointResult, Progress, StudyOptions,
    SweepPoint, SweepRunOptions,
};

/// Records what the engine reports; raises the stop request once `stop_after` items finished.
#[derive(Default)]
struct Recorder {
    stop_after: Option<usize>,
    totals: Mutex<Vec<(String, usize)>>,
    finished: Mutex<Vec<String>>,
    notes: Mutex<Vec<String>>,
    count: AtomicUsize,
}

impl Recorder {
    fn stopping_after(n: usize) -> Recorder {
        Recorder {
            stop_after: Some(n),
            ..Default::default()
        }
    }
    fn finished(&self) -> Vec<String> {
        self.finished.lock().unwrap().clone()
    }
    fn total(&self, what: &str) -> Option<usize> {
        self.totals
            .lock()
            .unwrap()
            .iter()
            .find(|(w, _)| w == what)
            .map(|x| x.1)
    }
}

impl Progress for Recorder {
    fn started(&self, what: &str, total: usize) {
        self.totals.lock().unwrap().push((what.into(), total));
    }
    fn finished(&self, what: &str, _secs: f64) {
        self.finished.lock().unwrap().push(what.into());
        let n = self.count.fetch_add(1, Ordering::SeqCst) + 1;
        if self.stop_after.is_some_and(|k| n >= k) {
            request_stop();
        }
    }
    fn note(&self, line: &Message) {
        self.notes.lock().unwrap().push(line.to_string());
    }
}

/// y' = −y: a run long enough to be stopped in the middle.
struct Decay;
impl OdeSystem for Decay {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = -y[0];
    }
}

fn solver_stops_at_a_step_boundary() {
    request_stop();
    for method in [Method::Dopri54, Method::Rk4, Method::Bdf, Method::Rodas5p] {
        let mut o = SolverOptions::with_method(method);
        if method.is_fixed_step() {
            o.step = Some(1e-3);
        }
        match solve(&Decay, (0.0, 1.0), &[1.0], &o) {
            // Stopped before the first step: at t0 with the initial state.
            Err(SolveError::Interrupted { t, y }) => assert_eq!((t, y), (0.0, vec![1.0])),
            other => panic!("{method}: {other:?}"),
        }
    }
    // The engine sees an interruption, not a solver failure (exit 130, not 3).
    let e = Error::from(SolveError::Interrupted {
        t: 0.25,
        y: vec![1.0],
    });
    assert_eq!(e.kind(), ErrorKind::Interrupted);
    clear_stop();
    assert!(solve(&Decay, (0.0, 1.0), &[1.0], &SolverOptions::default()).is_ok());
}

fn study_resumes_without_redoing_finished_runs(dir: &Path) {
    let mut plan = StudyPlan::paper();
    plan.realisations = 1;
    // 14 clearance cases and 4 ideal ones, one realisation each, at three settings, and the
    // four lubricated 150 rpm cases again until periodic (the periodicity claim).
    let all = 18 * 3 + 4 * 3;
    let out = dir.join("study");
    let options = |out: &Path| StudyOptions {
        out: Some(out.to_path_buf()),
        robustness: false,
        plan: Some(plan),
    };
    let first = Recorder::stopping_after(10);
    let e = lash_validation::study_paper(&options(&out), &first).unwrap_err();
    clear_stop();
    assert_eq!(e.kind(), ErrorKind::Interrupted, "{e}");
    let kept = first.finished().len();
    assert!(kept >= 10, "{kept}");
    assert!(
        e.to_string()
            .contains(&format!("{kept} of {all} runs finished and kept")),
        "{e}"
    );
    // Nothing but the cache is written; it holds exactly the finished runs.
    assert!(!out.join("study.json").exists() && !out.join("figures").exists());
    assert_eq!(std::fs::read_dir(out.join("cache")).unwrap().count(), kept);
    // The rerun does the other runs, and only those.
    let second = Recorder::default();
    let resumed = lash_validation::study_paper(&options(&out), &second)
        .unwrap()
        .result;
    assert_eq!(second.total("runs"), Some(all - kept));
    let redone: BTreeSet<String> = second.finished().into_iter().collect();
    assert_eq!(redone.len(), all - kept);
    assert!(
        first.finished().iter().all(|w| !redone.contains(w)),
        "a finished run ran again"
    );
    assert!(second.notes.lock().unwrap()[0].starts_with(&format!(
        "study: {kept} of {all} runs finished before, reused from"
    )));
    // The numbers are those of an uninterrupted study (wall times aside).
    let fresh = lash_validation::study_paper(&options(&dir.join("fresh")), &NoProgress)
        .unwrap()
        .result;
    for (a, b) in resumed.cases.iter().zip(&fresh.cases) {
        assert_eq!(
            (&a.study, &a.reference, &a.loose),
            (&b.study, &b.reference, &b.loose)
        );
        assert_eq!(a.solver.stats, b.solver.stats);
    }
    assert_eq!(resumed.claims, fresh.claims);
    // A third run reuses everything.
    let third = Recorder::default();
    lash_validation::study_paper(&options(&out), &third).unwrap();
    assert_eq!((third.total("runs"), third.finished().len()), (Some(0), 0));
}

fn extremes_resume_without_redoing_finished_runs(dir: &Path) {
    // rk4 inside and beyond, 8 adaptive methods × 2 tolerances.
    let all = 2 + 8 * 2;
    let options = ExtremesOptions {
        quick: true,
        scenes: Some(vec!["dry_stiffness_1e14".into()]),
        tolerances: Some(vec![1e-3, 1e-6]),
        out: Some(dir.join("extremes")),
        ..Default::default()
    };
    // Stop after the reference and 4 runs.
    let first = Recorder::stopping_after(5);
    let e = lash_validation::extremes(&options, &first).unwrap_err();
    clear_stop();
    assert_eq!(e.kind(), ErrorKind::Interrupted, "{e}");
    let done = first.finished();
    assert!(
        done[0].starts_with("dry_stiffness_1e14: reference"),
        "{done:?}"
    );
    let runs_kept = done.len() - 1;
    assert!(runs_kept >= 4);
    let second = Recorder::default();
    let w = lash_validation::extremes(&options, &second).unwrap();
    assert_eq!(second.total("references"), Some(0));
    assert_eq!(second.total("runs"), Some(all - runs_kept));
    // A run's name is what precedes its outcome ("scene method setting: outcome").
    let name = |w: &String| w.split(": ").next().unwrap_or_default().to_string();
    let redone: BTreeSet<String> = second.finished().iter().map(name).collect();
    assert_eq!(redone.len(), all - runs_kept);
    assert!(
        done[1..].iter().all(|w| !redone.contains(&name(w))),
        "a finished run ran again"
    );
    // extremes.json (the matrix as written, docs/outputs.md): every cell, no failure.
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(w.dir.join("extremes.json")).unwrap()).unwrap();
    assert_eq!(json["cells"].as_array().unwrap().len(), all);
    assert_eq!(
        json["failures"],
        0,
        "{}",
        w.dir.join("extremes.md").display()
    );
}

fn sweep_abandons_the_point_in_flight(dir: &Path) {
    std::fs::write(dir.join("base.json"), b"{}").unwrap();
    let file = dir.join("grid.json");
    std::fs::write(
        &file,
        br#"{"case": "base.json", "speed_rpm": [1, 2, 3, 4, 5, 6]}"#,
    )
    .unwrap();
    let root = dir.join("sweep");
    let options = SweepRunOptions {
        max_wall_time: None,
        window: None,
        file,
        jobs: Some(1),
        shard: None,
        out: Some(root.clone()),
    };
    let ran = Mutex::new(Vec::new());
    // The third point is stopped in flight after writing a partial file, as a run whose
    // solver hits the stop request would be.
    let runner = |p: &SweepPoint, d: &Path| -> Result<PointResult, Error> {
        ran.lock().unwrap().push((p.index, p.id.clone()));
        if p.index == 2 {
            std::fs::write(d.join("summary.json"), b"partial").unwrap();
            request_stop();
            return Err(Error::from(SolveError::Interrupted { t: 0.1, y: vec![] }));
        }
        Ok(PointResult::flatten(&serde_json::json!({"v": p.index})))
    };
    let e = lash_validation::sweep_with(&options, runner, &NoProgress).unwrap_err();
    clear_stop();
    assert!(
        e.kind() == ErrorKind::Interrupted
            && e.to_string().contains("2 of 6 in all are kept; 4 left"),
        "{e}"
    );
    let mut ran = ran.into_inner().unwrap();
    ran.sort();
    assert_eq!(ran.iter().map(|r| r.0).collect::<Vec<_>>(), [0, 1, 2]);
    // The abandoned point left nothing; the finished ones stay; no claim is left.
    assert!(!root.join(&ran[2].1).exists());
    for (_, id) in &ran[..2] {
        assert!(root.join(id).join("result.json").is_file());
        assert!(!root.join(id).join("claim.json").exists());
    }
    // The rerun runs the four others only.
    let again = AtomicUsize::new(0);
    let o = lash_validation::sweep_with(
        &options,
        |p, _| {
            again.fetch_add(1, Ordering::SeqCst);
            Ok(PointResult::flatten(&serde_json::json!({"v": p.index})))
        },
        &NoProgress,
    )
    .unwrap();
    let r = o.report;
    assert_eq!((r.skipped, r.ok, again.load(Ordering::SeqCst)), (2, 4, 4));
}

#[test]
fn interrupted_work_stops_cleanly_and_resumes() {
    let d = tempfile::tempdir().unwrap();
    solver_stops_at_a_step_boundary();
    sweep_abandons_the_point_in_flight(d.path());
    assert!(!stop_requested());
    study_resumes_without_redoing_finished_runs(d.path());
    extremes_resume_without_redoing_finished_runs(d.path());
}
