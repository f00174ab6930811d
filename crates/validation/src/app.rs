//! Dispatch: parsed command line → work → exit code.
//!
//! ```text
//! main_with(args) = 0 on success; on failure print Error::report() to stderr and return
//!                   Error::exit_code()  (2 usage/input, 3 solver, 1 bug)
//! ```
//!
//! Source: INTERFACES.md ("Exit codes of `lash`"). Commands whose engine (the model, the
//! adaptive and stiff solvers) is not wired in yet check all their input and then fail with
//! [`Error::NotYetAvailable`].

use std::ffi::OsString;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use lash_solver::{Method, SolverOptions};

use crate::case::Case;
use crate::cli::{
    self, Command, CompareArgs, Parsed, RunArgs, StudyName, SweepArgs, WorkPrecisionArgs,
};
use crate::compare::{self, Compared, Comparison, Reference};
use crate::error::{Error, EXIT_OK};
use crate::headline;
use crate::simulate::{simulate, Prepared, RunRequest, RunResult};
use crate::sweep::{self, PointResult, Shard, SweepOptions, SweepPoint, SweepReport};
use crate::workprecision::{WpRun, WpTable, DEFAULT_TARGETS};

/// Runs `lash` with these arguments (the first is the program name) and returns the exit code.
/// A panic (a bug) is caught and becomes exit code 1 (its message is printed by the panic hook).
pub fn main_with<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    guard(|| {
        cli::parse(args).and_then(|p| match p {
            Parsed::Print(s) => {
                print!("{s}");
                Ok(())
            }
            Parsed::Cli(c) => execute(c.command),
        })
    })
}

/// Runs `f` and maps its outcome to an exit code: 0, the error's code (its report printed on
/// standard error), or 1 for a panic.
pub fn guard<F: FnOnce() -> Result<(), Error>>(f: F) -> u8 {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(Ok(())) => EXIT_OK,
        Ok(Err(e)) => {
            eprintln!("{}", e.report());
            e.exit_code()
        }
        Err(_) => crate::error::EXIT_BUG,
    }
}

/// Executes one command; `None` is the default run (module `headline`: the 150 rpm press,
/// ideal vs dry vs lubricated, RK4 against the best adaptive method).
pub fn execute(command: Option<Command>) -> Result<(), Error> {
    let Some(command) = command else {
        return headline::run(None).map(|_| ());
    };
    match command {
        Command::Run(a) => run_command(&a).map(|_| ()),
        Command::Study(a) => {
            let StudyName::Paper = a.study;
            let out = a.out.unwrap_or_else(|| default_out("study", "paper"));
            crate::study::paper(&out).map(|_| ())
        }
        Command::Compare(a) => compare_command(&a).map(|_| ()),
        Command::WorkPrecision(a) => work_precision_command(&a).map(|_| ()),
        Command::Sweep(a) => {
            let spec = sweep::SweepSpec::load(&a.file)?;
            spec.points()?;
            let base = Prepared::load(spec.case.clone())?;
            sweep_command(&a, |p, dir| sweep_point(&base, p, dir)).map(|_| ())
        }
        Command::Stiffness(a) => stiffness_command(&a).map(|_| ()),
        Command::Poincare(a) => poincare_command(&a).map(|_| ()),
        Command::Extremes(a) => crate::extremes::command(&a).map(|_| ()),
        Command::Merge(a) => {
            let out = a.out.unwrap_or_else(|| a.dirs[0].clone());
            let table = sweep::merge(&a.dirs)?;
            let (csv, md) = table.write(&out)?;
            println!(
                "merged {} points into {} and {}",
                table.rows.len(),
                csv.display(),
                md.display()
            );
            Ok(())
        }
    }
}

/// `lash run`: checks the case and the flags (the flags first, so that a usage error is
/// reported before the scene is read), integrates, writes DIR/summary.json, DIR/trajectory.csv
/// and the figures, and prints what it did. Returns the result and the output directory.
pub fn run_command(a: &RunArgs) -> Result<(RunResult, PathBuf), Error> {
    let case = Case::load(&a.case, None)?;
    a.solver.apply(&SolverOptions::default())?;
    let prepared = Prepared::load(case)?;
    let opts = prepared.options(&a.solver)?;
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| default_out("run", &prepared.case.name));
    let mut req = RunRequest::new(opts);
    req.t_end = a.t_end;
    let r = simulate(&prepared, &req)?;
    let files = r.write(&out)?;
    print!("{}", describe_run(&r));
    println!("wrote {} files to {}", files.len(), out.display());
    Ok((r, out))
}

/// The RK4 steps of a comparison: the given ones, else the largest stable step h and h/2,
/// h/4 (`halvings` + 1 steps) for scene cases with a crank, none for test problems.
fn rk4_steps(
    p: &Prepared,
    given: &Option<Vec<f64>>,
    t_end: Option<f64>,
    halvings: usize,
) -> Result<Vec<f64>, Error> {
    match given {
        Some(v) => Ok(v.clone()),
        None if p.period().is_some() => {
            let h = compare::stable_rk4_step(p, t_end)?;
            eprintln!(
                "{}: largest stable RK4 step {h:e} s (1-2-5 series from T/400, ‖Φ‖ < 1e-8)",
                p.case.name
            );
            Ok((0..=halvings).map(|k| h / f64::from(1u32 << k)).collect())
        }
        None => Ok(Vec::new()),
    }
}

/// `lash compare`: RK4 at several steps, every embedded pair and every stiff method at each
/// tolerance, against the case's reference; writes compare.md and compare.json.
pub fn compare_command(a: &CompareArgs) -> Result<Comparison, Error> {
    let p = Prepared::load_spec(&a.case, None)?;
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| default_out("compare", &p.case.name));
    let reference = Reference::compute(&p, a.t_end)?;
    eprintln!("{}: reference {}", p.case.name, reference.how);
    let steps = rk4_steps(&p, &a.steps, a.t_end, 2)?;
    let tolerances = a
        .tolerances
        .clone()
        .unwrap_or_else(|| cli::COMPARE_TOLERANCES.to_vec());
    let mut runs = Vec::new();
    for &h in &steps {
        runs.push(compare::compare_one(&p, &reference, Method::Rk4, None, Some(h), None)?.0);
    }
    for m in Method::ALL.into_iter().filter(|m| !m.is_fixed_step()) {
        for &r in &tolerances {
            runs.push(compare::compare_one(&p, &reference, m, Some(r), None, None)?.0);
        }
    }
    let c = Comparison {
        case: p.case.name.clone(),
        reference: reference.how.clone(),
        reference_agreement: reference.agreement.clone(),
        window: reference.window.clone(),
        t_end: reference.t_end,
        runs,
    };
    let files = c.write(&out)?;
    print!("{}", c.to_markdown());
    println!("wrote {} files to {}", files.len(), out.display());
    Ok(c)
}

/// The method `lash work-precision` compares the controllers on when it is listed: the
/// highest-order pair, whose steps are longest and so most sensitive to the controller.
pub const CONTROLLER_METHOD: Method = Method::Dop853;

/// `lash work-precision`: every method × tolerance and RK4 × step, and the controllers
/// compared on one method of ours ([`CONTROLLER_METHOD`] if listed, else the first of ours in
/// the list), against the case's reference;
/// writes the markdown and JSON tables and the log–log figures.
pub fn work_precision_command(a: &WorkPrecisionArgs) -> Result<WpTable, Error> {
    let case = Case::load(&a.case, None)?;
    let plan = a.plan()?;
    let p = Prepared::load(case)?;
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| default_out("work-precision", &p.case.name));
    let wants_rk4 = plan.methods.iter().any(|m| m.is_fixed_step());
    if wants_rk4 && plan.steps.is_none() && p.period().is_none() {
        if a.methods.is_some() {
            return Err(Error::Usage(format!(
                "rk4 needs --steps for {} (no crank period to derive them from)",
                p.case.name
            )));
        }
        eprintln!("{}: rk4 left out (give --steps to include it)", p.case.name);
    }
    let reference = Reference::compute(&p, a.t_end)?;
    eprintln!("{}: reference {}", p.case.name, reference.how);
    let steps = if wants_rk4 {
        rk4_steps(&p, &plan.steps, a.t_end, 3)?
    } else {
        Vec::new()
    };
    let ours = |m: &Method| !m.is_fixed_step() && !m.is_diffsol();
    let ctl_method = if plan.methods.contains(&CONTROLLER_METHOD) {
        Some(CONTROLLER_METHOD)
    } else {
        plan.methods.iter().copied().find(ours)
    };
    let mut runs = Vec::new();
    let mut push = |c: Compared| {
        eprintln!(
            "  {} {}: error {}, {} RHS, {:.3} s",
            c.label(),
            c.setting(),
            c.error.map_or("failed".into(), |e| format!("{e:.3e}")),
            c.rhs_evals,
            c.wall_time_s
        );
        runs.push(WpRun {
            method: c.method,
            controller: c.controller,
            rtol: c.rtol,
            step: c.step,
            error: c.error,
            rhs_evals: c.rhs_evals,
            wall_time_s: c.wall_time_s,
            failure: c.failure,
        });
    };
    for &m in &plan.methods {
        if m.is_fixed_step() {
            for &h in &steps {
                push(compare::compare_one(&p, &reference, m, None, Some(h), None)?.0);
            }
        } else if Some(m) == ctl_method && !plan.controllers.is_empty() {
            for &c in &plan.controllers {
                for &r in &plan.tolerances {
                    push(compare::compare_one(&p, &reference, m, Some(r), None, Some(c))?.0);
                }
            }
        } else {
            for &r in &plan.tolerances {
                push(compare::compare_one(&p, &reference, m, Some(r), None, None)?.0);
            }
        }
    }
    let table = WpTable::new(&p.case.name, runs, &DEFAULT_TARGETS)?;
    let files = table.write(&out)?;
    print!("{}", table.to_markdown());
    println!(
        "reference: {}\nwrote {} files to {}",
        reference.how,
        files.len(),
        out.display()
    );
    Ok(table)
}

/// `lash stiffness`: checks the case and the flags, integrates the reference run analysing
/// the Jacobian at the sample points, measures the RK4 limit, writes stiffness.csv,
/// stiffness.{svg,png}, stiffness.md and stiffness.json, and prints the two limits and the
/// verdict.
pub fn stiffness_command(
    a: &cli::StiffnessArgs,
) -> Result<(crate::stiffness_cmd::StiffnessResult, PathBuf), Error> {
    use crate::stiffness_cmd::{analyse, StiffnessSettings, DEFAULT_SAMPLES};
    let case = Case::load(&a.case, None)?;
    a.solver.apply(&SolverOptions::default())?;
    let prepared = Prepared::load(case)?;
    let opts = prepared.options(&a.solver)?;
    prepared.t_span(a.t_end)?;
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| default_out("stiffness", &prepared.case.name));
    let settings = StiffnessSettings {
        samples: a.samples.unwrap_or(DEFAULT_SAMPLES),
        t_end: a.t_end,
        measure: !a.no_measure,
        ..Default::default()
    };
    let r = analyse(&prepared, &opts, &settings)?;
    let files = r.write(&out)?;
    print!("{}", r.report.describe());
    println!("wrote {} files to {}", files.len(), out.display());
    Ok((r, out))
}

/// `lash poincare`: checks the case (a crank driver and a clearance joint role) and the flags,
/// integrates the section run and the two Lyapunov trajectories, writes poincare.csv,
/// lyapunov.csv, the figures, poincare.md and poincare.json, and prints the estimate.
pub fn poincare_command(
    a: &cli::PoincareArgs,
) -> Result<(crate::poincare::PoincareResult, PathBuf), Error> {
    use crate::poincare::{analyse, PoincareSettings};
    let case = Case::load(&a.case, None)?;
    a.solver.apply(&SolverOptions::default())?;
    let prepared = Prepared::load(case)?;
    let opts = crate::poincare::options(&prepared, &a.solver)?;
    let d = PoincareSettings::default();
    let settings = PoincareSettings {
        revolutions: a.revolutions.unwrap_or(d.revolutions),
        perturbation: a.perturbation.unwrap_or(d.perturbation),
        renorm_per_rev: a.renorm_per_rev.unwrap_or(d.renorm_per_rev),
    };
    settings.validate()?;
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| default_out("poincare", &prepared.case.name));
    let r = analyse(&prepared, &opts, &settings)?;
    let files = r.write(&out)?;
    print!("{}", r.describe());
    println!("wrote {} files to {}", files.len(), out.display());
    Ok((r, out))
}

/// A few lines on what a run did: method, work, and the headline metrics.
pub fn describe_run(r: &RunResult) -> String {
    let s = &r.summary;
    let setting = match (s.step, s.rtol) {
        (Some(h), _) => format!("step {h:e} s"),
        (None, Some(rt)) => format!("rtol {rt:e}"),
        _ => String::new(),
    };
    let mut out = format!(
        "{}: {} {}, t_end {} s: {} steps ({} rejected), {} RHS evaluations, {} events, {:.3} s\n",
        s.case,
        s.method,
        setting,
        s.t_end,
        s.stats.accepted,
        s.stats.rejected_error + s.stats.rejected_newton,
        s.stats.rhs_evals,
        s.events,
        s.wall_time_s
    );
    if let Some(e) = s.reference_error {
        out.push_str(&format!("  reference error {e:.3e}\n"));
    }
    if let Some(m) = &s.metrics {
        let f = |v: Option<f64>| v.map_or("null".to_string(), |x| format!("{x:.6}"));
        let mut parts = Vec::new();
        if m.slider_acc_min.is_some() {
            parts.push(format!(
                "slider acceleration [{}, {}] m/s²",
                f(m.slider_acc_min),
                f(m.slider_acc_max)
            ));
        }
        if let Some(d) = m.slider_acc_rms_dev_ideal {
            parts.push(format!("RMS deviation from ideal {d:.3e} m/s²"));
        }
        if let Some(e) = m.eps_max {
            parts.push(format!("eps_max {e:.6}"));
        }
        if let Some(n) = m.contact_onsets {
            parts.push(format!("contact onsets {n}"));
        }
        parts.push(format!("max ‖Φ‖ {:.1e}", m.constraint_violation_max));
        out.push_str(&format!("  metrics: {}\n", parts.join(", ")));
        if let Some(e) = &m.energy {
            out.push_str(&format!(
                "  energy: driver work {:.6} J, balance error {:.3e} J (quadrature error {:.1e} J)\n",
                e.driver_work, e.balance_error, e.quadrature_error
            ));
        }
    }
    out
}

/// Default output directory of a command for a case: `out/COMMAND/NAME` (a `:` in a built-in
/// name becomes `_`).
pub fn default_out(command: &str, name: &str) -> PathBuf {
    PathBuf::from("out")
        .join(command)
        .join(name.replace(':', "_"))
}

/// The point runner of `lash sweep`: the base case with the point's physical parameters laid
/// over its scene ([`sweep::apply_params`]) and its solver choice over the case's defaults;
/// writes DIR/summary.json and returns the summary, flattened, for the merged table. A
/// solver failure is returned as such (the sweep records it as a finished point).
pub fn sweep_point(base: &Prepared, point: &SweepPoint, dir: &Path) -> Result<PointResult, Error> {
    let pp = &point.params;
    let physical = pp.speed_rpm.is_some()
        || pp.clearance.is_some()
        || pp.viscosity.is_some()
        || pp.stiffness.is_some();
    let prepared = match base.scene() {
        Some(scene) if physical => {
            let mut s = scene.clone();
            sweep::apply_params(&mut s, pp)?;
            Prepared::with_scene(base.case.clone(), s)?
        }
        None if physical => {
            return Err(Error::Input(format!(
                "sweep: speed_rpm, clearance, viscosity and stiffness need a scene case, not {}",
                base.case.name
            )))
        }
        _ => base.clone(),
    };
    let flags = cli::SolverFlags {
        method: pp.method,
        rtol: pp.rtol,
        step: pp.step,
        controller: pp.controller,
        ..Default::default()
    };
    let mut req = RunRequest::new(prepared.options(&flags)?);
    req.trajectory_points = Some(0);
    let r = simulate(&prepared, &req)?;
    r.summary.write(dir)?;
    let v = serde_json::to_value(&r.summary)
        .map_err(|e| Error::Internal(format!("summary of point {}: {e}", point.id)))?;
    Ok(point_values(v))
}

/// A point's summary as merged-table values: `case` and `scene_sha256` dropped (the point's
/// parameters hold them), the solver settings actually used renamed `used.method`,
/// `used.controller`, `used.rtol`, `used.step` (the parameters say what was asked for), `atol`
/// left in the point's summary.json only.
pub fn point_values(mut summary: serde_json::Value) -> PointResult {
    if let Some(o) = summary.as_object_mut() {
        for k in ["case", "scene_sha256", "atol"] {
            o.remove(k);
        }
        for k in ["method", "controller", "rtol", "step"] {
            if let Some(v) = o.remove(k) {
                o.insert(format!("used.{k}"), v);
            }
        }
    }
    PointResult::flatten(&summary)
}

/// `lash sweep` with a point runner: loads and checks the sweep file, runs the shard's
/// unfinished points in parallel (`--jobs`), a progress bar when standard error is a terminal,
/// and prints one line of counts. The output directory defaults to `out/sweep/STEM`.
pub fn sweep_command<F>(a: &SweepArgs, runner: F) -> Result<SweepReport, Error>
where
    F: Fn(&SweepPoint, &Path) -> Result<PointResult, Error> + Sync,
{
    let spec = sweep::SweepSpec::load(&a.file)?;
    let points = spec.points()?;
    let out = a.out.clone().unwrap_or_else(|| {
        let stem = a
            .file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "sweep".into());
        default_out("sweep", &stem)
    });
    let opts = SweepOptions {
        jobs: a.jobs,
        shard: a.shard.unwrap_or(Shard::ALL),
        progress: std::io::stderr().is_terminal(),
    };
    let report = sweep::run_sweep(&points, &out, &opts, runner)?.into_result()?;
    eprintln!(
        "sweep: shard {} of {} points: {} ran, {} solver failures, {} already done; results in {}",
        opts.shard,
        points.len(),
        report.ok,
        report.solver_failed,
        report.skipped,
        out.display()
    );
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::MergeArgs;

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
            };
            let r = sweep_command(&a, runner).unwrap();
            assert_eq!((r.selected, r.ok), (3, 3));
        }
        execute(Some(Command::Merge(MergeArgs {
            dirs: vec![out.clone()],
            out: None,
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

    #[test]
    fn default_out_is_per_command_and_case() {
        assert_eq!(
            default_out("run", "testset:hires"),
            PathBuf::from("out/run/testset_hires")
        );
    }
}
