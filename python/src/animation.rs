//! `animation_html`: a run's page as `lash animate` writes it (crates/validation,
//! `animation`), from the scene's JSON text and the run's columns held by Python; the engine
//! of `lash.Run.animate()` (python/lash/_run.py).
//!
//! ```text
//! Run.animate() ── scene text, column names, column-major f64 bytes ──▶ animation_html
//!     ──▶ lash_validation::animate_in_memory ──▶ the page's HTML (str)
//! ```
//!
//! Errors as `lash.run`'s: a scene the model rejects → `lash.SceneError`; a trajectory that
//! does not fit the scene, an unknown trace point or column → `lash.SceneError` /
//! `lash.UsageError`.

use pyo3::prelude::*;

use lash_validation::AnimateOptions;

use crate::convert::f64s_from_bytes;
use crate::scene::engine_error;

/// The animation page (one self-contained HTML text) of a run whose scene is `scene_json` and
/// whose trajectory has the columns `names` with `rows` values each in `columns`
/// (native-endian f64, column after column, NaN where a column is absent), headed `title`.
/// `trace`, `column`, `max_frames` as `lash animate`'s options.
#[pyfunction]
#[pyo3(signature = (scene_json, names, columns, rows, title, trace=None, column=None,
    max_frames=None))]
#[allow(clippy::too_many_arguments)]
pub fn animation_html(
    py: Python<'_>,
    scene_json: &str,
    names: Vec<String>,
    columns: &[u8],
    rows: usize,
    title: &str,
    trace: Option<String>,
    column: Option<String>,
    max_frames: Option<usize>,
) -> PyResult<String> {
    let values = f64s_from_bytes(columns);
    let data: Vec<Vec<f64>> = (0..names.len())
        .map(|k| values.get(k * rows..(k + 1) * rows).unwrap_or(&[]).to_vec())
        .collect();
    let o = AnimateOptions {
        trace,
        column,
        max_frames,
        ..Default::default()
    };
    lash_validation::animate_in_memory(scene_json, names, data, title, &o)
        .map_err(|e| engine_error(py, e))
}
