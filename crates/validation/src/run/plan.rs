//! What a run is asked to do (RunRequest) and the checks of a request against its case before
//! anything runs; the trajectory's output grid.
//!
//! Checks before a run (exit 2, naming the field or option; nothing runs):
//!
//! ```text
//! step          RK4's step longer than the run                                → step
//! trajectory    more than MAX_TRAJECTORY_ROWS rows                            → samples_per_
//!                                                                    revolution, output_every
//! time axis     16 ε max(|t_start|, |t_end|) (the smallest step f64 allows there) above
//!               TIME_RESOLUTION × the shortest time the run must resolve: the trajectory's
//!               and the metrics grid's spacing, h_max, the RK4 step, span/100 → t_start,
//!               t_end or revolutions (t_start = 1e15 s: steps ≥ 3.6 s)
//! driver angle  16 ε max|θ₀ + ω t| over the run above TIME_RESOLUTION × |ω| × that shortest
//!               time → joints[i].theta0 (θ₀ = 1e17 rad: angles 16 rad apart)
//! deadline      RunRequest::deadline (a command's budget from its start) already past
//!               → BudgetExhausted (exit 3); otherwise the integration gets what is left
//! ```
//!
//! Source: docs/outputs.md (`trajectory.csv`, "Exit codes of `lash`").

use std::time::Instant;

use lash_solver::{SolveError, SolverOptions};

use crate::error::{Error, OptionError};
use crate::report::metrics::GRID_POINTS;
use crate::report::trajectory::fmt_num;
use crate::run::prepare::Prepared;
use lash_model::MetricsWindow;

/// Longest trajectory a run writes, rows: beyond it a run is refused (exit 2) and asks to be
/// thinned. At the press's 47 columns a row is about 1 KB of CSV, so this is about 100 GB, a
/// file no script reads whole.
pub(crate) const MAX_TRAJECTORY_ROWS: u64 = 100_000_000;

/// The steps the f64 time axis must resolve: 16 ε |t| (the smallest step the solvers take at
/// time t, `lash_solver` step floor) must stay below this fraction of the shortest time the
/// run must resolve (module doc, "Checks before a run").
pub(crate) const TIME_RESOLUTION: f64 = 1e-3;

/// Default trajectory rows per crank revolution.
pub(crate) const SAMPLES_PER_REVOLUTION: usize = 2000;

/// What to run and what to record.
///
/// ```text
/// opts (method, tolerances, …; opts.output is ignored: the grids below are recorded),
/// t_end override, trajectory grid, extra output times, energy on/off, events kept,
/// the whole run's wall-clock deadline
/// trajectory grid: trajectory_points (a total, both ends) | output_every DT | samples per
///   revolution N (default 2000) | 4001 points without a crank driver
/// ```
///
/// Source: docs/outputs.md (`trajectory.csv`, `metrics`, `energy`).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RunRequest {
    /// Solver options (from [`Prepared::options`]). Their `max_wall_time` counts from the
    /// start of the integration unless `deadline` is given.
    pub opts: SolverOptions,
    /// End time override, s (mechanisms only). None = the scene's.
    pub t_end: Option<f64>,
    /// Points of the trajectory grid (uniform over the whole run, both ends); Some(0) = no
    /// trajectory. Overrides `output_every` and `samples_per_revolution`. Test problems
    /// record every accepted step instead.
    pub trajectory_points: Option<usize>,
    /// Spacing of the trajectory grid, s: t_start + k·DT, and t_end (mechanisms).
    pub output_every: Option<f64>,
    /// Trajectory rows per crank revolution (scenes with a crank driver); None = 2000.
    pub samples_per_revolution: Option<usize>,
    /// Further output times (sorted, inside the run), sampled like the others.
    pub extra_times: Vec<f64>,
    /// Whether to integrate the power terms for the energy balance (mechanisms only).
    pub energy: bool,
    /// Whether [`RunResult::events`] keeps every event of the run; false: only those of the
    /// metrics window (memory independent of the run's length).
    pub keep_events: bool,
    /// Wall-clock deadline of the whole run (a command's `max_wall_time` counted from its
    /// start): the integration gets what is left, and a run past it fails with
    /// `BudgetExhausted`.
    pub deadline: Option<Instant>,
    /// The metrics window (`--window`); None: the last revolution of a crank, else the whole
    /// run (crate::run::window).
    pub window: Option<MetricsWindow>,
}

impl RunRequest {
    /// A request with these options and the defaults: the scene's end time, the default
    /// trajectory grid, no extra times, energy on, every event kept, no deadline.
    pub(crate) fn new(opts: SolverOptions) -> RunRequest {
        RunRequest {
            opts,
            t_end: None,
            trajectory_points: None,
            output_every: None,
            samples_per_revolution: None,
            extra_times: Vec::new(),
            energy: true,
            keep_events: true,
            deadline: None,
            window: None,
        }
    }
}

/// Uniform grid of `n ≥ 2` points over [a, b], both ends exact.
pub(crate) fn uniform_grid(a: f64, b: f64, n: usize) -> Vec<f64> {
    let g = Grid::uniform(a, b, n.max(2));
    (0..g.n).map(|i| g.time(i)).collect()
}

/// The trajectory's output times, computed one at a time (never held as a whole).
///
/// ```text
/// uniform:  t_i = a + (b − a) i/(n − 1), t_{n−1} = b
/// spaced:   t_i = a + i·dt for i < n − 1, t_{n−1} = b
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Grid {
    pub(crate) a: f64,
    pub(crate) b: f64,
    pub(crate) n: usize,
    pub(crate) dt: Option<f64>,
}

impl Grid {
    fn uniform(a: f64, b: f64, n: usize) -> Grid {
        Grid { a, b, n, dt: None }
    }

    pub(crate) fn time(&self, i: usize) -> f64 {
        if i + 1 == self.n {
            return self.b;
        }
        match self.dt {
            Some(dt) => self.a + dt * i as f64,
            None => self.a + (self.b - self.a) * i as f64 / (self.n - 1) as f64,
        }
    }

    /// The shortest spacing of the grid (∞ with fewer than two points).
    fn spacing(&self) -> f64 {
        match (self.n, self.dt) {
            (0 | 1, _) => f64::INFINITY,
            (_, Some(dt)) => dt.min(self.b - self.time(self.n - 2)),
            (n, None) => (self.b - self.a) / (n - 1) as f64,
        }
    }
}

/// The solver options of a request: its `max_wall_time` cut to what is left before its
/// deadline; a deadline already past is `BudgetExhausted` at (t0, y0).
pub(crate) fn options_within(
    req: &RunRequest,
    t0: f64,
    y0: &[f64],
) -> Result<SolverOptions, Error> {
    let mut opts = req.opts.clone();
    if let Some(d) = req.deadline {
        let left = d.saturating_duration_since(Instant::now()).as_secs_f64();
        if !(left > 0.0) {
            return Err(Error::Solver(SolveError::BudgetExhausted {
                t: t0,
                y: y0.to_vec(),
                reason: format!(
                    "wall-clock budget of {} s used before the integration started",
                    opts.max_wall_time.unwrap_or_default()
                ),
            }));
        }
        opts.max_wall_time = Some(left);
    }
    Ok(opts)
}

pub(crate) fn check_times(times: &[f64], t0: f64, t_end: f64) -> Result<(), Error> {
    if times.windows(2).any(|w| !(w[1] >= w[0]))
        || times
            .iter()
            .any(|t| !(t.is_finite() && *t >= t0 && *t <= t_end))
    {
        return Err(Error::Internal(format!(
            "extra output times must be sorted and inside [{t0}, {t_end}]"
        )));
    }
    Ok(())
}

/// The checks of a request against its case before anything runs (module doc, "Checks before
/// a run"); returns the trajectory grid.
pub(crate) fn plan_run(p: &Prepared, req: &RunRequest, t0: f64, t_end: f64) -> Result<Grid, Error> {
    let o = &req.opts;
    let span = t_end - t0;
    let period = p.period();
    if let Some(h) = o.step.filter(|_| o.method.is_fixed_step()) {
        if h > span {
            return Err(OptionError::leading(
                "step",
                format!(
                    " {} s is longer than the run ({} s from t_start {} s to t_end {} s)",
                    fmt_num(h),
                    fmt_num(span),
                    fmt_num(t0),
                    fmt_num(t_end)
                ),
            )
            .into());
        }
    }
    if p.info.is_none() {
        return Ok(Grid::uniform(t0, t_end, 0));
    }
    // The trajectory grid.
    if let Some(n) = req.samples_per_revolution {
        if period.is_none() {
            return Err(OptionError::leading(
                "samples_per_revolution",
                format!(" needs a crank driver, and {} has none", p.case.name),
            )
            .text("; ")
            .name("output_every")
            .text(" spaces rows in time")
            .into());
        }
        if n == 0 {
            return Err(OptionError::leading("samples_per_revolution", " must be >= 1").into());
        }
    }
    if let Some(dt) = req.output_every {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(OptionError::leading(
                "output_every",
                format!(" must be finite and > 0, got {dt}"),
            )
            .into());
        }
    }
    let rows: f64 = match (req.trajectory_points, req.output_every, period) {
        (Some(n), _, _) => n as f64,
        (None, Some(dt), _) => (span / dt * (1.0 - 1e-9)).ceil().max(1.0) + 1.0,
        (None, None, Some(t)) => {
            let n = req.samples_per_revolution.unwrap_or(SAMPLES_PER_REVOLUTION) as f64;
            1.0 + (n * span / t).round().max(1.0)
        }
        (None, None, None) => (2 * (GRID_POINTS - 1) + 1) as f64,
    };
    if rows > MAX_TRAJECTORY_ROWS as f64 {
        let thin = if period.is_some() {
            OptionError::new("samples_per_revolution")
                .text(format!(
                    "the trajectory would have {} rows, more than the {} lash writes: thin it \
                     with ",
                    fmt_count(rows),
                    fmt_count(MAX_TRAJECTORY_ROWS as f64)
                ))
                .name("samples_per_revolution")
                .text(" or ")
        } else {
            OptionError::new("output_every").text(format!(
                "the trajectory would have {} rows, more than the {} lash writes: thin it with ",
                fmt_count(rows),
                fmt_count(MAX_TRAJECTORY_ROWS as f64)
            ))
        };
        return Err(thin
            .name("output_every")
            .text(", or shorten ")
            .name("t_end")
            .into());
    }
    let n = rows as usize;
    let grid = match (req.trajectory_points, req.output_every) {
        (None, Some(dt)) => Grid {
            a: t0,
            b: t_end,
            n,
            dt: Some(dt),
        },
        _ => Grid::uniform(t0, t_end, n),
    };
    // The time axis: f64 must resolve the shortest time the run must resolve.
    let mut need = vec![(grid.spacing(), "the trajectory's spacing".to_string())];
    if let Some(t) = period {
        need.push((
            t / (GRID_POINTS - 1) as f64,
            "the metrics grid's spacing T/2000".into(),
        ));
    }
    if o.h_max.is_finite() {
        need.push((o.h_max, "h_max".into()));
    }
    if o.h_max_near_events.is_finite() && !o.method.is_fixed_step() {
        need.push((o.h_max_near_events, "the step limit near contact".into()));
    }
    if let Some(h) = o.step.filter(|_| o.method.is_fixed_step()) {
        need.push((h, "the RK4 step".into()));
    }
    need.push((span / 100.0, "a hundredth of the run".into()));
    let (need, what) = need
        .into_iter()
        .fold((f64::INFINITY, String::new()), |a, b| {
            if b.0 < a.0 {
                b
            } else {
                a
            }
        });
    let floor_at = |t: f64| 16.0 * f64::EPSILON * t.abs();
    let floor = floor_at(t0).max(floor_at(t_end));
    if floor > TIME_RESOLUTION * need {
        // Blame t_start when it alone is too far out, else the end time.
        let start = floor_at(t0) > TIME_RESOLUTION * need;
        let text = format!(
            " = {:.6e} s is too far from 0 for f64 time: steps there are at least {:.2e} s \
             (16 ε |t|), but the run must resolve {:.2e} s ({what}); shift the scene's times \
             toward 0",
            if start { t0 } else { t_end },
            floor,
            need
        );
        let scene_field =
            |field: &str| Err(Error::Input(format!("case {}: {field}{text}", p.case.name)));
        return if start {
            scene_field("t_start")
        } else if req.t_end.is_some() {
            Err(OptionError::leading("t_end", text).into())
        } else if p.scene().is_some_and(|s| s.t_end.is_none()) {
            scene_field("revolutions (t_end)")
        } else {
            scene_field("t_end")
        };
    }
    // The angle axis of each driver: θ(t) = θ₀ + ω t must resolve the angle the crank turns in
    // the shortest time the run must resolve, as the time axis does (issue 23: θ₀ = 1e17 rad,
    // where f64's spacing is 16 rad, froze the crank and still exited 0).
    if let Some(scene) = p.scene() {
        for (i, j) in scene.joints.iter().enumerate() {
            let lash_model::scene::JointSpec::Driver(d) = j else {
                continue;
            };
            let w = d.omega_rad_s();
            if w == 0.0 || !w.is_finite() {
                continue;
            }
            let theta_max = (d.theta0 + w * t0).abs().max((d.theta0 + w * t_end).abs());
            let floor = floor_at(theta_max);
            let turn = w.abs() * need;
            if floor > TIME_RESOLUTION * turn {
                return Err(Error::Input(format!(
                    "case {}: joints[{i}].theta0 = {:.6e} rad: the driver's angle reaches \
                     {:.3e} rad, where f64 angles are at least {:.2e} rad apart (16 ε |θ|), but \
                     the run must resolve {:.2e} rad (ω × {what}); give theta0 modulo 2π",
                    p.case.name, d.theta0, theta_max, floor, turn
                )));
            }
        }
    }
    Ok(grid)
}

/// A count in words a reader takes in at once: 5e9, 2.5e8, 40000.
fn fmt_count(x: f64) -> String {
    if x < 1e6 {
        format!("{x:.0}")
    } else {
        let s = format!("{x:.1e}");
        s.replace(".0e", "e")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_grid_has_exact_ends() {
        let g = uniform_grid(0.1, 0.9, 7);
        assert_eq!((g.len(), g[0], g[6]), (7, 0.1, 0.9));
        assert!((g[3] - 0.5).abs() < 1e-15);
    }
}
