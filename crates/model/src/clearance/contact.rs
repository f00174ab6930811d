//! The contact laws a clearance joint chooses (revolute or prismatic): their scene types.

use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize};

use crate::scene::de::{object, object_opt, tagged_object, variant, NoData, PATH_MARK};

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

/// Normal contact law (`"law"` selects the variant). See [`crate::laws::NormalLaw`].
///
/// ```text
/// impact              K δ^{3/2} + STEP(δ,0,0,d_max,c_max) δ̇
/// lankarani_nikravesh K δ^{3/2} [1 + 3(1 − c_r²) δ̇/(4 δ̇⁻)]
/// flores              K δ^{3/2} [1 + 8(1 − c_r) δ̇/(5 c_r δ̇⁻)]
/// hunt_crossley       K δ^{3/2} [1 + 3(1 − c_r) δ̇/(2 δ̇⁻)]
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "law", rename_all = "snake_case")]
pub enum NormalSpec {
    /// ADAMS IMPACT (the paper's law).
    Impact(ImpactSpec),
    /// Lankarani–Nikravesh.
    LankaraniNikravesh(RestitutionSpec),
    /// Flores et al. 2011.
    Flores(RestitutionSpec),
    /// Hunt–Crossley.
    HuntCrossley(RestitutionSpec),
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

/// Friction law (`"law"` selects the variant). See [`crate::laws::FrictionLaw`].
///
/// ```text
/// none     F_T = 0
/// coulomb  F_T = −μ c_d(|v_T|) F_N sign(v_T)   (Ambrósio's c_d)
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Default)]
#[serde(tag = "law", rename_all = "snake_case")]
pub enum FrictionSpec {
    /// Frictionless (default).
    #[default]
    None,
    /// Coulomb with Ambrósio's dynamic correction.
    Coulomb(CoulombSpec),
}

impl<'de> Deserialize<'de> for NormalSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let (tag, obj) = tagged_object::<D>(d, "law")?;
        match tag.as_str() {
            "impact" => variant::<D, _>(obj, "law").map(NormalSpec::Impact),
            "lankarani_nikravesh" => {
                variant::<D, _>(obj, "law").map(NormalSpec::LankaraniNikravesh)
            }
            "flores" => variant::<D, _>(obj, "law").map(NormalSpec::Flores),
            "hunt_crossley" => variant::<D, _>(obj, "law").map(NormalSpec::HuntCrossley),
            other => Err(D::Error::custom(format!(
                "{PATH_MARK}law{PATH_MARK}unknown normal law `{other}`, expected one of \
                 `impact`, `lankarani_nikravesh`, `flores`, `hunt_crossley`"
            ))),
        }
    }
}

impl<'de> Deserialize<'de> for FrictionSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let (tag, obj) = tagged_object::<D>(d, "law")?;
        match tag.as_str() {
            "none" => variant::<D, NoData>(obj, "law").map(|_| FrictionSpec::None),
            "coulomb" => variant::<D, _>(obj, "law").map(FrictionSpec::Coulomb),
            other => Err(D::Error::custom(format!(
                "{PATH_MARK}law{PATH_MARK}unknown friction law `{other}`, expected `none` or \
                 `coulomb`"
            ))),
        }
    }
}
