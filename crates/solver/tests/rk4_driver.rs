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

/// y' = −k y / (1 + (y/s)²): the linearisation at the origin has λ = −k, and the rate falls as
/// |y| grows. The exact solution decays monotonically to 0. Fixed-step RK4 past its stability
/// radius r = 2.785 (h k = 4) amplifies small y by |R(−4)| = 5 per step until |y| is large
/// enough that the effective rate k/(1 + (y/s)²) is stable again: a spurious bounded solution
/// (Yee, Sweby & Griffiths 1991) that the divergence bound cannot catch.
struct Saturating {
    k: f64,
    s: f64,
}
impl OdeSystem for Saturating {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = -self.k * y[0] / (1.0 + (y[0] / self.s).powi(2));
    }
}

#[test]
fn stability_check_catches_spurious_bounded_solutions() {
    use lash_solver::rk4::RK4_STABILITY_RADIUS;
    // −r is the real root of z³ + 4z² + 12z + 24, where R(z) = 1 again.
    let r = RK4_STABILITY_RADIUS;
    assert!((-r * r * r + 4.0 * r * r - 12.0 * r + 24.0).abs() < 1e-12);
    let sys = Saturating { k: 1000.0, s: 1.0 };
    let run = |hk: f64, check: usize| {
        let o = SolverOptions {
            rk4_instability_steps: check,
            ..rk4(hk / sys.k)
        };
        solve(&sys, (0.0, 2.0), &[1e-3], &o)
    };
    // Past the radius, without the check: finite, bounded and wrong (the exact solution is
    // below 1e-3·e^{−k t/(1 + 1e-6)}, i.e. 0 in double precision at t = 2).
    let y = run(4.0, 0).unwrap().y_final[0].abs();
    assert!(y > 0.05 && y < 1.0, "spurious solution {y}");
    // With the check: Rk4Unstable within the first 15 + a few steps (the amplitude must
    // first grow from 1e-3; the flagged run starts at once since h ρ ≈ h k = 4 there). The
    // limit is 2.785/|λ| with λ = ∂f/∂y = −k(1 − (y/s)²)/(1 + (y/s)²)², |λ| ≤ k, so at least 2.785/k,
    // and at most the step (the step was flagged).
    for hk in [3.0, 4.0, 6.0] {
        match run(hk, 15) {
            Err(SolveError::Rk4Unstable {
                t,
                y,
                h,
                h_limit,
                steps,
            }) => {
                assert_eq!(h, hk / sys.k);
                assert!(t <= 40.0 * h && t >= 14.0 * h, "h k = {hk}: t = {t}");
                assert!(y[0].is_finite());
                assert_eq!(steps, 15);
                assert!(
                    h_limit >= 0.99 * RK4_STABILITY_RADIUS / sys.k && h_limit < h,
                    "h k = {hk}: limit {h_limit}"
                );
            }
            other => panic!("h k = {hk}: {other:?}"),
        }
    }
    // Inside the radius (h k = 2.7 < 2.785) the check never fires and the solution decays by
    // |R(−2.7)| = 0.8794 per step: 1e-3 · 0.8794^740 = 5e-45 after 740 steps.
    let y = run(2.7, 15).unwrap().y_final[0];
    assert!(y.abs() < 1e-43, "{y}");
}
