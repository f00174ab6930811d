//! Measures the performance targets (a)–(e) of BENCHMARKS.md ("Results"), every claim as a
//! ratio of two measurements taken side by side in one run.
//!
//! ```text
//! cargo run --release -p lash-benches --example targets -- [a] [b] [c] [d] [e] [f] [g] [p]
//!     [--reps N] [--formulation F] [--at METHOD:RTOL] [--hand-rtol R] [--methods M,..]
//!     [--kinks | --no-kinks] [--rtols R,..] [--perturb K]
//! (a) one RHS and one Jacobian of the dry and lubricated press (150 rpm, c = 0.1 mm), ns,
//!     against the hand-written minimal-coordinate RHS (`lash_benches::handwritten`)
//! (b) lubricated 150 rpm, c = 0.1 mm, two revolutions: error = max |ẍ_slider − ẍ_ref| over the
//!     second revolution (2001 points); the cheapest run of each method with error ≤ 1e-6 m/s²
//!     against RK4 at the largest step h = Δ/k (Δ the grid spacing) that reaches it
//! (c) dry 150 rpm, c = 0.1 mm: the same error over the first half revolution; the adaptive
//!     methods with event location against RK4 without events (its error over h)
//! (d) rodas5p against bdf at equal error on several press cases (work–precision)
//! (e) Rodas5P with the previous Jacobian (plain central differences of f) against the new one
//! (f) lubricated 150 rpm, c = 0.1 mm, as (b): lash's cheapest run with error ≤ 1e-6 m/s²
//!     against diffsol's BDF alone on the hand-written minimal-coordinate press
//!     (`lash_benches::handwritten`), finite-difference Jacobians counted; then the path
//!     `lash run` takes (the engine's `lash_validation::run`: the scene read and assembled,
//!     the case's defaults but method and rtol, trajectory.csv at 2000 rows per revolution,
//!     events, metrics, figures, summary.json) against the same hand-written run, side by side,
//!     with what the path costs beyond the integration; and the dry press through `lash run`
//!     (first half revolution, rows at T/4000 so that they are the 2001-point grid): its
//!     cheapest run with error ≤ 1e-6 by work (RHS + 12 per Jacobian)
//! (g) dry 150 rpm, c = 0.1 mm, as (c) against a reference with kink events: every method with
//!     and without the kink events of the force laws (`Mechanism::set_kink_events`), work in
//!     RHS-equivalents (RHS + n per Jacobian, n = 12 the cost of a finite-difference one), the
//!     observed order p from a least-squares fit of log error = c − p log work over the runs
//!     with 1e-7 ≥ error ≥ 1e-9 · 30 … (error below 1e-2), and the cheapest run with error ≤ 1e-6
//! (p) (f)'s lubricated press through `lash run` at one run, `--at METHOD:RTOL` (default
//!     bdf:1e-10, (f)'s cheapest), side by side with the hand-written bdf at `--hand-rtol`
//!     (default 3.2e-10, (f)'s cheapest), without (f)'s scans: not among the defaults
//! (q) (f)'s last part alone: the dry press through `lash run`, every adaptive method or
//!     `--methods` (not among the defaults), at rtol 1e-5 … 1e-11 in half decades or
//!     `--rtols`; the scene's kink events as it decides (`kink_events` absent: on, its
//!     clearance joint is dry), `--kinks` / `--no-kinks` with `kink_events` true / false;
//!     `--perturb K` repeats the scan from K initial states (the journal's initial
//!     eccentricity k µm, k = 0 … K − 1, each against its own reference) and prints the
//!     median, mean and largest error and work per method and rtol
//! ```
//! References: Rodas5P at rtol 1e-13 (atol 1e-16), events on; its distance to Rodas5P at 1e-12
//! and to DOP853 at 1e-12 is printed as an estimate of its own error. Wall times are the
//! minimum over `--reps` runs
//! (default 3; a run under 50 ms is repeated up to 10 times). `--formulation F` runs lash's
//! side (the library scans and `lash run`) with formulation F instead of the scene's own; the
//! references keep the scene's.

use std::time::Instant;

use lash_benches::{
    contact_and_free_states, crank_period, grid, max_abs_diff, options, press, sample, Sampled,
};
use lash_model::{FormulationName, Mechanism};
use lash_solver::{Method, OdeSystem, Output, SolverOptions};
use lash_validation::{Case, NoProgress, RunOptions, SolverChoice};

/// Grid points of a window (docs/outputs.md, "`metrics`").
const N_GRID: usize = 2001;
/// The error target (m/s²).
const TARGET: f64 = 1e-6;

struct Ctx {
    reps: usize,
    /// `--formulation`: lash's side runs with it (None: the scene's own).
    formulation: Option<FormulationName>,
    /// `--methods a,b`: (q) scans only these (None: every adaptive method).
    methods: Option<Vec<Method>>,
    /// `--kinks` / `--no-kinks`: (q) runs the scene with `kink_events` true / false (None:
    /// the scene's own choice, automatic for the catalogue's).
    kinks: Option<bool>,
    /// `--rtols a,b`: (q) scans these tolerances (None: 1e-5 … 1e-11 in half decades).
    rtols: Option<Vec<f64>>,
    /// `--perturb K`: (q) repeats the scan from K initial states (0: the catalogue's only).
    perturb: usize,
}

/// One measured run.
#[derive(Clone, Debug)]
struct Run {
    label: String,
    /// The method and rtol of a lash run (None: the hand-written comparator), to rerun it.
    method: Option<Method>,
    rtol: f64,
    error: f64,
    wall: f64,
    steps: usize,
    rhs: usize,
    jac: usize,
    lu: usize,
    events: usize,
}

impl Ctx {
    /// Runs `m` to `t_end` with `opts`, samples on `times`, repeats for the minimum wall time.
    fn measure(
        &self,
        m: &Mechanism,
        t_end: f64,
        opts: &lash_solver::SolverOptions,
        times: &[f64],
    ) -> Result<Sampled, String> {
        let first = sample(m, t_end, opts, times).map_err(|e| e.to_string())?;
        let mut best = first.wall;
        let reps = if first.wall < 0.05 {
            self.reps.max(10)
        } else {
            self.reps
        };
        for _ in 1..reps {
            let s = sample(m, t_end, opts, times).map_err(|e| e.to_string())?;
            best = best.min(s.wall);
        }
        Ok(Sampled {
            wall: best,
            ..first
        })
    }

    fn run(
        &self,
        label: String,
        m: &Mechanism,
        t_end: f64,
        opts: &lash_solver::SolverOptions,
        times: &[f64],
        reference: &[f64],
    ) -> Option<Run> {
        match self.measure(m, t_end, opts, times) {
            Ok(s) => Some(Run {
                label,
                method: Some(opts.method),
                rtol: opts.rtol,
                error: max_abs_diff(&s.slider_a, reference),
                wall: s.wall,
                steps: s.stats.accepted,
                rhs: s.stats.rhs_evals,
                jac: s.stats.jac_evals,
                lu: s.stats.lu_factorizations,
                events: s.stats.events,
            }),
            Err(e) => {
                println!("  {label:28} failed: {e}");
                None
            }
        }
    }
}

fn print_header() {
    println!(
        "  {:28} {:>10} {:>10} {:>9} {:>10} {:>7} {:>7} {:>6}",
        "run", "error", "wall [s]", "steps", "rhs", "jac", "lu", "events"
    );
}

fn print_run(r: &Run) {
    println!(
        "  {:28} {:>10.2e} {:>10.4} {:>9} {:>10} {:>7} {:>7} {:>6}",
        r.label, r.error, r.wall, r.steps, r.rhs, r.jac, r.lu, r.events
    );
}

/// Reference slider acceleration on `times`: Rodas5P at rtol 1e-13 (atol 1e-16), events on.
/// Prints its distance to Rodas5P at 1e-12 and to DOP853 at 1e-12 (an independent method): an
/// estimate of the reference's own error. (DOP853 at 1e-14 is no better on the lubricated
/// press: a million stability-bound steps there add up rounding errors of ~5e-7 m/s².)
fn reference(m: &Mechanism, t_end: f64, times: &[f64]) -> Vec<f64> {
    reference_with(m, t_end, times, false)
}

/// [`reference`], with `exact_event_steps` as given (q: on, as `lash run` of a scene with
/// kink events).
fn reference_with(m: &Mechanism, t_end: f64, times: &[f64], exact: bool) -> Vec<f64> {
    let run = |method: Method, rtol: f64| {
        let mut o = options(method, rtol, rtol * 1e-3, 0.0, Output::Final);
        o.exact_event_steps = exact;
        let start = Instant::now();
        let s = sample(m, t_end, &o, times).expect("the reference run succeeds");
        (s.slider_a, start.elapsed().as_secs_f64())
    };
    let (r13, wr) = run(Method::Rodas5p, 1e-13);
    let (r12, _) = run(Method::Rodas5p, 1e-12);
    let (d12, wd) = run(Method::Dop853, 1e-12);
    println!(
        "  reference rodas5p(1e-13): |rodas5p(1e-12) − ref| = {:.1e}, |dop853(1e-12) − ref| = \
         {:.1e} m/s² (walls {wr:.2} s, {wd:.2} s); max |a_ref| = {:.1} m/s²",
        max_abs_diff(&r12, &r13),
        max_abs_diff(&d12, &r13),
        r13.iter().fold(0.0f64, |a, v| a.max(v.abs()))
    );
    r13
}

/// Tolerances of the scans, half decades.
fn tolerances(from: i32, to: i32) -> Vec<f64> {
    let mut v = Vec::new();
    for e in from..=to {
        v.push(10f64.powi(-e));
        if e < to {
            v.push(10f64.powi(-e) / 10f64.sqrt());
        }
    }
    v
}

/// Scans one adaptive method over `tols`; stops after the first run below `TARGET / 30`.
fn scan(
    ctx: &Ctx,
    method: Method,
    m: &Mechanism,
    t_end: f64,
    times: &[f64],
    reference: &[f64],
    tols: &[f64],
    events: bool,
) -> Vec<Run> {
    let mut out = Vec::new();
    for &rtol in tols {
        let mut o = options(method, rtol, rtol * 1e-3, 0.0, Output::Final);
        o.events = events;
        o.max_wall_time = Some(60.0);
        if let Some(r) = ctx.run(
            format!("{} rtol {rtol:.1e}", method.name()),
            m,
            t_end,
            &o,
            times,
            reference,
        ) {
            print_run(&r);
            let done = r.error < TARGET / 30.0;
            out.push(r);
            if done {
                break;
            }
        }
    }
    out
}

/// The cheapest run with error ≤ target.
fn cheapest(runs: &[Run], target: f64) -> Option<&Run> {
    runs.iter()
        .filter(|r| r.error <= target)
        .min_by(|a, b| a.wall.total_cmp(&b.wall))
}

/// RK4 at h = Δ/k: returns the run.
fn rk4_run(
    ctx: &Ctx,
    m: &Mechanism,
    t_end: f64,
    times: &[f64],
    reference: &[f64],
    k: usize,
    events: bool,
) -> Option<Run> {
    let delta = times[1] - times[0];
    let h = delta / k as f64;
    let mut o = options(Method::Rk4, 0.0, 0.0, h, Output::Final);
    o.events = events;
    let r = ctx.run(
        format!("rk4 h {h:.3e}{}", if events { " events" } else { "" }),
        m,
        t_end,
        &o,
        times,
        reference,
    )?;
    print_run(&r);
    Some(r)
}

/// Smallest k (largest h = Δ/k) with RK4 error ≤ target, by bisection between `k_lo` (fails)
/// and `k_hi` (succeeds), single runs; the step found is then timed with `ctx.reps`.
fn rk4_search(
    ctx: &Ctx,
    m: &Mechanism,
    t_end: f64,
    times: &[f64],
    reference: &[f64],
    mut k_lo: usize,
    mut k_hi: usize,
) -> Option<Run> {
    let once = Ctx {
        reps: 1,
        formulation: None,
        methods: None,
        kinks: None,
        rtols: None,
        perturb: 0,
    };
    let ok = |r: &Option<Run>| r.as_ref().is_some_and(|r| r.error <= TARGET);
    let first = rk4_run(&once, m, t_end, times, reference, k_hi, false);
    if !ok(&first) {
        println!("  rk4 misses the target at k = {k_hi}");
        return None;
    }
    while k_hi - k_lo > 1 {
        let k = (k_lo + k_hi) / 2;
        if ok(&rk4_run(&once, m, t_end, times, reference, k, false)) {
            k_hi = k;
        } else {
            k_lo = k;
        }
    }
    println!("  rk4: largest step reaching the target: k = {k_hi}; timed:");
    rk4_run(ctx, m, t_end, times, reference, k_hi, false)
}

/// The press `stem` run for two revolutions, the grid of the second (N_GRID points), the end
/// time and the reference slider acceleration on the grid.
fn second_revolution(stem: &str) -> (Mechanism, Vec<f64>, f64, Vec<f64>) {
    let m = press(stem, 2.0);
    let per = crank_period(&m);
    let times = grid(per, 2.0 * per, N_GRID);
    let t_end = m.t_end();
    let reference = reference(&m, t_end, &times);
    (m, times, t_end, reference)
}

/// Every adaptive method over rtol 1e-4 … 1e-11 (each run printed); the cheapest run of each
/// that meets [`TARGET`].
fn cheapest_adaptive(
    ctx: &Ctx,
    m: &Mechanism,
    t_end: f64,
    times: &[f64],
    reference: &[f64],
) -> Vec<Run> {
    let mut best = Vec::new();
    for method in Method::ALL.into_iter().filter(|m| !m.is_fixed_step()) {
        let runs = scan(
            ctx,
            method,
            m,
            t_end,
            times,
            reference,
            &tolerances(4, 11),
            true,
        );
        if let Some(r) = cheapest(&runs, TARGET) {
            best.push(r.clone());
        }
    }
    best
}

/// Minimum over `reps` rounds of the mean time of `n` calls of `f` (s).
fn time_per_call(reps: usize, n: usize, mut f: impl FnMut()) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..reps {
        let start = Instant::now();
        for _ in 0..n {
            f();
        }
        best = best.min(start.elapsed().as_secs_f64() / n as f64);
    }
    best
}

fn section_a(ctx: &Ctx) {
    use lash_benches::handwritten::HandPress;
    println!(
        "\n(a) one right-hand side and one Jacobian of the press, 150 rpm, c = 0.1 mm, against \
         the hand-written minimal-coordinate right-hand side (rounds alternate, minimum of each)"
    );
    for stem in ["dry_150rpm_c0.1", "lubricated_150rpm_c0.1"] {
        let m = press(stem, 2.0);
        let hand = HandPress::paper(150.0, 1e-4, stem.starts_with("lubricated"));
        let (contact, free) = contact_and_free_states(&m);
        for (label, s) in [("contact", contact), ("free", free)] {
            let n = m.dim();
            let mut dy = vec![0.0; n];
            let mut jac = faer::Mat::<f64>::zeros(n, n);
            let ym = HandPress::minimal_state(&s.y);
            let mut dh = [0.0; 4];
            let (mut rhs, mut hand_rhs, mut jac_t) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
            for _ in 0..ctx.reps.max(5) {
                rhs = rhs.min(time_per_call(1, 200_000, || {
                    m.rhs(
                        std::hint::black_box(s.t),
                        std::hint::black_box(&s.y),
                        std::hint::black_box(&mut dy),
                    )
                }));
                hand_rhs = hand_rhs.min(time_per_call(1, 200_000, || {
                    hand.rhs(
                        std::hint::black_box(s.t),
                        std::hint::black_box(&ym),
                        std::hint::black_box(&mut dh),
                    )
                }));
                jac_t = jac_t.min(time_per_call(1, 10_000, || {
                    m.jacobian(
                        std::hint::black_box(s.t),
                        std::hint::black_box(&s.y),
                        jac.as_mut(),
                    )
                }));
            }
            println!(
                "  {stem:24} {label:8} δ = {:+.2e} m   rhs {:6.1} ns, hand-written {:5.1} ns: \
                 {:.2}× (goal ≤ 2);   jacobian {:7.0} ns = {:.1} rhs (goal ≤ 6)",
                s.delta,
                rhs * 1e9,
                hand_rhs * 1e9,
                rhs / hand_rhs,
                jac_t * 1e9,
                jac_t / rhs
            );
        }
    }
}

fn section_b(ctx: &Ctx) {
    let stem = "lubricated_150rpm_c0.1";
    println!("\n(b) {stem}, two revolutions, error over the second (target {TARGET:.0e} m/s²)");
    let (m, times, t_end, reference) = second_revolution(stem);
    print_header();
    let mut best = cheapest_adaptive(ctx, &m, t_end, &times, &reference);
    // RK4: h = Δ/k, Δ the grid spacing (grid times are step ends); k = 100 is the stable step
    // of the tests (2e-6 s). Below it RK4 is unstable; search k in (50, 800].
    let delta = times[1] - times[0];
    println!("  rk4: largest h = Δ/k with error ≤ {TARGET:.0e} (Δ = {delta:.1e} s)");
    for k in [50, 100] {
        rk4_run(
            &Ctx {
                reps: 1,
                formulation: None,
                methods: None,
                kinks: None,
                rtols: None,
                perturb: 0,
            },
            &m,
            t_end,
            &times,
            &reference,
            k,
            false,
        );
    }
    let rk4 = rk4_search(ctx, &m, t_end, &times, &reference, 100, 800);
    println!("  cheapest run of each method with error ≤ {TARGET:.0e}:");
    best.sort_by(|a, b| a.wall.total_cmp(&b.wall));
    for r in &best {
        print_run(r);
    }
    if let (Some(rk), Some(b)) = (rk4, best.first()) {
        print_run(&rk);
        println!(
            "  => rk4 wall / {} wall = {:.0}×  (target ≥ 100×)",
            b.label,
            rk.wall / b.wall
        );
    }
}

fn section_c(ctx: &Ctx) {
    let stem = "dry_150rpm_c0.1";
    println!("\n(c) {stem}, error over the first half revolution (target {TARGET:.0e} m/s²)");
    let m = press(stem, 0.5);
    let half = 0.5 * crank_period(&m);
    let times = grid(0.0, half, N_GRID);
    let t_end = m.t_end();
    let reference = reference(&m, t_end, &times);
    print_header();
    let mut best = cheapest_adaptive(ctx, &m, t_end, &times, &reference);
    println!(
        "  rk4 without events, h = Δ/k (Δ = {:.1e} s):",
        times[1] - times[0]
    );
    let mut rk4_runs = Vec::new();
    for k in [1, 2, 4, 8, 16, 32, 64, 128, 256] {
        if let Some(r) = rk4_run(
            &Ctx {
                reps: 1,
                formulation: None,
                methods: None,
                kinks: None,
                rtols: None,
                perturb: 0,
            },
            &m,
            t_end,
            &times,
            &reference,
            k,
            false,
        ) {
            rk4_runs.push(r);
        }
    }
    println!("  rk4 with events (located contact onsets and losses), h = Δ/k:");
    for k in [1, 4, 16, 64] {
        rk4_run(
            &Ctx {
                reps: 1,
                formulation: None,
                methods: None,
                kinks: None,
                rtols: None,
                perturb: 0,
            },
            &m,
            t_end,
            &times,
            &reference,
            k,
            true,
        );
    }
    println!("  cheapest run of each method with error ≤ {TARGET:.0e}:");
    best.sort_by(|a, b| a.wall.total_cmp(&b.wall));
    for r in &best {
        print_run(r);
    }
    let min_rk4 = rk4_runs
        .iter()
        .map(|r| r.error)
        .fold(f64::INFINITY, f64::min);
    println!("  => smallest rk4 error without events: {min_rk4:.2e} m/s²");
}

fn section_d(ctx: &Ctx) {
    println!("\n(d) rodas5p against bdf at equal error (error over the last revolution of two)");
    let targets = [1e-2, 1e-4, 1e-6];
    let mut summary = Vec::new();
    for stem in [
        "dry_150rpm_c0.1",
        "dry_150rpm_c0.5",
        "lubricated_150rpm_c0.1",
        "lubricated_150rpm_c0.2",
        "lubricated_200rpm_c0.1",
    ] {
        println!(" {stem}");
        let (m, times, t_end, reference) = second_revolution(stem);
        print_header();
        let tols = tolerances(3, 10);
        let rodas = scan(
            ctx,
            Method::Rodas5p,
            &m,
            t_end,
            &times,
            &reference,
            &tols,
            true,
        );
        let bdf = scan(ctx, Method::Bdf, &m, t_end, &times, &reference, &tols, true);
        for target in targets {
            let (r, b) = (cheapest(&rodas, target), cheapest(&bdf, target));
            let line = match (r, b) {
                (Some(r), Some(b)) => format!(
                    "{stem:24} error ≤ {target:.0e}: rodas5p {:.4} s ({}), bdf {:.4} s ({}), \
                     bdf/rodas5p = {:.2}",
                    r.wall,
                    r.label,
                    b.wall,
                    b.label,
                    b.wall / r.wall
                ),
                (r, b) => format!(
                    "{stem:24} error ≤ {target:.0e}: rodas5p {}, bdf {}",
                    r.map_or("not reached".into(), |r| format!("{:.4} s", r.wall)),
                    b.map_or("not reached".into(), |b| format!("{:.4} s", b.wall)),
                ),
            };
            println!("  {line}");
            summary.push(line);
        }
    }
    println!("\n(d) summary");
    for l in summary {
        println!("  {l}");
    }
}

/// The mechanism with the Jacobian of the previous version: central differences of f in every
/// component of y with h_j = 1e-8 · max(|y_j|, 1) (24 RHS evaluations), for a side-by-side
/// comparison with the mechanism's own Jacobian.
struct PlainDifferences<'a>(&'a Mechanism);

impl OdeSystem for PlainDifferences<'_> {
    fn dim(&self) -> usize {
        self.0.dim()
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.0.rhs(t, y, dy)
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, t: f64, y: &[f64], mut jac: faer::MatMut<'_, f64>) {
        let n = y.len();
        let nq = n / 2;
        let (mut yp, mut fp, mut fm) = (y.to_vec(), vec![0.0; n], vec![0.0; n]);
        for j in 0..n {
            for i in 0..n {
                jac[(i, j)] = 0.0;
            }
        }
        for i in 0..nq {
            jac[(i, nq + i)] = 1.0;
        }
        for j in 0..n {
            let h = 1e-8 * y[j].abs().max(1.0);
            yp[j] = y[j] + h;
            self.0.rhs(t, &yp, &mut fp);
            yp[j] = y[j] - h;
            self.0.rhs(t, &yp, &mut fm);
            yp[j] = y[j];
            for i in nq..n {
                jac[(i, j)] = (fp[i] - fm[i]) * (0.5 / h);
            }
        }
    }
    fn n_events(&self) -> usize {
        self.0.n_events()
    }
    fn event_spec(&self, i: usize) -> lash_solver::EventSpec {
        self.0.event_spec(i)
    }
    fn events(&self, t: f64, y: &[f64], g: &mut [f64]) {
        self.0.events(t, y, g)
    }
    fn on_event(&self, hit: &lash_solver::EventHit, y: &mut [f64]) -> lash_solver::EventAction {
        self.0.on_event(hit, y)
    }
}

fn section_e(ctx: &Ctx) {
    println!(
        "\n(e) Rodas5P with the previous Jacobian (plain differences of f) and with the new one"
    );
    for stem in ["lubricated_150rpm_c0.1", "dry_150rpm_c0.1"] {
        let m = press(stem, 2.0);
        for rtol in [1e-6, 1e-8] {
            let o = options(Method::Rodas5p, rtol, rtol * 1e-3, 0.0, Output::Final);
            let y0 = m.initial_state();
            let time = |sys: &dyn Fn() -> lash_solver::Solution| {
                let mut best = f64::INFINITY;
                let mut sol = None;
                for _ in 0..ctx.reps.max(3) {
                    let start = Instant::now();
                    sol = Some(sys());
                    best = best.min(start.elapsed().as_secs_f64());
                }
                (best, sol.expect("ran"))
            };
            let plain = PlainDifferences(&m);
            let (w_old, s_old) = time(&|| {
                lash_solver::solve(&plain, (m.t_start(), m.t_end()), &y0, &o).expect("runs")
            });
            let (w_new, s_new) =
                time(&|| lash_solver::solve(&m, (m.t_start(), m.t_end()), &y0, &o).expect("runs"));
            println!(
                "  {stem:24} rtol {rtol:.0e}: previous {:6} steps {:8.4} s, new {:6} steps {:8.4} s, \
                 previous/new wall = {:.1}×",
                s_old.stats.accepted,
                w_old,
                s_new.stats.accepted,
                w_new,
                w_old / w_new
            );
        }
    }
}

fn section_f(ctx: &Ctx) {
    use lash_benches::handwritten::{diffsol_bdf, diffsol_bdf_copies, HandPress};
    let stem = "lubricated_150rpm_c0.1";
    println!(
        "\n(f) {stem}, two revolutions: lash against diffsol's BDF on the hand-written press \
         (target {TARGET:.0e} m/s²)"
    );
    let (m, times, t_end, reference) = second_revolution(stem);
    let hand = HandPress::paper(150.0, 1e-4, true);
    let y0 = HandPress::minimal_state(&absolute_initial_state(stem));
    println!("  diffsol bdf on the hand-written press (4 states), atol = rtol·1e-3:");
    print_header();
    let mut hand_runs = Vec::new();
    for rtol in tolerances(4, 12) {
        let mut best: Option<lash_benches::handwritten::DiffsolRun> = None;
        for _ in 0..ctx.reps.max(10) {
            let r = match diffsol_bdf(&hand, m.t_start(), y0, rtol, [rtol * 1e-3; 4], &times) {
                Ok(r) => r,
                Err(e) => {
                    println!("  rtol {rtol:.1e}: {e}");
                    break;
                }
            };
            if best.as_ref().is_none_or(|b| r.wall < b.wall) {
                best = Some(r);
            }
        }
        let Some(r) = best else { continue };
        let run = Run {
            label: format!("hand bdf rtol {rtol:.1e}"),
            method: None,
            rtol,
            error: max_abs_diff(&r.slider_a, &reference),
            wall: r.wall,
            steps: r.steps,
            rhs: r.rhs_evals,
            jac: 0,
            lu: 0,
            events: 0,
        };
        print_run(&run);
        let done = run.error < TARGET / 30.0;
        hand_runs.push(run);
        if done {
            break;
        }
    }
    let lm = press_as(stem, 2.0, ctx.formulation);
    println!(
        "  lash on the general model ({} states, {}), every adaptive method:",
        lm.dim(),
        formulation_label(ctx.formulation)
    );
    print_header();
    let mut best = cheapest_adaptive(ctx, &lm, t_end, &times, &reference);
    best.sort_by(|a, b| a.wall.total_cmp(&b.wall));
    let hand_best = cheapest(&hand_runs, TARGET);
    println!("  cheapest with error ≤ {TARGET:.0e}:");
    if let Some(h) = hand_best {
        print_run(h);
    }
    if let Some(b) = best.first() {
        print_run(b);
    }
    if let (Some(h), Some(b)) = (hand_best, best.first()) {
        println!(
            "  => {} wall / hand-written diffsol bdf wall = {:.2}×  (goal ≤ 1.5×); RHS {} vs {}",
            b.label,
            b.wall / h.wall,
            b.rhs,
            h.rhs
        );
        // The scans above run minutes apart on a shared machine; the ratio that counts times
        // the two chosen runs alternately, round by round, and takes the minimum of each.
        let Some(method) = b.method else { return };
        let mut o = options(method, b.rtol, b.rtol * 1e-3, 0.0, Output::Final);
        o.events = true;
        let rounds = 10 * ctx.reps.max(2);
        let (mut tl, mut th, mut t3) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let mut steps3 = 0;
        for _ in 0..rounds {
            if let Ok(s) = sample(&lm, t_end, &o, &times) {
                tl = tl.min(s.wall);
            }
            let atol = [h.rtol * 1e-3; 4];
            if let Ok(r) = diffsol_bdf(&hand, m.t_start(), y0, h.rtol, atol, &times) {
                th = th.min(r.wall);
            }
            // The same run at the general model's dimension (three stacked copies, one
            // right-hand side per call): what 12 states cost diffsol alone.
            let atol = h.rtol * 1e-3;
            if let Ok(r) = diffsol_bdf_copies(&hand, m.t_start(), y0, h.rtol, atol, &times, 3) {
                t3 = t3.min(r.wall);
                steps3 = r.steps;
            }
        }
        println!(
            "  => side by side, {rounds} alternating rounds, minimum of each: {} {:.3} ms, hand \
             bdf rtol {:.1e} {:.3} ms: {:.2}×  (goal ≤ 1.5×)",
            b.label,
            tl * 1e3,
            h.rtol,
            th * 1e3,
            tl / th
        );
        println!(
            "  => the hand-written run at 12 states (3 stacked copies, {steps3} steps): {:.3} ms \
             = {:.2}× the 4-state run; lash / it = {:.2}×",
            t3 * 1e3,
            t3 / th,
            tl / t3
        );
    }
    if let Some(h) = hand_best {
        lubricated_through_lash_run(ctx, stem, &lm, &times, &reference, h);
    }
    dry_through_lash_run(ctx);
}

/// The assembled absolute initial state (q, q̇) of the press `stem`, whatever the scene's
/// formulation: what the hand-written press starts from.
fn absolute_initial_state(stem: &str) -> Vec<f64> {
    press_as(stem, 2.0, Some(FormulationName::LagrangeBaumgarte)).initial_state()
}

/// The press `stem` from `cases/press/` for `revolutions`, with `formulation` over the scene's
/// own (None: lagrange_baumgarte, as [`press`]).
fn press_as(stem: &str, revolutions: f64, formulation: Option<FormulationName>) -> Mechanism {
    let Some(f) = formulation else {
        return press(stem, revolutions);
    };
    let path = lash_benches::cases_dir().join(format!("{stem}.json"));
    let mut scene = lash_model::Scene::from_path(&path).expect("the catalogue's scene");
    scene.t_end = None;
    scene.revolutions = Some(revolutions);
    scene.formulation = f;
    Mechanism::from_scene(&scene).expect("the scene assembles")
}

fn formulation_label(f: Option<FormulationName>) -> String {
    f.map_or("the scene's formulation".into(), |f| f.to_string())
}

/// What `lash run` does with a press case: the engine's `run` (to `out`, files written) and
/// `run_in_memory` (the same run without the files) at `method` and `rtol`, the case's other
/// defaults (atol following rtol, 4 event samples, the step limit near contact), end time
/// `t_end`, `rows` trajectory rows per revolution.
struct RunPath<'a> {
    stem: &'a str,
    /// The scene to run instead of `cases/press/{stem}.json` (q: a copy with its perturbed
    /// initial state and `kink_events` as `--kinks` / `--no-kinks` say).
    case: Option<std::path::PathBuf>,
    t_end: f64,
    rows: usize,
    formulation: Option<FormulationName>,
    out: std::path::PathBuf,
}

impl RunPath<'_> {
    fn options(&self, method: Method, rtol: f64) -> RunOptions {
        let case = self
            .case
            .clone()
            .unwrap_or_else(|| lash_benches::cases_dir().join(format!("{}.json", self.stem)));
        RunOptions {
            case: case.display().to_string(),
            solver: SolverChoice {
                method: Some(method),
                rtol: Some(rtol),
                ..Default::default()
            },
            t_end: Some(self.t_end),
            samples_per_revolution: Some(self.rows),
            out: Some(self.out.clone()),
            formulation: self.formulation,
            ..Default::default()
        }
    }

    /// One run in memory: (wall s, the slider acceleration on the rows with t in `window`,
    /// those rows' times, the run's counters), or the error.
    fn in_memory(
        &self,
        method: Method,
        rtol: f64,
        window: (f64, f64),
    ) -> Result<(f64, Vec<f64>, Vec<f64>, lash_solver::Stats), String> {
        let o = self.options(method, rtol);
        let start = Instant::now();
        let case = Case::load(&o.case, None).map_err(|e| e.to_string())?;
        let r = lash_validation::run_in_memory(case, &o).map_err(|e| e.to_string())?;
        let wall = start.elapsed().as_secs_f64();
        let t = r.trajectory.column("t").ok_or("no t column")?;
        let a = r
            .trajectory
            .column("slider_a")
            .ok_or("no slider_a column")?;
        let slack = 1e-9 * (window.1 - window.0);
        let keep: Vec<usize> = (0..t.len())
            .filter(|&k| t[k] >= window.0 - slack && t[k] <= window.1 + slack)
            .collect();
        Ok((
            wall,
            keep.iter().map(|&k| a[k]).collect(),
            keep.iter().map(|&k| t[k]).collect(),
            r.summary.stats,
        ))
    }

    /// One `lash run` with its files (wall s).
    fn to_disk(&self, method: Method, rtol: f64) -> Result<f64, String> {
        let o = self.options(method, rtol);
        let start = Instant::now();
        lash_validation::run(&o, &NoProgress).map_err(|e| e.to_string())?;
        Ok(start.elapsed().as_secs_f64())
    }

    /// The run at (method, rtol) measured on `times` against `reference`: error, counters, the
    /// minimum in-memory wall time over the repetitions (None when it fails; the rows must be
    /// the grid's times).
    fn measure(
        &self,
        ctx: &Ctx,
        method: Method,
        rtol: f64,
        times: &[f64],
        reference: &[f64],
    ) -> Option<Run> {
        let window = (times[0], times[times.len() - 1]);
        let label = format!("lash run {} rtol {rtol:.1e}", method.name());
        let (w0, a, t, stats) = match self.in_memory(method, rtol, window) {
            Ok(v) => v,
            Err(e) => {
                println!("  {label:28} failed: {e}");
                return None;
            }
        };
        let on_grid = t.len() == times.len()
            && t.iter()
                .zip(times)
                .all(|(a, b)| (a - b).abs() <= 1e-12 * b.abs().max(1.0));
        assert!(
            on_grid,
            "the trajectory's rows are not the grid ({} rows)",
            t.len()
        );
        let mut wall = w0;
        let reps = if w0 < 0.05 {
            ctx.reps.max(10)
        } else {
            ctx.reps
        };
        for _ in 1..reps {
            if let Ok(v) = self.in_memory(method, rtol, window) {
                wall = wall.min(v.0);
            }
        }
        let r = Run {
            label,
            method: Some(method),
            rtol,
            error: max_abs_diff(&a, reference),
            wall,
            steps: stats.accepted,
            rhs: stats.rhs_evals,
            jac: stats.jac_evals,
            lu: stats.lu_factorizations,
            events: stats.events,
        };
        print_run(&r);
        Some(r)
    }

    /// `methods` scanned over rtol 1e-5 … 1e-11 in half decades (each stops after its first
    /// run below TARGET/30).
    fn scan_all(
        &self,
        ctx: &Ctx,
        methods: &[Method],
        times: &[f64],
        reference: &[f64],
    ) -> Vec<Run> {
        let mut runs = Vec::new();
        let tols = ctx.rtols.clone().unwrap_or_else(|| tolerances(5, 11));
        for &method in methods {
            for &rtol in &tols {
                if let Some(r) = self.measure(ctx, method, rtol, times, reference) {
                    // With perturbed scans every rtol is run, for the statistics.
                    let done = r.error < TARGET / 30.0 && ctx.perturb == 0;
                    runs.push(r);
                    if done {
                        break;
                    }
                }
            }
        }
        runs
    }
}

/// (f), continued: the lubricated press through `lash run` against the hand-written run `h`,
/// and where the time of the path goes.
fn lubricated_through_lash_run(
    ctx: &Ctx,
    stem: &str,
    lm: &Mechanism,
    times: &[f64],
    reference: &[f64],
    h: &Run,
) {
    let per = crank_period(lm);
    let dir = std::env::temp_dir().join(format!("lash-targets-f-{}", std::process::id()));
    let path = RunPath {
        stem,
        case: None,
        t_end: lm.t_start() + 2.0 * per,
        rows: 2000,
        formulation: ctx.formulation,
        out: dir.join("run"),
    };
    // The explicit pairs are stability-bound on the film (10⁵ steps, above): only the
    // implicit methods can be the cheapest.
    println!(
        "  `lash run` ({}; atol following rtol, the case's other defaults; in memory), the \
         implicit methods:",
        formulation_label(ctx.formulation)
    );
    print_header();
    let implicit = [
        Method::Bdf,
        Method::Trbdf2,
        Method::Esdirk34,
        Method::Rodas5p,
    ];
    let runs = path.scan_all(ctx, &implicit, times, reference);
    let Some(b) = cheapest(&runs, TARGET).cloned() else {
        println!("  no `lash run` reaches {TARGET:.0e}");
        return;
    };
    let method = b.method.expect("a lash run");
    path_side_by_side(ctx, &path, lm, times, (method, b.rtol, &b.label), h.rtol);
    let _ = std::fs::remove_dir_all(&dir);
}

/// (p): the lubricated press through `lash run` at one (method, rtol), (f)'s cheapest, side by
/// side with the hand-written bdf at (f)'s cheapest rtol, without (f)'s scans.
fn section_p(ctx: &Ctx, (method, rtol): (Method, f64), hand_rtol: f64) {
    let stem = "lubricated_150rpm_c0.1";
    println!(
        "\n(p) {stem}, two revolutions through `lash run` ({}) at {} rtol {rtol:.1e}, side by \
         side with the hand-written diffsol bdf at rtol {hand_rtol:.1e}",
        formulation_label(ctx.formulation),
        method.name()
    );
    let (m, times, _, reference) = second_revolution(stem);
    let per = crank_period(&m);
    let dir = std::env::temp_dir().join(format!("lash-targets-p-{}", std::process::id()));
    let path = RunPath {
        stem,
        case: None,
        t_end: m.t_start() + 2.0 * per,
        rows: 2000,
        formulation: ctx.formulation,
        out: dir.join("run"),
    };
    print_header();
    let Some(r) = path.measure(ctx, method, rtol, &times, &reference) else {
        return;
    };
    let lm = press_as(stem, 2.0, ctx.formulation);
    path_side_by_side(ctx, &path, &lm, &times, (method, rtol, &r.label), hand_rtol);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The `lash run` of `path` at (method, rtol) side by side with the hand-written diffsol bdf
/// at `hand_rtol` (atol hand_rtol·1e-3), and the library runs that split the difference:
/// `10 · reps` alternating rounds, the minimum of each.
fn path_side_by_side(
    ctx: &Ctx,
    path: &RunPath<'_>,
    lm: &Mechanism,
    times: &[f64],
    (method, rtol, label): (Method, f64, &str),
    hand_rtol: f64,
) {
    use lash_benches::handwritten::{diffsol_bdf, HandPress};
    let per = crank_period(lm);
    let hand = HandPress::paper(150.0, 1e-4, true);
    // The hand-written press starts from the absolute state (lash's side may be minimal).
    let y0 = HandPress::minimal_state(&absolute_initial_state(path.stem));
    let lib = |o: &SolverOptions| sample(lm, path.t_end, o, times).map(|s| s.wall).ok();
    let o_run = lash_benches::run_options(lm, method, rtol, 1e-4);
    let mut o_blanket = o_run.clone();
    o_blanket.h_max_near_events = f64::INFINITY;
    o_blanket.h_max = per / 100.0;
    let mut o_free = o_run.clone();
    o_free.h_max_near_events = f64::INFINITY;
    let mut o_noev = o_free.clone();
    o_noev.events = false;
    let rounds = 10 * ctx.reps.max(2);
    let mut best = [f64::INFINITY; 7];
    // The command's runs (files, in memory) in rounds of their own: run between the library
    // runs they would leave those a cold cache in every round, which the hand-written run,
    // timed after the warm library runs, would not pay (measured: 1.31× against 1.19× for
    // the same builds).
    for _ in 0..rounds {
        let walls = [
            path.to_disk(method, rtol).ok(),
            path.in_memory(method, rtol, (times[0], times[times.len() - 1]))
                .ok()
                .map(|v| v.0),
        ];
        for (b, w) in best.iter_mut().zip(walls) {
            if let Some(w) = w {
                *b = b.min(w);
            }
        }
    }
    for _ in 0..rounds {
        let walls = [
            lib(&o_run),
            lib(&o_blanket),
            lib(&o_free),
            lib(&o_noev),
            diffsol_bdf(
                &hand,
                lm.t_start(),
                y0,
                hand_rtol,
                [hand_rtol * 1e-3; 4],
                times,
            )
            .ok()
            .map(|r| r.wall),
        ];
        for (b, w) in best[2..].iter_mut().zip(walls) {
            if let Some(w) = w {
                *b = b.min(w);
            }
        }
    }
    let hw = best[6];
    println!(
        "  => side by side, {rounds} alternating rounds, minimum of each (ms, and / the \
         hand-written bdf rtol {:.1e}, {:.3} ms):",
        hand_rtol,
        hw * 1e3
    );
    for (what, w) in [
        ("`lash run`, files written", best[0]),
        ("`lash run` in memory (run_in_memory)", best[1]),
        ("library, the run's options", best[2]),
        ("library, blanket h_max = T/100 instead", best[3]),
        ("library, no step limit", best[4]),
        ("library, no step limit, events off", best[5]),
    ] {
        println!("     {what:42} {:8.3} ms  {:6.2}×", w * 1e3, w / hw);
    }
    println!(
        "  => best `lash run` ({}): {:.2}× the hand-written run in memory, {:.2}× with its files \
         (target ≤ 1.2×)",
        label,
        best[1] / hw,
        best[0] / hw
    );
}

/// The step of the perturbations of `q --perturb K` (m): scan k starts the journal at the
/// eccentricity k · PERTURB_STEP in the direction k · 137.5° (the golden angle, so that the
/// directions spread), 1 % of the clearance per k; k = 0 is the catalogue's centred journal.
const PERTURB_STEP: f64 = 1e-6;

/// The dry press scene `stem` of the catalogue, perturbed as scan `k` of `--perturb`
/// ([`PERTURB_STEP`]), with `kink_events` as given.
fn perturbed_dry_scene(stem: &str, k: usize, kinks: Option<bool>) -> lash_model::Scene {
    let path = lash_benches::cases_dir().join(format!("{stem}.json"));
    let mut scene = lash_model::Scene::from_path(&path).expect("the catalogue's scene");
    assert!(
        scene.kink_events.is_none(),
        "the scene sets kink_events itself"
    );
    scene.kink_events = kinks;
    let angle = (k as f64 * 137.5).to_radians();
    let e = k as f64 * PERTURB_STEP;
    let mut clearances = 0;
    for j in &mut scene.joints {
        if let lash_model::scene::JointSpec::Clearance(c) = j {
            c.initial_eccentricity = [e * angle.cos(), e * angle.sin()];
            clearances += 1;
        }
    }
    assert_eq!(clearances, 1, "the dry press has one clearance joint");
    scene
}

/// (f), the dry press: the first half revolution through `lash run`, error against the
/// reference with kink events; the cheapest run by work (target ≤ 30 000 RHS-equivalents).
/// With `--perturb K`, the scan is repeated from K initial states (k = 0 the catalogue's,
/// [`PERTURB_STEP`]), each against its own reference, and the error and work are summarised
/// per method and rtol (median, mean and largest over the K scans).
fn dry_through_lash_run(ctx: &Ctx) {
    let stem = "dry_150rpm_c0.1";
    println!(
        "\n(f) {stem}, first half revolution through `lash run` ({}): the cheapest run with \
         error ≤ {TARGET:.0e} m/s² by work = RHS + n per Jacobian (target ≤ 30 000)",
        formulation_label(ctx.formulation)
    );
    // The dimension `lash run` integrates: the scene's own formulation (`auto` resolves to
    // `minimal` for the press, 4 states) unless `--formulation` names one.
    let n = {
        let mut scene = perturbed_dry_scene(stem, 0, Some(false));
        if let Some(f) = ctx.formulation {
            scene.formulation = f;
        }
        Mechanism::from_scene(&scene)
            .expect("the scene assembles")
            .dim()
    };
    let dir = std::env::temp_dir().join(format!("lash-targets-fd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    let resolved = Mechanism::from_scene(&perturbed_dry_scene(stem, 0, ctx.kinks))
        .expect("the scene assembles")
        .kink_events();
    println!(
        "  lash's side with kink events {} ({})",
        if resolved { "on" } else { "off" },
        match ctx.kinks {
            Some(true) => "--kinks",
            Some(false) => "--no-kinks",
            None => "the scene's automatic choice",
        }
    );
    let adaptive: Vec<Method> = Method::ALL
        .into_iter()
        .filter(|m| !m.is_fixed_step())
        .filter(|m| ctx.methods.as_ref().is_none_or(|ms| ms.contains(m)))
        .collect();
    let scans = ctx.perturb.max(1);
    let mut all: Vec<Run> = Vec::new();
    for k in 0..scans {
        let scene = perturbed_dry_scene(stem, k, ctx.kinks);
        if ctx.perturb > 0 {
            println!(
                "  scan {k}: the journal's initial eccentricity {:.0e} m at {:.1}°",
                k as f64 * PERTURB_STEP,
                (k as f64 * 137.5) % 360.0
            );
        }
        // The reference: the same initial state, kink events on, exact event steps, in the
        // formulation lash's side runs (the scene's own, `auto`: `minimal`, or
        // `--formulation`); its distance to the same reference in lagrange_baumgarte (that of
        // `press` and of the tables before the perturbed scans) is printed.
        let mechanism = |f: Option<FormulationName>| {
            let mut s = scene.clone();
            s.t_end = None;
            s.revolutions = Some(0.5);
            s.kink_events = Some(true);
            if let Some(f) = f {
                s.formulation = f;
            }
            let mut m = Mechanism::from_scene(&s).expect("the scene assembles");
            m.set_kink_events(true);
            m
        };
        let kinked = mechanism(ctx.formulation);
        let half = 0.5 * crank_period(&kinked);
        let times = grid(0.0, half, N_GRID);
        println!(
            "  reference with kink events and exact event steps ({}):",
            formulation_label(ctx.formulation)
        );
        let reference = reference_with(&kinked, kinked.t_end(), &times, true);
        if ctx.formulation != Some(FormulationName::LagrangeBaumgarte) {
            let lb = mechanism(Some(FormulationName::LagrangeBaumgarte));
            let mut o = options(Method::Rodas5p, 1e-13, 1e-16, 0.0, Output::Final);
            o.exact_event_steps = true;
            let s = sample(&lb, lb.t_end(), &o, &times).expect("the reference run succeeds");
            println!(
                "  |reference − the same in lagrange_baumgarte| = {:.1e} m/s²",
                max_abs_diff(&reference, &s.slider_a)
            );
        }
        let case = dir.join(format!("{stem}_{k}.json"));
        std::fs::write(&case, scene.to_json_pretty()).expect("written");
        let path = RunPath {
            stem,
            case: Some(case),
            t_end: half,
            rows: 2 * (N_GRID - 1),
            formulation: ctx.formulation,
            out: dir.join("run"),
        };
        print_header();
        all.extend(path.scan_all(ctx, &adaptive, &times, &reference));
    }
    let _ = std::fs::remove_dir_all(&dir);
    if ctx.perturb > 0 {
        print_scatter(&all, &adaptive, n);
    }
    let mut ok: Vec<&Run> = all.iter().filter(|r| r.error <= TARGET).collect();
    ok.sort_by_key(|r| work(r, n));
    println!("  the cheapest by work with error ≤ {TARGET:.0e} (n = {n}):");
    for r in ok.iter().take(5) {
        println!(
            "  {:28} error {:.2e}  work {:>7}  wall {:.4} s",
            r.label,
            r.error,
            work(r, n),
            r.wall
        );
    }
    if ok.is_empty() {
        println!("  none within the scan");
    }
}

/// `q --perturb K`'s summary: per method and rtol, over the K scans, the median, mean and
/// largest error, the mean and largest work, and how many scans met the target within 30 000.
fn print_scatter(runs: &[Run], methods: &[Method], n: usize) {
    println!(
        "  scatter over the perturbed scans (error m/s², work = RHS + {n} per Jacobian):\n  \
         {:8} {:>8} {:>5} {:>10} {:>10} {:>10} {:>9} {:>9} {:>6}",
        "method",
        "rtol",
        "scans",
        "median err",
        "mean err",
        "max err",
        "mean work",
        "max work",
        "met"
    );
    for &m in methods {
        let mut tols: Vec<f64> = runs
            .iter()
            .filter(|r| r.method == Some(m))
            .map(|r| r.rtol)
            .collect();
        tols.sort_by(|a, b| b.total_cmp(a));
        tols.dedup();
        for rtol in tols {
            let rs: Vec<&Run> = runs
                .iter()
                .filter(|r| r.method == Some(m) && r.rtol == rtol)
                .collect();
            let k = rs.len() as f64;
            let mut errs: Vec<f64> = rs.iter().map(|r| r.error).collect();
            errs.sort_by(f64::total_cmp);
            let half = errs.len() / 2;
            let median_err = if errs.len() % 2 == 1 {
                errs[half]
            } else {
                0.5 * (errs[half - 1] + errs[half])
            };
            let mean_err = rs.iter().map(|r| r.error).sum::<f64>() / k;
            let max_err = rs.iter().map(|r| r.error).fold(0.0, f64::max);
            let mean_work = rs.iter().map(|r| work(r, n) as f64).sum::<f64>() / k;
            let max_work = rs.iter().map(|r| work(r, n)).max().unwrap_or(0);
            let met = rs
                .iter()
                .filter(|r| r.error <= TARGET && work(r, n) <= 30_000)
                .count();
            println!(
                "  {:8} {:>8.1e} {:>5} {:>10.2e} {:>10.2e} {:>10.2e} {:>9.0} {:>9} {:>3}/{}",
                m.name(),
                rtol,
                rs.len(),
                median_err,
                mean_err,
                max_err,
                mean_work,
                max_work,
                met,
                rs.len()
            );
        }
    }
}

/// Work of a run in RHS-equivalents: RHS evaluations plus, per Jacobian, the `n` evaluations of
/// a forward-difference one.
fn work(r: &Run, n: usize) -> usize {
    r.rhs + n * r.jac
}

/// Observed order: least-squares slope p of log error = c − p log work over the runs with
/// error in [1e-9, 1e-2] (None with fewer than three).
fn observed_order(runs: &[Run], n: usize) -> Option<f64> {
    let pts: Vec<(f64, f64)> = runs
        .iter()
        .filter(|r| r.error <= 1e-2 && r.error >= 1e-9)
        .map(|r| ((work(r, n) as f64).ln(), r.error.ln()))
        .collect();
    if pts.len() < 3 {
        return None;
    }
    let k = pts.len() as f64;
    let (mx, my) = pts
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / k, b + y / k));
    let (sxy, sxx) = pts.iter().fold((0.0, 0.0), |(a, b), (x, y)| {
        (a + (x - mx) * (y - my), b + (x - mx) * (x - mx))
    });
    Some(-sxy / sxx)
}

fn section_g(ctx: &Ctx) {
    let stem = "dry_150rpm_c0.1";
    println!(
        "\n(g) {stem}, error over the first half revolution (target {TARGET:.0e} m/s²), without \
         and with kink events; work = RHS + 12 per Jacobian"
    );
    let plain = press(stem, 0.5);
    let mut kinked = press(stem, 0.5);
    kinked.set_kink_events(true);
    let n = plain.dim();
    let half = 0.5 * crank_period(&plain);
    let times = grid(0.0, half, N_GRID);
    let t_end = plain.t_end();
    println!("  reference with kink events:");
    let reference = reference(&kinked, t_end, &times);
    let tols: Vec<f64> = (32..=48).map(|k| 10f64.powf(-k as f64 / 4.0)).collect();
    let mut summary = Vec::new();
    for method in [
        Method::Tsit54,
        Method::Dopri54,
        Method::Dop853,
        Method::Bdf,
        Method::Rodas5p,
    ] {
        for (label, m) in [("without kinks", &plain), ("with kinks", &kinked)] {
            println!("  {} {label}:", method.name());
            print_header();
            let runs = scan(ctx, method, m, t_end, &times, &reference, &tols, true);
            let order = observed_order(&runs, n);
            let best = runs
                .iter()
                .filter(|r| r.error <= TARGET)
                .min_by_key(|r| work(r, n))
                .cloned();
            summary.push((method.name(), label, order, best));
        }
    }
    println!("  summary (cheapest run with error ≤ {TARGET:.0e}, by work):");
    for (name, label, order, best) in &summary {
        let order = order.map_or("-".to_string(), |p| format!("{p:.1}"));
        match best {
            Some(r) => println!(
                "  {name:8} {label:14} order {order:>4}  {:28} error {:.2e}  work {:>7}  wall {:.4} s",
                r.label,
                r.error,
                work(r, n),
                r.wall
            ),
            None => println!("  {name:8} {label:14} order {order:>4}  none within the scan"),
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut reps = 3;
    let mut formulation = None;
    let mut at = (Method::Bdf, 1e-10);
    let mut hand_rtol = 3.2e-10;
    let mut methods = None;
    let mut kinks = None;
    let mut rtols = None;
    let mut perturb = 0;
    let mut sections = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--reps" => {
                reps = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--reps takes a number");
            }
            "--formulation" => {
                let f = it.next().expect("--formulation takes a name");
                formulation = Some(f.parse::<FormulationName>().unwrap_or_else(|e| {
                    eprintln!("{e}");
                    std::process::exit(2)
                }));
            }
            "--at" => {
                let v = it.next().expect("--at takes METHOD:RTOL");
                at = v
                    .split_once(':')
                    .and_then(|(m, r)| Some((Method::from_name(m)?, r.parse().ok()?)))
                    .unwrap_or_else(|| {
                        eprintln!("--at takes METHOD:RTOL, e.g. bdf:1e-10 (got {v})");
                        std::process::exit(2)
                    });
            }
            "--methods" => {
                let v = it.next().expect("--methods takes a,b,…");
                methods = Some(
                    v.split(',')
                        .map(|m| Method::from_name(m).expect("a method name"))
                        .collect(),
                );
            }
            "--kinks" => kinks = Some(true),
            "--no-kinks" => kinks = Some(false),
            "--perturb" => {
                perturb = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--perturb takes a number of scans");
            }
            "--rtols" => {
                let v = it.next().expect("--rtols takes r1,r2,…");
                rtols = Some(
                    v.split(',')
                        .map(|r| r.parse().expect("a tolerance"))
                        .collect(),
                );
            }
            "--hand-rtol" => {
                hand_rtol = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--hand-rtol takes a number");
            }
            s @ ("a" | "b" | "c" | "d" | "e" | "f" | "g" | "p" | "q") => {
                sections.push(s.to_string())
            }
            other => {
                eprintln!(
                    "unknown argument {other}: expected a, b, c, d, e, f, g, p, q, --reps N, \
                     --formulation F, --at METHOD:RTOL, --hand-rtol R, --methods M,.., \
                     --kinks, --no-kinks, --rtols R,.., --perturb K"
                );
                std::process::exit(2);
            }
        }
    }
    if sections.is_empty() {
        sections = ["a", "b", "c", "d", "e", "f", "g"]
            .map(String::from)
            .to_vec();
    }
    let ctx = Ctx {
        reps,
        formulation,
        methods,
        kinks,
        rtols,
        perturb,
    };
    for s in sections {
        match s.as_str() {
            "a" => section_a(&ctx),
            "b" => section_b(&ctx),
            "c" => section_c(&ctx),
            "d" => section_d(&ctx),
            "e" => section_e(&ctx),
            "f" => section_f(&ctx),
            "p" => section_p(&ctx, at, hand_rtol),
            "q" => dry_through_lash_run(&ctx),
            _ => section_g(&ctx),
        }
    }
}
