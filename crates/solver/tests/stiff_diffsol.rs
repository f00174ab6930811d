//! diffsol's BDF, TR-BDF2 and ESDIRK34 behind our Stepper: restarts, h_max, finite-difference
//! Jacobians, option checks and typed failures.

mod stiff_problems;

use lash_solver::diffsol_backend::DiffsolStepper;
use lash_solver::*;
use stiff_problems::{opts, Cliff, Logistic, NanJacobian, StiffLinear};

const DIFFSOL: [Method; 3] = [Method::Bdf, Method::Trbdf2, Method::Esdirk34];

/// The logistic equation from y(0) = 0.5 (the exact solution 1/(1 + e^{−t})).
fn logistic_b(t: f64) -> f64 {
    1.0 / (1.0 + (-t).exp())
}

#[test]
fn bdf_restart_resets_the_order_and_forgets_the_history() {
    // Integrate y(0) = 0.1 to t = 2, then restart on another trajectory (y(0) = 0.5, taken at
    // t = 2) and go on to t = 4. Stale history from the first trajectory would leave an error
    // of the size of the jump (~0.3); a clean restart keeps it at the tolerance.
    let o = opts(Method::Bdf, 1e-8, 1e-10);
    let problem = Problem::new(&Logistic, &o).unwrap();
    let mut st = DiffsolStepper::new(problem.diffsol().unwrap(), 0.0, &[0.1], &o).unwrap();
    assert_eq!(st.order(), 1);
    while st.t() < 2.0 {
        st.step(2.0).unwrap();
    }
    assert_eq!(st.t(), 2.0, "the stop time is hit exactly");
    assert!(st.order() >= 2, "BDF raised its order, got {}", st.order());
    assert!((st.y()[0] - Logistic::exact(2.0)).abs() < 1e-7);
    let accepted = st.stats().accepted;
    st.restart(2.0, &[logistic_b(2.0)]).unwrap();
    assert_eq!(st.order(), 1, "order reset by the restart");
    assert_eq!((st.t(), st.t_prev()), (2.0, 2.0));
    assert_eq!(st.stats().accepted, accepted, "counters carried over");
    while st.t() < 4.0 {
        st.step(4.0).unwrap();
    }
    assert_eq!(st.t(), 4.0);
    let err = (st.y()[0] - logistic_b(4.0)).abs();
    assert!(err < 1e-7, "error after restart {err:.3e}");
}

#[test]
fn sdirk_restart_starts_from_the_new_state() {
    for method in [Method::Trbdf2, Method::Esdirk34] {
        let o = opts(method, 1e-8, 1e-10);
        let problem = Problem::new(&Logistic, &o).unwrap();
        let mut st = DiffsolStepper::new(problem.diffsol().unwrap(), 0.0, &[0.1], &o).unwrap();
        while st.t() < 2.0 {
            st.step(2.0).unwrap();
        }
        st.restart(2.0, &[logistic_b(2.0)]).unwrap();
        while st.t() < 4.0 {
            st.step(4.0).unwrap();
        }
        let err = (st.y()[0] - logistic_b(4.0)).abs();
        // Stale stages would leave ~0.3; TR-BDF2 (order 2) ends at 2e-7, ESDIRK34 below.
        assert!(err < 1e-6, "{method}: error after restart {err:.3e}");
    }
}

#[test]
fn dense_output_stays_inside_the_last_step_and_is_accurate() {
    for method in DIFFSOL {
        let o = opts(method, 1e-8, 1e-10);
        let problem = Problem::new(&Logistic, &o).unwrap();
        let mut st = DiffsolStepper::new(problem.diffsol().unwrap(), 0.0, &[0.1], &o).unwrap();
        let mut worst: f64 = 0.0;
        let mut buf = [0.0];
        while st.t() < 4.0 {
            st.step(4.0).unwrap();
            let (a, b) = (st.t_prev(), st.t());
            for j in 0..=4 {
                let t = a + (b - a) * j as f64 / 4.0;
                st.interpolate(t, &mut buf);
                worst = worst.max((buf[0] - Logistic::exact(t)).abs());
            }
            st.interpolate(b, &mut buf);
            assert_eq!(
                buf[0],
                st.y()[0],
                "{method}: dense output ends on the state"
            );
        }
        // Global error of the order of the tolerance: the interpolant adds no more than it.
        assert!(worst < 1e-6, "{method}: worst dense error {worst:.3e}");
    }
}

#[test]
fn h_max_bounds_every_diffsol_step() {
    for method in DIFFSOL {
        let free = solve(
            &StiffLinear,
            (0.0, 10.0),
            &StiffLinear::Y0,
            &opts(method, 1e-6, 1e-10),
        )
        .unwrap();
        assert!(free.stats.h_max_used > 0.01, "{method}: h_max must matter");
        let o = SolverOptions {
            h_max: 0.01,
            ..opts(method, 1e-6, 1e-10)
        };
        let s = solve(&StiffLinear, (0.0, 10.0), &StiffLinear::Y0, &o).unwrap();
        assert!(
            s.stats.h_max_used <= 0.01 * (1.0 + 1e-10),
            "{method}: {:?}",
            s.stats
        );
        assert!(s.stats.accepted >= 1000, "10 s in steps of at most 0.01");
        assert_eq!(s.t_final, 10.0);
        let e = StiffLinear::exact(10.0);
        assert!(((s.y_final[0] - e[0]) / e[0]).abs() < 2e-4, "{method}");
    }
}

/// StiffLinear without its Jacobian.
struct NoJacobian;
impl OdeSystem for NoJacobian {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        StiffLinear.rhs(t, y, dy);
    }
}

#[test]
fn finite_difference_jacobians_are_counted_and_accurate() {
    for method in DIFFSOL {
        let o = SolverOptions {
            output: Output::Final,
            ..opts(method, 1e-6, 1e-10)
        };
        let s = solve(&NoJacobian, (0.0, 10.0), &StiffLinear::Y0, &o).unwrap();
        // One RHS per Newton iteration, f(t0, y0), the starting-step estimate, and n + 1 per
        // finite-difference Jacobian (f(t, y) and one per column).
        assert_eq!(
            s.stats.rhs_evals,
            s.stats.newton_iters + 2 + 3 * s.stats.jac_evals,
            "{method}: {:?}",
            s.stats
        );
        let analytic = solve(&StiffLinear, (0.0, 10.0), &StiffLinear::Y0, &o).unwrap();
        let d = ((s.y_final[0] - analytic.y_final[0]) / analytic.y_final[0]).abs();
        // The linear problem's differences are exact to ~1e-8: same answer to the tolerance.
        assert!(
            d < 1e-6,
            "{method}: FD vs analytic Jacobian differ by {d:.3e}"
        );
    }
}

#[test]
fn non_adaptive_and_controllers_are_rejected() {
    for method in DIFFSOL {
        let o = SolverOptions {
            adaptive: false,
            h0: Some(0.01),
            ..opts(method, 1e-6, 1e-10)
        };
        assert!(matches!(
            solve(&StiffLinear, (0.0, 1.0), &StiffLinear::Y0, &o),
            Err(SolveError::InvalidOptions(_))
        ));
        let o = SolverOptions {
            controller: Some(ControllerKind::Pi),
            ..opts(method, 1e-6, 1e-10)
        };
        assert!(matches!(
            solve(&StiffLinear, (0.0, 1.0), &StiffLinear::Y0, &o),
            Err(SolveError::InvalidOptions(_))
        ));
    }
}

#[test]
fn diffsol_failures_are_typed_errors_with_time_and_state() {
    for method in DIFFSOL {
        // RHS NaN past t = 1: Newton fails on every step reaching beyond.
        match solve(&Cliff, (0.0, 2.0), &[1.0], &opts(method, 1e-6, 1e-9)) {
            Err(SolveError::NewtonFailure { t, y, .. }) => {
                assert!(t <= 1.0 && t > 1.0 - 1e-6, "{method}: t = {t}");
                assert!((y[0] - (-t).exp()).abs() < 1e-4, "{method}: {y:?}");
            }
            other => panic!("{method}: expected NewtonFailure, got {other:?}"),
        }
        // NaN Jacobian: no step can be taken.
        match solve(&NanJacobian, (0.0, 1.0), &[1.0], &opts(method, 1e-6, 1e-9)) {
            Err(SolveError::NewtonFailure { t, y, .. }) => assert!(t == 0.0 && y == [1.0]),
            other => panic!("{method}: expected NewtonFailure, got {other:?}"),
        }
        // h_min above what the fast mode needs at rtol 1e-10.
        let o = SolverOptions {
            h_min: 1e-3,
            ..opts(method, 1e-10, 1e-12)
        };
        match solve(&StiffLinear, (0.0, 1.0), &StiffLinear::Y0, &o) {
            // (the SDIRK methods report the floor itself: the failing step is below it)
            Err(SolveError::StepSizeTooSmall { t, h, y }) => {
                assert!(
                    t == 0.0 && h <= 1e-3 && y == StiffLinear::Y0,
                    "{method}: t {t} h {h}"
                );
            }
            other => panic!("{method}: expected StepSizeTooSmall, got {other:?}"),
        }
    }
}

#[test]
fn max_steps_is_a_typed_error() {
    for method in DIFFSOL {
        let o = SolverOptions {
            max_steps: 20,
            ..opts(method, 1e-6, 1e-10)
        };
        match solve(&StiffLinear, (0.0, 10.0), &StiffLinear::Y0, &o) {
            Err(SolveError::TooManySteps { t, steps, y }) => {
                assert!(t > 0.0 && t < 10.0 && steps >= 20 && y.iter().all(|v| v.is_finite()));
            }
            other => panic!("{method}: expected TooManySteps, got {other:?}"),
        }
    }
}

#[test]
fn a_stop_time_within_round_off_is_bridged() {
    for method in DIFFSOL {
        let o = opts(method, 1e-8, 1e-10);
        let problem = Problem::new(&Logistic, &o).unwrap();
        let mut st = DiffsolStepper::new(problem.diffsol().unwrap(), 0.0, &[0.1], &o).unwrap();
        while st.t() < 1.0 {
            st.step(1.0).unwrap();
        }
        // diffsol cannot step 4 ulps: the stepper takes an explicit Euler sliver instead.
        let (t1, y1, acc) = (st.t(), st.y()[0], st.stats().accepted);
        let t2 = t1 + 4.0 * f64::EPSILON;
        st.step(t2).unwrap();
        assert_eq!((st.t_prev(), st.t()), (t1, t2), "{method}");
        assert_eq!(st.stats().accepted, acc + 1);
        let slope = y1 * (1.0 - y1);
        assert!((st.y()[0] - y1 - (t2 - t1) * slope).abs() <= f64::EPSILON * y1);
        // and integration goes on from there, accurately
        while st.t() < 4.0 {
            st.step(4.0).unwrap();
        }
        let err = (st.y()[0] - Logistic::exact(4.0)).abs();
        assert!(err < 1e-6, "{method}: {err:.3e}");
    }
}

/// The heat equation u_t = u_xx on (0, 1), u = 0 at both ends, by central differences on n
/// interior points: y' = A y, A = tridiag(1, −2, 1)/h², h = 1/(n + 1), stiff (|λ_max| ≈ 4/h²).
/// From the first eigenvector y_j(0) = sin(π j h) the exact solution of the discrete system is
/// y(t) = e^{λ₁ t} y(0), λ₁ = −4 sin²(π h/2)/h².
struct Heat(usize);

impl Heat {
    fn h(&self) -> f64 {
        1.0 / (self.0 as f64 + 1.0)
    }
    fn y0(&self) -> Vec<f64> {
        let h = self.h();
        (1..=self.0)
            .map(|j| (std::f64::consts::PI * j as f64 * h).sin())
            .collect()
    }
    fn lambda1(&self) -> f64 {
        let h = self.h();
        let s = (std::f64::consts::PI * h / 2.0).sin();
        -4.0 * s * s / (h * h)
    }
}

impl OdeSystem for Heat {
    fn dim(&self) -> usize {
        self.0
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        let n = self.0;
        let k = 1.0 / (self.h() * self.h());
        for j in 0..n {
            let l = if j > 0 { y[j - 1] } else { 0.0 };
            let r = if j + 1 < n { y[j + 1] } else { 0.0 };
            dy[j] = k * (l - 2.0 * y[j] + r);
        }
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], mut jac: faer::MatMut<'_, f64>) {
        let n = self.0;
        let k = 1.0 / (self.h() * self.h());
        for j in 0..n {
            jac[(j, j)] = -2.0 * k;
            if j > 0 {
                jac[(j, j - 1)] = k;
                jac[(j - 1, j)] = k;
            }
        }
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

#[test]
fn newton_matrices_on_both_sides_of_the_lu_crossover_solve_the_heat_equation() {
    // n = 60 is factored by nalgebra's LU, n = 150 by faer's (crate::auto_lu, from 100
    // unknowns): both follow the exact decay of the first mode to the tolerance.
    for n in [60, 150] {
        let sys = Heat(n);
        let t_end = 0.05;
        let want = (sys.lambda1() * t_end).exp();
        for method in DIFFSOL {
            let o = opts(method, 1e-8, 1e-10);
            let problem = Problem::new(&sys, &o).unwrap();
            let mut st =
                DiffsolStepper::new(problem.diffsol().unwrap(), 0.0, &sys.y0(), &o).unwrap();
            while st.t() < t_end {
                st.step(t_end).unwrap();
            }
            let err = st
                .y()
                .iter()
                .zip(sys.y0())
                .map(|(y, y0)| (y - want * y0).abs())
                .fold(0.0f64, f64::max);
            // e^{λ₁ t} ≈ 0.61: rtol 1e-8 per step, a few hundred steps at most.
            assert!(err < 1e-6, "{method} n = {n}: error {err:.3e}");
            assert!(st.stats().lu_factorizations > 0, "{method} n = {n}");
        }
    }
}

/// A damped string in first-order form, y = (q, v): q̈ = K q − α q̇ with K the heat equation's
/// Laplacian on `Heat(k)`'s grid; its Jacobian is [[0, I], [K, −αI]], whose Newton matrix
/// crate::auto_lu reduces to one system of size k from 100 unknowns.
struct String2(Heat, f64);

impl String2 {
    /// The first mode's amplitude from a(0) = 1, ȧ(0) = 0: ä + α ȧ − λ₁ a = 0.
    fn amplitude(&self, t: f64) -> f64 {
        let a = self.1;
        let wd = (-self.0.lambda1() - a * a / 4.0).sqrt();
        (-a * t / 2.0).exp() * ((wd * t).cos() + a / (2.0 * wd) * (wd * t).sin())
    }
}

impl OdeSystem for String2 {
    fn dim(&self) -> usize {
        2 * self.0 .0
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        let k = self.0 .0;
        dy[..k].copy_from_slice(&y[k..]);
        self.0.rhs(t, &y[..k], &mut dy[k..]);
        for j in 0..k {
            dy[k + j] -= self.1 * y[k + j];
        }
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, t: f64, y: &[f64], mut jac: faer::MatMut<'_, f64>) {
        let k = self.0 .0;
        jac.fill(0.0);
        for j in 0..k {
            jac[(j, k + j)] = 1.0;
            jac[(k + j, k + j)] = -self.1;
        }
        self.0.jacobian(t, &y[..k], jac.submatrix_mut(k, 0, k, k));
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

#[test]
fn a_damped_string_decays_as_its_first_mode_on_both_sides_of_the_lu_crossover() {
    // n = 60 (nalgebra's LU) and n = 200 (the Newton matrix reduced to k = 100 unknowns):
    // the first mode's amplitude follows its closed form to the tolerance.
    for k in [30, 100] {
        let sys = String2(Heat(k), 1.0);
        let t_end = 1.0;
        let want = sys.amplitude(t_end);
        let mut y0 = sys.0.y0();
        y0.resize(2 * k, 0.0);
        for method in DIFFSOL {
            let o = opts(method, 1e-8, 1e-10);
            let problem = Problem::new(&sys, &o).unwrap();
            let mut st = DiffsolStepper::new(problem.diffsol().unwrap(), 0.0, &y0, &o).unwrap();
            while st.t() < t_end {
                st.step(t_end).unwrap();
            }
            let err = st.y()[..k]
                .iter()
                .zip(&y0)
                .map(|(y, y0)| (y - want * y0).abs())
                .fold(0.0f64, f64::max);
            // a(1) ≈ −0.6: a few hundred steps at rtol 1e-8 leave ~1e-7.
            assert!(
                err < 1e-6,
                "{method} k = {k}: error {err:.3e} (a = {want:.4})"
            );
        }
    }
}
