//! Seeing a run: `lash animate RUN_DIR` (the mechanism moving, one HTML page), `lash plot
//! RUN_DIR COLUMN…` (any trajectory columns as a figure), and what `lash run --animate` adds.
//!
//! ```text
//! lash animate RUN_DIR [--trace BODY[.POINT]] [--column NAME] [--max-frames N] [--out FILE]
//! lash plot RUN_DIR COLUMN... [--x COLUMN] [--out FILE]
//! lash run SCENE --animate        the run, then animate its directory
//! ```
//!
//! Source: docs/outputs.md ("`lash animate RUN_DIR`", "`lash plot RUN_DIR COLUMN…`").

use std::path::{Path, PathBuf};

use clap::Args;
use lash_validation::{self as engine, AnimateOptions, Animated, Error, PlotOptions, Written};

use crate::out::outln;

/// Arguments of `lash animate`.
///
/// ```text
/// lash animate RUN_DIR [--trace BODY[.POINT]] [--column NAME] [--max-frames N] [--out FILE]
/// ```
///
/// Source: docs/outputs.md ("`lash animate RUN_DIR`").
#[derive(Debug, Clone, PartialEq, Args)]
pub struct AnimateArgs {
    /// A run directory of `lash run` (it holds scene.json and trajectory.csv).
    pub run_dir: PathBuf,
    /// The point whose path is drawn: BODY.POINT, or BODY for its centre of mass. Default:
    /// the centre of mass of the body carrying the clearance joint's journal.
    #[arg(long, value_name = "BODY[.POINT]")]
    pub trace: Option<String>,
    /// The trajectory column the time-series panel shows first (any can be chosen on the
    /// page). Default: contact_force, else slider_a, else the first body's angle.
    #[arg(long, value_name = "NAME")]
    pub column: Option<String>,
    /// Most frames of the page, a whole number >= 2 (rows are decimated to at most this).
    /// Default 2500.
    #[arg(long = "max-frames", value_name = "N", value_parser = parse_max_frames)]
    pub max_frames: Option<usize>,
    /// The page's file. Default RUN_DIR/animation.html.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

fn parse_max_frames(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if n >= 2 => Ok(n),
        _ => Err(format!("max-frames must be a whole number >= 2, got {s}")),
    }
}

impl AnimateArgs {
    /// The engine's options.
    pub fn options(&self) -> AnimateOptions {
        AnimateOptions {
            run_dir: self.run_dir.clone(),
            trace: self.trace.clone(),
            column: self.column.clone(),
            max_frames: self.max_frames,
            out: self.out.clone(),
        }
    }
}

/// Arguments of `lash plot`.
///
/// ```text
/// lash plot RUN_DIR COLUMN... [--x COLUMN] [--out FILE]
/// ```
///
/// Source: docs/outputs.md ("`lash plot RUN_DIR COLUMN…`").
#[derive(Debug, Clone, PartialEq, Args)]
pub struct PlotArgs {
    /// A run directory of `lash run` (it holds trajectory.csv).
    pub run_dir: PathBuf,
    /// Columns of trajectory.csv to draw (e.g. rocker.theta crank_driver.torque); columns of
    /// different units go to panels of their own.
    #[arg(required = true, value_name = "COLUMN")]
    pub columns: Vec<String>,
    /// The abscissa: a column of trajectory.csv. Default t.
    #[arg(long, value_name = "COLUMN")]
    pub x: Option<String>,
    /// The figure: FILE.svg and FILE.png (FILE may end in .svg or .png). Default
    /// RUN_DIR/plot_COLUMNS (joined by +).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

impl PlotArgs {
    /// The engine's options.
    pub fn options(&self) -> PlotOptions {
        PlotOptions {
            run_dir: self.run_dir.clone(),
            columns: self.columns.clone(),
            x: self.x.clone(),
            out: self.out.clone(),
        }
    }
}

/// One line about a written page.
fn describe_animation(w: &Written<Animated>) -> String {
    let a = &w.result;
    let every = if a.stride > 1 {
        format!(", one per {} of {} rows", a.stride, a.rows)
    } else {
        String::new()
    };
    format!(
        "wrote {} ({:.2} MB, {} frames{every})",
        w.files[0].display(),
        a.bytes as f64 / 1e6,
        a.frames
    )
}

/// `lash animate`: writes the page, says where and how big.
pub fn animate_command(a: &AnimateArgs) -> Result<Written<Animated>, Error> {
    let w = engine::animate(&a.options())?;
    outln(&describe_animation(&w));
    Ok(w)
}

/// What `lash run --animate` adds after the run: the page of `dir`, with the defaults.
pub fn animate_run(dir: &Path) -> Result<Written<Animated>, Error> {
    let w = engine::animate(&AnimateOptions {
        run_dir: dir.to_path_buf(),
        ..Default::default()
    })?;
    outln(&describe_animation(&w));
    Ok(w)
}

/// `lash plot`: writes the figure, says where.
pub fn plot_command(a: &PlotArgs) -> Result<Written<()>, Error> {
    let w = engine::plot(&a.options())?;
    outln(&format!(
        "wrote {} and {}",
        w.files[0].display(),
        w.files[1].display()
    ));
    Ok(w)
}
