//! The library functions `lash stiffness` and `lash poincare` are built on, on problems whose
//! answers are known in closed form: a linear system, an ideal press whose only dynamics are
//! the Baumgarte modes (Lyapunov exponent −α + √(α² − β²)). (The commands themselves, through
//! the built binary: `crates/cli/tests/diagnostics.rs`.)

use crate::diagnostics::poincare::{self, Chaos, PoincareSettings};
use crate::diagnostics::stiffness::sample::{measure_limit, sample_along};
use crate::run::prepare::Prepared;
use lash_model::cases::{press_scene, PressJoint};
use lash_solver::analysis::stiffness::{Rk4ProbeOptions, StiffnessOptions};
use lash_solver::{Method, OdeSystem, SolverOptions};

/// y' = A y, A = blockdiag(−1000, [[−1, 100], [−100, −1]]) (normal), through the functions the
/// command runs: every sample has λ = −1000 (dominant) and the limit 2.7853/1000 (the real
/// root of z³ + 4z² + 12z + 24), the stiffness ratio 1000 (to the rounding of the
/// differenced Jacobian); the measurement, started from a
/// guess 20× too large, widens its bracket downwards and lands within the bound of the
/// library's own test (2 ln 10/(N κ) ≈ 3e-3 with N = 359, κ = 4.2).
#[test]
fn linear_system_through_the_command_functions() {
    struct Linear;
    impl OdeSystem for Linear {
        fn dim(&self) -> usize {
            3
        }
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = -1000.0 * y[0];
            dy[1] = -y[1] + 100.0 * y[2];
            dy[2] = -100.0 * y[1] - y[2];
        }
    }
    let mut z = -2.8f64;
    for _ in 0..50 {
        z -= (((z + 4.0) * z + 12.0) * z + 24.0) / ((3.0 * z + 8.0) * z + 12.0);
    }
    let pred = -z / 1000.0;
    let opts = SolverOptions::with_method(Method::Rodas5p);
    let times: Vec<f64> = (0..11).map(|k| 0.1 * k as f64).collect();
    let s = sample_along(
        &Linear,
        (0.0, 1.0),
        &[1.0, 1.0, 1.0],
        &opts,
        &times,
        &StiffnessOptions::default(),
        &|_, _| None,
    )
    .unwrap();
    assert_eq!(s.points.len(), 11);
    // The system has no analytic Jacobian: central differences, exact for a linear f up to
    // the rounding of f over the step δ = ε^{1/3}: ε |f| / δ ≈ 4e-8 absolute on the entries
    // of the −1000 row and 4e-9 on those of the pair, so 1e-10 relative on λ = −1000 and
    // 1e-8 on the ratio (whose denominator is Re λ = −1 of the pair).
    let tol = 1e-10;
    for p in &s.points {
        assert!(
            (p.dominant.re / -1000.0 - 1.0).abs() < tol && p.dominant.im.abs() < 1000.0 * tol,
            "{:?}",
            p.dominant
        );
        assert!((p.rk4_h_max.unwrap() / pred - 1.0).abs() < tol);
        assert!((p.stiffness_ratio.unwrap() / 1000.0 - 1.0).abs() < 1e-8);
        assert_eq!(p.n_unstable, 0);
    }
    assert!(s.median_step().unwrap() > 0.0);
    let base = SolverOptions {
        method: Method::Rk4,
        step: Some(pred),
        ..Default::default()
    };
    let m = measure_limit(
        &Linear,
        (0.0, 1.0),
        &[1.0, 1.0, 1.0],
        &base,
        20.0 * pred,
        &Rk4ProbeOptions::default(),
        &|_, _| true,
    )
    .unwrap();
    assert!(m.brackets >= 2, "the bracket had to widen: {}", m.brackets);
    let l = m.limit.unwrap();
    assert!(l.h_unstable > pred);
    assert!(l.h_stable / pred - 1.0 <= 2.0 * 10f64.ln() / (359.0 * 4.2));
}

/// The ideal press has no degree of freedom: every perturbation is a constraint violation,
/// which obeys Φ̈ = −2α Φ̇ − β² Φ exactly (docs/model.md §1), with roots −α ± √(α² − β²). With
/// α = 5, β = 4 they are −2 and −8, so the largest Lyapunov exponent is −2. The estimate over
/// the late half (revolutions 4–8 at 150 rpm, t ∈ [1.6, 3.2] s) is the slope of
/// ln‖δy(t)‖ = −2t + ln‖M(t) v‖ + O(e^{−6t}); the first term is exact and the second is
/// periodic in T (M(t) maps (Φ, Φ̇) to the state and depends on the crank angle only), so over
/// whole revolutions it cancels. What remains: the fast mode, e^{−6·1.6} ≈ 7e-5 relative at
/// the window's start, which moves the slope by at most 7e-5/1.6 s ≈ 4.3e-5 1/s, and the
/// integration error, rtol 1e-11 (atol 1e-14 m) against d0 = 1e-4 L = 1e-7 m: tolerance
/// 1e-4. A stable response: `NotChaotic`.
#[test]
fn lyapunov_exponent_of_the_baumgarte_modes() {
    let d = tempfile::tempdir().unwrap();
    let mut scene = press_scene(PressJoint::Ideal, 150.0, 0.0);
    scene.baumgarte.alpha = 5.0;
    scene.baumgarte.beta = 4.0;
    // The Baumgarte modes are Lagrange–Baumgarte's (`auto` would take the augmented
    // Lagrangian for the ideal press's loop).
    scene.formulation = lash_model::FormulationName::LagrangeBaumgarte;
    let path = d.path().join("ideal_beta4.json");
    std::fs::write(&path, scene.to_json_pretty()).unwrap();
    let p = Prepared::load_spec(path.to_str().unwrap(), None).unwrap();
    let mut opts = p.default_options();
    opts.rtol = 1e-11;
    opts.atol = p.default_atol(1e-11);
    let s = PoincareSettings {
        revolutions: 8,
        perturbation: 1e-4,
        renorm_per_rev: 10,
    };
    let r = poincare::lyapunov(&p, &opts, &s, p.period().unwrap()).unwrap();
    let l = &r.summary;
    eprintln!(
        "Baumgarte: λ = {:.6} ± {:?}, running {:.4}",
        l.exponent, l.std_error, l.exponent_running
    );
    assert!((l.exponent + 2.0).abs() < 1e-4, "{}", l.exponent);
    assert_eq!(l.chaos, Chaos::NotChaotic);
    assert_eq!(l.late_revolutions, 4);
    assert_eq!(r.estimate.log_growth.len(), 80);
    // Benettin's running estimate includes the alignment transient: −2 + O(1/t).
    assert!((l.exponent_running + 2.0).abs() < 1.0);
    // The section needs a clearance joint, which the ideal press has not.
    let e = poincare::section(&p, &opts, &s).unwrap_err();
    assert_eq!(e.kind(), crate::ErrorKind::BadInput);
}
