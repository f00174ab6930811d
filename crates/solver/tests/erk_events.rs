//! Event location on the dense output of the explicit pairs.
//!
//! ```text
//! events g_i(t, y) = 0 located by Brent's method on g_i(t, u(t)), u the step's dense
//! output, to a bracket of 2 ε |t| (a few ulps of t)
//! ```

mod common;
use common::*;
use lash_solver::*;

fn adaptive(method: Method, rtol: f64) -> SolverOptions {
    SolverOptions {
        method,
        rtol,
        atol: Atol::Scalar(rtol * 1e-2),
        ..Default::default()
    }
}

#[test]
fn bouncing_ball_bounce_times_with_every_pair() {
    // Dropped from 1 m at rest: first impact at t1 = √(2/g); each later flight lasts
    // 2 e v_k / g with v_k the impact speed, reduced by e at each bounce. The trajectory is
    // quadratic, which every pair and its dense output (order ≥ 3) reproduce exactly, so the
    // bounce times are limited only by the root finder (1e-13 relative) and rounding.
    // Because the steps grow freely on an exactly integrated problem, a whole flight (0.72 s
    // down to 0.24 s) could fit in one step, and g would be negative at both of its ends;
    // h_max = 0.05 keeps at least 4 step ends in every flight.
    let (g, e, h0) = (Ball::G, 0.8f64, 1.0f64);
    let expected = Ball { e }.bounce_times(h0, 6);
    let t1 = expected[0];
    let t_end = expected[5] + 0.1;
    for (m, _) in PAIRS {
        let o = SolverOptions {
            h_max: 0.05,
            ..adaptive(m, 1e-6)
        };
        let s = solve(&Ball { e }, (0.0, t_end), &[h0, 0.0], &o).unwrap();
        assert_eq!(s.events.len(), 6, "{m}");
        assert_eq!(s.stats.events, 6, "{m}");
        for (hit, te) in s.events.iter().zip(&expected) {
            assert!((hit.t - te).abs() < 1e-9, "{m}: {} vs {te}", hit.t);
            assert!(!hit.rising && hit.index == 0, "{m}");
        }
        // After the last bounce the ball flies up with speed e⁶ v1.
        let v_end = -9.81 * (t_end - expected[5]) + e.powi(6) * g * t1;
        assert!((s.y_final[1] - v_end).abs() < 1e-9, "{m}");
    }
}

/// y' = 1 (y = t) with g = 1e-4 − (y − 5)²: positive only on the thin window (4.99, 5.01).
struct Thin;
impl OdeSystem for Thin {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, _y: &[f64], dy: &mut [f64]) {
        dy[0] = 1.0;
    }
    fn n_events(&self) -> usize {
        1
    }
    fn events(&self, _t: f64, y: &[f64], g: &mut [f64]) {
        g[0] = 1e-4 - (y[0] - 5.0).powi(2);
    }
}

#[test]
fn thin_event_is_missed_by_a_large_step_and_found_with_help() {
    for (m, _) in PAIRS {
        // y' = 1 is integrated exactly: the error estimate is 0 and the step grows to the
        // caps, so some step spans the window and g has the same sign at both of its ends.
        let plain = solve(&Thin, (0.0, 10.0), &[0.0], &adaptive(m, 1e-6)).unwrap();
        assert!(plain.events.is_empty(), "{m}: {:?}", plain.events);
        assert!(plain.stats.h_max_used > 0.02, "{m}");
        // h_max = 0.01 < window width 0.02: some step end lands inside the window.
        let o = SolverOptions {
            h_max: 0.01,
            ..adaptive(m, 1e-6)
        };
        let with_hmax = solve(&Thin, (0.0, 10.0), &[0.0], &o).unwrap();
        // event_samples = 64 with h_max = 1: samples 1/65 < 0.02 apart inside every step.
        let o = SolverOptions {
            h_max: 1.0,
            event_samples: 64,
            ..adaptive(m, 1e-6)
        };
        let with_samples = solve(&Thin, (0.0, 10.0), &[0.0], &o).unwrap();
        for s in [&with_hmax, &with_samples] {
            let times: Vec<(f64, bool)> = s.events.iter().map(|h| (h.t, h.rising)).collect();
            assert_eq!(times.len(), 2, "{m}: {times:?}");
            assert!(
                (times[0].0 - 4.99).abs() < 1e-9 && times[0].1,
                "{m}: {times:?}"
            );
            assert!(
                (times[1].0 - 5.01).abs() < 1e-9 && !times[1].1,
                "{m}: {times:?}"
            );
        }
    }
}

/// Harmonic oscillator y = (cos t, −sin t) with g = y0 (zeros at π/2 + kπ), one copy of g
/// per direction.
struct Osc;
impl OdeSystem for Osc {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = -y[0];
    }
    fn n_events(&self) -> usize {
        3
    }
    fn event_spec(&self, i: usize) -> EventSpec {
        EventSpec {
            direction: [Direction::Rising, Direction::Falling, Direction::Either][i],
            action: EventAction::Continue,
        }
    }
    fn events(&self, _t: f64, y: &[f64], g: &mut [f64]) {
        g.fill(y[0]);
    }
}

#[test]
fn direction_filtering() {
    // cos t on [0, 12]: falling zeros at π/2, 5π/2, rising at 3π/2, 7π/2. At rtol 1e-10 the
    // solution error is below 1e-9, so the zeros are located to 1e-8 (|g'| = 1).
    let pi = std::f64::consts::PI;
    for (m, _) in PAIRS {
        let s = solve(&Osc, (0.0, 12.0), &[1.0, 0.0], &adaptive(m, 1e-10)).unwrap();
        let of = |i: usize| -> Vec<(f64, bool)> {
            s.events
                .iter()
                .filter(|h| h.index == i)
                .map(|h| (h.t, h.rising))
                .collect()
        };
        let check = |got: Vec<(f64, bool)>, want: &[(f64, bool)]| {
            assert_eq!(got.len(), want.len(), "{m}: {got:?}");
            for (g, w) in got.iter().zip(want) {
                assert!(
                    (g.0 - w.0).abs() < 1e-8 && g.1 == w.1,
                    "{m}: {g:?} vs {w:?}"
                );
            }
        };
        check(of(0), &[(1.5 * pi, true), (3.5 * pi, true)]);
        check(of(1), &[(0.5 * pi, false), (2.5 * pi, false)]);
        check(
            of(2),
            &[
                (0.5 * pi, false),
                (1.5 * pi, true),
                (2.5 * pi, false),
                (3.5 * pi, true),
            ],
        );
        // The three copies cross together: each crossing is one event outcome with the
        // matching components, so 4 outcomes carry 8 hits.
        assert_eq!(s.events.len(), 8, "{m}");
    }
}

/// Two different event functions with the same root: g0 = y0 and g1 = y0 (1 + y1²).
struct Twin;
impl OdeSystem for Twin {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = -y[0];
    }
    fn n_events(&self) -> usize {
        2
    }
    fn events(&self, _t: f64, y: &[f64], g: &mut [f64]) {
        g[0] = y[0];
        g[1] = y[0] * (1.0 + y[1] * y[1]);
    }
}

#[test]
fn simultaneous_events_are_reported_together() {
    for (m, _) in PAIRS {
        let o = adaptive(m, 1e-10);
        let problem = Problem::new(&Twin, &o).unwrap();
        let mut it = problem.integrator(0.0, 2.0, &[1.0, 0.0]).unwrap();
        let mut outcomes = Vec::new();
        loop {
            match it.step().unwrap() {
                StepOutcome::StopTime { .. } => break,
                StepOutcome::Event { t, hits, stopped } => outcomes.push((t, hits, stopped)),
                StepOutcome::Accepted { .. } => {}
            }
        }
        assert_eq!(outcomes.len(), 1, "{m}: {outcomes:?}");
        let (t, hits, stopped) = &outcomes[0];
        assert!(!stopped);
        assert!((t - std::f64::consts::FRAC_PI_2).abs() < 1e-8, "{m}: {t}");
        let idx: Vec<usize> = hits.iter().map(|h| h.index).collect();
        assert_eq!(idx, vec![0, 1], "{m}");
        assert!(hits.iter().all(|h| h.t == *t && !h.rising), "{m}");
        assert_eq!(it.stats().events, 2, "{m}");
    }
}

/// cos t with a stopping event at its first falling zero.
struct StopAtZero;
impl OdeSystem for StopAtZero {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = -y[0];
    }
    fn n_events(&self) -> usize {
        1
    }
    fn event_spec(&self, _i: usize) -> EventSpec {
        EventSpec {
            direction: Direction::Falling,
            action: EventAction::Stop,
        }
    }
    fn events(&self, _t: f64, y: &[f64], g: &mut [f64]) {
        g[0] = y[0];
    }
}

#[test]
fn stop_action_ends_the_integration_at_the_event() {
    let half_pi = std::f64::consts::FRAC_PI_2;
    for (m, _) in PAIRS {
        let s = solve(&StopAtZero, (0.0, 10.0), &[1.0, 0.0], &adaptive(m, 1e-10)).unwrap();
        assert_eq!(s.events.len(), 1, "{m}");
        assert!((s.t_final - half_pi).abs() < 1e-8, "{m}: {}", s.t_final);
        assert_eq!(s.events[0].t, s.t_final);
        assert_eq!(*s.t.last().unwrap(), s.t_final);
        // The state at the event: cos → 0 (just past the root), −sin → −1.
        assert!(s.y_final[0].abs() < 1e-8 && s.y_final[0] <= 0.0, "{m}");
        assert!((s.y_final[1] + 1.0).abs() < 1e-8, "{m}");
    }
}

#[test]
fn event_location_costs_a_few_evaluations_per_event() {
    // Without interior samples (event_samples = 0):
    // event_evals = 1 (at t0) + 1 per accepted step (g at its end) + per event: the root
    // finder's evaluations + 1 after the hook. Brent's method from the step's bracket down to
    // 2 ε |t| (a few ulps of t) takes 3 to 5 evaluations per event here (measured: bs32 12,
    // dopri54 and tsit54 16, dop853 19 for 4 events); Illinois to the former 1e-13 relative
    // took about 3, and before the fixes of integrator.rs (stale left value g_a after
    // event-free steps, and bisection once the secant point hit a bracket end) dopri54
    // needed 18 here.
    struct Cos;
    impl OdeSystem for Cos {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = y[1];
            dy[1] = -y[0];
        }
        fn n_events(&self) -> usize {
            1
        }
        fn events(&self, _t: f64, y: &[f64], g: &mut [f64]) {
            g[0] = y[0];
        }
    }
    for (m, _) in PAIRS {
        let o = SolverOptions {
            event_samples: 0,
            ..adaptive(m, 1e-10)
        };
        let s = solve(&Cos, (0.0, 12.0), &[1.0, 0.0], &o).unwrap();
        assert_eq!(s.events.len(), 4, "{m}");
        let root_evals = s.stats.event_evals - 1 - s.stats.accepted - s.stats.events;
        assert!(
            root_evals <= 5 * s.stats.events,
            "{m}: {root_evals} evaluations for {} events",
            s.stats.events
        );
    }
}
