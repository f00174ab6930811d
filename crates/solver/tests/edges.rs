//! The solver at the edges of its input (issue 23): an event function that returns NaN, a
//! method whose dense matrices do not fit the memory budget, and diffsol's starting step on a
//! span shorter than its probe.
//!
//! ```text
//! g(t, y) = NaN from t_nan on        → SolveError::EventNan { index, at ≥ t_nan }, every
//!                                       adaptive method, never a silent run without events
//! max_memory < 8 k n² (k = 4 diffsol, 3 Rodas5P) → SolveError::OutOfMemory before any
//!                                       evaluation; the explicit methods allocate no n²
//! y' = 2y on [0, 1e-4] (scipy's gh-17341): f is never evaluated beyond t_end, and where the
//!                                       probe fits the span the step is diffsol's own
//! max_wall_time = 1e300 s (finite, beyond the clock) → no deadline, never a panic
//! ```

use std::cell::Cell;

use lash_solver::*;

/// y' = −y with event functions g_0 = 1 (never zero) and g_1 = t − t_nan before t_nan, NaN
/// from t_nan on.
struct NanEvent {
    t_nan: f64,
    rhs_calls: Cell<usize>,
}

impl OdeSystem for NanEvent {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        self.rhs_calls.set(self.rhs_calls.get() + 1);
        dy[0] = -y[0];
    }
    fn n_events(&self) -> usize {
        2
    }
    fn event_spec(&self, _i: usize) -> EventSpec {
        EventSpec {
            direction: Direction::Either,
            action: EventAction::Continue,
        }
    }
    fn events(&self, t: f64, _y: &[f64], g: &mut [f64]) {
        g[0] = 1.0;
        g[1] = if t < self.t_nan {
            t - 2.0 * self.t_nan
        } else {
            f64::NAN
        };
    }
}

fn opts_for(method: Method) -> SolverOptions {
    SolverOptions {
        method,
        rtol: 1e-6,
        atol: Atol::Scalar(1e-9),
        step: method.is_fixed_step().then_some(1e-3),
        ..Default::default()
    }
}

#[test]
fn an_event_function_returning_nan_is_a_typed_error_naming_it() {
    for method in Method::ALL {
        let sys = NanEvent {
            t_nan: 0.5,
            rhs_calls: Cell::new(0),
        };
        let e = solve(&sys, (0.0, 2.0), &[1.0], &opts_for(method)).unwrap_err();
        match &e {
            SolveError::EventNan { t, y, index, at } => {
                assert_eq!(*index, 1, "{method}");
                // Seen at the first evaluation at or after t_nan: within the step that
                // crosses it; the state is the last accepted one, before `at`.
                assert!(*t < 0.5 && 0.5 <= *at, "{method}: {e}");
                assert!((y[0] - (-t).exp()).abs() < 1e-4, "{method}: state at t");
            }
            other => panic!("{method}: expected EventNan, got {other:?}"),
        }
        assert!(
            e.to_string().contains("event function 1 returned NaN"),
            "{e}"
        );
    }
}

#[test]
fn an_event_function_that_is_nan_at_the_start_fails_before_the_first_step() {
    let sys = NanEvent {
        t_nan: 0.0,
        rhs_calls: Cell::new(0),
    };
    let o = opts_for(Method::Dopri54);
    let problem = Problem::new(&sys, &o).unwrap();
    let e = problem.integrator(0.0, 1.0, &[1.0]).err().unwrap();
    assert_eq!(
        e,
        SolveError::EventNan {
            t: 0.0,
            y: vec![1.0],
            index: 1,
            at: 0.0
        }
    );
}

/// y' = −y in n dimensions.
struct Decay(usize);

impl OdeSystem for Decay {
    fn dim(&self) -> usize {
        self.0
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        for (d, v) in dy.iter_mut().zip(y) {
            *d = -v;
        }
    }
}

#[test]
fn dense_matrices_over_max_memory_are_refused_before_anything_is_allocated() {
    let n = 200;
    for (method, k) in [
        (Method::Bdf, 4u64),
        (Method::Trbdf2, 4),
        (Method::Esdirk34, 4),
        (Method::Rodas5p, 3),
    ] {
        let need = 8 * k * (n * n) as u64;
        let mut o = opts_for(method);
        o.max_memory = Some(need - 1);
        match Problem::new(&Decay(n), &o) {
            Err(SolveError::OutOfMemory(m)) => {
                assert_eq!((m.needed, m.budget), (need, need - 1), "{method}");
                assert_eq!(m.basis, "max_memory");
            }
            Err(e) => panic!("{method}: {e}"),
            Ok(_) => panic!("{method}: not refused"),
        }
        // At the budget it runs, and the answer is e^{-1}.
        o.max_memory = Some(need);
        let sol = solve(&Decay(n), (0.0, 1.0), &vec![1.0; n], &o).unwrap();
        assert!(
            (sol.y_final[n - 1] - (-1.0f64).exp()).abs() < 1e-4,
            "{method}"
        );
    }
    // The explicit methods need no n² memory: a budget of one byte is enough.
    let mut o = opts_for(Method::Dopri54);
    o.max_memory = Some(1);
    let sol = solve(&Decay(n), (0.0, 1.0), &vec![1.0; n], &o).unwrap();
    assert!((sol.y_final[0] - (-1.0f64).exp()).abs() < 1e-5);
}

#[test]
fn an_implicit_method_at_n_1e5_is_refused_by_the_automatic_budget() {
    // 4 · (1e5)² · 8 = 3.2e11 bytes: more than half of any machine this runs on. Where no
    // figure is known (not Linux) nothing can be refused: the test then has nothing to check.
    if memory::available().is_none() {
        return;
    }
    let o = opts_for(Method::Bdf);
    match Problem::new(&Decay(100_000), &o) {
        Err(SolveError::OutOfMemory(m)) => {
            assert_eq!(m.needed, 320_000_000_000);
            assert!(m.budget < m.needed && m.basis.starts_with("half of"), "{m}");
        }
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("not refused"),
    }
}

/// y' = 2y, which must not be evaluated after `t_end` (scipy's gh-17341).
struct Bounded {
    t_end: f64,
    t_max: Cell<f64>,
}

impl OdeSystem for Bounded {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.t_max.set(self.t_max.get().max(t));
        dy[0] = if t > self.t_end { f64::NAN } else { 2.0 * y[0] };
    }
}

#[test]
fn diffsol_methods_never_evaluate_f_beyond_a_short_span() {
    for method in [Method::Bdf, Method::Trbdf2, Method::Esdirk34] {
        let sys = Bounded {
            t_end: 1e-4,
            t_max: Cell::new(0.0),
        };
        // scipy's defaults: rtol 1e-3, atol 1e-6. Hairer's probe would be 0.01 d0/d1 = 5e-3,
        // fifty times the span.
        let o = SolverOptions {
            method,
            rtol: 1e-3,
            atol: Atol::Scalar(1e-6),
            ..Default::default()
        };
        let sol = solve(&sys, (0.0, 1e-4), &[1.0], &o).unwrap();
        assert!(
            sys.t_max.get() <= 1e-4,
            "{method}: f at {}",
            sys.t_max.get()
        );
        assert_eq!(sol.t_final, 1e-4);
        // e^{2e-4} to the tolerance.
        assert!((sol.y_final[0] - 2e-4f64.exp()).abs() < 1e-6, "{method}");
    }
}

/// scipy's fun_rational, y1' = y2/t, y2' = y2 (y1 + 2 y2 − 1)/(t (y1 − 1)), with the solution
/// y1 = t/(t + 10), y2 = 10 t/(t + 10)², integrated backwards from t = 5 to 1 in solver time
/// s = −t: z(s) = y(−s), z' = −f(−s, z).
struct RationalBackwards;

impl OdeSystem for RationalBackwards {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, s: f64, z: &[f64], dz: &mut [f64]) {
        let t = -s;
        dz[0] = -(z[1] / t);
        dz[1] = -(z[1] * (z[0] + 2.0 * z[1] - 1.0) / (t * (z[0] - 1.0)));
    }
}

#[test]
fn bdf_steps_of_equal_size_land_on_its_h_max_stops_without_a_crawl() {
    // scipy's test_first_step: first step 0.1, max_step 0.5. BDF keeps h = 0.1, its times
    // drift by a few hundred ulps, and a step ended 3.8e-13 short of the stop at t = 2.
    // diffsol then shrank the next step to that remainder (its difference table rescaled by
    // 2e-12: the dense output of the step just taken was off by 455) and took thousands of
    // steps to grow back. Now such a step stops at its own end.
    let exact = |s: f64| {
        let t = -s;
        [t / (t + 10.0), 10.0 * t / ((t + 10.0) * (t + 10.0))]
    };
    let o = SolverOptions {
        method: Method::Bdf,
        rtol: 1e-3,
        atol: Atol::Scalar(1e-6),
        h0: Some(0.1),
        h_max: 0.5,
        ..Default::default()
    };
    let problem = Problem::new(&RationalBackwards, &o).unwrap();
    let mut it = problem.integrator(-5.0, -1.0, &exact(-5.0)).unwrap();
    let (mut y_prev, mut buf) = (exact(-5.0).to_vec(), vec![0.0; 2]);
    let mut worst_start = 0.0f64;
    loop {
        let out = it.step().unwrap();
        // The dense output of the step, at its start, is the state there.
        it.interpolate(it.t_prev(), &mut buf);
        for (a, b) in buf.iter().zip(&y_prev) {
            worst_start = worst_start.max((a - b).abs());
        }
        // ... and in its middle it is within the tolerance of the solution.
        let mid = 0.5 * (it.t_prev() + it.t());
        it.interpolate(mid, &mut buf);
        let e = exact(mid);
        for i in 0..2 {
            assert!(
                (buf[i] - e[i]).abs() < 5.0 * (1e-6 + 1e-3 * e[i].abs()),
                "s = {mid}: {buf:?} vs {e:?}"
            );
        }
        y_prev.copy_from_slice(it.y());
        if matches!(out, StepOutcome::StopTime { .. }) {
            break;
        }
    }
    assert!(
        worst_start < 1e-12,
        "dense output at a step's start off by {worst_start}"
    );
    // 4 time units at h ≤ 0.5 with h = 0.1 kept: about 40 steps (not thousands).
    let accepted = it.stats().accepted;
    assert!(accepted <= 60, "{accepted} steps");
}

/// A wall-clock budget longer than the clock can hold (1e300 s passes the option rule: finite
/// and > 0) is no budget: every method runs to the end with the exact decay, where
/// `Duration::from_secs_f64` used to panic. The deadline itself: none beyond the clock's range
/// or for a value the rules reject, `start + w` otherwise.
#[test]
fn a_wall_time_budget_beyond_the_clock_is_no_budget() {
    use lash_solver::stepper::deadline_after;
    use std::time::{Duration, Instant};
    for method in Method::ALL {
        let mut o = opts_for(method);
        o.max_wall_time = Some(1e300);
        let sol = solve(&Decay(1), (0.0, 1.0), &[1.0], &o).unwrap();
        let tol = if method.is_fixed_step() { 1e-9 } else { 1e-4 };
        assert!(
            (sol.y_final[0] - (-1.0f64).exp()).abs() < tol,
            "{method}: {}",
            sol.y_final[0]
        );
    }
    let start = Instant::now();
    for w in [1e300, f64::INFINITY, f64::NAN, 0.0, -1.0] {
        assert_eq!(deadline_after(start, w), None, "{w}");
    }
    assert_eq!(
        deadline_after(start, 2.5),
        Some(start + Duration::from_millis(2500))
    );
}

/// Every method stops at its first step attempt when the call's deadline
/// (`interrupt::deadline_scope`) has passed, with the budget named and the initial state,
/// however large its own `max_wall_time`; outside the scope the same solve runs to the end.
#[test]
fn every_method_stops_at_the_deadline_of_its_call() {
    for method in Method::ALL {
        let o = opts_for(method);
        let err = {
            let _scope = interrupt::deadline_scope(Some((std::time::Instant::now(), 0.125)));
            solve(&Decay(1), (0.0, 1.0), &[1.0], &o).unwrap_err()
        };
        match err {
            SolveError::BudgetExhausted { t, y, reason } => {
                assert_eq!((t, y), (0.0, vec![1.0]), "{method}");
                assert_eq!(reason, "wall-clock budget of 0.125 s used", "{method}");
            }
            e => panic!("{method}: {e}"),
        }
        assert!(solve(&Decay(1), (0.0, 1.0), &[1.0], &o).is_ok(), "{method}");
    }
}
