//! Adaptive runs of the explicit pairs: periodic orbit, tolerance proportionality, limits and
//! typed failures.

mod common;
use common::*;
use lash_solver::*;

fn opts(method: Method, rtol: f64, atol: f64) -> SolverOptions {
    SolverOptions {
        method,
        rtol,
        atol: Atol::Scalar(atol),
        output: Output::Final,
        ..Default::default()
    }
}

fn arenstorf_error(m: Method, tol: f64) -> f64 {
    let s = solve(
        &Arenstorf,
        (0.0, Arenstorf::T),
        &Arenstorf::Y0,
        &opts(m, tol, tol),
    )
    .unwrap();
    assert_eq!(s.t_final, Arenstorf::T);
    dist(&s.y_final, &Arenstorf::Y0)
}

#[test]
fn arenstorf_orbit_closes_after_one_period() {
    // HNW I p. 129–130: the orbit is periodic with period T, so y(T) = y0. Near the close
    // approach to the moon local errors are amplified about 1e3–1e4 times (measured
    // err/tol: bs32 3e4, dopri54 2e4, tsit54 1e3, dop853 1e3), so at tol = 1e-12 the orbit
    // must close to 1e-7; and tightening the tolerance 100× must shrink the error at least
    // 30× (proportionality would give 100×).
    for (m, _) in PAIRS {
        let e10 = arenstorf_error(m, 1e-10);
        let e12 = arenstorf_error(m, 1e-12);
        assert!(e12 < 1e-7, "{m}: ‖y(T) − y0‖ = {e12:e}");
        assert!(e10 / e12 > 30.0, "{m}: {e10:e} → {e12:e}");
    }
}

#[test]
fn linear_spiral_global_error_tracks_tolerance() {
    // y' = A y, A = [[−0.1, −1], [1, −0.1]] on [0, 20], exact e^{At} y0. With local
    // extrapolation the step is h ∝ tol^{1/(q̂+1)} and the global error ∝ h^p with p = q̂ + 1
    // for every pair here, so err ∝ tol¹: the slope of log err against log tol is 1.
    let sys = Spiral { a: 0.1, w: 1.0 };
    let y0 = [1.0, 0.5];
    let exact = sys.exact(20.0, &y0);
    let tols = [1e-4, 1e-6, 1e-8, 1e-10];
    for (m, _) in PAIRS {
        let errs: Vec<f64> = tols
            .iter()
            .map(|&tol| {
                let s = solve(&sys, (0.0, 20.0), &y0, &opts(m, tol, tol)).unwrap();
                dist(&s.y_final, &exact)
            })
            .collect();
        let k = slope(&tols, &errs);
        assert!(
            (k - 1.0).abs() <= 0.15,
            "{m}: slope {k:.3}, errors {errs:?}"
        );
        // And the error is of the size of the tolerance (measured err/tol: bs32 14,
        // dopri54 1.5, tsit54 0.5–1.7, dop853 0.25).
        for (e, t) in errs.iter().zip(&tols) {
            assert!(
                *e / t > 0.05 && *e / t < 50.0,
                "{m}: err {e:e} at tol {t:e}"
            );
        }
    }
}

/// y' = 0.4 cos t (y = 1 + 0.4 sin t ≤ 1.4), but the RHS is NaN outside y ≤ 1.5: a model
/// defined on a domain that a too-large stage leaves.
struct Domain;
impl OdeSystem for Domain {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = if y[0] <= 1.5 { 0.4 * t.cos() } else { f64::NAN };
    }
}

#[test]
fn nan_stage_is_a_rejection_and_the_step_shrinks() {
    // h0 = 3: stages reach y ≈ 1 + 3·0.4 > 1.5 → NaN → rejected (ε = ∞), h ← 0.2 h.
    for (m, _) in PAIRS {
        let o = SolverOptions {
            h0: Some(3.0),
            ..opts(m, 1e-8, 1e-10)
        };
        let s = solve(&Domain, (0.0, 6.0), &[1.0], &o).unwrap();
        assert!(s.stats.rejected_error >= 1, "{m}");
        assert!(s.stats.h_max_used < 3.0, "{m}");
        assert!(
            (s.y_final[0] - (1.0 + 0.4 * 6f64.sin())).abs() < 1e-7,
            "{m}"
        );
    }
}

/// y' = 1, but the RHS is NaN for t > 1: nothing can step past t = 1.
struct Wall;
impl OdeSystem for Wall {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, _y: &[f64], dy: &mut [f64]) {
        dy[0] = if t <= 1.0 { 1.0 } else { f64::NAN };
    }
}

#[test]
fn non_finite_rhs_that_no_step_avoids_is_non_finite_state() {
    // Steps shrink towards t = 1 until they underflow 16 ε |t|; the error names the last
    // finite state, y(t) = t.
    for (m, _) in PAIRS {
        match solve(&Wall, (0.0, 2.0), &[0.0], &opts(m, 1e-6, 1e-9)) {
            Err(SolveError::NonFiniteState { t, y }) => {
                assert!(t <= 1.0 && t > 1.0 - 1e-12, "{m}: t = {t}");
                assert!((y[0] - t).abs() < 1e-12, "{m}");
            }
            other => panic!("{m}: expected NonFiniteState, got {other:?}"),
        }
    }
}

#[test]
fn step_below_h_min_is_step_size_too_small() {
    // y' = −1000 y: explicit stability needs h ≲ 3/1000, but h_min = 0.01; the error test
    // fails at h_min and the solver reports the step it would need.
    struct Stiff;
    impl OdeSystem for Stiff {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = -1000.0 * y[0];
        }
    }
    for (m, _) in PAIRS {
        let o = SolverOptions {
            h_min: 0.01,
            ..opts(m, 1e-6, 1e-9)
        };
        match solve(&Stiff, (0.0, 1.0), &[1.0], &o) {
            Err(SolveError::StepSizeTooSmall { t, h, y }) => {
                assert!(h < 0.01, "{m}: h = {h}");
                assert!((0.0..1.0).contains(&t) && y[0].is_finite(), "{m}");
            }
            other => panic!("{m}: expected StepSizeTooSmall, got {other:?}"),
        }
    }
}

#[test]
fn max_steps_counts_attempts() {
    for (m, _) in PAIRS {
        let o = SolverOptions {
            max_steps: 10,
            ..opts(m, 1e-8, 1e-8)
        };
        match solve(&Arenstorf, (0.0, Arenstorf::T), &Arenstorf::Y0, &o) {
            Err(SolveError::TooManySteps { t, steps, y }) => {
                assert_eq!(steps, 10, "{m}");
                assert!(t > 0.0 && t < Arenstorf::T && y.len() == 4, "{m}");
            }
            other => panic!("{m}: expected TooManySteps, got {other:?}"),
        }
    }
}

#[test]
fn h_max_is_honoured() {
    let sys = Spiral { a: 0.1, w: 1.0 };
    for (m, _) in PAIRS {
        let o = SolverOptions {
            h_max: 0.01,
            ..opts(m, 1e-4, 1e-6)
        };
        let s = solve(&sys, (0.0, 2.0), &[1.0, 0.0], &o).unwrap();
        assert!(s.stats.h_max_used <= 0.01, "{m}");
        // 2 / 0.01 = 200 steps at least (the first one starts smaller).
        assert!(s.stats.accepted >= 200, "{m}: {}", s.stats.accepted);
    }
}

#[test]
fn restart_resets_fsal_and_chooses_the_first_step_afresh() {
    // After restart(t, y) the stepper forgets its FSAL stage and controller history: its next
    // step evaluates f(t, y) and the starting-step estimate (2 RHS) before the stages, and is
    // the step a stepper built at (t, y) takes, bit for bit.
    let sys = Spiral { a: 0.1, w: 1.0 };
    for (m, _) in PAIRS {
        let o = opts(m, 1e-6, 1e-9);
        let problem = Problem::new(&sys, &o).unwrap();
        let mut st = make_stepper(&problem, 0.0, &[1.0, 0.0]).unwrap();
        for _ in 0..5 {
            st.step(100.0).unwrap();
        }
        let rhs = st.stats().rhs_evals;
        let (t, y) = (st.t(), [0.3, -0.2]);
        st.restart(t, &y).unwrap();
        assert_eq!(st.t(), t);
        assert_eq!(st.t_prev(), t);
        assert_eq!(st.y(), &y);
        assert_eq!(
            st.stats().rhs_evals,
            rhs,
            "{m}: nothing evaluated before the next step"
        );
        let mut out = [0.0; 2];
        st.interpolate(t, &mut out);
        assert_eq!(
            out, y,
            "{m}: dense output after restart is the restart state"
        );
        st.step(100.0).unwrap();
        let mut fresh = make_stepper(&problem, t, &y).unwrap();
        fresh.step(100.0).unwrap();
        assert_eq!((st.t_prev(), st.t()), (fresh.t_prev(), fresh.t()), "{m}");
        assert_eq!(st.y(), fresh.y(), "{m}");
        assert_eq!(
            st.stats().rhs_evals - rhs,
            fresh.stats().rhs_evals,
            "{m}: the same work as a fresh start"
        );
    }
}

#[test]
fn a_step_ending_within_ulps_of_the_stop_time_lands_on_it() {
    // Fixed steps of 1e-5 from t = 1 to 1 + 2e-5 + 2e-15: the sliver 2e-15 left after two
    // steps is below 16 ulps of t (3.6e-15), which no step could take; the second step is
    // stretched to end exactly on t_end.
    let sys = Spiral { a: 0.1, w: 1.0 };
    let t_end = 1.0 + 2e-5 + 2e-15;
    for (m, _) in PAIRS {
        let s = solve(&sys, (1.0, t_end), &[1.0, 0.0], &fixed(m, 1e-5)).unwrap();
        assert_eq!(s.stats.accepted, 2, "{m}");
        assert_eq!(s.t_final, t_end, "{m}");
    }
}
