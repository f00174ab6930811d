//! `lash compare` and `lash work-precision`: the methods against a converged reference.
//!
//! Source: docs/outputs.md ("`lash compare CASE`", "`lash work-precision CASE`").

use std::path::PathBuf;
use std::time::Instant;

use lash_solver::{ControllerKind, Method};

use crate::commands::default_out;
use crate::compare::reference::{
    self as compare, Compared, Comparison, Reference, COMPARE_TOLERANCES,
};
use crate::compare::workprecision::{WorkPrecisionPlan, WpRun, WpTable, DEFAULT_TARGETS};
use crate::error::{Error, Message, OptionError};
use crate::progress::Progress;
use crate::run::case::Case;
use crate::run::prepare::Prepared;
use crate::store::io::Written;

/// The RK4 steps of a comparison: the given ones, else the largest stable step h and h/2,
/// h/4 (`halvings` + 1 steps) for every scene case (compare::Rk4Search), none for test
/// problems.
fn rk4_steps(
    p: &Prepared,
    given: &Option<Vec<f64>>,
    t_end: Option<f64>,
    halvings: usize,
    progress: &dyn Progress,
) -> Result<Vec<f64>, Error> {
    match given {
        Some(v) => Ok(v.clone()),
        None if p.scene().is_some() => {
            let clock = Instant::now();
            let h = compare::stable_rk4_step(p, t_end)?;
            let rule = compare::Rk4Search::of(p, t_end)?.rule;
            progress.finished(
                &format!("{}: largest stable RK4 step {h:e} s ({rule})", p.case.name),
                clock.elapsed().as_secs_f64(),
            );
            Ok((0..=halvings).map(|k| h / f64::from(1u32 << k)).collect())
        }
        None => Ok(Vec::new()),
    }
}

/// What to compare: one case, every method.
///
/// ```text
/// case [tolerances] [steps] [t_end] [out]
/// ```
///
/// Source: docs/outputs.md ("`lash compare CASE`").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CompareOptions {
    /// The case: a scene file (JSON) or `testset:NAME`.
    pub case: String,
    /// Relative tolerances of the adaptive methods; None = `COMPARE_TOLERANCES`.
    pub tolerances: Option<Vec<f64>>,
    /// RK4 steps, s; None = the largest stable step h of the case and h/2, h/4 (every scene
    /// case), none for test problems.
    pub steps: Option<Vec<f64>>,
    /// End time override, s (scene cases only).
    pub t_end: Option<f64>,
    /// Wall-clock budget of each integration (the reference and every row), s; a row over it
    /// fails with "budget exhausted". None = no budget.
    pub max_wall_time: Option<f64>,
    /// Where errors are measured (`--window`); None = the case's own rule (docs/outputs.md).
    pub window: Option<lash_model::MetricsWindow>,
    /// Output directory; None = `out/compare/CASE`.
    pub out: Option<PathBuf>,
    /// Formulations compared side by side (docs/model.md §12): every row of the comparison
    /// (RK4 steps and adaptive settings) is run with each, against one reference (the case's
    /// own formulation's), and names it. None = the case's own only.
    pub formulations: Option<Vec<lash_model::FormulationName>>,
}

/// The passes of a comparison: one per listed formulation (the case with it, and its name
/// for the rows), else the case as it is.
fn formulation_passes(
    p: &Prepared,
    formulations: &Option<Vec<lash_model::FormulationName>>,
) -> Result<Vec<(Prepared, Option<String>)>, Error> {
    match formulations {
        Some(fs) => fs
            .iter()
            .map(|&f| Ok((p.clone().with_formulation(f)?, Some(f.to_string()))))
            .collect(),
        None => Ok(vec![(p.clone(), None)]),
    }
}

/// Compares the methods on one case: RK4 at several steps, every embedded pair and every stiff
/// method at each tolerance, against the case's reference; writes compare.md and
/// compare.json. Notes the reference and a derived RK4 step. With `formulations`, the whole
/// set of rows once per formulation, against the one reference.
pub fn compare(o: &CompareOptions, progress: &dyn Progress) -> Result<Written<Comparison>, Error> {
    let mut p = Prepared::load_spec(&o.case, None)?;
    p.max_wall_time = o.max_wall_time;
    let passes = formulation_passes(&p, &o.formulations)?;
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| default_out("compare", &p.case.name));
    let tolerances = o
        .tolerances
        .clone()
        .unwrap_or_else(|| COMPARE_TOLERANCES.to_vec());
    let derive = o.steps.is_none() && p.scene().is_some();
    let n_steps = o
        .steps
        .as_ref()
        .map_or(if derive { 3 } else { 0 }, Vec::len);
    let adaptive = Method::ALL.iter().filter(|m| !m.is_fixed_step()).count();
    progress.started(
        "runs",
        1 + usize::from(derive) + passes.len() * (n_steps + adaptive * tolerances.len()),
    );
    let clock = Instant::now();
    let reference = Reference::compute_in(&p, o.t_end, o.window)?;
    progress.finished(
        &format!("{}: reference {}", p.case.name, reference.how),
        clock.elapsed().as_secs_f64(),
    );
    let steps = rk4_steps(&p, &o.steps, o.t_end, 2, progress)?;
    let mut runs = Vec::new();
    let mut push = |c: Compared, secs: f64| {
        progress.finished(&run_line(&c), secs);
        runs.push(c);
    };
    for (pf, tag) in &passes {
        let named = |mut c: Compared| {
            c.formulation = tag.clone();
            c
        };
        for &h in &steps {
            let t = Instant::now();
            let c = compare::compare_one(pf, &reference, Method::Rk4, None, Some(h), None)?.0;
            push(named(c), t.elapsed().as_secs_f64());
        }
        for m in Method::ALL.into_iter().filter(|m| !m.is_fixed_step()) {
            for &r in &tolerances {
                let t = Instant::now();
                let c = compare::compare_one(pf, &reference, m, Some(r), None, None)?.0;
                push(named(c), t.elapsed().as_secs_f64());
            }
        }
    }
    let c = Comparison {
        case: p.case.name.clone(),
        reference: reference.how.clone(),
        reference_agreement: reference.agreement.clone(),
        window: reference.window.clone(),
        t_end: reference.t_end,
        error_measure: reference.measure(),
        runs,
    };
    let files = c.write(&out)?;
    Ok(Written {
        result: c,
        dir: out,
        files,
    })
}

/// What to measure: error against cost on one case.
///
/// ```text
/// case [methods] [tolerances] [steps] [controllers] [t_end] [out]   (None = the default)
/// ```
///
/// Source: docs/outputs.md ("`lash work-precision CASE`").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WorkPrecisionOptions {
    /// The case: a scene file (JSON) or `testset:NAME`.
    pub case: String,
    /// Methods; None = every method of this build.
    pub methods: Option<Vec<Method>>,
    /// Relative tolerances of the adaptive methods (atol as in the case); None = the
    /// defaults (`crate::compare::workprecision::DEFAULT_TOLERANCES`).
    pub tolerances: Option<Vec<f64>>,
    /// Steps of the fixed-step methods, s; None = derived from the case.
    pub steps: Option<Vec<f64>>,
    /// Controllers compared on one adaptive method; None = all.
    pub controllers: Option<Vec<ControllerKind>>,
    /// End time override, s (scene cases only).
    pub t_end: Option<f64>,
    /// Wall-clock budget of each integration (the reference and every run), s; a run over it
    /// fails with "budget exhausted". None = no budget.
    pub max_wall_time: Option<f64>,
    /// Output directory; None = `out/work-precision/CASE`.
    pub out: Option<PathBuf>,
    /// Formulations compared side by side (docs/model.md §12): every run of the plan is made
    /// with each, against one reference (the case's own formulation's), and its row names
    /// it. None = the case's own only.
    pub formulations: Option<Vec<lash_model::FormulationName>>,
}

impl WorkPrecisionOptions {
    /// Checks the lists against each other and applies the defaults
    /// (`WorkPrecisionPlan::new`).
    pub fn plan(&self) -> Result<WorkPrecisionPlan, Error> {
        WorkPrecisionPlan::new(
            self.methods.as_deref(),
            self.tolerances.as_deref(),
            self.steps.as_deref(),
            self.controllers.as_deref(),
        )
    }
}

/// What [`work_precision`] measured: the table and how its reference was obtained.
///
/// Source: this module.
#[derive(Debug)]
pub struct WorkPrecisionResult {
    /// The runs and the cheapest per target.
    pub table: WpTable,
    /// How the reference was obtained.
    pub reference: String,
}

/// Error against cost on one case: every method × tolerance and RK4 × step, and the
/// controllers compared on one method of ours (`WorkPrecisionPlan::controller_method`),
/// against the case's reference; writes the markdown and JSON tables and the log–log figures.
/// Notes the reference, a derived RK4 step (or that RK4 is left out) and each run as it ends.
pub fn work_precision(
    o: &WorkPrecisionOptions,
    progress: &dyn Progress,
) -> Result<Written<WorkPrecisionResult>, Error> {
    let case = Case::load(&o.case, None)?;
    let plan = o.plan()?;
    let mut p = Prepared::load(case)?;
    p.max_wall_time = o.max_wall_time;
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| default_out("work-precision", &p.case.name));
    let wants_rk4 = plan.methods.iter().any(|m| m.is_fixed_step());
    if wants_rk4 && plan.steps.is_none() && p.scene().is_none() {
        if o.methods.is_some() {
            return Err(OptionError::new("steps")
                .text("rk4 needs ")
                .name("steps")
                .text(format!(
                    " for {} (a test problem: no scene to derive them from)",
                    p.case.name
                ))
                .into());
        }
        progress.note(
            &Message::default()
                .text(format!("{}: rk4 left out (give ", p.case.name))
                .name("steps")
                .text(" to include it)"),
        );
    }
    let ctl_method = plan.controller_method();
    let derive = wants_rk4 && plan.steps.is_none() && p.scene().is_some();
    let n_steps = match &plan.steps {
        Some(v) => v.len(),
        None if derive => 4,
        None => 0,
    };
    let total_runs: usize = plan
        .methods
        .iter()
        .map(|&m| {
            if m.is_fixed_step() {
                n_steps
            } else if Some(m) == ctl_method && !plan.controllers.is_empty() {
                plan.controllers.len() * plan.tolerances.len()
            } else {
                plan.tolerances.len()
            }
        })
        .sum();
    let n_passes = o.formulations.as_ref().map_or(1, |f| f.len());
    progress.started("runs", 1 + usize::from(derive) + total_runs * n_passes);
    let clock = Instant::now();
    let reference = Reference::compute(&p, o.t_end)?;
    progress.finished(
        &format!("{}: reference {}", p.case.name, reference.how),
        clock.elapsed().as_secs_f64(),
    );
    let steps = if wants_rk4 {
        rk4_steps(&p, &plan.steps, o.t_end, 3, progress)?
    } else {
        Vec::new()
    };
    let mut runs = Vec::new();
    let mut clock = Instant::now();
    let mut tag: Option<String> = None;
    let mut push = |c: Compared, tag: &Option<String>| {
        progress.finished(&run_line(&c), clock.elapsed().as_secs_f64());
        clock = Instant::now();
        runs.push(WpRun {
            formulation: tag.clone(),
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
    // One pass per formulation (the case's own when none are listed), every pass against
    // the same reference.
    let passes: Vec<Option<lash_model::FormulationName>> = match &o.formulations {
        Some(fs) => fs.iter().map(|&f| Some(f)).collect(),
        None => vec![None],
    };
    for f in passes {
        let pf = match f {
            Some(f) => {
                tag = Some(f.to_string());
                p.clone().with_formulation(f)?
            }
            None => p.clone(),
        };
        let p = &pf;
        for &m in &plan.methods {
            if m.is_fixed_step() {
                for &h in &steps {
                    push(
                        compare::compare_one(p, &reference, m, None, Some(h), None)?.0,
                        &tag,
                    );
                }
            } else if Some(m) == ctl_method && !plan.controllers.is_empty() {
                for &c in &plan.controllers {
                    for &r in &plan.tolerances {
                        let c = compare::compare_one(p, &reference, m, Some(r), None, Some(c))?;
                        push(c.0, &tag);
                    }
                }
            } else {
                for &r in &plan.tolerances {
                    push(
                        compare::compare_one(p, &reference, m, Some(r), None, None)?.0,
                        &tag,
                    );
                }
            }
        }
    }
    let mut table = WpTable::new(&p.case.name, runs, &DEFAULT_TARGETS)?;
    table.error_measure = reference.measure();
    let files = table.write(&out)?;
    Ok(Written {
        result: WorkPrecisionResult {
            table,
            reference: reference.how,
        },
        dir: out,
        files,
    })
}

/// One line on a comparison run: label, setting, error, work.
fn run_line(c: &Compared) -> String {
    format!(
        "{} {}: error {}, {} RHS evaluations, {:.3} s",
        c.label(),
        c.setting(),
        c.error.map_or("failed".into(), |e| format!("{e:.3e}")),
        c.rhs_evals,
        c.wall_time_s
    )
}

#[cfg(test)]
mod tests {
    //! `--formulations`: one pass of the plan per formulation, every row naming its
    //! formulation, every error against the one reference (the case's own formulation's).
    use super::*;
    use crate::progress::NoProgress;
    use lash_model::FormulationName;

    #[test]
    fn formulations_are_compared_side_by_side_against_one_reference() {
        // A02 N = 1 over 1 s: the first horizontal (singular) position is at t = 0.708 s.
        let out = std::env::temp_dir().join(format!("lash-wp-formulations-{}", std::process::id()));
        let o = WorkPrecisionOptions {
            case: concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../../cases/iftomm/a02_n1.json"
            )
            .into(),
            methods: Some(vec![Method::Dop853]),
            tolerances: Some(vec![1e-5, 1e-9]),
            controllers: Some(vec![ControllerKind::Pi]),
            t_end: Some(1.0),
            out: Some(out.clone()),
            formulations: Some(vec![
                FormulationName::LagrangeBaumgarte,
                FormulationName::AugmentedLagrangian,
            ]),
            ..Default::default()
        };
        let w = work_precision(&o, &NoProgress).unwrap();
        let _ = std::fs::remove_dir_all(&out);
        let runs = &w.result.table.runs;
        let tags: Vec<_> = runs.iter().map(|r| r.formulation.as_deref()).collect();
        assert_eq!(
            tags,
            [
                Some("lagrange_baumgarte"),
                Some("lagrange_baumgarte"),
                Some("augmented_lagrangian"),
                Some("augmented_lagrangian")
            ]
        );
        assert_eq!(runs[0].label(), "dop853/pi [lagrange_baumgarte]");
        // Lagrange–Baumgarte cannot pass the singular position: its rows are failures naming
        // it (issue 26), not numbers.
        for r in &runs[..2] {
            assert!(r.error.is_none(), "{r:?}");
            let f = r.failure.as_deref().unwrap_or_default();
            assert!(f.contains("singular configuration"), "{f}");
        }
        // The augmented Lagrangian converges to the reference: the error falls with rtol, to
        // below 1e-6 at rtol 1e-9 (B0 moves 1 m: a branch switch would be ~1).
        let (loose, tight) = (runs[2].error.unwrap(), runs[3].error.unwrap());
        assert!(tight < 1e-6 && tight < loose, "{loose:e} {tight:e}");
    }

    #[test]
    fn compare_puts_formulations_side_by_side() {
        // A02 N = 1 over 1 s, through its first horizontal position at t = 0.708 s: every row
        // of `lash compare` (one RK4 step, every adaptive method at rtol 1e-8) once per
        // formulation, against the case's own reference (augmented Lagrangian).
        let out =
            std::env::temp_dir().join(format!("lash-cmp-formulations-{}", std::process::id()));
        let o = CompareOptions {
            case: concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../../cases/iftomm/a02_n1.json"
            )
            .into(),
            tolerances: Some(vec![1e-8]),
            steps: Some(vec![1e-3]),
            t_end: Some(1.0),
            out: Some(out.clone()),
            formulations: Some(vec![
                FormulationName::LagrangeBaumgarte,
                FormulationName::AugmentedLagrangian,
            ]),
            ..Default::default()
        };
        let c = compare(&o, &NoProgress).unwrap().result;
        let md = std::fs::read_to_string(out.join("compare.md")).unwrap();
        let js = std::fs::read_to_string(out.join("compare.json")).unwrap();
        let _ = std::fs::remove_dir_all(&out);
        let adaptive = Method::ALL.iter().filter(|m| !m.is_fixed_step()).count();
        assert_eq!(c.runs.len(), 2 * (1 + adaptive));
        let (lb, al) = c.runs.split_at(1 + adaptive);
        for r in lb {
            assert_eq!(r.formulation.as_deref(), Some("lagrange_baumgarte"));
        }
        for r in al {
            assert_eq!(r.formulation.as_deref(), Some("augmented_lagrangian"));
        }
        assert_eq!(lb[0].label(), "rk4 [lagrange_baumgarte]");
        assert!(
            md.contains("| rk4 [augmented_lagrangian] | h 1e-3 |"),
            "{md}"
        );
        assert!(js.contains("\"formulation\": \"augmented_lagrangian\""));
        // Lagrange–Baumgarte cannot pass the singular position with any method: its rows are
        // failures naming it (issue 26), not numbers.
        for r in lb {
            let f = r.failure.as_deref().unwrap_or_default();
            assert!(
                r.error.is_none() && f.contains("singular configuration"),
                "{r:?}"
            );
        }
        // The augmented Lagrangian runs through it with every method; at rtol 1e-8 the error
        // of B0 (which moves 1 m; a branch switch would be ~1) is far below 1e-4, and RK4 at
        // 1 ms (error ~ h⁴) below 1e-6.
        for r in al {
            let e = r.error.unwrap_or_else(|| panic!("{r:?}"));
            assert!(e < 1e-4, "{}: {e:e}", r.label());
        }
    }
}
