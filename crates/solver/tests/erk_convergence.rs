//! Fixed-step convergence orders (the `adaptive = false` mode) and dense-output orders.
//!
//! ```text
//! global error  ‖y_N − y(T)‖ = C h^p + O(h^{p+1})       → slope p of log err vs log h
//! dense output  ‖u(t0 + θh) − y(t0 + θh)‖ = C h^{q+1}     (one step from the exact state)
//! ```
//! Problem: Kepler's two-body problem (HNW I §II.10), exact solution from Kepler's equation,
//! eccentricity 0.1, except 0.05 for DOP853 (its 8th-order terms stay pre-asymptotic near
//! the pericentre longer) and 0.5 for Tsitouras' dense output (on the milder orbit its
//! pairwise slopes wander between 4.8 and 5.7 over the usable step range). Measured slopes: global bs32 2.99,
//! dopri54 4.97, tsit54 5.00, dop853 7.93, rk4 4.06; dense bs32 4.02, dopri54 5.01,
//! tsit54 5.04, dop853 7.91. Step ranges
//! are chosen per method where the error lies between about 1e-5 and 1e-13: past the
//! pre-asymptotic regime, above round-off (≈ 1e-14).

mod common;
use common::*;
use lash_solver::*;

const E: f64 = 0.1;

/// Global error after one period (t = 2π) with N fixed steps; the exact solution is y0.
fn kepler_error(method: Method, n: usize, e: f64) -> f64 {
    let sys = Kepler { e };
    let t_end = 2.0 * std::f64::consts::PI;
    let h = t_end / n as f64;
    let s = solve(&sys, (0.0, t_end), &sys.y0(), &fixed(method, h)).unwrap();
    assert_eq!(
        s.stats.accepted, n,
        "{method}: fixed mode must take exactly N steps"
    );
    assert_eq!(s.stats.rejected_error, 0);
    dist(&s.y_final, &sys.y0())
}

fn assert_global_order(method: Method, p: usize, ns: &[usize], e: f64) {
    let hs: Vec<f64> = ns.iter().map(|&n| 1.0 / n as f64).collect();
    let errs: Vec<f64> = ns.iter().map(|&n| kepler_error(method, n, e)).collect();
    let order = slope(&hs, &errs);
    assert!(
        (order - p as f64).abs() <= 0.2,
        "{method}: observed order {order:.3}, nominal {p} (errors {errs:?})"
    );
    // The smallest error is far above round-off, so the slope is the method's.
    assert!(errs.iter().all(|&e| e > 1e-12), "{method}: {errs:?}");
}

#[test]
fn bs32_fixed_step_order_3() {
    assert_global_order(Method::Bs32, 3, &[320, 640, 1280], E);
}

#[test]
fn dopri54_fixed_step_order_5() {
    assert_global_order(Method::Dopri54, 5, &[160, 320, 640], E);
}

#[test]
fn tsit54_fixed_step_order_5() {
    assert_global_order(Method::Tsit54, 5, &[160, 320, 640], E);
}

#[test]
fn dop853_fixed_step_order_8() {
    assert_global_order(Method::Dop853, 8, &[32, 40, 48, 57], 0.05);
}

#[test]
fn rk4_fixed_step_order_4() {
    assert_global_order(Method::Rk4, 4, &[320, 640, 1280], E);
}

#[test]
fn fixed_mode_needs_h0_and_is_refused_for_diffsol() {
    let sys = Kepler { e: E };
    let opts = SolverOptions {
        method: Method::Dopri54,
        adaptive: false,
        ..Default::default()
    };
    assert!(matches!(
        solve(&sys, (0.0, 1.0), &sys.y0(), &opts),
        Err(SolveError::InvalidOptions(_))
    ));
    let opts = SolverOptions {
        method: Method::Bdf,
        adaptive: false,
        h0: Some(0.1),
        ..Default::default()
    };
    assert!(matches!(
        solve(&sys, (0.0, 1.0), &sys.y0(), &opts),
        Err(SolveError::InvalidOptions(_))
    ));
}

#[test]
fn fixed_mode_counts_are_stages_per_step() {
    // 10 steps of 0.1: 1 RHS at the start, then s − 1 per step for FSAL pairs (the last stage
    // is the next first), 12 per step for DOP853 (11 new stages + f(t+h, y_{n+1})). No
    // starting-step estimate (h0 is given), no error test.
    let sys = Kepler { e: E };
    for (m, per_step) in [
        (Method::Bs32, 3),
        (Method::Dopri54, 6),
        (Method::Tsit54, 6),
        (Method::Dop853, 12),
    ] {
        let s = solve(&sys, (0.0, 1.0), &sys.y0(), &fixed(m, 0.1)).unwrap();
        assert_eq!(s.stats.accepted, 10, "{m}");
        assert_eq!(s.stats.steps, 10, "{m}");
        assert_eq!(s.stats.rhs_evals, 1 + 10 * per_step, "{m}");
        assert_eq!(s.t_final, 1.0);
    }
}

/// Max over θ ∈ {0.1, …, 0.9} of the dense-output error of one step of size h from the
/// exact state at t0 = 0.7 (a generic point of the orbit).
fn dense_error(method: Method, h: f64, e: f64) -> f64 {
    let sys = Kepler { e };
    let t0 = 0.7;
    let y0 = sys.exact(t0);
    let o = fixed(method, h);
    let problem = Problem::new(&sys, &o).unwrap();
    let mut it = problem.integrator(t0, t0 + h, &y0).unwrap();
    let out = it.step().unwrap();
    assert_eq!(out, StepOutcome::StopTime { t: t0 + h });
    let mut worst: f64 = 0.0;
    let mut y = [0.0; 4];
    for j in 1..10 {
        let theta = j as f64 / 10.0;
        it.interpolate(t0 + theta * h, &mut y);
        worst = worst.max(dist(&y, &sys.exact(t0 + theta * h)));
    }
    worst
}

fn assert_dense_order(method: Method, q: usize, hs: &[f64], e: f64) {
    let errs: Vec<f64> = hs.iter().map(|&h| dense_error(method, h, e)).collect();
    let order = slope(hs, &errs);
    assert!(
        (order - (q + 1) as f64).abs() <= 0.2,
        "{method}: dense local order {order:.3}, nominal {} (errors {errs:?})",
        q + 1
    );
    assert!(errs.iter().all(|&e| e > 1e-13), "{method}: {errs:?}");
}

#[test]
fn bs32_hermite_dense_output_order_3() {
    // Local interpolation error O(h⁴) for a dense output of order 3.
    assert_dense_order(Method::Bs32, 3, &[0.05, 0.025, 0.0125], E);
}

#[test]
fn dopri54_dense_output_order_4() {
    assert_dense_order(Method::Dopri54, 4, &[0.05, 0.025, 0.0125], E);
}

#[test]
fn tsit54_dense_output_order_4() {
    assert_dense_order(Method::Tsit54, 4, &[0.1, 0.05, 0.025, 0.0125], 0.5);
}

#[test]
fn dop853_dense_output_order_7() {
    // The three extra stages are evaluated on first use of the step's dense output. Local
    // error O(h⁸) for a dense output of order 7.
    assert_dense_order(Method::Dop853, 7, &[0.3, 0.2, 0.15, 0.1], 0.05);
}

#[test]
fn dop853_dense_stages_are_lazy_and_counted() {
    // One fixed step: 1 (f0) + 12 RHS. Interpolating adds the 3 dense stages once; they are
    // counted in the stats returned by `solve` (folded in at the end of the run).
    let sys = Kepler { e: E };
    let s = solve(&sys, (0.0, 0.1), &sys.y0(), &fixed(Method::Dop853, 0.1)).unwrap();
    assert_eq!(s.stats.rhs_evals, 13);
    let opts = SolverOptions {
        output: Output::Times(vec![0.03, 0.05, 0.07]),
        ..fixed(Method::Dop853, 0.1)
    };
    let s = solve(&sys, (0.0, 0.1), &sys.y0(), &opts).unwrap();
    assert_eq!(s.stats.rhs_evals, 16);
    assert_eq!(s.len(), 3);
}
