//! The engine's doors for `lash.sweep` (python/lash/_sweep.py): a sweep's points as `lash
//! sweep` expands and checks them, and its points run into a directory as `lash sweep` runs
//! them (all of them in parallel here, or one, for a task of an executor).
//!
//! ```text
//! sweep_points_core({file, text})                → [(index, id, params JSON, scene JSON | None)]
//! sweep_run_core({file, text, out, only, jobs,    → None; OUT/points.json, OUT/id/result.json
//!                 max_wall_time})                    (lash_validation::sweep_run, the command's)
//! ```
//!
//! `text`: the sweep's JSON (a dict serialised by Python), read as if from `file` (a relative
//! case path is resolved against its directory); None: the file itself. Errors as
//! `lash.run`'s (scene.rs): a bad sweep raises `lash.SceneError(".", message naming the key)`
//! or `lash.UsageError` before anything runs; Ctrl-C stops the run ([`run_watched`]).

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::PyList;

use lash_validation::{Error, NoProgress, SweepRunOptions};

use crate::errors::guard;
use crate::scene::{engine_error, run_watched};

/// The keyword arguments of the sweep doors, as one dict (python/lash/_sweep.py).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct SweepArgs {
    /// The sweep file, or the path the `text` is read as.
    pub file: String,
    /// The sweep's JSON text, or None: read `file`.
    pub text: Option<Vec<u8>>,
    /// The output directory (`sweep_run_core`).
    #[pyo3(default)]
    pub out: Option<String>,
    /// The one point to run (index), or None: all.
    #[pyo3(default)]
    pub only: Option<usize>,
    /// Parallel points (None: one per core).
    #[pyo3(default)]
    pub jobs: Option<usize>,
    /// Wall-clock budget of each point's integration, s.
    #[pyo3(default)]
    pub max_wall_time: Option<f64>,
}

impl SweepArgs {
    fn options(&self) -> SweepRunOptions {
        SweepRunOptions {
            file: PathBuf::from(&self.file),
            jobs: self.jobs,
            shard: None,
            out: self.out.as_ref().map(PathBuf::from),
            max_wall_time: self.max_wall_time,
            // lash.sweep has no --window: every point's default window, as `lash sweep`.
            window: None,
        }
    }
}

/// The points of a sweep as `lash sweep` expands them (`lash_validation::sweep_points`),
/// every point's scene built and checked: a list of `(index, id, params, scene)`, `params`
/// the JSON text of the point's parameters (result.json's `params`), `scene` the JSON text of
/// the scene it runs (None for a built-in test problem).
#[pyfunction]
pub fn sweep_points_core<'py>(py: Python<'py>, args: SweepArgs) -> PyResult<Bound<'py, PyList>> {
    guard(py, "lash.sweep", || {
        let o = args.options();
        let text = args.text;
        let points = run_watched(py, "lash.sweep", move || {
            (lash_validation::sweep_points(&o, text.as_deref()), ())
        })?
        .map_err(|e| engine_error(py, e))?;
        let out = PyList::empty(py);
        for (p, scene) in points {
            let params = serde_json::to_string(&p.params)
                .map_err(|e| engine_error(py, Error::Internal(format!("params: {e}"))))?;
            out.append((p.index, p.id, params, scene))?;
        }
        Ok(out)
    })
}

/// Runs the sweep's points into `out` as `lash sweep` does (`lash_validation::sweep_run`):
/// all of them in parallel (`only` None, `jobs` threads) or the point with index `only`. The
/// GIL is released; the calling thread looks for Ctrl-C. Returns the number of points in the
/// grid.
#[pyfunction]
pub fn sweep_run_core(py: Python<'_>, args: SweepArgs) -> PyResult<usize> {
    guard(py, "lash.sweep", || {
        let o = args.options();
        let (text, only) = (args.text, args.only);
        let outcome = run_watched(py, "lash.sweep", move || {
            (
                lash_validation::sweep_run(&o, text.as_deref(), only, &NoProgress),
                (),
            )
        })?
        .map_err(|e| engine_error(py, e))?;
        Ok(outcome.points)
    })
}
