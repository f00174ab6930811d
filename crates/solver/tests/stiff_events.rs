//! Every stiff method on problems with closed forms, through the event-locating driver:
//! the bouncing ball (events + restarts), a stiff linear system, Prothero–Robinson.

mod common;
mod stiff_problems;

use common::Ball;
use lash_solver::*;
use stiff_problems::{opts, ProtheroRobinson, StiffLinear, STIFF};

/// Bounce times of the ball dropped from 1 m, e = 0.8, over [0, 2.5] (4 bounces).
fn bounces(o: &SolverOptions) -> Vec<EventHit> {
    let ball = Ball { e: 0.8 };
    let s = solve(&ball, (0.0, 2.5), &[1.0, 0.0], o).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.t_final, 2.5);
    s.events
}

/// The ball's trajectory is quadratic: every method here but BDF integrates it exactly (and
/// their dense outputs are exact for it); BDF restarts at order 1 after each bounce, whose
/// error ∝ rtol is why rtol = 10⁻¹¹ (at 10⁻⁸ the 4th bounce is 9·10⁻⁸ late, at 10⁻¹¹
/// 9·10⁻¹¹). Each method runs twice: with h_max = 0.1 (for diffsol via stop times) and no
/// interior event samples, and with no h_max and 4 interior event samples per step.
#[test]
fn bouncing_ball_bounce_times_with_every_stiff_method() {
    let expected = Ball { e: 0.8 }.bounce_times(1.0, 4);
    for method in STIFF {
        for (h_max, samples) in [(0.1, 0), (f64::INFINITY, 4)] {
            let o = SolverOptions {
                h_max,
                event_samples: samples,
                ..opts(method, 1e-11, 1e-11)
            };
            let hits = bounces(&o);
            assert_eq!(hits.len(), 4, "{method} h_max {h_max} samples {samples}");
            for (hit, te) in hits.iter().zip(&expected) {
                assert!(
                    (hit.t - te).abs() < 1e-9,
                    "{method} h_max {h_max} samples {samples}: {} vs {te}",
                    hit.t
                );
                assert!(!hit.rising && hit.index == 0);
            }
        }
    }
}

/// Why no option is needed any more: after a bounce the stepper restarts with the
/// starting-step algorithm, so its first step ends inside the next flight (the ball above
/// the floor), and the falling crossing that ends the flight is seen even without interior
/// samples and without h_max. (Rodas5P integrates a flight exactly; before restarts chose a
/// fresh first step it kept its last step, spanned a whole flight and found 1 of 4 bounces.)
#[test]
fn the_first_step_after_a_bounce_ends_inside_the_next_flight() {
    let ball = Ball { e: 0.8 };
    let expected = ball.bounce_times(1.0, 5);
    for method in STIFF {
        let o = SolverOptions {
            event_samples: 0,
            ..opts(method, 1e-8, 1e-8)
        };
        let problem = Problem::new(&ball, &o).unwrap();
        let mut it = problem.integrator(0.0, 2.5, &[1.0, 0.0]).unwrap();
        let mut bounces = 0;
        let mut after_bounce = false;
        loop {
            match it.step().unwrap() {
                StepOutcome::Event { t, .. } => {
                    assert!((t - expected[bounces]).abs() < 1e-6, "{method}: {t}");
                    bounces += 1;
                    after_bounce = true;
                }
                StepOutcome::Accepted { t } => {
                    if after_bounce {
                        assert!(
                            t < expected[bounces] && it.y()[0] > 0.0,
                            "{method}: first step after bounce {bounces} ends at {t}, \
                             past the next bounce at {}",
                            expected[bounces]
                        );
                    }
                    after_bounce = false;
                }
                StepOutcome::StopTime { .. } => break,
            }
        }
        assert_eq!(bounces, 4, "{method}");
    }
}

/// y' = A y with eigenvalues −1 and −5000 on [0, 10] at rtol 10⁻⁶: an explicit method would
/// need h < 2.8/5000 (RK4), i.e. ≥ 17 900 steps; the stiff methods take a few hundred. The
/// largest relative error over all steps is compared with the exact solution; the bounds
/// are ~1.5× the measured values (BDF 3.4e-6, TR-BDF2 1.8e-4, ESDIRK34 3.0e-5, Rodas5P
/// 1.3e-7): the global error of the second- and third-order SDIRK methods grows along the
/// decaying slow mode to well above rtol.
#[test]
fn stiff_linear_problem_matches_its_exact_solution() {
    for method in STIFF {
        let s = solve(
            &StiffLinear,
            (0.0, 10.0),
            &StiffLinear::Y0,
            &opts(method, 1e-6, 1e-10),
        )
        .unwrap();
        let mut worst: f64 = 0.0;
        for k in 0..s.len() {
            let (y, e) = (s.state(k), StiffLinear::exact(s.t[k]));
            for i in 0..2 {
                worst = worst.max((y[i] - e[i]).abs() / e[i].abs().max(1e-10));
            }
        }
        let bound = match method {
            Method::Bdf => 5e-6,
            Method::Trbdf2 => 3e-4,
            Method::Esdirk34 => 5e-5,
            _ => 2e-7,
        };
        assert!(worst < bound, "{method}: worst relative error {worst:.3e}");
        assert!(s.stats.accepted < 1000, "{method}: {:?}", s.stats);
        // L-stability: the fast mode is gone after the first steps, y1 = y2 to round-off.
        let y = &s.y_final;
        assert!((y[0] - y[1]).abs() <= 1e-12 * y[0], "{method}: {y:?}");
    }
}

/// Prothero–Robinson, λ = −10⁶, exact y = cos t, no Jacobian given (finite differences; and
/// ∂f/∂t for Rodas5P). Stiffly accurate methods follow cos t to the tolerance.
#[test]
fn prothero_robinson_follows_the_smooth_solution() {
    for method in STIFF {
        let s = solve(
            &ProtheroRobinson,
            (0.0, 10.0),
            &[1.0],
            &opts(method, 1e-6, 1e-9),
        )
        .unwrap();
        let worst = (0..s.len())
            .map(|k| (s.state(k)[0] - s.t[k].cos()).abs())
            .fold(0.0, f64::max);
        // measured: BDF 1.5e-7, TR-BDF2 3.8e-7, ESDIRK34 2.3e-7, Rodas5P 1.2e-7
        assert!(worst < 1e-6, "{method}: worst error {worst:.3e}");
        assert!(
            s.stats.jac_evals > 0 && s.stats.accepted < 500,
            "{method}: {:?}",
            s.stats
        );
    }
}
