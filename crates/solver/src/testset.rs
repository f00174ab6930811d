//! Stiff problems of the IVP Test Set with their published reference solutions, and the error
//! measure the tests and the `lash` command report.
//!
//! ```text
//! ROBER   y1' = −0.04 y1 + 10⁴ y2 y3,  y2' = 0.04 y1 − 10⁴ y2 y3 − 3·10⁷ y2²,  y3' = 3·10⁷ y2²
//!         y(0) = (1, 0, 0), t ∈ [0, 10¹¹]
//! VDPOLM  y1' = y2,  y2' = 1000 (1 − y1²) y2 − y1,  y(0) = (2, 0), t ∈ [0, 2000]
//! HIRES   8 linear/bilinear reactions (below), y(0) = (1, 0, 0, 0, 0, 0, 0, 0.0057),
//!         t ∈ [0, 321.8122]
//! OREGO   y1' = 77.27 (y2 + y1 (1 − 8.375·10⁻⁶ y1 − y2)),  y2' = (y3 − (1 + y1) y2) / 77.27,
//!         y3' = 0.161 (y1 − y3),  y(0) = (1, 2, 3), t ∈ [0, 360]
//! ```
//!
//! Source: F. Mazzia and C. Magherini, *Test Set for Initial Value Problem Solvers*, release
//! 2.4 (University of Bari, 2008), problems ROBER, HIRES and OREGO with their reference
//! solutions at the end point; VDPOLM is the van der Pol oscillator with μ = 1000 in its
//! unscaled form, with the reference values at t = 2000 given to this project. All four
//! references were re-checked here with Rodas5P at rtol 10⁻¹²–10⁻¹³ and atol 10⁻¹⁶–10⁻²⁰: the
//! largest relative difference was 6·10⁻¹³ (ROBER), 2·10⁻¹³ (VDPOLM), 1.4·10⁻¹³ (HIRES).
//! Every system has its analytic Jacobian and is autonomous.
//!
//! `atol` of each problem is both the absolute tolerance the tests run with and the threshold
//! of [`reference_error`] (components at or below it are not compared). It is chosen so that
//! at rtol = 10⁻⁸ every compared component is controlled relatively, atol ≲ rtol·|y_i(t_end)|;
//! a larger atol caps the relative accuracy of the small components whatever rtol is (with
//! ROBER at atol 10⁻¹⁴, y1 stalls near 10⁻⁶ relative error for BDF and 10⁻⁵ for TR-BDF2 from
//! rtol 10⁻⁸ to 10⁻¹⁰):
//! - ROBER 10⁻¹⁶: y1 ends at 2·10⁻⁸ (rtol·y1 = 2·10⁻¹⁶). y2 ends at 8·10⁻¹⁴ but is in
//!   quasi-steady state (y2 ≈ 4·10⁻⁶ y1 / y3), so its relative error follows y1's.
//! - VDPOLM 10⁻¹¹: y2 ends at −8.9·10⁻⁴ (rtol·|y2| = 9·10⁻¹²); y1 is O(1).
//! - HIRES 10⁻¹²: the smallest final component is y3 = 5.9·10⁻⁵ (and y(0) has zeros).
//! - OREGO 10⁻⁸: every component stays above 1 (they range from 1 to 10⁵).
use faer::MatMut;

use crate::system::OdeSystem;

/// One test problem: the system, its span, initial value, reference solution at `t_end`
/// and the absolute tolerance that goes with it.
///
/// ```text
/// y' = f(y),  y(t0) = y0;   y(t_end) ≈ reference
/// ```
/// Mazzia & Magherini, IVP Test Set 2.4 (see the module documentation).
pub struct TestProblem {
    /// Name (`rober`, `vdpolm`, `hires`, `orego`).
    pub name: &'static str,
    /// Start time.
    pub t0: f64,
    /// End time, where the reference solution holds.
    pub t_end: f64,
    /// Initial value.
    pub y0: Vec<f64>,
    /// Reference solution at `t_end`.
    pub reference: Vec<f64>,
    /// Absolute tolerance for the solver and threshold of [`reference_error`].
    pub atol: f64,
    /// The system (with analytic Jacobian).
    pub system: Box<dyn OdeSystem + Send + Sync>,
}

/// The names [`by_name`] knows.
pub const NAMES: [&str; 4] = ["rober", "vdpolm", "hires", "orego"];

/// The test problem of this name, or None.
pub fn by_name(name: &str) -> Option<TestProblem> {
    Some(match name {
        "rober" => TestProblem {
            name: "rober",
            t0: 0.0,
            t_end: 1e11,
            y0: vec![1.0, 0.0, 0.0],
            reference: vec![
                2.083340149701255e-8,
                8.333360770334713e-14,
                0.999999979166505,
            ],
            atol: 1e-16,
            system: Box::new(Rober),
        },
        "vdpolm" => TestProblem {
            name: "vdpolm",
            t0: 0.0,
            t_end: 2000.0,
            y0: vec![2.0, 0.0],
            reference: vec![1.706167732170469, -8.928097010248125e-4],
            atol: 1e-11,
            system: Box::new(VdPolM),
        },
        "hires" => TestProblem {
            name: "hires",
            t0: 0.0,
            t_end: 321.8122,
            y0: vec![1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0057],
            reference: vec![
                7.371312573325668e-4,
                1.442485726316185e-4,
                5.888729740967575e-5,
                1.175651343283149e-3,
                2.386356198831331e-3,
                6.238968252742796e-3,
                2.849998395185769e-3,
                2.850001604814231e-3,
            ],
            atol: 1e-12,
            system: Box::new(Hires),
        },
        "orego" => TestProblem {
            name: "orego",
            t0: 0.0,
            t_end: 360.0,
            y0: vec![1.0, 2.0, 3.0],
            reference: vec![1.000814870318523, 1228.178521549917, 132.0554942846706],
            atol: 1e-8,
            system: Box::new(Orego),
        },
        _ => return None,
    })
}

/// Largest relative error over components whose |reference| > atol.
///
/// ```text
/// max_{i : |ref_i| > atol} |y_i − ref_i| / |ref_i|
/// ```
/// 0 when no component counts; +∞ when the lengths differ or a compared y_i is not finite.
pub fn reference_error(y: &[f64], reference: &[f64], atol: f64) -> f64 {
    if y.len() != reference.len() {
        return f64::INFINITY;
    }
    let mut worst: f64 = 0.0;
    for (&yi, &ri) in y.iter().zip(reference) {
        if ri.abs() > atol {
            let e = (yi - ri).abs() / ri.abs();
            if !e.is_finite() {
                return f64::INFINITY;
            }
            worst = worst.max(e);
        }
    }
    worst
}

/// Robertson's chemical kinetics (IVP Test Set, ROBER).
///
/// ```text
/// y1' = −0.04 y1 + 10⁴ y2 y3
/// y2' =  0.04 y1 − 10⁴ y2 y3 − 3·10⁷ y2²
/// y3' =  3·10⁷ y2²
/// ```
/// Robertson (1966); Mazzia & Magherini, IVP Test Set 2.4.
#[derive(Clone, Copy, Debug, Default)]
pub struct Rober;

impl OdeSystem for Rober {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        let (a, b) = (0.04 * y[0], 1e4 * y[1] * y[2]);
        let c = 3e7 * y[1] * y[1];
        dy[0] = -a + b;
        dy[1] = a - b - c;
        dy[2] = c;
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, y: &[f64], mut jac: MatMut<'_, f64>) {
        jac[(0, 0)] = -0.04;
        jac[(0, 1)] = 1e4 * y[2];
        jac[(0, 2)] = 1e4 * y[1];
        jac[(1, 0)] = 0.04;
        jac[(1, 1)] = -1e4 * y[2] - 6e7 * y[1];
        jac[(1, 2)] = -1e4 * y[1];
        jac[(2, 0)] = 0.0;
        jac[(2, 1)] = 6e7 * y[1];
        jac[(2, 2)] = 0.0;
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

/// Van der Pol's oscillator with μ = 1000, unscaled (VDPOLM).
///
/// ```text
/// y1' = y2
/// y2' = μ (1 − y1²) y2 − y1,   μ = 1000
/// ```
/// Van der Pol (1926); HNW II, §IV.1 (its stiff van der Pol problem in unscaled time).
#[derive(Clone, Copy, Debug, Default)]
pub struct VdPolM;

impl OdeSystem for VdPolM {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = 1000.0 * (1.0 - y[0] * y[0]) * y[1] - y[0];
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, y: &[f64], mut jac: MatMut<'_, f64>) {
        jac[(0, 0)] = 0.0;
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = -2000.0 * y[0] * y[1] - 1.0;
        jac[(1, 1)] = 1000.0 * (1.0 - y[0] * y[0]);
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

/// High Irradiance RESponse of photomorphogenesis (IVP Test Set, HIRES).
///
/// ```text
/// y1' = −1.71 y1 + 0.43 y2 + 8.32 y3 + 0.0007
/// y2' =  1.71 y1 − 8.75 y2
/// y3' = −10.03 y3 + 0.43 y4 + 0.035 y5
/// y4' =  8.32 y2 + 1.71 y3 − 1.12 y4
/// y5' = −1.745 y5 + 0.43 y6 + 0.43 y7
/// y6' = −280 y6 y8 + 0.69 y4 + 1.71 y5 − 0.43 y6 + 0.69 y7
/// y7' =  280 y6 y8 − 1.81 y7
/// y8' = −280 y6 y8 + 1.81 y7
/// ```
/// Schäfer (1975); HNW II, §IV.10; Mazzia & Magherini, IVP Test Set 2.4.
#[derive(Clone, Copy, Debug, Default)]
pub struct Hires;

impl OdeSystem for Hires {
    fn dim(&self) -> usize {
        8
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        let r = 280.0 * y[5] * y[7];
        dy[0] = -1.71 * y[0] + 0.43 * y[1] + 8.32 * y[2] + 0.0007;
        dy[1] = 1.71 * y[0] - 8.75 * y[1];
        dy[2] = -10.03 * y[2] + 0.43 * y[3] + 0.035 * y[4];
        dy[3] = 8.32 * y[1] + 1.71 * y[2] - 1.12 * y[3];
        dy[4] = -1.745 * y[4] + 0.43 * y[5] + 0.43 * y[6];
        dy[5] = -r + 0.69 * y[3] + 1.71 * y[4] - 0.43 * y[5] + 0.69 * y[6];
        dy[6] = r - 1.81 * y[6];
        dy[7] = -r + 1.81 * y[6];
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, y: &[f64], mut jac: MatMut<'_, f64>) {
        jac.fill(0.0);
        jac[(0, 0)] = -1.71;
        jac[(0, 1)] = 0.43;
        jac[(0, 2)] = 8.32;
        jac[(1, 0)] = 1.71;
        jac[(1, 1)] = -8.75;
        jac[(2, 2)] = -10.03;
        jac[(2, 3)] = 0.43;
        jac[(2, 4)] = 0.035;
        jac[(3, 1)] = 8.32;
        jac[(3, 2)] = 1.71;
        jac[(3, 3)] = -1.12;
        jac[(4, 4)] = -1.745;
        jac[(4, 5)] = 0.43;
        jac[(4, 6)] = 0.43;
        jac[(5, 3)] = 0.69;
        jac[(5, 4)] = 1.71;
        jac[(5, 5)] = -0.43 - 280.0 * y[7];
        jac[(5, 6)] = 0.69;
        jac[(5, 7)] = -280.0 * y[5];
        jac[(6, 5)] = 280.0 * y[7];
        jac[(6, 6)] = -1.81;
        jac[(6, 7)] = 280.0 * y[5];
        jac[(7, 5)] = -280.0 * y[7];
        jac[(7, 6)] = 1.81;
        jac[(7, 7)] = -280.0 * y[5];
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

/// The Oregonator, Field and Noyes' model of the Belousov–Zhabotinskii reaction
/// (IVP Test Set, OREGO).
///
/// ```text
/// y1' = 77.27 (y2 + y1 (1 − 8.375·10⁻⁶ y1 − y2))
/// y2' = (y3 − (1 + y1) y2) / 77.27
/// y3' = 0.161 (y1 − y3)
/// ```
/// Field & Noyes (1974); HNW II, §IV.10; Mazzia & Magherini, IVP Test Set 2.4.
#[derive(Clone, Copy, Debug, Default)]
pub struct Orego;

impl OdeSystem for Orego {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = 77.27 * (y[1] + y[0] * (1.0 - 8.375e-6 * y[0] - y[1]));
        dy[1] = (y[2] - (1.0 + y[0]) * y[1]) / 77.27;
        dy[2] = 0.161 * (y[0] - y[2]);
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, y: &[f64], mut jac: MatMut<'_, f64>) {
        jac[(0, 0)] = 77.27 * (1.0 - 2.0 * 8.375e-6 * y[0] - y[1]);
        jac[(0, 1)] = 77.27 * (1.0 - y[0]);
        jac[(0, 2)] = 0.0;
        jac[(1, 0)] = -y[1] / 77.27;
        jac[(1, 1)] = -(1.0 + y[0]) / 77.27;
        jac[(1, 2)] = 1.0 / 77.27;
        jac[(2, 0)] = 0.161;
        jac[(2, 1)] = 0.0;
        jac[(2, 2)] = -0.161;
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::jacobian::JacobianEvaluator;
    use crate::stats::Stats;
    use faer::Mat;

    #[test]
    fn analytic_jacobians_match_finite_differences() {
        for name in NAMES {
            let p = by_name(name).unwrap();
            let sys = &*p.system;
            let n = sys.dim();
            assert_eq!(n, p.y0.len());
            assert_eq!(n, p.reference.len());
            // A generic interior point (the initial values have zeros that hide terms).
            let y: Vec<f64> =
                p.y0.iter()
                    .enumerate()
                    .map(|(i, v)| v + 0.3 + 0.1 * i as f64)
                    .collect();
            let mut f0 = vec![0.0; n];
            sys.rhs(0.0, &y, &mut f0);
            let mut exact = Mat::<f64>::zeros(n, n);
            sys.jacobian(0.0, &y, exact.as_mut());
            let mut fd = Mat::<f64>::zeros(n, n);
            JacobianEvaluator::new(vec![1.0; n]).finite_difference(
                sys,
                0.0,
                &y,
                &f0,
                fd.as_mut(),
                &mut Stats::default(),
            );
            // Forward differences with δ ≈ 1.5e-8 are good to ~1e-7 relative to the row scale.
            for i in 0..n {
                let row: f64 = (0..n).map(|j| exact[(i, j)].abs()).fold(0.0, f64::max);
                for j in 0..n {
                    let e = (fd[(i, j)] - exact[(i, j)]).abs();
                    assert!(e <= 1e-6 * row.max(1.0), "{name}: J[{i},{j}] off by {e}");
                }
            }
        }
    }

    #[test]
    fn reference_error_counts_only_components_above_atol() {
        let r = [1.0, 1e-12, -2.0];
        assert_eq!(reference_error(&[1.0, 5.0, -2.0], &r, 1e-10), 0.0);
        assert!((reference_error(&[1.001, 0.0, -2.0], &r, 1e-10) - 1e-3).abs() < 1e-12);
        assert_eq!(
            reference_error(&[f64::NAN, 0.0, -2.0], &r, 1e-10),
            f64::INFINITY
        );
        assert_eq!(reference_error(&[1.0], &r, 1e-10), f64::INFINITY);
        assert!(by_name("nope").is_none());
    }
}
