//! # lash-validation
//!
//! The `lash` command: cases, the paper's study, comparisons, work–precision, sweeps, figures.
//!
//! ```text
//! CASE ──case──▶ scene ──model──▶ OdeSystem ──solver──▶ samples on the grid, events, stats
//!      ──metrics──▶ summary.json ──io──▶ --out (atomic)      trajectory.csv, figures (plot)
//! SWEEP.json ──sweep──▶ points × runner ──▶ one result.json per point ──merge──▶ table
//! ```
//!
//! Modules: [`cli`] (arguments), [`app`] (dispatch), [`compare`] (errors against a
//! reference), [`error`] (exit codes), [`io`] (atomic
//! writes), [`headline`] (the default run), [`case`] (case references), [`summary`] (summary.json), [`trajectory`]
//! (trajectory.csv), [`metrics`] (last-revolution metrics), [`plot`] (SVG + PNG figures),
//! [`report`] (the files of one run), [`simulate`] (running a case: the core of every
//! command), [`sweep`] (grids, shards, resume, merge), [`workprecision`] (error against cost,
//! cheapest runs), [`stiffness_cmd`] (`lash stiffness`: eigenvalues, RK4 limits, verdict),
//! [`poincare`] (`lash poincare`: Poincaré section, Lyapunov exponent), [`extremes`] (the
//! matrix of extreme scenes × methods × tolerances).

#![warn(missing_docs)]

pub mod app;
pub mod case;
pub mod cli;
pub mod compare;
pub mod error;
pub mod extremes;
pub mod headline;
pub mod io;
pub mod metrics;
pub mod plot;
pub mod poincare;
pub mod report;
pub mod simulate;
pub mod stiffness_cmd;
pub mod study;
pub mod summary;
pub mod sweep;
pub mod trajectory;
pub mod workprecision;

pub use error::Error;
