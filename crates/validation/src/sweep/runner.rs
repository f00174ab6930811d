//! Running a sweep's points: in parallel, each claimed by one process, its result written
//! atomically, a stop request abandoning the point in flight; the counts of what ran.
//!
//! Source: docs/outputs.md ("Sweeps", "Progress and interrupting a command").

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::Error;
use crate::progress::{self, Progress};
use crate::store::claim;
use crate::store::io;
use crate::sweep::spec::PointParams;
use crate::sweep::spec::Shard;
use crate::sweep::spec::SweepPoint;

/// Name of the result file of a point.
pub(crate) const RESULT_FILE: &str = "result.json";

/// What a point runner returns: named scalar values for the merged table.
///
/// ```text
/// values = flatten(object): {"a": {"b": 1}} → {"a.b": 1};
///          an array of per-joint records → one column per joint and field:
///          {"law_range": [{"joint": "j1", "depth_max": 1}]} → {"law_range[j1].joint": "j1",
///          "law_range[j1].depth_max": 1} (the scene-path notation of a named element);
///          other arrays kept as JSON text
/// ```
///
/// Source: docs/outputs.md ("Sweeps": point files, merge).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PointResult {
    /// Column name → value (number, string, bool or null).
    pub values: BTreeMap<String, Value>,
}

impl PointResult {
    /// Flattens a JSON object (a summary.json, say) into dotted column names.
    pub fn flatten(v: &Value) -> PointResult {
        let mut values = BTreeMap::new();
        flatten_into("", v, &mut values);
        PointResult { values }
    }
}

/// The name of an array entry that is a record of one joint (`law_range`): its `joint` field.
fn named(v: &Value) -> Option<&str> {
    v.as_object()?.get("joint")?.as_str()
}

fn flatten_into(prefix: &str, v: &Value, out: &mut BTreeMap<String, Value>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten_into(&key, x, out);
            }
        }
        Value::Array(items) if !items.is_empty() && items.iter().all(|x| named(x).is_some()) => {
            for x in items {
                let name = named(x).unwrap_or_default();
                flatten_into(&format!("{prefix}[{name}]"), x, out);
            }
        }
        Value::Array(_) => {
            out.insert(prefix.to_string(), Value::String(v.to_string()));
        }
        other => {
            out.insert(prefix.to_string(), other.clone());
        }
    }
}

/// How a finished point ended.
///
/// ```text
/// ok | solver_failed  (both finished: a rerun skips them)
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum PointStatus {
    /// The runner returned results.
    Ok,
    /// The solver failed: a result too (a method that cannot do the point), not rerun.
    SolverFailed,
}

/// The content of OUT/id/result.json.
///
/// ```text
/// OUT/id/result.json = { id, index, params, status, error, values }
/// ```
///
/// Source: docs/outputs.md ("Sweeps").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct PointRecord {
    /// The point's id (its directory name).
    pub id: String,
    /// Its index in the grid.
    pub index: usize,
    /// Its parameters.
    pub params: PointParams,
    /// How it ended.
    pub status: PointStatus,
    /// The solver's error (status `solver_failed`), else None.
    pub error: Option<String>,
    /// The runner's values (empty on solver failure).
    pub values: BTreeMap<String, Value>,
}

/// How [`run_sweep`] runs.
///
/// ```text
/// jobs threads (None = cores), shard I/N
/// ```
///
/// Source: docs/outputs.md ("Sweeps": `--jobs`, `--shard`).
#[derive(Clone, Debug)]
pub(crate) struct SweepOptions {
    /// Worker threads; None = one per core.
    pub jobs: Option<usize>,
    /// Which points.
    pub shard: Shard,
}

impl Default for SweepOptions {
    fn default() -> Self {
        SweepOptions {
            jobs: None,
            shard: Shard::ALL,
        }
    }
}

/// What `run_sweep` did.
///
/// ```text
/// selected = skipped + ok + solver_failed + |failed| + |busy| + abandoned
/// ```
///
/// Source: this module.
#[derive(Debug, Default)]
pub struct SweepReport {
    /// Points in the shard.
    pub selected: usize,
    /// Points skipped because they had finished before (or finished meanwhile in another
    /// process).
    pub skipped: usize,
    /// Points that ran and finished ok.
    pub ok: usize,
    /// Points that ran and ended in a solver failure (recorded, finished).
    pub solver_failed: usize,
    /// Points whose runner failed otherwise (not recorded: a rerun tries them again).
    pub failed: Vec<(usize, Error)>,
    /// Points another live process holds a claim on (index, "host:pid"): left to it.
    pub busy: Vec<(usize, String)>,
    /// Points not run or abandoned because a stop was requested (left for a rerun).
    pub abandoned: usize,
    /// Points whose result.json was there but corrupt (index, reason): run again.
    pub corrupt: Vec<(usize, String)>,
}

impl SweepReport {
    /// Ok if no point failed unrecorded and no stop was requested; else the first failure's
    /// error kind with a message that counts them, or [`Error::Interrupted`] with the counts.
    pub(crate) fn into_result(mut self) -> Result<SweepReport, Error> {
        let held = if self.busy.is_empty() {
            String::new()
        } else {
            self.busy.sort();
            let mut v: Vec<String> = self
                .busy
                .iter()
                .take(5)
                .map(|(i, h)| format!("#{i} (claimed by {h})"))
                .collect();
            if self.busy.len() > 5 {
                v.push(format!("and {} more", self.busy.len() - 5));
            }
            format!(
                "; {} of them claimed by other live processes: {}",
                self.busy.len(),
                v.join(", ")
            )
        };
        if self.abandoned > 0 {
            let done = self.skipped + self.ok + self.solver_failed;
            return Err(Error::Interrupted(format!(
                "sweep: {} point(s) finished in this run and {done} of {} in all are kept; {} \
                 left{held} (rerun the same command to resume)",
                self.ok + self.solver_failed,
                self.selected,
                self.selected - done
            )));
        }
        if !self.busy.is_empty() && self.failed.is_empty() {
            let done = self.skipped + self.ok + self.solver_failed;
            return Err(Error::Input(format!(
                "sweep: {} of {} point(s) unfinished{held} (rerun the same command to finish \
                 them)",
                self.selected - done,
                self.selected
            )));
        }
        if self.failed.is_empty() {
            return Ok(self);
        }
        self.failed.sort_by_key(|(i, _)| *i);
        let n = self.failed.len();
        let (i, e) = self.failed.swap_remove(0);
        let head = format!("{n} sweep point(s) failed; first, point {i}: ");
        let msg = format!("{head}{e}");
        Err(match e {
            Error::Usage(_) => Error::Usage(msg),
            Error::Option(o) => Error::Option(o.prefixed(head)),
            Error::Input(_) | Error::Scene { .. } | Error::Io { .. } => Error::Input(msg),
            Error::Solver(_) | Error::Internal(_) => Error::Internal(msg),
            Error::Interrupted(_) => Error::Interrupted(msg),
        })
    }
}

/// What a point's directory holds.
///
/// ```text
/// Finished(record) | Missing (no result.json) | Corrupt(reason: unreadable, not a
/// PointRecord, or a record of another point)
/// ```
///
/// Source: docs/outputs.md ("Sweeps").
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum PointState {
    /// result.json names this point.
    Finished(Box<PointRecord>),
    /// No result.json.
    Missing,
    /// result.json is there but unusable: why.
    Corrupt(String),
}

/// The state of the point with id `id` in `dir` (its directory).
pub(crate) fn point_state(dir: &Path, id: &str) -> PointState {
    let p = dir.join(RESULT_FILE);
    let bytes = match std::fs::read(&p) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return PointState::Missing,
        Err(e) => return PointState::Corrupt(format!("{}: {e}", p.display())),
    };
    match serde_json::from_slice::<PointRecord>(&bytes) {
        Ok(r) if r.id == id => PointState::Finished(Box::new(r)),
        Ok(r) => PointState::Corrupt(format!(
            "{}: the record of point {}, not {id}",
            p.display(),
            r.id
        )),
        Err(e) => PointState::Corrupt(format!("{}: {e}", p.display())),
    }
}

/// Name of the grid's manifest in a sweep's output directory: every point (index, id,
/// parameters), so that `merge` can name the points that have not finished.
pub(crate) const MANIFEST_FILE: &str = "points.json";

/// The content of OUT/points.json.
///
/// ```text
/// { points: [{ index, id, params }] }   the whole grid, whatever the shard
/// ```
///
/// Source: docs/outputs.md ("Sweeps").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct Manifest {
    /// The grid's points.
    pub points: Vec<ManifestPoint>,
}

/// One point of a [`Manifest`].
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct ManifestPoint {
    /// Index in the grid.
    pub index: usize,
    /// Id (directory name).
    pub id: String,
    /// Parameters.
    pub params: PointParams,
}

/// Runs the points of `opts.shard` that have not finished, in parallel, each in its own
/// directory `root/id` (created before `runner` is called and passed to it). A finished
/// point's `result.json` is written atomically; a solver failure is recorded as finished; any
/// other runner error leaves the point unfinished for a rerun. `progress` gets `started` with
/// the number of points to run, then `finished` (the point and its wall time) as each point
/// ends, whatever its outcome.
///
/// ```text
/// root/points.json  the grid (atomically, every run)
/// per point:  stop requested → left (abandoned);  finished → skipped;
///             claim::try_claim(root/id) busy → left to its holder for now;
///             claimed → finished meanwhile? skipped : clear temporaries of dead holders,
///             run, write result.json, release the claim
/// a stop requested while a point runs: the point's partial files are removed, its claim
///             released; the report counts it as abandoned
/// then        the points left to other processes, every RECHECK until none is left:
///             finished by the holder → already done; holder dead (claim stale) → taken over
///             and run here; stop requested → left in `busy` (an error naming them)
/// ```
pub(crate) fn run_sweep<F>(
    points: &[SweepPoint],
    root: &Path,
    opts: &SweepOptions,
    runner: F,
    progress: &dyn Progress,
) -> Result<SweepReport, Error>
where
    F: Fn(&SweepPoint, &Path) -> Result<PointResult, Error> + Sync,
{
    io::create_dir(root)?;
    let manifest = Manifest {
        points: points
            .iter()
            .map(|p| ManifestPoint {
                index: p.index,
                id: p.id.clone(),
                params: p.params.clone(),
            })
            .collect(),
    };
    io::write_json_atomic(&root.join(MANIFEST_FILE), &manifest)?;
    claim::remove_dead_temporaries(root);
    let selected: Vec<&SweepPoint> = points
        .iter()
        .filter(|p| opts.shard.contains(p.index))
        .collect();
    let mut corrupt = Vec::new();
    let mut todo = Vec::new();
    for p in &selected {
        match point_state(&root.join(&p.id), &p.id) {
            PointState::Finished(_) => {}
            PointState::Missing => todo.push(*p),
            PointState::Corrupt(why) => {
                progress
                    .note(&format!("sweep: point {} ({}) runs again: {why}", p.index, p.id).into());
                corrupt.push((p.index, why));
                todo.push(*p);
            }
        }
    }
    let report = Mutex::new(SweepReport {
        selected: selected.len(),
        skipped: selected.len() - todo.len(),
        corrupt,
        ..Default::default()
    });
    if report.lock().map(|r| r.skipped).unwrap_or(0) > 0 {
        progress.note(
            &format!(
                "sweep: {} of {} points already done",
                selected.len() - todo.len(),
                selected.len()
            )
            .into(),
        );
    }
    progress.started("points", todo.len());
    let jobs = progress::jobs_within_parallelism(opts.jobs, progress);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| Error::Internal(format!("thread pool: {e}")))?;
    let held_set: Mutex<BTreeSet<PathBuf>> = Mutex::new(BTreeSet::new());
    let held = &held_set;
    let (stop_beat, beat) = std::sync::mpsc::channel::<()>();
    std::thread::scope(|s| {
        // Dropped on every way out of this closure (a panic too), which ends the heartbeat.
        let stop_beat = stop_beat;
        // The heartbeat: refreshes the claims this process holds (claim::HEARTBEAT).
        s.spawn(move || {
            while let Err(std::sync::mpsc::RecvTimeoutError::Timeout) =
                beat.recv_timeout(claim::HEARTBEAT)
            {
                for p in held.lock().unwrap_or_else(|e| e.into_inner()).iter() {
                    claim::touch(p);
                }
            }
        });
        pool.install(|| {
            todo.par_iter().for_each(|p| {
                let clock = Instant::now();
                let outcome = run_point(p, root, &runner, held);
                let what = tally(outcome, p, &report);
                progress.finished(
                    &format!("point {} ({}): {what}", p.index, p.id),
                    clock.elapsed().as_secs_f64(),
                );
            })
        });
        wait_for_holders(points, root, &runner, held, &report, &pool, progress);
        let _ = stop_beat.send(());
    });
    let r = report.into_inner().unwrap_or_else(|e| e.into_inner());
    if !r.busy.is_empty() {
        let mut holders: Vec<&str> = r.busy.iter().map(|(_, h)| h.as_str()).collect();
        holders.sort();
        holders.dedup();
        progress.note(
            &format!(
                "sweep: {} point(s) claimed by other processes ({}) left unfinished",
                r.busy.len(),
                holders.join(", ")
            )
            .into(),
        );
    }
    Ok(r)
}

/// Counts how a point went in `report`; returns the words for its progress line.
fn tally(outcome: Result<Ran, Error>, p: &SweepPoint, report: &Mutex<SweepReport>) -> String {
    let mut r = report.lock().unwrap_or_else(|e| e.into_inner());
    match outcome {
        Ok(Ran::Status(PointStatus::Ok)) => {
            r.ok += 1;
            "ok".to_string()
        }
        Ok(Ran::Status(PointStatus::SolverFailed)) => {
            r.solver_failed += 1;
            "solver failure (recorded)".to_string()
        }
        Ok(Ran::AlreadyDone) => {
            r.skipped += 1;
            "finished meanwhile by another process".to_string()
        }
        Ok(Ran::Busy(holder)) => {
            r.busy.push((p.index, holder.clone()));
            format!("claimed by {holder}, left to it")
        }
        Ok(Ran::Abandoned) => {
            r.abandoned += 1;
            "abandoned (stop requested)".to_string()
        }
        Err(e) => {
            let s = format!("failed: {e}");
            r.failed.push((p.index, e));
            s
        }
    }
}

/// How often a process that has finished its own points looks again at the claims of
/// points other processes hold.
pub(crate) const RECHECK: std::time::Duration = std::time::Duration::from_millis(500);

/// The second pass (issue 23): once this process has run its own points, the points it left
/// to other processes are looked at again every [`RECHECK`] until each is finished (by its
/// holder: counted as already done) or its claim is stale (its holder died: the claim is
/// taken over and the point run here, `claim::try_claim`), or a stop is requested (those
/// left stay in `busy`: the sweep's error names them).
fn wait_for_holders<F>(
    points: &[SweepPoint],
    root: &Path,
    runner: &F,
    held: &Mutex<BTreeSet<PathBuf>>,
    report: &Mutex<SweepReport>,
    pool: &rayon::ThreadPool,
    progress: &dyn Progress,
) where
    F: Fn(&SweepPoint, &Path) -> Result<PointResult, Error> + Sync,
{
    let take = || std::mem::take(&mut report.lock().unwrap_or_else(|e| e.into_inner()).busy);
    let mut busy = take();
    if busy.is_empty() {
        return;
    }
    let mut holders: Vec<&str> = busy.iter().map(|(_, h)| h.as_str()).collect();
    holders.sort();
    holders.dedup();
    progress.note(
        &format!(
            "sweep: waiting for {} point(s) claimed by other processes ({}); a holder that dies \
             is taken over (on this host at once, on another when its claim is {} s without \
             heartbeat)",
            busy.len(),
            holders.join(", "),
            claim::STALE_AFTER.as_secs()
        )
        .into(),
    );
    loop {
        if lash_solver::interrupt::stop_requested() {
            report.lock().unwrap_or_else(|e| e.into_inner()).busy = busy;
            return;
        }
        std::thread::sleep(RECHECK);
        let mut again: Vec<(usize, String)> = Vec::new();
        let next: Vec<(&SweepPoint, String)> = busy
            .iter()
            .filter_map(|(i, h)| {
                points
                    .iter()
                    .find(|p| p.index == *i)
                    .map(|p| (p, h.clone()))
            })
            .collect();
        let outcomes: Vec<(usize, String, Option<String>)> = pool.install(|| {
            next.par_iter()
                .map(|(p, holder)| {
                    let clock = Instant::now();
                    match run_point(p, root, runner, held) {
                        Ok(Ran::Busy(h)) => (p.index, h, None),
                        outcome => {
                            let took_over = matches!(outcome, Ok(Ran::Status(_)) | Err(_));
                            let what = tally(outcome, p, report);
                            let line = if took_over {
                                format!(
                                    "sweep: point {} ({}): its holder {holder} left it \
                                     unfinished; taken over here: {what} ({:.2} s)",
                                    p.index,
                                    p.id,
                                    clock.elapsed().as_secs_f64()
                                )
                            } else {
                                format!("sweep: point {} ({}): {what}", p.index, p.id)
                            };
                            (p.index, holder.clone(), Some(line))
                        }
                    }
                })
                .collect()
        });
        for (i, h, line) in outcomes {
            match line {
                Some(l) => progress.note(&l.into()),
                None => again.push((i, h)),
            }
        }
        busy = again;
        if busy.is_empty() {
            return;
        }
    }
}

/// How one point of a sweep went in this process.
enum Ran {
    /// It ran to the end: its status is recorded.
    Status(PointStatus),
    /// Another process finished it between the listing and the claim.
    AlreadyDone,
    /// Another live process holds its claim ("host:pid").
    Busy(String),
    /// A stop was requested before or while it ran; nothing of it is kept.
    Abandoned,
}

fn run_point<F>(
    p: &SweepPoint,
    root: &Path,
    runner: &F,
    held: &Mutex<BTreeSet<PathBuf>>,
) -> Result<Ran, Error>
where
    F: Fn(&SweepPoint, &Path) -> Result<PointResult, Error>,
{
    if lash_solver::interrupt::stop_requested() {
        return Ok(Ran::Abandoned);
    }
    let dir = root.join(&p.id);
    io::create_dir(&dir)?;
    let guard = match claim::try_claim(&dir)? {
        claim::Claimed::Mine(g) => g,
        claim::Claimed::Busy(h) => return Ok(Ran::Busy(h.holder())),
    };
    if matches!(point_state(&dir, &p.id), PointState::Finished(_)) {
        return Ok(Ran::AlreadyDone);
    }
    // Whatever an earlier holder left half-written is ours to clear now.
    claim::remove_all_temporaries(&dir);
    held.lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(guard.path().to_path_buf());
    let ran = runner(p, &dir);
    held.lock()
        .unwrap_or_else(|e| e.into_inner())
        .remove(guard.path());
    let (status, error, values) = match ran {
        Ok(r) => (PointStatus::Ok, None, r.values),
        Err(e @ Error::Solver(_)) => (
            PointStatus::SolverFailed,
            Some(e.to_string()),
            BTreeMap::new(),
        ),
        Err(Error::Interrupted(_)) => {
            abandon(&dir, guard);
            return Ok(Ran::Abandoned);
        }
        Err(e) => return Err(e),
    };
    let record = PointRecord {
        id: p.id.clone(),
        index: p.index,
        params: p.params.clone(),
        status,
        error,
        values,
    };
    io::write_json_atomic(&dir.join(RESULT_FILE), &record)?;
    drop(guard);
    Ok(Ran::Status(status))
}

/// Removes what an abandoned point wrote (every file but its claim, which `guard` releases),
/// then its directory if nothing else is in it.
fn abandon(dir: &Path, guard: claim::ClaimGuard) {
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            if e.path() != guard.path() && e.path().is_file() {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
    drop(guard);
    let _ = std::fs::remove_dir(dir);
}
