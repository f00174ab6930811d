//! Dispatch: parsed command line → the engine's options → work → what is printed → exit code.
//!
//! ```text
//! main_with(args) = 0 on success; on failure print report() to stderr and return
//!                   exit_code()  (2 usage/input, 3 solver, 1 bug); standard output closed by
//!                   its reader: quiet, the same code; unwritable (full): 2 after the work
//!                   (module `out`)
//! stdout: the command's result (tables, descriptions, "wrote N files to DIR")
//! stderr: the engine's notes and the progress of long commands (StderrProgress: a bar on a
//!         terminal, else a line per finished item), errors
//! lash run --max-wall-time W: the engine stops itself at its next check (set-up's phases and
//!                   iterations, every step attempt); a watchdog ends the process with exit 3
//!                   at W + max(1 s, W/20) if it has not (work between checks: one
//!                   factorisation or Jacobian of a large system), so a budget is overrun by at
//!                   most 1 s or 5 %
//! ```
//!
//! Source: docs/outputs.md ("Exit codes of `lash`").

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use lash_validation::extremes::Matrix;
use lash_validation::{
    self as engine, describe_run, Comparison, Error, Headline, PoincareResult, PointResult,
    RunResult, StiffnessResult, SweepOutcome, SweepPoint, SweepReport, WorkPrecisionResult,
    WpTable, Written,
};

use crate::args::{
    self, Command, CompareArgs, ExtremesArgs, Parsed, PoincareArgs, RunArgs, StiffnessArgs,
    SweepArgs, WorkPrecisionArgs,
};
use crate::exit::{flagged, ExitStatus, EXIT_BUG, EXIT_OK, EXIT_SOLVER, EXIT_USAGE};
use crate::out::{errln, out, outln, stdout_error};
use crate::progress::StderrProgress;

/// Runs `lash` with these arguments (the first is the program name) and returns the exit code.
/// A panic (a bug) is caught and becomes exit code 1 (its message is printed by the panic hook).
/// Standard output that cannot be written (other than closed by its reader) makes a successful
/// command exit 2 (module `out`).
pub fn main_with<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let code = guard(|| {
        args::parse(args).and_then(|p| match p {
            Parsed::Print(s) => {
                out(&s);
                Ok(())
            }
            Parsed::Cli(c) => match c.command {
                None => default_command(c.out).map(|_| ()),
                command => execute(command),
            },
        })
    });
    match stdout_error() {
        Some(e) if code == EXIT_OK => {
            errln(&format!("error: writing standard output: {e}"));
            EXIT_USAGE
        }
        _ => code,
    }
}

/// Runs `f` and maps its outcome to an exit code: 0, the error's code (its report printed on
/// standard error), or 1 for a panic.
pub fn guard<F: FnOnce() -> Result<(), Error>>(f: F) -> u8 {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(Ok(())) => EXIT_OK,
        Ok(Err(e)) => {
            errln(&e.report());
            e.exit_code()
        }
        Err(_) => EXIT_BUG,
    }
}

/// Executes one command; `None` is the default run (the engine's `headline`: the 150 rpm
/// press, ideal vs dry vs lubricated, RK4 against the best adaptive method).
pub fn execute(command: Option<Command>) -> Result<(), Error> {
    let Some(command) = command else {
        return default_command(None).map(|_| ());
    };
    match command {
        Command::Run(a) => run_command(&a).map(|_| ()),
        Command::Study(a) if a.robustness => {
            let progress = StderrProgress::new();
            let w = engine::study_robustness(&a.options(), &progress);
            progress.clear();
            let w = w?;
            outln(&w.result.describe(&w.dir));
            Ok(())
        }
        Command::Study(a) => {
            let progress = StderrProgress::new();
            let w = engine::study_paper(&a.options(), &progress);
            progress.clear();
            let w = w?;
            outln(&w.result.describe(&w.dir));
            Ok(())
        }
        Command::Compare(a) => compare_command(&a).map(|_| ()),
        Command::WorkPrecision(a) => work_precision_command(&a).map(|_| ()),
        Command::Sweep(a) => {
            let progress = StderrProgress::new();
            let outcome = engine::sweep(&a.options(), &progress);
            progress.clear();
            print_sweep(&outcome?);
            Ok(())
        }
        Command::Stiffness(a) => stiffness_command(&a).map(|_| ()),
        Command::Poincare(a) => poincare_command(&a).map(|_| ()),
        Command::Extremes(a) => extremes_command(&a).map(|_| ()),
        Command::Animate(a) => crate::viz::animate_command(&a).map(|_| ()),
        Command::Plot(a) => crate::viz::plot_command(&a).map(|_| ()),
        Command::Merge(a) => {
            let m = engine::merge(&a.options()).map_err(flagged)?;
            let missing = m.table.unfinished.len() + m.table.corrupt.len();
            outln(&format!(
                "merged {} points into {} and {}",
                m.table.rows.len() - missing,
                m.csv.display(),
                m.md.display()
            ));
            if missing > 0 {
                errln(&format!(
                    "merge: {} (rows with status unfinished / corrupt)",
                    m.table.missing_summary(20)
                ));
            }
            Ok(())
        }
    }
}

/// The default run: notes each case on standard error, prints the table and the files
/// written (into `out`, default `./lash-default/`).
pub fn default_command(dir: Option<PathBuf>) -> Result<Written<Headline>, Error> {
    let w = engine::default_run(dir, &StderrProgress::new())?;
    out(&w.result.to_markdown());
    outln(&format!(
        "\nwrote {} files to {}",
        w.files.len(),
        w.dir.display()
    ));
    Ok(w)
}

/// `lash run`: the engine's run (module `commands`), then what it did and where the files are.
/// Returns the result and the output directory. With `--max-wall-time` a watchdog stops the
/// process (exit 3) if the engine overruns the budget inside work it cannot interrupt.
pub fn run_command(a: &RunArgs) -> Result<(RunResult, PathBuf), Error> {
    // `testset:NAME` (docs/outputs.md, "`lash run CASE`"): a test problem, no mechanism.
    if a.animate && a.case.starts_with("testset:") {
        return Err(Error::Usage(
            "--animate needs a scene: a built-in test problem has no mechanism to draw".into(),
        ));
    }
    let _watchdog = a.solver.max_wall_time.map(Watchdog::start);
    let w = engine::run(&a.options(), &StderrProgress::new())?;
    out(&describe_run(&w.result));
    outln(&format!(
        "wrote {} files to {}",
        w.files.len(),
        w.dir.display()
    ));
    if a.animate {
        crate::viz::animate_run(&w.dir)?;
    }
    Ok((w.result, w.dir))
}

/// Ends the process with exit 3 when a wall-clock budget of `w` s is overrun by
/// max(1 s, w/20) (module doc); dropped (the command ended) it does nothing.
struct Watchdog {
    done: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl Watchdog {
    fn start(w: f64) -> Watchdog {
        use std::sync::atomic::{AtomicBool, Ordering};
        let done = std::sync::Arc::new(AtomicBool::new(false));
        let flag = done.clone();
        let grace = (0.05 * w).max(1.0);
        // A budget longer than a Duration holds (finite w up to 1.8e308 passes the rule) has
        // no end to watch for.
        let Ok(limit) = std::time::Duration::try_from_secs_f64(w + grace) else {
            return Watchdog { done };
        };
        let started = std::time::Instant::now();
        std::thread::spawn(move || {
            while started.elapsed() < limit {
                if flag.load(Ordering::Relaxed) {
                    return;
                }
                std::thread::sleep(std::time::Duration::from_millis(20));
            }
            if !flag.load(Ordering::Relaxed) {
                errln(&format!(
                    "error: solver failed: budget exhausted: wall-clock budget of {w} s used; \
                     stopped {grace:.1} s later inside work that cannot be interrupted (one \
                     factorisation or Jacobian of a large system); nothing written"
                ));
                std::process::exit(i32::from(EXIT_SOLVER));
            }
        });
        Watchdog { done }
    }
}

impl Drop for Watchdog {
    fn drop(&mut self) {
        self.done.store(true, std::sync::atomic::Ordering::Relaxed);
    }
}

/// `lash compare`: RK4 at several steps, every embedded pair and every stiff method at each
/// tolerance, against the case's reference; notes the reference on standard error, writes
/// compare.md and compare.json and prints the table.
pub fn compare_command(a: &CompareArgs) -> Result<Comparison, Error> {
    let progress = StderrProgress::new();
    let w = engine::compare(&a.options(), &progress);
    progress.clear();
    let w = w?;
    out(&w.result.to_markdown());
    outln(&format!(
        "wrote {} files to {}",
        w.files.len(),
        w.dir.display()
    ));
    Ok(w.result)
}

/// `lash work-precision`: every method × tolerance and RK4 × step, and the controllers
/// compared on one method of ours, against the case's reference; notes each run on standard
/// error, writes the markdown and JSON tables and the log–log figures, prints the table.
pub fn work_precision_command(a: &WorkPrecisionArgs) -> Result<WpTable, Error> {
    let progress = StderrProgress::new();
    let w = engine::work_precision(&a.options(), &progress);
    progress.clear();
    let w = w?;
    let WorkPrecisionResult { table, reference } = w.result;
    out(&table.to_markdown());
    outln(&format!(
        "reference: {}\nwrote {} files to {}",
        reference,
        w.files.len(),
        w.dir.display()
    ));
    Ok(table)
}

/// `lash stiffness`: the engine's analysis, then the two limits and the verdict.
pub fn stiffness_command(a: &StiffnessArgs) -> Result<(StiffnessResult, PathBuf), Error> {
    let progress = StderrProgress::new();
    let w = engine::stiffness(&a.options(), &progress);
    progress.clear();
    let w = w?;
    out(&w.result.describe());
    outln(&format!(
        "wrote {} files to {}",
        w.files.len(),
        w.dir.display()
    ));
    Ok((w.result, w.dir))
}

/// `lash poincare`: the engine's section and Lyapunov exponent, then the estimate.
pub fn poincare_command(a: &PoincareArgs) -> Result<(PoincareResult, PathBuf), Error> {
    let progress = StderrProgress::new();
    let w = engine::poincare(&a.options(), &progress);
    progress.clear();
    let w = w?;
    out(&w.result.describe());
    outln(&format!(
        "wrote {} files to {}",
        w.files.len(),
        w.dir.display()
    ));
    Ok((w.result, w.dir))
}

/// `lash extremes`: runs the matrix (or its quick subset), notes each scene and run on
/// standard error, writes extremes.md and extremes.json, prints the counts, and fails with
/// exit code 1 (a bug) when some run ended in an outcome that is not allowed (the report is
/// written first, to show which).
pub fn extremes_command(a: &ExtremesArgs) -> Result<Matrix, Error> {
    let progress = StderrProgress::new();
    let w = engine::extremes(&a.options(), &progress);
    progress.clear();
    let w = w?;
    out(&w.result.describe(&w.files[0], &w.files[1]));
    w.result.check(&w.files[0])?;
    Ok(w.result)
}

/// `lash sweep` with a point runner: the engine's sweep ([`engine::sweep_with`]) with a
/// progress bar when standard error is a terminal, then one line of counts.
pub fn sweep_command<F>(a: &SweepArgs, runner: F) -> Result<SweepReport, Error>
where
    F: Fn(&SweepPoint, &Path) -> Result<PointResult, Error> + Sync,
{
    let progress = StderrProgress::new();
    let outcome = engine::sweep_with(&a.options(), runner, &progress);
    progress.clear();
    let outcome = outcome?;
    print_sweep(&outcome);
    Ok(outcome.report)
}

/// Prints the closing line of a sweep on standard error.
fn print_sweep(o: &SweepOutcome) {
    let busy = if o.report.busy.is_empty() {
        String::new()
    } else {
        format!(", {} claimed by other processes", o.report.busy.len())
    };
    errln(&format!(
        "sweep: shard {} of {} points: {} ran, {} solver failures, {} already done{busy}; results in {}",
        o.shard,
        o.points,
        o.report.ok,
        o.report.solver_failed,
        o.report.skipped,
        o.dir.display()
    ));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::args::MergeArgs;
    use lash_validation::Shard;

    #[test]
    fn sweep_shards_then_merge_through_the_commands() {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("base.json"), b"{}").unwrap();
        let file = d.path().join("grid.json");
        std::fs::write(
            &file,
            br#"{"case": "base.json", "speed_rpm": [120, 150, 180], "clearance": [1e-4, 2e-4]}"#,
        )
        .unwrap();
        let out = d.path().join("res");
        let runner = |p: &SweepPoint, _: &Path| {
            Ok(PointResult::flatten(&serde_json::json!({
                "x": p.params.speed_rpm.unwrap() * p.params.clearance.unwrap()
            })))
        };
        for i in 0..2 {
            let a = SweepArgs {
                file: file.clone(),
                jobs: Some(2),
                shard: Some(Shard { index: i, count: 2 }),
                out: Some(out.clone()),
                max_wall_time: None,
                window: None,
            };
            let r = sweep_command(&a, runner).unwrap();
            assert_eq!((r.selected, r.ok), (3, 3));
        }
        execute(Some(Command::Merge(MergeArgs {
            dirs: vec![out.clone()],
            out: None,
            allow_partial: false,
            columns: Vec::new(),
        })))
        .unwrap();
        let csv = std::fs::read_to_string(out.join("merged.csv")).unwrap();
        let rows: Vec<&str> = csv.lines().collect();
        assert_eq!(rows.len(), 7);
        assert!(
            rows[0].ends_with(",speed_rpm,clearance,status,error,x"),
            "{}",
            rows[0]
        );
        // Point 0 = 120 rpm × 1e-4 m.
        assert!(rows[1].ends_with(",120.0,0.0001,ok,,0.012"), "{}", rows[1]);
    }

    #[test]
    fn guard_maps_outcomes_to_exit_codes() {
        assert_eq!(guard(|| Ok(())), 0);
        assert_eq!(guard(|| Err(Error::Usage("x".into()))), 2);
        assert_eq!(
            guard(
                || Err(Error::Solver(lash_solver::SolveError::NonFiniteState {
                    t: 1.0,
                    y: vec![]
                }))
            ),
            3
        );
        assert_eq!(guard(|| panic!("a bug")), 1);
    }
}
