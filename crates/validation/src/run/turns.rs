//! Once-per-revolution section times of a crank, whatever turns it: `lash poincare` and
//! `lash run --until-periodic` take their sections here.
//!
//! ```text
//! driven crank (crank_driver, T = 2π/|ω|)   t_k = t_0 + kT
//! crank that is not driven (roles.crank)     φ(t_k) = φ_0 + 2πk·s, the first crossing after
//!                                            t_{k−1}; s = sign φ̇(t_0) (or, if the crank starts
//!                                            at rest, the sign of φ − φ_0 once it has turned
//!                                            half a revolution); located by bisection to the
//!                                            last bit on the step's dense output
//! horizon (not driven)                       the integration is given up at
//!                                            t_0 + HORIZON_FACTOR·K·2π/|φ̇(t_0)|  (K turns);
//!                                            a crank at rest at t_0 has no horizon: an error
//! ```
//!
//! A motor-driven mechanism is autonomous: its period is the time the crank takes for a turn,
//! known only as the run goes, so the section is taken on the crank angle, not on time.
//!
//! Source: docs/outputs.md (`lash poincare`, `until_periodic`); J. Guckenheimer, P. Holmes,
//! *Nonlinear Oscillations, Dynamical Systems, and Bifurcations of Vector Fields*, Springer
//! 1983, §1.4 (sections of autonomous flows on a transversal surface).

use std::f64::consts::{PI, TAU};

use lash_model::Mechanism;

use crate::error::Error;

/// How far a crank that is not driven may lag its starting speed before a run of K turns
/// is given up: the horizon is this many times K turns at the starting speed.
pub(crate) const HORIZON_FACTOR: f64 = 4.0;

/// The section of a crank that is not driven: φ_0, the turning direction s and the turns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Turns {
    phi0: f64,
    /// s = ±1, or 0 until known.
    dir: f64,
    /// |φ̇(t_0)|, rad/s.
    rate0: f64,
}

impl Turns {
    /// The crank of `mech` at (t0, y0); None without a crank angle.
    pub(crate) fn new(mech: &Mechanism, t0: f64, y0: &[f64]) -> Option<Turns> {
        let o = mech.outputs(t0, y0);
        let (phi0, rate) = (o.crank_angle?, o.crank_rate?);
        Some(Turns {
            phi0,
            dir: if rate != 0.0 { rate.signum() } else { 0.0 },
            rate0: rate.abs(),
        })
    }

    /// The end of the integration of `turns` turns (module doc); None for a crank at rest.
    pub(crate) fn horizon(&self, t0: f64, turns: usize) -> Option<f64> {
        (self.rate0 > 0.0 && self.rate0.is_finite())
            .then(|| t0 + HORIZON_FACTOR * turns.max(1) as f64 * TAU / self.rate0)
    }

    /// An option or usage error for a crank at rest at t0 (`what` names the command).
    pub(crate) fn at_rest(what: &str, case: &str) -> Error {
        Error::Usage(format!(
            "{what}: the crank of {case} is at rest at the start, so a turn has no time scale; \
             give the crank an initial rate (joints[i].initial_rate or the body's \
             angular_velocity)"
        ))
    }

    /// The time of turn k ≥ 1 in the step [ta, tb] (ta after turn k − 1), if the crank angle
    /// `phi(t)` (the step's dense output) reaches φ_0 + 2πk·s there.
    pub(crate) fn crossing(
        &mut self,
        k: usize,
        ta: f64,
        tb: f64,
        phi: &mut dyn FnMut(f64) -> f64,
    ) -> Option<f64> {
        let end = phi(tb);
        if self.dir == 0.0 {
            if (end - self.phi0).abs() < PI {
                return None;
            }
            self.dir = (end - self.phi0).signum();
        }
        let target = self.phi0 + self.dir * TAU * k as f64;
        let g = |v: f64| self.dir * (v - target);
        if g(end) < 0.0 {
            return None;
        }
        let (mut a, mut b) = (ta, tb);
        if g(phi(a)) >= 0.0 {
            return Some(a);
        }
        loop {
            let m = 0.5 * (a + b);
            if m <= a || m >= b {
                return Some(b);
            }
            if g(phi(m)) >= 0.0 {
                b = m;
            } else {
                a = m;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn turns(dir: f64) -> Turns {
        Turns {
            phi0: 0.5,
            dir,
            rate0: 2.0,
        }
    }

    /// φ(t) = 0.5 + 2t (a crank at 2 rad/s from φ_0 = 0.5): turn k at t = πk, to the last bit;
    /// a step short of the target has none; backwards φ = 0.5 − 2t crosses at the same times.
    #[test]
    fn crossing_of_a_uniform_turn() {
        let mut tr = turns(1.0);
        let t1 = tr.crossing(1, 3.0, 3.5, &mut |t| 0.5 + 2.0 * t).unwrap();
        assert!((t1 - PI).abs() <= 4.0 * f64::EPSILON * PI, "{t1}");
        assert_eq!(tr.crossing(2, 3.5, 6.0, &mut |t| 0.5 + 2.0 * t), None);
        let t2 = tr.crossing(2, 6.0, 6.5, &mut |t| 0.5 + 2.0 * t).unwrap();
        assert!((t2 - 2.0 * PI).abs() <= 4.0 * f64::EPSILON * TAU, "{t2}");
        let mut back = turns(-1.0);
        let t1 = back.crossing(1, 3.0, 3.5, &mut |t| 0.5 - 2.0 * t).unwrap();
        assert!((t1 - PI).abs() <= 4.0 * f64::EPSILON * PI, "{t1}");
        // Horizon: 4 K turns at 2 rad/s.
        assert_eq!(tr.horizon(1.0, 3), Some(1.0 + 4.0 * 3.0 * PI));
    }

    /// A crank at rest learns its direction once it has turned half a revolution (here
    /// backwards) and has no horizon.
    #[test]
    fn a_crank_at_rest_learns_its_direction() {
        let mut tr = Turns {
            phi0: 0.0,
            dir: 0.0,
            rate0: 0.0,
        };
        assert_eq!(tr.horizon(0.0, 5), None);
        assert_eq!(tr.crossing(1, 0.0, 1.0, &mut |t| -t * t), None);
        assert_eq!(tr.dir, 0.0);
        assert_eq!(tr.crossing(1, 1.0, 2.0, &mut |t| -t * t), None);
        assert_eq!(tr.dir, -1.0);
        let t1 = tr.crossing(1, 2.0, 3.0, &mut |t| -t * t).unwrap();
        assert!((t1 - TAU.sqrt()).abs() <= 4.0 * f64::EPSILON * 3.0, "{t1}");
    }
}
