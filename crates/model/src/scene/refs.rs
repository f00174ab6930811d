//! The ground, attachments, and the seam through which a part of a scene looks up the rest of
//! it while it is checked or compiled.
//!
//! ```text
//! SceneRefs   body_index, body_points                         (bodies and their points)
//!             joint_coordinate(_input), element_length(_input)  (table inputs: a joint's
//!                                                              relative coordinate, a spring's
//!                                                              length)
//! ```
//! The scene's format ([`crate::scene::format::Scene`]) lists the joints and force elements, so their
//! files cannot depend on it without an import circle: they check and compile themselves
//! against [`SceneRefs`], which the scene implements (scene/format.rs). The checks of
//! references every part shares (a moving body, a body point, an attachment) are here too.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::elements::input::{Input, Pt};
use crate::scene::check::Checker;
use crate::scene::error::{invalid, SceneError};

/// The reserved name of the ground (the fixed frame). No body may take it.
pub const GROUND: &str = "ground";

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

/// What a look-up by name found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Lookup {
    /// A part of that name that has what was asked for.
    Found,
    /// A part of that name, of this kind (its `"type"` tag), that has not.
    Other(&'static str),
    /// No part of that name.
    Missing,
}

/// What a part of a scene may look up about the rest of it (module doc). The `_input`
/// methods are for compilation, after the scene has been validated.
pub(crate) trait SceneRefs {
    /// Index of the moving body named `name`.
    fn body_index(&self, name: &str) -> Option<usize>;
    /// The named points of body `k` (local offsets from its centre of mass, m).
    fn body_points(&self, k: usize) -> &BTreeMap<String, [f64; 2]>;
    /// Whether the joint named `name` has a relative coordinate (a table input `of: joint`).
    fn joint_coordinate(&self, name: &str) -> Lookup;
    /// The relative coordinate of the joint named `name` (validated, [`Lookup::Found`]).
    fn joint_coordinate_input(&self, name: &str) -> Input;
    /// Whether the force element named `name` has a length (a table input `of: length`).
    fn element_length(&self, name: &str) -> Lookup;
    /// The length of the force element named `name` (validated, [`Lookup::Found`]).
    fn element_length_input(&self, name: &str) -> Input;
}

/// `None` for the ground, else the index of the (validated) body `name`.
pub(crate) fn body_or_ground(refs: &dyn SceneRefs, name: &str) -> Option<usize> {
    if name == GROUND {
        None
    } else {
        refs.body_index(name)
    }
}

/// The local offset of a validated attachment's point, or the ground location `at`.
pub(crate) fn point_of(refs: &dyn SceneRefs, a: &Attachment) -> [f64; 2] {
    if a.body == GROUND {
        return a.at.expect("validated");
    }
    let k = refs.body_index(&a.body).expect("validated");
    refs.body_points(k)[a.point.as_ref().expect("validated")]
}

/// A validated attachment as a point of a body or of the ground.
pub(crate) fn pt_of(refs: &dyn SceneRefs, a: &Attachment) -> Pt {
    pt_at(refs, &a.body, &a.point, &a.at)
}

/// A validated (body, point) or ground location (`at`) as a point of a body or of the ground.
pub(crate) fn pt_at(
    refs: &dyn SceneRefs,
    body: &str,
    point: &Option<String>,
    at: &Option<[f64; 2]>,
) -> Pt {
    if body == GROUND {
        Pt {
            body: None,
            s: at.expect("validated"),
        }
    } else {
        let k = refs.body_index(body).expect("validated");
        Pt {
            body: Some(k),
            s: refs.body_points(k)[point.as_ref().expect("validated")],
        }
    }
}

/// `body` names a moving body (not the ground): its index.
pub(crate) fn check_moving(
    refs: &dyn SceneRefs,
    path: &str,
    body: &str,
) -> Result<usize, SceneError> {
    if body == GROUND {
        return Err(invalid(path, "must name a moving body, not the ground"));
    }
    refs.body_index(body)
        .ok_or_else(|| invalid(path, format!("no body named '{body}'")))
}

/// `body` names a moving body or the ground.
pub(crate) fn check_body_or_ground(
    refs: &dyn SceneRefs,
    path: &str,
    body: &str,
) -> Result<(), SceneError> {
    if body == GROUND || refs.body_index(body).is_some() {
        Ok(())
    } else {
        Err(invalid(path, format!("no body named '{body}'")))
    }
}

/// `body` is a moving body with a point named `point` (`{path}.body`, `{path}.point`).
pub(crate) fn check_body_point(
    refs: &dyn SceneRefs,
    path: &str,
    body: &str,
    point: &str,
) -> Result<(), SceneError> {
    let k = check_moving(refs, &format!("{path}.body"), body)?;
    if !refs.body_points(k).contains_key(point) {
        return Err(invalid(
            format!("{path}.point"),
            format!("body '{body}' has no point named '{point}'"),
        ));
    }
    Ok(())
}

/// An attachment (or a clearance end): a body point, or a ground location `at`.
pub(crate) fn check_attachment(
    refs: &dyn SceneRefs,
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
        check_moving(refs, &format!("{path}.body"), body)?;
        if at.is_some() {
            return Err(invalid(
                format!("{path}.at"),
                "\"at\" is for ground attachments; name a point of the body instead",
            ));
        }
        match point {
            Some(pt) => check_body_point(refs, path, body, pt),
            None => Err(invalid(format!("{path}.point"), "missing the point name")),
        }
    }
}
