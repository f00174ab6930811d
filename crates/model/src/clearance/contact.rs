//! The contact laws a clearance joint chooses, revolute or prismatic (docs/model.md §3): their
//! scene types, the checks they share, and their compiled laws.
//!
//! ```text
//! normal   = impact {k | materials, c_max, d_max} | lankarani_nikravesh | flores |
//!            hunt_crossley {k | materials, restitution}
//! friction = none | coulomb {mu, v0, v1}
//! ```

use serde::{Deserialize, Serialize};

use crate::clearance::laws::{FrictionLaw, NormalLaw};
use crate::scene::check::Checker;
use crate::scene::de::{object, object_opt, tagged_kinds};
use crate::scene::error::{invalid, SceneError};

/// Elastic properties of one contacting body (for the Hertz stiffness of docs/model.md §3).
///
/// ```text
/// σ = (1 − ν²)/E
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Young's modulus E (Pa), > 0.
    pub youngs_modulus: f64,
    /// Poisson's ratio ν, in (−1, 0.5).
    pub poisson_ratio: f64,
}

/// Materials of bearing and journal, from which K is computed.
///
/// ```text
/// K = 4/(3(σ_B + σ_J)) · sqrt(R_B R_J/(R_B − R_J))
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Materials {
    /// Bearing material.
    #[serde(deserialize_with = "object")]
    pub bearing: Material,
    /// Journal material.
    #[serde(deserialize_with = "object")]
    pub journal: Material,
}

/// ADAMS IMPACT law data.
///
/// ```text
/// F_N = K δ^{3/2} + STEP(δ, 0, 0, d_max, c_max) δ̇
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImpactSpec {
    /// Stiffness K (N/m^1.5), > 0. Exactly one of `k` and `materials`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k: Option<f64>,
    /// Materials for the Hertz stiffness. Exactly one of `k` and `materials`.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "object_opt"
    )]
    pub materials: Option<Materials>,
    /// Maximum damping c_max (N·s/m), ≥ 0.
    pub c_max: f64,
    /// Penetration of full damping d_max (m), > 0.
    pub d_max: f64,
}

/// Data of the restitution-based laws (Lankarani–Nikravesh, Flores, Hunt–Crossley).
///
/// ```text
/// F_N = K δ^{3/2} [1 + χ(c_r) δ̇/δ̇⁻]
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RestitutionSpec {
    /// Stiffness K (N/m^1.5), > 0. Exactly one of `k` and `materials`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k: Option<f64>,
    /// Materials for the Hertz stiffness. Exactly one of `k` and `materials`.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "object_opt"
    )]
    pub materials: Option<Materials>,
    /// Coefficient of restitution c_r in (0, 1].
    pub restitution: f64,
}

tagged_kinds! {
    /// Normal contact law (`"law"` selects the variant). See [`crate::laws::NormalLaw`].
    ///
    /// ```text
    /// impact              K δ^{3/2} + STEP(δ,0,0,d_max,c_max) δ̇
    /// lankarani_nikravesh K δ^{3/2} [1 + 3(1 − c_r²) δ̇/(4 δ̇⁻)]
    /// flores              K δ^{3/2} [1 + 8(1 − c_r) δ̇/(5 c_r δ̇⁻)]
    /// hunt_crossley       K δ^{3/2} [1 + 3(1 − c_r) δ̇/(2 δ̇⁻)]
    /// ```
    pub enum NormalSpec, tag "law", unknown "normal law" {
        /// ADAMS IMPACT (the paper's law).
        "impact" => Impact(ImpactSpec),
        /// Lankarani–Nikravesh.
        "lankarani_nikravesh" => LankaraniNikravesh(RestitutionSpec),
        /// Flores et al. 2011.
        "flores" => Flores(RestitutionSpec),
        /// Hunt–Crossley.
        "hunt_crossley" => HuntCrossley(RestitutionSpec),
    }
}

/// Coulomb friction data.
///
/// ```text
/// F_T = −μ c_d(|v_T|) F_N sign(v_T)
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoulombSpec {
    /// Dynamic friction coefficient μ_d, ≥ 0.
    pub mu: f64,
    /// Slip speed below which no friction acts, v₀ (m/s), ≥ 0.
    pub v0: f64,
    /// Slip speed above which full friction acts, v₁ (m/s), ≥ v₀.
    pub v1: f64,
}

tagged_kinds! {
    /// Friction law (`"law"` selects the variant). See [`crate::laws::FrictionLaw`].
    ///
    /// ```text
    /// none     F_T = 0
    /// coulomb  F_T = −μ c_d(|v_T|) F_N sign(v_T)   (Ambrósio's c_d)
    /// ```
    #[derive(Default)]
    pub enum FrictionSpec, tag "law", unknown "friction law" {
        /// Frictionless (default).
        #[default]
        "none" => None,
        /// Coulomb with Ambrósio's dynamic correction.
        "coulomb" => Coulomb(CoulombSpec),
    }
}

/// `check_k(path of the normal law, k, materials)`: a joint's check of its contact stiffness.
pub(crate) type StiffnessCheck<'a> =
    dyn Fn(&str, &Option<f64>, &Option<Materials>) -> Result<(), SceneError> + 'a;

/// The checks a clearance joint's normal and friction laws share, revolute or prismatic:
/// `check_k(path of the normal law, k, materials)` checks the stiffness (a revolute joint may
/// derive it from materials, a flat guide face may not); the rest is the same for both.
pub(crate) fn check_contact_laws(
    p: &str,
    normal: &NormalSpec,
    friction: &FrictionSpec,
    check_k: &StiffnessCheck<'_>,
) -> Result<(), SceneError> {
    type C = Checker;
    let np = format!("{p}.normal");
    match normal {
        NormalSpec::Impact(s) => {
            check_k(&np, &s.k, &s.materials)?;
            C::non_negative(&format!("{np}.c_max"), s.c_max, "c_max")?;
            C::positive(&format!("{np}.d_max"), s.d_max, "d_max")?;
        }
        NormalSpec::LankaraniNikravesh(s) | NormalSpec::Flores(s) | NormalSpec::HuntCrossley(s) => {
            check_k(&np, &s.k, &s.materials)?;
            let rp = format!("{np}.restitution");
            C::finite(&rp, s.restitution)?;
            if !(s.restitution > 0.0 && s.restitution <= 1.0) {
                return Err(invalid(
                    rp,
                    format!(
                        "the coefficient of restitution must lie in (0, 1], got {}",
                        s.restitution
                    ),
                ));
            }
        }
    }
    if let FrictionSpec::Coulomb(f) = friction {
        let fp = format!("{p}.friction");
        C::non_negative(&format!("{fp}.mu"), f.mu, "mu")?;
        C::non_negative(&format!("{fp}.v0"), f.v0, "v0")?;
        C::finite(&format!("{fp}.v1"), f.v1)?;
        if !(f.v1 >= f.v0) {
            return Err(invalid(
                format!("{fp}.v1"),
                format!("v1 must be >= v0 = {}, got {}", f.v0, f.v1),
            ));
        }
    }
    Ok(())
}

/// The compiled normal law; `stiffness(k, materials)` gives K (validated: exactly one given,
/// or materials refused by the joint).
pub(crate) fn normal_law(
    spec: &NormalSpec,
    stiffness: impl Fn(Option<f64>, Option<Materials>) -> f64,
) -> NormalLaw {
    match spec {
        NormalSpec::Impact(s) => NormalLaw::Impact {
            k: stiffness(s.k, s.materials),
            c_max: s.c_max,
            d_max: s.d_max,
        },
        NormalSpec::LankaraniNikravesh(s) => NormalLaw::LankaraniNikravesh {
            k: stiffness(s.k, s.materials),
            restitution: s.restitution,
        },
        NormalSpec::Flores(s) => NormalLaw::Flores {
            k: stiffness(s.k, s.materials),
            restitution: s.restitution,
        },
        NormalSpec::HuntCrossley(s) => NormalLaw::HuntCrossley {
            k: stiffness(s.k, s.materials),
            restitution: s.restitution,
        },
    }
}

/// The compiled friction law: None when there is none or μ = 0 (no code runs).
pub(crate) fn friction_law(spec: &FrictionSpec) -> Option<FrictionLaw> {
    match spec {
        FrictionSpec::None => None,
        FrictionSpec::Coulomb(f) if f.mu == 0.0 => None,
        FrictionSpec::Coulomb(f) => Some(FrictionLaw::Coulomb {
            mu: f.mu,
            v0: f.v0,
            v1: f.v1,
        }),
    }
}
