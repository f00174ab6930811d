//! Every integration method runs the press cases of cases/press/ to their end time.
//!
//! The default run covers one case of each kind (ideal, dry, lubricated at 150 rpm, 0.1 mm)
//! with all nine methods; `all_press_cases_with_every_method` (ignored by default, minutes)
//! covers the whole catalogue.
//!
//! Adaptive runs use rtol 1e-6, atol 1e-9 and `event_samples = 2`: an adaptive step can hold a
//! whole contact (onset and loss), and sampling two interior points of each step is what keeps
//! such an impact from being skipped.

mod common;
use common::{case_stems, cases_dir, rk4_step};
use lash_model::{Mechanism, Scene};
use lash_solver::{solve, Atol, Method, Output, SolverOptions};
use std::time::Instant;

fn options(method: Method, stem: &str) -> SolverOptions {
    let mut o = SolverOptions::with_method(method);
    o.output = Output::Final;
    o.max_steps = 50_000_000;
    if method.is_fixed_step() {
        o.step = Some(rk4_step(stem));
    } else {
        o.rtol = 1e-6;
        o.atol = Atol::Scalar(1e-9);
        o.event_samples = 2;
    }
    o
}

/// Runs one case with one method; checks it reaches t_end with a finite state whose position
/// constraints hold. Baumgarte stabilisation damps the drift that local errors feed into Φ, so
/// the drift stays at the size of the local error, rtol·|q| with |q| ≈ l = 0.35 m (the rod
/// length); the bound is ten times that: 10 · 1e-6 · 0.35 m = 3.5e-6 m.
fn run(stem: &str, method: Method) -> (f64, usize, usize) {
    let scene = Scene::from_path(cases_dir().join(format!("{stem}.json"))).unwrap();
    let m = Mechanism::from_scene(&scene).unwrap();
    let y0 = m.initial_state();
    let t0 = Instant::now();
    let sol = solve(&m, (m.t_start(), m.t_end()), &y0, &options(method, stem))
        .unwrap_or_else(|e| panic!("{stem} with {method}: {e}"));
    let wall = t0.elapsed().as_secs_f64();
    assert_eq!(sol.t_final, m.t_end(), "{stem} with {method} reaches t_end");
    assert!(sol.y_final.iter().all(|v| v.is_finite()));
    let o = m.outputs(sol.t_final, &sol.y_final);
    assert!(
        o.constraint_violation < 3.5e-6,
        "{stem} with {method}: ‖Φ‖ = {}",
        o.constraint_violation
    );
    println!(
        "{stem:26} {:9} wall {wall:8.3} s  steps {:8}  rhs {:9}  events {:5}  ‖Φ‖ {:.1e}",
        method.name(),
        sol.stats.accepted,
        sol.stats.rhs_evals,
        sol.stats.events,
        o.constraint_violation
    );
    (wall, sol.stats.rhs_evals, sol.stats.events)
}

#[test]
fn headline_cases_with_every_method() {
    for stem in ["ideal_150rpm", "dry_150rpm_c0.1", "lubricated_150rpm_c0.1"] {
        for method in Method::ALL {
            run(stem, method);
        }
    }
}

#[test]
#[ignore = "minutes: the whole catalogue with all nine methods"]
fn all_press_cases_with_every_method() {
    let stems = case_stems();
    for stem in &stems {
        for method in Method::ALL {
            run(stem, method);
        }
    }
}
