//! `lash animate RUN_DIR` and `lash plot RUN_DIR COLUMN…`: seeing a finished run from the
//! files of its directory (nothing is integrated), and the animation of a run held in memory
//! (the Python binding's `Run.animate()`).
//!
//! ```text
//! animate(AnimateOptions)                → Written<Animated>  RUN_DIR/animation.html
//! animate_in_memory(scene, columns, title, AnimateOptions) → the same page as a String
//! plot(PlotOptions)                      → Written<()>        FILE.svg, FILE.png
//! ```
//!
//! Source: docs/outputs.md ("`lash animate RUN_DIR`", "`lash plot RUN_DIR COLUMN…`").

use std::path::PathBuf;

use crate::animation::{self, Animation, AnimationOptions, Table};
use crate::error::Error;
use crate::report::column_plot::{self, PlotRequest};
use crate::store::io::Written;

/// What `lash animate` does.
///
/// ```text
/// run_dir     a run's directory: scene.json, trajectory.csv (summary.json for the title)
/// trace       BODY.POINT | BODY (its centre of mass); None = the centre of mass of the body
///             carrying the clearance joint's journal
/// column      the trajectory column the time-series panel shows first; None =
///             contact_force, else slider_a, else the first body's angle
/// max_frames  most frames (≥ 2; rows are decimated to at most this); None = 2500
/// out         the page; None = RUN_DIR/animation.html
/// ```
///
/// Source: docs/outputs.md ("`lash animate RUN_DIR`").
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AnimateOptions {
    /// The run directory (not used by [`animate_in_memory`]).
    pub run_dir: PathBuf,
    /// The point whose path is drawn.
    pub trace: Option<String>,
    /// The column the time-series panel shows first.
    pub column: Option<String>,
    /// Most frames; None = 2500.
    pub max_frames: Option<usize>,
    /// Output file; None = `RUN_DIR/animation.html` (not used by [`animate_in_memory`]).
    pub out: Option<PathBuf>,
}

impl AnimateOptions {
    fn animation(&self) -> AnimationOptions {
        AnimationOptions {
            trace: self.trace.clone(),
            column: self.column.clone(),
            max_frames: self.max_frames,
        }
    }
}

/// What [`animate`] wrote.
///
/// ```text
/// frames of rows (stride), bytes of the page
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Animated {
    /// Frames of the page.
    pub frames: usize,
    /// Rows of the trajectory.
    pub rows: usize,
    /// Rows per frame.
    pub stride: usize,
    /// Size of the page, bytes.
    pub bytes: usize,
}

/// `lash animate RUN_DIR` (and `lash run --animate` after the run): the run as one
/// self-contained HTML page, from the directory's scene.json and trajectory.csv, written
/// atomically. Errors ([`Error::Input`] unless said): no such directory; no trajectory.csv (a
/// failed run, or not a run directory); no scene.json (a run of a built-in test problem); a
/// scene.json whose SHA-256 is not the summary's `scene_sha256`; a scene the model rejects
/// ([`Error::Scene`]); a trajectory that does not fit the scene; an unknown trace point or
/// column ([`Error::Usage`]).
pub fn animate(o: &AnimateOptions) -> Result<Written<Animated>, Error> {
    let (out, a) = animation::animate_dir(&o.run_dir, o.out.as_deref(), &o.animation())?;
    Ok(Written {
        result: Animated {
            frames: a.data.t.len(),
            rows: a.data.rows,
            stride: a.data.stride,
            bytes: a.html.len(),
        },
        dir: o.run_dir.clone(),
        files: vec![out],
    })
}

/// [`animate`] without files, for a library caller (the Python binding's `Run.animate()`):
/// the page of a run whose scene is `scene_json` and whose trajectory has the columns `names`
/// with the values `columns` (one vector per name, all as long; NaN where a column is
/// absent), headed `title`.
///
/// ```text
/// o.run_dir and o.out are not used
/// errors: a scene the model rejects → Error::Scene (named scene.json); columns of unequal
///         length, a trajectory that does not fit the scene → Error::Input; an unknown trace
///         point or column → Error::Usage
/// ```
pub fn animate_in_memory(
    scene_json: &str,
    names: Vec<String>,
    columns: Vec<Vec<f64>>,
    title: &str,
    o: &AnimateOptions,
) -> Result<String, Error> {
    let table = Table::from_columns(names, columns)?;
    Animation::from_scene_text(scene_json, &table, title, &o.animation()).map(|a| a.html)
}

/// What `lash plot` draws.
///
/// ```text
/// run_dir  columns (≥ 1)  [x]  [out]
/// ```
///
/// Source: docs/outputs.md ("`lash plot RUN_DIR COLUMN…`").
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlotOptions {
    /// The run directory.
    pub run_dir: PathBuf,
    /// The columns drawn (y); columns of different units go to panels of their own.
    pub columns: Vec<String>,
    /// The abscissa, a trajectory column; None = `t`.
    pub x: Option<String>,
    /// The figure's path (with or without .svg / .png); None = RUN_DIR/plot_COLUMNS (joined by
    /// `+`).
    pub out: Option<PathBuf>,
}

/// `lash plot RUN_DIR COLUMN…`: trajectory columns against time or another column, as SVG and
/// PNG (the files in [`Written::files`], SVG first).
pub fn plot(o: &PlotOptions) -> Result<Written<()>, Error> {
    let w = column_plot::plot_columns(&PlotRequest {
        run_dir: o.run_dir.clone(),
        columns: o.columns.clone(),
        x: o.x.clone(),
        out: o.out.clone(),
    })?;
    Ok(Written {
        result: (),
        dir: w.dir,
        files: w.files,
    })
}
