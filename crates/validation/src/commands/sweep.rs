//! `lash sweep` and `lash merge`: a grid of runs over a base case, and its merged table.
//!
//! Source: docs/outputs.md ("Sweeps").

use std::path::{Path, PathBuf};

use lash_model::Scene;

use crate::commands::default_out;
use crate::error::{Error, OptionError};
use crate::options::SolverChoice;
use crate::progress::Progress;
use crate::run::plan::RunRequest;
use crate::run::prepare::Prepared;
use crate::run::simulate::simulate;
use crate::sweep::merge::MergedTable;
use crate::sweep::runner::{PointResult, SweepOptions, SweepReport};
use crate::sweep::spec::{Shard, SweepPoint, SweepSpec};

/// What to sweep.
///
/// ```text
/// SWEEP.json [jobs] [shard] [out]
/// ```
///
/// Source: docs/outputs.md ("Sweeps").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SweepRunOptions {
    /// The sweep file (JSON): a base case and lists of parameter values.
    pub file: PathBuf,
    /// Parallel jobs (≥ 1, capped at the available parallelism with a note); None = the
    /// number of cores.
    pub jobs: Option<usize>,
    /// The points to run; None = all.
    pub shard: Option<Shard>,
    /// Output directory (one subdirectory per point); None = `out/sweep/STEM` of the file.
    pub out: Option<PathBuf>,
    /// Wall-clock budget of each point's integration, s; a point over it is a solver failure
    /// ("budget exhausted", recorded like any other). None = no budget.
    pub max_wall_time: Option<f64>,
    /// The metrics window of every point (`--window`); None: the crank's last revolution,
    /// else the whole run (docs/outputs.md, "The metrics window").
    pub window: Option<lash_model::MetricsWindow>,
}

/// What a sweep did.
///
/// Source: this module.
#[derive(Debug)]
pub struct SweepOutcome {
    /// Counts of the shard's points.
    pub report: SweepReport,
    /// The shard run.
    pub shard: Shard,
    /// Points in the whole grid.
    pub points: usize,
    /// The output directory.
    pub dir: PathBuf,
}

/// Runs a sweep of scene runs (`sweep_point`): loads and checks the sweep file and its base
/// case (every point's scene built and checked before any point runs: [`sweep_points`]'s
/// checks), then runs the shard's unfinished points in parallel ([`sweep_run`]).
pub fn sweep(o: &SweepRunOptions, progress: &dyn Progress) -> Result<SweepOutcome, Error> {
    sweep_run(o, None, None, progress)
}

/// The points of a sweep as `lash sweep` expands and checks them, each with the JSON text of
/// the scene it runs (None for a built-in test problem): the grid of the sweep file `o.file`,
/// or of `text` (that file's JSON, read as `o.file`: a relative case path is resolved against
/// its directory). Every point's scene is built and checked: a bad sweep is an error naming
/// the key (and the point) before anything runs. Nothing is written.
pub fn sweep_points(
    o: &SweepRunOptions,
    text: Option<&[u8]>,
) -> Result<Vec<(SweepPoint, Option<String>)>, Error> {
    let (spec, points) = expand(o, text)?;
    let base = checked_base(&spec, &points, None, o.window)?;
    points
        .into_iter()
        .map(|p| {
            let scene = match point_scene(&base, &p)? {
                Some(s) => Some(s),
                None => base.scene().cloned(),
            };
            let json = scene
                .map(|s| serde_json::to_string(&s))
                .transpose()
                .map_err(|e| Error::Internal(format!("scene of point {}: {e}", p.id)))?;
            Ok((p, json))
        })
        .collect()
}

/// Runs the points of a sweep (`o.file`, or `text` as in [`sweep_points`]) into `o.out`, as
/// `lash sweep` does: OUT/points.json (the whole grid), each point claimed (OUT/id/claim.json),
/// its summary.json and result.json written atomically, a solver failure recorded as
/// finished, a finished point skipped; `lash merge OUT` joins them. `only`: None = the
/// points of `o.shard`, in parallel (`o.jobs`), every point's scene checked first (the
/// command); Some(i) = the point with index i alone, only its scene checked: one point of a
/// sweep spread over processes or machines (lash.sweep's executors), whose grid
/// [`sweep_points`] checked.
pub fn sweep_run(
    o: &SweepRunOptions,
    text: Option<&[u8]>,
    only: Option<usize>,
    progress: &dyn Progress,
) -> Result<SweepOutcome, Error> {
    let (spec, points) = expand(o, text)?;
    let Some(index) = only else {
        let base = checked_base(&spec, &points, o.max_wall_time, o.window)?;
        return run_points(
            o,
            &points,
            |p, dir| sweep_point(&base, p, dir, o.window),
            progress,
        );
    };
    let Some(point) = points.get(index) else {
        return Err(Error::Usage(format!(
            "sweep: no point {index} (the grid has {})",
            points.len()
        )));
    };
    let base = checked_base(
        &spec,
        std::slice::from_ref(point),
        o.max_wall_time,
        o.window,
    )?;
    let one = SweepRunOptions {
        jobs: Some(1),
        shard: Some(Shard {
            index,
            count: points.len(),
        }),
        ..o.clone()
    };
    run_points(
        &one,
        &points,
        |p, dir| sweep_point(&base, p, dir, o.window),
        progress,
    )
}

/// The sweep (from its file, or `text` read as it) and its grid: the one expansion of
/// `lash sweep`, [`sweep_points`] and [`sweep_run`].
fn expand(o: &SweepRunOptions, text: Option<&[u8]>) -> Result<(SweepSpec, Vec<SweepPoint>), Error> {
    let spec = match text {
        Some(t) => SweepSpec::from_json(&o.file, t)?,
        None => SweepSpec::load(&o.file)?,
    };
    let points = spec.points()?;
    Ok((spec, points))
}

/// The sweep's base case, loaded, with `points`' scenes built and checked: a path that does
/// not exist or a value the scene rejects is an input error naming the path and the point.
fn checked_base(
    spec: &SweepSpec,
    points: &[SweepPoint],
    max_wall_time: Option<f64>,
    window: Option<lash_model::MetricsWindow>,
) -> Result<Prepared, Error> {
    let mut base = Prepared::load(spec.case.clone())?;
    base.max_wall_time = max_wall_time;
    // Every point's scene is built and checked before any point runs: a path that does not
    // exist or a value the scene rejects is an input error naming the path and the point.
    // A sampled path is named as the sweep file names it, not as a `set` key.
    let sampled: Vec<&String> = spec
        .file
        .sample
        .iter()
        .flat_map(|s| s.vary.keys())
        .collect();
    for p in points {
        point_scene(&base, p).map_err(|e| match e {
            Error::Input(m) => Error::Input(sampled.iter().fold(m, |m, k| {
                m.replace(&format!("set['{k}']"), &format!("sample.vary['{k}']"))
            })),
            e => e,
        })?;
    }
    // A window a point's run cannot have is an option error before anything runs.
    if window.is_some() {
        for p in points {
            let checked = match point_scene(&base, p)? {
                Some(s) => Prepared::with_scene(base.case.clone(), s)?,
                None => base.clone(),
            };
            if checked.info.is_some() {
                let (t0, t_end) = checked.t_span(None)?;
                checked.window_plan(window, t0, t_end)?;
            }
        }
    }
    Ok(base)
}

/// Runs a sweep with a point runner: loads and checks the sweep file, runs the shard's
/// unfinished points in parallel (progress: each point as it ends). A point that failed
/// otherwise than in the solver makes the whole sweep an error, after the others ran
/// (`SweepReport::into_result`).
pub fn sweep_with<F>(
    o: &SweepRunOptions,
    runner: F,
    progress: &dyn Progress,
) -> Result<SweepOutcome, Error>
where
    F: Fn(&SweepPoint, &Path) -> Result<PointResult, Error> + Sync,
{
    let (_, points) = expand(o, None)?;
    run_points(o, &points, runner, progress)
}

/// Runs a sweep's `points` with a point runner: the shard's unfinished points in parallel,
/// into `o.out` (or the default directory of the sweep file).
fn run_points<F>(
    o: &SweepRunOptions,
    points: &[SweepPoint],
    runner: F,
    progress: &dyn Progress,
) -> Result<SweepOutcome, Error>
where
    F: Fn(&SweepPoint, &Path) -> Result<PointResult, Error> + Sync,
{
    let out = o.out.clone().unwrap_or_else(|| {
        let stem = o
            .file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "sweep".into());
        default_out("sweep", &stem)
    });
    let opts = SweepOptions {
        jobs: o.jobs,
        shard: o.shard.unwrap_or(Shard::ALL),
    };
    let report =
        crate::sweep::runner::run_sweep(points, &out, &opts, runner, progress)?.into_result()?;
    Ok(SweepOutcome {
        report,
        shard: opts.shard,
        points: points.len(),
        dir: out,
    })
}

/// The scene of a point: the base scene with the point's shorthands
/// ([`crate::sweep::spec::apply_params`]) and its `set` paths ([`crate::sweep::set::apply_set`])
/// laid over it, checked as a scene file is; None when the point changes no scene field.
fn point_scene(base: &Prepared, point: &SweepPoint) -> Result<Option<Scene>, Error> {
    let pp = &point.params;
    let physical = pp.speed_rpm.is_some()
        || pp.clearance.is_some()
        || pp.viscosity.is_some()
        || pp.stiffness.is_some();
    if !physical && pp.set.is_empty() {
        return Ok(None);
    }
    let which = format!("point {} ({})", point.index, point.id);
    let Some(scene) = base.scene() else {
        return Err(Error::Input(format!(
            "sweep: speed_rpm, clearance, viscosity, stiffness and set need a scene case, not {}",
            base.case.name
        )));
    };
    let mut s = scene.clone();
    crate::sweep::spec::apply_params(&mut s, pp)
        .map_err(|e| Error::Input(format!("{e} ({which})")))?;
    let s = crate::sweep::set::apply_set(&s, &pp.set, &which)?;
    s.validate().map_err(|e| {
        Error::Input(format!(
            "sweep: {which}: the scene rejects its parameters: {e}"
        ))
    })?;
    Ok(Some(s))
}

/// The point runner of a sweep: the base case with the point's physical parameters laid over
/// its scene ([`crate::sweep::spec::apply_params`]) and its solver choice over the case's defaults;
/// writes DIR/summary.json and returns the summary, flattened, for the merged table. A
/// solver failure is returned as such (the sweep records it as a finished point).
pub(crate) fn sweep_point(
    base: &Prepared,
    point: &SweepPoint,
    dir: &Path,
    window: Option<lash_model::MetricsWindow>,
) -> Result<PointResult, Error> {
    let pp = &point.params;
    let prepared = match point_scene(base, point)? {
        Some(s) => {
            let mut p = Prepared::with_scene(base.case.clone(), s)?;
            p.max_wall_time = base.max_wall_time;
            p
        }
        None => base.clone(),
    };
    let choice = SolverChoice {
        method: pp.method,
        rtol: pp.rtol,
        step: pp.step,
        controller: pp.controller,
        ..Default::default()
    };
    let mut req = RunRequest::new(prepared.options(&choice)?);
    req.trajectory_points = Some(0);
    req.window = window;
    let r = simulate(&prepared, &req)?;
    r.summary.write(dir)?;
    let v = serde_json::to_value(&r.summary)
        .map_err(|e| Error::Internal(format!("summary of point {}: {e}", point.id)))?;
    Ok(point_values(v))
}

/// A point's summary as merged-table values: `case` and `scene_sha256` dropped (the point's
/// parameters hold them), the solver settings actually used renamed `used.method`,
/// `used.controller`, `used.rtol`, `used.step` (the parameters say what was asked for), `atol`
/// left in the point's summary.json only.
pub(crate) fn point_values(mut summary: serde_json::Value) -> PointResult {
    if let Some(o) = summary.as_object_mut() {
        for k in ["case", "scene_sha256", "atol"] {
            o.remove(k);
        }
        for k in ["method", "controller", "rtol", "step"] {
            if let Some(v) = o.remove(k) {
                o.insert(format!("used.{k}"), v);
            }
        }
    }
    PointResult::flatten(&summary)
}

/// What to merge.
///
/// ```text
/// DIR... [out]
/// ```
///
/// Source: docs/outputs.md ("Sweeps").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MergeOptions {
    /// Sweep output directories (or point directories) to join; at least one.
    pub dirs: Vec<PathBuf>,
    /// Where merged.csv and merged.md go; None = the first directory.
    pub out: Option<PathBuf>,
    /// Merge what finished even if some points of the grid are unfinished or corrupt (they
    /// get rows with status `unfinished` / `corrupt`); else that is an error.
    pub allow_partial: bool,
    /// The columns merged.md shows, in order; empty = the parameters, `status`, `error` and a
    /// short default set of metrics. merged.csv has every column either way.
    pub columns: Vec<String>,
}

/// What [`merge`] wrote.
///
/// Source: this module.
#[derive(Debug)]
pub struct Merged {
    /// The table.
    pub table: MergedTable,
    /// merged.csv.
    pub csv: PathBuf,
    /// merged.md.
    pub md: PathBuf,
}

/// Joins the finished points of sweep directories into one table: merged.csv and merged.md.
/// Points of the grids that are unfinished or whose result is corrupt make it an input error
/// that names them (nothing written), unless `allow_partial`: then they are rows of their own
/// (status `unfinished`, `corrupt`).
pub fn merge(o: &MergeOptions) -> Result<Merged, Error> {
    let Some(first) = o.dirs.first() else {
        return Err(Error::Usage("merge: no directory to merge".into()));
    };
    let out = o.out.clone().unwrap_or_else(|| first.clone());
    let table = crate::sweep::merge::merge(&o.dirs)?;
    let complete = table.unfinished.is_empty() && table.corrupt.is_empty();
    if !complete && !o.allow_partial {
        return Err(OptionError::new("allow_partial")
            .text(format!(
                "merge: the sweep is incomplete ({} finished): {}; rerun the sweep to finish \
                 them, or give ",
                table.rows.len(),
                table.missing_summary(5)
            ))
            .name("allow_partial")
            .text(" to merge what finished")
            .into());
    }
    let table = table.with_missing();
    let (csv, md) = table.write(&out, &o.columns)?;
    Ok(Merged { table, csv, md })
}
