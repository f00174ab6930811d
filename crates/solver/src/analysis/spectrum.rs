//! The spectrum at one point, the piece of the stiffness diagnostics that integrates
//! nothing: the Jacobian ∂f/∂y, its eigenvalues, and RK4's stability region along a ray. The
//! RK4 stepper's stability check reads it too (crate::rk4), so it imports no integrator.
//!
//! ```text
//! J = ∂f/∂y (t, y)               analytic if the system has one, else central differences
//! λ_1, …, λ_n = eig(J)            sorted by |λ| (largest first); complex pairs for real J
//!
//! RK4 on y' = λy:  y_{n+1} = R(hλ) y_n,   R(z) = 1 + z + z²/2 + z³/6 + z⁴/24
//! ray limit        r(θ) = sup { r ≥ 0 : |R(s e^{iθ})| ≤ 1 for all 0 ≤ s ≤ r },  Re e^{iθ} ≤ 0
//!                  576 (|R(r e^{iθ})|² − 1) = 1152c r + 1152c² r² + 768c³ r³ + 384c⁴ r⁴
//!                      + (192c³ − 48c) r⁵ + (48c² − 8) r⁶ + 8c r⁷ + r⁸,   c = cos θ
//! ```
//!
//! The values of r(θ) and the sources are in the [`super::stiffness`] module documentation.

use faer::{Mat, MatMut, MatRef};

use super::error::AnalysisError;
use crate::system::OdeSystem;

/// One eigenvalue λ = re + i·im of the Jacobian.
///
/// ```text
/// λ = re + i im,   |λ| = √(re² + im²),   arg λ ∈ (−π, π]
/// ```
/// Eigenvalues of a real matrix (HNW II, §IV.2 reads them as the rates of the linearised modes:
/// Re λ decay (< 0) or growth (> 0), Im λ angular frequency).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Eigenvalue {
    /// Real part (1/s): decay rate when negative.
    pub re: f64,
    /// Imaginary part (rad/s).
    pub im: f64,
}

impl Eigenvalue {
    /// |λ|.
    pub fn modulus(&self) -> f64 {
        self.re.hypot(self.im)
    }
    /// arg λ in (−π, π].
    pub fn arg(&self) -> f64 {
        self.im.atan2(self.re)
    }
}

/// The Jacobian ∂f/∂y at (t, y): the system's own when [`OdeSystem::has_jacobian`], else
/// central differences with step δ_j = ε^{1/3}·max(|y_j|, s_j) (s_j from `fd_scale`, default 1).
/// Costs 2n RHS evaluations when differenced.
pub fn jacobian_at<S: OdeSystem + ?Sized>(
    sys: &S,
    t: f64,
    y: &[f64],
    fd_scale: Option<&[f64]>,
) -> Result<Mat<f64>, AnalysisError> {
    let n = sys.dim();
    if y.len() != n {
        return Err(AnalysisError::InvalidInput(format!(
            "y has {} entries, the system {n}",
            y.len()
        )));
    }
    if !t.is_finite() || y.iter().any(|v| !v.is_finite()) {
        return Err(AnalysisError::InvalidInput(format!(
            "t and y must be finite (t = {t})"
        )));
    }
    if let Some(s) = fd_scale {
        if s.len() != n || s.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(AnalysisError::InvalidInput(format!(
                "fd_scale must have {n} finite entries > 0"
            )));
        }
    }
    let mut jac = Mat::<f64>::zeros(n, n);
    let what = if sys.has_jacobian() {
        sys.jacobian(t, y, jac.as_mut());
        "analytic Jacobian"
    } else {
        fd_jacobian(sys, t, y, fd_scale, jac.as_mut());
        "finite-difference Jacobian"
    };
    for j in 0..n {
        for i in 0..n {
            if !jac[(i, j)].is_finite() {
                return Err(AnalysisError::NonFinite {
                    t,
                    what: format!("{what} entry ({i}, {j})"),
                });
            }
        }
    }
    Ok(jac)
}

/// Central-difference Jacobian, column by column (private: the stiff methods keep their own
/// finite-difference Jacobian; this one favours accuracy, O(δ²), over cost).
fn fd_jacobian<S: OdeSystem + ?Sized>(
    sys: &S,
    t: f64,
    y: &[f64],
    fd_scale: Option<&[f64]>,
    mut jac: MatMut<'_, f64>,
) {
    let n = y.len();
    let cbrt_eps = f64::EPSILON.cbrt();
    let mut yp = y.to_vec();
    let mut fp = vec![0.0; n];
    let mut fm = vec![0.0; n];
    for j in 0..n {
        let s = fd_scale.map_or(1.0, |s| s[j]);
        let delta = cbrt_eps * y[j].abs().max(s);
        // Steps that are exactly representable differences of the perturbed arguments.
        let up = y[j] + delta;
        let dn = y[j] - delta;
        yp[j] = up;
        sys.rhs(t, &yp, &mut fp);
        yp[j] = dn;
        sys.rhs(t, &yp, &mut fm);
        yp[j] = y[j];
        let width = up - dn;
        for i in 0..n {
            jac[(i, j)] = (fp[i] - fm[i]) / width;
        }
    }
}

/// All eigenvalues of a real square matrix (faer's real Schur / Hessenberg QR), sorted by
/// modulus, largest first; among equal moduli the larger imaginary part first (so a complex
/// pair is listed as +im, −im). Non-finite entries are an error, not NaN eigenvalues.
pub fn eigenvalues(jac: MatRef<'_, f64>) -> Result<Vec<Eigenvalue>, AnalysisError> {
    if jac.nrows() != jac.ncols() {
        return Err(AnalysisError::InvalidInput(format!(
            "the matrix is {}×{}, not square",
            jac.nrows(),
            jac.ncols()
        )));
    }
    let n = jac.nrows();
    for j in 0..n {
        for i in 0..n {
            if !jac[(i, j)].is_finite() {
                return Err(AnalysisError::NonFinite {
                    t: f64::NAN,
                    what: format!("matrix entry ({i}, {j})"),
                });
            }
        }
    }
    if n == 0 {
        return Ok(Vec::new());
    }
    let ev = jac
        .eigenvalues()
        .map_err(|_| AnalysisError::EigenNoConvergence { t: f64::NAN })?;
    let mut out: Vec<Eigenvalue> = ev
        .iter()
        .map(|c| Eigenvalue { re: c.re, im: c.im })
        .collect();
    if out.iter().any(|e| !(e.re.is_finite() && e.im.is_finite())) {
        return Err(AnalysisError::NonFinite {
            t: f64::NAN,
            what: "eigenvalue".into(),
        });
    }
    out.sort_by(|a, b| {
        b.modulus()
            .total_cmp(&a.modulus())
            .then(b.im.total_cmp(&a.im))
    });
    Ok(out)
}

/// |R(z)| for classical RK4, R(z) = 1 + z + z²/2 + z³/6 + z⁴/24 (HNW II, §IV.2, (2.8) with
/// s = p = 4), by Horner's rule in complex arithmetic.
pub fn rk4_amplification(re: f64, im: f64) -> f64 {
    // Horner: ((((1/24) z + 1/6) z + 1/2) z + 1) z + 1
    let coef = [1.0 / 24.0, 1.0 / 6.0, 0.5, 1.0, 1.0];
    let (mut pr, mut pi) = (coef[0], 0.0);
    for &c in &coef[1..] {
        let nr = pr * re - pi * im + c;
        let ni = pr * im + pi * re;
        pr = nr;
        pi = ni;
    }
    pr.hypot(pi)
}

/// 576 (|R(r e^{iθ})|² − 1) / r as a polynomial in r with c = cos θ (module docs): expanded in
/// c so that no coefficient suffers cancellation near the imaginary axis (c → 0).
fn rk4_ray_poly(c: f64, r: f64) -> f64 {
    let c2 = c * c;
    let c3 = c2 * c;
    let coef = [
        1152.0 * c,
        1152.0 * c2,
        768.0 * c3,
        384.0 * c2 * c2,
        192.0 * c3 - 48.0 * c,
        48.0 * c2 - 8.0,
        8.0 * c,
        1.0,
    ];
    coef.iter().rev().fold(0.0, |acc, &a| acc * r + a)
}

/// Extent r(θ) of RK4's stability region along the ray from 0 through z = re + i·im: the
/// largest r with |R(s e^{iθ})| ≤ 1 for every 0 ≤ s ≤ r (the first exit of the ray, so every
/// step up to the limit is stable). r(π) = 2.7852935634, r(±π/2) = 2√2 (HNW II, §IV.2,
/// Fig. 2.1).
///
/// None when z is zero or not finite, or Re z > 0 (the ray leaves the region at once, as
/// |R(z)| ≈ |e^z| > 1 near 0). The first sign change of the ray polynomial is found on a grid
/// of 1e-3 in r over [0, 7] (the region lies inside |z| < 7, where |z|⁴/24 outgrows the rest of
/// R) and refined by bisection to machine precision.
pub fn rk4_ray_limit(re: f64, im: f64) -> Option<f64> {
    if !(re.is_finite() && im.is_finite()) || re > 0.0 {
        return None;
    }
    let m = re.hypot(im);
    if m == 0.0 {
        return None;
    }
    let c = re / m;
    let q = |r: f64| rk4_ray_poly(c, r);
    const DR: f64 = 1e-3;
    let mut lo = 0.0;
    let mut k = 1usize;
    loop {
        let hi = k as f64 * DR;
        if hi > 7.0 {
            return None; // unreachable for RK4: the region is bounded by |z| < 7
        }
        if q(hi) > 0.0 {
            let mut hi = hi;
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                if q(mid) > 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            return Some(lo);
        }
        lo = hi;
        k += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Quadratic;
    impl OdeSystem for Quadratic {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = y[0] * y[0] + 3.0 * y[1];
            dy[1] = y[0] * y[1] * y[1] - 2.0 * y[0];
        }
    }

    /// Central differences are exact for quadratics up to rounding, and within O(δ²) for the
    /// cubic term: J = [[2a, 3], [b² − 2, 2ab]].
    #[test]
    fn fd_jacobian_matches_the_closed_form() {
        let (a, b) = (1.5, -0.7);
        let j = jacobian_at(&Quadratic, 0.0, &[a, b], None).unwrap();
        let exact = [[2.0 * a, 3.0], [b * b - 2.0, 2.0 * a * b]];
        for i in 0..2 {
            for k in 0..2 {
                assert!(
                    (j[(i, k)] - exact[i][k]).abs() < 1e-9,
                    "J[{i},{k}] = {} vs {}",
                    j[(i, k)],
                    exact[i][k]
                );
            }
        }
    }

    /// The ray polynomial is 576(|R|² − 1)/r: compare with the direct evaluation.
    #[test]
    fn ray_polynomial_matches_direct_evaluation() {
        for &th in &[1.7f64, 2.0, 2.5, 3.0, std::f64::consts::PI] {
            for &r in &[0.3, 1.1, 2.2, 2.9] {
                let (re, im) = (r * th.cos(), r * th.sin());
                let direct = 576.0 * (rk4_amplification(re, im).powi(2) - 1.0) / r;
                let poly = rk4_ray_poly(th.cos(), r);
                assert!(
                    (direct - poly).abs() < 1e-10 * (1.0 + direct.abs()),
                    "θ = {th}, r = {r}: {direct} vs {poly}"
                );
            }
        }
    }
}
