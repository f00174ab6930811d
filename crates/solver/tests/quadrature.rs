//! The quadrature variables of a system ([`OdeSystem::quadrature`]), integrated by each
//! method with its own formula at its own stages ([`Integrator::step_quadrature`]).
//!
//! ```text
//! damped oscillator  x' = v,  v' = −ω² x − c v,  c = 2ζω,  E = ½ v² + ½ ω² x²
//! quadratures        Q₀' = c v²   (the damper's dissipation),  Q₁' = x,  Q₂' = v
//!                    (three for two states: diffsol sizes BDF's output table by them)
//! closed forms       Q₀(T) = E(0) − E(T)            (dE/dt = −c v²)
//!                    Q₁(T) = (v(0) − v(T) + c (x(0) − x(T))) / ω²   (∫ x = −∫ (v' + c v)/ω²)
//!                    Q₂(T) = x(T) − x(0)
//! with the exact x(T), v(T) of the underdamped oscillator.
//! ```
//! The quadrature is out of the error norm: with or without it every method takes the same
//! steps to the same states, bit for bit.

mod common;
use common::*;
use lash_solver::*;

const W: f64 = 2.0;
const ZETA: f64 = 0.1;
const T_END: f64 = 3.0;

/// The damped oscillator, with its two quadratures when `quad`.
struct Damped {
    quad: bool,
}

impl Damped {
    fn c() -> f64 {
        2.0 * ZETA * W
    }
    /// Exact (x, v) at t from x(0) = 1, v(0) = 0.
    fn exact(t: f64) -> [f64; 2] {
        let wd = W * (1.0 - ZETA * ZETA).sqrt();
        let s = ZETA * W;
        let (a, b) = (1.0, s / wd);
        let e = (-s * t).exp();
        let (co, si) = ((wd * t).cos(), (wd * t).sin());
        let x = e * (a * co + b * si);
        let v = e * (-s * (a * co + b * si) + (-a * wd * si + b * wd * co));
        [x, v]
    }
    fn closed_form() -> [f64; 3] {
        let [x, v] = Self::exact(T_END);
        let energy = |x: f64, v: f64| 0.5 * v * v + 0.5 * W * W * x * x;
        [
            energy(1.0, 0.0) - energy(x, v),
            (0.0 - v + Self::c() * (1.0 - x)) / (W * W),
            x - 1.0,
        ]
    }
}

impl OdeSystem for Damped {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = -W * W * y[0] - Self::c() * y[1];
    }
    fn is_autonomous(&self) -> bool {
        true
    }
    fn n_quadratures(&self) -> usize {
        if self.quad {
            3
        } else {
            0
        }
    }
    fn quadrature(&self, _t: f64, y: &[f64], q: &mut [f64]) {
        q[0] = Self::c() * y[1] * y[1];
        q[1] = y[0];
        q[2] = y[1];
    }
}

/// Every step's end (t, y), the counters, the summed quadrature and its summed estimate, and
/// how many steps gave an estimate.
struct Run {
    ts: Vec<f64>,
    ys: Vec<f64>,
    stats: Stats,
    q: [f64; 3],
    est: [f64; 3],
    with_estimate: usize,
}

fn run(quad: bool, opts: &SolverOptions) -> Run {
    let sys = Damped { quad };
    let problem = Problem::new(&sys, opts).unwrap();
    let mut it = problem.integrator(0.0, T_END, &[1.0, 0.0]).unwrap();
    let mut r = Run {
        ts: vec![],
        ys: vec![],
        stats: Stats::default(),
        q: [0.0; 3],
        est: [0.0; 3],
        with_estimate: 0,
    };
    let (mut v, mut e) = ([0.0; 3], [0.0; 3]);
    loop {
        let out = it.step().unwrap();
        r.ts.push(it.t());
        r.ys.extend_from_slice(it.y());
        let got = it.step_quadrature(&mut v, &mut e);
        if quad {
            assert_ne!(got, StepQuadrature::Unavailable, "{}", opts.method);
            for c in 0..3 {
                r.q[c] += v[c];
            }
            if got == StepQuadrature::ValueAndEstimate {
                r.with_estimate += 1;
                for c in 0..3 {
                    r.est[c] += e[c];
                }
            }
        } else {
            assert_eq!(got, StepQuadrature::Unavailable);
        }
        if matches!(out, StepOutcome::StopTime { .. }) {
            break;
        }
    }
    r.stats = it.stats();
    r
}

fn q_error(quad: &[f64; 3]) -> f64 {
    let exact = Damped::closed_form();
    (0..3)
        .map(|c| (quad[c] - exact[c]).abs())
        .fold(0.0, f64::max)
}

/// The quadrature's global error with N fixed steps converges at the method's order p:
/// the slope lies in [p − 0.25, p + 0.6] (it approaches p from above over these ranges,
/// where the errors lie between about 1e-4 and 1e-12; measured slopes: rk4 4.0, bs32 3.0,
/// dopri54 5.1, tsit54 5.4, dop853 8.4, rodas5p 5.1).
fn assert_order(method: Method, p: f64, ns: &[usize]) {
    let hs: Vec<f64> = ns.iter().map(|&n| T_END / n as f64).collect();
    let errs: Vec<f64> = hs
        .iter()
        .map(|&h| q_error(&run(true, &fixed(method, h)).q))
        .collect();
    let order = slope(&hs, &errs);
    eprintln!("{method}: quadrature slope {order:.2}, errors {errs:?}");
    assert!(
        order >= p - 0.25 && order <= p + 0.6,
        "{method}: quadrature order {order:.3}, nominal {p} (errors {errs:?})"
    );
    assert!(errs.iter().all(|&e| e > 1e-13), "{method}: {errs:?}");
}

#[test]
fn rk4_quadrature_order_4() {
    assert_order(Method::Rk4, 4.0, &[40, 80, 160]);
}

#[test]
fn bs32_quadrature_order_3() {
    assert_order(Method::Bs32, 3.0, &[80, 160, 320]);
}

#[test]
fn dopri54_quadrature_order_5() {
    assert_order(Method::Dopri54, 5.0, &[80, 160, 320]);
}

#[test]
fn tsit54_quadrature_order_5() {
    assert_order(Method::Tsit54, 5.0, &[40, 80, 160]);
}

#[test]
fn dop853_quadrature_order_8() {
    assert_order(Method::Dop853, 8.0, &[8, 12, 16]);
}

#[test]
fn rodas5p_quadrature_order_5() {
    assert_order(Method::Rodas5p, 5.0, &[10, 20, 40]);
}

/// diffsol's methods run adaptively only: the quadrature's error follows the tolerance
/// (global error ∝ rtol for these error-per-step controllers) and stays within 10³ rtol.
#[test]
fn diffsol_quadrature_follows_the_tolerance() {
    for method in [Method::Bdf, Method::Trbdf2, Method::Esdirk34] {
        for rtol in [1e-6, 1e-9] {
            let opts = SolverOptions {
                method,
                rtol,
                atol: Atol::Scalar(rtol),
                ..Default::default()
            };
            let r = run(true, &opts);
            let err = q_error(&r.q);
            eprintln!("{method} rtol {rtol:e}: quadrature error {err:e}");
            assert!(err < 1e3 * rtol, "{method} rtol {rtol:e}: {err:e}");
        }
    }
}

/// The quadrature is out of the error norm: every method takes the same steps to the same
/// states with and without it, bit for bit, with the same counters.
#[test]
fn quadrature_leaves_the_steps_unchanged() {
    for method in Method::ALL {
        let opts = SolverOptions {
            method,
            rtol: 1e-7,
            atol: Atol::Scalar(1e-9),
            step: method.is_fixed_step().then_some(1e-3),
            ..Default::default()
        };
        let (a, b) = (run(false, &opts), run(true, &opts));
        assert_eq!(a.ts, b.ts, "{method}");
        assert_eq!(a.ys, b.ys, "{method}");
        assert_eq!(a.stats, b.stats, "{method}");
        let expect_estimate = !method.is_diffsol();
        assert_eq!(b.with_estimate > 0, expect_estimate, "{method}");
        if expect_estimate {
            // Summed over the steps, the local estimates (of the lower-order formula: local
            // extrapolation) bound the propagated formula's global error on this non-stiff
            // problem.
            let err = q_error(&b.q);
            let est = b.est.iter().fold(0.0_f64, |a, e| a.max(*e));
            eprintln!("{method}: error {err:e}, summed estimate {est:e}");
            assert!(
                est >= err,
                "{method}: estimate {est:e} below the error {err:e}"
            );
        }
    }
}
