//! The cost of one Jacobian in right-hand sides (issue 26: "the Jacobian stays at or under 6
//! RHS-equivalents per evaluation"; BENCHMARKS.md, "Minimal with loop closures").
//!
//! ```text
//! cargo build --release -p lash-benches --example jac_cost
//! target/release/examples/jac_cost SCENE FORMULATION [REPS]
//! target/release/examples/jac_cost SCENE FORMULATION --run LINALG T_END RTOL
//! valgrind --tool=callgrind --callgrind-out-file=OUT target/release/examples/jac_cost SCENE FORMULATION 50
//! callgrind_annotate --inclusive=yes OUT | grep 'jac_cost::'
//! ```
//!
//! SCENE is a scene file (e.g. `cases/andrews/andrews.json`), FORMULATION one of
//! `lagrange_baumgarte`, `augmented_lagrangian`, `minimal`, `auto`, REPS the evaluations per
//! round (default 200). The mechanism is built from the scene under that formulation and, at
//! its initial state, `Mechanism::jacobian` and `Mechanism::rhs` are each called REPS times
//! in a loop, in two functions that are never inlined (`jac_cost::jacobians`,
//! `jac_cost::rhss`) so that callgrind's inclusive instruction counts of the two give the
//! ratio independently of the machine's load: the number BENCHMARKS.md records. The calls
//! alternate between t = 0 and t = 1 ms (the state stays on the tree's constraints: minimal
//! places every body from θ), so every call recomputes the prescribed bodies' kinematics,
//! which the mechanism keeps between evaluations at one t (`Scratch::pres_t`): at a single t
//! the right-hand side would be cheaper than any in a run, where t moves with every step. The example
//! also prints the best of 7 wall-time rounds of each and their ratio, which on a loaded
//! machine is only indicative.
//!
//! With `--run`, the scene is integrated by bdf from its initial state to T_END at RTOL
//! (atol = RTOL) on the linear algebra LINALG (`dense`, `kkt`, `sparse`, `auto`:
//! `lash_solver::LinearAlgebra`; `lash run` has no option for it), and the example prints
//! the solver's counters (steps, right-hand sides, Jacobians, LU factorisations) and the
//! integration's wall time: the dense and kkt Newton side by side on one cluster (A02 N = 40,
//! BENCHMARKS.md, "Minimal with loop closures").

use std::hint::black_box;
use std::process::ExitCode;
use std::time::Instant;

use lash_model::{FormulationName, Mechanism, Scene};
use lash_solver::{Atol, LinearAlgebra, Method, OdeSystem, Problem, SolverOptions};

/// The times the calls alternate between (module doc).
const TIMES: [f64; 2] = [0.0, 1e-3];

/// `reps` Jacobians at `(t, y)`, t alternating over [`TIMES`].
#[inline(never)]
fn jacobians(m: &Mechanism, y: &[f64], jac: &mut faer::Mat<f64>, reps: usize) {
    for k in 0..reps {
        m.jacobian(TIMES[k % 2], black_box(y), jac.as_mut());
    }
}

/// `reps` right-hand sides at `(t, y)`, t alternating over [`TIMES`].
#[inline(never)]
fn rhss(m: &Mechanism, y: &[f64], dy: &mut [f64], reps: usize) {
    for k in 0..reps {
        m.rhs(TIMES[k % 2], black_box(y), dy);
    }
}

fn run(args: &[String]) -> Result<(), String> {
    let [path, form, rest @ ..] = args else {
        return Err("usage: jac_cost SCENE FORMULATION [REPS]".into());
    };
    let formulation = form.parse::<FormulationName>().map_err(|e| e.to_string())?;
    if rest.first().map(String::as_str) == Some("--run") {
        return integrate(path, formulation, &rest[1..]);
    }
    let reps: usize = match rest.first() {
        Some(r) => r.parse().map_err(|e| format!("REPS `{r}`: {e}"))?,
        None => 200,
    };
    let mut scene = Scene::from_path(path).map_err(|e| format!("{path}: {e}"))?;
    scene.formulation = formulation;
    let m = Mechanism::from_scene(&scene).map_err(|e| format!("{path}: {e}"))?;
    let y = m.initial_state();
    let n = m.dim();
    let mut jac = faer::Mat::<f64>::zeros(n, n);
    let mut dy = vec![0.0; n];
    let (mut best_jac, mut best_rhs) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..7 {
        let t0 = Instant::now();
        jacobians(&m, &y, &mut jac, reps);
        best_jac = best_jac.min(t0.elapsed().as_secs_f64() / reps as f64);
        let t0 = Instant::now();
        rhss(&m, &y, &mut dy, reps);
        best_rhs = best_rhs.min(t0.elapsed().as_secs_f64() / reps as f64);
    }
    println!(
        "{path} {formulation} (n = {n}): rhs {:.2} us, jacobian {:.2} us, ratio {:.1} (wall time, best of 7)",
        best_rhs * 1e6,
        best_jac * 1e6,
        best_jac / best_rhs
    );
    Ok(())
}

/// `--run LINALG T_END RTOL` (module doc).
fn integrate(path: &str, formulation: FormulationName, args: &[String]) -> Result<(), String> {
    let [la, t_end, rtol] = args else {
        return Err("usage: jac_cost SCENE FORMULATION --run LINALG T_END RTOL".into());
    };
    let linear_algebra = match la.as_str() {
        "dense" => LinearAlgebra::Dense,
        "kkt" => LinearAlgebra::Kkt,
        "sparse" => LinearAlgebra::Sparse,
        "auto" => LinearAlgebra::Auto,
        other => return Err(format!("LINALG `{other}`: dense, kkt, sparse or auto")),
    };
    let t_end: f64 = t_end.parse().map_err(|e| format!("T_END `{t_end}`: {e}"))?;
    let rtol: f64 = rtol.parse().map_err(|e| format!("RTOL `{rtol}`: {e}"))?;
    let mut scene = Scene::from_path(path).map_err(|e| format!("{path}: {e}"))?;
    scene.formulation = formulation;
    let m = Mechanism::from_scene(&scene).map_err(|e| format!("{path}: {e}"))?;
    let mut o = SolverOptions::with_method(Method::Bdf);
    o.output = lash_solver::Output::Final;
    o.linear_algebra = linear_algebra;
    o.rtol = rtol;
    o.atol = Atol::Scalar(rtol);
    let t0 = Instant::now();
    let sol = Problem::new(&m, &o)
        .map_err(|e| e.to_string())?
        .solve((0.0, t_end), &m.initial_state())
        .map_err(|e| e.to_string())?;
    let wall = t0.elapsed().as_secs_f64();
    let s = &sol.stats;
    println!(
        "{path} {formulation} (n = {}) bdf {la} to {t_end} s at {rtol:e}: {wall:.2} s, \
         {} steps ({} accepted), {} rhs, {} jacobians, {} LU",
        m.dim(),
        s.steps,
        s.accepted,
        s.rhs_evals,
        s.jac_evals,
        s.lu_factorizations
    );
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("jac_cost: {e}");
            ExitCode::FAILURE
        }
    }
}
