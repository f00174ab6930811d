//! # lash-validation
//!
//! The engine behind the `lash` command: cases, runs, metrics, comparisons against the
//! paper's RK4, work–precision, sweeps, studies, diagnostics, reports and figures. It takes
//! plain option structs, returns typed errors and reports progress through a hook; it parses
//! no command line and prints nothing (the `lash` binary is the crate `lash-cli`).
//!
//! ```text
//! CASE ──case──▶ scene ──model──▶ OdeSystem ──solver──▶ samples on the grid, events, stats
//!      ──metrics──▶ summary.json ──io──▶ out dir (atomic)    trajectory.csv, figures (plot)
//! SWEEP.json ──sweep──▶ points × runner ──▶ one result.json per point ──merge──▶ table
//! front end ──RunOptions, CompareOptions, …──▶ commands ──▶ Written<result> | Error
//!                                                  └──Progress (notes, sweep progress)
//! ```
//!
//! Rooms: [`commands`] (one function per command: options in, results out), [`run`] (case
//! references, the runner every command calls, runs until periodic, the files of one run),
//! [`report`] (summary.json, trajectory.csv, metrics, figures), [`store`] (atomic writes, the
//! cache of finished runs, claim files), [`compare`] (errors against a reference,
//! work–precision), [`studies`] (the default run, the paper's §4 and its claims, their
//! robustness, the extremes matrix), [`diagnostics`] (stiffness, Poincaré section and
//! Lyapunov exponent), [`sweep`] (grids, shards, resume, merge), [`animation`] (a run as one
//! self-contained HTML page: the mechanism moving); [`options`] (the solver choice of a
//! request), [`progress`] (the progress hook), [`error`] (typed errors and their kinds).

#![warn(missing_docs)]

pub mod animation;
pub mod commands;
pub mod compare;
pub mod diagnostics;
pub mod error;
pub mod options;
pub mod progress;
pub mod report;
pub mod run;
pub mod store;
pub mod studies;
pub mod sweep;

pub use error::{Error, ErrorKind};
pub use options::SolverChoice;
pub use progress::{NoProgress, Progress};
