//! The drive stage of `solve_ivp_core`: lash-solver's integrator stepped to the end, a
//! terminal event or a failure, recording the steps (or `t_eval`), the dense output and the
//! states before event hooks.
//!
//! Dense output: every step's interpolant is sampled at the m + 1 Chebyshev–Lobatto points of
//! its interval, m the degree of the method's dense output (`Method::dense_degree`, the
//! solver's table of method facts), which
//! reproduces it exactly (a polynomial of degree ≤ m is determined by m + 1 values);
//! python/lash/_ivp.py evaluates it by barycentric interpolation (Berrut & Trefethen, SIAM
//! Review 46(3) 501–517, 2004). The end nodes are the states themselves (the step's start,
//! after any hook; its end, before any hook), not values of the interpolant, so that the
//! solution passes through every recorded state exactly.

use pyo3::prelude::*;

use lash_solver::{Problem, SolveError, Stats, StepOutcome};

use super::parse::Parsed;
use super::system::PySystem;

/// θ_j = (1 − cos(π j / m)) / 2, j = 0..m: the Chebyshev–Lobatto points on [0, 1], ascending.
pub fn lobatto_nodes(m: usize) -> Vec<f64> {
    (0..=m)
        .map(|j| 0.5 * (1.0 - (std::f64::consts::PI * j as f64 / m as f64).cos()))
        .collect()
}

/// What the integration loop records.
#[derive(Default)]
pub struct Record {
    /// Output times (in t) and states (row-major).
    pub t: Vec<f64>,
    /// The states at `t`.
    pub y: Vec<f64>,
    /// Dense output: segment ends (in t) and values at the Lobatto nodes, (m + 1) · n each.
    pub seg_t0: Vec<f64>,
    /// The segments' right ends.
    pub seg_t1: Vec<f64>,
    /// Values at the nodes.
    pub seg_values: Vec<f64>,
    /// 1 when a terminal event stopped the run, else 0.
    pub status: i32,
    /// The solver's failure, if any.
    pub failure: Option<SolveError>,
    /// The solver's counters.
    pub stats: Stats,
}

/// Integrates `sys` as `p` says. An exception a callback raised comes back as `Err` (before
/// any solver error); a solver failure is recorded in [`Record::failure`] with what was
/// computed up to it; an options error or memory refused before the start is `Ok(Err(e))`
/// for the caller to raise.
pub fn drive(
    sys: &PySystem<'_>,
    p: &Parsed<'_>,
    nodes: &[f64],
) -> PyResult<Result<Record, SolveError>> {
    let problem = match Problem::new(sys, &p.opts) {
        Ok(problem) => problem,
        Err(e) => return sys.take_error().map_or(Ok(Err(e)), Err),
    };
    let dir = p.dir;
    let degree = nodes.len() - 1;
    let mut rec = Record::default();
    let push = |rec: &mut Record, s: f64, y: &[f64]| {
        rec.t.push(dir * s);
        rec.y.extend_from_slice(y);
    };
    let mut it = match problem.integrator(p.s0, p.s1, &p.y0) {
        Err(e) => {
            if let Some(err) = sys.take_error() {
                return Err(err);
            }
            if let SolveError::InvalidOptions(_) | SolveError::OutOfMemory(_) = e {
                return Ok(Err(e));
            }
            rec.failure = Some(e);
            return Ok(Ok(rec));
        }
        Ok(it) => it,
    };
    if let Some(err) = sys.take_error() {
        return Err(err);
    }
    let mut next_eval = 0usize;
    match &p.s_eval {
        Some(ts) => {
            while next_eval < ts.len() && ts[next_eval] <= p.s0 {
                push(&mut rec, ts[next_eval], &p.y0);
                next_eval += 1;
            }
        }
        None => push(&mut rec, p.s0, &p.y0),
    }
    let mut buf = vec![0.0; p.y0.len()];
    // The state at the start of the step (after any hook): the segment's first node, exactly
    // (diffsol's BDF interpolates its own start to rounding only, and `sol(t)` at a step's
    // time must be `y` there, as scipy's tests ask to 1e-15).
    let mut y_start = p.y0.clone();
    // Length of the last recorded dense-output segment.
    let mut last_len = 0.0f64;
    loop {
        let outcome = it.step();
        if let Some(err) = sys.take_error() {
            return Err(err);
        }
        let outcome = match outcome {
            Ok(o) => o,
            Err(e) => {
                rec.failure = Some(e);
                break;
            }
        };
        let s_now = it.t();
        let s_prev = it.t_prev();
        // The state before the hook, when a hook changed it at this event.
        let pre_hook = match outcome {
            StepOutcome::Event { .. } => sys.log.borrow_mut().pre_hook.take(),
            _ => None,
        };
        // A segment shorter than 1e-9 of the one before (an event located a few ulps after a
        // step end) is left out: its values at the nodes agree to rounding, and a
        // polynomial through them would extrapolate noise (scipy's test_duplicate_timestamps
        // evaluates the solution past such an event). The previous segment covers it, to
        // its own accuracy over 1e-9 of its length.
        let len = s_now - s_prev;
        if p.dense_output && len > 0.0 && len > 1e-9 * last_len {
            last_len = len;
            rec.seg_t0.push(dir * s_prev);
            rec.seg_t1.push(dir * s_now);
            for (j, th) in nodes.iter().enumerate() {
                if j == 0 {
                    rec.seg_values.extend_from_slice(&y_start);
                } else if j == degree {
                    // The right end: the state before any hook.
                    match &pre_hook {
                        Some(yp) => rec.seg_values.extend_from_slice(yp),
                        None => rec.seg_values.extend_from_slice(it.y()),
                    }
                } else {
                    it.interpolate(s_prev + th * (s_now - s_prev), &mut buf);
                    rec.seg_values.extend_from_slice(&buf);
                }
            }
        }
        match &p.s_eval {
            Some(ts) => {
                while next_eval < ts.len() && ts[next_eval] <= s_now {
                    let sq = ts[next_eval];
                    if sq >= s_now {
                        buf.copy_from_slice(it.y());
                    } else {
                        it.interpolate(sq, &mut buf);
                    }
                    push(&mut rec, sq, &buf);
                    next_eval += 1;
                }
            }
            None => {
                if let Some(yp) = &pre_hook {
                    push(&mut rec, s_now, yp);
                }
                push(&mut rec, s_now, it.y());
            }
        }
        y_start.copy_from_slice(it.y());
        match outcome {
            StepOutcome::Event { stopped: true, .. } => {
                rec.status = 1;
                break;
            }
            StepOutcome::StopTime { .. } => break,
            _ => {}
        }
        if it.is_finished() {
            break;
        }
    }
    rec.stats = it.stats();
    Ok(Ok(rec))
}
