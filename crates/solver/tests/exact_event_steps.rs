//! Exact event steps (`SolverOptions::exact_event_steps`, `Stepper::retake`): the step that
//! contains an event is taken again to end on it, so that no step spans a point where the
//! right-hand side is not smooth.
//!
//! ```text
//! y' = y + 5 max(y − 2, 0),  y(0) = 1,  event g = y − 2 (rising)
//!   y = eᵗ                                  t ≤ t_k = ln 2
//!   y = 5/3 + (1/3) e^{6 (t − t_k)}         t ≥ t_k      (f is C⁰ at y = 2: f' jumps by 5)
//! ```

use lash_solver::*;

/// The kinked growth above, with its event at the kink.
struct Kinked;

const T_END: f64 = 1.0;

fn exact(t: f64) -> f64 {
    let tk = 2f64.ln();
    if t <= tk {
        t.exp()
    } else {
        5.0 / 3.0 + (6.0 * (t - tk)).exp() / 3.0
    }
}

impl OdeSystem for Kinked {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[0] + 5.0 * (y[0] - 2.0).max(0.0);
    }
    fn n_events(&self) -> usize {
        1
    }
    fn event_spec(&self, _i: usize) -> EventSpec {
        EventSpec {
            direction: Direction::Either,
            action: EventAction::Continue,
        }
    }
    fn events(&self, _t: f64, y: &[f64], g: &mut [f64]) {
        g[0] = y[0] - 2.0;
    }
}

/// [`Kinked`] with the rate of its event function (ġ = y' = f(y)), which turns on the
/// predicted-crossing limit of exact event steps (integrator/exact.rs).
struct RatedKinked;

impl OdeSystem for RatedKinked {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        Kinked.rhs(t, y, dy);
    }
    fn n_events(&self) -> usize {
        1
    }
    fn event_spec(&self, i: usize) -> EventSpec {
        Kinked.event_spec(i)
    }
    fn events(&self, t: f64, y: &[f64], g: &mut [f64]) {
        Kinked.events(t, y, g);
    }
    fn event_rates(&self, t: f64, y: &[f64], g: &mut [f64], g_dot: &mut [f64]) -> bool {
        g[0] = y[0] - 2.0;
        let mut f = [0.0];
        Kinked.rhs(t, y, &mut f);
        g_dot[0] = f[0];
        true
    }
}

/// |y(1) − exact| with fixed steps h (the restart after the event at t_k starts a fresh grid
/// of steps h from t_k), with or without exact event steps; and the event time.
fn fixed_error(method: Method, h: f64, exact_steps: bool) -> (f64, f64) {
    let o = SolverOptions {
        method,
        adaptive: false,
        h0: Some(h),
        exact_event_steps: exact_steps,
        output: Output::Final,
        ..Default::default()
    };
    let s = solve(&Kinked, (0.0, T_END), &[1.0], &o).unwrap();
    assert_eq!(s.events.len(), 1, "{method} h {h}: one event");
    ((s.y_final[0] - exact(T_END)).abs(), s.events[0].t)
}

/// Least-squares slope of log e(h) against log h over `hs`.
fn observed_order(method: Method, hs: &[f64], exact_steps: bool) -> f64 {
    let pts: Vec<(f64, f64)> = hs
        .iter()
        .map(|&h| (h.ln(), fixed_error(method, h, exact_steps).0.ln()))
        .collect();
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

#[test]
fn exact_event_steps_keep_the_order_of_the_pairs_across_a_kink() {
    // A step across a C⁰ kink has a local error of order h² (f' jumps: the stages past the
    // kink see the other slope), and so has the dense output inside it, where the event
    // state is read; restarting there leaves a global error of order about 2 (measured 1.9,
    // 2.3, 2.5, 3.5 for the pairs below). Taken again to end on the event, the steps see one
    // smooth piece each: the method's own order p up to the event and after it (measured
    // 2.9, 4.6, 4.0, 7.7: least-squares slopes over h = 1/25 … 1/400, dop853 over
    // 1/5 … 1/40 above its rounding floor; the e^{6t} growth after the kink, hλ up to 0.24,
    // keeps the 5th-order pairs short of 5 there).
    let fine: Vec<f64> = (0..5).map(|k| 1.0 / (25.0 * 2f64.powi(k))).collect();
    let coarse: Vec<f64> = (0..4).map(|k| 1.0 / (5.0 * 2f64.powi(k))).collect();
    for (method, p, hs) in [
        (Method::Bs32, 3.0, &fine),
        (Method::Dopri54, 5.0, &fine),
        (Method::Tsit54, 5.0, &fine),
        (Method::Dop853, 8.0, &coarse),
    ] {
        let on = observed_order(method, hs, true);
        let off = observed_order(method, hs, false);
        assert!(
            on >= p - 1.2,
            "{method}: order {on:.2} with exact event steps, theory {p}"
        );
        assert!(
            off <= on - 0.9,
            "{method}: order {off:.2} from the dense output, {on:.2} with exact event steps"
        );
    }
}

#[test]
fn the_event_time_is_refined_to_the_accuracy_of_the_motion() {
    // The located time comes from the dense output of the step across the kink (its error
    // there is of order h², 5e-6 s at h = 0.01); Newton's corrections on g along the
    // retaken steps put it where the retaken motion reaches g = 0, within the motion's own
    // error over g's rate (y' = 2 at the kink): 1e-10 s at h = 0.01 for tsit54.
    let (_, off) = fixed_error(Method::Tsit54, 0.01, false);
    let (_, on) = fixed_error(Method::Tsit54, 0.01, true);
    let tk = 2f64.ln();
    assert!((on - tk).abs() <= 1e-10, "t* = {on}");
    assert!((off - tk).abs() >= 1e-7, "t* = {off} from the dense output");
}

/// The adaptive methods of order ≥ 4 with exact event steps.
const ADAPTIVE: [Method; 4] = [
    Method::Dopri54,
    Method::Tsit54,
    Method::Dop853,
    Method::Rodas5p,
];

/// `method` at `rtol` (atol the same), exact event steps, the final state only.
fn exact_options(method: Method, rtol: f64) -> SolverOptions {
    SolverOptions {
        method,
        rtol,
        atol: Atol::Scalar(rtol),
        exact_event_steps: true,
        output: Output::Final,
        ..Default::default()
    }
}

#[test]
fn adaptive_runs_with_exact_event_steps_meet_the_tolerance() {
    // With error control and exact event steps the global error at t = 1 is within a decade
    // of rtol·|y(1)| (|y(1)| = 3.77), as on a smooth problem, for every method of order ≥ 4;
    // from the dense-output event state it is up to 460 times that (dop853, rtol 1e-6).
    for method in ADAPTIVE {
        for rtol in [1e-6, 1e-8, 1e-10] {
            let o = exact_options(method, rtol);
            let s = solve(&Kinked, (0.0, T_END), &[1.0], &o).unwrap();
            assert_eq!(s.events.len(), 1, "{method} rtol {rtol:e}");
            let err = (s.y_final[0] - exact(T_END)).abs();
            assert!(
                err <= 10.0 * rtol * exact(T_END),
                "{method} rtol {rtol:e}: error {err:.2e}"
            );
        }
    }
}

#[test]
fn the_predicted_crossing_limit_keeps_the_tolerance_without_more_rejections() {
    // With the rate ġ given, the step after each step without an event ends at most 2 % past
    // the linear prediction of the crossing y = 2 (integrator/exact.rs, crossing_limit): the
    // global error at t = 1 keeps the bound of the test above (10 rtol |y(1)|), and the step
    // across the kink no longer straddles it by a whole step, so no more attempts are
    // rejected than without the rate, summed over the methods and tolerances (66 against 70
    // measured; fewer at rtol 1e-10 for dopri54 and tsit54, 4 and 5 against 7).
    let (mut with, mut without) = (0, 0);
    for method in ADAPTIVE {
        for rtol in [1e-6, 1e-8, 1e-10] {
            let o = exact_options(method, rtol);
            let s = solve(&RatedKinked, (0.0, T_END), &[1.0], &o).unwrap();
            assert_eq!(s.events.len(), 1, "{method} rtol {rtol:e}");
            let err = (s.y_final[0] - exact(T_END)).abs();
            assert!(
                err <= 10.0 * rtol * exact(T_END),
                "{method} rtol {rtol:e}: error {err:.2e} with the crossing limit"
            );
            let plain = solve(&Kinked, (0.0, T_END), &[1.0], &o).unwrap();
            println!(
                "{method} rtol {rtol:e}: rejected {} with the limit, {} without; steps {} / {}",
                s.stats.rejected_error,
                plain.stats.rejected_error,
                s.stats.accepted,
                plain.stats.accepted
            );
            with += s.stats.rejected_error;
            without += plain.stats.rejected_error;
        }
    }
    assert!(
        with <= without,
        "{with} rejected attempts with the crossing limit, {without} without"
    );
}
