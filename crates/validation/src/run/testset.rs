//! A run of a built-in test problem (the IVP Test Set's): one trajectory row per accepted step,
//! the final state and its error against the problem's reference solution.
//!
//! Source: docs/outputs.md (`final_state`, `reference_error`); `lash_solver::testset`.

use lash_solver::{testset, EventHit, Solution};

use crate::error::Error;
use crate::report::trajectory::{Columns, Header, TrajectorySink};
use crate::run::drive::drive;
use crate::run::drive::empty_solution;
use crate::run::drive::Observer;
use crate::run::plan::check_times;
use crate::run::plan::options_within;
use crate::run::plan::plan_run;
use crate::run::plan::RunRequest;
use crate::run::prepare::Prepared;
use crate::run::quadrature::Own;
use crate::run::result::RunResult;

/// The observer of a test problem: a row per accepted step (the start included), states at
/// the extra times.
struct TestSetRun<'a> {
    header: Header,
    sink: &'a mut dyn TrajectorySink,
    rows: usize,
    row: Vec<f64>,
    extra_times: &'a [f64],
    next: usize,
    extra_states: Solution,
}

impl TestSetRun<'_> {
    fn push(&mut self, t: f64, y: &[f64]) -> Result<(), Error> {
        self.row.clear();
        self.row.push(t);
        self.row.extend([f64::NAN; 10]);
        self.row.push(0.0);
        self.row.push(f64::NAN);
        self.row.extend_from_slice(y);
        self.header.check(&self.row)?;
        self.sink.row(&self.row)?;
        self.rows += 1;
        Ok(())
    }
}

impl Observer for TestSetRun<'_> {
    fn next_time(&self) -> Option<f64> {
        self.extra_times.get(self.next).copied()
    }
    fn output(&mut self, t: f64, y: &[f64]) -> Result<(), Error> {
        self.extra_states.t.push(t);
        self.extra_states.y.extend_from_slice(y);
        self.next += 1;
        Ok(())
    }
    fn step(
        &mut self,
        _: f64,
        tb: f64,
        _: bool,
        y: &[f64],
        _: Option<Own>,
        _: &dyn Fn(f64, &mut [f64]),
    ) -> Result<(), Error> {
        self.push(tb, y)
    }
    fn event(&mut self, _: EventHit) {}
}

pub(crate) fn simulate_testset(
    p: &Prepared,
    req: &RunRequest,
    t0: f64,
    t_end: f64,
    sink: &mut dyn TrajectorySink,
) -> Result<RunResult, Error> {
    let prob = p
        .test_problem()
        .ok_or_else(|| Error::Internal("not a test problem".into()))?;
    check_times(&req.extra_times, t0, t_end)?;
    plan_run(p, req, t0, t_end)?;
    let opts = &options_within(req, t0, &prob.y0)?;
    let n = prob.y0.len();
    let mut fixed = [false; 13];
    fixed[0] = true;
    fixed[11] = true;
    let header = Header::new(fixed, (0..n).map(|i| format!("y{i}")).collect())?;
    sink.start(&header)?;
    let mut obs = TestSetRun {
        header,
        sink,
        rows: 0,
        row: Vec::with_capacity(13 + n),
        extra_times: &req.extra_times,
        next: 0,
        extra_states: empty_solution(n),
    };
    obs.push(t0, &prob.y0)?;
    let d = drive(&*prob.system, t0, t_end, &prob.y0, opts, &mut obs)?;
    let mut extra_states = obs.extra_states;
    extra_states.stats = d.stats;
    extra_states.t_final = d.t_final;
    extra_states.y_final = d.y_final.clone();
    let mut summary = d.summary(p, opts, t_end);
    let err = testset::reference_error(&d.y_final, &prob.reference, prob.atol);
    if !err.is_finite() {
        return Err(Error::Internal(format!(
            "{}: reference error is not finite (final state {:?})",
            p.case.name, d.y_final
        )));
    }
    summary.final_state = Some(d.y_final.clone());
    summary.reference_error = Some(err);
    Ok(RunResult {
        summary,
        window: Vec::new(),
        trajectory: Columns::new(),
        trajectory_rows: obs.rows,
        extra: Vec::new(),
        extra_states,
        events: Vec::new(),
        event_names: Vec::new(),
        ideal: None,
    })
}
