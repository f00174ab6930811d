//! The path `lash run` takes, in memory, repeated: for `perf record` and for splitting a run's
//! wall time between the integration and what the path adds (BENCHMARKS.md, "The press targets
//! through `lash run`").
//!
//! ```text
//! cargo run --release -p lash-benches --example run_path -- [CASE] [--at METHOD:RTOL]
//!     [--reps N] [--formulation F]
//! CASE        a scene of cases/press/ by stem (default lubricated_150rpm_c0.1), two revolutions,
//!             2000 trajectory rows per revolution (the run's defaults)
//! --at        method and rtol (default bdf:1e-10, the cheapest `lash run` of the lubricated
//!             press with error ≤ 1e-6 m/s², BENCHMARKS.md)
//! prints      per repetition: run_in_memory's wall time, the integration's own (summary
//!             wall_time_s) and the difference; then the minimum of each
//! ```

use std::time::Instant;

use lash_model::FormulationName;
use lash_solver::Method;
use lash_validation::{Case, RunOptions, SolverChoice};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut stem = "lubricated_150rpm_c0.1".to_string();
    let (mut method, mut rtol) = (Method::Bdf, 1e-10);
    let mut reps = 20;
    let mut formulation = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--at" => {
                let v = it.next().expect("--at takes METHOD:RTOL");
                let (m, r) = v
                    .split_once(':')
                    .and_then(|(m, r)| Some((Method::from_name(m)?, r.parse().ok()?)))
                    .expect("--at takes METHOD:RTOL, e.g. bdf:1e-10");
                (method, rtol) = (m, r);
            }
            "--reps" => {
                reps = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--reps takes a number");
            }
            "--formulation" => {
                let f = it.next().expect("--formulation takes a name");
                formulation = Some(f.parse::<FormulationName>().expect("a formulation"));
            }
            s => stem = s.to_string(),
        }
    }
    let case = lash_benches::cases_dir().join(format!("{stem}.json"));
    let o = RunOptions {
        case: case.display().to_string(),
        solver: SolverChoice {
            method: Some(method),
            rtol: Some(rtol),
            ..Default::default()
        },
        formulation,
        ..Default::default()
    };
    let (mut best_run, mut best_int) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..reps {
        let start = Instant::now();
        let c = Case::load(&o.case, None).expect("the catalogue's case");
        let r = lash_validation::run_in_memory(c, &o).expect("the run succeeds");
        let wall = start.elapsed().as_secs_f64();
        let int = r.summary.wall_time_s;
        println!(
            "{stem} {} rtol {rtol:.1e}: run_in_memory {:.3} ms, integration {:.3} ms, path {:.3} ms \
             ({} steps, {} rows)",
            method.name(),
            wall * 1e3,
            int * 1e3,
            (wall - int) * 1e3,
            r.summary.stats.accepted,
            r.trajectory_rows
        );
        best_run = best_run.min(wall);
        best_int = best_int.min(int);
    }
    println!(
        "minimum over {reps}: run_in_memory {:.3} ms, integration {:.3} ms",
        best_run * 1e3,
        best_int * 1e3
    );
}
