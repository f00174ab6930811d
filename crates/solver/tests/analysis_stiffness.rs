//! Stiffness diagnostics on problems whose eigenvalues are known in closed form.

use faer::{Mat, MatMut};
use lash_solver::analysis::stiffness::IMPLICIT_FACTOR;
use lash_solver::analysis::*;
use lash_solver::*;

/// RK4's real-axis limit: the negative root of z³ + 4z² + 12z + 24 = 0 (R(z) = 1 with z ≠ 0),
/// by Newton's method — independent of the ray polynomial the library bisects.
fn real_axis_root() -> f64 {
    let mut z = -2.8f64;
    for _ in 0..50 {
        let p = ((z + 4.0) * z + 12.0) * z + 24.0;
        let dp = (3.0 * z + 8.0) * z + 12.0;
        z -= p / dp;
    }
    -z
}

/// y' = A y with a constant matrix A (row-major), analytic Jacobian optional.
struct Linear {
    n: usize,
    a: Vec<f64>,
    analytic: bool,
}

impl Linear {
    fn new(n: usize, a: Vec<f64>) -> Self {
        assert_eq!(a.len(), n * n);
        Linear {
            n,
            a,
            analytic: true,
        }
    }
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
    fn has_jacobian(&self) -> bool {
        self.analytic
    }
    fn jacobian(&self, _t: f64, _y: &[f64], mut jac: MatMut<'_, f64>) {
        for i in 0..self.n {
            for j in 0..self.n {
                jac[(i, j)] = self.a[i * self.n + j];
            }
        }
    }
}

/// blockdiag(−1000, [[−1, 100], [−100, −1]]): eigenvalues −1000 and −1 ± 100i; a normal
/// matrix, so ‖y‖₂ never grows under RK4 when every |R(hλ)| ≤ 1.
fn block_system() -> Linear {
    Linear::new(
        3,
        vec![-1000.0, 0.0, 0.0, 0.0, -1.0, 100.0, 0.0, -100.0, -1.0],
    )
}

/// Van der Pol y1' = y2, y2' = μ(1 − y1²) y2 − y1, with or without its analytic Jacobian
/// J = [[0, 1], [−2μ y1 y2 − 1, μ(1 − y1²)]].
struct Vdp {
    mu: f64,
    analytic: bool,
}

impl OdeSystem for Vdp {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = self.mu * (1.0 - y[0] * y[0]) * y[1] - y[0];
    }
    fn has_jacobian(&self) -> bool {
        self.analytic
    }
    fn jacobian(&self, _t: f64, y: &[f64], mut jac: MatMut<'_, f64>) {
        jac[(0, 0)] = 0.0;
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = -2.0 * self.mu * y[0] * y[1] - 1.0;
        jac[(1, 1)] = self.mu * (1.0 - y[0] * y[0]);
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn rk4_ray_limit_on_the_axes() {
    let real = rk4_ray_limit(-1.0, 0.0).unwrap();
    let imag = rk4_ray_limit(0.0, 1.0).unwrap();
    // The brief's constants, to 1e-3.
    assert!((real - 2.785).abs() < 1e-3, "real axis: {real}");
    assert!((imag - 2.828).abs() < 1e-3, "imaginary axis: {imag}");
    // Bisection runs to machine precision: against the exact values to 1e-12.
    assert!((real - real_axis_root()).abs() < 1e-12, "{real} vs Newton");
    assert!((real - 2.785_293_563_405_282).abs() < 1e-12, "{real}");
    assert!((imag - 8f64.sqrt()).abs() < 1e-12, "{imag} vs 2√2");
    // Conjugate symmetry, and the modulus of the direction does not matter.
    assert_eq!(rk4_ray_limit(0.0, -3.0), Some(imag));
    assert_eq!(rk4_ray_limit(-1e6, 0.0), Some(real));
}

/// On every ray of the closed left half-plane the limit lies on the boundary |R| = 1, every
/// point before it inside (first exit), and a point just after it outside.
#[test]
fn rk4_ray_limit_is_the_first_exit_of_the_stability_region() {
    for k in 0..=40 {
        let th = std::f64::consts::FRAC_PI_2 + std::f64::consts::PI * k as f64 / 40.0;
        let (s, c) = th.sin_cos();
        let c = if k == 0 || k == 40 { 0.0 } else { c };
        let r = rk4_ray_limit(c, s).unwrap();
        assert!(
            (rk4_amplification(r * c, r * s) - 1.0).abs() < 1e-12,
            "θ = {th}: |R| = {} at r = {r}",
            rk4_amplification(r * c, r * s)
        );
        for j in 1..200 {
            let q = r * j as f64 / 200.0;
            assert!(
                rk4_amplification(q * c, q * s) <= 1.0 + 1e-15,
                "θ = {th}, r = {q}"
            );
        }
        let out = r * (1.0 + 1e-6);
        assert!(rk4_amplification(out * c, out * s) > 1.0, "θ = {th}");
        // A sanity bound against a wrong root: the region reaches between 2.5 and 3 along
        // every ray of the left half-plane (2.785 on the real axis, 2.828 on the imaginary).
        assert!((2.5..3.0).contains(&r), "θ = {th}: r = {r}");
    }
}

#[test]
fn rk4_ray_limit_has_no_limit_in_the_right_half_plane() {
    assert_eq!(rk4_ray_limit(1e-9, 1.0), None);
    assert_eq!(rk4_ray_limit(1.0, 0.0), None);
    assert_eq!(rk4_ray_limit(0.0, 0.0), None);
    assert_eq!(rk4_ray_limit(f64::NAN, 1.0), None);
}

/// A = V D V⁻¹ with D = blockdiag(−1000, [[−1, 100], [−100, −1]]) and V unit upper
/// triangular: a full non-normal matrix with eigenvalues −1000, −1 ± 100i.
#[test]
fn eigenvalues_of_a_similarity_transformed_block_matrix() {
    let d = Mat::<f64>::from_fn(3, 3, |i, j| block_system().a[i * 3 + j]);
    let v = Mat::<f64>::from_fn(3, 3, |i, j| {
        [[1.0, 2.0, 0.0], [0.0, 1.0, 3.0], [0.0, 0.0, 1.0]][i][j]
    });
    let vinv = Mat::<f64>::from_fn(3, 3, |i, j| {
        [[1.0, -2.0, 6.0], [0.0, 1.0, -3.0], [0.0, 0.0, 1.0]][i][j]
    });
    let a = &v * &d * &vinv;
    let eig = eigenvalues(a.as_ref()).unwrap();
    let want = [(-1000.0, 0.0), (-1.0, 100.0), (-1.0, -100.0)];
    for (e, w) in eig.iter().zip(want) {
        // Backward-stable QR: errors of order ε‖A‖ ≈ 1e-12 relative to |λ|.
        assert!(
            (e.re - w.0).abs() < 1e-9 && (e.im - w.1).abs() < 1e-9,
            "{e:?} vs {w:?}"
        );
    }
    let sys = Linear::new(3, (0..9).map(|k| a[(k / 3, k % 3)]).collect());
    let s = analyze(&sys, 0.0, &[0.0; 3], &StiffnessOptions::default()).unwrap();
    let h = s.rk4_h_max.unwrap();
    assert!(rel(h, real_axis_root() / 1000.0) < 1e-12, "h_max = {h}");
    assert!((s.limiting.unwrap().re + 1000.0).abs() < 1e-9);
    assert!(s.unstable.is_empty());
    // Lambert's ratio max|Re λ| / min|Re λ| = 1000 / 1.
    assert!(rel(s.stiffness_ratio.unwrap(), 1000.0) < 1e-9);
    assert!(rel(s.spectral_radius, 1000.0) < 1e-12);
}

/// Measured largest stable RK4 step against the predicted 2.7853/1000 on the block system.
///
/// Tolerance 1e-2 relative (the brief): the bisection stops at a bracket of 1e-4, and the finite
/// horizon detects a step h*(1 + δ) only once |R|^N > growth_bound = 10, i.e. for
/// δ ≳ ln 10 / (N κ) with N = T/h* ≈ 359 steps and κ = d ln|R| / d ln h = x R'(x)/R(x) at
/// x = −2.785 (≈ 4.2): δ ≈ 1.5e-3. Together ≈ 1.6e-3, inside 1e-2. Sharper, one-sided: below
/// the limit nothing grows (normal matrix), so the unstable end lies above the prediction, and
/// the stable end at most 2 ln 10 / (N κ) above it.
#[test]
fn measured_rk4_limit_matches_the_real_eigenvalue() {
    let sys = block_system();
    let x = -real_axis_root();
    let pred = -x / 1000.0;
    let base = SolverOptions::default();
    let m = measure_rk4_limit(
        &sys,
        (0.0, 1.0),
        &[1.0, 1.0, 1.0],
        (1e-3, 1e-2),
        &base,
        &Rk4ProbeOptions::default(),
    )
    .unwrap();
    eprintln!(
        "real: predicted {pred:.6e}, measured [{:.6e}, {:.6e}] in {} runs",
        m.h_stable, m.h_unstable, m.runs
    );
    assert!(
        m.h_unstable > pred,
        "{} flagged below the limit {pred}",
        m.h_unstable
    );
    assert!(rel(m.estimate(), pred) < 1e-2);
    assert!(m.h_unstable / m.h_stable <= 1.0 + 1e-4);
    let r = 1.0 + x + x * x / 2.0 + x.powi(3) / 6.0 + x.powi(4) / 24.0;
    let dr = 1.0 + x + x * x / 2.0 + x.powi(3) / 6.0;
    let kappa = (x * dr / r).abs();
    let n_steps = 1.0 / pred;
    assert!(
        m.h_stable / pred - 1.0 <= 2.0 * 10f64.ln() / (n_steps * kappa),
        "δ = {:.3e}, κ = {kappa:.3}",
        m.h_stable / pred - 1.0
    );
}

/// The complex pair −1 ± 100i alone: the limit along the ray arg(−1 + 100i) (just past π/2,
/// so close to 2√2/100). The prediction is checked against a direct bisection on |R(hλ)| = 1
/// and the measurement as above (T = 10: N ≈ 353 steps, κ ≈ 7.1: δ ≈ 9e-4).
#[test]
fn measured_rk4_limit_matches_the_complex_pair() {
    let sys = Linear::new(2, vec![-1.0, 100.0, -100.0, -1.0]);
    let s = analyze(&sys, 0.0, &[1.0, 0.0], &StiffnessOptions::default()).unwrap();
    let pred = s.rk4_h_max.unwrap();
    // Independent: bisection on |R(h(−1 + 100i))| − 1 between 0.02 (inside) and 0.03.
    let (mut lo, mut hi) = (0.02f64, 0.03f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if rk4_amplification(-mid, 100.0 * mid) > 1.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    assert!(rel(pred, lo) < 1e-12, "{pred} vs {lo}");
    assert!(rel(pred, 8f64.sqrt() / 100.0) < 1e-2, "close to 2√2/|λ|");
    let m = measure_rk4_limit(
        &sys,
        (0.0, 10.0),
        &[1.0, 1.0],
        (0.01, 0.05),
        &SolverOptions::default(),
        &Rk4ProbeOptions::default(),
    )
    .unwrap();
    eprintln!(
        "complex: predicted {pred:.6e}, measured [{:.6e}, {:.6e}]",
        m.h_stable, m.h_unstable
    );
    assert!(m.h_unstable > pred);
    assert!(rel(m.estimate(), pred) < 1e-2);
}

/// A check on the accepted states sharpens the measurement and is applied to every run. On the
/// block system (normal: ‖y‖₂ never grows below the limit) the check ‖y‖₂ ≤ 1.5‖y0‖₂ = 1.5√3
/// fails after a growth of the −1000 mode by about 1.5√3 instead of the tenfold growth of
/// ‖y‖∞ the bare criterion needs, so the stable end lies within 2 ln(1.5√3)/(N κ) ≈ 1.3e-3 of
/// the prediction (N, κ as above) and strictly below the bare measurement's. A check that
/// always fails makes the lower end unstable.
#[test]
fn measured_rk4_limit_with_a_state_check() {
    let sys = block_system();
    let x = -real_axis_root();
    let pred = -x / 1000.0;
    let base = SolverOptions::default();
    let p = Rk4ProbeOptions::default();
    let y0 = [1.0, 1.0, 1.0];
    let cap = 1.5 * 3f64.sqrt();
    let check = |_: f64, y: &[f64]| y.iter().map(|v| v * v).sum::<f64>().sqrt() <= cap;
    let m =
        measure_rk4_limit_where(&sys, (0.0, 1.0), &y0, (1e-3, 1e-2), &base, &p, &check).unwrap();
    let bare = measure_rk4_limit(&sys, (0.0, 1.0), &y0, (1e-3, 1e-2), &base, &p).unwrap();
    let r = 1.0 + x + x * x / 2.0 + x.powi(3) / 6.0 + x.powi(4) / 24.0;
    let dr = 1.0 + x + x * x / 2.0 + x.powi(3) / 6.0;
    let kappa = (x * dr / r).abs();
    let n_steps = 1.0 / pred;
    eprintln!(
        "checked: predicted {pred:.6e}, measured [{:.6e}, {:.6e}], bare stable end {:.6e}",
        m.h_stable, m.h_unstable, bare.h_stable
    );
    assert!(m.h_unstable > pred);
    assert!(m.h_stable / pred - 1.0 <= 2.0 * cap.ln() / (n_steps * kappa));
    assert!(m.h_stable < bare.h_stable);
    let never = |_: f64, _: &[f64]| false;
    assert_eq!(
        measure_rk4_limit_where(&sys, (0.0, 1.0), &y0, (1e-3, 1e-2), &base, &p, &never)
            .unwrap_err(),
        AnalysisError::NoBracket {
            h: 1e-3,
            stable: false
        }
    );
}

#[test]
fn measured_rk4_limit_needs_a_bracket() {
    let sys = block_system();
    let base = SolverOptions::default();
    let p = Rk4ProbeOptions::default();
    let y0 = [1.0, 1.0, 1.0];
    // Both ends stable (below 2.785e-3).
    let e = measure_rk4_limit(&sys, (0.0, 1.0), &y0, (1e-4, 2e-3), &base, &p).unwrap_err();
    assert_eq!(
        e,
        AnalysisError::NoBracket {
            h: 2e-3,
            stable: true
        }
    );
    // Lower end unstable.
    let e = measure_rk4_limit(&sys, (0.0, 1.0), &y0, (3e-3, 1e-2), &base, &p).unwrap_err();
    assert_eq!(
        e,
        AnalysisError::NoBracket {
            h: 3e-3,
            stable: false
        }
    );
    assert!(matches!(
        measure_rk4_limit(&sys, (0.0, 1.0), &y0, (1e-2, 1e-3), &base, &p),
        Err(AnalysisError::InvalidInput(_))
    ));
    assert!(matches!(
        measure_rk4_limit(&sys, (0.0, 1.0), &[0.0; 3], (1e-4, 1e-2), &base, &p),
        Err(AnalysisError::InvalidInput(_))
    ));
    assert!(rk4_is_stable(&sys, (0.0, 1.0), &y0, 2.7e-3, &base, 10.0).unwrap());
    assert!(!rk4_is_stable(&sys, (0.0, 1.0), &y0, 2.9e-3, &base, 10.0).unwrap());
}

/// Van der Pol, μ = 1000, at (2, 0.5): J = [[0, 1], [−2μ − 1, −3μ]], so
/// λ = (−3μ ∓ √(9μ² − 8μ − 4)) / 2, both real and negative (det = 2μ + 1 > 0).
#[test]
fn van_der_pol_eigenvalues_at_a_known_point() {
    let mu = 1000.0;
    let y = [2.0, 0.5];
    let disc = (9.0 * mu * mu - 8.0 * mu - 4.0f64).sqrt();
    let l1 = (-3.0 * mu - disc) / 2.0;
    let l2 = (2.0 * mu + 1.0) / l1; // λ1 λ2 = det, without cancellation
    for (analytic, tol) in [(true, 1e-12), (false, 1e-8)] {
        // FD: central differences of a function quadratic in y1 and linear in y2 are exact but
        // for rounding, ε|f|/δ ≈ 2e-16 · 1500 / 1.2e-5 ≈ 3e-8 absolute on J21 ≈ −2001.
        let sys = Vdp { mu, analytic };
        let s = analyze(&sys, 0.0, &y, &StiffnessOptions::default()).unwrap();
        let d = &s.dominant;
        assert_eq!(d.len(), 2);
        assert!(
            rel(d[0].re, l1) < tol && d[0].im == 0.0,
            "{analytic}: {:?} vs {l1}",
            d[0]
        );
        assert!(
            rel(d[1].re, l2) < tol && d[1].im == 0.0,
            "{analytic}: {:?} vs {l2}",
            d[1]
        );
        assert!(rel(s.rk4_h_max.unwrap(), real_axis_root() / -l1) < tol);
        assert!(rel(s.stiffness_ratio.unwrap(), l1 / l2) < tol);
        eprintln!(
            "vdp μ=1000 at (2, 0.5), analytic = {analytic}: λ = {:.6e}, {:.6e}; h_max = {:.4e}; S = {:.4e}",
            d[0].re, d[1].re, s.rk4_h_max.unwrap(), s.stiffness_ratio.unwrap()
        );
    }
}

/// Van der Pol near the origin is a repeller: at (0, 0.5) J = [[0, 1], [−1, μ]] has
/// λ = (μ ± √(μ² − 4))/2 > 0; with μ = 1, (1 ± i√3)/2. Both are reported as growing modes and
/// give no step limit.
#[test]
fn growing_modes_are_reported_not_used_as_limits() {
    for (mu, re, im) in [(1000.0, 0.0, 0.0), (1.0, 0.5, 0.75f64.sqrt())] {
        let sys = Vdp { mu, analytic: true };
        let s = analyze(&sys, 0.0, &[0.0, 0.5], &StiffnessOptions::default()).unwrap();
        assert_eq!(s.rk4_h_max, None);
        assert_eq!(s.limiting, None);
        assert_eq!(s.unstable.len(), 2);
        assert_eq!(s.stiffness_ratio, None);
        if mu == 1.0 {
            assert!((s.unstable[0].re - re).abs() < 1e-14 && (s.unstable[0].im - im).abs() < 1e-14);
        } else {
            let disc = (mu * mu - 4.0f64).sqrt();
            assert!(rel(s.unstable[0].re, (mu + disc) / 2.0) < 1e-12);
            assert!(rel(s.unstable[1].re, 2.0 / (mu + disc)) < 1e-9);
        }
    }
}

/// An undamped oscillator: λ = ±ωi exactly; rounding may put Re λ at ±1e−16ω, which the
/// neutral tolerance puts on the imaginary axis: the limit is 2√2/ω and no mode grows.
/// A zero eigenvalue (a free coordinate) gives no limit.
#[test]
fn neutral_and_zero_modes() {
    let w = 50.0;
    let sys = Linear::new(3, vec![0.0, 1.0, 0.0, -w * w, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let s = analyze(&sys, 0.0, &[1.0, 0.0, 0.0], &StiffnessOptions::default()).unwrap();
    assert!(s.unstable.is_empty());
    assert!(rel(s.rk4_h_max.unwrap(), 8f64.sqrt() / w) < 1e-12);
    assert_eq!(s.stiffness_ratio, None);
    assert_eq!(s.dominant.len(), 3);
    assert!(s.dominant[2].modulus() < 1e-12);
    assert!(
        s.dominant[0].im > 0.0 && s.dominant[1].im < 0.0,
        "+im first"
    );
}

/// Along y' = −y³, y(0) = 1: y(t) = 1/√(1 + 2t) and J = −3y² = −3/(1 + 2t). The sampler must
/// analyse each dense-output point at its own time and state.
#[test]
fn sampler_follows_the_trajectory() {
    struct Cubic;
    impl OdeSystem for Cubic {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = -y[0] * y[0] * y[0];
        }
    }
    let times: Vec<f64> = (0..=20).map(|k| 0.5 * k as f64).collect();
    let solver = SolverOptions {
        rtol: 1e-10,
        atol: Atol::Scalar(1e-12),
        ..Default::default()
    };
    let samples = sample_trajectory(
        &Cubic,
        (0.0, 10.0),
        &[1.0],
        &solver,
        &times,
        &StiffnessOptions::default(),
    )
    .unwrap();
    assert_eq!(samples.len(), times.len());
    for (s, &t) in samples.iter().zip(&times) {
        assert_eq!(s.t, t);
        let lam = -3.0 / (1.0 + 2.0 * t);
        // Solver error 1e-10 relative, FD error O(ε^{2/3}) ≈ 1e-10 relative.
        assert!(
            rel(s.dominant[0].re, lam) < 1e-8,
            "t = {t}: {:?} vs {lam}",
            s.dominant[0]
        );
        assert!(rel(s.rk4_h_max.unwrap(), real_axis_root() / -lam) < 1e-8);
    }
    // The same points given as a list.
    let ys: Vec<f64> = times.iter().map(|t| 1.0 / (1.0 + 2.0 * t).sqrt()).collect();
    let again = sample_states(&Cubic, &times, &ys, &StiffnessOptions::default()).unwrap();
    for (a, b) in again.iter().zip(&samples) {
        assert!(rel(a.dominant[0].re, b.dominant[0].re) < 1e-8);
    }
    assert!(matches!(
        sample_states(&Cubic, &times, &ys[1..], &StiffnessOptions::default()),
        Err(AnalysisError::InvalidInput(_))
    ));
}

/// The verdict is a function of q = h_accuracy / h_stability with thresholds 1 and 10.
#[test]
fn verdict_thresholds() {
    let v = verdict(1e-3, Some(2e-3), 0).unwrap();
    assert_eq!(v.family, Family::Explicit);
    assert_eq!(v.step_ratio, 0.5);
    let v = verdict(1e-3, Some(2e-4), 0).unwrap();
    assert_eq!(v.family, Family::Either);
    assert!(rel(v.step_ratio, 5.0) < 1e-15);
    let v = verdict(1e-3, Some(1e-3 / IMPLICIT_FACTOR), 0).unwrap();
    assert_eq!(v.family, Family::Implicit);
    assert!(v.reason.contains("rodas5p"));
    let v = verdict(1e-3, None, 1).unwrap();
    assert_eq!(v.family, Family::Explicit);
    assert!(v.reason.contains("1 growing mode"));
    assert!(verdict(0.0, Some(1e-3), 0).is_err());
    assert!(verdict(1e-3, Some(f64::NAN), 0).is_err());
}

/// Van der Pol μ = 1000 on its slow branch y2 = −y1 / (μ(1 − y1²)), here (2, 2/(3μ)):
/// J = [[0, 1], [−11/3, −3μ]], λ ≈ −3μ and −11/(9μ). The solution changes on the time scale μ,
/// so an accuracy step of 1e-2 is generous, while the stability limit is 2.785/3000 ≈ 9.3e-4:
/// q ≈ 11 ≥ 10 → implicit, and no growing mode.
#[test]
fn van_der_pol_verdict_is_implicit() {
    let mu = 1000.0;
    let sys = Vdp { mu, analytic: true };
    let s = analyze(
        &sys,
        0.0,
        &[2.0, 2.0 / (3.0 * mu)],
        &StiffnessOptions::default(),
    )
    .unwrap();
    assert!(s.unstable.is_empty());
    // λ1 λ2 = det J = 11/3; the small eigenvalue carries an error of order ε‖J‖ ≈ 7e-13,
    // 6e-10 of its size.
    assert!(rel(s.dominant[1].re, -11.0 / 3.0 / s.dominant[0].re.abs()) < 1e-8);
    let v = verdict(1e-2, s.rk4_h_max, s.unstable.len()).unwrap();
    eprintln!("{}", v.reason);
    assert_eq!(v.family, Family::Implicit);
    assert!(rel(v.step_ratio, 1e-2 * s.spectral_radius / real_axis_root()) < 1e-12);
}

#[test]
fn non_finite_jacobian_is_an_error() {
    struct Bad;
    impl OdeSystem for Bad {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = y[0].sqrt();
        }
    }
    // FD around y = 0 evaluates √(−δ) = NaN.
    let e = analyze(&Bad, 2.0, &[0.0], &StiffnessOptions::default()).unwrap_err();
    assert!(
        matches!(e, AnalysisError::NonFinite { t, .. } if t == 2.0),
        "{e:?}"
    );
    assert!(matches!(
        analyze(&Bad, 0.0, &[0.0, 1.0], &StiffnessOptions::default()),
        Err(AnalysisError::InvalidInput(_))
    ));
}
