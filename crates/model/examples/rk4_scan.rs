//! Scans fixed RK4 steps on every press case: does the run reach its end time, how large does
//! the constraint violation get, and how long does it take.
//!
//! ```text
//! cargo run --release -p lash-model --example rk4_scan [-- STEM_FILTER]
//! ```
use lash_model::Mechanism;
use lash_solver::{solve, Method, Output, SolverOptions};

fn main() {
    let filter = std::env::args().nth(1).unwrap_or_default();
    for (stem, scene) in lash_model::cases::press_catalogue() {
        if !stem.contains(&filter) {
            continue;
        }
        let m = Mechanism::from_scene(&scene).expect("valid case");
        let custom: Vec<f64> = std::env::var("STEPS")
            .map(|v| v.split(',').map(|x| x.parse().expect("a step")).collect())
            .unwrap_or_default();
        let steps: &[f64] = if !custom.is_empty() {
            &custom
        } else if stem.starts_with("lubricated") {
            &[2e-5, 1e-5, 5e-6, 2e-6, 1e-6, 5e-7, 2e-7]
        } else {
            &[1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4]
        };
        for &h in steps {
            let times: Vec<f64> = (0..=400).map(|i| m.t_end() * i as f64 / 400.0).collect();
            let opts = SolverOptions {
                method: Method::Rk4,
                step: Some(h),
                events: false,
                max_steps: usize::MAX,
                output: Output::Times(times),
                ..Default::default()
            };
            let t0 = std::time::Instant::now();
            let res = solve(&m, (0.0, m.t_end()), &m.initial_state(), &opts);
            let wall = t0.elapsed().as_secs_f64();
            match res {
                Ok(sol) => {
                    let (mut phi, mut eps) = (0.0f64, 0.0f64);
                    for k in 0..sol.len() {
                        let o = m.outputs(sol.t[k], sol.state(k));
                        phi = phi.max(o.constraint_violation);
                        eps = eps.max(o.clearance.first().map_or(0.0, |c| c.eps));
                    }
                    println!("{stem:28} h={h:8.1e} ok   wall={wall:7.3}s max|Phi|={phi:9.2e} eps_max={eps:6.3} rhs={}", sol.stats.rhs_evals);
                }
                Err(e) => println!(
                    "{stem:28} h={h:8.1e} FAIL wall={wall:7.3}s {}",
                    e.to_string().chars().take(80).collect::<String>()
                ),
            }
        }
    }
}
