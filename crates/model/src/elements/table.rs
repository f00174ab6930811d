//! Tables and their inputs as a scene gives them (the `table`, `curve` and `torque_speed` of
//! the force elements, docs/scene-format.md "Tables"): their types, checks and compilation.
//!
//! ```text
//! table = {input: {of: time | x | y | angle | joint | length, …}, points: [[s, f], …],
//!          outside: hold | linear}
//! curve = {points, outside}       (an element's own coordinate as the input)
//! ```

use serde::{Deserialize, Serialize};

use crate::elements::input::{Input, Law, Outside, Pt, Table};
use crate::scene::check::Checker;
use crate::scene::de::tagged_kinds;
use crate::scene::error::{invalid, SceneError};
use crate::scene::refs::{check_moving, Lookup, SceneRefs, GROUND};

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

tagged_kinds! {
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
    pub enum InputSpec, tag "of", unknown "table input" {
        /// Time.
        "time" => Time,
        /// Global x of a body point.
        "x" => X(PointRef),
        /// Global y of a body point.
        "y" => Y(PointRef),
        /// A body's angle.
        "angle" => Angle(BodyRef),
        /// A joint's relative coordinate.
        "joint" => Joint(JointRef),
        /// A spring's length.
        "length" => Length(ElementRef),
    }
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

/// "ground", the default stator or second body.
pub(crate) fn ground_name() -> String {
    GROUND.to_string()
}

/// The default v_ramp of an opposing load (m/s or rad/s).
pub(crate) fn default_ramp() -> f64 {
    1e-4
}

// ---------------------------------------------------------------------------------------------
// Checks
// ---------------------------------------------------------------------------------------------

/// At least two points, each finite, the inputs strictly increasing.
pub(crate) fn check_curve(path: &str, points: &[[f64; 2]]) -> Result<(), SceneError> {
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

/// A body point (or the centre of mass): a moving body, and its point if named.
pub(crate) fn check_point_ref(
    refs: &dyn SceneRefs,
    path: &str,
    r: &PointRef,
) -> Result<(), SceneError> {
    let k = check_moving(refs, &format!("{path}.body"), &r.body)?;
    if let Some(p) = &r.point {
        if !refs.body_points(k).contains_key(p) {
            return Err(invalid(
                format!("{path}.point"),
                format!("body '{}' has no point named '{p}'", r.body),
            ));
        }
    }
    Ok(())
}

/// A table's input: its body, point, joint or element exists and has the coordinate.
pub(crate) fn check_input(
    refs: &dyn SceneRefs,
    path: &str,
    input: &InputSpec,
) -> Result<(), SceneError> {
    match input {
        InputSpec::Time => Ok(()),
        InputSpec::X(r) | InputSpec::Y(r) => check_point_ref(refs, path, r),
        InputSpec::Angle(b) => check_moving(refs, &format!("{path}.body"), &b.body).map(|_| ()),
        InputSpec::Joint(j) => match refs.joint_coordinate(&j.joint) {
            Lookup::Found => Ok(()),
            Lookup::Other(kind) => Err(invalid(
                format!("{path}.joint"),
                format!(
                    "joint '{}' is a {kind} joint, which has no relative coordinate (revolute, \
                     translational or prismatic_clearance)",
                    j.joint,
                ),
            )),
            Lookup::Missing => Err(invalid(
                format!("{path}.joint"),
                format!("no joint named '{}'", j.joint),
            )),
        },
        InputSpec::Length(e) => match refs.element_length(&e.element) {
            Lookup::Found => Ok(()),
            Lookup::Other(kind) => Err(invalid(
                format!("{path}.element"),
                format!(
                    "element '{}' is a {kind}, not a spring_damper (only a spring has a length)",
                    e.element,
                ),
            )),
            Lookup::Missing => Err(invalid(
                format!("{path}.element"),
                format!("no force element named '{}'", e.element),
            )),
        },
    }
}

/// Exactly one of a constant `value` and a `table` (path `{p}.value`, `{p}.table`).
pub(crate) fn check_value_or_table(
    refs: &dyn SceneRefs,
    p: &str,
    value: Option<f64>,
    table: &Option<TableSpec>,
) -> Result<(), SceneError> {
    match (value, table) {
        (Some(v), None) => Checker::finite(&format!("{p}.value"), v),
        (None, Some(t)) => {
            check_input(refs, &format!("{p}.table.input"), &t.input)?;
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

/// At most one of `stiffness` (≥ 0) and a `curve` (a `what` table, e.g. "force–length").
pub(crate) fn check_stiffness_or_curve(
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

// ---------------------------------------------------------------------------------------------
// Compilation (of validated specs)
// ---------------------------------------------------------------------------------------------

/// A body point (the centre of mass when no point is named).
pub(crate) fn point_ref(refs: &dyn SceneRefs, r: &PointRef) -> Pt {
    let k = refs.body_index(&r.body).expect("validated");
    Pt {
        body: Some(k),
        s: r.point
            .as_ref()
            .map_or([0.0; 2], |p| refs.body_points(k)[p]),
    }
}

/// The resolved input of a table.
pub(crate) fn input(refs: &dyn SceneRefs, i: &InputSpec) -> Input {
    match i {
        InputSpec::Time => Input::Time,
        InputSpec::X(r) => Input::X(point_ref(refs, r)),
        InputSpec::Y(r) => Input::Y(point_ref(refs, r)),
        InputSpec::Angle(b) => Input::Angle(refs.body_index(&b.body).expect("validated")),
        InputSpec::Joint(j) => refs.joint_coordinate_input(&j.joint),
        InputSpec::Length(e) => refs.element_length_input(&e.element),
    }
}

/// A constant `value` or a `table` as a [`Law`].
pub(crate) fn law(refs: &dyn SceneRefs, value: Option<f64>, table: &Option<TableSpec>) -> Law {
    match (value, table) {
        (Some(v), _) => Law::Const(v),
        (None, Some(t)) => Law::Table(Table::new(&t.points, t.outside), input(refs, &t.input)),
        (None, None) => unreachable!("validated"),
    }
}

/// A curve as a [`Table`].
pub(crate) fn curve(c: &CurveSpec) -> Table {
    Table::new(&c.points, c.outside)
}
