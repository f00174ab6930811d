//! Small planar vector helpers shared by every part of the model.
//!
//! ```text
//! rot(cs, v) = A(φ) v,  (c, s) = (cos φ, sin φ);  perp(v) = k × v;  cross(a, b) = a × b;  dot
//! ```

/// A(φ) s with (c, s) = (cos φ, sin φ).
#[inline]
pub(crate) fn rot(cs: [f64; 2], v: [f64; 2]) -> [f64; 2] {
    [cs[0] * v[0] - cs[1] * v[1], cs[1] * v[0] + cs[0] * v[1]]
}

/// k × v = (−v_y, v_x).
#[inline]
pub(crate) fn perp(v: [f64; 2]) -> [f64; 2] {
    [-v[1], v[0]]
}

#[inline]
pub(crate) fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

#[inline]
pub(crate) fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
