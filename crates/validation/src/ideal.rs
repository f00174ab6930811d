//! The ideal (clearance-free) slider-crank in closed form.
//!
//! ```text
//! θ = crank angle, S = sqrt(l² − r² sin²θ)
//! x  = r cos θ + S
//! ẋ  = −r ω sin θ (1 + r cos θ / S)
//! ẍ  = −r ω² cos θ − r² ω² cos 2θ / S − r⁴ ω² sin²θ cos²θ / S³
//! ẍ(θ=0) = −r ω² (1 + r/l),   ẍ(θ=π) = r ω² (1 − r/l)
//! ```
//!
//! Source: MODEL.md §5 (the paper's Figure 3 mechanism at constant crank speed ω).

use crate::error::Error;

/// A slider-crank with crank radius `r`, rod length `l`, constant crank speed `omega`, the
/// slider moving along the line through the crank pivot.
///
/// ```text
/// x(θ) = r cos θ + sqrt(l² − r² sin²θ),  0 < r < l
/// ```
///
/// Source: MODEL.md §5.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IdealSliderCrank {
    /// Crank radius r, m (> 0).
    pub r: f64,
    /// Rod length l, m (> r).
    pub l: f64,
    /// Crank speed ω, rad/s (finite).
    pub omega: f64,
}

impl IdealSliderCrank {
    /// Checks 0 < r < l and a finite ω.
    pub fn new(r: f64, l: f64, omega: f64) -> Result<Self, Error> {
        if !(r > 0.0 && l > r && l.is_finite() && omega.is_finite()) {
            return Err(Error::Input(format!(
                "ideal slider-crank needs 0 < r < l and finite ω, got r = {r}, l = {l}, ω = {omega}"
            )));
        }
        Ok(IdealSliderCrank { r, l, omega })
    }

    /// From a crank speed in rpm (ω = 2π rpm / 60).
    pub fn from_rpm(r: f64, l: f64, rpm: f64) -> Result<Self, Error> {
        IdealSliderCrank::new(r, l, rpm * std::f64::consts::PI / 30.0)
    }

    fn s(&self, theta: f64) -> f64 {
        let rs = self.r * theta.sin();
        (self.l * self.l - rs * rs).sqrt()
    }

    /// Slider position x(θ), m.
    pub fn x(&self, theta: f64) -> f64 {
        self.r * theta.cos() + self.s(theta)
    }

    /// Slider velocity ẋ(θ), m/s.
    pub fn v(&self, theta: f64) -> f64 {
        let (sn, cs) = theta.sin_cos();
        -self.r * self.omega * sn * (1.0 + self.r * cs / self.s(theta))
    }

    /// Slider acceleration ẍ(θ), m/s².
    pub fn a(&self, theta: f64) -> f64 {
        let (sn, cs) = theta.sin_cos();
        let s = self.s(theta);
        let (r, w2) = (self.r, self.omega * self.omega);
        -r * w2 * cs
            - r * r * w2 * (2.0 * theta).cos() / s
            - r.powi(4) * w2 * sn * sn * cs * cs / s.powi(3)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dead_centre_accelerations_match_model_md() {
        // MODEL.md §5: r = 15 mm, l = 350 mm, ẍ(θ=0) at 120, 150, 180, 200 rpm.
        for (rpm, a0) in [
            (120.0, -2.47022),
            (150.0, -3.85972),
            (180.0, -5.55800),
            (200.0, -6.86172),
        ] {
            let m = IdealSliderCrank::from_rpm(0.015, 0.350, rpm).unwrap();
            assert!((m.a(0.0) - a0).abs() < 5e-6, "{rpm}: {}", m.a(0.0));
            let w2 = m.omega * m.omega;
            assert!((m.a(std::f64::consts::PI) - 0.015 * w2 * (1.0 - 0.015 / 0.35)).abs() < 1e-12);
        }
    }

    #[test]
    fn velocity_and_acceleration_are_time_derivatives() {
        // Central differences in θ: dx/dt = ω dx/dθ, error O(h²) ≈ 1e-10 relative.
        let m = IdealSliderCrank::from_rpm(0.015, 0.350, 150.0).unwrap();
        let h = 1e-5;
        for k in 0..24 {
            let th = 0.3 + k as f64 * 0.27;
            let dx = m.omega * (m.x(th + h) - m.x(th - h)) / (2.0 * h);
            let dv = m.omega * (m.v(th + h) - m.v(th - h)) / (2.0 * h);
            assert!((dx - m.v(th)).abs() < 1e-9, "θ = {th}");
            assert!((dv - m.a(th)).abs() < 1e-8, "θ = {th}");
        }
        assert!((m.x(0.0) - 0.365).abs() < 1e-15);
    }

    #[test]
    fn rejects_impossible_geometry() {
        assert!(IdealSliderCrank::new(0.4, 0.35, 1.0).is_err());
        assert!(IdealSliderCrank::new(0.0, 0.35, 1.0).is_err());
        assert!(IdealSliderCrank::new(0.01, 0.35, f64::NAN).is_err());
    }
}
