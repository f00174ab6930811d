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
//! Modules: [`commands`] (one function per command: options in, results out), [`cache`]
//! (finished runs by the hash of their inputs: resuming), [`claim`] (claim files of sweep
//! points, liveness of processes), [`options`]
//! (the solver choice of a request), [`progress`] (the progress hook), [`error`] (typed
//! errors and their kinds), [`compare`] (errors against a reference), [`io`] (atomic writes),
//! [`headline`] (the default run), [`case`] (case references), [`summary`] (summary.json),
//! [`trajectory`] (trajectory.csv), [`metrics`] (last-revolution metrics), [`plot`] (SVG + PNG
//! figures), [`report`] (the files of one run), [`simulate`] (running a case: the core of
//! every command), [`steady`] (running until the orbit is periodic), [`sweep`] (grids, shards, resume, merge), [`workprecision`] (error against
//! cost, cheapest runs), [`stiffness_cmd`] (stiffness diagnostics: eigenvalues, RK4 limits,
//! verdict), [`poincare`] (Poincaré section, Lyapunov exponent), [`study`] (the paper's §4
//! and its claims; `study::robustness`, the claims under the modelling choices the paper
//! leaves open), [`extremes`] (the matrix of extreme scenes × methods × tolerances),
//! [`animation`] (the run as a self-contained HTML page: the mechanism moving),
//! [`column_plot`] (any trajectory columns as a figure).

#![warn(missing_docs)]

pub mod animation;
pub mod cache;
pub mod case;
pub mod claim;
pub mod column_plot;
pub mod commands;
pub mod compare;
pub mod error;
pub mod extremes;
pub mod headline;
pub mod io;
pub mod metrics;
pub mod options;
pub mod plot;
pub mod poincare;
pub mod progress;
pub mod report;
pub mod simulate;
pub mod steady;
pub mod stiffness_cmd;
pub mod study;
pub mod summary;
pub mod sweep;
pub mod trajectory;
pub mod workprecision;

pub use error::{Error, ErrorKind};
pub use options::SolverChoice;
pub use progress::{NoProgress, Progress};
