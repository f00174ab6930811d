//! Force laws of the clearance joint: normal contact (docs/model.md §3), friction (§3) and the
//! hydrodynamic film (§4). Each law is a small `Copy` value with a pure `force` method.

use serde::{Deserialize, Serialize};

/// A force-law parameter outside its valid range.
///
/// ```text
/// K > 0, c_max ≥ 0, d_max > 0, 0 < c_r ≤ 1              (normal laws, docs/model.md §3)
/// μ_d ≥ 0, 0 ≤ v₀ ≤ v₁                                  (friction, docs/model.md §3)
/// μ > 0, L > 0, R > 0, c > 0, 0 < ε_cap < 1             (film, docs/model.md §4)
/// ```
/// A scene's film may have μ = 0, a zero film (docs/model.md §4); the law itself asks for μ > 0.
/// Every value must also be finite. Ranges follow from the laws of docs/model.md §3–§4: outside
/// them a force is infinite, NaN or unphysical (negative damping, c_r = 0 in Flores' 1/c_r).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{law}: {parameter} = {value} is outside its valid range {range}")]
pub struct LawError {
    /// The law (`impact`, `lankarani_nikravesh`, `flores`, `hunt_crossley`, `coulomb`, `film`).
    pub law: &'static str,
    /// The parameter's symbol.
    pub parameter: &'static str,
    /// The offending value.
    pub value: f64,
    /// The valid range, as text.
    pub range: &'static str,
}

/// `Ok` when `ok` holds and `value` is finite, else the [`LawError`].
fn check(
    law: &'static str,
    parameter: &'static str,
    value: f64,
    ok: bool,
    range: &'static str,
) -> Result<(), LawError> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(LawError {
            law,
            parameter,
            value,
            range,
        })
    }
}

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

/// dC/dδ of [`step_damping`]: 6 c_max s (1 − s) / d_max for 0 < δ < d_max, else 0 (the
/// one-sided slopes at the kinks δ = 0 and δ = d_max are both 0).
#[inline]
pub fn step_damping_slope(delta: f64, d_max: f64, c_max: f64) -> f64 {
    if delta <= 0.0 || delta >= d_max {
        return 0.0;
    }
    let s = delta / d_max;
    6.0 * c_max * s * (1.0 - s) / d_max
}

/// Hertz stiffness of a pin in a hole from the materials (docs/model.md §3).
///
/// ```text
/// K = 4 / (3(σ_B + σ_J)) · sqrt(R_B R_J / (R_B − R_J)),  σ_k = (1 − ν_k²)/E_k
/// ```
/// The Hertz sphere-in-sphere stiffness with the conformal radius R_B R_J/(R_B − R_J), as used
/// for revolute clearance joints by Flores, Ambrósio, Claro and Lankarani (Kinematics and
/// Dynamics of Multibody Systems with Imperfect Joints, Springer 2008). Needs
/// R_B > R_J > 0, E_k > 0, ν_k in (−1, 1); the scene validates these before calling.
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

    /// Checks the parameters: K > 0; c_max ≥ 0 and d_max > 0 (IMPACT); 0 < c_r ≤ 1 (the
    /// restitution laws). All finite.
    pub fn validate(&self) -> Result<(), LawError> {
        let (law, k) = match *self {
            NormalLaw::Impact { k, .. } => ("impact", k),
            NormalLaw::LankaraniNikravesh { k, .. } => ("lankarani_nikravesh", k),
            NormalLaw::Flores { k, .. } => ("flores", k),
            NormalLaw::HuntCrossley { k, .. } => ("hunt_crossley", k),
        };
        check(law, "K", k, k > 0.0, "(0, ∞)")?;
        match *self {
            NormalLaw::Impact { c_max, d_max, .. } => {
                check(law, "c_max", c_max, c_max >= 0.0, "[0, ∞)")?;
                check(law, "d_max", d_max, d_max > 0.0, "(0, ∞)")
            }
            NormalLaw::LankaraniNikravesh { restitution, .. }
            | NormalLaw::Flores { restitution, .. }
            | NormalLaw::HuntCrossley { restitution, .. } => check(
                law,
                "c_r",
                restitution,
                restitution > 0.0 && restitution <= 1.0,
                "(0, 1]",
            ),
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
            _ => hyst(self.hysteresis_coefficient()),
        };
        f.max(0.0)
    }

    /// The partial derivatives (∂F_N/∂δ, ∂F_N/∂δ̇) of [`NormalLaw::force`] at fixed δ̇⁻:
    ///
    /// ```text
    /// Impact:           (3/2 K δ^{1/2} + C'(δ) δ̇,  C(δ))
    /// restitution laws: (3/2 K δ^{1/2} r,  K δ^{3/2} coef/δ̇⁻),  r = 1 + coef δ̇/δ̇⁻
    /// ```
    /// (0, 0) for δ ≤ 0 and where the force is clipped at 0; at the kinks (δ = d_max, the
    /// clip) the one-sided derivative of the side the arguments lie on.
    #[inline]
    pub fn force_derivatives(&self, delta: f64, delta_dot: f64, impact_velocity: f64) -> [f64; 2] {
        if delta <= 0.0 || self.force(delta, delta_dot, impact_velocity) <= 0.0 {
            return [0.0, 0.0];
        }
        let k = self.stiffness();
        let sq = delta.sqrt();
        let elastic = k * delta * sq;
        let d_elastic = 1.5 * k * sq;
        match *self {
            NormalLaw::Impact { c_max, d_max, .. } => [
                d_elastic + step_damping_slope(delta, d_max, c_max) * delta_dot,
                step_damping(delta, d_max, c_max),
            ],
            _ => {
                let v_minus = impact_velocity.abs();
                if v_minus < MIN_IMPACT_VELOCITY {
                    [d_elastic, 0.0]
                } else {
                    let a = self.hysteresis_coefficient() / v_minus;
                    [d_elastic * (1.0 + a * delta_dot), elastic * a]
                }
            }
        }
    }

    /// The coefficient of δ̇/δ̇⁻ of a restitution law: 3(1 − c_r²)/4 (Lankarani–Nikravesh),
    /// 8(1 − c_r)/(5 c_r) (Flores), 3(1 − c_r)/2 (Hunt–Crossley); 0 for IMPACT.
    #[inline]
    fn hysteresis_coefficient(&self) -> f64 {
        match *self {
            NormalLaw::Impact { .. } => 0.0,
            NormalLaw::LankaraniNikravesh {
                restitution: cr, ..
            } => 3.0 * (1.0 - cr * cr) / 4.0,
            NormalLaw::Flores {
                restitution: cr, ..
            } => 8.0 * (1.0 - cr) / (5.0 * cr),
            NormalLaw::HuntCrossley {
                restitution: cr, ..
            } => 3.0 * (1.0 - cr) / 2.0,
        }
    }

    /// Whether the force can reach the clip at 0 during restitution (a damping term that can
    /// outweigh the elastic one): c_max > 0 for IMPACT, c_r < 1 for the restitution laws.
    pub fn can_clip(&self) -> bool {
        match *self {
            NormalLaw::Impact { c_max, .. } => c_max > 0.0,
            NormalLaw::LankaraniNikravesh { restitution, .. }
            | NormalLaw::Flores { restitution, .. }
            | NormalLaw::HuntCrossley { restitution, .. } => restitution < 1.0,
        }
    }

    /// The unclipped force over its elastic part, for δ > 0 (1 for δ ≤ 0):
    ///
    /// ```text
    /// r = (K δ^{3/2} + D(δ, δ̇)) / (K δ^{3/2}),  F_N = max(K δ^{3/2} r, 0)
    /// Impact: r = 1 + C(δ) δ̇ / (K δ^{3/2});  restitution laws: r = 1 + coef · δ̇ / δ̇⁻
    /// ```
    /// r changes sign exactly where the clip of F_N at 0 starts or ends acting (a kink of the
    /// force in time). For IMPACT, C(δ)/δ^{3/2} → 0 as δ → 0, so r is continuous at contact
    /// onset and loss.
    #[inline]
    pub fn unclipped_ratio(&self, delta: f64, delta_dot: f64, impact_velocity: f64) -> f64 {
        if delta <= 0.0 {
            return 1.0;
        }
        let v_minus = impact_velocity.abs();
        let hyst = |coef: f64| {
            if v_minus < MIN_IMPACT_VELOCITY {
                1.0
            } else {
                1.0 + coef * delta_dot / v_minus
            }
        };
        match *self {
            NormalLaw::Impact { k, c_max, d_max } => {
                1.0 + step_damping(delta, d_max, c_max) * delta_dot / (k * delta * delta.sqrt())
            }
            _ => hyst(self.hysteresis_coefficient()),
        }
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
    /// Checks the parameters: μ_d ≥ 0 and 0 ≤ v₀ ≤ v₁, all finite (`None` is always valid).
    pub fn validate(&self) -> Result<(), LawError> {
        match *self {
            FrictionLaw::None => Ok(()),
            FrictionLaw::Coulomb { mu, v0, v1 } => {
                check("coulomb", "mu_d", mu, mu >= 0.0, "[0, ∞)")?;
                check("coulomb", "v0", v0, v0 >= 0.0, "[0, v1]")?;
                check("coulomb", "v1", v1, v1 >= v0, "[v0, ∞)")
            }
        }
    }

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

    /// The partial derivatives (∂F_T/∂v_T, ∂F_T/∂F_N) of [`FrictionLaw::force`]:
    ///
    /// ```text
    /// (−μ_d c_d'(|v_T|) F_N,  −μ_d c_d(|v_T|) sign(v_T)),  c_d' = 1/(v₁ − v₀) on v₀ < |v_T| < v₁, else 0
    /// ```
    /// At v_T = 0 with v₀ = 0 < v₁ the slope −μ_d F_N / v₁ (the law is linear through 0 there);
    /// pure Coulomb (v₀ = v₁) has no derivative at 0 and gets 0.
    #[inline]
    pub fn force_derivatives(&self, v_t: f64, f_n: f64) -> [f64; 2] {
        match *self {
            FrictionLaw::None => [0.0, 0.0],
            FrictionLaw::Coulomb { mu, v0, v1 } => {
                let v = v_t.abs();
                let slope = if v1 > v0 && ((v > v0 && v < v1) || (v == 0.0 && v0 == 0.0)) {
                    1.0 / (v1 - v0)
                } else {
                    0.0
                };
                let by_fn = if v_t == 0.0 {
                    0.0
                } else {
                    -mu * Self::cd(v_t, v0, v1) * v_t.signum()
                };
                [-mu * slope * f_n, by_fn]
            }
        }
    }
}

/// Which hydrodynamic film model (docs/model.md §4).
///
/// ```text
/// long_gumbel             infinitely long bearing, Gümbel (half-Sommerfeld), as printed
/// long_gumbel_mirrored    (F_r, F_t)(ε, ε̇, Ω) = (F_r, sign(Ω) F_t)(ε, ε̇, |Ω|) of long_gumbel,
///                         sign smoothed: tanh(Ω/Ω₀) (formulas on [`Film`])
/// long_sommerfeld         infinitely long bearing, full Sommerfeld
/// short_ocvirk            short (Ocvirk) bearing, Gümbel conditions
/// short_ocvirk_mirrored   the same mirroring applied to short_ocvirk
/// ```
/// Formulas on [`Film`]; Peng et al. 2025 §2.3 (long Gümbel, with R³ for R²), docs/model.md §4.
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

/// Width Ω₀ of the smooth sign of the mirrored film models when the scene gives none, rad/s
/// (docs/model.md §4, "The mirrored models").
pub const DEFAULT_MIRROR_WIDTH: f64 = 0.01;

/// The guard of a film without a cap: the law is evaluated at min(ε, 1 − η) with η = 1e-12
/// (docs/model.md §4, "A film without a cap"). Not a model parameter: the exact motion under a
/// bounded load never reaches it, and positions in f64 resolve ε only to about
/// 2.2e-16 · |r|/c, 1e-13 for the press.
pub const UNCAPPED_GUARD: f64 = 1e-12;

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
/// each law is F_r = −S (a_r(ε) Ω + b_r(ε) ε̇),  F_t = S (a_t(ε) Ω + b_t(ε) ε̇);
/// mirrored:  F_r = −S (a_r |Ω|_s + b_r ε̇),  F_t = S (a_t Ω + s(Ω) b_t ε̇),
///            s(Ω) = tanh(Ω/Ω₀),  |Ω|_s = Ω s(Ω)   (s = sign(Ω) in f64 for |Ω| ≥ 19.1 Ω₀)
/// ε is replaced by ε_eff = min(ε, ε_cap), or by min(ε, 1 − η) without a cap (η = 1e-12);
/// (1−ε²)^{−k} is never evaluated at ε ≥ 1.
/// ```
/// f_J = F_r n + F_t t on the journal, −f_J on the bearing. Long bearing with Gümbel
/// conditions: Peng et al. 2025 §2.3 (printed with R² for R³); full Sommerfeld and short
/// (Ocvirk) bearing: docs/model.md §4, checked there against a numerical Reynolds solution and
/// MBDyn's bearing models.
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
    /// Eccentricity cap ε_cap in (0, 1), or `None`: no cap, the law at the true ε up to the
    /// guard 1 − [`UNCAPPED_GUARD`].
    pub eps_cap: Option<f64>,
    /// Width Ω₀ > 0 of the smooth sign of the mirrored models (rad/s); unused by the others.
    pub mirror_width: f64,
}

/// A film's constants ([`Film::constants`]): computed once, read by [`Film::force_with`]
/// (the default, zeros, stands for a joint without a film, where nothing reads them).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct FilmConstants {
    /// The law's scale S (12 μ L R³/c², 12 π μ L R³/c² or μ R L³/(2 c²)).
    pub scale: f64,
    /// [`Film::eps_limit`].
    pub limit: f64,
}

impl Film {
    /// Checks the parameters: μ, L, R, c, Ω₀ > 0 and 0 < ε_cap < 1 (when capped), all finite.
    /// With them, [`Film::force`] is finite for every finite (ε, ε̇, Ω) unless S·ε̇ or S·Ω
    /// exceeds about 1e270 (without a cap the factors at the guard reach 1e36).
    pub fn validate(&self) -> Result<(), LawError> {
        let pos = |p: &'static str, v: f64| check("film", p, v, v > 0.0, "(0, ∞)");
        pos("mu", self.viscosity)?;
        pos("L", self.length)?;
        pos("R", self.radius)?;
        pos("c", self.clearance)?;
        pos("omega0", self.mirror_width)?;
        match self.eps_cap {
            Some(cap) => check("film", "eps_cap", cap, cap > 0.0 && cap < 1.0, "(0, 1)"),
            None => Ok(()),
        }
    }

    /// The largest ε the law is evaluated at: ε_cap, or 1 − η without a cap.
    pub fn eps_limit(&self) -> f64 {
        self.eps_cap.unwrap_or(1.0 - UNCAPPED_GUARD)
    }

    /// Whether the model is one of the mirrored ones.
    pub fn is_mirrored(&self) -> bool {
        matches!(
            self.model,
            FilmModel::LongGumbelMirrored | FilmModel::ShortOcvirkMirrored
        )
    }

    /// The law's constants, S and the largest ε it is evaluated at, by the expressions of
    /// [`Film::force`]: computed once where the film is compiled and handed to
    /// [`Film::force_with`] (the same numbers, so the same bits).
    pub(crate) fn constants(&self) -> FilmConstants {
        let (mu, l, r, c) = (self.viscosity, self.length, self.radius, self.clearance);
        let pi = std::f64::consts::PI;
        FilmConstants {
            scale: match self.model {
                FilmModel::LongGumbel | FilmModel::LongGumbelMirrored => {
                    12.0 * mu * l * r * r * r / (c * c)
                }
                FilmModel::LongSommerfeld => 12.0 * pi * mu * l * r * r * r / (c * c),
                FilmModel::ShortOcvirk | FilmModel::ShortOcvirkMirrored => {
                    mu * r * l * l * l / (2.0 * c * c)
                }
            },
            limit: self.eps_limit(),
        }
    }

    /// Film force (F_r, F_t) on the journal, radial along n and tangential along t (N).
    ///
    /// ε is replaced by ε_eff = min(ε, ε_cap), or min(ε, 1 − η) without a cap (and by 0 if
    /// negative); ε̇ and Ω are used as given. A NaN ε gives NaN forces (it is not hidden).
    #[inline]
    pub fn force(&self, eps: f64, eps_dot: f64, omega: f64) -> (f64, f64) {
        self.force_with(&self.constants(), eps, eps_dot, omega)
    }

    /// [`Film::force`] with its constants `k` computed once ([`Film::constants`] of this film).
    /// (Always inlined: a call from the small-tree right-hand side spilled its registers.)
    #[inline(always)]
    pub(crate) fn force_with(
        &self,
        k: &FilmConstants,
        eps: f64,
        eps_dot: f64,
        omega: f64,
    ) -> (f64, f64) {
        // ε_eff = min(ε, limit), and ε ≥ 0. Written with comparisons rather than
        // `f64::min/max` so that a NaN ε propagates (the solver reports it) instead of being
        // silently replaced by the limit.
        let limit = k.limit;
        let e = if eps > limit {
            limit
        } else if eps < 0.0 {
            0.0
        } else {
            eps
        };
        // Mirrored: |Ω| → Ω s(Ω) in the radial wedge term, sign(Ω) → s(Ω) on the tangential
        // squeeze term; s = tanh(Ω/Ω₀) is exactly ±1 in f64 for |Ω| ≥ 19.1 Ω₀. The printed
        // laws take s = 1 (multiplications by 1 are exact: their arithmetic is unchanged).
        let (sgn, om) = if self.is_mirrored() {
            let s = (omega / self.mirror_width).tanh();
            (s, omega * s)
        } else {
            (1.0, omega)
        };
        let s = k.scale;
        let e2 = e * e;
        // Without a cap ε comes arbitrarily close to 1, where 1 − ε² loses digits; (1 − ε)(1 + ε)
        // keeps them (1 − ε is exact for ε ≥ 1/2). The capped laws keep their arithmetic.
        let one = if self.eps_cap.is_some() {
            1.0 - e2
        } else {
            (1.0 - e) * (1.0 + e)
        };
        let pi = std::f64::consts::PI;
        match self.model {
            FilmModel::LongGumbel | FilmModel::LongGumbelMirrored => {
                let fr = -s
                    * (e2 * om / ((2.0 + e2) * one)
                        + eps_dot * (pi / 2.0 - 8.0 / (pi * (2.0 + e2))) / (one * one.sqrt()));
                let ft = s
                    * (pi * e * omega / (2.0 * (2.0 + e2) * one.sqrt())
                        + sgn * (2.0 * e * eps_dot / ((2.0 + e2) * one)));
                (fr, ft)
            }
            FilmModel::LongSommerfeld => (
                -s * eps_dot / (one * one.sqrt()),
                s * e * omega / ((2.0 + e2) * one.sqrt()),
            ),
            FilmModel::ShortOcvirk | FilmModel::ShortOcvirkMirrored => {
                let fr = -s
                    * (2.0 * e2 * om / (one * one)
                        + pi * (1.0 + 2.0 * e2) * eps_dot / (one * one * one.sqrt()));
                let ft = s
                    * (pi * e * omega / (2.0 * one * one.sqrt())
                        + sgn * (4.0 * e * eps_dot / (one * one)));
                (fr, ft)
            }
        }
    }

    /// The partial derivatives of [`Film::force`] in (ε, ε̇, Ω):
    /// `[[∂F_r/∂ε, ∂F_r/∂ε̇, ∂F_r/∂Ω], [∂F_t/∂ε, ∂F_t/∂ε̇, ∂F_t/∂Ω]]`.
    ///
    /// ```text
    /// F_r = −S (a_r(ε) Ω_s + b_r(ε) ε̇),  F_t = S (a_t(ε) Ω + s(Ω) b_t(ε) ε̇)
    /// (Ω_s = Ω, s = 1 for the printed laws; Ω_s = Ω tanh(Ω/Ω₀), s = tanh(Ω/Ω₀) mirrored)
    /// ∂/∂ε  = ∓S (a' Ω_s + b' ε̇) …,  ∂/∂ε̇ = −S b_r, S s b_t,
    /// ∂F_r/∂Ω = −S a_r dΩ_s/dΩ,  ∂F_t/∂Ω = S (a_t + s'(Ω) b_t ε̇)
    /// a', b' from (1 − ε²)^{−k}' = 2kε (1 − ε²)^{−k−1},  (2 + ε²)^{−1}' = −2ε (2 + ε²)^{−2}
    /// ```
    /// Beyond the cap (or the guard) ε_eff is constant and ∂/∂ε = 0. NaN in, NaN out.
    pub fn force_derivatives(&self, eps: f64, eps_dot: f64, omega: f64) -> [[f64; 3]; 2] {
        let limit = self.eps_limit();
        let (e, de) = if eps > limit {
            (limit, 0.0)
        } else if eps < 0.0 {
            (0.0, 0.0)
        } else {
            (eps, 1.0)
        };
        let (sgn, dsgn, om, dom) = if self.is_mirrored() {
            let s = (omega / self.mirror_width).tanh();
            let ds = (1.0 - s * s) / self.mirror_width;
            (s, ds, omega * s, s + omega * ds)
        } else {
            (1.0, 0.0, omega, 1.0)
        };
        let (scale, [ar, br, at, bt]) = self.coefficients(e);
        [
            [
                -scale * (ar[1] * om + br[1] * eps_dot) * de,
                -scale * br[0],
                -scale * ar[0] * dom,
            ],
            [
                scale * (at[1] * omega + sgn * bt[1] * eps_dot) * de,
                scale * sgn * bt[0],
                scale * (at[0] + dsgn * bt[0] * eps_dot),
            ],
        ]
    }

    /// The law's scale S and its coefficients with their ε-derivatives,
    /// `[(a_r, a_r'), (b_r, b_r'), (a_t, a_t'), (b_t, b_t')]` at ε = `e` (see
    /// [`Film::force_derivatives`]).
    fn coefficients(&self, e: f64) -> (f64, [[f64; 2]; 4]) {
        let (mu, l, r, c) = (self.viscosity, self.length, self.radius, self.clearance);
        let pi = std::f64::consts::PI;
        let e2 = e * e;
        let one = if self.eps_cap.is_some() {
            1.0 - e2
        } else {
            (1.0 - e) * (1.0 + e)
        };
        // Q^k = (1 − ε²)^{−k} and (Q^k)' = 2kε Q^{k+1}; P = 1/(2 + ε²), P' = −2ε P².
        let q = 1.0 / one;
        let q12 = q.sqrt();
        let q32 = q * q12;
        let q52 = q32 * q;
        let p = 1.0 / (2.0 + e2);
        let dp = -2.0 * e * p * p;
        match self.model {
            FilmModel::LongGumbel | FilmModel::LongGumbelMirrored => {
                let s = 12.0 * mu * l * r * r * r / (c * c);
                let dq = 2.0 * e * q * q;
                let g = pi / 2.0 - 8.0 * p / pi;
                (
                    s,
                    [
                        [e2 * p * q, 2.0 * e * p * q + e2 * (dp * q + p * dq)],
                        [g * q32, -8.0 * dp / pi * q32 + g * 3.0 * e * q52],
                        [
                            pi / 2.0 * e * p * q12,
                            pi / 2.0 * (p * q12 + e * dp * q12 + e * p * e * q32),
                        ],
                        [2.0 * e * p * q, 2.0 * (p * q + e * dp * q + e * p * dq)],
                    ],
                )
            }
            FilmModel::LongSommerfeld => {
                let s = 12.0 * pi * mu * l * r * r * r / (c * c);
                (
                    s,
                    [
                        [0.0, 0.0],
                        [q32, 3.0 * e * q52],
                        [e * p * q12, p * q12 + e * dp * q12 + e * p * e * q32],
                        [0.0, 0.0],
                    ],
                )
            }
            FilmModel::ShortOcvirk | FilmModel::ShortOcvirkMirrored => {
                let s = mu * r * l * l * l / (2.0 * c * c);
                let q2 = q * q;
                let q3 = q2 * q;
                let q72 = q52 * q;
                (
                    s,
                    [
                        [2.0 * e2 * q2, 4.0 * e * q2 + 2.0 * e2 * 4.0 * e * q3],
                        [
                            pi * (1.0 + 2.0 * e2) * q52,
                            pi * (4.0 * e * q52 + (1.0 + 2.0 * e2) * 5.0 * e * q72),
                        ],
                        [pi / 2.0 * e * q32, pi / 2.0 * (q32 + e * 3.0 * e * q52)],
                        [4.0 * e * q2, 4.0 * (q2 + e * 4.0 * e * q3)],
                    ],
                )
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// F_N = max(K δ^{3/2} r, 0) for every law, so r changes sign exactly where the clip
    /// starts or ends acting; r → 1 at δ → 0 for IMPACT (continuous at contact onset).
    #[test]
    fn unclipped_ratio_marks_the_clip() {
        let k = 2.34e10;
        let laws = [
            NormalLaw::Impact {
                k,
                c_max: 1e5,
                d_max: 1e-5,
            },
            NormalLaw::LankaraniNikravesh {
                k,
                restitution: 0.5,
            },
            NormalLaw::Flores {
                k,
                restitution: 0.3,
            },
            NormalLaw::HuntCrossley {
                k,
                restitution: 0.5,
            },
        ];
        let v_minus = 0.1;
        for law in laws {
            assert!(law.can_clip());
            let mut clipped = 0;
            for &delta in &[1e-8, 1e-7, 1e-6, 5e-6, 1e-5, 5e-5] {
                for i in -40..=40 {
                    let delta_dot = 0.01 * i as f64;
                    let r = law.unclipped_ratio(delta, delta_dot, v_minus);
                    let elastic = k * delta * delta.sqrt();
                    let f = law.force(delta, delta_dot, v_minus);
                    assert!(
                        (f - (elastic * r).max(0.0)).abs() <= 1e-12 * elastic.max(f),
                        "{law:?} δ {delta} δ̇ {delta_dot}: F {f} against {}",
                        elastic * r
                    );
                    assert_eq!(f == 0.0, r <= 0.0);
                    clipped += usize::from(r <= 0.0);
                }
            }
            assert!(clipped > 0, "{law:?}: the grid reaches the clip");
            assert_eq!(law.unclipped_ratio(0.0, -1.0, v_minus), 1.0);
        }
        let impact = laws[0];
        let r = impact.unclipped_ratio(1e-20, -1.0, v_minus);
        assert!((r - 1.0).abs() < 1e-3, "IMPACT's r near δ = 0: {r}");
        let elastic_only = NormalLaw::HuntCrossley {
            k,
            restitution: 1.0,
        };
        assert!(!elastic_only.can_clip());
    }

    /// Central difference of `f` at `x` with step `h`.
    fn diff(f: impl Fn(f64) -> f64, x: f64, h: f64) -> f64 {
        (f(x + h) - f(x - h)) / (2.0 * h)
    }

    /// |a − b| within 1e-8 of the scale (max |a|, |b|, `floor`). With steps of 1e-5 relative,
    /// central differences of these smooth laws err by O(1e-10) (truncation h² f‴/6 and
    /// rounding 1e-16/h); 1e-8 is far above that and far below any wrong term.
    fn close(a: f64, b: f64, floor: f64, what: &str) {
        let scale = a.abs().max(b.abs()).max(floor);
        assert!(
            (a - b).abs() <= 1e-8 * scale,
            "{what}: analytic {a:e}, differences {b:e}"
        );
    }

    #[test]
    fn normal_law_derivatives_match_differences() {
        let k = 2.34e10;
        let laws = [
            NormalLaw::Impact {
                k,
                c_max: 1e4,
                d_max: 1e-5,
            },
            NormalLaw::LankaraniNikravesh {
                k,
                restitution: 0.8,
            },
            NormalLaw::Flores {
                k,
                restitution: 0.7,
            },
            NormalLaw::HuntCrossley {
                k,
                restitution: 0.9,
            },
        ];
        // Below and above d_max, approach and restitution (unclipped), with and without δ̇⁻.
        for law in laws {
            for (delta, delta_dot, v_minus) in [
                (3e-6, 0.05, 0.2),
                (3e-6, -0.01, 0.2),
                (4e-5, 0.1, 0.5),
                (4e-5, 0.1, 0.0),
            ] {
                let d = law.force_derivatives(delta, delta_dot, v_minus);
                let f0 = law.force(delta, delta_dot, v_minus);
                assert!(f0 > 0.0);
                let fd = diff(|x| law.force(x, delta_dot, v_minus), delta, 1e-5 * delta);
                let fv = diff(|v| law.force(delta, v, v_minus), delta_dot, 1e-5);
                close(d[0], fd, f0 / delta, &format!("{law:?} dF/dδ at {delta}"));
                close(d[1], fv, f0, &format!("{law:?} dF/dδ̇ at {delta}"));
            }
            // Clipped (restitution fast enough): no force, no slope. Not in contact: the same.
            if law.can_clip() {
                assert_eq!(law.force_derivatives(3e-6, -1e3, 0.2), [0.0, 0.0]);
            }
            assert_eq!(law.force_derivatives(-1e-6, 0.1, 0.2), [0.0, 0.0]);
        }
        // The slope of STEP: the closed form against its own differences, 0 beyond d_max.
        let (d_max, c_max) = (1e-5, 1e4);
        let x = 0.3 * d_max;
        close(
            step_damping_slope(x, d_max, c_max),
            diff(|x| step_damping(x, d_max, c_max), x, 1e-6 * x),
            c_max / d_max,
            "STEP slope",
        );
        assert_eq!(step_damping_slope(2.0 * d_max, d_max, c_max), 0.0);
    }

    #[test]
    fn friction_derivatives_match_differences() {
        let law = FrictionLaw::Coulomb {
            mu: 0.1,
            v0: 1e-4,
            v1: 1e-3,
        };
        let f_n = 250.0;
        for v in [5e-4, -5e-4, 2e-3, -0.3, 5e-5] {
            let d = law.force_derivatives(v, f_n);
            let fv = diff(|x| law.force(x, f_n), v, 1e-6 * v.abs());
            let ff = diff(|x| law.force(v, x), f_n, 1e-3);
            close(d[0], fv, 0.1 * f_n / 1e-3, &format!("dF_T/dv at {v}"));
            close(d[1], ff, 0.1, &format!("dF_T/dF_N at {v}"));
        }
        // v₀ = 0: linear through 0, slope −μ F_N / v₁ there.
        let lin = FrictionLaw::Coulomb {
            mu: 0.1,
            v0: 0.0,
            v1: 1e-3,
        };
        let d = lin.force_derivatives(0.0, f_n);
        close(
            d[0],
            diff(|x| lin.force(x, f_n), 0.0, 1e-6),
            1.0,
            "slope at 0",
        );
        assert_eq!(d[0], -0.1 * f_n / 1e-3);
        assert_eq!(FrictionLaw::None.force_derivatives(0.2, f_n), [0.0, 0.0]);
    }

    /// The constants computed once (`Film::constants`, read by `Film::force`): the scale S
    /// of each law against its closed form at ε = 0, Ω = 0 (where F_r = −S ε̇ times
    /// π/2 − 4/π, 1 and π), and the limit: beyond ε_cap the law is the law at ε_cap.
    #[test]
    fn film_constants_give_each_laws_scale_and_limit() {
        let (mu, l, r, c) = (0.4, 0.1, 0.0499, 1e-4);
        let pi = std::f64::consts::PI;
        let r3 = r * r * r;
        for (model, radial) in [
            (
                FilmModel::LongGumbel,
                12.0 * mu * l * r3 / (c * c) * (pi / 2.0 - 4.0 / pi),
            ),
            (FilmModel::LongSommerfeld, 12.0 * pi * mu * l * r3 / (c * c)),
            (
                FilmModel::ShortOcvirk,
                mu * r * l * l * l / (2.0 * c * c) * pi,
            ),
        ] {
            let film = Film {
                model,
                viscosity: mu,
                length: l,
                radius: r,
                clearance: c,
                eps_cap: Some(0.99),
                mirror_width: 0.01,
            };
            let (fr, ft) = film.force(0.0, 1.0, 0.0);
            assert!(
                (fr + radial).abs() <= 4e-16 * radial,
                "{model:?}: {fr} against {radial}"
            );
            assert_eq!(ft, 0.0);
            let k = film.constants();
            assert_eq!(k.limit, 0.99);
            let at = |eps: f64| film.force_with(&k, eps, -3.0, 25.0);
            assert_eq!(at(2.0), at(0.99), "{model:?}");
            assert_eq!(at(0.4), film.force(0.4, -3.0, 25.0), "{model:?}");
        }
    }

    #[test]
    fn film_derivatives_match_differences() {
        let models = [
            FilmModel::LongGumbel,
            FilmModel::LongGumbelMirrored,
            FilmModel::LongSommerfeld,
            FilmModel::ShortOcvirk,
            FilmModel::ShortOcvirkMirrored,
        ];
        for model in models {
            for eps_cap in [Some(0.999), None] {
                let film = Film {
                    model,
                    viscosity: 0.1,
                    length: 0.06,
                    radius: 0.02,
                    clearance: 1e-4,
                    eps_cap,
                    mirror_width: 0.01,
                };
                // Ω near the mirrored laws' sign width and far from it; ε low and near 1.
                for (eps, eps_dot, omega) in [
                    (0.3, 2.0, 15.7),
                    (0.9, -40.0, -3.0),
                    (0.99, 5.0, 0.004),
                    (0.5, -0.7, -0.013),
                ] {
                    let d = film.force_derivatives(eps, eps_dot, omega);
                    let (fr, ft) = film.force(eps, eps_dot, omega);
                    let scale = fr.abs().max(ft.abs());
                    let fe = |x: f64| film.force(x, eps_dot, omega);
                    let fv = |x: f64| film.force(eps, x, omega);
                    let fo = |x: f64| film.force(eps, eps_dot, x);
                    let he = 1e-5 * (1.0 - eps);
                    // The mirrored laws turn over Ω₀ (tanh is ±1 in f64 beyond 19.1 Ω₀).
                    let near = film.is_mirrored() && omega.abs() < 20.0 * film.mirror_width;
                    let ho = 1e-5 * if near { film.mirror_width } else { omega.abs() };
                    let oscale = scale / film.mirror_width.max(omega.abs());
                    let what = |q: &str| format!("{model:?} cap {eps_cap:?} {q} at ε {eps}");
                    close(d[0][0], diff(|x| fe(x).0, eps, he), scale, &what("dF_r/dε"));
                    close(d[1][0], diff(|x| fe(x).1, eps, he), scale, &what("dF_t/dε"));
                    close(
                        d[0][1],
                        diff(|x| fv(x).0, eps_dot, 1e-5),
                        scale,
                        &what("dF_r/dε̇"),
                    );
                    close(
                        d[1][1],
                        diff(|x| fv(x).1, eps_dot, 1e-5),
                        scale,
                        &what("dF_t/dε̇"),
                    );
                    close(
                        d[0][2],
                        diff(|x| fo(x).0, omega, ho),
                        oscale,
                        &what("dF_r/dΩ"),
                    );
                    close(
                        d[1][2],
                        diff(|x| fo(x).1, omega, ho),
                        oscale,
                        &what("dF_t/dΩ"),
                    );
                }
                // Beyond the cap ε_eff is constant.
                if eps_cap.is_some() {
                    let d = film.force_derivatives(0.9995, 1.0, 10.0);
                    assert_eq!((d[0][0], d[1][0]), (0.0, 0.0));
                }
            }
        }
    }
}
