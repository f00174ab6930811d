//! Why Rodas5P needs more steps than BDF on the lubricated press: measurements.
//!
//! ```text
//! cargo run --release -p lash-benches --example rodas_order -- [pr] [jac] [eig] [hist]
//!     [restart] [history] [order]            (none: all; `order` is the slow one)
//! jac    the mechanism Jacobian against Richardson-extrapolated central differences of f
//! order  error vs accepted steps of Rodas5P (and BDF) on lubricated 150 rpm c 0.1 over the
//!        second of two revolutions, with (i) the mechanism Jacobian, (ii) the accurate
//!        Jacobian, (iii) (ii) made autonomous (t a state, ∂f/∂t in the Jacobian), (iv) (i)
//!        without event location (event_samples 0); errors on the 2001-point grid (dense output)
//!        and at the step ends; effective order p = −Δlog(error)/Δlog(steps)
//! hist   step sizes and rejected steps of Rodas5P against the crank angle, with ε
//! eig    eigenvalues of ∂f/∂y along the second revolution against the step sizes taken
//! pr     Prothero–Robinson y' = λ(y − sin t) + cos t, fixed steps: error in y and in y',
//!        as given and in autonomous form (t a state, exact ∂f/∂t)
//! restart  the second revolution alone, started from the reference state at t = T
//! history  the error of the through run per tenth of a revolution
//! ```
//! Error = |ẍ_slider − ẍ_ref|, ẍ_slider = `Mechanism::outputs(t, y).slider_a`; the reference
//! is Rodas5P at rtol 1e-13 (atol 1e-16), evaluated at every time any run needs.

use lash_benches::{crank_period, grid, options, press};
use lash_model::Mechanism;
use lash_solver::analysis::stiffness::eigenvalues;
use lash_solver::{
    make_stepper, solve, EventAction, EventHit, EventSpec, Method, OdeSystem, Output, SolverOptions,
};

/// Richardson-extrapolated central differences of the full right-hand side:
/// D(h) = (f(y + h e_j) − f(y − h e_j)) / 2h,  J_j = (4 D(h/2) − D(h)) / 3  (error O(h⁴)).
/// Steps: 2e-7 (positions and angles; |e| ≈ 5e-5 m, c = 1e-4 m in the second revolution),
/// 1e-4 (velocities; f is at most quadratic in them), 1e-5 s (time, when augmented).
/// With `augment`, the state is (y, t) and f = (f(t, y), 1): an autonomous system whose
/// Jacobian carries ∂f/∂t, so Rodas5P needs no difference in t.
struct Accurate<'a> {
    m: &'a Mechanism,
    augment: bool,
    scale: f64,
}

impl Accurate<'_> {
    fn n(&self) -> usize {
        self.m.dim()
    }
    fn f(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        let n = self.n();
        self.m.rhs(t, &y[..n], &mut dy[..n]);
        if self.augment {
            dy[n] = 1.0;
        }
    }
    fn step(&self, j: usize) -> f64 {
        let n = self.n();
        let s = if j == n {
            1e-5
        } else if j < n / 2 {
            2e-7
        } else {
            1e-4
        };
        s * self.scale
    }
}

impl OdeSystem for Accurate<'_> {
    fn dim(&self) -> usize {
        self.n() + usize::from(self.augment)
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        let t = if self.augment { y[self.n()] } else { t };
        self.f(t, y, dy)
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn is_autonomous(&self) -> bool {
        self.augment
    }
    fn jacobian(&self, t: f64, y: &[f64], mut jac: faer::MatMut<'_, f64>) {
        let d = self.dim();
        let t = if self.augment { y[self.n()] } else { t };
        let mut yp = y.to_vec();
        let (mut fp, mut fm) = (vec![0.0; d], vec![0.0; d]);
        let mut diff = |j: usize, h: f64, out: &mut [f64]| {
            let mut at = |sign: f64, f: &mut [f64]| {
                yp[j] = y[j] + sign * h;
                let tt = if self.augment { yp[self.n()] } else { t };
                self.f(tt, &yp, f);
                yp[j] = y[j];
            };
            at(1.0, &mut fp);
            at(-1.0, &mut fm);
            for i in 0..d {
                out[i] = (fp[i] - fm[i]) / (2.0 * h);
            }
        };
        let (mut d1, mut d2) = (vec![0.0; d], vec![0.0; d]);
        for j in 0..d {
            let h = self.step(j);
            diff(j, h, &mut d1);
            diff(j, 0.5 * h, &mut d2);
            for i in 0..d {
                jac[(i, j)] = (4.0 * d2[i] - d1[i]) / 3.0;
            }
        }
    }
    fn n_events(&self) -> usize {
        self.m.n_events()
    }
    fn event_spec(&self, i: usize) -> EventSpec {
        self.m.event_spec(i)
    }
    fn events(&self, t: f64, y: &[f64], g: &mut [f64]) {
        self.m.events(t, &y[..self.n()], g)
    }
    fn on_event(&self, hit: &EventHit, y: &mut [f64]) -> EventAction {
        let n = self.n();
        self.m.on_event(hit, &mut y[..n])
    }
}

fn jac_of(sys: &dyn OdeSystem, t: f64, y: &[f64]) -> faer::Mat<f64> {
    let d = sys.dim();
    let mut j = faer::Mat::zeros(d, d);
    sys.jacobian(t, y, j.as_mut());
    j
}

/// max over rows i of max_j |A_ij − B_ij| / max_j |B_ij| (lower block only).
fn row_rel_diff(a: &faer::Mat<f64>, b: &faer::Mat<f64>, n: usize) -> f64 {
    let mut worst = 0.0f64;
    for i in n / 2..n {
        let scale = (0..n).map(|j| b[(i, j)].abs()).fold(0.0, f64::max);
        let d = (0..n)
            .map(|j| (a[(i, j)] - b[(i, j)]).abs())
            .fold(0.0, f64::max);
        worst = worst.max(d / scale);
    }
    worst
}

/// States of the second revolution: a Rodas5P run at rtol 1e-8 with every step.
fn second_revolution_states(m: &Mechanism) -> (Vec<f64>, Vec<Vec<f64>>) {
    let per = crank_period(m);
    let o = options(Method::Rodas5p, 1e-8, 1e-11, 0.0, Output::Steps);
    let sol = solve(m, (m.t_start(), m.t_end()), &m.initial_state(), &o).expect("runs");
    let mut ts = Vec::new();
    let mut ys = Vec::new();
    for k in 0..sol.len() {
        if sol.t[k] >= per {
            ts.push(sol.t[k]);
            ys.push(sol.state(k).to_vec());
        }
    }
    (ts, ys)
}

fn section_jac(m: &Mechanism) {
    println!(
        "\n[jac] mechanism Jacobian vs Richardson differences of f (lower block, row-relative)"
    );
    let (ts, ys) = second_revolution_states(m);
    let n = m.dim();
    let acc = Accurate {
        m,
        augment: false,
        scale: 1.0,
    };
    let acc2 = Accurate {
        m,
        augment: false,
        scale: 0.5,
    };
    let mut worst_mech = 0.0f64;
    let mut worst_self = 0.0f64;
    let stride = (ts.len() / 12).max(1);
    for k in (0..ts.len()).step_by(stride) {
        let (t, y) = (ts[k], &ys[k]);
        let jm = jac_of(m, t, y);
        let ja = jac_of(&acc, t, y);
        let jb = jac_of(&acc2, t, y);
        let dm = row_rel_diff(&jm, &ja, n);
        let ds = row_rel_diff(&jb, &ja, n);
        let eps = m.outputs(t, y).clearance[0].eps;
        println!(
            "  t = {t:.4} s, ε = {eps:.3}: |J_mech − J_rich| = {dm:.1e}, |J_rich(h/2) − J_rich(h)| = {ds:.1e}"
        );
        worst_mech = worst_mech.max(dm);
        worst_self = worst_self.max(ds);
    }
    println!("  worst: mechanism {worst_mech:.1e}, Richardson self-consistency {worst_self:.1e}");
}

/// One run's record: accepted steps, rejected, and its sampled output.
struct Rec {
    label: String,
    rtol: f64,
    steps: usize,
    rejected: usize,
    /// ẍ_slider on the grid.
    grid_a: Vec<f64>,
    /// Step ends in the second revolution and ẍ there.
    ends: Vec<(f64, f64)>,
}

fn slider_a_t(m: &Mechanism, t: f64, y: &[f64]) -> f64 {
    m.outputs(t, &y[..m.dim()]).slider_a.expect("slider")
}

fn run_rec(
    m: &Mechanism,
    sys: &dyn OdeSystem,
    y0: &[f64],
    label: &str,
    o: &SolverOptions,
    times: &[f64],
    t_from: f64,
) -> Option<Rec> {
    let (t0, t1) = (m.t_start(), m.t_end());
    let mut og = o.clone();
    og.output = Output::Times(times.to_vec());
    let sg = solve(sys, (t0, t1), y0, &og).ok()?;
    let mut os = o.clone();
    os.output = Output::Steps;
    let ss = solve(sys, (t0, t1), y0, &os).ok()?;
    let grid_a = (0..sg.len())
        .map(|k| slider_a_t(m, sg.t[k], sg.state(k)))
        .collect();
    let mut ends: Vec<(f64, f64)> = (0..ss.len())
        .filter(|&k| ss.t[k] > t_from && ss.t[k] < t1)
        .map(|k| (ss.t[k], slider_a_t(m, ss.t[k], ss.state(k))))
        .collect();
    ends.dedup_by(|a, b| a.0 == b.0);
    Some(Rec {
        label: label.to_string(),
        rtol: o.rtol,
        steps: ss.stats.accepted,
        rejected: ss.stats.rejected_error + ss.stats.rejected_newton,
        grid_a,
        ends,
    })
}

fn section_order(m: &Mechanism) {
    println!("\n[order] lubricated 150 rpm c 0.1, error over the second revolution");
    let per = crank_period(m);
    let times = grid(per, 2.0 * per, 2001);
    let y0 = m.initial_state();
    let mut y0a = y0.clone();
    y0a.push(m.t_start());
    let acc = Accurate {
        m,
        augment: false,
        scale: 1.0,
    };
    let aut = Accurate {
        m,
        augment: true,
        scale: 1.0,
    };
    let tols: Vec<f64> = (0..=14)
        .map(|k| 10f64.powf(-3.0 - 0.5 * k as f64))
        .collect();
    let mut recs: Vec<Rec> = Vec::new();
    for &rtol in &tols {
        let o = options(Method::Rodas5p, rtol, rtol * 1e-3, 0.0, Output::Final);
        let mut o_noev = o.clone();
        o_noev.events = false;
        let ob = options(Method::Bdf, rtol, rtol * 1e-3, 0.0, Output::Final);
        for (label, sys, y, oo) in [
            ("rodas5p mech", m as &dyn OdeSystem, &y0, &o),
            ("rodas5p rich", &acc as &dyn OdeSystem, &y0, &o),
            ("rodas5p rich+t", &aut as &dyn OdeSystem, &y0a, &o),
            ("rodas5p mech noev", m as &dyn OdeSystem, &y0, &o_noev),
            ("bdf", m as &dyn OdeSystem, &y0, &ob),
        ] {
            if rtol < 1e-10 && label != "rodas5p mech" && label != "bdf" {
                continue;
            }
            if let Some(r) = run_rec(m, sys, y, label, oo, &times, per) {
                recs.push(r);
            }
        }
    }
    // One reference run at every time needed.
    let mut all: Vec<f64> = times.clone();
    for r in &recs {
        all.extend(r.ends.iter().map(|e| e.0));
    }
    all.sort_by(f64::total_cmp);
    all.dedup();
    let oref = options(
        Method::Rodas5p,
        1e-13,
        1e-16,
        0.0,
        Output::Times(all.clone()),
    );
    let sref = solve(m, (m.t_start(), m.t_end()), &y0, &oref).expect("reference");
    let aref: Vec<f64> = (0..sref.len())
        .map(|k| slider_a_t(m, sref.t[k], sref.state(k)))
        .collect();
    let at = |t: f64| {
        let i = all.partition_point(|&x| x < t);
        aref[i]
    };
    let grid_ref: Vec<f64> = times.iter().map(|&t| at(t)).collect();
    println!(
        "  {:20} {:>8} {:>7} {:>7} {:>10} {:>10}",
        "run", "rtol", "steps", "rej %", "err grid", "err ends"
    );
    for label in [
        "rodas5p mech",
        "rodas5p rich",
        "rodas5p rich+t",
        "rodas5p mech noev",
        "bdf",
    ] {
        let mut pts = Vec::new();
        for r in recs.iter().filter(|r| r.label == label) {
            let eg = r
                .grid_a
                .iter()
                .zip(&grid_ref)
                .fold(0.0f64, |w, (a, b)| w.max((a - b).abs()));
            let ee = r
                .ends
                .iter()
                .fold(0.0f64, |w, &(t, a)| w.max((a - at(t)).abs()));
            println!(
                "  {:20} {:8.1e} {:7} {:7.1} {:10.2e} {:10.2e}",
                r.label,
                r.rtol,
                r.steps,
                100.0 * r.rejected as f64 / (r.steps + r.rejected) as f64,
                eg,
                ee
            );
            pts.push((r.steps as f64, eg, ee));
        }
        // Effective order between consecutive points and over the whole range.
        let slope = |a: (f64, f64), b: (f64, f64)| -(b.1 / a.1).ln() / (b.0 / a.0).ln();
        let mut line = String::new();
        for w in pts.windows(2) {
            line += &format!(
                " {:.1}/{:.1}",
                slope((w[0].0, w[0].1), (w[1].0, w[1].1)),
                slope((w[0].0, w[0].2), (w[1].0, w[1].2))
            );
        }
        println!("  {label}: local orders (grid/ends):{line}");
    }
}

fn section_hist(m: &Mechanism, rtol: f64) {
    println!(
        "\n[hist] rodas5p rtol {rtol:.0e}: step sizes and rejections vs crank angle (2nd rev)"
    );
    let per = crank_period(m);
    let o = options(Method::Rodas5p, rtol, rtol * 1e-3, 0.0, Output::Final);
    let y0 = m.initial_state();
    let problem = lash_solver::Problem::new(m, &o).expect("options");
    let mut st = make_stepper(&problem, m.t_start(), &y0).expect("stepper");
    let nb = 12;
    let mut acc = vec![0usize; nb];
    let mut rej = vec![0usize; nb];
    let mut hsum = vec![0.0f64; nb];
    let mut epsmax = vec![0.0f64; nb];
    let mut hmin = vec![f64::INFINITY; nb];
    let mut last_rej = 0;
    while st.t() < m.t_end() {
        let t0 = st.t();
        st.step(m.t_end()).expect("step");
        let s = st.stats();
        let r = s.rejected_error + s.rejected_newton;
        if t0 >= per {
            let b = (((t0 - per) / per) * nb as f64) as usize % nb;
            acc[b] += 1;
            rej[b] += r - last_rej;
            let h = st.t() - t0;
            hsum[b] += h;
            hmin[b] = hmin[b].min(h);
            let eps = m.outputs(st.t(), st.y()).clearance[0].eps;
            epsmax[b] = epsmax[b].max(eps);
        }
        last_rej = r;
    }
    println!("  crank °   steps  rejected  mean h     min h      max ε");
    for b in 0..nb {
        println!(
            "  {:3}-{:3} {:6} {:8} {:10.2e} {:10.2e} {:8.3}",
            b * 30,
            (b + 1) * 30,
            acc[b],
            rej[b],
            hsum[b] / acc[b].max(1) as f64,
            hmin[b],
            epsmax[b]
        );
    }
}

fn section_eig(m: &Mechanism) {
    println!("\n[eig] eigenvalues of ∂f/∂y (mechanism Jacobian) along the 2nd revolution, rodas5p 1e-8 steps");
    let (ts, ys) = second_revolution_states(m);
    let stride = (ts.len() / 12).max(1);
    for k in (1..ts.len()).step_by(stride) {
        let j = jac_of(m, ts[k], &ys[k]);
        let ev = eigenvalues(j.as_ref()).expect("eig");
        let h = ts[k] - ts[k - 1];
        let top: Vec<String> = ev
            .iter()
            .take(4)
            .map(|e| format!("{:.2e}{:+.2e}i", e.re, e.im))
            .collect();
        let eps = m.outputs(ts[k], &ys[k]).clearance[0].eps;
        println!(
            "  t = {:.4} ε = {eps:.3} h = {h:.2e}: λ = {}   h|λ_max| = {:.1}",
            ts[k],
            top.join(", "),
            h * ev[0].modulus()
        );
    }
}

/// y' = λ (y − sin t) + cos t, y(0) = 0: solution sin t.
struct Pr(f64);
impl OdeSystem for Pr {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = self.0 * (y[0] - t.sin()) + t.cos();
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], mut jac: faer::MatMut<'_, f64>) {
        jac[(0, 0)] = self.0;
    }
}

/// The same problem made autonomous: (y, t)' = (λ(y − sin t) + cos t, 1), exact Jacobian
/// (∂f/∂t in its second column), so Rodas5P takes no difference in t.
struct PrAut(f64);
impl OdeSystem for PrAut {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = self.0 * (y[0] - y[1].sin()) + y[1].cos();
        dy[1] = 1.0;
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn is_autonomous(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, y: &[f64], mut jac: faer::MatMut<'_, f64>) {
        jac[(0, 0)] = self.0;
        jac[(0, 1)] = -self.0 * y[1].cos() - y[1].sin();
        jac[(1, 0)] = 0.0;
        jac[(1, 1)] = 0.0;
    }
}

fn section_pr() {
    for aut in [false, true] {
        println!("\n[pr] Prothero–Robinson y' = λ(y − sin t) + cos t on [0, 1], fixed steps N, autonomous form: {aut}");
        for lambda in [-1.0, -1e3, -1e6] {
            let sys1 = Pr(lambda);
            let sys2 = PrAut(lambda);
            let sys: &dyn OdeSystem = if aut { &sys2 } else { &sys1 };
            let d = sys.dim();
            let mut prev: Option<(f64, f64, f64, f64)> = None;
            println!("  λ = {lambda:.0e}:   N   err y(1)   order   err y'(1)  order  err y mid (dense)  order");
            for nst in [10usize, 20, 40, 80, 160, 320, 640] {
                let h = 1.0 / nst as f64;
                let mut o = SolverOptions::with_method(Method::Rodas5p);
                o.adaptive = false;
                o.h0 = Some(h);
                let mids: Vec<f64> = (0..nst).map(|k| (k as f64 + 0.5) * h).collect();
                let mut times = mids.clone();
                times.push(1.0);
                o.output = Output::Times(times);
                let s = solve(sys, (0.0, 1.0), &[0.0, 0.0][..d], &o).expect("pr");
                let yend = s.y[nst * d];
                let ey = (yend - 1f64.sin()).abs();
                let mut fd = [0.0];
                sys1.rhs(1.0, &[yend], &mut fd);
                let ed = (fd[0] - 1f64.cos()).abs();
                let em = (0..nst)
                    .map(|k| (s.y[k * d] - mids[k].sin()).abs())
                    .fold(0.0, f64::max);
                let ord = |a: f64, b: f64| (a / b).log2();
                match prev {
                    Some((_, py, pd, pm)) => println!(
                        "  {nst:17} {ey:10.2e} {:6.2} {ed:10.2e} {:6.2} {em:10.2e} {:6.2}",
                        ord(py, ey),
                        ord(pd, ed),
                        ord(pm, em)
                    ),
                    None => println!(
                        "  {nst:17} {ey:10.2e} {:>6} {ed:10.2e} {:>6} {em:10.2e}",
                        "", ""
                    ),
                }
                prev = Some((h, ey, ed, em));
            }
        }
    }
}

/// Error over the second revolution of a run restarted at t = T from the reference state:
/// isolates the discretization error of the revolution from the error carried over from the
/// first (which starts at the singular centred journal, e = 0).
fn section_restart(m: &Mechanism) {
    println!("\n[restart] second revolution only, started from the reference state at t = T");
    let per = crank_period(m);
    let times = grid(per, 2.0 * per, 2001);
    let y0 = m.initial_state();
    let oref = options(
        Method::Rodas5p,
        1e-13,
        1e-16,
        0.0,
        Output::Times(times.clone()),
    );
    let sref = solve(m, (m.t_start(), 2.0 * per), &y0, &oref).expect("reference");
    let yt = sref.state(0).to_vec();
    let aref: Vec<f64> = (0..sref.len())
        .map(|k| slider_a_t(m, sref.t[k], sref.state(k)))
        .collect();
    // The reference restarted at T, to 1e-13 (its distance to the through-run reference).
    let sr2 = solve(m, (per, 2.0 * per), &yt, &oref).expect("reference");
    let a2: Vec<f64> = (0..sr2.len())
        .map(|k| slider_a_t(m, sr2.t[k], sr2.state(k)))
        .collect();
    let d = a2
        .iter()
        .zip(&aref)
        .fold(0.0f64, |w, (a, b)| w.max((a - b).abs()));
    println!("  restarted reference vs through reference: {d:.1e} m/s²");
    for method in [Method::Rodas5p, Method::Bdf] {
        let mut pts: Vec<(f64, f64)> = Vec::new();
        for k in 0..=14 {
            let rtol = 10f64.powf(-3.0 - 0.5 * k as f64);
            let o = options(method, rtol, rtol * 1e-3, 0.0, Output::Times(times.clone()));
            let Ok(s) = solve(m, (per, 2.0 * per), &yt, &o) else {
                continue;
            };
            let e = (0..s.len())
                .map(|k| (slider_a_t(m, s.t[k], s.state(k)) - a2[k]).abs())
                .fold(0.0, f64::max);
            let n = s.stats.accepted as f64;
            let ord = pts.last().map_or(String::new(), |p| {
                format!("{:.1}", -(e / p.1).ln() / (n / p.0).ln())
            });
            println!(
                "  {:8} rtol {rtol:8.1e} steps {:6} rej {:5} err {e:9.2e}  local order {ord}",
                method.name(),
                s.stats.accepted,
                s.stats.rejected_error + s.stats.rejected_newton
            );
            pts.push((n, e));
        }
    }
}

/// Time history of the error of the through run (grid of the two revolutions).
fn section_history(m: &Mechanism) {
    println!("\n[history] |a − a_ref| over both revolutions, rodas5p and bdf, max per tenth of a revolution");
    let per = crank_period(m);
    let times = grid(1e-4, 2.0 * per, 4001);
    let y0 = m.initial_state();
    let run = |method: Method, rtol: f64| {
        let o = options(method, rtol, rtol * 1e-3, 0.0, Output::Times(times.clone()));
        let s = solve(m, (m.t_start(), 2.0 * per), &y0, &o).expect("runs");
        (0..s.len())
            .map(|k| slider_a_t(m, s.t[k], s.state(k)))
            .collect::<Vec<f64>>()
    };
    let r = run(Method::Rodas5p, 1e-13);
    for (method, rtol) in [
        (Method::Rodas5p, 1e-6),
        (Method::Rodas5p, 1e-8),
        (Method::Bdf, 1e-8),
    ] {
        let a = run(method, rtol);
        let mut line = String::new();
        for b in 0..20 {
            let lo = b * 200;
            let hi = ((b + 1) * 200).min(a.len());
            let e = (lo..hi).map(|k| (a[k] - r[k]).abs()).fold(0.0, f64::max);
            line += &format!(" {e:.0e}");
        }
        println!("  {:8} {rtol:.0e}:{line}", method.name());
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let want = |s: &str| args.is_empty() || args.iter().any(|a| a == s);
    let m = press("lubricated_150rpm_c0.1", 2.0);
    if want("pr") {
        section_pr();
    }
    if want("jac") {
        section_jac(&m);
    }
    if want("eig") {
        section_eig(&m);
    }
    if want("hist") {
        for rtol in [1e-6, 1e-9] {
            section_hist(&m, rtol);
        }
    }
    if want("restart") {
        section_restart(&m);
    }
    if want("history") {
        section_history(&m);
    }
    if want("order") {
        section_order(&m);
    }
}
