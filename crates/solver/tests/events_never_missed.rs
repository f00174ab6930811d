//! Events are never missed at the library's default options: a property test over random
//! bouncing balls with every adaptive method, and a bounce whose flight is shorter than the
//! step the method was taking before it (two roots inside what would have been one step).
//!
//! ```text
//! ball: h' = v, v' = −g;  event h = 0 falling;  hook v ← −e v, stop once |v| < 5 % of v₁
//! analytic bounce times:  t₁ = √(2 h₀ / g),  v₁ = g t₁,  t_{k+1} = t_k + 2 e^k v₁ / g
//! ```
//! Each bounce is also located to the floating-point limit: the height on the dense output at
//! the located time is at most 2 ε t |v| (the final bracket of the root finder, a few ulps
//! of t, times the speed) plus the interpolant's rounding, 512 ε h0 (2048 ε h0 for the
//! degree-7 interpolant of dop853). The rounding varies from ball to ball: measured maxima
//! over three runs of 500 balls were about 110 ε h0 for tsit54 and 190 ε h0 for dop853, below
//! 5 ε h0 for the others.
//!
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
    /// Largest |height| at a located bounce in units of the floating-point limit
    /// 2 ε t |v| + noise · ε h0 (module doc): ≤ 1 when the bounce is located to a few ulps of t.
    worst_location: Cell<f64>,
    /// The interpolant's rounding in units of ε h0 (512, or 2048 for dop853).
    noise: Cell<f64>,
}

impl Ball {
    fn new(g: f64, e: f64, h0: f64) -> Self {
        Ball {
            g,
            e,
            h0,
            stop_fraction: 0.05,
            lowest: Cell::new(f64::INFINITY),
            worst_location: Cell::new(0.0),
            noise: Cell::new(512.0),
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
    fn on_event(&self, hit: &EventHit, y: &mut [f64]) -> EventAction {
        self.lowest.set(self.lowest.get().min(y[0]));
        let limit =
            2.0 * f64::EPSILON * hit.t * y[1].abs() + self.noise.get() * f64::EPSILON * self.h0;
        let worst = self.worst_location.get().max(y[0].abs() / limit);
        self.worst_location.set(worst);
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
    check_ball_with(ball, &SolverOptions::with_method(method))
}

/// [`check_ball`] with the options `o`.
fn check_ball_with(ball: &Ball, o: &SolverOptions) -> Result<(), TestCaseError> {
    let method = o.method;
    ball.worst_location.set(0.0);
    ball.noise.set(if method == Method::Dop853 {
        2048.0
    } else {
        512.0
    });
    let expected = ball.bounce_times();
    let t_end = expected.last().unwrap() + 1.0;
    let sol = solve(ball, (0.0, t_end), &[ball.h0, 0.0], o)
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
    // Each bounce is located on the dense output to the floating-point limit: the height
    // there is at most |v| times the final bracket (2 ε t) plus the interpolant's rounding.
    // With exact event steps the state at a bounce is the end of the retaken step, whose
    // time Newton's method corrects only while the correction moves the state by more than
    // the tolerance: its height is bounded by the tolerance (the check of `lowest` above),
    // not by the floating-point limit.
    prop_assert!(
        o.exact_event_steps || ball.worst_location.get() <= 1.0,
        "{}: a bounce located {} times the floating-point limit from the floor",
        method,
        ball.worst_location.get()
    );
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

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, failure_persistence: None, ..ProptestConfig::default() })]

    /// 200 random balls × every one-step adaptive method with `exact_event_steps`: the step
    /// that contains a bounce is retaken to end on it, and the first step after the restart
    /// is at most the fresh one (crate::integrator, "Exact event steps"), so every bounce is
    /// still found, located as precisely.
    #[test]
    fn every_bounce_is_found_with_exact_event_steps(
        g in 1.0f64..20.0,
        e in 0.3f64..0.95,
        log_h0 in (0.01f64).ln()..(10.0f64).ln(),
    ) {
        for method in adaptive_methods().filter(|m| m.info().family != lash_solver::method::Family::Diffsol) {
            let o = SolverOptions {
                exact_event_steps: true,
                ..SolverOptions::with_method(method)
            };
            check_ball_with(&Ball::new(g, e, log_h0.exp()), &o)?;
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

/// The ball with the rates of its event function (ġ = v), so that the integrator's far test
/// (`lash_solver::integrator`, module documentation) skips the interior samples of steps
/// where the ball stays far above the floor.
struct RatedBall(Ball);

impl OdeSystem for RatedBall {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.0.rhs(t, y, dy);
    }
    fn n_events(&self) -> usize {
        1
    }
    fn event_spec(&self, i: usize) -> EventSpec {
        self.0.event_spec(i)
    }
    fn events(&self, t: f64, y: &[f64], g: &mut [f64]) {
        self.0.events(t, y, g);
    }
    fn event_rates(&self, _t: f64, y: &[f64], g: &mut [f64], g_dot: &mut [f64]) -> bool {
        g[0] = y[0];
        g_dot[0] = y[1];
        true
    }
    fn on_event(&self, hit: &EventHit, y: &mut [f64]) -> EventAction {
        self.0.on_event(hit, y)
    }
}

/// Runs the rated ball with `method` at default options: the bounces of the plain ball (same
/// times to 1e-6 relative, none lost) and the number of interior samples the far test skipped.
fn rated_ball_bounces(ball: Ball, method: Method) -> Result<(Vec<f64>, usize), SolveError> {
    rated_ball_bounces_with(ball, &SolverOptions::with_method(method))
}

/// [`rated_ball_bounces`] with options `o`.
fn rated_ball_bounces_with(ball: Ball, o: &SolverOptions) -> Result<(Vec<f64>, usize), SolveError> {
    let rated = RatedBall(ball);
    let expected = rated.0.bounce_times();
    let t_end = expected.last().unwrap() + 1.0;
    let problem = Problem::new(&rated, o)?;
    let mut it = problem.integrator(0.0, t_end, &[rated.0.h0, 0.0])?;
    let mut bounces = Vec::new();
    loop {
        match it.step()? {
            StepOutcome::Accepted { .. } => {}
            StepOutcome::Event { t, stopped, .. } => {
                bounces.push(t);
                if stopped {
                    break;
                }
            }
            StepOutcome::StopTime { .. } => break,
        }
    }
    Ok((bounces, it.samples_skipped()))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, failure_persistence: None, ..ProptestConfig::default() })]

    /// The far test keeps the guarantee: 200 random balls with event rates × every adaptive
    /// method find every bounce at its analytic time, as the balls without rates do.
    #[test]
    fn every_bounce_is_found_when_the_far_test_skips_samples(
        g in 1.0f64..20.0,
        e in 0.3f64..0.95,
        log_h0 in (0.01f64).ln()..(10.0f64).ln(),
    ) {
        let ball = Ball::new(g, e, log_h0.exp());
        let expected = ball.bounce_times();
        for method in adaptive_methods() {
            let (found, _) = rated_ball_bounces(Ball::new(g, e, log_h0.exp()), method)
                .map_err(|e| TestCaseError::fail(format!("{method}: {e}")))?;
            prop_assert_eq!(found.len(), expected.len(), "{}: {:?} vs {:?}", method, found, expected);
            for (t, te) in found.iter().zip(&expected) {
                prop_assert!((t - te).abs() <= 1e-6 * te, "{}: {} vs {}", method, t, te);
            }
        }
    }

    /// With the rates given, exact event steps also limit each step to end just past the
    /// predicted crossing (crate::integrator, "Exact event steps"; integrator/exact.rs): 200
    /// random balls with event rates × every one-step adaptive method find every bounce at
    /// its analytic time.
    #[test]
    fn every_bounce_is_found_with_the_predicted_crossing_limit(
        g in 1.0f64..20.0,
        e in 0.3f64..0.95,
        log_h0 in (0.01f64).ln()..(10.0f64).ln(),
    ) {
        let expected = Ball::new(g, e, log_h0.exp()).bounce_times();
        for method in adaptive_methods().filter(|m| m.info().family != lash_solver::method::Family::Diffsol) {
            let o = SolverOptions {
                exact_event_steps: true,
                ..SolverOptions::with_method(method)
            };
            let (found, _) = rated_ball_bounces_with(Ball::new(g, e, log_h0.exp()), &o)
                .map_err(|e| TestCaseError::fail(format!("{method}: {e}")))?;
            prop_assert_eq!(found.len(), expected.len(), "{}: {:?} vs {:?}", method, found, expected);
            for (t, te) in found.iter().zip(&expected) {
                prop_assert!((t - te).abs() <= 1e-6 * te, "{}: {} vs {}", method, t, te);
            }
        }
    }

    /// Soundness of the far test on every constant-acceleration motion (the ball's flight,
    /// and the local model of any smooth g): g(t) = g₀ + v₀ t + a t²/2 on [0, h] never
    /// reaches zero when `far_from_zero` holds for its end values and rates. (Its extremum
    /// g₀ − v₀²/(2a) lies inside only if the rate changes sign, and then the travel to it,
    /// v₀²/(2|a|) ≤ |v₀| h/2, is below the margin κ h max|ġ| with κ = 2.)
    #[test]
    fn far_test_is_sound_for_parabolas(
        g0 in -10.0f64..10.0,
        v0 in -10.0f64..10.0,
        a in -100.0f64..100.0,
        log_h in (1e-4f64).ln()..(1.0f64).ln(),
    ) {
        let h = log_h.exp();
        let gh = g0 + v0 * h + 0.5 * a * h * h;
        let vh = v0 + a * h;
        if lash_solver::integrator::far_from_zero(g0, v0, gh, vh, h) {
            // Minimum of |g| over [0, h]: the ends and the extremum if inside.
            let mut lo = g0.abs().min(gh.abs());
            let same_sign = g0.signum() == gh.signum();
            if a != 0.0 {
                let ts = -v0 / a;
                if ts > 0.0 && ts < h {
                    let gs = g0 + v0 * ts + 0.5 * a * ts * ts;
                    prop_assert!(gs.signum() == g0.signum(), "root inside: g0 {} v0 {} a {} h {}", g0, v0, a, h);
                    lo = lo.min(gs.abs());
                }
            }
            prop_assert!(same_sign && lo > 0.0);
        }
    }
}

/// On a long fall the far test skips interior samples (the steps far above the floor), with
/// every adaptive method, and the bounces are those of the plain ball.
#[test]
fn the_far_test_skips_the_samples_of_steps_far_from_the_floor() {
    for method in adaptive_methods() {
        let (found, skipped) = rated_ball_bounces(Ball::new(9.81, 0.5, 10.0), method).unwrap();
        let expected = Ball::new(9.81, 0.5, 10.0).bounce_times();
        assert_eq!(found.len(), expected.len(), "{method}");
        assert!(skipped > 0, "{method}: no sample skipped");
    }
}
