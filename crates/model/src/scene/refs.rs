//! The ground and attachments: how a scene part names a body point or a ground location.

use serde::{Deserialize, Serialize};

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
