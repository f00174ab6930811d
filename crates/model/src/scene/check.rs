//! Value checks shared by every part of a scene: finite numbers in range, names.

use crate::scene::error::{invalid, SceneError};

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
