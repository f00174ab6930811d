//! Helpers shared by the benchmarks (`benches/benches/*.rs`) and the measurement program
//! (`benches/examples/targets.rs`): the press cases of `cases/press/` and the options the tests
//! run them with, representative states, and the slider-acceleration error on a time grid.
//!
//! ```text
//! error(method) = max_i |ẍ_slider(t_i; method) − ẍ_slider(t_i; reference)|,
//! t_i = a + i (b − a)/(N − 1),  i = 0..N−1   (a uniform grid over a window [a, b])
//! ```
//! The acceleration is `Mechanism::outputs(t, y).slider_a`, the right-hand side at the
//! dense-output state y(t_i) (docs/outputs.md, "`metrics`").

pub mod handwritten;

use std::path::PathBuf;
use std::time::Instant;

use lash_model::{Mechanism, Scene};
use lash_solver::{solve, Atol, Method, Output, SolveError, SolverOptions, Stats};

/// The folder of the press catalogue, `cases/press/` of the repository.
pub fn cases_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../cases/press")
}

/// The press case `stem` (e.g. `dry_150rpm_c0.1`) from `cases/press/`, run for `revolutions`
/// crank revolutions instead of the file's span, in the paper's formulation
/// (lagrange_baumgarte, 12 absolute states: the one BENCHMARKS' press rows were measured with,
/// whatever the default; `targets --formulation F` chooses another), and without kink events
/// (as those rows were measured: a dry scene now has them by default, docs/model.md §7;
/// `Mechanism::set_kink_events` turns them on where a measurement wants them).
///
/// Panics when the file is missing or invalid: the benchmarks run on the repository's own
/// catalogue, which the tests validate.
pub fn press(stem: &str, revolutions: f64) -> Mechanism {
    let path = cases_dir().join(format!("{stem}.json"));
    let mut scene = Scene::from_path(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    scene.t_end = None;
    scene.revolutions = Some(revolutions);
    scene.formulation = lash_model::FormulationName::LagrangeBaumgarte;
    scene.kink_events.get_or_insert(false);
    Mechanism::from_scene(&scene).unwrap_or_else(|e| panic!("{stem}: {e}"))
}

/// The crank period T = 2π/|ω| of a press (s).
pub fn crank_period(m: &Mechanism) -> f64 {
    2.0 * std::f64::consts::PI / m.crank_speed().expect("a press declares its crank").abs()
}

/// Options of an adaptive run at (rtol, atol), with the two interior event samples per step
/// that the press tests use (an adaptive step can hold a whole contact); RK4 takes `step`.
pub fn options(method: Method, rtol: f64, atol: f64, step: f64, output: Output) -> SolverOptions {
    let mut o = SolverOptions::with_method(method);
    o.output = output;
    o.max_steps = 100_000_000;
    if method.is_fixed_step() {
        o.step = Some(step);
    } else {
        o.rtol = rtol;
        o.atol = Atol::Scalar(atol);
        o.event_samples = 2;
    }
    o
}

/// The options of the press tests: rtol 1e-6, atol 1e-9, 2 event samples; RK4 at the step the
/// engine runs the case at (`lash_validation::PressCase::rk4_step`); final state only. Panics
/// for a stem that is not a press case.
pub fn test_options(method: Method, stem: &str) -> SolverOptions {
    let step = stem
        .parse::<lash_validation::PressCase>()
        .unwrap_or_else(|e| panic!("{e}"))
        .rk4_step();
    options(method, 1e-6, 1e-9, step, Output::Final)
}

/// The library options of a `lash run` of a press at (method, rtol), clearance `c` (m): the
/// engine's defaults (`crates/validation/src/run/prepare.rs`), atol rtol·c for positions and
/// rtol·c·ω for velocities, 4 event samples, the step limit near contact T/100.
pub fn run_options(m: &Mechanism, method: Method, rtol: f64, c: f64) -> SolverOptions {
    use lash_solver::OdeSystem;
    let w = m.crank_speed().expect("a press has a crank").abs();
    let n = m.dim();
    let mut o = SolverOptions::with_method(method);
    o.rtol = rtol;
    o.atol = Atol::Vector(
        (0..n)
            .map(|k| if k < n / 2 { rtol * c } else { rtol * c * w })
            .collect(),
    );
    o.event_samples = 4;
    o.h_max_near_events = crank_period(m) / 100.0;
    o.max_steps = 50_000_000;
    o
}

/// `n` equally spaced times from `a` to `b`, both included.
pub fn grid(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| {
            if i + 1 == n {
                b
            } else {
                a + (b - a) * i as f64 / (n - 1) as f64
            }
        })
        .collect()
}

/// One run sampled on a grid: slider acceleration at each grid time, counters, wall time of
/// the integration alone.
#[derive(Clone, Debug)]
pub struct Sampled {
    /// ẍ_slider at each grid time (m/s²).
    pub slider_a: Vec<f64>,
    /// The solver's counters.
    pub stats: Stats,
    /// Wall time of `solve` (s).
    pub wall: f64,
}

/// Integrates `m` from its start to `t_end` with `opts` (its output replaced by the grid) and
/// samples the slider acceleration on `times` (inside [t_start, t_end]).
pub fn sample(
    m: &Mechanism,
    t_end: f64,
    opts: &SolverOptions,
    times: &[f64],
) -> Result<Sampled, SolveError> {
    let mut o = opts.clone();
    o.output = Output::Times(times.to_vec());
    let y0 = m.initial_state();
    let start = Instant::now();
    let sol = solve(m, (m.t_start(), t_end), &y0, &o)?;
    let wall = start.elapsed().as_secs_f64();
    let slider_a = (0..sol.len())
        .map(|k| {
            m.outputs(sol.t[k], sol.state(k))
                .slider_a
                .expect("a press declares its slider")
        })
        .collect();
    Ok(Sampled {
        slider_a,
        stats: sol.stats,
        wall,
    })
}

/// max_i |a_i − b_i| (+∞ when the lengths differ or a value is not finite).
pub fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    if a.len() != b.len() {
        return f64::INFINITY;
    }
    a.iter().zip(b).fold(0.0, |w, (x, y)| {
        let d = (x - y).abs();
        if d.is_finite() {
            w.max(d)
        } else {
            f64::INFINITY
        }
    })
}

/// A state of a press: time and y.
#[derive(Clone, Debug)]
pub struct State {
    /// Time (s).
    pub t: f64,
    /// y = (q, q̇).
    pub y: Vec<f64>,
    /// Penetration δ of the first clearance joint there (m; < 0 when apart).
    pub delta: f64,
}

/// Two representative states of a press with one clearance joint, from a run of two
/// revolutions with DOP853 at rtol 1e-8: the state of largest penetration δ (in contact, or
/// for a lubricated joint the most loaded film) and a free-flight state, the one after the
/// first quarter of the run whose δ is nearest −c/2 (journal half-way between the bearing's
/// centre and its wall; the initial state is centred, a special case of the geometry).
pub fn contact_and_free_states(m: &Mechanism) -> (State, State) {
    let mut o = options(Method::Dop853, 1e-8, 1e-11, 0.0, Output::Steps);
    o.event_samples = 2;
    let y0 = m.initial_state();
    let (t0, t1) = (m.t_start(), m.t_end());
    let sol = solve(m, (t0, t1), &y0, &o).expect("the press case runs");
    let mut contact: Option<State> = None;
    let mut free: Option<(f64, State)> = None;
    for k in 0..sol.len() {
        let (t, y) = (sol.t[k], sol.state(k));
        let cl = m.outputs(t, y).clearance[0].clone();
        let delta = cl.delta;
        let s = || State {
            t,
            y: y.to_vec(),
            delta,
        };
        if contact.as_ref().is_none_or(|b| delta > b.delta) {
            contact = Some(s());
        }
        if t > t0 + 0.25 * (t1 - t0) && delta < 0.0 {
            // c = |e| − δ = ε c − δ  ⇒  c = −δ / (1 − ε), and ε < 1 when δ < 0.
            let clearance = -delta / (1.0 - cl.eps);
            let dist = (delta + 0.5 * clearance).abs();
            if free.as_ref().is_none_or(|(d, _)| dist < *d) {
                free = Some((dist, s()));
            }
        }
    }
    (contact.expect("steps"), free.expect("a free flight").1)
}
