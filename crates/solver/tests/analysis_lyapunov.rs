//! Benettin's largest Lyapunov exponent and the stroboscopic map on systems with known
//! exponents: linear systems (closed forms), a limit cycle (zero), Lorenz (published value),
//! and a system whose event hook changes the exponent.

use lash_solver::analysis::*;
use lash_solver::*;

/// y' = A y with a constant matrix A (row-major).
struct Linear {
    n: usize,
    a: Vec<f64>,
}

impl OdeSystem for Linear {
    fn dim(&self) -> usize {
        self.n
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        for i in 0..self.n {
            dy[i] = (0..self.n).map(|j| self.a[i * self.n + j] * y[j]).sum();
        }
    }
}

fn tight(rtol: f64) -> SolverOptions {
    SolverOptions {
        rtol,
        atol: Atol::Scalar(rtol * 1e-2),
        ..Default::default()
    }
}

/// A linear system's largest exponent is its largest Re λ. From the fixed point y = 0 with
/// d0 = 1 (any d0 is exact for a linear system), renormalisation only rescales, so the sum of
/// log growths telescopes to ln‖e^{At}u‖: with A = blockdiag([[0.3, 2], [−2, 0.3]], −1) (normal)
/// and u = (1, 1, 1)/√3,
///     λ(t) = ln((2 e^{0.6t} + e^{−2t}) / 3) / (2t)  →  0.3.
/// Tolerance 1e-8: the solver's relative error (rtol 1e-10) per interval, summed over at most
/// t/Δt intervals and divided by t, is below 1e-10/Δt = 1e-9.
#[test]
fn linear_system_exponent_is_the_largest_real_part() {
    let sys = Linear {
        n: 3,
        a: vec![0.3, 2.0, 0.0, -2.0, 0.3, 0.0, 0.0, 0.0, -1.0],
    };
    let opts = LyapunovOptions {
        solver: tight(1e-10),
        renorm_interval: 0.1,
        duration: 50.0,
        d0: 1.0,
        ..Default::default()
    };
    let e = largest_lyapunov(&sys, 0.0, &[0.0; 3], &opts).unwrap();
    assert_eq!(e.running.len(), 500);
    for (k, (&t, &r)) in e.t.iter().zip(&e.running).enumerate() {
        let exact = ((2.0 * (0.6 * t).exp() + (-2.0 * t).exp()) / 3.0).ln() / (2.0 * t);
        assert!((r - exact).abs() < 1e-8, "k = {k}, t = {t}: {r} vs {exact}");
    }
    // At T = 50 the estimate is 0.3 + ln(2/3)/(2T) = 0.29595.
    assert!((e.exponent - (0.3 + (2.0f64 / 3.0).ln() / 100.0)).abs() < 1e-8);
    eprintln!("linear: λ(50) = {:.8}", e.exponent);
}

/// Damped oscillator x'' + 2ζω x' + ω² x = 0 (ζ = 0.1, ω = 2π): λ_max = −ζω. With norm weights
/// (1, 1/ω) and the perturbation (1, 0) from the fixed point, the separation is the closed-form
/// solution x = e^{−ζωt}(cos ω_d t + (ζω/ω_d) sin ω_d t), v = −(ω²/ω_d) e^{−ζωt} sin ω_d t,
/// so λ(t) = ln ‖(x, v/ω)‖ / t at every renormalisation (to 1e-8 as above). The bounded factor
/// ‖(x, v/ω)‖ e^{ζωt} lies in [√μ_min, √μ_max], the eigenvalues of [[1, a], [a, a² + b²]] with
/// a = ζ/√(1 − ζ²), b = 1/√(1 − ζ²): |λ(T) + ζω| ≤ ln μ_max / (2T).
#[test]
fn damped_oscillator_exponent_is_minus_zeta_omega() {
    let (zeta, w) = (0.1f64, 2.0 * std::f64::consts::PI);
    let sys = Linear {
        n: 2,
        a: vec![0.0, 1.0, -w * w, -2.0 * zeta * w],
    };
    let opts = LyapunovOptions {
        solver: tight(1e-10),
        renorm_interval: 0.05,
        duration: 20.0,
        d0: 1.0,
        direction: Some(vec![1.0, 0.0]),
        weights: Some(vec![1.0, 1.0 / w]),
        ..Default::default()
    };
    let e = largest_lyapunov(&sys, 0.0, &[0.0, 0.0], &opts).unwrap();
    let wd = w * (1.0 - zeta * zeta).sqrt();
    for (&t, &r) in e.t.iter().zip(&e.running) {
        let dec = (-zeta * w * t).exp();
        let (s, c) = (wd * t).sin_cos();
        let x = dec * (c + zeta * w / wd * s);
        let v = -w * w / wd * dec * s;
        let exact = x.hypot(v / w).ln() / t;
        assert!((r - exact).abs() < 1e-8, "t = {t}: {r} vs {exact}");
    }
    let a = zeta / (1.0 - zeta * zeta).sqrt();
    let b2 = 1.0 / (1.0 - zeta * zeta);
    // Trace and determinant (= b²) of [[1, a], [a, a² + b²]].
    let (p, q) = (1.0 + a * a + b2, b2);
    let mu_max = 0.5 * (p + (p * p - 4.0 * q).sqrt());
    let bound = mu_max.ln() / (2.0 * 20.0);
    assert!(
        (e.exponent + zeta * w).abs() <= bound,
        "λ = {}, −ζω = {}, bound {bound}",
        e.exponent,
        -zeta * w
    );
    assert!(e.exponent < 0.0);
    eprintln!(
        "damped oscillator: λ(20) = {:.6}, −ζω = {:.6}, bound {bound:.2e}",
        e.exponent,
        -zeta * w
    );
}

/// Van der Pol y1' = y2, y2' = μ(1 − y1²) y2 − y1.
struct Vdp(f64);
impl OdeSystem for Vdp {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = self.0 * (1.0 - y[0] * y[0]) * y[1] - y[0];
    }
}

fn speed(y: &[f64]) -> f64 {
    let mut d = [0.0; 2];
    Vdp(1.0).rhs(0.0, y, &mut d);
    d[0].hypot(d[1])
}

/// On a stable limit cycle the largest exponent is 0 (Floquet: the tangent f(y) has
/// multiplier 1, the transverse direction decays). Once the transverse part has died, the
/// separation is α·d0·f(y(t))/|f(y_s)|, so the telescoped sum T·λ(T) = ln|α| + ln(|f(y_T)| /
/// |f(y_s)|): T·λ(T) − ln(|f(y_T)|/|f(y_s)|) is the same constant for every T, and λ(T) → 0 as
/// 1/T. Van der Pol μ = 1 after a transient of 50 onto the cycle; runs of T = 100 and 400.
/// Tolerance 1e-3 on the constant: measured drift 9e-5 (the O(d0) curvature of the cycle,
/// d0 = 1e-6, and the uncorrelated solver errors of the two trajectories).
#[test]
fn limit_cycle_exponent_is_zero() {
    let solver = tight(1e-10);
    let mut so = solver.clone();
    so.output = Output::Final;
    let ys = solve(&Vdp(1.0), (0.0, 50.0), &[2.0, 0.0], &so)
        .unwrap()
        .y_final;
    let mut consts = Vec::new();
    for dur in [100.0, 400.0] {
        let opts = LyapunovOptions {
            solver: solver.clone(),
            duration: dur,
            d0: 1e-6,
            ..Default::default()
        };
        let e = largest_lyapunov(&Vdp(1.0), 50.0, &ys, &opts).unwrap();
        let c = e.exponent * dur - (speed(&e.y_final) / speed(&ys)).ln();
        eprintln!(
            "van der pol: T = {dur}: λ = {:.3e}, ln|α| = {c:.6}",
            e.exponent
        );
        consts.push(c);
        // |λ(T)| ≤ (|ln|α|| + ln(max|f| / min|f|)) / T; on this cycle both logs are below 2.
        assert!(e.exponent.abs() < 4.0 / dur, "λ = {}", e.exponent);
    }
    assert!((consts[0] - consts[1]).abs() < 1e-3, "{consts:?}");
}

/// Lorenz σ = 10, ρ = 28, β = 8/3.
struct Lorenz;
impl OdeSystem for Lorenz {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = 10.0 * (y[1] - y[0]);
        dy[1] = y[0] * (28.0 - y[2]) - y[1];
        dy[2] = y[0] * y[1] - 8.0 / 3.0 * y[2];
    }
}

/// Lorenz's largest exponent is 0.9056 (Sprott 2003, Table A.1). Over T = 500 after a
/// transient of 10, twenty initial states gave estimates with standard deviation 0.007 (mean
/// 0.904 with dopri54, 0.905 with rk4, largest deviation 0.014): the finite-time exponent
/// fluctuates along a chaotic orbit, and any rounding difference picks another orbit. ±0.05 is
/// seven standard deviations, and still far from the other exponents (0 and −14.57). Two
/// methods: adaptive dopri54 (rtol 1e-10) and fixed-step rk4 (h = 0.005).
#[test]
fn lorenz_exponent_matches_sprott() {
    for solver in [
        tight(1e-10),
        SolverOptions {
            method: Method::Rk4,
            step: Some(0.005),
            ..Default::default()
        },
    ] {
        let opts = LyapunovOptions {
            solver,
            duration: 500.0,
            transient: 10.0,
            ..Default::default()
        };
        let e = largest_lyapunov(&Lorenz, 0.0, &[1.0, 1.0, 1.0], &opts).unwrap();
        eprintln!(
            "lorenz ({}): λ = {:.4} ({} RHS evaluations)",
            opts.solver.method, e.exponent, e.rhs_evals
        );
        assert!((e.exponent - 0.9056).abs() < 0.05, "λ = {}", e.exponent);
        assert_eq!(e.running.len(), 5000);
        assert_eq!(e.t_start, 10.0);
    }
}

/// y' = a y with an event at y = 2 (rising) whose hook halves y: a sawtooth
/// y(t) = exp(a t mod ln 2) from y = 1. The flow and the hook both preserve z/y, so the
/// separation is ε·y(t) and the telescoped sum is ln(y_T / y_s): λ(T) = ln(y_T)/T, bounded by
/// ln 2 / T → 0, whereas without events λ = a. Both trajectories cross 50 times in T = 50 (a =
/// 0.7, period ln 2/a = 0.99), and no renormalisation time lies within the 1e-6 window between
/// their crossings (the nearest is 1.4e-3 away).
#[test]
fn events_and_hooks_enter_the_exponent() {
    struct Sawtooth(f64);
    impl OdeSystem for Sawtooth {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = self.0 * y[0];
        }
        fn n_events(&self) -> usize {
            1
        }
        fn event_spec(&self, _i: usize) -> EventSpec {
            EventSpec {
                direction: Direction::Rising,
                action: EventAction::Continue,
            }
        }
        fn events(&self, _t: f64, y: &[f64], g: &mut [f64]) {
            g[0] = y[0] - 2.0;
        }
        fn on_event(&self, _hit: &EventHit, y: &mut [f64]) -> EventAction {
            y[0] *= 0.5;
            EventAction::Continue
        }
    }
    let a = 0.7;
    let mut opts = LyapunovOptions {
        solver: tight(1e-12),
        duration: 50.0,
        d0: 1e-6,
        ..Default::default()
    };
    let e = largest_lyapunov(&Sawtooth(a), 0.0, &[1.0], &opts).unwrap();
    let y_t = e.y_final[0];
    let exact_y = (a * 50.0 % 2f64.ln()).exp();
    assert!((y_t - exact_y).abs() < 1e-8, "{y_t} vs {exact_y}");
    assert!(
        (e.exponent - y_t.ln() / 50.0).abs() < 1e-8,
        "λ = {}",
        e.exponent
    );
    assert!(e.exponent.abs() <= 2f64.ln() / 50.0);
    assert_eq!(e.events, 100);
    // Without events y grows like e^{at}; over T = 10 it stays below e^7 ≈ 1100, where the
    // rounding of y + d0·u is ulp(y)/d0 ≤ 2.3e-7 relative per interval (longer, d0 would drown
    // in the rounding of y: a Degenerate error).
    opts.solver.events = false;
    opts.duration = 10.0;
    let e = largest_lyapunov(&Sawtooth(a), 0.0, &[1.0], &opts).unwrap();
    assert!(
        (e.exponent - a).abs() < 1e-6,
        "no events: λ = {}",
        e.exponent
    );
    assert_eq!(e.events, 0);
}

/// A stopping event inside a segment ends the analysis with a typed error, and bad settings are
/// rejected before any integration.
#[test]
fn lyapunov_rejects_bad_input_and_stopped_runs() {
    struct Stopper;
    impl OdeSystem for Stopper {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&self, _t: f64, _y: &[f64], dy: &mut [f64]) {
            dy[0] = 1.0;
        }
        fn n_events(&self) -> usize {
            1
        }
        fn event_spec(&self, _i: usize) -> EventSpec {
            EventSpec {
                direction: Direction::Rising,
                action: EventAction::Stop,
            }
        }
        fn events(&self, _t: f64, y: &[f64], g: &mut [f64]) {
            g[0] = y[0] - 0.55;
        }
    }
    let opts = LyapunovOptions {
        duration: 1.0,
        ..Default::default()
    };
    let e = largest_lyapunov(&Stopper, 0.0, &[0.0], &opts).unwrap_err();
    assert!(
        matches!(e, AnalysisError::Degenerate { t, .. } if (t - 0.55).abs() < 1e-9),
        "{e:?}"
    );
    let bad = |o: LyapunovOptions| {
        matches!(
            largest_lyapunov(&Lorenz, 0.0, &[1.0, 1.0, 1.0], &o),
            Err(AnalysisError::InvalidInput(_))
        )
    };
    let d = LyapunovOptions::default;
    assert!(bad(LyapunovOptions {
        renorm_interval: 0.0,
        ..d()
    }));
    assert!(bad(LyapunovOptions {
        duration: 0.05,
        ..d()
    }));
    assert!(bad(LyapunovOptions { d0: -1.0, ..d() }));
    assert!(bad(LyapunovOptions {
        transient: f64::NAN,
        ..d()
    }));
    assert!(bad(LyapunovOptions {
        direction: Some(vec![0.0; 3]),
        ..d()
    }));
    assert!(bad(LyapunovOptions {
        direction: Some(vec![1.0; 2]),
        ..d()
    }));
    assert!(bad(LyapunovOptions {
        weights: Some(vec![1.0, -1.0, 1.0]),
        ..d()
    }));
}

/// Forced damped oscillator x'' + 2ζω x' + ω² x = cos Ωt (ζ = 0.1, ω = 1, Ω = 1.3). The
/// steady state x_p = A cos(Ωt − φ), A = 1/√((ω² − Ω²)² + (2ζωΩ)²), tan φ = 2ζωΩ/(ω² − Ω²),
/// sampled once per forcing period T = 2π/Ω is the fixed point (A cos φ, AΩ sin φ) of the
/// stroboscopic map. Started on it, every sample equals it (to the solver's 1e-9); started from
/// rest and sampled after 40 periods, the transient has decayed by e^{−ζω·40T} ≈ 4e-9.
#[test]
fn stroboscopic_map_of_a_forced_oscillator() {
    struct Forced;
    const Z: f64 = 0.1;
    const W: f64 = 1.3;
    impl OdeSystem for Forced {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = y[1];
            dy[1] = (W * t).cos() - 2.0 * Z * y[1] - y[0];
        }
    }
    let amp = 1.0 / ((1.0 - W * W).powi(2) + (2.0 * Z * W).powi(2)).sqrt();
    let phi = (2.0 * Z * W).atan2(1.0 - W * W);
    let fixed = [amp * phi.cos(), amp * W * phi.sin()];
    let period = 2.0 * std::f64::consts::PI / W;
    let solver = tight(1e-11);
    let s = stroboscopic_map(&Forced, 0.0, &fixed, period, 0, 20, &solver, |_, y| y[0]).unwrap();
    assert_eq!(s.t.len(), 20);
    for j in 0..20 {
        assert!((s.t[j] - j as f64 * period).abs() < 1e-12);
        assert!(
            (s.values[j] - fixed[0]).abs() < 1e-9,
            "j = {j}: {}",
            s.values[j]
        );
        assert!((s.states[2 * j + 1] - fixed[1]).abs() < 1e-9);
    }
    let s = stroboscopic_map(
        &Forced,
        0.0,
        &[0.0, 0.0],
        period,
        40,
        10,
        &solver,
        |_, y| y[0],
    )
    .unwrap();
    assert!((s.t[0] - 40.0 * period).abs() < 1e-9);
    for v in &s.values {
        assert!((v - fixed[0]).abs() < 1e-7, "{v} vs {}", fixed[0]);
    }
    assert!(matches!(
        stroboscopic_map(&Forced, 0.0, &fixed, 0.0, 0, 5, &solver, |_, y| y[0]),
        Err(AnalysisError::InvalidInput(_))
    ));
    assert!(matches!(
        stroboscopic_map(&Forced, 0.0, &fixed, period, 0, 3, &solver, |_, _| f64::NAN),
        Err(AnalysisError::NonFinite { .. })
    ));
}
