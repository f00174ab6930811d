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
//! --library   instead: the library run with the run's options (`lash_benches::run_options`,
//!             dense output on the 2001-point grid of the second revolution) and the
//!             hand-written diffsol bdf at rtol 3.2e-10 (4 states), alternately, the minimum
//!             of each, their counters and the cost per step, and a digest of the library
//!             run's sampled accelerations (bit for bit comparisons of builds): the loop to
//!             `perf record`
//! --lib-only  with --library: the library run alone, `--reps` times, and its counters (no
//!             hand-written run, no right-hand-side loop): the loop to count instructions with
//!             `valgrind --tool=callgrind`
//! --no-limit  with --library: the library run without the contact-aware step limit
//! ```

use std::time::Instant;

use lash_model::FormulationName;
use lash_solver::Method;
use lash_solver::OdeSystem;
use lash_validation::{Case, RunOptions, SolverChoice};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut stem = "lubricated_150rpm_c0.1".to_string();
    let (mut method, mut rtol) = (Method::Bdf, 1e-10);
    let mut reps = 20;
    let mut formulation = None;
    let mut library = false;
    let mut lib_only = false;
    let mut no_limit = false;
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
            "--library" => library = true,
            "--lib-only" => lib_only = true,
            "--no-limit" => no_limit = true,
            s => stem = s.to_string(),
        }
    }
    if library {
        let flags = LoopFlags { lib_only, no_limit };
        return library_loop(&stem, method, rtol, reps, formulation, flags);
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

/// `--lib-only` and `--no-limit` of `--library`.
#[derive(Clone, Copy)]
struct LoopFlags {
    lib_only: bool,
    no_limit: bool,
}

/// `--library`: the library run of the case at (method, rtol) with the run's options and the
/// hand-written diffsol bdf (rtol 3.2e-10, atol 1e-3 rtol), `reps` alternating rounds.
fn library_loop(
    stem: &str,
    method: Method,
    rtol: f64,
    reps: usize,
    formulation: Option<FormulationName>,
    flags: LoopFlags,
) {
    let LoopFlags { lib_only, no_limit } = flags;
    use lash_benches::handwritten::{diffsol_bdf, HandPress};
    let path = lash_benches::cases_dir().join(format!("{stem}.json"));
    let mut scene = lash_model::Scene::from_path(&path).expect("the catalogue's scene");
    scene.t_end = None;
    scene.revolutions = Some(2.0);
    let y_abs = {
        let mut s = scene.clone();
        s.formulation = FormulationName::LagrangeBaumgarte;
        lash_model::Mechanism::from_scene(&s)
            .expect("the scene assembles")
            .initial_state()
    };
    if let Some(f) = formulation {
        scene.formulation = f;
    }
    let m = lash_model::Mechanism::from_scene(&scene).expect("the scene assembles");
    let per = lash_benches::crank_period(&m);
    let times = lash_benches::grid(m.t_start() + per, m.t_start() + 2.0 * per, 2001);
    let mut o = lash_benches::run_options(&m, method, rtol, 1e-4);
    if no_limit {
        o.h_max_near_events = f64::INFINITY;
    }
    let hand = HandPress::paper(150.0, 1e-4, true);
    let y0 = HandPress::minimal_state(&y_abs);
    let hand_rtol = 3.2e-10;
    let (mut best_lib, mut best_hand) = (f64::INFINITY, f64::INFINITY);
    let (mut lib_stats, mut hand_counts) = (None, (0, 0));
    let mut digest = 0u64;
    for _ in 0..reps {
        let s = lash_benches::sample(&m, m.t_start() + 2.0 * per, &o, &times)
            .expect("the library run succeeds");
        best_lib = best_lib.min(s.wall);
        lib_stats = Some(s.stats);
        // FNV-1a of the sampled accelerations' bits: equal digests, equal results.
        digest = s.slider_a.iter().fold(0xcbf2_9ce4_8422_2325, |h, v| {
            (h ^ v.to_bits()).wrapping_mul(0x0100_0000_01b3)
        });
        if lib_only {
            continue;
        }
        let h = diffsol_bdf(
            &hand,
            m.t_start(),
            y0,
            hand_rtol,
            [hand_rtol * 1e-3; 4],
            &times,
        )
        .expect("the hand-written run succeeds");
        best_hand = best_hand.min(h.wall);
        hand_counts = (h.steps, h.rhs_evals);
    }
    if lib_only {
        let st = lib_stats.expect("reps > 0");
        println!(
            "library ({}, {} rtol {rtol:.1e}): {:.3} ms, {} steps, {} RHS + {} Jacobians, \
             {} event evaluations; digest {digest:016x}",
            m.formulation_name(),
            method.name(),
            best_lib * 1e3,
            st.accepted,
            st.rhs_evals,
            st.jac_evals,
            st.event_evals
        );
        return;
    }
    // One right-hand side at the start of the second revolution (the lubricated film loaded),
    // each side's, 100 000 calls a round, the minimum of five rounds.
    let (t1, y_lib, y_hand) = {
        let mut oo = o.clone();
        oo.output = lash_solver::Output::Times(vec![times[0]]);
        let s = lash_solver::solve(&m, (m.t_start(), times[0]), &m.initial_state(), &oo)
            .expect("the library run succeeds");
        let y = s.state(0).to_vec();
        let mut oa = o.clone();
        oa.atol = lash_solver::Atol::Scalar(1e-14);
        let abs = {
            let mut s2 = scene.clone();
            s2.formulation = FormulationName::LagrangeBaumgarte;
            lash_model::Mechanism::from_scene(&s2).expect("the scene assembles")
        };
        let sa = lash_solver::solve(&abs, (abs.t_start(), times[0]), &y_abs, &oa)
            .expect("the absolute run succeeds");
        (times[0], y, HandPress::minimal_state(sa.state(0)))
    };
    let (mut rhs_lib, mut rhs_hand) = (f64::INFINITY, f64::INFINITY);
    let (mut dy, mut dh) = (vec![0.0; y_lib.len()], [0.0; 4]);
    for _ in 0..5 {
        let calls = 100_000;
        let start = Instant::now();
        for _ in 0..calls {
            m.rhs(
                std::hint::black_box(t1),
                std::hint::black_box(&y_lib),
                std::hint::black_box(&mut dy),
            );
        }
        rhs_lib = rhs_lib.min(start.elapsed().as_secs_f64() / calls as f64);
        let start = Instant::now();
        for _ in 0..calls {
            hand.rhs(
                std::hint::black_box(t1),
                std::hint::black_box(&y_hand),
                std::hint::black_box(&mut dh),
            );
        }
        rhs_hand = rhs_hand.min(start.elapsed().as_secs_f64() / calls as f64);
    }
    println!(
        "one right-hand side at t = {t1:.4} s: library {:.1} ns, hand-written {:.1} ns ({:.2}×)",
        rhs_lib * 1e9,
        rhs_hand * 1e9,
        rhs_lib / rhs_hand
    );
    let st = lib_stats.expect("reps > 0");
    println!(
        "library ({}, {} rtol {rtol:.1e}, the run's options): {:.3} ms, {} steps, {} RHS + {} \
         Jacobians, {:.3} µs/step",
        m.formulation_name(),
        method.name(),
        best_lib * 1e3,
        st.accepted,
        st.rhs_evals,
        st.jac_evals,
        best_lib * 1e6 / st.accepted as f64
    );
    println!("  digest of the sampled slider accelerations' bits: {digest:016x}");
    println!(
        "hand-written diffsol bdf rtol {hand_rtol:.1e}: {:.3} ms, {} steps, {} RHS, {:.3} µs/step",
        best_hand * 1e3,
        hand_counts.0,
        hand_counts.1,
        best_hand * 1e6 / hand_counts.0 as f64
    );
    println!(
        "minimum over {reps} alternating rounds: library / hand-written = {:.2}×",
        best_lib / best_hand
    );
}
