//! The scene: a planar mechanism described in JSON (typed with serde, unknown fields rejected),
//! and its validation. The reference page of every field is `docs/scene-format.md`.
//!
//! ```text
//! scene  = { bodies[], joints[], gravity, baumgarte, t_start, t_end | revolutions, roles }
//! body   = { name, mass, inertia (about the centre of mass), points{name: [x', y']},
//!            position, angle, velocity, angular_velocity }      (initial guesses)
//! joint  = revolute {a, b} | translational {body, point, origin, direction, angle}
//!        | driver {body, theta0, omega | rpm}                     θ(t) = θ₀ + ω t
//!        | clearance {bearing, journal, normal, friction, film, initial_eccentricity}
//! ```
//! Source: docs/model.md §1–§6 (after Peng et al. 2025, Lubricants 13(3) 124).
//!
//! Errors name the JSON path (`joints[3].bearing.radius`) and the reason; see [`SceneError`].

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

use serde::de::{DeserializeOwned, Error as _};
use serde::{Deserialize, Deserializer, Serialize};

use crate::elements::{ForceElementSpec, PrismaticClearanceSpec};
use crate::laws::FilmModel;

/// The reserved name of the ground (the fixed frame). No body may take it.
pub const GROUND: &str = "ground";

/// Why a scene is rejected. Every message names where (a JSON path such as
/// `joints[3].bearing.radius`, or a body/point name) and why.
///
/// ```text
/// Syntax      JSON syntax error at line L, column C: …
/// Schema      <path>: unknown field / wrong type / missing field (serde, path tracked)
/// Invalid     <path>: <reason>                    (a value out of range, a missing name, …)
/// Redundant   <path>: redundant or contradictory constraints: …
/// Assembly    <path>: initial assembly did not converge: equation …, residual …
/// Dynamics    <path>: the equations of motion fail at the initial state: … (not finite, or
///             Φ_q M⁻¹ Φ_qᵀ singular in f64)
/// Unknown     unknown body 'x' / unknown point 'p' on body 'x'   (output look-ups)
/// ```
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// The text is not valid JSON.
    #[error("JSON syntax error at line {line}, column {column}: {message}")]
    Syntax {
        /// Line (1-based).
        line: usize,
        /// Column (1-based).
        column: usize,
        /// serde_json's message.
        message: String,
    },
    /// Valid JSON that does not fit the schema: unknown field, wrong type, missing field.
    #[error("{path}: {message}")]
    Schema {
        /// JSON path of the offending value.
        path: String,
        /// serde's message (with line and column).
        message: String,
    },
    /// A value out of range, a name that refers to nothing, a missing choice.
    #[error("{path}: {reason}")]
    Invalid {
        /// JSON path of the offending value.
        path: String,
        /// Why it is rejected.
        reason: String,
    },
    /// The constraint Jacobian is rank deficient at the initial state.
    #[error("{path}: redundant or contradictory constraints: {reason}")]
    Redundant {
        /// JSON path of the joint whose equation depends on earlier ones.
        path: String,
        /// Which equation, and the rank found.
        reason: String,
    },
    /// Newton's method on the position (or velocity) constraints did not converge.
    #[error("{path}: initial assembly did not converge: {reason}")]
    Assembly {
        /// JSON path of the joint with the largest residual.
        path: String,
        /// Which equation and by how much.
        reason: String,
    },
    /// The equations of motion are not finite, or their KKT system is singular in f64, at the
    /// assembled initial state (numbers each finite, but beyond what f64 can combine).
    #[error("{path}: the equations of motion fail at the initial state: {reason}")]
    Dynamics {
        /// JSON path of the body or joint to blame.
        path: String,
        /// Which quantity, its value, and the numbers of the scene behind it.
        reason: String,
    },
    /// An output asked for a body or point the scene does not have.
    #[error("unknown {0}")]
    Unknown(String),
    /// The scene file could not be read.
    #[error("cannot read {path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// The OS error.
        message: String,
    },
}

pub(crate) fn invalid(path: impl Into<String>, reason: impl Into<String>) -> SceneError {
    SceneError::Invalid {
        path: path.into(),
        reason: reason.into(),
    }
}

// ---------------------------------------------------------------------------------------------
// Types
// ---------------------------------------------------------------------------------------------

/// A planar mechanism scene (docs/model.md §1–§6).
///
/// ```text
/// bodies, joints, gravity g (m/s²), Baumgarte α, β (1/s), time span [t_start, t_end]
/// t_end = t_start + revolutions · 2π / |ω_crank|   when `revolutions` is given
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Free text: what the scene is. Default empty.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub description: String,
    /// Free text notes: assumptions, caveats. Default empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    /// The moving bodies (ground is implicit). At least one.
    #[serde(deserialize_with = "objects")]
    pub bodies: Vec<BodySpec>,
    /// Joints, drivers and clearance joints. Default none.
    #[serde(default)]
    pub joints: Vec<JointSpec>,
    /// Force elements: springs, dampers, applied forces and torques, motors
    /// (docs/scene-format.md, "Force elements"). Default none (no code of theirs runs).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub forces: Vec<ForceElementSpec>,
    /// Gravity vector (m/s²). Default [0, 0] (no gravity code runs).
    #[serde(default)]
    pub gravity: [f64; 2],
    /// Baumgarte stabilisation. Default α = β = 5 s⁻¹.
    #[serde(default, deserialize_with = "object")]
    pub baumgarte: Baumgarte,
    /// Start time (s). Default 0.
    #[serde(default)]
    pub t_start: f64,
    /// End time (s), > t_start. Exactly one of `t_end` and `revolutions`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub t_end: Option<f64>,
    /// Simulated crank revolutions (> 0; needs `roles.crank_driver` with ω ≠ 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub revolutions: Option<f64>,
    /// Named parts the press metrics need (docs/outputs.md, "Scene roles"). Default none.
    #[serde(default, deserialize_with = "object")]
    pub roles: RoleNames,
    /// Events at the kinks of the revolute clearance joints' force laws (δ = d_max, the clip
    /// of F_N at 0, |v_T| = v₀ and v₁; docs/model.md §7), so that an integration restarts at
    /// each. Default false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub kink_events: bool,
}

/// A rigid body with its centre of mass as reference point.
///
/// ```text
/// q = (x, y, φ) of the centre of mass;  r^P = r + A(φ) s'_P;  M = diag(m, m, I)
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Unique name (not "ground").
    pub name: String,
    /// Mass m (kg), > 0.
    pub mass: f64,
    /// Moment of inertia about the centre of mass I (kg·m²), > 0.
    pub inertia: f64,
    /// Named points: local offsets s' from the centre of mass in the body frame (m).
    #[serde(default)]
    pub points: BTreeMap<String, [f64; 2]>,
    /// Initial guess of the centre-of-mass position (m). Default [0, 0].
    #[serde(default)]
    pub position: [f64; 2],
    /// Initial guess of the angle φ (rad). Default 0.
    #[serde(default)]
    pub angle: f64,
    /// Initial guess of the centre-of-mass velocity (m/s). Default [0, 0].
    #[serde(default)]
    pub velocity: [f64; 2],
    /// Initial guess of the angular velocity (rad/s). Default 0.
    #[serde(default)]
    pub angular_velocity: f64,
    /// Initial velocity components held exactly by the projection onto the velocity
    /// constraints (the guesses `velocity` and `angular_velocity` are only targets).
    /// Default none.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "object_opt"
    )]
    pub initial_velocity: Option<InitialVelocity>,
}

/// Initial velocity components of a body that the projection must keep exactly
/// (docs/model.md §1, "Initial conditions").
///
/// ```text
/// ẋ(t₀) = vx,  ẏ(t₀) = vy,  φ̇(t₀) = omega   (each optional; the others follow from the
///                                            constraints and the mass-weighted projection)
/// ```
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialVelocity {
    /// ẋ of the centre of mass (m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vx: Option<f64>,
    /// ẏ of the centre of mass (m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vy: Option<f64>,
    /// φ̇ (rad/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub omega: Option<f64>,
}

/// Where a joint attaches: a named point of a body, or a fixed location on the ground.
///
/// ```text
/// body ≠ "ground":  r^P = r_body + A(φ_body) s'_point      ("point" required, no "at")
/// body = "ground":  r^P = at                               ("at" required, no "point")
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Attachment {
    /// Body name, or "ground".
    pub body: String,
    /// Point name on the body (bodies only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<String>,
    /// Global location (m) (ground only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<[f64; 2]>,
}

/// Ideal revolute (pin) joint: two points coincide.
///
/// ```text
/// Φ = r_a^P − r_b^P = 0   (2 equations)
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RevoluteSpec {
    /// Unique joint name.
    pub name: String,
    /// First attachment.
    #[serde(deserialize_with = "object")]
    pub a: Attachment,
    /// Second attachment.
    #[serde(deserialize_with = "object")]
    pub b: Attachment,
    /// Initial relative rate φ̇_a − φ̇_b (rad/s), held exactly by the initial projection
    /// (φ_ground = 0). Default none (it follows from the bodies' guesses).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_rate: Option<f64>,
}

/// Translational (prismatic) joint: a body point slides along a fixed global line and the body
/// does not rotate.
///
/// ```text
/// Φ₁ = n·(r^P − o) = 0,  n = direction rotated by +90°, normalised
/// Φ₂ = φ − φ₀ = 0
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TranslationalSpec {
    /// Unique joint name.
    pub name: String,
    /// The sliding body (not ground).
    pub body: String,
    /// The point of the body that stays on the line.
    pub point: String,
    /// A point of the line, global (m). Default [0, 0].
    #[serde(default)]
    pub origin: [f64; 2],
    /// Direction of the line, global (any length > 0). Default [1, 0].
    #[serde(default = "default_direction")]
    pub direction: [f64; 2],
    /// The fixed body angle φ₀ (rad). Default: the body's initial `angle`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle: Option<f64>,
    /// Initial sliding speed u·ṙ^P along the direction (m/s), held exactly by the initial
    /// projection. Default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_rate: Option<f64>,
}

fn default_direction() -> [f64; 2] {
    [1.0, 0.0]
}

/// Rotational driver: the absolute angle of a body follows θ(t).
///
/// ```text
/// Φ = φ − θ(t) = 0,  θ(t) = θ₀ + ω t,  ω = omega or 2π·rpm/60
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriverSpec {
    /// Unique joint name.
    pub name: String,
    /// The driven body (not ground).
    pub body: String,
    /// θ₀ (rad). Default 0.
    #[serde(default)]
    pub theta0: f64,
    /// ω (rad/s). Exactly one of `omega` and `rpm`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub omega: Option<f64>,
    /// ω in revolutions per minute. Exactly one of `omega` and `rpm`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rpm: Option<f64>,
}

impl DriverSpec {
    /// ω in rad/s (from `omega` or `rpm`; 0 when neither is given).
    pub fn omega_rad_s(&self) -> f64 {
        match (self.omega, self.rpm) {
            (Some(w), _) => w,
            (None, Some(n)) => n * std::f64::consts::PI / 30.0,
            (None, None) => 0.0,
        }
    }
}

/// One side of a clearance joint: an attachment with a radius.
///
/// ```text
/// r^P as for [`Attachment`]; R (m) the bearing (hole) or journal (pin) radius
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClearanceEnd {
    /// Body name, or "ground".
    pub body: String,
    /// Point name on the body (bodies only): the centre of the hole or pin.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<String>,
    /// Global location (m) (ground only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<[f64; 2]>,
    /// Radius (m), > 0.
    pub radius: f64,
}

/// Revolute clearance joint (docs/model.md §2–§4): no constraint, a force pair.
///
/// ```text
/// e = r_J^P − r_B^P,  c = R_B − R_J,  δ = |e| − c
/// f_J = −F_N n + F_T t (at Q_J = r_J^P + R_J n) [+ F_r n + F_t t at P_J with a film]
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClearanceSpec {
    /// Unique joint name.
    pub name: String,
    /// The bearing (hole), radius R_B.
    #[serde(deserialize_with = "object")]
    pub bearing: ClearanceEnd,
    /// The journal (pin), radius R_J < R_B.
    #[serde(deserialize_with = "object")]
    pub journal: ClearanceEnd,
    /// Normal contact law.
    pub normal: NormalSpec,
    /// Friction law. Default none.
    #[serde(default)]
    pub friction: FrictionSpec,
    /// Hydrodynamic film. Default none (dry joint).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "object_opt"
    )]
    pub film: Option<FilmSpec>,
    /// Initial eccentricity e(t_start), global (m). Default [0, 0] (centred). |e| must not
    /// exceed the clearance unless `allow_initial_penetration` is set.
    #[serde(default)]
    pub initial_eccentricity: [f64; 2],
    /// Initial eccentricity rate ė(t_start), global (m/s). Default [0, 0].
    #[serde(default, skip_serializing_if = "is_zero2")]
    pub initial_eccentricity_rate: [f64; 2],
    /// Accept |e(t_start)| > c (a start in contact, up to the journal radius). Default false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub allow_initial_penetration: bool,
}

fn is_zero2(v: &[f64; 2]) -> bool {
    *v == [0.0, 0.0]
}

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

/// An empty object (the `none` friction law has no data).
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoData {}

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

/// Hydrodynamic film of a lubricated clearance joint (docs/model.md §4).
///
/// ```text
/// F_r, F_t = film model(ε_eff, ε̇, Ω);  R = R_J, c = R_B − R_J
/// ε_eff = min(ε, ε_cap)  ("eps_cap": number, default 0.99)
///       = min(ε, 1 − 1e-12)  ("eps_cap": null: no cap, the law at the true ε)
/// mirrored models: sign(Ω) → tanh(Ω/Ω₀)  ("omega0": Ω₀ > 0, rad/s, default 0.01)
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilmSpec {
    /// Film model. Default `long_gumbel` (the paper's formula).
    #[serde(default = "default_film_model")]
    pub model: FilmModel,
    /// Dynamic viscosity μ (Pa·s), ≥ 0.
    pub viscosity: f64,
    /// Bearing length L (m), > 0.
    pub length: f64,
    /// Eccentricity cap ε_cap in (0, 1), or `None` (JSON `null`): no cap. An absent field is
    /// the default cap 0.99, not `None`.
    #[serde(default = "default_eps_cap", deserialize_with = "nullable")]
    pub eps_cap: Option<f64>,
    /// Width Ω₀ of the smooth sign of the mirrored models (rad/s), > 0; only with a mirrored
    /// model. Default [`crate::laws::DEFAULT_MIRROR_WIDTH`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub omega0: Option<f64>,
}

fn default_film_model() -> FilmModel {
    FilmModel::LongGumbel
}
fn default_eps_cap() -> Option<f64> {
    Some(0.99)
}
/// A number or `null` (`None`); the field's absence is handled by its `default`.
fn nullable<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    Option::<f64>::deserialize(d)
}

/// Baumgarte stabilisation parameters (docs/model.md §1).
///
/// ```text
/// Φ_q q̈ = γ − 2α Φ̇ − β² Φ
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Baumgarte {
    /// α (1/s), ≥ 0. Default 5.
    #[serde(default = "five")]
    pub alpha: f64,
    /// β (1/s), ≥ 0. Default 5.
    #[serde(default = "five")]
    pub beta: f64,
}

fn five() -> f64 {
    5.0
}

impl Default for Baumgarte {
    fn default() -> Self {
        Baumgarte {
            alpha: 5.0,
            beta: 5.0,
        }
    }
}

/// Names of the parts the press metrics need (docs/outputs.md, "Scene roles").
///
/// ```text
/// slider: BODY,  crank_driver: driver JOINT,  clearance_joint: clearance JOINT
/// ```
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoleNames {
    /// The slider body.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slider: Option<String>,
    /// The driver that turns the crank.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crank_driver: Option<String>,
    /// The clearance joint the metrics report.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clearance_joint: Option<String>,
}

/// A joint of the scene (`"type"` selects the variant).
///
/// ```text
/// revolute       Φ = r_a^P − r_b^P                      (2 equations)
/// translational  Φ = (n·(r^P − o), φ − φ₀)              (2 equations)
/// driver         Φ = φ − θ₀ − ω t                       (1 equation)
/// clearance      no equation: the force pair of docs/model.md §2–§4
/// prismatic_clearance  no equation: the corner contacts of docs/model.md §11
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum JointSpec {
    /// Ideal revolute joint.
    Revolute(RevoluteSpec),
    /// Translational joint along a global line.
    Translational(TranslationalSpec),
    /// Rotational driver.
    Driver(DriverSpec),
    /// Revolute clearance joint.
    Clearance(ClearanceSpec),
    /// Translational clearance joint (a block in a guide).
    PrismaticClearance(PrismaticClearanceSpec),
}

impl JointSpec {
    /// The joint's name.
    pub fn name(&self) -> &str {
        match self {
            JointSpec::Revolute(j) => &j.name,
            JointSpec::Translational(j) => &j.name,
            JointSpec::Driver(j) => &j.name,
            JointSpec::Clearance(j) => &j.name,
            JointSpec::PrismaticClearance(j) => &j.name,
        }
    }

    /// The `"type"` tag.
    pub fn type_name(&self) -> &'static str {
        match self {
            JointSpec::Revolute(_) => "revolute",
            JointSpec::Translational(_) => "translational",
            JointSpec::Driver(_) => "driver",
            JointSpec::Clearance(_) => "clearance",
            JointSpec::PrismaticClearance(_) => "prismatic_clearance",
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Structs only as objects.
//
// serde's derive also reads a struct from an array of its fields in order (`"baumgarte": [5, 5]`,
// a body as `["crank", 1.0, 0.1]`). The format has no such form: these read a struct through
// `deserialize_map`, so an array is "invalid type: sequence, expected an object" at its own path
// (the map access passed on is serde_path_to_error's, so deeper paths are kept).
// ---------------------------------------------------------------------------------------------

struct Obj<T>(T);

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Obj<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for V<T> {
            type Value = T;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an object")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<T, A::Error> {
                T::deserialize(serde::de::value::MapAccessDeserializer::new(map))
            }
        }
        d.deserialize_map(V(std::marker::PhantomData)).map(Obj)
    }
}

pub(crate) fn object<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<T, D::Error> {
    Obj::deserialize(d).map(|o| o.0)
}

fn object_opt<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<Option<T>, D::Error> {
    Option::<Obj<T>>::deserialize(d).map(|o| o.map(|o| o.0))
}

fn objects<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<Vec<T>, D::Error> {
    Vec::<Obj<T>>::deserialize(d).map(|v| v.into_iter().map(|o| o.0).collect())
}

// ---------------------------------------------------------------------------------------------
// Internally tagged enums with full error paths.
//
// serde's derive for internally tagged enums buffers the object, so errors inside a variant lose
// their path. These impls read the object as a JSON value, dispatch on the tag, and deserialize
// the variant struct with path tracking; the inner path travels in the error message between
// PATH_MARK characters and `SceneError` joins it to the outer path.
// ---------------------------------------------------------------------------------------------

pub(crate) const PATH_MARK: char = '\u{1}';

pub(crate) fn variant<'de, D: Deserializer<'de>, T: DeserializeOwned>(
    mut obj: serde_json::Map<String, serde_json::Value>,
    tag: &str,
) -> Result<T, D::Error> {
    obj.remove(tag);
    serde_path_to_error::deserialize(serde_json::Value::Object(obj)).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner().to_string();
        // Nested marks (a tagged enum inside a variant) carry a deeper path: join them.
        let (path, inner) = match split_marked(&inner) {
            Some((p, m)) if path == "." => (p.to_string(), m.to_string()),
            Some((p, m)) => (format!("{path}.{p}"), m.to_string()),
            None => (path, inner),
        };
        if path == "." {
            // At the variant object itself (a missing field): the outer path says where.
            D::Error::custom(inner)
        } else {
            D::Error::custom(format!("{PATH_MARK}{path}{PATH_MARK}{inner}"))
        }
    })
}

fn split_marked(msg: &str) -> Option<(&str, &str)> {
    let rest = msg.strip_prefix(PATH_MARK)?;
    let end = rest.find(PATH_MARK)?;
    Some((&rest[..end], &rest[end + 1..]))
}

pub(crate) fn tagged_object<'de, D: Deserializer<'de>>(
    d: D,
    tag: &str,
) -> Result<(String, serde_json::Map<String, serde_json::Value>), D::Error> {
    let v = serde_json::Value::deserialize(d)?;
    let serde_json::Value::Object(obj) = v else {
        return Err(D::Error::custom(format!(
            "expected an object with a \"{tag}\" field"
        )));
    };
    let tag_value = match obj.get(tag) {
        Some(serde_json::Value::String(s)) => s.clone(),
        Some(_) => {
            return Err(D::Error::custom(format!(
                "{PATH_MARK}{tag}{PATH_MARK}must be a string"
            )))
        }
        None => return Err(D::Error::custom(format!("missing field `{tag}`"))),
    };
    Ok((tag_value, obj))
}

impl<'de> Deserialize<'de> for JointSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let (tag, obj) = tagged_object::<D>(d, "type")?;
        match tag.as_str() {
            "revolute" => variant::<D, _>(obj, "type").map(JointSpec::Revolute),
            "translational" => variant::<D, _>(obj, "type").map(JointSpec::Translational),
            "driver" => variant::<D, _>(obj, "type").map(JointSpec::Driver),
            "clearance" => variant::<D, _>(obj, "type").map(JointSpec::Clearance),
            "prismatic_clearance" => {
                variant::<D, _>(obj, "type").map(JointSpec::PrismaticClearance)
            }
            other => Err(D::Error::custom(format!(
                "{PATH_MARK}type{PATH_MARK}unknown joint type `{other}`, expected one of \
                 `revolute`, `translational`, `driver`, `clearance`, `prismatic_clearance`"
            ))),
        }
    }
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

// ---------------------------------------------------------------------------------------------
// Parsing
// ---------------------------------------------------------------------------------------------

impl Scene {
    /// Parses and validates a scene from JSON text.
    ///
    /// Text that is not JSON gets a [`SceneError::Syntax`] (its first syntax error), never a
    /// schema error about the part read before it; a missing field's path names the field.
    pub fn from_json_str(text: &str) -> Result<Scene, SceneError> {
        // Syntax first, on the whole text: the typed pass below stops at the first value of
        // the wrong type, which may come before a syntax error (`0x`, a truncated file).
        let value: serde_json::Value = serde_json::from_str(text).map_err(|e| syntax_error(&e))?;
        if !value.is_object() {
            return Err(SceneError::Schema {
                path: ".".into(),
                message: format!("expected a JSON object (the scene), got {}", kind(&value)),
            });
        }
        // A repeated key would silently keep one of its values (docs/scene-format.md).
        check_duplicate_keys(text)?;
        let de = &mut serde_json::Deserializer::from_str(text);
        let scene: Scene = serde_path_to_error::deserialize(de).map_err(|e| {
            let outer = e.path().to_string();
            let inner = e.into_inner();
            use serde_json::error::Category;
            match inner.classify() {
                // The text is JSON (checked above): serde_json reports an array longer than a
                // fixed-size field (`[1, 2, 3]` for [x, y]) as "trailing characters".
                Category::Syntax | Category::Eof => SceneError::Schema {
                    path: outer,
                    message: format!(
                        "{}: the array has more elements than the field takes",
                        strip_position(&inner.to_string())
                    ),
                },
                Category::Io => syntax_error(&inner),
                Category::Data => {
                    let msg = inner.to_string();
                    let (path, message) = match split_marked(&msg) {
                        // (The inner path starts with a key: a variant is an object.)
                        Some((p, m)) => (join_path(&outer, p), m.to_string()),
                        None => (outer, msg),
                    };
                    // serde reports a missing field at its object: name the field itself.
                    let path = match message
                        .strip_prefix("missing field `")
                        .and_then(|r| r.split_once('`'))
                    {
                        Some((field, _)) => join_path(&path, field),
                        None => path,
                    };
                    SceneError::Schema { path, message }
                }
            }
        })?;
        scene.validate()?;
        Ok(scene)
    }

    /// Reads, parses and validates a scene file.
    pub fn from_path(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let p = path.as_ref();
        let text = std::fs::read_to_string(p).map_err(|e| SceneError::Io {
            path: p.display().to_string(),
            message: e.to_string(),
        })?;
        Scene::from_json_str(&text)
    }

    /// The scene as pretty-printed JSON.
    pub fn to_json_pretty(&self) -> String {
        serde_json::to_string_pretty(self).expect("a scene always serialises")
    }

    /// Index of the body named `name`.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }

    /// Index of the joint named `name`.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name() == name)
    }
}

/// The first key that an object of `text` repeats, as a [`SceneError::Schema`] at its path.
fn check_duplicate_keys(text: &str) -> Result<(), SceneError> {
    use serde::de::DeserializeSeed;
    let mut de = serde_json::Deserializer::from_str(text);
    NoDuplicates(".".into()).deserialize(&mut de).map_err(|e| {
        let msg = strip_position(&e.to_string());
        match split_marked(&msg) {
            Some((path, m)) => SceneError::Schema {
                path: path.to_string(),
                message: m.to_string(),
            },
            None => syntax_error(&e),
        }
    })
}

/// Walks a JSON document and fails at the first repeated key of an object.
struct NoDuplicates(String);

impl NoDuplicates {
    fn key(&self, k: &str) -> String {
        join_path(&self.0, k)
    }
}

impl<'de> serde::de::DeserializeSeed<'de> for NoDuplicates {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> serde::de::Visitor<'de> for NoDuplicates {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("any JSON value")
    }
    fn visit_bool<E>(self, _: bool) -> Result<(), E> {
        Ok(())
    }
    fn visit_i64<E>(self, _: i64) -> Result<(), E> {
        Ok(())
    }
    fn visit_u64<E>(self, _: u64) -> Result<(), E> {
        Ok(())
    }
    fn visit_f64<E>(self, _: f64) -> Result<(), E> {
        Ok(())
    }
    fn visit_str<E>(self, _: &str) -> Result<(), E> {
        Ok(())
    }
    fn visit_unit<E>(self) -> Result<(), E> {
        Ok(())
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        let mut i = 0usize;
        while seq
            .next_element_seed(NoDuplicates(format!("{}[{i}]", self.0)))?
            .is_some()
        {
            i += 1;
        }
        Ok(())
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let mut seen = std::collections::HashSet::new();
        while let Some(k) = map.next_key::<String>()? {
            let path = self.key(&k);
            if !seen.insert(k.clone()) {
                return Err(A::Error::custom(format!(
                    "{PATH_MARK}{path}{PATH_MARK}duplicate key `{k}`: an object must not \
                     repeat a key"
                )));
            }
            map.next_value_seed(NoDuplicates(path))?;
        }
        Ok(())
    }
}

/// The JSON type of a value, for messages.
fn kind(v: &serde_json::Value) -> &'static str {
    match v {
        serde_json::Value::Null => "null",
        serde_json::Value::Bool(_) => "a boolean",
        serde_json::Value::Number(_) => "a number",
        serde_json::Value::String(_) => "a string",
        serde_json::Value::Array(_) => "an array",
        serde_json::Value::Object(_) => "an object",
    }
}

/// `outer.inner`; `.` (the root) on either side is left out.
fn join_path(outer: &str, inner: &str) -> String {
    if inner == "." {
        outer.to_string()
    } else if outer == "." {
        inner.to_string()
    } else {
        format!("{outer}.{inner}")
    }
}

fn syntax_error(e: &serde_json::Error) -> SceneError {
    SceneError::Syntax {
        line: e.line(),
        column: e.column(),
        message: strip_position(&e.to_string()),
    }
}

fn strip_position(msg: &str) -> String {
    match msg.rfind(" at line ") {
        Some(i) => msg[..i].to_string(),
        None => msg.to_string(),
    }
}

// ---------------------------------------------------------------------------------------------
// Validation
// ---------------------------------------------------------------------------------------------

/// Largest magnitude of a number in a scene.
///
/// ```text
/// every number x of a scene:  x = 0  or  MIN_MAGNITUDE ≤ |x| ≤ MAX_MAGNITUDE
/// MAX_MAGNITUDE = 1e150, MIN_MAGNITUDE = 1e-150:  x·y and x/y of any two such numbers are
/// finite, normal f64 numbers (1e300 < f64::MAX ≈ 1.8e308, 1e-300 > f64::MIN_POSITIVE ≈ 2.2e-308)
/// ```
///
/// The equations square and multiply scene values (m g, ω² r, β² Φ, K δ^1.5, |s'|²/I), so a
/// value outside the range overflows or underflows in the first evaluation; the range is far
/// beyond any physical scene in SI units. Products of three or more values can still overflow
/// inside the range: [`crate::Mechanism::from_scene`] evaluates the equations once at the
/// initial state and rejects what is not finite ([`SceneError::Dynamics`]).
/// Source: IEEE 754-2008 binary64 range.
pub const MAX_MAGNITUDE: f64 = 1e150;
/// Smallest non-zero magnitude of a number in a scene; see [`MAX_MAGNITUDE`].
pub const MIN_MAGNITUDE: f64 = 1e-150;

pub(crate) struct Checker;

impl Checker {
    pub(crate) fn finite(path: &str, v: f64) -> Result<(), SceneError> {
        if !v.is_finite() {
            return Err(invalid(path, format!("must be a finite number, got {v}")));
        }
        if v != 0.0 && !(MIN_MAGNITUDE..=MAX_MAGNITUDE).contains(&v.abs()) {
            return Err(invalid(
                path,
                format!(
                    "must be 0 or of magnitude between {MIN_MAGNITUDE:e} and {MAX_MAGNITUDE:e} \
                     (squares and products of scene values must be normal f64 numbers), got {v:e}"
                ),
            ));
        }
        Ok(())
    }
    pub(crate) fn finite2(path: &str, v: [f64; 2]) -> Result<(), SceneError> {
        Checker::finite(&format!("{path}[0]"), v[0])?;
        Checker::finite(&format!("{path}[1]"), v[1])
    }
    pub(crate) fn positive(path: &str, v: f64, what: &str) -> Result<(), SceneError> {
        Checker::finite(path, v)?;
        if v > 0.0 {
            Ok(())
        } else {
            Err(invalid(path, format!("{what} must be > 0, got {v}")))
        }
    }
    pub(crate) fn non_negative(path: &str, v: f64, what: &str) -> Result<(), SceneError> {
        Checker::finite(path, v)?;
        if v >= 0.0 {
            Ok(())
        } else {
            Err(invalid(path, format!("{what} must be >= 0, got {v}")))
        }
    }
}

/// A body or joint name: not empty, and usable as the prefix of a `trajectory.csv` column
/// (`<name>.x`): no comma, no double quote, no control character.
pub(crate) fn check_name(path: &str, name: &str) -> Result<(), SceneError> {
    if name.is_empty() {
        return Err(invalid(path, "must not be empty"));
    }
    if let Some(c) = name
        .chars()
        .find(|c| *c == ',' || *c == '"' || c.is_control())
    {
        return Err(invalid(
            path,
            format!("must not contain {c:?} (names become trajectory.csv column names)"),
        ));
    }
    Ok(())
}

impl Scene {
    /// Checks every value and every reference; the first failure is returned with its JSON path.
    /// (Constraint rank and assembly are checked by [`crate::Mechanism::from_scene`].)
    pub fn validate(&self) -> Result<(), SceneError> {
        type C = Checker;
        if self.bodies.is_empty() {
            return Err(invalid("bodies", "a scene needs at least one body"));
        }
        for (i, b) in self.bodies.iter().enumerate() {
            let p = format!("bodies[{i}]");
            check_name(&format!("{p}.name"), &b.name)?;
            if b.name == GROUND {
                return Err(invalid(
                    format!("{p}.name"),
                    "\"ground\" is reserved for the fixed frame",
                ));
            }
            if self.bodies[..i].iter().any(|o| o.name == b.name) {
                return Err(invalid(
                    format!("{p}.name"),
                    format!("duplicate body name '{}'", b.name),
                ));
            }
            C::positive(&format!("{p}.mass"), b.mass, "mass")?;
            C::positive(&format!("{p}.inertia"), b.inertia, "inertia")?;
            for (name, s) in &b.points {
                C::finite2(&format!("{p}.points.{name}"), *s)?;
            }
            C::finite2(&format!("{p}.position"), b.position)?;
            C::finite(&format!("{p}.angle"), b.angle)?;
            C::finite2(&format!("{p}.velocity"), b.velocity)?;
            C::finite(&format!("{p}.angular_velocity"), b.angular_velocity)?;
            if let Some(iv) = &b.initial_velocity {
                for (f, v) in [("vx", iv.vx), ("vy", iv.vy), ("omega", iv.omega)] {
                    if let Some(v) = v {
                        C::finite(&format!("{p}.initial_velocity.{f}"), v)?;
                    }
                }
            }
        }
        for (i, j) in self.joints.iter().enumerate() {
            let p = format!("joints[{i}]");
            check_name(&format!("{p}.name"), j.name())?;
            if self.joints[..i].iter().any(|o| o.name() == j.name()) {
                return Err(invalid(
                    format!("{p}.name"),
                    format!("duplicate joint name '{}'", j.name()),
                ));
            }
            match j {
                JointSpec::Revolute(r) => {
                    self.check_attachment(&format!("{p}.a"), &r.a.body, &r.a.point, &r.a.at)?;
                    self.check_attachment(&format!("{p}.b"), &r.b.body, &r.b.point, &r.b.at)?;
                    if r.a.body == r.b.body {
                        return Err(invalid(
                            format!("{p}.b.body"),
                            format!(
                                "a revolute joint needs two different bodies, both are '{}'",
                                r.a.body
                            ),
                        ));
                    }
                }
                JointSpec::Translational(t) => {
                    self.check_body_point(&p, &t.body, &t.point)?;
                    C::finite2(&format!("{p}.origin"), t.origin)?;
                    C::finite2(&format!("{p}.direction"), t.direction)?;
                    if t.direction[0] == 0.0 && t.direction[1] == 0.0 {
                        return Err(invalid(
                            format!("{p}.direction"),
                            "must not be the zero vector",
                        ));
                    }
                    if let Some(a) = t.angle {
                        C::finite(&format!("{p}.angle"), a)?;
                    }
                }
                JointSpec::Driver(d) => {
                    self.check_moving_body(&format!("{p}.body"), &d.body)?;
                    C::finite(&format!("{p}.theta0"), d.theta0)?;
                    match (d.omega, d.rpm) {
                        (Some(w), None) => C::finite(&format!("{p}.omega"), w)?,
                        (None, Some(n)) => C::finite(&format!("{p}.rpm"), n)?,
                        (Some(_), Some(_)) => {
                            return Err(invalid(
                                format!("{p}.rpm"),
                                "give either omega (rad/s) or rpm, not both",
                            ))
                        }
                        (None, None) => {
                            return Err(invalid(p.clone(), "a driver needs omega (rad/s) or rpm"))
                        }
                    }
                }
                JointSpec::Clearance(c) => self.check_clearance(&p, c)?,
                JointSpec::PrismaticClearance(c) => {
                    crate::elements::validate_prismatic(self, &p, c)?
                }
            }
            let rate = match j {
                JointSpec::Revolute(r) => r.initial_rate,
                JointSpec::Translational(t) => t.initial_rate,
                _ => None,
            };
            if let Some(v) = rate {
                C::finite(&format!("{p}.initial_rate"), v)?;
            }
        }
        crate::elements::validate_forces(self)?;
        C::finite2("gravity", self.gravity)?;
        C::non_negative("baumgarte.alpha", self.baumgarte.alpha, "alpha")?;
        C::non_negative("baumgarte.beta", self.baumgarte.beta, "beta")?;
        C::finite("t_start", self.t_start)?;
        // Roles.
        if let Some(s) = &self.roles.slider {
            if self.body_index(s).is_none() {
                return Err(invalid("roles.slider", format!("no body named '{s}'")));
            }
        }
        if let Some(d) = &self.roles.crank_driver {
            match self.joint_index(d).map(|k| &self.joints[k]) {
                Some(JointSpec::Driver(_)) => {}
                Some(other) => {
                    return Err(invalid(
                        "roles.crank_driver",
                        format!("joint '{d}' is a {} joint, not a driver", other.type_name()),
                    ))
                }
                None => {
                    return Err(invalid(
                        "roles.crank_driver",
                        format!("no joint named '{d}'"),
                    ))
                }
            }
        }
        if let Some(d) = &self.roles.clearance_joint {
            match self.joint_index(d).map(|k| &self.joints[k]) {
                Some(JointSpec::Clearance(_)) => {}
                Some(other) => {
                    return Err(invalid(
                        "roles.clearance_joint",
                        format!(
                            "joint '{d}' is a {} joint, not a clearance joint",
                            other.type_name()
                        ),
                    ))
                }
                None => {
                    return Err(invalid(
                        "roles.clearance_joint",
                        format!("no joint named '{d}'"),
                    ))
                }
            }
        }
        // Time span.
        match (self.t_end, self.revolutions) {
            (Some(te), None) => {
                C::finite("t_end", te)?;
                if !(te > self.t_start) {
                    return Err(invalid(
                        "t_end",
                        format!("must be greater than t_start = {}, got {te}", self.t_start),
                    ));
                }
                if !(te - self.t_start).is_finite() {
                    return Err(invalid(
                        "t_end",
                        format!(
                            "the time span t_end − t_start = {te:?} − {:?} overflows",
                            self.t_start
                        ),
                    ));
                }
            }
            (None, Some(n)) => {
                C::positive("revolutions", n, "revolutions")?;
                let Some(d) = &self.roles.crank_driver else {
                    return Err(invalid(
                        "revolutions",
                        "needs roles.crank_driver (the driver whose revolutions are counted)",
                    ));
                };
                let k = self.joint_index(d).expect("checked above");
                if let JointSpec::Driver(dr) = &self.joints[k] {
                    let w = dr.omega_rad_s();
                    if w == 0.0 {
                        return Err(invalid(
                            "revolutions",
                            format!("the crank driver '{d}' does not turn (omega = 0)"),
                        ));
                    }
                    // The end time must be a finite time after t_start in f64 (1e300 revolutions
                    // overflow; t_start = 1e300 absorbs any span).
                    let span = n * 2.0 * std::f64::consts::PI / w.abs();
                    let te = self.t_start + span;
                    if !(span.is_finite() && te.is_finite() && te > self.t_start) {
                        return Err(invalid(
                            "revolutions",
                            format!(
                                "the end time t_start + revolutions·2π/|ω| = {:?} + {span:?} s \
                                 is not a finite time after t_start",
                                self.t_start
                            ),
                        ));
                    }
                }
            }
            (Some(_), Some(_)) => {
                return Err(invalid(
                    "revolutions",
                    "give either t_end or revolutions, not both",
                ))
            }
            (None, None) => {
                return Err(invalid(
                    ".",
                    "the scene needs t_end (s) or revolutions (of roles.crank_driver)",
                ))
            }
        }
        Ok(())
    }

    fn check_moving_body(&self, path: &str, body: &str) -> Result<usize, SceneError> {
        if body == GROUND {
            return Err(invalid(path, "must name a moving body, not the ground"));
        }
        self.body_index(body)
            .ok_or_else(|| invalid(path, format!("no body named '{body}'")))
    }

    fn check_body_point(&self, path: &str, body: &str, point: &str) -> Result<(), SceneError> {
        let k = self.check_moving_body(&format!("{path}.body"), body)?;
        if !self.bodies[k].points.contains_key(point) {
            return Err(invalid(
                format!("{path}.point"),
                format!("body '{body}' has no point named '{point}'"),
            ));
        }
        Ok(())
    }

    pub(crate) fn check_attachment(
        &self,
        path: &str,
        body: &str,
        point: &Option<String>,
        at: &Option<[f64; 2]>,
    ) -> Result<(), SceneError> {
        if body == GROUND {
            if point.is_some() {
                return Err(invalid(
                    format!("{path}.point"),
                    "the ground has no named points: give its location with \"at\"",
                ));
            }
            match at {
                Some(a) => Checker::finite2(&format!("{path}.at"), *a),
                None => Err(invalid(
                    format!("{path}.at"),
                    "a ground attachment needs its global location \"at\": [x, y]",
                )),
            }
        } else {
            // The body first: a misspelt "ground" is an unknown body, not a misplaced "at".
            self.check_moving_body(&format!("{path}.body"), body)?;
            if at.is_some() {
                return Err(invalid(
                    format!("{path}.at"),
                    "\"at\" is for ground attachments; name a point of the body instead",
                ));
            }
            match point {
                Some(pt) => self.check_body_point(path, body, pt),
                None => Err(invalid(format!("{path}.point"), "missing the point name")),
            }
        }
    }

    fn check_clearance(&self, p: &str, c: &ClearanceSpec) -> Result<(), SceneError> {
        type C = Checker;
        let b = &c.bearing;
        let j = &c.journal;
        self.check_attachment(&format!("{p}.bearing"), &b.body, &b.point, &b.at)?;
        self.check_attachment(&format!("{p}.journal"), &j.body, &j.point, &j.at)?;
        if b.body == j.body {
            return Err(invalid(
                format!("{p}.journal.body"),
                format!(
                    "bearing and journal must be on different bodies, both are '{}'",
                    b.body
                ),
            ));
        }
        C::positive(&format!("{p}.bearing.radius"), b.radius, "bearing radius")?;
        C::finite(&format!("{p}.journal.radius"), j.radius)?;
        let clearance = b.radius - j.radius;
        if !(clearance > 0.0) {
            return Err(invalid(
                format!("{p}.journal.radius"),
                format!(
                    "clearance R_B − R_J = {clearance} m must be > 0 (bearing radius {}, journal radius {})",
                    b.radius, j.radius
                ),
            ));
        }
        if !(clearance < b.radius) {
            return Err(invalid(
                format!("{p}.journal.radius"),
                format!(
                    "clearance R_B − R_J = {clearance} m must be smaller than the bearing radius {} m (the journal radius must be > 0)",
                    b.radius
                ),
            ));
        }
        let check_k =
            |path: &str, k: &Option<f64>, m: &Option<Materials>| -> Result<(), SceneError> {
                match (k, m) {
                    (Some(k), None) => C::positive(&format!("{path}.k"), *k, "stiffness k"),
                    (None, Some(m)) => {
                        for (side, mat) in [("bearing", m.bearing), ("journal", m.journal)] {
                            let mp = format!("{path}.materials.{side}");
                            C::positive(
                                &format!("{mp}.youngs_modulus"),
                                mat.youngs_modulus,
                                "Young's modulus",
                            )?;
                            C::finite(&format!("{mp}.poisson_ratio"), mat.poisson_ratio)?;
                            if !(mat.poisson_ratio > -1.0 && mat.poisson_ratio < 0.5) {
                                return Err(invalid(
                                    format!("{mp}.poisson_ratio"),
                                    format!(
                                        "Poisson's ratio must lie in (-1, 0.5), got {}",
                                        mat.poisson_ratio
                                    ),
                                ));
                            }
                        }
                        // Within the magnitude range K stays finite and positive (c ≥ ulp(R_B)
                        // bounds K by about E·√(R_B/(2ε)) < 1e233); the check guards the
                        // formula should the range ever be widened.
                        let k = crate::laws::hertz_stiffness(
                            b.radius,
                            j.radius,
                            m.bearing.youngs_modulus,
                            m.bearing.poisson_ratio,
                            m.journal.youngs_modulus,
                            m.journal.poisson_ratio,
                        );
                        if !(k.is_finite() && k > 0.0) {
                            return Err(invalid(
                                format!("{path}.materials"),
                                format!(
                                    "the Hertz stiffness K = {k} N/m^1.5 of these materials is \
                                     not a finite positive number"
                                ),
                            ));
                        }
                        Ok(())
                    }
                    (Some(_), Some(_)) => Err(invalid(
                        format!("{path}.materials"),
                        "give either k or materials, not both",
                    )),
                    (None, None) => Err(invalid(
                        path,
                        "the normal law needs its stiffness: k (N/m^1.5) or materials",
                    )),
                }
            };
        check_contact_laws(p, &c.normal, &c.friction, &check_k)?;
        if let Some(film) = &c.film {
            let fp = format!("{p}.film");
            C::non_negative(&format!("{fp}.viscosity"), film.viscosity, "viscosity")?;
            C::positive(&format!("{fp}.length"), film.length, "bearing length")?;
            if let Some(cap) = film.eps_cap {
                C::finite(&format!("{fp}.eps_cap"), cap)?;
                if !(cap > 0.0 && cap < 1.0) {
                    return Err(invalid(
                        format!("{fp}.eps_cap"),
                        format!("eps_cap must lie in (0, 1) or be null (no cap), got {cap}"),
                    ));
                }
            }
            if let Some(w) = film.omega0 {
                C::positive(&format!("{fp}.omega0"), w, "omega0")?;
                if !matches!(
                    film.model,
                    FilmModel::LongGumbelMirrored | FilmModel::ShortOcvirkMirrored
                ) {
                    return Err(invalid(
                        format!("{fp}.omega0"),
                        "omega0 (the width of the smooth sign of the mirrored models) applies \
                         only to long_gumbel_mirrored and short_ocvirk_mirrored"
                            .to_string(),
                    ));
                }
            }
        }
        C::finite2(&format!("{p}.initial_eccentricity"), c.initial_eccentricity)?;
        C::finite2(
            &format!("{p}.initial_eccentricity_rate"),
            c.initial_eccentricity_rate,
        )?;
        let e0 = c.initial_eccentricity[0].hypot(c.initial_eccentricity[1]);
        if e0 > clearance && !c.allow_initial_penetration {
            return Err(invalid(
                format!("{p}.initial_eccentricity"),
                format!(
                    "|e| = {e0:e} m exceeds the clearance R_B − R_J = {clearance:e} m (the \
                     journal would start {:e} m into the bearing); set \
                     allow_initial_penetration: true to start in contact",
                    e0 - clearance
                ),
            ));
        }
        if !(e0 - clearance < j.radius) {
            return Err(invalid(
                format!("{p}.initial_eccentricity"),
                format!(
                    "|e| = {e0:e} m puts the journal {:e} m into the bearing, beyond the \
                     journal radius {} m: the contact law does not hold there",
                    e0 - clearance,
                    j.radius
                ),
            ));
        }
        Ok(())
    }
}

impl fmt::Display for JointSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} joint '{}'", self.type_name(), self.name())
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
