//! Pinned work counters: any change in stepping or controller behaviour shows in review.
//!
//! ```text
//! FSAL pair:  rhs = 1 (f(t0, y0)) + 1 (starting step) + (s − 1) · attempts
//! DOP853:     rhs = 2 + 11 · attempts + accepted      (f(t+h, y_{n+1}) only when accepted)
//! ```
//! Problem: the Arenstorf orbit over one period (HNW I p. 129) at rtol = atol = 1e-6, default
//! options (PI controller, StepLimits defaults), output of the final state only.

mod common;
use common::*;
use lash_solver::*;

fn run(method: Method, controller: Option<ControllerKind>) -> Stats {
    let o = SolverOptions {
        method,
        rtol: 1e-6,
        atol: Atol::Scalar(1e-6),
        controller,
        output: Output::Final,
        ..Default::default()
    };
    solve(&Arenstorf, (0.0, Arenstorf::T), &Arenstorf::Y0, &o)
        .unwrap()
        .stats
}

/// (accepted, rejected, rhs) and the RHS formula above.
fn check(method: Method, controller: Option<ControllerKind>, pinned: (usize, usize, usize)) {
    let s = run(method, controller);
    assert_eq!(s.steps, s.accepted + s.rejected_error, "{method}");
    let formula = match method {
        Method::Bs32 => 2 + 3 * s.steps,
        Method::Dopri54 | Method::Tsit54 => 2 + 6 * s.steps,
        Method::Dop853 => 2 + 11 * s.steps + s.accepted,
        _ => unreachable!(),
    };
    assert_eq!(s.rhs_evals, formula, "{method}: RHS count formula");
    assert_eq!(
        (s.accepted, s.rejected_error, s.rhs_evals),
        pinned,
        "{method} {controller:?}: counts changed"
    );
}

#[test]
fn pinned_counts_per_method() {
    check(Method::Bs32, None, (915, 0, 2747));
    check(Method::Dopri54, None, (147, 22, 1016));
    check(Method::Tsit54, None, (153, 29, 1094));
    check(Method::Dop853, None, (74, 21, 1121));
}

#[test]
fn pinned_counts_per_controller() {
    // Dormand–Prince 5(4) with each preset (pi is the default, same as above).
    let pinned = [
        (ControllerKind::I, (132, 35, 1004)),
        (ControllerKind::Pi, (147, 22, 1016)),
        (ControllerKind::Pid, (148, 22, 1022)),
        (ControllerKind::H211, (150, 31, 1088)),
        (ControllerKind::H312, (153, 36, 1136)),
        (ControllerKind::Gustafsson, (127, 5, 794)),
    ];
    for (c, counts) in pinned {
        check(Method::Dopri54, Some(c), counts);
    }
}
