//! The scene's own types (serde): the scene, bodies, ideal joints and drivers, the joint table.

use std::collections::BTreeMap;
use std::fmt;

use serde::{Deserialize, Serialize};

use crate::clearance::prismatic::PrismaticClearanceSpec;
use crate::clearance::revolute::ClearanceSpec;
use crate::elements::input::{Input, Pt};
use crate::elements::ForceElementSpec;
use crate::scene::de::{object, object_opt, objects, tagged_kinds};
use crate::scene::names::BodyNames;
use crate::scene::refs::{body_or_ground, Attachment, Lookup, SceneRefs};
use crate::scene::solver::SolverSpec;

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
    /// each. `None` (the field absent): automatic, on for a scene with a dry revolute
    /// clearance joint whose laws have a kink ([`crate::Mechanism::kink_events`] holds the
    /// value a mechanism resolved); `Some(_)` as the scene says. Serialised only when given,
    /// so a scene round-trips.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kink_events: Option<bool>,
    /// How the constraint equations are enforced (the state layout and the acceleration
    /// solve: crates/model/src/mechanism/formulation). Default `auto`.
    #[serde(default, skip_serializing_if = "FormulationName::is_default")]
    pub formulation: FormulationName,
    /// The augmented Lagrangian's parameters (read when `formulation` is
    /// `augmented_lagrangian`, and by `minimal`'s loop closures). Defaults:
    /// [`AugmentedLagrangianParams::default`].
    #[serde(
        default,
        skip_serializing_if = "AugmentedLagrangianParams::is_default",
        deserialize_with = "object"
    )]
    pub augmented_lagrangian: AugmentedLagrangianParams,
    /// The integration settings the scene asks for where a run gives none
    /// (crate::scene::solver; docs/scene-format.md). Default: none.
    #[serde(
        default,
        skip_serializing_if = "SolverSpec::is_empty",
        deserialize_with = "object"
    )]
    pub solver: SolverSpec,
    /// The body index by name (a cache; crate::scene::names).
    #[serde(skip)]
    pub(crate) body_names: BodyNames,
}

/// The formulations a scene (or `--formulation`) can choose (docs/model.md §12).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FormulationName {
    /// Lagrange multipliers with Baumgarte stabilisation (the paper's; docs/model.md §1).
    /// Needs a constraint Jacobian of full row rank.
    LagrangeBaumgarte,
    /// The augmented Lagrangian of Bayo & Ledesma (1996) in the same absolute coordinates
    /// (docs/model.md §12): its leading matrix M + Φ_qᵀαΦ_q stays positive definite through
    /// singular configurations and with redundant constraints.
    AugmentedLagrangian,
    /// Joint coordinates on the spanning tree of the ideal joints (docs/model.md §12): the
    /// state is the tree's coordinates only; the joints that close a loop are kept as
    /// constraints on the reduced system, enforced by the augmented Lagrangian.
    Minimal,
    /// The cheapest formulation that is correct for the scene (docs/model.md §12): `minimal`
    /// for a tree of at most [`FormulationName::AUTO_MINIMAL_MAX_DOF`] degrees of freedom,
    /// `augmented_lagrangian` otherwise. The default.
    #[default]
    Auto,
}

impl FormulationName {
    /// Its name as the scene field and the flag spell it.
    pub fn as_str(self) -> &'static str {
        match self {
            FormulationName::LagrangeBaumgarte => "lagrange_baumgarte",
            FormulationName::AugmentedLagrangian => "augmented_lagrangian",
            FormulationName::Minimal => "minimal",
            FormulationName::Auto => "auto",
        }
    }

    /// Every formulation, in the order of the docs.
    pub const ALL: [FormulationName; 4] = [
        FormulationName::LagrangeBaumgarte,
        FormulationName::AugmentedLagrangian,
        FormulationName::Minimal,
        FormulationName::Auto,
    ];

    /// The most degrees of freedom of a tree that `auto` gives to `minimal`. Measured
    /// (`cargo bench -p lash-benches --bench rhs -- formulation_chain`: a chain of n links, one
    /// right-hand side): minimal costs 0.58, 1.5, 10, 74, 504 µs at n = 4, 8, 16, 32, 64 (its
    /// dense Rᵀ M R grows like n³), the augmented Lagrangian 2.8, 7.0, 23, 75, 138 µs (banded);
    /// they cross at n ≈ 32, and 24 keeps minimal where it is clearly the cheaper.
    pub const AUTO_MINIMAL_MAX_DOF: usize = 24;

    fn is_default(&self) -> bool {
        *self == FormulationName::default()
    }
}

impl std::str::FromStr for FormulationName {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        FormulationName::ALL
            .into_iter()
            .find(|f| f.as_str() == s)
            .ok_or_else(|| {
                format!(
                    "unknown formulation '{s}' (one of: {})",
                    FormulationName::ALL.map(|f| f.as_str()).join(", ")
                )
            })
    }
}

impl fmt::Display for FormulationName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Parameters of the augmented Lagrangian formulation (docs/model.md §12), also those of the
/// minimal formulation's loop closures (the same equations on the reduced system).
///
/// ```text
/// (M + Φ_qᵀ α Φ_q) q̈ = Q − Φ_qᵀ λ* + Φ_qᵀ α (γ − 2ξω Φ̇ − ω² Φ),
/// λ* ← λ* + α (Φ_q q̈ − (γ − 2ξω Φ̇ − ω² Φ))   until max|Δq̈| ≤ tol · max|q̈|
/// α = penalty · (mean mass of the integrated bodies, kg)
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AugmentedLagrangianParams {
    /// α per kilogram of mean body mass (the scale of Φ_qᵀαΦ_q against M), > 0. Default 1e4:
    /// each iteration reduces the error of the multipliers by about 1/(1 + α σ(Φ_q M⁻¹ Φ_qᵀ))
    /// (4–5 iterations to 1e-12 at σ ~ 1/m), while the iteration's rounding floor in q̈ grows
    /// like ε·α‖Φ_q‖²/m: the book's α = 1e7 (García de Jalón & Bayo 1994, §5.3) leaves q̈
    /// 1e-9 off and an energy drift of 1.6e-8 on IFToMM A01 at rtol 1e-10; 1e4 gives 1e-11.
    /// Near singular positions a larger α corrects more (1e2 is 100× worse on A02 N = 2).
    #[serde(default = "al_penalty")]
    pub penalty: f64,
    /// Damping ratio ξ of the constraint violation Φ̈ + 2ξωΦ̇ + ω²Φ = 0, ≥ 0. Default 1
    /// (critical damping: the fastest decay without overshoot).
    #[serde(default = "al_xi")]
    pub xi: f64,
    /// Natural frequency ω of the constraint violation (rad/s), ≥ 0. Default 10 (García de
    /// Jalón & Bayo 1994: a decay time 1/ω = 0.1 s, slower than any motion of interest of a
    /// mechanism it would otherwise stiffen).
    #[serde(default = "al_omega")]
    pub omega: f64,
    /// Relative tolerance of the multiplier iteration on q̈, in (0, 1). Default 1e-12 (near
    /// the rounding of the solve, so that q̈ is a function of (t, y) to the last digits an
    /// error estimate at rtol 1e-10 reads).
    #[serde(default = "al_tol")]
    pub tol: f64,
    /// Iterations before the evaluation counts as unconverged (the last iterate is used and
    /// counted in the statistics), ≥ 1. Default 20.
    #[serde(default = "al_max_iter")]
    pub max_iterations: usize,
}

fn al_penalty() -> f64 {
    1e4
}
fn al_xi() -> f64 {
    1.0
}
fn al_omega() -> f64 {
    10.0
}
fn al_tol() -> f64 {
    1e-12
}
fn al_max_iter() -> usize {
    20
}

impl Default for AugmentedLagrangianParams {
    fn default() -> Self {
        AugmentedLagrangianParams {
            penalty: al_penalty(),
            xi: al_xi(),
            omega: al_omega(),
            tol: al_tol(),
            max_iterations: al_max_iter(),
        }
    }
}

impl AugmentedLagrangianParams {
    fn is_default(&self) -> bool {
        *self == AugmentedLagrangianParams::default()
    }
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
/// slider: BODY,  crank_driver: driver JOINT,  clearance_joint: clearance JOINT,
/// crank: BODY | revolute JOINT  (the crank angle φ_body, or φ_a − φ_b of the joint;
///        crank_driver implies crank = the driver's body)
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
    /// The crank whose angle counts revolutions: a body, or a revolute joint (its relative
    /// angle φ_a − φ_b). Default: the crank driver's body, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crank: Option<String>,
}

tagged_kinds! {
    /// A joint of the scene (`"type"` selects the variant).
    ///
    /// ```text
    /// revolute       Φ = r_a^P − r_b^P                      (2 equations)
    /// translational  Φ = (n·(r^P − o), φ − φ₀)              (2 equations)
    /// driver         Φ = φ − θ₀ − ω t                       (1 equation)
    /// clearance      no equation: the force pair of docs/model.md §2–§4
    /// prismatic_clearance  no equation: the corner contacts of docs/model.md §11
    /// ```
    pub enum JointSpec named, tag "type", unknown "joint type" {
        /// Ideal revolute joint.
        "revolute" => Revolute(RevoluteSpec),
        /// Translational joint along a global line.
        "translational" => Translational(TranslationalSpec),
        /// Rotational driver.
        "driver" => Driver(DriverSpec),
        /// Revolute clearance joint.
        "clearance" => Clearance(ClearanceSpec),
        /// Translational clearance joint (a block in a guide).
        "prismatic_clearance" => PrismaticClearance(PrismaticClearanceSpec),
    }
}

impl Scene {
    /// Index of the body named `name`.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.body_names
            .index(name, self.bodies.len(), |k| self.bodies[k].name.as_str())
    }

    /// Index of the joint named `name`.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name() == name)
    }
}

impl RevoluteSpec {
    /// Its relative coordinate φ_a − φ_b (validated).
    fn coordinate(&self, refs: &dyn SceneRefs) -> Input {
        Input::Relative(
            body_or_ground(refs, &self.a.body),
            body_or_ground(refs, &self.b.body),
        )
    }
}

impl TranslationalSpec {
    /// Its relative coordinate u·(r^P − o) (validated).
    fn coordinate(&self, refs: &dyn SceneRefs) -> Input {
        let k = refs.body_index(&self.body).expect("validated");
        let l = self.direction[0].hypot(self.direction[1]);
        Input::Along {
            p: Pt {
                body: Some(k),
                s: refs.body_points(k)[&self.point],
            },
            o: self.origin,
            u: [self.direction[0] / l, self.direction[1] / l],
        }
    }
}

impl SceneRefs for Scene {
    fn body_index(&self, name: &str) -> Option<usize> {
        Scene::body_index(self, name)
    }

    fn body_points(&self, k: usize) -> &BTreeMap<String, [f64; 2]> {
        &self.bodies[k].points
    }

    fn joint_coordinate(&self, name: &str) -> Lookup {
        match self.joint_index(name).map(|k| &self.joints[k]) {
            Some(JointSpec::Revolute(_))
            | Some(JointSpec::Translational(_))
            | Some(JointSpec::PrismaticClearance(_)) => Lookup::Found,
            Some(other) => Lookup::Other(other.type_name()),
            None => Lookup::Missing,
        }
    }

    fn joint_coordinate_input(&self, name: &str) -> Input {
        match &self.joints[self.joint_index(name).expect("validated")] {
            JointSpec::Revolute(r) => r.coordinate(self),
            JointSpec::Translational(t) => t.coordinate(self),
            JointSpec::PrismaticClearance(p) => p.coordinate(self),
            _ => unreachable!("validated"),
        }
    }

    fn element_length(&self, name: &str) -> Lookup {
        match self.forces.iter().find(|f| f.name() == name) {
            Some(f) if f.has_length() => Lookup::Found,
            Some(f) => Lookup::Other(f.type_name()),
            None => Lookup::Missing,
        }
    }

    fn element_length_input(&self, name: &str) -> Input {
        let f = self.forces.iter().find(|f| f.name() == name);
        f.and_then(|f| f.length(self)).expect("validated")
    }
}

impl fmt::Display for JointSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} joint '{}'", self.type_name(), self.name())
    }
}
