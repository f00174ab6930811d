//! Force laws of the clearance joint: normal contact (MODEL.md §3), friction (§3) and the
//! hydrodynamic film (§4). Each law is a small `Copy` value with a pure `force` method.

use serde::{Deserialize, Serialize};

/// ADAMS STEP(δ, 0, 0, d_max, c_max): the damping coefficient of the IMPACT law.
///
/// ```text
/// C(δ) = c_max · s² (3 − 2s),  s = min(δ/d_max, 1)  (δ ≥ 0; 0 for δ ≤ 0)
/// ```
/// MSC Adams function reference, STEP and IMPACT.
#[inline]
pub fn step_damping(delta: f64, d_max: f64, c_max: f64) -> f64 {
    if delta <= 0.0 {
        return 0.0;
    }
    let s = (delta / d_max).min(1.0);
    c_max * s * s * (3.0 - 2.0 * s)
}

/// Hertz stiffness of a pin in a hole from the materials (MODEL.md §3).
///
/// ```text
/// K = 4 / (3(σ_B + σ_J)) · sqrt(R_B R_J / (R_B − R_J)),  σ_k = (1 − ν_k²)/E_k
/// ```
pub fn hertz_stiffness(
    radius_b: f64,
    radius_j: f64,
    e_b: f64,
    nu_b: f64,
    e_j: f64,
    nu_j: f64,
) -> f64 {
    let sigma_b = (1.0 - nu_b * nu_b) / e_b;
    let sigma_j = (1.0 - nu_j * nu_j) / e_j;
    4.0 / (3.0 * (sigma_b + sigma_j)) * (radius_b * radius_j / (radius_b - radius_j)).sqrt()
}

/// Impact velocities below this are treated as "no impact recorded": the restitution laws then
/// act elastically (their damping term divides by δ̇⁻).
pub const MIN_IMPACT_VELOCITY: f64 = 1e-12;

/// Normal contact force law, called only with δ > 0; the force is clipped at 0 (no adhesion).
///
/// ```text
/// Impact              F_N = K δ^{3/2} + C(δ) δ̇,  C = STEP(δ, 0, 0, d_max, c_max)   (MSC Adams)
/// LankaraniNikravesh  F_N = K δ^{3/2} [1 + 3(1 − c_r²) δ̇ / (4 δ̇⁻)]                 (1990)
/// Flores              F_N = K δ^{3/2} [1 + 8(1 − c_r) δ̇ / (5 c_r δ̇⁻)]              (2011)
/// HuntCrossley        F_N = K δ^{3/2} [1 + 3(1 − c_r) δ̇ / (2 δ̇⁻)]                  (1975)
/// ```
/// δ̇⁻ is the normal velocity stored at the last contact onset (event hook).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NormalLaw {
    /// ADAMS IMPACT with STEP damping (the paper's law).
    Impact {
        /// Stiffness K (N/m^1.5).
        k: f64,
        /// Maximum damping c_max (N·s/m).
        c_max: f64,
        /// Penetration of full damping d_max (m).
        d_max: f64,
    },
    /// Lankarani–Nikravesh hysteresis damping.
    LankaraniNikravesh {
        /// Stiffness K (N/m^1.5).
        k: f64,
        /// Coefficient of restitution c_r in (0, 1].
        restitution: f64,
    },
    /// Flores et al. 2011 hysteresis damping.
    Flores {
        /// Stiffness K (N/m^1.5).
        k: f64,
        /// Coefficient of restitution c_r in (0, 1].
        restitution: f64,
    },
    /// Hunt–Crossley hysteresis damping.
    HuntCrossley {
        /// Stiffness K (N/m^1.5).
        k: f64,
        /// Coefficient of restitution c_r in (0, 1].
        restitution: f64,
    },
}

impl NormalLaw {
    /// Stiffness K.
    pub fn stiffness(&self) -> f64 {
        match *self {
            NormalLaw::Impact { k, .. }
            | NormalLaw::LankaraniNikravesh { k, .. }
            | NormalLaw::Flores { k, .. }
            | NormalLaw::HuntCrossley { k, .. } => k,
        }
    }

    /// Whether the law needs the impact velocity δ̇⁻ stored at contact onset.
    pub fn needs_impact_velocity(&self) -> bool {
        !matches!(self, NormalLaw::Impact { .. })
    }

    /// Normal force magnitude F_N ≥ 0 for penetration `delta` (> 0 expected; 0 returned
    /// otherwise), normal velocity `delta_dot` and stored impact velocity `impact_velocity`.
    #[inline]
    pub fn force(&self, delta: f64, delta_dot: f64, impact_velocity: f64) -> f64 {
        if delta <= 0.0 {
            return 0.0;
        }
        let k = self.stiffness();
        let elastic = k * delta * delta.sqrt();
        let v_minus = impact_velocity.abs();
        let hyst = |coef: f64| {
            if v_minus < MIN_IMPACT_VELOCITY {
                elastic
            } else {
                elastic * (1.0 + coef * delta_dot / v_minus)
            }
        };
        let f = match *self {
            NormalLaw::Impact { c_max, d_max, .. } => {
                elastic + step_damping(delta, d_max, c_max) * delta_dot
            }
            NormalLaw::LankaraniNikravesh {
                restitution: cr, ..
            } => hyst(3.0 * (1.0 - cr * cr) / 4.0),
            NormalLaw::Flores {
                restitution: cr, ..
            } => hyst(8.0 * (1.0 - cr) / (5.0 * cr)),
            NormalLaw::HuntCrossley {
                restitution: cr, ..
            } => hyst(3.0 * (1.0 - cr) / 2.0),
        };
        f.max(0.0)
    }

    /// Elastic contact potential 2/5 · K · δ^{5/2} (0 for δ ≤ 0), J.
    #[inline]
    pub fn potential(&self, delta: f64) -> f64 {
        if delta <= 0.0 {
            0.0
        } else {
            0.4 * self.stiffness() * delta * delta * delta.sqrt()
        }
    }
}

/// Friction law at the contact.
///
/// ```text
/// F_T = −μ_d · c_d(|v_T|) · F_N · sign(v_T)
/// c_d = 0 (|v_T| ≤ v₀);  (|v_T| − v₀)/(v₁ − v₀) (v₀ < |v_T| < v₁);  1 (|v_T| ≥ v₁)
/// ```
/// Coulomb friction with Ambrósio's dynamic correction (Ambrósio 2002).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum FrictionLaw {
    /// Frictionless.
    None,
    /// Coulomb with dynamic correction.
    Coulomb {
        /// Dynamic friction coefficient μ_d.
        mu: f64,
        /// Speed below which no friction acts, v₀ (m/s).
        v0: f64,
        /// Speed above which full friction acts, v₁ (m/s).
        v1: f64,
    },
}

impl FrictionLaw {
    /// Ambrósio's correction coefficient c_d(|v|) (1 for v₀ = v₁ ≤ |v|).
    #[inline]
    pub fn cd(v: f64, v0: f64, v1: f64) -> f64 {
        let v = v.abs();
        if v <= v0 {
            0.0
        } else if v >= v1 {
            1.0
        } else {
            (v - v0) / (v1 - v0)
        }
    }

    /// Tangential force F_T (signed along t) for slip `v_t` and normal force `f_n`.
    #[inline]
    pub fn force(&self, v_t: f64, f_n: f64) -> f64 {
        match *self {
            FrictionLaw::None => 0.0,
            FrictionLaw::Coulomb { mu, v0, v1 } => {
                if v_t == 0.0 {
                    0.0
                } else {
                    -mu * Self::cd(v_t, v0, v1) * f_n * v_t.signum()
                }
            }
        }
    }
}

/// Which hydrodynamic film model (MODEL.md §4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FilmModel {
    /// Infinitely long bearing, Gümbel conditions, as the paper prints it (default).
    LongGumbel,
    /// Long Gümbel with the positive-pressure half kept on the side the wedge acts.
    LongGumbelMirrored,
    /// Infinitely long bearing, full Sommerfeld conditions.
    LongSommerfeld,
    /// Short (Ocvirk) bearing, Gümbel conditions.
    ShortOcvirk,
    /// Short bearing with the mirroring of `long_gumbel_mirrored`.
    ShortOcvirkMirrored,
}

/// A hydrodynamic film: model and bearing data.
///
/// ```text
/// long Gümbel (S = 12 μ L R³ / c²):
///   F_r = −S [ ε² Ω / ((2+ε²)(1−ε²)) + ε̇ (π/2 − 8/(π(2+ε²))) / (1−ε²)^{3/2} ]
///   F_t =  S [ π ε Ω / (2(2+ε²)(1−ε²)^{1/2}) + 2 ε ε̇ / ((2+ε²)(1−ε²)) ]
/// long Sommerfeld:
///   F_r = −12πμLR³ ε̇ / (c²(1−ε²)^{3/2}),  F_t = 12πμLR³ ε Ω / (c²(2+ε²)(1−ε²)^{1/2})
/// short Ocvirk (S = μ R L³ / (2c²)):
///   F_r = −S [ 2ε²Ω/(1−ε²)² + π(1+2ε²)ε̇/(1−ε²)^{5/2} ]
///   F_t =  S [ πεΩ/(2(1−ε²)^{3/2}) + 4εε̇/(1−ε²)² ]
/// mirrored: F_r(ε, ε̇, |Ω|), F_t = sign(Ω)·F_t(ε, ε̇, |Ω|)  (sign(0) = +1)
/// ε is capped: ε_eff = min(ε, ε_cap); (1−ε²)^{−k} is never evaluated at ε ≥ 1.
/// ```
/// f_J = F_r n + F_t t on the journal, −f_J on the bearing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Film {
    /// The model.
    pub model: FilmModel,
    /// Dynamic viscosity μ (Pa·s).
    pub viscosity: f64,
    /// Bearing length L (m).
    pub length: f64,
    /// Journal radius R = R_J (m).
    pub radius: f64,
    /// Radial clearance c (m).
    pub clearance: f64,
    /// Eccentricity cap ε_cap in (0, 1).
    pub eps_cap: f64,
}

impl Film {
    /// Film force (F_r, F_t) on the journal, radial along n and tangential along t (N).
    #[inline]
    pub fn force(&self, eps: f64, eps_dot: f64, omega: f64) -> (f64, f64) {
        let e = eps.min(self.eps_cap).max(0.0);
        let (mirrored, om) = match self.model {
            FilmModel::LongGumbelMirrored | FilmModel::ShortOcvirkMirrored => (true, omega.abs()),
            _ => (false, omega),
        };
        let (mu, l, r, c) = (self.viscosity, self.length, self.radius, self.clearance);
        let e2 = e * e;
        let one = 1.0 - e2;
        let pi = std::f64::consts::PI;
        let (fr, ft) = match self.model {
            FilmModel::LongGumbel | FilmModel::LongGumbelMirrored => {
                let s = 12.0 * mu * l * r * r * r / (c * c);
                let fr = -s
                    * (e2 * om / ((2.0 + e2) * one)
                        + eps_dot * (pi / 2.0 - 8.0 / (pi * (2.0 + e2))) / (one * one.sqrt()));
                let ft = s
                    * (pi * e * om / (2.0 * (2.0 + e2) * one.sqrt())
                        + 2.0 * e * eps_dot / ((2.0 + e2) * one));
                (fr, ft)
            }
            FilmModel::LongSommerfeld => {
                let s = 12.0 * pi * mu * l * r * r * r / (c * c);
                (
                    -s * eps_dot / (one * one.sqrt()),
                    s * e * om / ((2.0 + e2) * one.sqrt()),
                )
            }
            FilmModel::ShortOcvirk | FilmModel::ShortOcvirkMirrored => {
                let s = mu * r * l * l * l / (2.0 * c * c);
                let fr = -s
                    * (2.0 * e2 * om / (one * one)
                        + pi * (1.0 + 2.0 * e2) * eps_dot / (one * one * one.sqrt()));
                let ft =
                    s * (pi * e * om / (2.0 * one * one.sqrt()) + 4.0 * e * eps_dot / (one * one));
                (fr, ft)
            }
        };
        if mirrored && omega < 0.0 {
            (fr, -ft)
        } else {
            (fr, ft)
        }
    }
}
