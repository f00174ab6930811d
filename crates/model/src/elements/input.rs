//! What force elements compute from: points of bodies, the inputs s of tables, tables
//! themselves and constant-or-tabulated magnitudes, all resolved to body indices.
//!
//! ```text
//! Pt      a body point (local s) or a ground point (global s)
//! Input   s = t | x, y of a point | φ of a body | φ_a − φ_b | u·(r^P − o) | |r_b − r_a|
//! Table   f(s) piecewise linear with its outside rule, and ∫ f ds (potentials)
//! Law     f = value | table(s)
//! Kin     the poses, velocities and (cos φ, sin φ) of every body at one instant
//! ```
//! Source: docs/model.md §10.

use serde::{Deserialize, Serialize};

use crate::planar::{dot, rot};

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

/// The poses (x, y, φ), velocities (ẋ, ẏ, φ̇) and (cos φ, sin φ) of every body of a scene at
/// one instant, in scene order.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Kin<'a> {
    pub pose: &'a [[f64; 3]],
    pub vel: &'a [[f64; 3]],
    pub cs: &'a [[f64; 2]],
}

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

/// A generalized force on one body: (body, force at the global arm from the centre of mass).
pub(crate) type Load = (usize, [f64; 2], [f64; 2], f64);

/// r(v) of an opposing load f at speed v along it: min(|v|/v_ramp, 1) when f v < 0, else 0.
#[inline]
pub(crate) fn opposing_factor(f: f64, v: f64, ramp: f64) -> f64 {
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

/// Position and velocity of a point, and its arm A s from its body's centre of mass (0 for
/// the ground).
#[inline]
pub(crate) fn point_state(p: &Pt, kin: &Kin<'_>) -> ([f64; 2], [f64; 2], [f64; 2]) {
    match p.body {
        None => (p.s, [0.0; 2], [0.0; 2]),
        Some(k) => {
            let a = rot(kin.cs[k], p.s);
            let [x, y, _] = kin.pose[k];
            let [vx, vy, w] = kin.vel[k];
            ([x + a[0], y + a[1]], [vx - w * a[1], vy + w * a[0]], a)
        }
    }
}

/// φ of a body (0 for the ground).
#[inline]
pub(crate) fn angle_of(b: Option<usize>, kin: &Kin<'_>) -> f64 {
    b.map_or(0.0, |k| kin.pose[k][2])
}

/// φ̇ of a body (0 for the ground).
#[inline]
pub(crate) fn omega_of(b: Option<usize>, kin: &Kin<'_>) -> f64 {
    b.map_or(0.0, |k| kin.vel[k][2])
}

impl Input {
    /// s at t and the poses of `kin`.
    #[inline]
    pub(crate) fn value(&self, t: f64, kin: &Kin<'_>) -> f64 {
        match *self {
            Input::Time => t,
            Input::X(p) => point_state(&p, kin).0[0],
            Input::Y(p) => point_state(&p, kin).0[1],
            Input::Angle(k) => kin.pose[k][2],
            Input::Relative(a, b) => angle_of(a, kin) - angle_of(b, kin),
            Input::Along { p, o, u } => {
                let r = point_state(&p, kin).0;
                dot(u, [r[0] - o[0], r[1] - o[1]])
            }
            Input::Length(a, b) => {
                let ra = point_state(&a, kin).0;
                let rb = point_state(&b, kin).0;
                (rb[0] - ra[0]).hypot(rb[1] - ra[1])
            }
        }
    }
}

impl Law {
    /// The magnitude at t and the poses of `kin`.
    #[inline]
    pub(crate) fn value(&self, t: f64, kin: &Kin<'_>) -> f64 {
        match self {
            Law::Const(v) => *v,
            Law::Table(tab, input) => tab.eval(input.value(t, kin)),
        }
    }
}
