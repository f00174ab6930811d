//! The RK4 steps of the extremes catalogue: for each scene, RK4 (with the stability check of
//! mechanism runs) at the 1–2–5 series of steps, each run judged as a matrix cell (agreement
//! with the scene's reference within RK4's promise, or the typed error). The catalogue's
//! `rk4_inside` is the largest step that agrees, `rk4_beyond` a step past the limit that fails
//! with NonFiniteState (BENCHMARKS.md "Extremes"). The scan stops after two agreeing steps.
//!
//! ```text
//! cargo run --release -p lash-validation --example extremes_rk4_scan -- [STEM...]
//! RK4_STEPS=1e-3,2e-3 cargo run ... -- STEM     (only these steps)
//! ```
use lash_validation::extremes::{catalogue, prepare, run_cell, Budget, Outcome, Setting};

fn main() {
    let wanted: Vec<String> = std::env::args().skip(1).collect();
    let budget = Budget {
        max_steps: 2_000_000,
        max_wall_time: 20.0,
    };
    for scene in catalogue() {
        if !wanted.is_empty() && !wanted.iter().any(|w| w == scene.stem) {
            continue;
        }
        let stem = scene.stem;
        let ready = match prepare(scene) {
            Ok(r) => r,
            Err(e) => {
                println!("{stem}: no reference: {e}");
                continue;
            }
        };
        println!(
            "{stem}: reference {} vs {} at {:e}, E_ref {:.2e}",
            ready.report.reference,
            ready.report.check,
            ready.report.reference_rtol,
            ready.report.agreement
        );
        if let Ok(list) = std::env::var("RK4_STEPS") {
            for h in list.split(',') {
                let h: f64 = h.parse().expect("a step");
                let c = run_cell(&ready, Setting::Rk4Inside { h }, &budget);
                println!("  h {h:e}: {:?}", c.outcome);
            }
            continue;
        }
        let mut agreed = 0;
        'scan: for exp in (-11..=-2).rev() {
            for k in [5.0, 2.0, 1.0] {
                let h: f64 = format!("{k}e{exp}").parse().unwrap();
                if h > ready.report.t_end / 10.0 {
                    continue;
                }
                let c = run_cell(&ready, Setting::Rk4Inside { h }, &budget);
                println!(
                    "  h {h:e}: ({:.2} s, measured C {:?}) {:?}",
                    c.wall_time_s, c.measured_c, c.outcome
                );
                if matches!(c.outcome, Outcome::Agrees { .. }) {
                    agreed += 1;
                    if agreed == 2 {
                        break 'scan;
                    }
                }
            }
        }
    }
}
