//! RK4's stability check on the lubricated press (150 rpm, c = 0.1 mm): it never stops a run
//! whose every step is inside RK4's stability region, and it stops one that is not.
//!
//! ```text
//! film modes of ∂f/∂y along the run: λ ≈ −1.5e5 … −4.5e5 1/s (BENCHMARKS.md, (d))
//! RK4's real stability interval: h |λ| ≤ 2.785   ⇒  h ≤ 2.785 / 4.5e5 ≈ 6.2 µs
//! h = 3 µs: h |λ| ≤ 1.4, stable;   h = 10 µs: h |λ| up to 4.5, unstable
//! ```
//! The check (`lash_solver::rk4`) suspects a step from its stages (h·ρ > 2.785) and confirms
//! it from the eigenvalues; the stage quotient alone flagged runs of hundreds of steps at
//! h = 3 µs and would have stopped this run.

mod common;
use common::cases_dir;
use lash_model::{Mechanism, Scene};
use lash_solver::{solve, Atol, Method, OdeSystem, Output, SolveError, SolverOptions};

fn press() -> Mechanism {
    let mut scene = Scene::from_path(cases_dir().join("lubricated_150rpm_c0.1.json")).unwrap();
    // The paper's RK4 on the paper's formulation (and the absolute slider x at index 3).
    scene.formulation = lash_model::FormulationName::LagrangeBaumgarte;
    Mechanism::from_scene(&scene).unwrap()
}

fn rk4(h: f64) -> SolverOptions {
    SolverOptions {
        step: Some(h),
        output: Output::Final,
        max_steps: 50_000_000,
        rk4_instability_steps: 15,
        ..SolverOptions::with_method(Method::Rk4)
    }
}

#[test]
fn rk4_check_lets_a_stable_step_run_and_stops_an_unstable_one() {
    let m = press();
    let (t0, t1) = (m.t_start(), m.t_end());
    let y0 = m.initial_state();
    // h = 3 µs: runs to the end, and agrees with a converged BDF run.
    let sol = solve(&m, (t0, t1), &y0, &rk4(3e-6)).expect("RK4 at 3 µs is stable");
    assert_eq!(sol.t_final, t1);
    let reference = {
        let o = SolverOptions {
            rtol: 1e-10,
            atol: Atol::Scalar(1e-13),
            output: Output::Final,
            ..SolverOptions::with_method(Method::Bdf)
        };
        solve(&m, (t0, t1), &y0, &o).unwrap()
    };
    let nq = m.dim() / 2;
    // Slider x (coordinate 3) and its velocity: RK4's global error at h = 3 µs.
    let dx = (sol.y_final[3] - reference.y_final[3]).abs();
    let dv = (sol.y_final[nq + 3] - reference.y_final[nq + 3]).abs();
    println!("rk4 3 µs: |Δx| = {dx:e} m, |Δv| = {dv:e} m/s");
    // A solution, not a spurious bounded one (those leave the slider's acceleration off by
    // 1e4 m/s², BENCHMARKS.md, "Extremes"): within 1e-4 of the stroke 2r = 30 mm and of the
    // crank pin's speed r ω = 0.236 m/s (measured: 5.0e-7 m, 1.4e-6 m/s).
    assert!(
        dx < 1e-4 * 0.03 && dv < 1e-4 * 0.236,
        "|Δx| = {dx:e}, |Δv| = {dv:e}"
    );
    // h = 10 µs: stopped as unstable, with a limit between the two steps.
    match solve(&m, (t0, t1), &y0, &rk4(1e-5)) {
        Err(SolveError::Rk4Unstable { h, h_limit, .. }) => {
            assert_eq!(h, 1e-5);
            assert!(h_limit > 3e-6 && h_limit < 1e-5, "limit {h_limit:e}");
        }
        other => panic!("expected Rk4Unstable at 10 µs, got {other:?}"),
    }
}
