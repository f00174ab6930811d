//! RK4 and the event driver on problems with closed forms.

mod common;
use common::Ball;
use lash_solver::*;

/// y' = λ y, y(0) = 1: exact solution e^{λt}.
struct Exp(f64);
impl OdeSystem for Exp {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = self.0 * y[0];
    }
}

fn rk4(step: f64) -> SolverOptions {
    SolverOptions {
        method: Method::Rk4,
        step: Some(step),
        ..Default::default()
    }
}

#[test]
fn rk4_converges_with_order_four() {
    let sys = Exp(-1.0);
    let err = |h: f64| {
        let s = solve(&sys, (0.0, 1.0), &[1.0], &rk4(h)).unwrap();
        (s.y_final[0] - (-1.0f64).exp()).abs()
    };
    let (e1, e2) = (err(0.1), err(0.05));
    let order = (e1 / e2).log2();
    assert!((order - 4.0).abs() < 0.2, "observed order {order}");
}

#[test]
fn rk4_counts_are_four_per_step_plus_one() {
    let s = solve(&Exp(-1.0), (0.0, 1.0), &[1.0], &rk4(0.1)).unwrap();
    assert_eq!(s.stats.accepted, 10);
    assert_eq!(s.stats.rhs_evals, 41);
    assert_eq!(s.len(), 11);
    assert!((s.t_final - 1.0).abs() == 0.0);
}

#[test]
fn rk4_beyond_stability_limit_is_a_typed_error() {
    // RK4's real stability interval is [-2.785, 0]: h = 0.3 with λ = -10 gives hλ = -3.
    let r = solve(&Exp(-10.0), (0.0, 1000.0), &[1.0], &rk4(0.3));
    match r {
        Err(SolveError::NonFiniteState { t, y }) => {
            assert!(t > 0.0 && y[0].is_finite());
        }
        other => panic!("expected NonFiniteState, got {other:?}"),
    }
}

#[test]
fn bouncing_ball_bounce_times_with_rk4() {
    // Dropped from h0 = 1 m at rest: first impact at t1 = sqrt(2 h0 / g); each later flight
    // lasts 2 e v_k / g with v_k the impact speed, reduced by e at each bounce.
    let (e, h0) = (0.8f64, 1.0f64);
    let expected = Ball { e }.bounce_times(h0, 4);
    // A quadratic trajectory is integrated exactly by RK4; the Hermite dense output is exact
    // for cubics, so event location is limited only by the root-finder tolerance.
    let s = solve(&Ball { e }, (0.0, 2.5), &[h0, 0.0], &rk4(0.01)).unwrap();
    assert_eq!(s.events.len(), 4);
    for (hit, te) in s.events.iter().zip(&expected) {
        assert!((hit.t - te).abs() < 1e-9, "{} vs {}", hit.t, te);
        assert!(!hit.rising);
    }
}
