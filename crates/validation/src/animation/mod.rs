//! The animation of a run: one self-contained HTML page (`animation.html`) that draws the
//! mechanism moving, from the scene the run ran (`scene.json`) and its trajectory.
//!
//! ```text
//! scene.json + trajectory.csv ──Table, geometry::page_data──▶ PageData (frames, poses,
//!     clearance joints, forces, columns) ──html──▶ page.html with the data inline
//! the page: every body (the hull of its points, a bar between two, a block, a disc), the
//!     ground, pins, drivers, guides, springs; each clearance joint with the journal's
//!     eccentricity magnified by a shown factor and its contact and film forces as arrows
//!     (beside: one zoomed view per clearance joint with its orbit); the path of a chosen
//!     point; play and pause, a time scrubber, a speed control; a time-series panel of a
//!     chosen column with a cursor at the shown time
//! no network: script, style and data inline; nothing fetched
//! ```
//!
//! [`animate_dir`] is `lash animate RUN_DIR` (and `lash run --animate`): it reads
//! `RUN_DIR/scene.json` (checked against `summary.json`'s `scene_sha256`) and
//! `RUN_DIR/trajectory.csv`, and writes `RUN_DIR/animation.html` atomically. [`Animation`]
//! is the page in memory (the Python binding's `Run.animate()`).
//!
//! Source: docs/outputs.md ("`animation.html`"); README.md ("Seeing the mechanism").

pub(crate) mod geometry;
pub(crate) mod table;

use std::path::{Path, PathBuf};

use lash_model::Scene;

use crate::error::Error;
use crate::report::summary::SUMMARY_FILE;
use crate::report::trajectory::{PARTIAL_TRAJECTORY_FILE, TRAJECTORY_FILE};
use crate::store::io;

pub(crate) use geometry::{AnimationOptions, PageData};
pub(crate) use table::{unit, Table};

/// File name of the animation in a run directory.
pub(crate) const ANIMATION_FILE: &str = "animation.html";

/// File name of the scene a run ran, kept in its directory.
pub(crate) const SCENE_FILE: &str = "scene.json";

/// The page template (HTML, CSS and script; the data goes where `{{DATA}}` is).
const PAGE: &str = include_str!("page.html");

/// An animation page: its data and its HTML.
///
/// ```text
/// html = page.html with {{TITLE}} (escaped), {{VERSION}} and {{DATA}} (PageData as JSON)
/// ```
///
/// Source: module doc.
#[derive(Clone, Debug)]
pub(crate) struct Animation {
    /// What the page receives.
    pub(crate) data: PageData,
    /// The page.
    pub html: String,
}

/// `&`, `<`, `>`, `"` escaped for HTML text and attributes.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

impl Animation {
    /// The animation of `scene`'s run whose trajectory is `table`, headed `title`.
    pub(crate) fn build(
        scene: &Scene,
        table: &Table,
        title: &str,
        o: &AnimationOptions,
    ) -> Result<Animation, Error> {
        let data = geometry::page_data(scene, table, title, o)?;
        let json = data.to_json()?;
        let html = PAGE
            .replacen("{{TITLE}}", &escape(title), 1)
            .replacen("{{VERSION}}", env!("CARGO_PKG_VERSION"), 1)
            .replacen("{{DATA}}", &json, 1);
        Ok(Animation { data, html })
    }

    /// The animation from a scene's JSON text (`scene.json`); errors of the scene name it
    /// as `scene.json`.
    pub(crate) fn from_scene_text(
        scene_json: &str,
        table: &Table,
        title: &str,
        o: &AnimationOptions,
    ) -> Result<Animation, Error> {
        let scene = Scene::from_json_str(scene_json).map_err(|error| Error::Scene {
            case: SCENE_FILE.into(),
            error,
        })?;
        Animation::build(&scene, table, title, o)
    }
}

/// The title of a run's page: case, method and setting from its summary.json.
fn title_of(summary: &serde_json::Value, dir: &Path) -> String {
    let s = |k: &str| summary.get(k).and_then(|v| v.as_str()).map(str::to_string);
    let case = s("case").unwrap_or_else(|| {
        dir.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "run".into())
    });
    let setting = match (
        s("method"),
        summary.get("rtol").and_then(|v| v.as_f64()),
        summary.get("step").and_then(|v| v.as_f64()),
    ) {
        (Some(m), Some(r), _) => format!(", {m} rtol {r:e}"),
        (Some(m), None, Some(h)) => format!(", {m} step {h:e} s"),
        (Some(m), _, _) => format!(", {m}"),
        _ => String::new(),
    };
    format!("{case}{setting}")
}

/// `lash animate RUN_DIR`: reads the run directory's scene and trajectory, writes the page
/// (to `out`, else RUN_DIR/animation.html; module doc) and returns its path and itself. Errors ([`Error::Input`] unless said): no such directory; no trajectory.csv
/// (a failed run, or not a run directory); no scene.json (a run of a built-in test problem);
/// a scene.json whose SHA-256 is not the summary's `scene_sha256`; a scene the model rejects
/// ([`Error::Scene`]); a trajectory that does not fit the scene; an unknown trace point or
/// column ([`Error::Usage`]).
pub(crate) fn animate_dir(
    dir: &Path,
    out: Option<&Path>,
    o: &AnimationOptions,
) -> Result<(PathBuf, Animation), Error> {
    if !dir.is_dir() {
        return Err(Error::Input(format!(
            "run directory {} not found",
            dir.display()
        )));
    }
    let traj = dir.join(TRAJECTORY_FILE);
    if !traj.is_file() {
        let why = if dir.join(PARTIAL_TRAJECTORY_FILE).is_file() {
            "the run failed (failure.json): it has no trajectory to animate"
        } else {
            "not a run directory"
        };
        return Err(Error::Input(format!(
            "{} has no {TRAJECTORY_FILE}: {why}",
            dir.display()
        )));
    }
    let scene_path = dir.join(SCENE_FILE);
    if !scene_path.is_file() {
        return Err(Error::Input(format!(
            "{} has no {SCENE_FILE}: a run of a built-in test problem has no mechanism, and \
             runs of lash before 0.2 did not keep their scene; run the scene again into it",
            dir.display()
        )));
    }
    let scene_bytes = std::fs::read(&scene_path).map_err(|e| Error::io(&scene_path, e))?;
    let summary: serde_json::Value = match std::fs::read(dir.join(SUMMARY_FILE)) {
        Ok(b) => serde_json::from_slice(&b).unwrap_or(serde_json::Value::Null),
        Err(_) => serde_json::Value::Null,
    };
    if let Some(want) = summary.get("scene_sha256").and_then(|v| v.as_str()) {
        let have = crate::run::case::sha256_hex(&scene_bytes);
        if have != want {
            return Err(Error::Input(format!(
                "{} is not the scene of this run: its SHA-256 {have} differs from \
                 summary.json's scene_sha256 {want}",
                scene_path.display()
            )));
        }
    }
    let scene_text = std::str::from_utf8(&scene_bytes)
        .map_err(|e| Error::Input(format!("{}: {e}", scene_path.display())))?;
    let csv = std::fs::read_to_string(&traj).map_err(|e| Error::io(&traj, e))?;
    let table = Table::from_csv(&csv, &traj.display().to_string())?;
    let title = title_of(&summary, dir);
    let a = Animation::from_scene_text(scene_text, &table, &title, o)?;
    let out = out.map_or_else(|| dir.join(ANIMATION_FILE), Path::to_path_buf);
    io::write_atomic(&out, a.html.as_bytes())?;
    Ok((out, a))
}

#[cfg(test)]
mod tests;
