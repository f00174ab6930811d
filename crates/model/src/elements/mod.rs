//! Force elements a researcher brings (docs/model.md §10): springs and dampers, applied forces
//! and torques (constant, or tabulated against time or one coordinate), motors with a
//! torque–speed curve, and the translational clearance joint (block in a guide, §11).
//!
//! ```text
//! spring_damper             F = k (L − L₀) + c L̇   (or F = curve(L) + c L̇), tension > 0
//! rotational_spring_damper  τ = k (θ − θ₀) + c θ̇   (or curve(θ) + c θ̇),  θ = φ_a − φ_b
//! force                     F = f(s) d̂  at a body point, d̂ global or in the body frame
//! torque                    τ = f(s)    on a body
//! motor                     τ = T(ω),  ω = φ̇_rotor − φ̇_stator  (table, or T_s (1 − ω/ω₀))
//! f(s) = value | table(s) piecewise linear, s = t | x, y of a body point | a body angle |
//!        a joint's relative coordinate | a spring's length
//! ```
//! The scene types (`*Spec`) are read and validated here (docs/scene-format.md, "Force
//! elements" and "Prismatic clearance joint"); the compiled elements (`Element`,
//! `Prismatic`) are what the mechanism evaluates. A scene without them runs none of this code.
//!
//! Sources: docs/model.md §10–§11; Flores, Leine and Glocker, Multibody Syst. Dyn. 23 (2010)
//! 165–190 (the block-in-guide geometry); Nikravesh, Computer-Aided Analysis of Mechanical
//! Systems (1988), §5 (point-to-point and rotational spring-damper-actuators).

use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize};

use crate::planar::{dot, rot};
use crate::scene::{
    invalid, object, tagged_object, variant, Attachment, Checker, JointSpec, Scene, SceneError,
    GROUND, PATH_MARK,
};

// ---------------------------------------------------------------------------------------------
// Scene types
// ---------------------------------------------------------------------------------------------

/// What a table does outside its first and last point.
///
/// ```text
/// hold    f(s) = f(s₀) for s < s₀,  f(s) = f(s_n) for s > s_n
/// linear  the first and last segments extended
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outside {
    /// The end values are held (default).
    #[default]
    Hold,
    /// The end segments are extended.
    Linear,
}

/// A piecewise-linear curve: points (s_i, f_i) with s strictly increasing.
///
/// ```text
/// f(s) = f_i + (f_{i+1} − f_i)(s − s_i)/(s_{i+1} − s_i)   for s_i ≤ s ≤ s_{i+1}
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurveSpec {
    /// At least two points [s, f], s strictly increasing.
    pub points: Vec<[f64; 2]>,
    /// Outside the table. Default `hold`.
    #[serde(default)]
    pub outside: Outside,
}

/// A body point (or the centre of mass when `point` is absent).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointRef {
    /// A moving body.
    pub body: String,
    /// A named point of the body. Default: the centre of mass.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<String>,
}

/// A body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyRef {
    /// A moving body.
    pub body: String,
}

/// A joint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointRef {
    /// A revolute, translational or prismatic clearance joint.
    pub joint: String,
}

/// A spring.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ElementRef {
    /// A `spring_damper` force element.
    pub element: String,
}

/// The input s of a table (`"of"` selects it).
///
/// ```text
/// time    s = t (s)
/// x, y    s = x or y of a body point, global (m)
/// angle   s = φ of a body (rad, not wrapped)
/// joint   s = φ_a − φ_b (revolute, rad) | u·(r^P − o) (translational, m) |
///         u·(r_C − o) (prismatic clearance: the block centre along the guide, m)
/// length  s = L of a spring_damper (m)
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "of", rename_all = "snake_case")]
pub enum InputSpec {
    /// Time.
    Time,
    /// Global x of a body point.
    X(PointRef),
    /// Global y of a body point.
    Y(PointRef),
    /// A body's angle.
    Angle(BodyRef),
    /// A joint's relative coordinate.
    Joint(JointRef),
    /// A spring's length.
    Length(ElementRef),
}

/// A tabulated load: a curve of one input.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TableSpec {
    /// The input s.
    pub input: InputSpec,
    /// At least two points [s, f], s strictly increasing.
    pub points: Vec<[f64; 2]>,
    /// Outside the table. Default `hold`.
    #[serde(default)]
    pub outside: Outside,
}

/// When an applied load acts.
///
/// ```text
/// always    f(s) as given
/// opposing  r(v) f(s) while the load opposes the motion (F·v < 0 for a force, τ φ̇ < 0 for a
///           torque), 0 otherwise: a load that is only ever a resistance (a punch cutting);
///           r(v) = min(|v| / v_ramp, 1) with v = d̂·ṙ^P (m/s) or φ̇ (rad/s), so that the
///           load fades in from rest like the friction law's c_d (no sticking at v = 0)
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Acts {
    /// Always (default).
    #[default]
    Always,
    /// Only while it does negative work.
    Opposing,
}

/// In which frame a force's direction is given.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Frame {
    /// Global (default).
    #[default]
    Global,
    /// The body's frame (the direction turns with the body).
    Body,
}

/// Point-to-point spring-damper (docs/model.md §10.1).
///
/// ```text
/// L = |r_b^P − r_a^P|,  L̇ = (r_b^P − r_a^P)·(ṙ_b^P − ṙ_a^P)/L
/// F = k (L − L₀) + c L̇   (F = curve(L) + c L̇ with a force–length curve);  F > 0 pulls
/// f_a = F (r_b − r_a)/L on a, −f_a on b;  V = ½ k (L − L₀)² (or ∫ curve dL);  D = c L̇²
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringDamperSpec {
    /// Unique element name.
    pub name: String,
    /// First end (a body point, or the ground with `at`).
    #[serde(deserialize_with = "object")]
    pub a: Attachment,
    /// Second end.
    #[serde(deserialize_with = "object")]
    pub b: Attachment,
    /// Stiffness k (N/m), ≥ 0. Default 0. Not with `curve`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// Damping c (N·s/m), ≥ 0. Default 0.
    #[serde(default)]
    pub damping: f64,
    /// Free length L₀ (m), ≥ 0. Default: the length at the assembled initial state.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub free_length: Option<f64>,
    /// Force–length curve F(L) (N against m) instead of k (L − L₀).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub curve: Option<CurveSpec>,
}

/// Rotational spring-damper between two bodies' angles (docs/model.md §10.2).
///
/// ```text
/// θ = φ_a − φ_b (φ_ground = 0),  τ = k (θ − θ₀) + c θ̇  (or curve(θ) + c θ̇)
/// torque −τ on a, +τ on b;  V = ½ k (θ − θ₀)² (or ∫ curve dθ);  D = c θ̇²
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotationalSpringDamperSpec {
    /// Unique element name.
    pub name: String,
    /// Body a (a moving body).
    pub a: String,
    /// Body b, or "ground". Default "ground".
    #[serde(default = "ground_name")]
    pub b: String,
    /// Stiffness k (N·m/rad), ≥ 0. Default 0. Not with `curve`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// Damping c (N·m·s/rad), ≥ 0. Default 0.
    #[serde(default)]
    pub damping: f64,
    /// Free angle θ₀ (rad). Default: θ at the assembled initial state.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub free_angle: Option<f64>,
    /// Torque–angle curve τ(θ) (N·m against rad) instead of k (θ − θ₀).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub curve: Option<CurveSpec>,
}

fn ground_name() -> String {
    GROUND.to_string()
}

/// An applied force at a body point (docs/model.md §10.3).
///
/// ```text
/// F = f(s) d̂,  d̂ = direction/|direction| (global) or A(φ) direction/|direction| (body frame)
/// f(s) = value, or the table; 0 while acts = opposing and F·ṙ^P ≥ 0;  P = F·ṙ^P
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceSpec {
    /// Unique element name.
    pub name: String,
    /// The loaded body (moving).
    pub body: String,
    /// Point of application. Default: the centre of mass.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<String>,
    /// Frame of `direction`. Default `global`.
    #[serde(default)]
    pub frame: Frame,
    /// Direction (any length > 0).
    pub direction: [f64; 2],
    /// Constant magnitude f (N). Exactly one of `value` and `table`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<f64>,
    /// Tabulated magnitude f(s) (N). Exactly one of `value` and `table`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table: Option<TableSpec>,
    /// When it acts. Default `always`.
    #[serde(default)]
    pub acts: Acts,
    /// v_ramp of an opposing load (m/s), ≥ 0. Default 1e-4.
    #[serde(default = "default_ramp")]
    pub ramp_speed: f64,
}

fn default_ramp() -> f64 {
    1e-4
}

/// An applied torque on a body (docs/model.md §10.3).
///
/// ```text
/// τ = f(s) (counter-clockwise);  0 while acts = opposing and τ φ̇ ≥ 0;  P = τ φ̇
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TorqueSpec {
    /// Unique element name.
    pub name: String,
    /// The loaded body (moving).
    pub body: String,
    /// Constant torque (N·m). Exactly one of `value` and `table`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<f64>,
    /// Tabulated torque f(s) (N·m). Exactly one of `value` and `table`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table: Option<TableSpec>,
    /// When it acts. Default `always`.
    #[serde(default)]
    pub acts: Acts,
    /// v_ramp of an opposing torque (rad/s), ≥ 0. Default 1e-4.
    #[serde(default = "default_ramp")]
    pub ramp_speed: f64,
}

/// A motor: a torque between a rotor and a stator from its torque–speed curve (docs/model.md
/// §10.4).
///
/// ```text
/// ω = φ̇_rotor − φ̇_stator;  τ = T(ω): the table, or T_s (1 − ω/ω₀) (a DC motor's line)
/// τ on the rotor, −τ on the stator;  P = τ ω
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotorSpec {
    /// Unique element name.
    pub name: String,
    /// The rotor (a moving body).
    pub rotor: String,
    /// The stator: a body or "ground". Default "ground".
    #[serde(default = "ground_name")]
    pub stator: String,
    /// Torque–speed curve: points [ω (rad/s), τ (N·m)]. Not with the line's two numbers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque_speed: Option<CurveSpec>,
    /// Stall torque T_s (N·m) of the line T_s (1 − ω/ω₀).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stall_torque: Option<f64>,
    /// No-load speed ω₀ (rad/s, ≠ 0) of the line. Exactly one of `no_load_speed` and
    /// `no_load_rpm` with `stall_torque`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub no_load_speed: Option<f64>,
    /// No-load speed in revolutions per minute.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub no_load_rpm: Option<f64>,
}

/// A force element (`"type"` selects the variant).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ForceElementSpec {
    /// Point-to-point spring-damper.
    SpringDamper(SpringDamperSpec),
    /// Rotational spring-damper.
    RotationalSpringDamper(RotationalSpringDamperSpec),
    /// Applied force.
    Force(ForceSpec),
    /// Applied torque.
    Torque(TorqueSpec),
    /// Motor.
    Motor(MotorSpec),
}

impl ForceElementSpec {
    /// The element's name.
    pub fn name(&self) -> &str {
        match self {
            ForceElementSpec::SpringDamper(e) => &e.name,
            ForceElementSpec::RotationalSpringDamper(e) => &e.name,
            ForceElementSpec::Force(e) => &e.name,
            ForceElementSpec::Torque(e) => &e.name,
            ForceElementSpec::Motor(e) => &e.name,
        }
    }

    /// The `"type"` tag.
    pub fn type_name(&self) -> &'static str {
        match self {
            ForceElementSpec::SpringDamper(_) => "spring_damper",
            ForceElementSpec::RotationalSpringDamper(_) => "rotational_spring_damper",
            ForceElementSpec::Force(_) => "force",
            ForceElementSpec::Torque(_) => "torque",
            ForceElementSpec::Motor(_) => "motor",
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Tagged enums with full error paths (see scene.rs)
// ---------------------------------------------------------------------------------------------

impl<'de> Deserialize<'de> for ForceElementSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let (tag, obj) = tagged_object::<D>(d, "type")?;
        match tag.as_str() {
            "spring_damper" => variant::<D, _>(obj, "type").map(ForceElementSpec::SpringDamper),
            "rotational_spring_damper" => {
                variant::<D, _>(obj, "type").map(ForceElementSpec::RotationalSpringDamper)
            }
            "force" => variant::<D, _>(obj, "type").map(ForceElementSpec::Force),
            "torque" => variant::<D, _>(obj, "type").map(ForceElementSpec::Torque),
            "motor" => variant::<D, _>(obj, "type").map(ForceElementSpec::Motor),
            other => Err(D::Error::custom(format!(
                "{PATH_MARK}type{PATH_MARK}unknown force element type `{other}`, expected one \
                 of `spring_damper`, `rotational_spring_damper`, `force`, `torque`, `motor`"
            ))),
        }
    }
}

impl<'de> Deserialize<'de> for InputSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let (tag, obj) = tagged_object::<D>(d, "of")?;
        match tag.as_str() {
            "time" => variant::<D, crate::scene::NoData>(obj, "of").map(|_| InputSpec::Time),
            "x" => variant::<D, _>(obj, "of").map(InputSpec::X),
            "y" => variant::<D, _>(obj, "of").map(InputSpec::Y),
            "angle" => variant::<D, _>(obj, "of").map(InputSpec::Angle),
            "joint" => variant::<D, _>(obj, "of").map(InputSpec::Joint),
            "length" => variant::<D, _>(obj, "of").map(InputSpec::Length),
            other => Err(D::Error::custom(format!(
                "{PATH_MARK}of{PATH_MARK}unknown table input `{other}`, expected one of \
                 `time`, `x`, `y`, `angle`, `joint`, `length`"
            ))),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Validation
// ---------------------------------------------------------------------------------------------

fn check_curve(path: &str, points: &[[f64; 2]]) -> Result<(), SceneError> {
    if points.len() < 2 {
        return Err(invalid(
            path,
            format!("a table needs at least 2 points, got {}", points.len()),
        ));
    }
    for (i, p) in points.iter().enumerate() {
        Checker::finite2(&format!("{path}[{i}]"), *p)?;
        if i > 0 && !(p[0] > points[i - 1][0]) {
            return Err(invalid(
                format!("{path}[{i}][0]"),
                format!(
                    "table inputs must increase strictly: {} follows {}",
                    p[0],
                    points[i - 1][0]
                ),
            ));
        }
    }
    Ok(())
}

pub(crate) fn check_moving(scene: &Scene, path: &str, body: &str) -> Result<usize, SceneError> {
    if body == GROUND {
        return Err(invalid(path, "must name a moving body, not the ground"));
    }
    scene
        .body_index(body)
        .ok_or_else(|| invalid(path, format!("no body named '{body}'")))
}

fn check_body_or_ground(scene: &Scene, path: &str, body: &str) -> Result<(), SceneError> {
    if body == GROUND || scene.body_index(body).is_some() {
        Ok(())
    } else {
        Err(invalid(path, format!("no body named '{body}'")))
    }
}

fn check_point_ref(scene: &Scene, path: &str, r: &PointRef) -> Result<(), SceneError> {
    let k = check_moving(scene, &format!("{path}.body"), &r.body)?;
    if let Some(p) = &r.point {
        if !scene.bodies[k].points.contains_key(p) {
            return Err(invalid(
                format!("{path}.point"),
                format!("body '{}' has no point named '{p}'", r.body),
            ));
        }
    }
    Ok(())
}

fn check_input(scene: &Scene, path: &str, input: &InputSpec) -> Result<(), SceneError> {
    match input {
        InputSpec::Time => Ok(()),
        InputSpec::X(r) | InputSpec::Y(r) => check_point_ref(scene, path, r),
        InputSpec::Angle(b) => check_moving(scene, &format!("{path}.body"), &b.body).map(|_| ()),
        InputSpec::Joint(j) => match scene.joint_index(&j.joint).map(|k| &scene.joints[k]) {
            Some(JointSpec::Revolute(_))
            | Some(JointSpec::Translational(_))
            | Some(JointSpec::PrismaticClearance(_)) => Ok(()),
            Some(other) => Err(invalid(
                format!("{path}.joint"),
                format!(
                    "joint '{}' is a {} joint, which has no relative coordinate (revolute, \
                     translational or prismatic_clearance)",
                    j.joint,
                    other.type_name()
                ),
            )),
            None => Err(invalid(
                format!("{path}.joint"),
                format!("no joint named '{}'", j.joint),
            )),
        },
        InputSpec::Length(e) => match scene.forces.iter().find(|f| f.name() == e.element) {
            Some(ForceElementSpec::SpringDamper(_)) => Ok(()),
            Some(other) => Err(invalid(
                format!("{path}.element"),
                format!(
                    "element '{}' is a {}, not a spring_damper (only a spring has a length)",
                    e.element,
                    other.type_name()
                ),
            )),
            None => Err(invalid(
                format!("{path}.element"),
                format!("no force element named '{}'", e.element),
            )),
        },
    }
}

fn check_value_or_table(
    scene: &Scene,
    p: &str,
    value: Option<f64>,
    table: &Option<TableSpec>,
) -> Result<(), SceneError> {
    match (value, table) {
        (Some(v), None) => Checker::finite(&format!("{p}.value"), v),
        (None, Some(t)) => {
            check_input(scene, &format!("{p}.table.input"), &t.input)?;
            check_curve(&format!("{p}.table.points"), &t.points)
        }
        (Some(_), Some(_)) => Err(invalid(
            format!("{p}.table"),
            "give either value or table, not both",
        )),
        (None, None) => Err(invalid(
            p,
            "needs its magnitude: value (a constant) or table (of time or a coordinate)",
        )),
    }
}

fn check_stiffness_or_curve(
    p: &str,
    stiffness: Option<f64>,
    curve: &Option<CurveSpec>,
    what: &str,
) -> Result<(), SceneError> {
    if let Some(k) = stiffness {
        Checker::non_negative(&format!("{p}.stiffness"), k, "stiffness")?;
    }
    if let Some(c) = curve {
        if stiffness.is_some() {
            return Err(invalid(
                format!("{p}.curve"),
                format!("give either stiffness or a {what} curve, not both"),
            ));
        }
        check_curve(&format!("{p}.curve.points"), &c.points)?;
    }
    Ok(())
}

/// Checks every force element of the scene (docs/scene-format.md, "Force elements").
pub(crate) fn validate_forces(scene: &Scene) -> Result<(), SceneError> {
    type C = Checker;
    for (i, f) in scene.forces.iter().enumerate() {
        let p = format!("forces[{i}]");
        crate::scene::check_name(&format!("{p}.name"), f.name())?;
        if scene.forces[..i].iter().any(|o| o.name() == f.name()) {
            return Err(invalid(
                format!("{p}.name"),
                format!("duplicate force element name '{}'", f.name()),
            ));
        }
        match f {
            ForceElementSpec::SpringDamper(s) => {
                scene.check_attachment(&format!("{p}.a"), &s.a.body, &s.a.point, &s.a.at)?;
                scene.check_attachment(&format!("{p}.b"), &s.b.body, &s.b.point, &s.b.at)?;
                if s.a.body == s.b.body {
                    return Err(invalid(
                        format!("{p}.b.body"),
                        format!(
                            "a spring needs two different bodies (or a body and the ground), \
                             both are '{}'",
                            s.a.body
                        ),
                    ));
                }
                check_stiffness_or_curve(&p, s.stiffness, &s.curve, "force–length")?;
                C::non_negative(&format!("{p}.damping"), s.damping, "damping")?;
                if let Some(l0) = s.free_length {
                    C::non_negative(&format!("{p}.free_length"), l0, "free length")?;
                }
            }
            ForceElementSpec::RotationalSpringDamper(s) => {
                check_moving(scene, &format!("{p}.a"), &s.a)?;
                check_body_or_ground(scene, &format!("{p}.b"), &s.b)?;
                if s.a == s.b {
                    return Err(invalid(
                        format!("{p}.b"),
                        format!(
                            "a rotational spring needs two different bodies, both are '{}'",
                            s.a
                        ),
                    ));
                }
                check_stiffness_or_curve(&p, s.stiffness, &s.curve, "torque–angle")?;
                C::non_negative(&format!("{p}.damping"), s.damping, "damping")?;
                if let Some(a) = s.free_angle {
                    C::finite(&format!("{p}.free_angle"), a)?;
                }
            }
            ForceElementSpec::Force(s) => {
                check_point_ref(
                    scene,
                    &p,
                    &PointRef {
                        body: s.body.clone(),
                        point: s.point.clone(),
                    },
                )?;
                C::finite2(&format!("{p}.direction"), s.direction)?;
                if s.direction == [0.0, 0.0] {
                    return Err(invalid(
                        format!("{p}.direction"),
                        "must not be the zero vector",
                    ));
                }
                check_value_or_table(scene, &p, s.value, &s.table)?;
                C::non_negative(&format!("{p}.ramp_speed"), s.ramp_speed, "ramp speed")?;
            }
            ForceElementSpec::Torque(s) => {
                check_moving(scene, &format!("{p}.body"), &s.body)?;
                check_value_or_table(scene, &p, s.value, &s.table)?;
                C::non_negative(&format!("{p}.ramp_speed"), s.ramp_speed, "ramp speed")?;
            }
            ForceElementSpec::Motor(s) => {
                check_moving(scene, &format!("{p}.rotor"), &s.rotor)?;
                check_body_or_ground(scene, &format!("{p}.stator"), &s.stator)?;
                if s.rotor == s.stator {
                    return Err(invalid(
                        format!("{p}.stator"),
                        format!("rotor and stator must differ, both are '{}'", s.rotor),
                    ));
                }
                let line = s.stall_torque.is_some()
                    || s.no_load_speed.is_some()
                    || s.no_load_rpm.is_some();
                match (&s.torque_speed, line) {
                    (Some(c), false) => {
                        check_curve(&format!("{p}.torque_speed.points"), &c.points)?
                    }
                    (Some(_), true) => {
                        return Err(invalid(
                            format!("{p}.torque_speed"),
                            "give either a torque_speed table or stall_torque and a no-load \
                             speed, not both",
                        ))
                    }
                    (None, true) => {
                        let Some(ts) = s.stall_torque else {
                            return Err(invalid(
                                format!("{p}.stall_torque"),
                                "the motor line T_s (1 − ω/ω₀) needs stall_torque (N·m)",
                            ));
                        };
                        C::finite(&format!("{p}.stall_torque"), ts)?;
                        let (w0, wp) =
                            match (s.no_load_speed, s.no_load_rpm) {
                                (Some(w), None) => (w, "no_load_speed"),
                                (None, Some(n)) => (n, "no_load_rpm"),
                                (Some(_), Some(_)) => return Err(invalid(
                                    format!("{p}.no_load_rpm"),
                                    "give either no_load_speed (rad/s) or no_load_rpm, not both",
                                )),
                                (None, None) => return Err(invalid(
                                    format!("{p}.no_load_speed"),
                                    "the motor line T_s (1 − ω/ω₀) needs no_load_speed (rad/s) \
                                     or no_load_rpm",
                                )),
                            };
                        C::finite(&format!("{p}.{wp}"), w0)?;
                        if w0 == 0.0 {
                            return Err(invalid(format!("{p}.{wp}"), "must not be 0"));
                        }
                    }
                    (None, false) => {
                        return Err(invalid(
                            p,
                            "a motor needs a torque_speed table, or stall_torque and \
                             no_load_speed (or no_load_rpm)",
                        ))
                    }
                }
            }
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Compiled elements
// ---------------------------------------------------------------------------------------------

/// A piecewise-linear function with its outside rule; also its integral (for potentials).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Table {
    pub s: Vec<f64>,
    pub f: Vec<f64>,
    pub outside: Outside,
    /// ∫_{s₀}^{s_i} f ds at every table point.
    cum: Vec<f64>,
}

impl Table {
    pub(crate) fn new(points: &[[f64; 2]], outside: Outside) -> Table {
        let s: Vec<f64> = points.iter().map(|p| p[0]).collect();
        let f: Vec<f64> = points.iter().map(|p| p[1]).collect();
        let mut cum = vec![0.0; s.len()];
        for i in 1..s.len() {
            cum[i] = cum[i - 1] + 0.5 * (f[i] + f[i - 1]) * (s[i] - s[i - 1]);
        }
        Table { s, f, outside, cum }
    }

    /// Segment index i (s_i ≤ x < s_{i+1}, clamped to the first and last segments).
    #[inline]
    fn segment(&self, x: f64) -> usize {
        let n = self.s.len();
        self.s.partition_point(|&v| v <= x).clamp(1, n - 1) - 1
    }

    #[inline]
    fn slope(&self, i: usize) -> f64 {
        (self.f[i + 1] - self.f[i]) / (self.s[i + 1] - self.s[i])
    }

    /// f(x).
    #[inline]
    pub(crate) fn eval(&self, x: f64) -> f64 {
        let n = self.s.len();
        if self.outside == Outside::Hold {
            if x <= self.s[0] {
                return self.f[0];
            }
            if x >= self.s[n - 1] {
                return self.f[n - 1];
            }
        }
        let i = self.segment(x);
        self.f[i] + self.slope(i) * (x - self.s[i])
    }

    /// ∫_{s₀}^{x} f ds (exact for the piecewise-linear f and its outside rule).
    pub(crate) fn integral(&self, x: f64) -> f64 {
        let n = self.s.len();
        if self.outside == Outside::Hold {
            if x <= self.s[0] {
                return self.f[0] * (x - self.s[0]);
            }
            if x >= self.s[n - 1] {
                return self.cum[n - 1] + self.f[n - 1] * (x - self.s[n - 1]);
            }
        }
        let i = self.segment(x);
        let fx = self.eval(x);
        self.cum[i] + 0.5 * (self.f[i] + fx) * (x - self.s[i])
    }
}

/// A point of a body (local offset) or of the ground (global).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Pt {
    pub body: Option<usize>,
    pub s: [f64; 2],
}

/// The input s of a table, resolved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Input {
    Time,
    X(Pt),
    Y(Pt),
    Angle(usize),
    /// φ_a − φ_b of a revolute joint (None: the ground).
    Relative(Option<usize>, Option<usize>),
    /// u·(r^P − o) along a line.
    Along {
        p: Pt,
        o: [f64; 2],
        u: [f64; 2],
    },
    /// |r_b − r_a| of two points.
    Length(Pt, Pt),
}

/// A load's magnitude: a constant or a table of an input.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Law {
    Const(f64),
    Table(Table, Input),
}

/// One compiled force element.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Kind {
    Spring {
        a: Pt,
        b: Pt,
        k: f64,
        c: f64,
        l0: f64,
        curve: Option<Table>,
    },
    RotSpring {
        a: usize,
        b: Option<usize>,
        k: f64,
        c: f64,
        theta0: f64,
        curve: Option<Table>,
    },
    Force {
        p: Pt,
        dir: [f64; 2],
        body_frame: bool,
        law: Law,
        /// v_ramp of an opposing load; None: always acts.
        opposing: Option<f64>,
    },
    Torque {
        body: usize,
        law: Law,
        opposing: Option<f64>,
    },
    Motor {
        rotor: usize,
        stator: Option<usize>,
        curve: Table,
    },
}

/// A compiled force element of the scene's `forces` (docs/model.md §10).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Element {
    pub name: String,
    pub kind: Kind,
}

/// What one force element does at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ElementEval {
    /// Force (N) of a spring or force; torque (N·m) of the others.
    pub load: f64,
    /// Spring length L, rotational spring angle θ, motor speed ω (NaN for force, torque).
    pub coord: f64,
    /// Power into the mechanism (force, torque, motor; W).
    pub power: f64,
    /// Power dissipated by the damper (W, ≥ 0).
    pub dissipation: f64,
    /// Elastic potential (J).
    pub potential: f64,
}

impl Element {
    /// Column suffixes of the element in trajectory.csv (docs/outputs.md).
    pub(crate) fn columns(&self) -> &'static [&'static str] {
        match self.kind {
            Kind::Spring { .. } => &["force", "length"],
            Kind::RotSpring { .. } => &["torque", "angle"],
            Kind::Force { .. } => &["force"],
            Kind::Torque { .. } => &["torque"],
            Kind::Motor { .. } => &["torque", "speed"],
        }
    }
}

/// r(v) of an opposing load f at speed v along it: min(|v|/v_ramp, 1) when f v < 0, else 0.
#[inline]
fn opposing_factor(f: f64, v: f64, ramp: f64) -> f64 {
    if f * v < 0.0 {
        if v.abs() >= ramp {
            1.0
        } else {
            v.abs() / ramp
        }
    } else {
        0.0
    }
}

/// Position and velocity of a point; ω of its body (0 for the ground).
#[inline]
pub(crate) fn point_state(
    p: &Pt,
    pose: &[[f64; 3]],
    vel: &[[f64; 3]],
    cs: &[[f64; 2]],
) -> ([f64; 2], [f64; 2], [f64; 2]) {
    match p.body {
        None => (p.s, [0.0; 2], [0.0; 2]),
        Some(k) => {
            let a = rot(cs[k], p.s);
            let [x, y, _] = pose[k];
            let [vx, vy, w] = vel[k];
            ([x + a[0], y + a[1]], [vx - w * a[1], vy + w * a[0]], a)
        }
    }
}

#[inline]
fn angle_of(b: Option<usize>, pose: &[[f64; 3]]) -> f64 {
    b.map_or(0.0, |k| pose[k][2])
}

#[inline]
fn omega_of(b: Option<usize>, vel: &[[f64; 3]]) -> f64 {
    b.map_or(0.0, |k| vel[k][2])
}

impl Input {
    #[inline]
    pub(crate) fn value(
        &self,
        t: f64,
        pose: &[[f64; 3]],
        vel: &[[f64; 3]],
        cs: &[[f64; 2]],
    ) -> f64 {
        match *self {
            Input::Time => t,
            Input::X(p) => point_state(&p, pose, vel, cs).0[0],
            Input::Y(p) => point_state(&p, pose, vel, cs).0[1],
            Input::Angle(k) => pose[k][2],
            Input::Relative(a, b) => angle_of(a, pose) - angle_of(b, pose),
            Input::Along { p, o, u } => {
                let r = point_state(&p, pose, vel, cs).0;
                dot(u, [r[0] - o[0], r[1] - o[1]])
            }
            Input::Length(a, b) => {
                let ra = point_state(&a, pose, vel, cs).0;
                let rb = point_state(&b, pose, vel, cs).0;
                (rb[0] - ra[0]).hypot(rb[1] - ra[1])
            }
        }
    }
}

impl Law {
    #[inline]
    fn value(&self, t: f64, pose: &[[f64; 3]], vel: &[[f64; 3]], cs: &[[f64; 2]]) -> f64 {
        match self {
            Law::Const(v) => *v,
            Law::Table(tab, input) => tab.eval(input.value(t, pose, vel, cs)),
        }
    }
}

/// A generalized force on one body: (body, force at the global arm from the centre of mass).
pub(crate) type Load = (usize, [f64; 2], [f64; 2], f64);

impl Element {
    /// Evaluates the element; `apply(body, arm, force, torque)` receives every load.
    #[inline]
    pub(crate) fn eval(
        &self,
        t: f64,
        pose: &[[f64; 3]],
        vel: &[[f64; 3]],
        cs: &[[f64; 2]],
        mut apply: impl FnMut(Load),
    ) -> ElementEval {
        let mut out = ElementEval {
            coord: f64::NAN,
            ..ElementEval::default()
        };
        match &self.kind {
            Kind::Spring {
                a,
                b,
                k,
                c,
                l0,
                curve,
            } => {
                let (ra, va, arm_a) = point_state(a, pose, vel, cs);
                let (rb, vb, arm_b) = point_state(b, pose, vel, cs);
                let d = [rb[0] - ra[0], rb[1] - ra[1]];
                let len = d[0].hypot(d[1]);
                // At zero length the line is undefined: no force (docs/model.md §10.1).
                let e = if len > 0.0 {
                    [d[0] / len, d[1] / len]
                } else {
                    [0.0; 2]
                };
                let ldot = dot(e, [vb[0] - va[0], vb[1] - va[1]]);
                let (elastic, pot) = match curve {
                    Some(tab) => (tab.eval(len), tab.integral(len)),
                    None => (k * (len - l0), 0.5 * k * (len - l0) * (len - l0)),
                };
                let f = elastic + c * ldot;
                let fa = [f * e[0], f * e[1]];
                if let Some(ka) = a.body {
                    apply((ka, arm_a, fa, 0.0));
                }
                if let Some(kb) = b.body {
                    apply((kb, arm_b, [-fa[0], -fa[1]], 0.0));
                }
                out.load = f;
                out.coord = len;
                out.dissipation = c * ldot * ldot;
                out.potential = pot;
            }
            Kind::RotSpring {
                a,
                b,
                k,
                c,
                theta0,
                curve,
            } => {
                let th = pose[*a][2] - angle_of(*b, pose);
                let thd = vel[*a][2] - omega_of(*b, vel);
                let (elastic, pot) = match curve {
                    Some(tab) => (tab.eval(th), tab.integral(th)),
                    None => (k * (th - theta0), 0.5 * k * (th - theta0) * (th - theta0)),
                };
                let tau = elastic + c * thd;
                apply((*a, [0.0; 2], [0.0; 2], -tau));
                if let Some(kb) = b {
                    apply((*kb, [0.0; 2], [0.0; 2], tau));
                }
                out.load = tau;
                out.coord = th;
                out.dissipation = c * thd * thd;
                out.potential = pot;
            }
            Kind::Force {
                p,
                dir,
                body_frame,
                law,
                opposing,
            } => {
                let (_, v, arm) = point_state(p, pose, vel, cs);
                let k = p.body.expect("forces act on bodies");
                let d = if *body_frame { rot(cs[k], *dir) } else { *dir };
                let mut f = law.value(t, pose, vel, cs);
                if let Some(ramp) = opposing {
                    f *= opposing_factor(f, dot(d, v), *ramp);
                }
                apply((k, arm, [f * d[0], f * d[1]], 0.0));
                out.load = f;
                out.power = f * dot(d, v);
            }
            Kind::Torque {
                body,
                law,
                opposing,
            } => {
                let w = vel[*body][2];
                let mut tau = law.value(t, pose, vel, cs);
                if let Some(ramp) = opposing {
                    tau *= opposing_factor(tau, w, *ramp);
                }
                apply((*body, [0.0; 2], [0.0; 2], tau));
                out.load = tau;
                out.power = tau * w;
            }
            Kind::Motor {
                rotor,
                stator,
                curve,
            } => {
                let w = vel[*rotor][2] - omega_of(*stator, vel);
                let tau = curve.eval(w);
                apply((*rotor, [0.0; 2], [0.0; 2], tau));
                if let Some(ks) = stator {
                    apply((*ks, [0.0; 2], [0.0; 2], -tau));
                }
                out.load = tau;
                out.coord = w;
                out.power = tau * w;
            }
        }
        out
    }
}

/// Compiles the scene's force elements (validated).
pub(crate) fn compile(scene: &Scene, initial: &dyn Fn(&Input) -> f64) -> Vec<Element> {
    let pt = |a: &Attachment| -> Pt {
        if a.body == GROUND {
            Pt {
                body: None,
                s: a.at.expect("validated"),
            }
        } else {
            let k = scene.body_index(&a.body).expect("validated");
            Pt {
                body: Some(k),
                s: scene.bodies[k].points[a.point.as_ref().expect("validated")],
            }
        }
    };
    let body_opt = |b: &str| -> Option<usize> {
        if b == GROUND {
            None
        } else {
            scene.body_index(b)
        }
    };
    let point_ref = |r: &PointRef| -> Pt {
        let k = scene.body_index(&r.body).expect("validated");
        Pt {
            body: Some(k),
            s: r.point
                .as_ref()
                .map_or([0.0; 2], |p| scene.bodies[k].points[p]),
        }
    };
    let input = |i: &InputSpec| -> Input {
        match i {
            InputSpec::Time => Input::Time,
            InputSpec::X(r) => Input::X(point_ref(r)),
            InputSpec::Y(r) => Input::Y(point_ref(r)),
            InputSpec::Angle(b) => Input::Angle(scene.body_index(&b.body).expect("validated")),
            InputSpec::Joint(j) => {
                match &scene.joints[scene.joint_index(&j.joint).expect("validated")] {
                    JointSpec::Revolute(r) => {
                        Input::Relative(body_opt(&r.a.body), body_opt(&r.b.body))
                    }
                    JointSpec::Translational(tr) => {
                        let k = scene.body_index(&tr.body).expect("validated");
                        let l = tr.direction[0].hypot(tr.direction[1]);
                        Input::Along {
                            p: Pt {
                                body: Some(k),
                                s: scene.bodies[k].points[&tr.point],
                            },
                            o: tr.origin,
                            u: [tr.direction[0] / l, tr.direction[1] / l],
                        }
                    }
                    JointSpec::PrismaticClearance(pc) => {
                        let k = scene.body_index(&pc.block.body).expect("validated");
                        let d = pc.guide.direction;
                        let l = d[0].hypot(d[1]);
                        Input::Along {
                            p: Pt {
                                body: Some(k),
                                s: scene.bodies[k].points[&pc.block.point],
                            },
                            o: pc.guide.at,
                            u: [d[0] / l, d[1] / l],
                        }
                    }
                    _ => unreachable!("validated"),
                }
            }
            InputSpec::Length(e) => match scene.forces.iter().find(|f| f.name() == e.element) {
                Some(ForceElementSpec::SpringDamper(s)) => Input::Length(pt(&s.a), pt(&s.b)),
                _ => unreachable!("validated"),
            },
        }
    };
    let law = |value: Option<f64>, table: &Option<TableSpec>| match (value, table) {
        (Some(v), _) => Law::Const(v),
        (None, Some(t)) => Law::Table(Table::new(&t.points, t.outside), input(&t.input)),
        (None, None) => unreachable!("validated"),
    };
    scene
        .forces
        .iter()
        .map(|f| {
            let kind = match f {
                ForceElementSpec::SpringDamper(s) => {
                    let (a, b) = (pt(&s.a), pt(&s.b));
                    Kind::Spring {
                        a,
                        b,
                        k: s.stiffness.unwrap_or(0.0),
                        c: s.damping,
                        l0: s
                            .free_length
                            .unwrap_or_else(|| initial(&Input::Length(a, b))),
                        curve: s.curve.as_ref().map(|c| Table::new(&c.points, c.outside)),
                    }
                }
                ForceElementSpec::RotationalSpringDamper(s) => {
                    let a = scene.body_index(&s.a).expect("validated");
                    let b = body_opt(&s.b);
                    Kind::RotSpring {
                        a,
                        b,
                        k: s.stiffness.unwrap_or(0.0),
                        c: s.damping,
                        theta0: s
                            .free_angle
                            .unwrap_or_else(|| initial(&Input::Relative(Some(a), b))),
                        curve: s.curve.as_ref().map(|c| Table::new(&c.points, c.outside)),
                    }
                }
                ForceElementSpec::Force(s) => {
                    let k = scene.body_index(&s.body).expect("validated");
                    let l = s.direction[0].hypot(s.direction[1]);
                    Kind::Force {
                        p: Pt {
                            body: Some(k),
                            s: s.point
                                .as_ref()
                                .map_or([0.0; 2], |p| scene.bodies[k].points[p]),
                        },
                        dir: [s.direction[0] / l, s.direction[1] / l],
                        body_frame: s.frame == Frame::Body,
                        law: law(s.value, &s.table),
                        opposing: (s.acts == Acts::Opposing).then_some(s.ramp_speed),
                    }
                }
                ForceElementSpec::Torque(s) => Kind::Torque {
                    body: scene.body_index(&s.body).expect("validated"),
                    law: law(s.value, &s.table),
                    opposing: (s.acts == Acts::Opposing).then_some(s.ramp_speed),
                },
                ForceElementSpec::Motor(s) => {
                    let curve = match &s.torque_speed {
                        Some(c) => Table::new(&c.points, c.outside),
                        None => {
                            let ts = s.stall_torque.expect("validated");
                            let w0 = s
                                .no_load_speed
                                .or(s.no_load_rpm.map(|n| n * std::f64::consts::PI / 30.0))
                                .expect("validated");
                            // The line through (0, T_s) and (ω₀, 0), extended both ways.
                            let mut pts = [[0.0, ts], [w0, 0.0]];
                            pts.sort_by(|a, b| a[0].total_cmp(&b[0]));
                            Table::new(&pts, Outside::Linear)
                        }
                    };
                    Kind::Motor {
                        rotor: scene.body_index(&s.rotor).expect("validated"),
                        stator: body_opt(&s.stator),
                        curve,
                    }
                }
            };
            Element {
                name: f.name().to_string(),
                kind,
            }
        })
        .collect()
}
