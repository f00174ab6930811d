//! Events are never missed at the library's default options: a property test over random
//! bouncing balls with every adaptive method, and a bounce whose flight is shorter than the
//! step the method was taking before it (two roots inside what would have been one step).
//!
//! ```text
//! ball: h' = v, v' = −g;  event h = 0 falling;  hook v ← −e v, stop once |v| < 5 % of v₁
//! analytic bounce times:  t₁ = √(2 h₀ / g),  v₁ = g t₁,  t_{k+1} = t_k + 2 e^k v₁ / g
//! ```
//! The guarantee comes from the integrator: after every located event it restarts the
//! method with the starting-step algorithm (HNW I §II.4) from the event state and reads the
//! event functions there, so the first step after a bounce is a small fraction of the time
//! scale |y|/|f| and ends inside the next flight; interior samples (default 4 per step) see
//! an excursion longer than h/5 inside any later step.

use std::cell::Cell;

use lash_solver::*;
use proptest::prelude::*;

/// A bouncing ball with gravity g, restitution e, dropped from h0 at rest; it stops when
/// the rebound speed falls below 5 % of the first impact speed.
struct Ball {
    g: f64,
    e: f64,
    h0: f64,
    /// The run stops once the rebound speed falls below this fraction of v₁.
    stop_fraction: f64,
    /// Lowest height seen in any event hook (the state at the located event).
    lowest: Cell<f64>,
}

impl Ball {
    fn new(g: f64, e: f64, h0: f64) -> Self {
        Ball {
            g,
            e,
            h0,
            stop_fraction: 0.05,
            lowest: Cell::new(f64::INFINITY),
        }
    }
    fn first_impact_speed(&self) -> f64 {
        (2.0 * self.g * self.h0).sqrt()
    }
    /// Analytic bounce times up to the last one whose rebound speed is ≥ 5 % of v₁ (that one
    /// included: its hook stops the run).
    fn bounce_times(&self) -> Vec<f64> {
        let v1 = self.first_impact_speed();
        let mut times = vec![v1 / self.g];
        let mut v = v1;
        while self.e * v >= 0.05 * v1 {
            v *= self.e;
            let last = *times.last().unwrap();
            times.push(last + 2.0 * v / self.g);
        }
        times
    }
}

impl OdeSystem for Ball {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = -self.g;
    }
    fn n_events(&self) -> usize {
        1
    }
    fn event_spec(&self, _i: usize) -> EventSpec {
        EventSpec {
            direction: Direction::Falling,
            action: EventAction::Continue,
        }
    }
    fn events(&self, _t: f64, y: &[f64], g: &mut [f64]) {
        g[0] = y[0];
    }
    fn on_event(&self, _hit: &EventHit, y: &mut [f64]) -> EventAction {
        self.lowest.set(self.lowest.get().min(y[0]));
        y[1] *= -self.e;
        if y[1].abs() < self.stop_fraction * self.first_impact_speed() {
            EventAction::Stop
        } else {
            EventAction::Continue
        }
    }
}

/// Every adaptive method.
fn adaptive_methods() -> impl Iterator<Item = Method> {
    Method::ALL.into_iter().filter(|m| !m.is_fixed_step())
}

/// Runs the ball with `method` at default options and checks every bounce: found, in
/// order, within 1e-6 relative of its analytic time, and the ball never below −1e-6 m at
/// an accepted step or an event.
fn check_ball(ball: &Ball, method: Method) -> Result<(), TestCaseError> {
    let expected = ball.bounce_times();
    let t_end = expected.last().unwrap() + 1.0;
    let sol = solve(
        ball,
        (0.0, t_end),
        &[ball.h0, 0.0],
        &SolverOptions::with_method(method),
    )
    .map_err(|e| TestCaseError::fail(format!("{method}: {e}")))?;
    let found: Vec<f64> = sol.events.iter().map(|h| h.t).collect();
    prop_assert_eq!(
        found.len(),
        expected.len(),
        "{}: {} of {} bounces (g {}, e {}, h0 {})",
        method,
        found.len(),
        expected.len(),
        ball.g,
        ball.e,
        ball.h0
    );
    for (k, (t, te)) in found.iter().zip(&expected).enumerate() {
        prop_assert!(
            (t - te).abs() <= 1e-6 * te,
            "{}: bounce {} at {} instead of {} (rel {:e})",
            method,
            k,
            t,
            te,
            (t - te).abs() / te
        );
    }
    let lowest = sol
        .y
        .chunks(2)
        .map(|s| s[0])
        .fold(ball.lowest.get(), f64::min);
    prop_assert!(lowest >= -1e-6, "{}: the ball reached {} m", method, lowest);
    prop_assert!(
        sol.t_final < t_end,
        "{}: the last hook stops the run",
        method
    );
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 500, failure_persistence: None, ..ProptestConfig::default() })]

    /// 500 random balls (g ∈ [1, 20] m/s², e ∈ [0.3, 0.95], h0 ∈ [0.01, 10] m, log-uniform)
    /// × every adaptive method at default options.
    #[test]
    fn every_bounce_of_a_random_ball_is_found(
        g in 1.0f64..20.0,
        e in 0.3f64..0.95,
        log_h0 in (0.01f64).ln()..(10.0f64).ln(),
    ) {
        for method in adaptive_methods() {
            check_ball(&Ball::new(g, e, log_h0.exp()), method)?;
        }
    }
}

/// Two roots inside what would have been one step: dropped from 10 m, the ball falls for
/// 1.43 s in a few long steps (every method integrates the parabola exactly or nearly, so
/// the steps grow to a large fraction of the fall); the bounce with e = 0.01 leaves a flight
/// of 28.6 ms, much shorter than the step before the bounce. Continuing with that step would
/// put both crossings of the flight inside one step (the state is below the floor at both
/// ends), and the bounce would be missed; the restart with a fresh first step finds it, and
/// the one after it.
#[test]
fn a_flight_shorter_than_the_last_step_is_found_with_every_method() {
    // Rebound speeds 1e-2, 1e-4, 1e-6 of v₁: the third bounce stops the run.
    let ball = Ball {
        stop_fraction: 1e-5,
        ..Ball::new(9.81, 0.01, 10.0)
    };
    let mut expected = vec![(2.0 * 10.0 / 9.81f64).sqrt()];
    let mut v = 9.81 * expected[0];
    for _ in 0..2 {
        v *= 0.01;
        expected.push(expected.last().unwrap() + 2.0 * v / 9.81);
    }
    let flight = expected[1] - expected[0];
    assert!((flight - 2.8557e-2).abs() < 1e-6, "flight {flight}");
    for method in adaptive_methods() {
        let o = SolverOptions::with_method(method);
        let problem = Problem::new(&ball, &o).unwrap();
        // The end time lies far beyond the bounces (the third one stops the run), so that it
        // does not cap the steps.
        let mut it = problem.integrator(0.0, 100.0, &[10.0, 0.0]).unwrap();
        let mut last_step_before_bounce = 0.0;
        let mut bounces = Vec::new();
        loop {
            match it.step().unwrap() {
                StepOutcome::Accepted { t } => {
                    if bounces.is_empty() {
                        last_step_before_bounce = t - it.t_prev();
                    }
                }
                StepOutcome::Event { t, stopped, .. } => {
                    bounces.push(t);
                    if stopped {
                        break;
                    }
                }
                StepOutcome::StopTime { .. } => break,
            }
        }
        assert!(
            last_step_before_bounce > 5.0 * flight,
            "{method}: the step before the bounce ({last_step_before_bounce:e} s) should span \
             several such flights"
        );
        assert_eq!(bounces.len(), 3, "{method}: {bounces:?}");
        for (t, te) in bounces.iter().zip(&expected) {
            assert!((t - te).abs() <= 1e-6 * te, "{method}: {t} vs {te}");
        }
    }
}
