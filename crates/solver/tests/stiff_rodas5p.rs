//! Rodas5P: convergence orders, controllers, fixed steps, restarts and typed failures.

mod stiff_problems;

use faer::MatMut;
use lash_solver::rosenbrock::GAMMA;
use lash_solver::*;
use stiff_problems::{opts, Cliff, ForcedSine, Logistic, NanJacobian, StiffLinear};

fn fixed(h: f64) -> SolverOptions {
    SolverOptions {
        method: Method::Rodas5p,
        adaptive: false,
        h0: Some(h),
        ..Default::default()
    }
}

/// Error at t = 4 and largest error of the dense output (9 interior points per step) on
/// the logistic equation with fixed step h.
fn logistic_errors(h: f64) -> (f64, f64, usize) {
    let o = fixed(h);
    let problem = Problem::new(&Logistic, &o).unwrap();
    let mut it = problem.integrator(0.0, 4.0, &[0.1]).unwrap();
    let mut dense: f64 = 0.0;
    let mut buf = [0.0];
    loop {
        let outcome = it.step().unwrap();
        let (a, b) = (it.t_prev(), it.t());
        for j in 1..10 {
            let t = a + (b - a) * j as f64 / 10.0;
            it.interpolate(t, &mut buf);
            dense = dense.max((buf[0] - Logistic::exact(t)).abs());
        }
        if matches!(outcome, StepOutcome::StopTime { .. }) {
            break;
        }
    }
    let end = (it.y()[0] - Logistic::exact(4.0)).abs();
    (end, dense, it.stats().accepted)
}

#[test]
fn rodas5p_fixed_step_converges_with_order_five() {
    let runs: Vec<_> = [0.1, 0.05, 0.025].map(logistic_errors).to_vec();
    assert_eq!(
        runs.iter().map(|r| r.2).collect::<Vec<_>>(),
        [40, 80, 160],
        "fixed steps of 4/h"
    );
    for w in runs.windows(2) {
        let order = (w[0].0 / w[1].0).log2();
        assert!((order - 5.0).abs() <= 0.2, "observed order {order}");
    }
}

/// The continuous extension has order 4 (local error O(h⁵)), so the interpolated values
/// carry the O(h⁵) global error of the steps.
#[test]
fn rodas5p_dense_output_converges_with_order_five() {
    let runs: Vec<_> = [0.1, 0.05, 0.025].map(logistic_errors).to_vec();
    for w in runs.windows(2) {
        let order = (w[0].1 / w[1].1).log2();
        assert!((order - 5.0).abs() <= 0.2, "observed dense order {order}");
    }
}

/// Fixed steps h = 1/n on [0, 1]: (|y(1) − sin 1|, max |y(t_m) − sin t_m| over the step
/// midpoints t_m from the dense output).
fn prothero_robinson_errors(lambda: f64, n: usize) -> (f64, f64) {
    let h = 1.0 / n as f64;
    let mids: Vec<f64> = (0..n).map(|k| (k as f64 + 0.5) * h).collect();
    let mut times = mids.clone();
    times.push(1.0);
    let o = SolverOptions {
        output: Output::Times(times),
        ..fixed(h)
    };
    let s = solve(&ForcedSine(lambda), (0.0, 1.0), &[0.0], &o).unwrap();
    let mid = (0..n)
        .map(|k| (s.y[k] - mids[k].sin()).abs())
        .fold(0.0, f64::max);
    ((s.y[n] - 1f64.sin()).abs(), mid)
}

/// Non-stiff forced problem (λ = −1): the dense output converges with order 5 (the O(h⁵)
/// global error of the steps dominates its O(h⁵) local error). Measured 5.03 and 5.02 for
/// n = 10 → 20 → 40. With a forward difference for ∂f/∂t (relative error ~1e-8) it was
/// 4.98 then 1.83: an error 1.6e-8 h² of the dense output from the f_t terms.
#[test]
fn rodas5p_dense_output_of_a_forced_problem() {
    let e: Vec<f64> = [10, 20, 40]
        .map(|n| prothero_robinson_errors(-1.0, n).1)
        .to_vec();
    for w in e.windows(2) {
        let order = (w[0] / w[1]).log2();
        assert!((order - 5.0).abs() <= 0.2, "dense order {order} ({e:?})");
    }
}

/// Stiff Prothero–Robinson, λ = −1e6 (hλ = −1e5 … −2.5e4): the step-end error converges with
/// order 3, not 5. This is the order reduction of Rosenbrock methods on stiff forced problems
/// (HNW II, §IV.15): in the limit hλ → −∞ the error is governed by the stage order, and
/// Rodas5P, built to limit it (Steinebach 2023), keeps 3. Measured 2.98, 3.06 for n = 10 → 20
/// → 40 (the errors are 5e-12 … 8e-14, above rounding).
#[test]
fn rodas5p_stiff_prothero_robinson_order_is_three() {
    let e: Vec<f64> = [10, 20, 40]
        .map(|n| prothero_robinson_errors(-1e6, n).0)
        .to_vec();
    for w in e.windows(2) {
        let order = (w[0] / w[1]).log2();
        assert!((order - 3.0).abs() <= 0.3, "stiff order {order} ({e:?})");
    }
}

#[test]
fn rodas5p_non_adaptive_takes_h0_every_step() {
    let s = solve(&StiffLinear, (0.0, 1.0), &StiffLinear::Y0, &fixed(0.01)).unwrap();
    assert_eq!(s.stats.accepted, 100);
    assert_eq!(s.stats.steps, 100);
    // f(t_n, y_n) and 7 stages per step, analytic Jacobian, autonomous: no f_t.
    assert_eq!(s.stats.rhs_evals, 800);
    assert!((s.stats.h_max_used - 0.01).abs() < 1e-15 && (s.stats.h_min_used - 0.01).abs() < 1e-12);
    assert_eq!(s.t_final, 1.0);
    // Stable at h·λ = −50 on the fast mode (L-stable method): the solution is right.
    let e = StiffLinear::exact(1.0);
    assert!(
        (s.y_final[0] - e[0]).abs() < 1e-9 * e[0],
        "{:?} vs {e:?}",
        s.y_final
    );
}

#[test]
fn rodas5p_accepts_every_controller() {
    for kind in ControllerKind::ALL {
        let o = SolverOptions {
            controller: Some(kind),
            output: Output::Final,
            ..opts(Method::Rodas5p, 1e-6, 1e-10)
        };
        let s = solve(&StiffLinear, (0.0, 10.0), &StiffLinear::Y0, &o).unwrap();
        let e = StiffLinear::exact(10.0);
        let rel = (s.y_final[0] - e[0]).abs() / e[0];
        // Global error of the order of the tolerance (Gustafsson: 1.3e-7).
        assert!(rel < 1e-6, "{kind}: relative error {rel:.3e}");
        assert!(s.stats.accepted < 200, "{kind}: {:?}", s.stats);
    }
}

#[test]
fn rodas5p_restart_is_a_fresh_start() {
    // After a restart the stepper forgets its controller history and chooses the first step
    // as at t0: the step it takes equals the first step of a stepper built at that state.
    let o = opts(Method::Rodas5p, 1e-6, 1e-10);
    let problem = Problem::new(&StiffLinear, &o).unwrap();
    let mut st = make_stepper(&problem, 0.0, &StiffLinear::Y0).unwrap();
    while st.t() < 1.0 {
        st.step(10.0).unwrap();
    }
    let (t, y) = (st.t(), st.y().to_vec());
    st.restart(t, &y).unwrap();
    assert_eq!(st.t_prev(), t);
    let mut out = [0.0; 2];
    st.interpolate(t, &mut out);
    assert_eq!(out.as_slice(), y.as_slice());
    st.step(10.0).unwrap();
    let mut fresh = make_stepper(&problem, t, &y).unwrap();
    fresh.step(10.0).unwrap();
    assert_eq!((st.t_prev(), st.t()), (fresh.t_prev(), fresh.t()));
    assert_eq!(st.y(), fresh.y());
}

/// λ = 1/(hγ) makes W = I/(hγ) − J exactly zero at step h.
struct SingularAt(f64);
impl OdeSystem for SingularAt {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = 1.0 / (self.0 * GAMMA) * y[0];
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], mut jac: MatMut<'_, f64>) {
        jac[(0, 0)] = 1.0 / (self.0 * GAMMA);
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

#[test]
fn rodas5p_singular_w_is_a_newton_failure() {
    // Fixed step: no smaller step to try.
    let r = solve(&SingularAt(0.1), (0.0, 1.0), &[1.0], &fixed(0.1));
    match r {
        Err(SolveError::NewtonFailure { t, y, .. }) => assert!(t == 0.0 && y == [1.0]),
        other => panic!("expected NewtonFailure, got {other:?}"),
    }
    // Adaptive, with a NaN Jacobian: every W fails; the step shrinks until it underflows.
    let o = opts(Method::Rodas5p, 1e-6, 1e-9);
    let problem = Problem::new(&NanJacobian, &o).unwrap();
    let mut it = problem.integrator(0.0, 1.0, &[1.0]).unwrap();
    match it.step() {
        Err(SolveError::NewtonFailure { t, y, .. }) => assert!(t == 0.0 && y == [1.0]),
        other => panic!("expected NewtonFailure, got {other:?}"),
    }
    let s = it.stats();
    assert_eq!(s.accepted, 0);
    assert!(
        s.rejected_newton > 10 && s.rejected_newton == s.lu_factorizations,
        "{s:?}"
    );
}

#[test]
fn rodas5p_non_finite_stages_end_in_a_typed_error() {
    // The RHS is NaN past t = 1: steps that reach beyond are rejected and shrink until the
    // floor 16 ε |t|; the error carries the last finite state, e^{−t} there.
    match solve(
        &Cliff,
        (0.0, 2.0),
        &[1.0],
        &opts(Method::Rodas5p, 1e-6, 1e-9),
    ) {
        Err(SolveError::NonFiniteState { t, y }) => {
            assert!(t <= 1.0 && t > 1.0 - 1e-6, "t = {t}");
            assert!((y[0] - (-t).exp()).abs() < 1e-6, "{y:?}");
        }
        other => panic!("expected NonFiniteState, got {other:?}"),
    }
}

#[test]
fn rodas5p_h_min_is_a_floor() {
    let o = SolverOptions {
        h_min: 1e-3,
        ..opts(Method::Rodas5p, 1e-10, 1e-12)
    };
    // The fast mode (rate 5000) needs steps far below 1e-3 at rtol 1e-10.
    match solve(&StiffLinear, (0.0, 1.0), &StiffLinear::Y0, &o) {
        Err(SolveError::StepSizeTooSmall { t, h, y }) => {
            assert!(t == 0.0 && h < 1e-3 && y == StiffLinear::Y0);
        }
        other => panic!("expected StepSizeTooSmall, got {other:?}"),
    }
}
