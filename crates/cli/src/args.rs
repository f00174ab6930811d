//! The command line of `lash` (clap derive) and the checks clap cannot express.
//!
//! ```text
//! lash                                   the default run: the 150 rpm press, ideal vs dry vs
//!                                        lubricated, RK4 against the best adaptive method
//! lash run CASE [--method M] [--rtol R] [--atol A[,A..]] [--step H] [--controller C]
//!              [--max-steps N] [--max-wall-time S] [--t-end S]
//!              [--samples-per-revolution N | --output-every DT] [--no-energy-check] [--out DIR]
//! lash study paper [--out DIR]
//! lash compare CASE [--tolerances R,..] [--steps H,..] [--t-end S] [--max-wall-time S]
//!                   [--window W] [--out DIR]
//! lash work-precision CASE [--methods M,..] [--tolerances R,..] [--steps H,..]
//!                          [--controllers C,..] [--t-end S] [--max-wall-time S] [--out DIR]
//! lash sweep SWEEP.json [--jobs N] [--shard I/N] [--max-wall-time S] [--out DIR]
//! lash merge DIR... [--out DIR] [--allow-partial] [--columns A,B,C]
//! lash stiffness CASE [solver flags] [--samples N] [--t-end S] [--no-measure] [--out DIR]
//! lash poincare CASE [--revolutions N] [--perturbation D] [--renorm-per-rev R]
//!                    [solver flags] [--out DIR]
//! lash extremes [--quick] [--jobs N] [--max-steps N] [--max-wall-time S] [--out DIR]
//! lash animate RUN_DIR [--trace BODY[.POINT]] [--column NAME] [--max-frames N] [--out FILE]
//! lash plot RUN_DIR COLUMN... [--x COLUMN] [--out FILE]          (module `viz`)
//! ```
//!
//! Names and list syntax are the contract of docs/outputs.md ("Method and controller names"):
//! methods and controllers by [`Method::from_name`] and [`ControllerKind::from_name`], lists
//! comma-separated, `--step` only for fixed-step methods, `--rtol`/`--atol`/`--controller` only for
//! adaptive ones. Every parse error becomes one line and exit code 2 ([`parse`]).
//!
//! Each argument struct converts into the engine's options (`lash_validation::RunOptions`, …):
//! `SolverFlags` → [`SolverChoice`], `RunArgs` → `RunOptions`, and so on. The checks that are
//! facts of the engine (which option fits which method, the work–precision lists) are the
//! engine's; their errors name options by the engine's names, spelled here as flags
//! ([`crate::exit::flagged`]).

use std::ffi::OsString;
use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};
use lash_solver::{Atol, ControllerKind, Method, Rule, SolverOptions};
use lash_validation::{
    CompareOptions, Error, ExtremesOptions, MergeOptions, PoincareOptions, RunOptions, Shard,
    SolverChoice, StiffnessOptions, StudyOptions, SweepRunOptions, UntilPeriodic,
    WorkPrecisionOptions, WorkPrecisionPlan, DEFAULT_MAX_REVOLUTIONS, MIN_REVOLUTIONS,
};

use crate::exit::flagged;

/// The `lash` command line.
///
/// ```text
/// lash [COMMAND]      no command = the default run (module `headline`)
/// ```
///
/// Source: README.md ("The `lash` command"); names from docs/outputs.md ("Method and controller
/// names").
#[derive(Debug, Parser)]
#[command(
    name = "lash",
    version,
    long_about = None,
    about = "Planar mechanisms with revolute clearance joints: runs, studies, comparisons, work-precision, sweeps",
    after_help = "Without a command, `lash` runs the default job: the paper's press at 150 rpm with \
a 0.1 mm clearance (ideal, dry and lubricated joint), the paper's RK4 at its largest stable step \
against the best adaptive method at matched accuracy, each against a converged reference. It \
prints the table and writes it, the figures and each case's reference run to ./lash-default/ \
(or --out DIR), replacing that directory as a whole.",
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    /// What to do; without one, the default run (see below).
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Output directory of the default run (no command). Default `./lash-default/`.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

/// The subcommands.
///
/// ```text
/// run | study | compare | work-precision | sweep | merge
/// stiffness | poincare                          (diagnostics)
/// ```
///
/// Source: docs/outputs.md ("Files each command writes").
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run one case: DIR/summary.json, DIR/trajectory.csv and figures.
    Run(RunArgs),
    /// Run a study (a set of cases with its report).
    Study(StudyArgs),
    /// Compare the methods on one case.
    Compare(CompareArgs),
    /// Error against cost for every method and tolerance (and RK4 against step).
    WorkPrecision(WorkPrecisionArgs),
    /// Run a parameter grid, in parallel, resumable, shardable.
    Sweep(SweepArgs),
    /// Join the finished points of sweep directories into one table (CSV and markdown).
    Merge(MergeArgs),
    /// Stiffness diagnostics: Jacobian eigenvalues along the run, the RK4 step limit
    /// (predicted and measured), which method family should win.
    Stiffness(StiffnessArgs),
    /// Chaos diagnostics: e/c once per crank revolution (Poincaré section) and the largest
    /// Lyapunov exponent (Benettin's method).
    Poincare(PoincareArgs),
    /// Run the extremes matrix: extreme scenes × every method × tolerances 1e-2 … 1e-12;
    /// exit 0 when no run fails (each agrees with its reference within its promise, ends in a
    /// typed solver error, or is a documented known finding), 1 otherwise.
    Extremes(ExtremesArgs),
    /// Animate a run: RUN_DIR/animation.html, one self-contained page a browser opens (the
    /// mechanism moving, its clearance joints magnified, forces, a time-series panel).
    Animate(crate::viz::AnimateArgs),
    /// Plot trajectory columns of a run against time or another column (SVG and PNG).
    Plot(crate::viz::PlotArgs),
}

/// The solver flags of `lash run`.
///
/// ```text
/// [--method M] [--rtol R] [--atol A[,A..]] [--step H] [--controller C]
/// [--max-steps N] [--max-wall-time S] [--max-memory BYTES]
/// fixed-step: --step only;  adaptive: --rtol, --atol, --controller only;  budgets: any method
/// ```
///
/// A budget that runs out is a solver failure (exit 3, time and state printed; `lash run`
/// writes failure.json): `--max-steps` as `too many steps`, `--max-wall-time` as `budget
/// exhausted`.
///
/// Source: docs/outputs.md ("Method and controller names").
#[derive(Debug, Clone, Default, PartialEq, Args)]
pub struct SolverFlags {
    /// Integration method (rk4, bs32, dopri54, tsit54, dop853, bdf, trbdf2, esdirk34, rodas5p).
    /// Default: the case's: bdf for scenes, rodas5p for test problems.
    #[arg(long, value_name = "M", value_parser = parse_method)]
    pub method: Option<Method>,
    /// Relative tolerance of adaptive methods, in [1e-14, 1). Default: the case's: 1e-8 for
    /// scenes, 1e-6 for test problems.
    #[arg(long, value_name = "R", value_parser = parse_rtol, allow_hyphen_values = true)]
    pub rtol: Option<f64>,
    /// Absolute tolerance of adaptive methods: one number, or one per state component
    /// (comma-separated); each finite and > 0. Default: scenes rtol × the smallest clearance
    /// (positions) and × that × the crank speed (velocities); test problems their own.
    #[arg(long, value_name = "A", value_parser = parse_atol, allow_hyphen_values = true)]
    pub atol: Option<Atol>,
    /// Fixed step of fixed-step methods, s; finite and > 0. Default: none (rk4 needs it).
    #[arg(long, value_name = "H", value_parser = parse_step, allow_hyphen_values = true)]
    pub step: Option<f64>,
    /// Step-size controller of adaptive methods (i, pi, pid, h211, h312, gustafsson). Default:
    /// the method's own: pi for the explicit pairs, gustafsson for rodas5p (diffsol's methods
    /// take none).
    #[arg(long, value_name = "C", value_parser = parse_controller)]
    pub controller: Option<ControllerKind>,
    /// Step budget: most step attempts (accepted and rejected), a whole number >= 1. Running
    /// out fails the run with "too many steps" (exit 3). Default: the case's (50 000 000 for
    /// scenes).
    #[arg(long = "max-steps", value_name = "N", value_parser = parse_max_steps)]
    pub max_steps: Option<usize>,
    /// Wall-clock budget, s; finite and > 0: of the whole run under `lash run` (reading the
    /// case, assembly, integration, output), of each integration elsewhere. Running out fails
    /// the run with "budget exhausted" (exit 3). Default: none.
    #[arg(long = "max-wall-time", value_name = "S", value_parser = parse_wall_time,
          allow_hyphen_values = true)]
    pub max_wall_time: Option<f64>,
    /// Memory budget of the implicit methods' dense Jacobian and LU (n² each), bytes, a whole
    /// number >= 1. A run whose matrices need more fails before it starts with "not enough
    /// memory" (exit 3). Default: half of the memory available (MemAvailable, the cgroup's
    /// limit, the address-space limit).
    #[arg(long = "max-memory", value_name = "BYTES", value_parser = parse_max_memory)]
    pub max_memory: Option<u64>,
}

impl SolverFlags {
    /// The engine's solver choice these flags make.
    pub fn choice(&self) -> SolverChoice {
        SolverChoice {
            method: self.method,
            rtol: self.rtol,
            atol: self.atol.clone(),
            step: self.step,
            controller: self.controller,
            max_steps: self.max_steps,
            max_wall_time: self.max_wall_time,
            max_memory: self.max_memory,
        }
    }

    /// Lays the flags over `base` (the case's own options, or the defaults) and checks that
    /// they fit the method that results ([`SolverChoice::apply`]); an error names the flags.
    ///
    /// ```text
    /// method = --method or base.method
    /// fixed-step: --rtol, --atol, --controller are usage errors; step = --step, or base.step
    ///             if the method did not change; none → "needs --step"
    /// adaptive:   --step is a usage error; --controller on diffsol's methods is a usage error;
    ///             rtol, atol = the flag or base; controller = the flag, or base's if the
    ///             method did not change
    /// budgets:   --max-steps, --max-wall-time replace base's for any method
    /// ```
    pub fn apply(&self, base: &SolverOptions) -> Result<SolverOptions, Error> {
        self.choice().apply(base).map_err(flagged)
    }
}

/// Arguments of `lash run`.
///
/// ```text
/// lash run CASE [solver flags] [--t-end S] [--samples-per-revolution N | --output-every DT]
///              [--out DIR]
/// ```
///
/// Source: docs/outputs.md ("`lash run CASE`").
#[derive(Debug, Clone, PartialEq, Args)]
pub struct RunArgs {
    /// The case: a scene file (JSON) or a built-in test problem `testset:NAME`.
    pub case: String,
    /// Solver choice.
    #[command(flatten)]
    pub solver: SolverFlags,
    /// End time override, s (scene cases only). Default: the scene's t_end or revolutions.
    #[arg(long = "t-end", value_name = "S", value_parser = parse_t_end, allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// Rows of trajectory.csv per crank revolution, a whole number >= 1 (scenes with a crank
    /// driver). Default 2000.
    #[arg(long = "samples-per-revolution", value_name = "N", value_parser = parse_samples_per_rev,
          conflicts_with = "output_every")]
    pub samples_per_revolution: Option<usize>,
    /// Time between rows of trajectory.csv, s; finite and > 0 (any scene). Default: 2000 rows
    /// per crank revolution, 4001 rows without a crank driver.
    #[arg(long = "output-every", value_name = "DT", value_parser = parse_output_every,
          allow_hyphen_values = true)]
    pub output_every: Option<f64>,
    /// Output directory, replaced as a whole when the run ends (it must be new, empty, or an
    /// earlier run's). Default `out/run/CASE`.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Run until the clearance joint's once-per-revolution section e/c moves by less than TOL
    /// (units of the clearance c) between revolutions, at least 2 revolutions (scenes with a
    /// crank, driven or turned by a motor, and a clearance joint; a motor-driven crank's
    /// revolutions are its full turns); replaces the scene's end time. The revolutions
    /// used go to stdout and summary.json (`until_periodic`). Default: off (the scene's end
    /// time).
    #[arg(long = "until-periodic", value_name = "TOL", value_parser = parse_until_periodic,
          conflicts_with = "t_end")]
    pub until_periodic: Option<f64>,
    /// Cap on the revolutions of --until-periodic, a whole number >= 2. Default 100.
    #[arg(long = "max-revolutions", value_name = "N", value_parser = parse_max_revolutions,
          requires = "until_periodic")]
    pub max_revolutions: Option<usize>,
    /// Also write DIR/animation.html, the run as a page a browser opens (as `lash animate
    /// DIR`; scenes only). Default: off.
    #[arg(long)]
    pub animate: bool,
    /// How the constraints are enforced, over the scene's `formulation`:
    /// lagrange_baumgarte, augmented_lagrangian, minimal or auto (docs/model.md §12). Default:
    /// the scene's (whose default is auto).
    #[arg(long, value_name = "F", value_parser = parse_formulation)]
    pub formulation: Option<lash_model::FormulationName>,
    /// The window the metrics of summary.json cover: last-revolution (of the crank:
    /// roles.crank or roles.crank_driver; a crank a motor turns takes a first pass to find
    /// where its last turn starts), all (the whole run), or T0:T1 in seconds. Default:
    /// last-revolution with a crank, all without one.
    #[arg(long, value_name = "W", value_parser = parse_window, allow_hyphen_values = true)]
    pub window: Option<lash_model::MetricsWindow>,
    /// Leave out the energy check of the finished run, for a run that is coarse on purpose.
    /// Default: on: a run whose energy balance is off by more than its accuracy allows (5 % of
    /// its energy flows plus its integrals' and its states' own error) fails with exit 3,
    /// `energy_balance` (docs/outputs.md, "The energy check of a run").
    #[arg(long = "no-energy-check")]
    pub no_energy_check: bool,
}

/// Parses --window (lash_model::MetricsWindow).
fn parse_window(s: &str) -> Result<lash_model::MetricsWindow, String> {
    s.parse()
}

/// Parses --formulation.
fn parse_formulation(s: &str) -> Result<lash_model::FormulationName, String> {
    s.parse()
}

impl RunArgs {
    /// The engine's options.
    pub fn options(&self) -> RunOptions {
        RunOptions {
            case: self.case.clone(),
            solver: self.solver.choice(),
            t_end: self.t_end,
            samples_per_revolution: self.samples_per_revolution,
            output_every: self.output_every,
            out: self.out.clone(),
            until_periodic: self.until_periodic.map(|tol| UntilPeriodic {
                tol,
                max_revolutions: self.max_revolutions.unwrap_or(DEFAULT_MAX_REVOLUTIONS),
            }),
            formulation: self.formulation,
            window: self.window,
            skip_energy_check: self.no_energy_check,
        }
    }
}

/// Parses the tolerance of --until-periodic: finite and > 0 (units of c).
fn parse_until_periodic(s: &str) -> Result<f64, String> {
    let v = parse_number(s, "until-periodic")?;
    if !(v > 0.0) {
        return Err(format!("until-periodic must be > 0, got {s}"));
    }
    Ok(v)
}

fn parse_max_revolutions(s: &str) -> Result<usize, String> {
    parse_whole(s, "max-revolutions", MIN_REVOLUTIONS)
}

/// The studies `lash study` knows.
///
/// ```text
/// paper = the paper's speeds (120–200 rpm) and clearances (0.1–0.5 mm), dry and lubricated
/// ```
///
/// Source: docs/model.md §6.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum StudyName {
    /// The paper's case study: speeds and clearances, dry and lubricated.
    Paper,
}

/// Arguments of `lash study`.
///
/// ```text
/// lash study NAME [--out DIR]
/// ```
///
/// Source: docs/outputs.md ("`lash study paper`").
#[derive(Debug, Clone, PartialEq, Args)]
pub struct StudyArgs {
    /// Which study.
    #[arg(value_enum)]
    pub study: StudyName,
    /// Output directory. Default `out/study/NAME`.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Instead of the study, its robustness: every case under the modelling choices the paper
    /// leaves open (eps_cap, film law, contact damping, run length), one at a time;
    /// robustness.md and robustness.json in DIR (resumable through DIR/cache). Default: off.
    #[arg(long)]
    pub robustness: bool,
}

impl StudyArgs {
    /// The engine's options.
    pub fn options(&self) -> StudyOptions {
        let StudyName::Paper = self.study;
        StudyOptions {
            out: self.out.clone(),
            robustness: self.robustness,
            plan: None,
        }
    }
}

/// Arguments of `lash compare`.
///
/// ```text
/// lash compare CASE [--tolerances R,..] [--steps H,..] [--t-end S] [--window W] [--out DIR]
/// ```
///
/// Source: docs/outputs.md ("`lash compare CASE`").
#[derive(Debug, Clone, PartialEq, Args)]
pub struct CompareArgs {
    /// The case: a scene file (JSON) or `testset:NAME`.
    pub case: String,
    /// Relative tolerances of the adaptive methods, comma-separated. Default 1e-6,1e-9.
    #[arg(long, value_name = "R,..", value_delimiter = ',', value_parser = parse_rtol,
          allow_hyphen_values = true)]
    pub tolerances: Option<Vec<f64>>,
    /// RK4 steps, s, comma-separated. Default: the largest stable step h of the case and h/2,
    /// h/4 (every scene case); none for test problems.
    #[arg(long, value_name = "H,..", value_delimiter = ',', value_parser = parse_step,
          allow_hyphen_values = true)]
    pub steps: Option<Vec<f64>>,
    /// End time override, s (scene cases only). Default: the scene's t_end or revolutions.
    #[arg(long = "t-end", value_name = "S", value_parser = parse_t_end, allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// Wall-clock budget of each integration, s; finite and > 0. An integration that runs
    /// out fails with "budget exhausted" (the reference, or that row of compare.md). Default: none
    #[arg(long = "max-wall-time", value_name = "S", value_parser = parse_wall_time,
          allow_hyphen_values = true)]
    pub max_wall_time: Option<f64>,
    /// Where the errors are measured: last-revolution (of the crank; a crank a motor turns:
    /// its last turn, found by a run at the case's options), all (the whole run), or T0:T1 in
    /// seconds. Default: the case's rule (the first half revolution with a dry clearance joint,
    /// else the last revolution of a driven crank, else the whole run). Scene cases only.
    #[arg(long, value_name = "W", value_parser = parse_window, allow_hyphen_values = true)]
    pub window: Option<lash_model::MetricsWindow>,
    /// Output directory. Default `out/compare/CASE`.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Formulations compared side by side, comma-separated (lagrange_baumgarte,
    /// augmented_lagrangian, minimal, auto; docs/model.md §12): every row (RK4 steps and
    /// adaptive settings) with each, against one reference (the case's own formulation's:
    /// auto unless the scene names one), each row naming its formulation. Default: the case's.
    #[arg(long, value_name = "F,..", value_delimiter = ',', value_parser = parse_formulation)]
    pub formulations: Option<Vec<lash_model::FormulationName>>,
}

impl CompareArgs {
    /// The engine's options.
    pub fn options(&self) -> CompareOptions {
        CompareOptions {
            case: self.case.clone(),
            tolerances: self.tolerances.clone(),
            steps: self.steps.clone(),
            t_end: self.t_end,
            max_wall_time: self.max_wall_time,
            window: self.window,
            out: self.out.clone(),
            formulations: self.formulations.clone(),
        }
    }
}

/// Arguments of `lash work-precision`.
///
/// ```text
/// lash work-precision CASE [--methods M,..] [--tolerances R,..] [--steps H,..] [--controllers C,..]
///                          [--t-end S] [--out DIR]
/// ```
///
/// Source: docs/outputs.md ("Method and controller names": comma-separated lists).
#[derive(Debug, Clone, PartialEq, Args)]
pub struct WorkPrecisionArgs {
    /// The case: a scene file (JSON) or `testset:NAME`.
    pub case: String,
    /// Methods, comma-separated. Default: every method of this build.
    #[arg(long, value_name = "M,..", value_delimiter = ',', value_parser = parse_method)]
    pub methods: Option<Vec<Method>>,
    /// Relative tolerances of the adaptive methods, comma-separated (atol as
    /// in the case). Default 1e-4,1e-6,1e-8.
    #[arg(long, value_name = "R,..", value_delimiter = ',', value_parser = parse_rtol,
          allow_hyphen_values = true)]
    pub tolerances: Option<Vec<f64>>,
    /// Steps of the fixed-step methods, s, comma-separated. Default: the largest stable RK4
    /// step h of the case and h/2, h/4, h/8 (scene cases with a crank; test problems need
    /// the list).
    #[arg(long, value_name = "H,..", value_delimiter = ',', value_parser = parse_step,
          allow_hyphen_values = true)]
    pub steps: Option<Vec<f64>>,
    /// Controllers compared on dop853 (else the first adaptive method of ours listed),
    /// comma-separated. Default: all (i, pi, pid, h211, h312, gustafsson).
    #[arg(long, value_name = "C,..", value_delimiter = ',', value_parser = parse_controller)]
    pub controllers: Option<Vec<ControllerKind>>,
    /// End time override, s (scene cases only). Default: the scene's t_end or revolutions.
    #[arg(long = "t-end", value_name = "S", value_parser = parse_t_end, allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// Wall-clock budget of each integration, s; finite and > 0. An integration that runs
    /// out fails with "budget exhausted" (the reference, or that run of the table). Default: none
    #[arg(long = "max-wall-time", value_name = "S", value_parser = parse_wall_time,
          allow_hyphen_values = true)]
    pub max_wall_time: Option<f64>,
    /// Output directory. Default `out/work-precision/CASE`.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Formulations compared side by side, comma-separated (lagrange_baumgarte,
    /// augmented_lagrangian, minimal; docs/model.md §12): every run with each, against one reference
    /// (the case's own formulation's), each row naming its formulation. Default: the case's.
    #[arg(long, value_name = "F,..", value_delimiter = ',', value_parser = parse_formulation)]
    pub formulations: Option<Vec<lash_model::FormulationName>>,
}

impl WorkPrecisionArgs {
    /// The engine's options.
    pub fn options(&self) -> WorkPrecisionOptions {
        WorkPrecisionOptions {
            case: self.case.clone(),
            methods: self.methods.clone(),
            tolerances: self.tolerances.clone(),
            steps: self.steps.clone(),
            controllers: self.controllers.clone(),
            t_end: self.t_end,
            max_wall_time: self.max_wall_time,
            out: self.out.clone(),
            formulations: self.formulations.clone(),
        }
    }

    /// Checks the lists against each other and applies the defaults
    /// ([`WorkPrecisionPlan::new`]); an error names the flags.
    pub fn plan(&self) -> Result<WorkPrecisionPlan, Error> {
        self.options().plan().map_err(flagged)
    }
}

/// Arguments of `lash sweep`.
///
/// ```text
/// lash sweep SWEEP.json [--jobs N] [--shard I/N] [--out DIR]
/// ```
///
/// Source: docs/outputs.md ("Sweeps").
#[derive(Debug, Clone, PartialEq, Args)]
pub struct SweepArgs {
    /// The sweep file (JSON): a base case and lists of parameter values.
    pub file: PathBuf,
    /// Parallel jobs (≥ 1; more than the cores available are capped with a note). Default:
    /// the number of cores.
    #[arg(long, value_name = "N", value_parser = parse_jobs)]
    pub jobs: Option<usize>,
    /// Run only the points whose index modulo N equals I (I counts from 0). Default: 0/1,
    /// every point.
    #[arg(long, value_name = "I/N", value_parser = parse_shard)]
    pub shard: Option<Shard>,
    /// Wall-clock budget of each integration, s; finite and > 0. An integration that runs
    /// out fails with "budget exhausted" (that point, recorded as a solver failure). Default: none
    #[arg(long = "max-wall-time", value_name = "S", value_parser = parse_wall_time,
          allow_hyphen_values = true)]
    pub max_wall_time: Option<f64>,
    /// Output directory (one subdirectory per point). Default `out/sweep/STEM` of the file.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// The window the metrics of summary.json cover: last-revolution (of the crank:
    /// roles.crank or roles.crank_driver; a crank a motor turns takes a first pass to find
    /// where its last turn starts), all (the whole run), or T0:T1 in seconds. Default:
    /// last-revolution with a crank, all without one.
    #[arg(long, value_name = "W", value_parser = parse_window, allow_hyphen_values = true)]
    pub window: Option<lash_model::MetricsWindow>,
}

impl SweepArgs {
    /// The engine's options.
    pub fn options(&self) -> SweepRunOptions {
        SweepRunOptions {
            file: self.file.clone(),
            jobs: self.jobs,
            shard: self.shard,
            out: self.out.clone(),
            max_wall_time: self.max_wall_time,
            window: self.window,
        }
    }
}

/// Arguments of `lash extremes`.
///
/// ```text
/// lash extremes [--quick] [--jobs N] [--max-steps N] [--max-wall-time S] [--out DIR]
///   → DIR/extremes.md, DIR/extremes.json;  exit 0 no run failed (known findings are
///     reported, not failures), 1 some run failed (report written first), 3 a scene's
///     reference failed at every rtol of its ladder (nothing written)
/// ```
///
/// Source: docs/outputs.md ("`lash extremes`"); module `extremes`.
#[derive(Debug, Clone, PartialEq, Args)]
pub struct ExtremesArgs {
    /// The quick subset (3 scenes × every method × 3 tolerances), as in the default tests.
    /// Default: off (the full matrix).
    #[arg(long)]
    pub quick: bool,
    /// Parallel runs (≥ 1; more than the cores available are capped with a note). Default 1:
    /// the wall-clock budget is per run, and parallel runs share the cores.
    #[arg(long, value_name = "N", value_parser = parse_jobs)]
    pub jobs: Option<usize>,
    /// Step budget of every run (attempts). Default 1 000 000 (100 000 with --quick).
    #[arg(long = "max-steps", value_name = "N", value_parser = parse_max_steps)]
    pub max_steps: Option<usize>,
    /// Wall-clock budget of every run, s. Default 20 (10 with --quick).
    #[arg(long = "max-wall-time", value_name = "S", value_parser = parse_wall_time,
          allow_hyphen_values = true)]
    pub max_wall_time: Option<f64>,
    /// Output directory. Default `out/extremes` (`out/extremes-quick` with --quick).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

impl ExtremesArgs {
    /// The engine's options.
    pub fn options(&self) -> ExtremesOptions {
        ExtremesOptions {
            quick: self.quick,
            jobs: self.jobs,
            max_steps: self.max_steps,
            max_wall_time: self.max_wall_time,
            out: self.out.clone(),
            ..Default::default()
        }
    }
}

/// Arguments of `lash merge`.
///
/// ```text
/// lash merge DIR... [--out DIR] [--allow-partial] [--columns A,B,C]  →  DIR/merged.csv, DIR/merged.md
/// ```
///
/// Source: docs/outputs.md ("Sweeps").
#[derive(Debug, Clone, PartialEq, Args)]
pub struct MergeArgs {
    /// Sweep output directories (or point directories) to join.
    #[arg(required = true, value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
    /// Where merged.csv and merged.md go. Default: the first DIR.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Merge what finished although some points of the grid are unfinished or have a corrupt
    /// result (they get rows with status unfinished / corrupt). Default: off, and an
    /// incomplete sweep is an error (exit 2) that names the missing points.
    #[arg(long = "allow-partial")]
    pub allow_partial: bool,
    /// The columns merged.md shows, comma-separated, in order (names as in merged.csv's
    /// header). Default: the parameters, status, error and a short set of metrics; merged.csv
    /// has every column either way.
    #[arg(long, value_name = "A,B,C", value_delimiter = ',')]
    pub columns: Vec<String>,
}

impl MergeArgs {
    /// The engine's options.
    pub fn options(&self) -> MergeOptions {
        MergeOptions {
            dirs: self.dirs.clone(),
            out: self.out.clone(),
            allow_partial: self.allow_partial,
            columns: self.columns.clone(),
        }
    }
}

/// Arguments of `lash stiffness`.
///
/// ```text
/// lash stiffness CASE [solver flags] [--samples N] [--t-end S] [--no-measure] [--out DIR]
/// ```
///
/// Source: docs/outputs.md ("`lash stiffness CASE`").
#[derive(Debug, Clone, PartialEq, Args)]
pub struct StiffnessArgs {
    /// The case: a scene file (JSON) or a built-in test problem `testset:NAME`.
    pub case: String,
    /// Solver of the reference run (default: the case's, as `lash run`).
    #[command(flatten)]
    pub solver: SolverFlags,
    /// Sample points along the run, both ends included (≥ 2). Default 1000.
    #[arg(long, value_name = "N", value_parser = parse_samples)]
    pub samples: Option<usize>,
    /// End time override, s (scene cases only). Default: the scene's t_end or revolutions.
    #[arg(long = "t-end", value_name = "S", value_parser = parse_t_end, allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// Skip the measured RK4 limit (the bisection runs RK4 over the whole run many times).
    /// Default: off (the limit is measured).
    #[arg(long = "no-measure")]
    pub no_measure: bool,
    /// Output directory. Default `out/stiffness/CASE`.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

impl StiffnessArgs {
    /// The engine's options.
    pub fn options(&self) -> StiffnessOptions {
        StiffnessOptions {
            case: self.case.clone(),
            solver: self.solver.choice(),
            samples: self.samples,
            t_end: self.t_end,
            measure: !self.no_measure,
            out: self.out.clone(),
        }
    }
}

/// Arguments of `lash poincare`.
///
/// ```text
/// lash poincare CASE [--revolutions N] [--perturbation D] [--renorm-per-rev R]
///                    [solver flags] [--out DIR]
/// ```
///
/// Source: docs/outputs.md ("`lash poincare CASE`").
#[derive(Debug, Clone, PartialEq, Args)]
pub struct PoincareArgs {
    /// The case: a scene file (JSON) with a crank (driven, or turned by a motor: the section is
    /// then taken at its full turns) and a clearance joint role.
    pub case: String,
    /// Crank revolutions (≥ 1). Default 20.
    #[arg(long, value_name = "N", value_parser = parse_count)]
    pub revolutions: Option<usize>,
    /// Initial and renormalised separation of the two trajectories, in clearances (weighted
    /// norm), in (0, 1). Default 1e-4.
    #[arg(long, value_name = "D", value_parser = parse_perturbation, allow_hyphen_values = true)]
    pub perturbation: Option<f64>,
    /// Renormalisations per crank revolution (≥ 1). Default 10.
    #[arg(long = "renorm-per-rev", value_name = "R", value_parser = parse_count)]
    pub renorm_per_rev: Option<usize>,
    /// Solver of both trajectories (default: the case's, as `lash run`).
    #[command(flatten)]
    pub solver: SolverFlags,
    /// Output directory. Default `out/poincare/CASE`.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

impl PoincareArgs {
    /// The engine's options.
    pub fn options(&self) -> PoincareOptions {
        PoincareOptions {
            case: self.case.clone(),
            revolutions: self.revolutions,
            perturbation: self.perturbation,
            renorm_per_rev: self.renorm_per_rev,
            solver: self.solver.choice(),
            out: self.out.clone(),
        }
    }
}

/// What parsing the command line gave.
///
/// ```text
/// Cli(command) | Print(help or version text, exit 0)
/// ```
///
/// Source: clap's error kinds DisplayHelp, DisplayVersion.
#[derive(Debug)]
// Built once per process: the size of the larger variant costs nothing worth a box.
#[allow(clippy::large_enum_variant)]
pub enum Parsed {
    /// A command to execute (boxed: far larger than the text).
    Cli(Box<Cli>),
    /// Help or version text to print on standard output, then exit 0.
    Print(String),
}

/// Parses the command line. A usage error becomes [`Error::Usage`] with clap's message on one
/// line (without "error: ", the usage block and the tip).
pub fn parse<I, T>(args: I) -> Result<Parsed, Error>
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    match Cli::try_parse_from(args) {
        Ok(cli) => Ok(Parsed::Cli(Box::new(cli))),
        Err(e) => {
            use clap::error::ErrorKind;
            match e.kind() {
                ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
                    Ok(Parsed::Print(e.render().to_string()))
                }
                _ => Err(Error::Usage(one_line(&e.render().to_string()))),
            }
        }
    }
}

/// The first paragraph of a clap error message, on one line, without the `error: ` prefix.
pub fn one_line(msg: &str) -> String {
    let parts: Vec<&str> = msg
        .lines()
        .take_while(|l| !l.trim().is_empty())
        .map(str::trim)
        .collect();
    let joined = parts.join(" ");
    joined
        .strip_prefix("error: ")
        .unwrap_or(&joined)
        .to_string()
}

/// Parses a method name (docs/outputs.md, "Method and controller names").
pub fn parse_method(s: &str) -> Result<Method, String> {
    Method::from_name(s).ok_or_else(|| {
        let known: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        format!("unknown method '{s}' (known: {})", known.join(", "))
    })
}

/// Parses a controller name (docs/outputs.md, "Method and controller names").
pub fn parse_controller(s: &str) -> Result<ControllerKind, String> {
    ControllerKind::from_name(s).ok_or_else(|| {
        let known: Vec<&str> = ControllerKind::ALL.iter().map(|c| c.name()).collect();
        format!("unknown controller '{s}' (known: {})", known.join(", "))
    })
}

fn parse_number(s: &str, what: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{what} must be a number, got '{s}'"))?;
    if !v.is_finite() {
        return Err(format!("{what} must be finite, got {s}"));
    }
    Ok(v)
}

/// Parses a relative tolerance: a number in the solver's range ([`Rule::RTOL`]).
pub fn parse_rtol(s: &str) -> Result<f64, String> {
    let v = parse_number(s, "rtol")?;
    Rule::RTOL.check(v).map_err(|e| e.to_string())
}

/// Parses an absolute tolerance: one number, or comma-separated numbers; each finite and > 0.
pub fn parse_atol(s: &str) -> Result<Atol, String> {
    let mut v = Vec::new();
    for part in s.split(',') {
        let a = parse_number(part, "atol")?;
        if !(a > 0.0) {
            return Err(format!("atol must be > 0, got {}", part.trim()));
        }
        v.push(a);
    }
    Ok(if v.len() == 1 {
        Atol::Scalar(v[0])
    } else {
        Atol::Vector(v)
    })
}

/// Parses an end-time override: finite and > 0 (s).
pub fn parse_t_end(s: &str) -> Result<f64, String> {
    let v = parse_number(s, "t-end")?;
    if !(v > 0.0) {
        return Err(format!("t-end must be > 0, got {s}"));
    }
    Ok(v)
}

/// Parses a trajectory spacing: finite and > 0 (s).
pub fn parse_output_every(s: &str) -> Result<f64, String> {
    let v = parse_number(s, "output-every")?;
    if !(v > 0.0) {
        return Err(format!("output-every must be > 0, got {s}"));
    }
    Ok(v)
}

fn parse_samples_per_rev(s: &str) -> Result<usize, String> {
    parse_whole(s, "samples-per-revolution", 1)
}

/// Parses a fixed step: finite and > 0 (s).
pub fn parse_step(s: &str) -> Result<f64, String> {
    let v = parse_number(s, "step")?;
    if !(v > 0.0) {
        return Err(format!("step must be > 0, got {s}"));
    }
    Ok(v)
}

/// Parses a whole number `>= min` for the flag `name`.
fn parse_whole(s: &str, name: &str, min: usize) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if n >= min => Ok(n),
        _ => Err(format!("{name} must be a whole number >= {min}, got '{s}'")),
    }
}

fn parse_samples(s: &str) -> Result<usize, String> {
    parse_whole(s, "samples", 2)
}

fn parse_count(s: &str) -> Result<usize, String> {
    parse_whole(s, "the value", 1)
}

/// Parses a Lyapunov perturbation: a number in (0, 1) (clearances).
pub fn parse_perturbation(s: &str) -> Result<f64, String> {
    let v = parse_number(s, "perturbation")?;
    if !(v > 0.0 && v < 1.0) {
        return Err(format!(
            "perturbation must be in (0, 1) clearances, got {s}"
        ));
    }
    Ok(v)
}

/// Parses a step budget: a whole number >= 1.
pub fn parse_max_steps(s: &str) -> Result<usize, String> {
    parse_whole(s, "max-steps", 1)
}

/// Parses a memory budget: a whole number of bytes >= 1.
pub fn parse_max_memory(s: &str) -> Result<u64, String> {
    match s.trim().parse::<u64>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!(
            "max-memory must be a whole number of bytes >= 1, got '{s}'"
        )),
    }
}

/// Parses a wall-clock budget: finite and > 0 (s).
pub fn parse_wall_time(s: &str) -> Result<f64, String> {
    let v = parse_number(s, "max-wall-time")?;
    if !(v > 0.0) {
        return Err(format!("max-wall-time must be > 0, got {s}"));
    }
    Ok(v)
}

fn parse_jobs(s: &str) -> Result<usize, String> {
    parse_whole(s, "jobs", 1)
}

fn parse_shard(s: &str) -> Result<Shard, String> {
    s.parse::<Shard>().map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exit::ExitStatus;

    fn cli(args: &[&str]) -> Result<Cli, Error> {
        let mut v = vec!["lash"];
        v.extend_from_slice(args);
        match parse(v)? {
            Parsed::Cli(c) => Ok(*c),
            Parsed::Print(_) => panic!("help printed"),
        }
    }

    fn usage(args: &[&str]) -> String {
        match cli(args) {
            Err(Error::Usage(m)) => {
                assert!(!m.contains('\n'), "multi-line: {m}");
                m
            }
            other => panic!("expected a usage error for {args:?}, got {other:?}"),
        }
    }

    fn run_flags(args: &[&str]) -> SolverFlags {
        let mut v = vec!["run", "case.json"];
        v.extend_from_slice(args);
        match cli(&v).unwrap().command {
            Some(Command::Run(r)) => r.solver,
            c => panic!("{c:?}"),
        }
    }

    #[test]
    fn no_subcommand_is_the_default_run() {
        let c = cli(&[]).unwrap();
        assert!(c.command.is_none() && c.out.is_none());
        let c = cli(&["--out", "here"]).unwrap();
        assert_eq!(c.out, Some(PathBuf::from("here")));
        // The default run's --out is not a subcommand's.
        assert!(cli(&["--out", "here", "run", "c.json"]).is_err());
    }

    #[test]
    fn long_commands_take_a_wall_time_budget() {
        let c = cli(&["compare", "c.json", "--max-wall-time", "5"]).unwrap();
        let Some(Command::Compare(a)) = c.command else {
            panic!()
        };
        assert_eq!(a.options().max_wall_time, Some(5.0));
        let c = cli(&["work-precision", "c.json", "--max-wall-time", "6"]).unwrap();
        let Some(Command::WorkPrecision(a)) = c.command else {
            panic!()
        };
        assert_eq!(a.options().max_wall_time, Some(6.0));
        let c = cli(&["sweep", "s.json", "--max-wall-time", "7"]).unwrap();
        let Some(Command::Sweep(a)) = c.command else {
            panic!()
        };
        assert_eq!(a.options().max_wall_time, Some(7.0));
        for cmd in [
            ["compare", "c.json"],
            ["work-precision", "c.json"],
            ["sweep", "s.json"],
        ] {
            let m = usage(&[cmd[0], cmd[1], "--max-wall-time", "0"]);
            assert!(m.contains("max-wall-time must be > 0, got 0"), "{m}");
        }
    }

    #[test]
    fn run_parses_every_flag() {
        let c = cli(&[
            "run",
            "c.json",
            "--method",
            "dopri54",
            "--rtol",
            "1e-8",
            "--atol",
            "1e-10,2e-10",
            "--controller",
            "h211",
            "--out",
            "o",
        ])
        .unwrap();
        let Some(Command::Run(r)) = c.command else {
            panic!()
        };
        assert_eq!(r.case, "c.json");
        assert_eq!(r.solver.method, Some(Method::Dopri54));
        assert_eq!(r.solver.rtol, Some(1e-8));
        assert_eq!(r.solver.atol, Some(Atol::Vector(vec![1e-10, 2e-10])));
        assert_eq!(r.solver.controller, Some(ControllerKind::H211));
        assert_eq!(r.out, Some(PathBuf::from("o")));
        let o = r.solver.apply(&SolverOptions::default()).unwrap();
        assert_eq!(o.method, Method::Dopri54);
        assert_eq!(o.rtol, 1e-8);
        assert_eq!(o.controller, Some(ControllerKind::H211));
        assert_eq!(o.step, None);
    }

    #[test]
    fn budget_flags_set_the_solver_budgets_for_any_method() {
        for method in ["bdf", "rk4"] {
            let mut args = vec![
                "--method",
                method,
                "--max-steps",
                "10",
                "--max-wall-time",
                "0.5",
            ];
            if method == "rk4" {
                args.extend(["--step", "1e-4"]);
            }
            let o = run_flags(&args).apply(&SolverOptions::default()).unwrap();
            assert_eq!((o.max_steps, o.max_wall_time), (10, Some(0.5)), "{method}");
        }
        // Without the flags the base's budgets stay.
        let base = SolverOptions {
            max_steps: 77,
            max_wall_time: Some(3.0),
            ..Default::default()
        };
        let o = run_flags(&[]).apply(&base).unwrap();
        assert_eq!((o.max_steps, o.max_wall_time), (77, Some(3.0)));
        let m = usage(&["run", "c.json", "--max-steps", "0"]);
        assert!(
            m.contains("max-steps must be a whole number >= 1, got '0'"),
            "{m}"
        );
        let m = usage(&["run", "c.json", "--max-steps", "1e3"]);
        assert!(m.contains("max-steps must be a whole number"), "{m}");
        let m = usage(&["run", "c.json", "--max-wall-time", "-1"]);
        assert!(m.contains("max-wall-time must be > 0, got -1"), "{m}");
        let m = usage(&["run", "c.json", "--max-wall-time", "inf"]);
        assert!(m.contains("max-wall-time must be finite"), "{m}");
    }

    #[test]
    fn every_interface_name_parses() {
        for m in Method::ALL {
            assert_eq!(parse_method(m.name()), Ok(m));
        }
        for c in ControllerKind::ALL {
            assert_eq!(parse_controller(c.name()), Ok(c));
        }
        for (s, c) in [
            ("i", ControllerKind::I),
            ("gustafsson", ControllerKind::Gustafsson),
        ] {
            assert_eq!(parse_controller(s), Ok(c));
        }
    }

    #[test]
    fn bad_values_name_the_flag_on_one_line() {
        let m = usage(&["run", "c.json", "--method", "euler"]);
        assert!(
            m.contains("'--method <M>'") && m.contains("unknown method 'euler'"),
            "{m}"
        );
        let m = usage(&["run", "c.json", "--controller", "pd"]);
        assert!(m.contains("unknown controller 'pd'"), "{m}");
        let m = usage(&["run", "c.json", "--rtol", "-1"]);
        assert!(m.contains("rtol must be in [1e-14, 1), got -1"), "{m}");
        let m = usage(&["run", "c.json", "--rtol", "1"]);
        assert!(m.contains("rtol must be in"), "{m}");
        let m = usage(&["run", "c.json", "--rtol", "1e-15"]);
        assert!(m.contains("rtol must be in"), "{m}");
        let m = usage(&["run", "c.json", "--rtol", "nan"]);
        assert!(m.contains("rtol must be finite"), "{m}");
        let m = usage(&["run", "c.json", "--atol", "1e-8,0"]);
        assert!(m.contains("atol must be > 0, got 0"), "{m}");
        let m = usage(&["run", "c.json", "--step", "0"]);
        assert!(m.contains("step must be > 0, got 0"), "{m}");
        let m = usage(&["run", "c.json", "--step", "abc"]);
        assert!(m.contains("step must be a number, got 'abc'"), "{m}");
        let m = usage(&["run"]);
        assert!(
            m.contains("required arguments were not provided") && m.contains("<CASE>"),
            "{m}"
        );
        let m = usage(&["run", "c.json", "--stp", "1"]);
        assert!(m.contains("unexpected argument '--stp'"), "{m}");
        let m = usage(&["study", "nonsense"]);
        assert!(m.contains("invalid value 'nonsense'"), "{m}");
        let m = usage(&["frobnicate"]);
        assert!(m.contains("unrecognized subcommand 'frobnicate'"), "{m}");
    }

    #[test]
    fn step_is_only_for_fixed_step_methods() {
        let d = SolverOptions::default(); // dopri54
        let e = run_flags(&["--method", "dopri54", "--step", "1e-4"])
            .apply(&d)
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "--step is only for fixed-step methods, and dopri54 is adaptive"
        );
        // Without --method the base method (adaptive here) decides.
        assert!(run_flags(&["--step", "1e-4"]).apply(&d).is_err());
        let o = run_flags(&["--method", "rk4", "--step", "1e-4"])
            .apply(&d)
            .unwrap();
        assert_eq!(
            (o.method, o.step, o.controller),
            (Method::Rk4, Some(1e-4), None)
        );
        for flag in [
            ["--rtol", "1e-6"],
            ["--atol", "1e-9"],
            ["--controller", "pi"],
        ] {
            let e = run_flags(&["--method", "rk4", "--step", "1e-4", flag[0], flag[1]])
                .apply(&d)
                .unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert_eq!(
                e.to_string(),
                format!(
                    "{} is only for adaptive methods, and rk4 is fixed-step",
                    flag[0]
                )
            );
        }
        let e = run_flags(&["--method", "rk4"]).apply(&d).unwrap_err();
        assert_eq!(
            e.to_string(),
            "method rk4 is fixed-step and needs --step (it needs a fixed step size)"
        );
    }

    #[test]
    fn base_options_fill_what_the_flags_leave_out() {
        let base = SolverOptions {
            method: Method::Rk4,
            step: Some(2e-5),
            ..Default::default()
        };
        // Same method: the case's step is kept; a flag overrides it.
        assert_eq!(run_flags(&[]).apply(&base).unwrap().step, Some(2e-5));
        assert_eq!(
            run_flags(&["--step", "1e-5"]).apply(&base).unwrap().step,
            Some(1e-5)
        );
        // Switching to an adaptive method drops the step.
        let o = run_flags(&["--method", "tsit54", "--rtol", "1e-9"])
            .apply(&base)
            .unwrap();
        assert_eq!((o.step, o.rtol, o.controller), (None, 1e-9, None));
        // diffsol's methods take no controller of ours.
        let e = run_flags(&["--method", "bdf", "--controller", "pi"])
            .apply(&SolverOptions::default())
            .unwrap_err();
        assert!(e
            .to_string()
            .starts_with("--controller does not apply to bdf"));
        let ctl = SolverOptions {
            controller: Some(ControllerKind::Pid),
            ..Default::default()
        };
        assert_eq!(
            run_flags(&[]).apply(&ctl).unwrap().controller,
            Some(ControllerKind::Pid)
        );
        assert_eq!(
            run_flags(&["--method", "bdf"])
                .apply(&ctl)
                .unwrap()
                .controller,
            None
        );
    }

    fn wp(args: &[&str]) -> Result<WorkPrecisionPlan, Error> {
        let mut v = vec!["work-precision", "c.json"];
        v.extend_from_slice(args);
        match cli(&v)?.command {
            Some(Command::WorkPrecision(w)) => w.plan(),
            c => panic!("{c:?}"),
        }
    }

    #[test]
    fn work_precision_lists() {
        let p = wp(&[
            "--methods",
            "bdf,rodas5p,rk4",
            "--tolerances",
            "1e-4,1e-6,1e-8",
            "--steps",
            "1e-4,5e-5",
            "--controllers",
            "pi,h211",
        ])
        .unwrap();
        assert_eq!(p.methods, vec![Method::Bdf, Method::Rodas5p, Method::Rk4]);
        assert_eq!(p.tolerances, vec![1e-4, 1e-6, 1e-8]);
        assert_eq!(p.steps, Some(vec![1e-4, 5e-5]));
        assert_eq!(
            p.controllers,
            vec![ControllerKind::Pi, ControllerKind::H211]
        );
        let p = wp(&[]).unwrap();
        assert_eq!(p.methods, Method::ALL.to_vec());
        // The engine's default tolerances of work-precision.
        assert_eq!(p.tolerances, [1e-4, 1e-6, 1e-8]);
        assert_eq!(p.controllers, ControllerKind::ALL.to_vec());
        let p = wp(&["--methods", "rk4"]).unwrap();
        assert!(p.tolerances.is_empty() && p.controllers.is_empty());
    }

    #[test]
    fn work_precision_mismatches_are_usage_errors() {
        let msg = |a: &[&str]| match wp(a) {
            Err(Error::Usage(m)) => m,
            r => panic!("{a:?}: {r:?}"),
        };
        assert_eq!(
            msg(&["--methods", "dopri54", "--steps", "1e-4"]),
            "--steps is only for fixed-step methods, and --methods lists none"
        );
        assert_eq!(
            msg(&["--methods", "rk4", "--tolerances", "1e-6"]),
            "--tolerances is only for adaptive methods, and --methods lists none"
        );
        assert!(msg(&["--methods", "bdf,rk4", "--controllers", "pi"]).starts_with("--controllers"));
        assert_eq!(msg(&["--methods", "bdf,bdf"]), "--methods lists bdf twice");
        assert!(msg(&["--tolerances", "1e-6,1e-6"]).contains("twice"));
        assert!(msg(&["--methods", "bdf,euler"]).contains("unknown method 'euler'"));
        assert!(msg(&["--tolerances", "1e-6,2"]).contains("rtol must be in"));
    }

    #[test]
    fn sweep_and_merge_arguments() {
        let c = cli(&["sweep", "s.json", "--jobs", "3", "--shard", "1/4"]).unwrap();
        let Some(Command::Sweep(s)) = c.command else {
            panic!()
        };
        assert_eq!(s.jobs, Some(3));
        assert_eq!(s.shard, Some(Shard { index: 1, count: 4 }));
        assert!(usage(&["sweep", "s.json", "--jobs", "0"]).contains("jobs must be"));
        assert!(usage(&["sweep", "s.json", "--shard", "4/4"]).contains("shard"));
        assert!(usage(&["sweep", "s.json", "--shard", "x"]).contains("shard"));
        assert!(usage(&["merge"]).contains("<DIR>"));
        let c = cli(&["merge", "a", "b"]).unwrap();
        let Some(Command::Merge(m)) = c.command else {
            panic!()
        };
        assert_eq!(m.dirs, vec![PathBuf::from("a"), PathBuf::from("b")]);
    }

    #[test]
    fn stiffness_and_poincare_arguments() {
        let c = cli(&[
            "stiffness",
            "c.json",
            "--samples",
            "50",
            "--no-measure",
            "--method",
            "rk4",
            "--step",
            "1e-4",
            "--t-end",
            "0.2",
        ])
        .unwrap();
        let Some(Command::Stiffness(s)) = c.command else {
            panic!()
        };
        assert_eq!(
            (s.samples, s.no_measure, s.t_end, s.solver.step),
            (Some(50), true, Some(0.2), Some(1e-4))
        );
        let c = cli(&[
            "poincare",
            "c.json",
            "--revolutions",
            "5",
            "--perturbation",
            "1e-5",
            "--renorm-per-rev",
            "4",
            "--rtol",
            "1e-10",
        ])
        .unwrap();
        let Some(Command::Poincare(p)) = c.command else {
            panic!()
        };
        assert_eq!(
            (
                p.revolutions,
                p.perturbation,
                p.renorm_per_rev,
                p.solver.rtol
            ),
            (Some(5), Some(1e-5), Some(4), Some(1e-10))
        );
        assert!(usage(&["stiffness", "c.json", "--samples", "1"]).contains("samples must be"));
        assert!(usage(&["poincare", "c.json", "--perturbation", "0"]).contains("perturbation"));
        assert!(usage(&["poincare", "c.json", "--renorm-per-rev", "0"]).contains(">= 1"));
    }

    #[test]
    fn every_option_states_its_default() {
        use clap::CommandFactory;
        let cli = Cli::command();
        let mut missing = Vec::new();
        for sub in cli.get_subcommands() {
            for a in sub.get_arguments() {
                if a.is_positional() || ["help", "version"].contains(&a.get_id().as_str()) {
                    continue;
                }
                let help = a
                    .get_long_help()
                    .or(a.get_help())
                    .map(|h| h.to_string())
                    .unwrap_or_default();
                if !help.contains("Default") && !help.contains("default:") {
                    missing.push(format!("{} --{}", sub.get_name(), a.get_id()));
                }
            }
        }
        assert!(
            missing.is_empty(),
            "options without a default in --help: {missing:?}"
        );
        // The defaults reach the printed help.
        let Parsed::Print(h) = parse(["lash", "merge", "--help"]).unwrap() else {
            panic!()
        };
        assert!(
            h.contains("--allow-partial") && h.contains("Default: off"),
            "{h}"
        );
    }

    #[test]
    fn help_and_version_are_printed_not_errors() {
        for a in [["lash", "--help"], ["lash", "--version"]] {
            match parse(a).unwrap() {
                Parsed::Print(s) => assert!(s.contains("lash")),
                Parsed::Cli(_) => panic!(),
            }
        }
    }

    #[test]
    fn one_line_joins_the_first_paragraph() {
        let m = "error: the following required arguments were not provided:\n  <CASE>\n\nUsage: lash run <CASE>\n";
        assert_eq!(
            one_line(m),
            "the following required arguments were not provided: <CASE>"
        );
    }
}
