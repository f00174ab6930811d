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
//! The public API is what the commands take and give: each command function with its option
//! struct and result type (re-exported here; the paper's study's and the extremes matrix's
//! result types under [`study`] and [`extremes`](mod@extremes)), [`Error`] with its [`ErrorKind`], and the
//! [`Progress`] hook; and [`PressCase`], the identity of a case of the paper's press. Everything
//! else lives in rooms private to the crate: `commands` (one function per command), `run`
//! (case references, press cases, preparing, planning and driving a run, sampling,
//! quadrature, runs until periodic, the files of one run), `report` (summary.json,
//! trajectory.csv, metrics, figures), `store` (atomic writes, the cache of finished runs, claim
//! files), `compare` (errors against a reference, work–precision), `studies` (the default
//! run, the paper's §4 and its claims, their robustness, the extremes matrix), `diagnostics`
//! (stiffness, Poincaré section and Lyapunov exponent), `sweep` (grids, shards, resume,
//! merge), `animation` (a run as one self-contained HTML page: the mechanism moving). No
//! source file imports one that imports it back.

#![warn(missing_docs)]
#![warn(unreachable_pub)]

mod animation;
mod commands;
mod compare;
mod diagnostics;
mod error;
mod options;
mod progress;
mod report;
mod run;
mod store;
mod studies;
mod sweep;

pub use commands::{
    compare::{compare, work_precision, CompareOptions, WorkPrecisionOptions, WorkPrecisionResult},
    diagnose::{poincare, stiffness, PoincareOptions, StiffnessOptions},
    run::{default_run, describe_run, run, run_in_memory, RunOptions},
    study::{extremes, study_paper, study_robustness, ExtremesOptions, StudyOptions},
    sweep::{
        merge, sweep, sweep_points, sweep_run, sweep_with, MergeOptions, Merged, SweepOutcome,
        SweepRunOptions,
    },
    viz::{animate, animate_in_memory, plot, AnimateOptions, Animated, PlotOptions},
};
pub use error::{Error, ErrorKind, Message, OptionError};
pub use options::SolverChoice;
pub use progress::{NoProgress, Progress};
pub use store::io::Written;

// The result types of the commands and what their fields hold.
pub use compare::{
    reference::{Compared, Comparison, ErrorNorms, ErrorWindow},
    workprecision::{WorkPrecisionPlan, WpTable},
};
pub use diagnostics::{poincare::PoincareResult, stiffness::report::StiffnessResult};
pub use report::{
    metrics::{Energy, EventQuantity, EventRecord, JointMetrics, Metrics},
    summary::{Settled, Summary},
    trajectory::{Columns, Header},
};
pub use run::{
    case::Case,
    press::{NotAPressCase, PressCase},
    result::RunResult,
    steady::{UntilPeriodic, DEFAULT_MAX_REVOLUTIONS, MIN_REVOLUTIONS},
};
pub use studies::{
    headline::{CaseReport, Headline},
    robustness::RobustnessResult,
};
pub use sweep::{
    merge::MergedTable,
    runner::{PointResult, SweepReport},
    spec::{Shard, SweepPoint},
};

/// The paper's study (`study_paper`): its plan, its result as study.json holds it, and the
/// claims judged on it.
pub mod study {
    pub use crate::run::press::Kind;
    pub use crate::studies::paper::{
        claims::{Claim, Number, Origin, Verdict},
        plan::{Plan, Setting, Settings},
        result::{CaseResult, FigureRecord, SolverRecord, SteadyRuns, StudyResult, Timing},
        stats::{CaseStats, Deviations, Ensemble},
    };
}

/// The extremes matrix (`extremes`): its result, and the pieces its tools in `examples/` use
/// (the scene catalogue, a scene's reference, one cell's run and its outcome).
pub mod extremes {
    pub use crate::studies::extremes::{
        catalogue::{catalogue, ExtremeScene},
        outcome::{Cell, FailureKind, Matrix, Outcome, SceneReport},
        plan::{Budget, Setting},
        runner::{prepare, run_cell, Ready},
    };
}
