//! Bodies: how each moves (integrated or prescribed) and the prescriptions of driven bodies.

use std::collections::BTreeMap;

/// How a body moves: integrated (index into q) or prescribed (index into the prescriptions).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Owner {
    Int(usize),
    Pres(usize),
}

#[derive(Clone, Debug)]
pub(crate) struct BodyInfo {
    pub name: String,
    pub mass: f64,
    pub inertia: f64,
    pub points: BTreeMap<String, [f64; 2]>,
    pub owner: Owner,
}

/// A prescribed body: φ = θ₀ + ω t, and its point `s_own` pinned to a ground location or to a
/// point of an earlier prescribed body.
#[derive(Clone, Debug)]
pub(crate) struct Prescription {
    pub body: usize,
    pub theta0: f64,
    pub omega: f64,
    pub s_own: [f64; 2],
    /// Parent body and its local point; None: the ground at `ground_at`.
    pub parent: Option<(usize, [f64; 2])>,
    pub ground_at: [f64; 2],
    pub driver_joint: usize,
}
