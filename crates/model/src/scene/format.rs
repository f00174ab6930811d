//! The scene's own types (serde): the scene, bodies, ideal joints and drivers, the joint table.

use std::collections::BTreeMap;
use std::fmt;

use serde::{Deserialize, Serialize};

use crate::clearance::prismatic::PrismaticClearanceSpec;
use crate::clearance::revolute::ClearanceSpec;
use crate::elements::input::{Input, Pt};
use crate::elements::ForceElementSpec;
use crate::scene::de::{object, object_opt, objects, tagged_kinds};
use crate::scene::refs::{body_or_ground, Attachment, Lookup, SceneRefs};

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
        self.bodies.iter().position(|b| b.name == name)
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
