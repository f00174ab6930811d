//! The prismatic clearance joint (docs/model.md §11): a block in a guide, its scene types, its
//! checks, its compiled form and its evaluation.

use std::cell::Cell;

use serde::{Deserialize, Serialize};

use crate::clearance::contact::{
    check_contact_laws, friction_law, normal_law, FrictionSpec, Materials, NormalSpec,
};
use crate::clearance::laws::{FrictionLaw, NormalLaw};
use crate::elements::input::{point_state, Input, Kin, Load, Pt};
use crate::labels::EventLabels;
use crate::mechanism::row::{Row, Term, TermKind};
use crate::planar::{dot, perp, rot};
use crate::scene::check::Checker;
use crate::scene::de::object;
use crate::scene::error::{invalid, SceneError};
use crate::scene::refs::{check_moving, SceneRefs, GROUND};

/// The guide of a prismatic clearance joint: a line through a ground point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GuideSpec {
    /// "ground" (a guide on a moving body is not supported).
    pub body: String,
    /// A point of the guide's centre line, global (m).
    pub at: [f64; 2],
    /// Direction u of the guide, global (any length > 0). Default [1, 0].
    #[serde(default = "default_direction")]
    pub direction: [f64; 2],
    /// Distance between the two faces h (m), > block width.
    pub width: f64,
}

fn default_direction() -> [f64; 2] {
    [1.0, 0.0]
}

/// The block of a prismatic clearance joint: a rectangle on a body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlockSpec {
    /// The sliding body (moving).
    pub body: String,
    /// The block's centre C (a point of the body).
    pub point: String,
    /// The block's axis a in the body frame (any length > 0). Default [1, 0].
    #[serde(default = "default_direction")]
    pub axis: [f64; 2],
    /// Length ℓ along the axis (m), > 0.
    pub length: f64,
    /// Width w across the axis (m), > 0 and < the guide's width.
    pub width: f64,
}

/// Translational clearance joint: a block in a guide, its four corners in contact with the
/// guide's two faces (docs/model.md §11; Flores, Leine and Glocker 2010).
///
/// ```text
/// corners P_i = r_C + A(φ)(±ℓ/2 â ± w/2 â⊥),  σ_i = ±1 the side of the corner
/// y_i = n·(P_i − o),  δ_i = σ_i y_i − h/2   (contact iff δ_i > 0),  n = u rotated +90°
/// on the block at P_i: −σ_i F_N,i n + F_T,i u;  F_N the normal law, F_T the friction law of
/// the revolute clearance joint with v_T = u·Ṗ_i;  c = (h − w)/2 the clearance
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrismaticClearanceSpec {
    /// Unique joint name.
    pub name: String,
    /// The guide.
    #[serde(deserialize_with = "object")]
    pub guide: GuideSpec,
    /// The block.
    #[serde(deserialize_with = "object")]
    pub block: BlockSpec,
    /// Normal contact law (its stiffness as `k`; `materials` need radii and are refused).
    pub normal: NormalSpec,
    /// Friction law. Default none.
    #[serde(default)]
    pub friction: FrictionSpec,
    /// Initial offset of the block centre from the guide's centre line, n·(r_C − o) (m).
    /// Default 0.
    #[serde(default)]
    pub initial_offset: f64,
    /// Initial tilt of the block axis from the guide (rad). Default 0.
    #[serde(default)]
    pub initial_tilt: f64,
    /// Initial rate of the offset (m/s). Default 0.
    #[serde(default)]
    pub initial_offset_rate: f64,
    /// Initial rate of the tilt (rad/s). Default 0.
    #[serde(default)]
    pub initial_tilt_rate: f64,
    /// Accept an initial pose whose corners penetrate a face. Default false.
    #[serde(default)]
    pub allow_initial_penetration: bool,
}

impl PrismaticClearanceSpec {
    /// Its relative coordinate u·(r_C − o), the block centre along the guide (validated).
    pub(crate) fn coordinate(&self, refs: &dyn SceneRefs) -> Input {
        let k = refs.body_index(&self.block.body).expect("validated");
        let d = self.guide.direction;
        let l = d[0].hypot(d[1]);
        Input::Along {
            p: Pt {
                body: Some(k),
                s: refs.body_points(k)[&self.block.point],
            },
            o: self.guide.at,
            u: [d[0] / l, d[1] / l],
        }
    }

    /// Radial clearance c = (h − w)/2 (m).
    pub fn clearance(&self) -> f64 {
        0.5 * (self.guide.width - self.block.width)
    }

    /// The deepest corner penetration max_i δ_i (m) of a pose with the given offset and tilt.
    pub fn penetration_at(&self, offset: f64, tilt: f64) -> f64 {
        let (s, c) = tilt.sin_cos();
        let half_l = 0.5 * self.block.length;
        let half_w = 0.5 * self.block.width;
        half_l * s.abs() + half_w * c + offset.abs() - 0.5 * self.guide.width
    }
}

/// Checks a prismatic clearance joint (docs/scene-format.md, "Prismatic clearance joint"): its
/// guide, its block, its contact laws, its initial pose.
pub(crate) fn validate(
    refs: &dyn SceneRefs,
    p: &str,
    s: &PrismaticClearanceSpec,
) -> Result<(), SceneError> {
    check_guide(p, s)?;
    check_block(refs, p, s)?;
    check_contact_laws(p, &s.normal, &s.friction, &check_stiffness)?;
    check_initial_pose(p, s)
}

type C = Checker;

/// The guide: the ground, a finite line of non-zero direction, a positive width.
fn check_guide(p: &str, s: &PrismaticClearanceSpec) -> Result<(), SceneError> {
    if s.guide.body != GROUND {
        return Err(invalid(
            format!("{p}.guide.body"),
            format!(
                "the guide must be the ground (a guide on a moving body is not supported), got \
                 '{}'",
                s.guide.body
            ),
        ));
    }
    C::finite2(&format!("{p}.guide.at"), s.guide.at)?;
    C::finite2(&format!("{p}.guide.direction"), s.guide.direction)?;
    if s.guide.direction == [0.0, 0.0] {
        return Err(invalid(
            format!("{p}.guide.direction"),
            "must not be the zero vector",
        ));
    }
    C::positive(&format!("{p}.guide.width"), s.guide.width, "guide width")?;
    Ok(())
}

/// The block: a point of a moving body, a non-zero axis, positive sizes narrower than the
/// guide.
fn check_block(
    refs: &dyn SceneRefs,
    p: &str,
    s: &PrismaticClearanceSpec,
) -> Result<(), SceneError> {
    let k = check_moving(refs, &format!("{p}.block.body"), &s.block.body)?;
    if !refs.body_points(k).contains_key(&s.block.point) {
        return Err(invalid(
            format!("{p}.block.point"),
            format!(
                "body '{}' has no point named '{}'",
                s.block.body, s.block.point
            ),
        ));
    }
    C::finite2(&format!("{p}.block.axis"), s.block.axis)?;
    if s.block.axis == [0.0, 0.0] {
        return Err(invalid(
            format!("{p}.block.axis"),
            "must not be the zero vector",
        ));
    }
    C::positive(&format!("{p}.block.length"), s.block.length, "block length")?;
    C::positive(&format!("{p}.block.width"), s.block.width, "block width")?;
    if !(s.block.width < s.guide.width) {
        return Err(invalid(
            format!("{p}.block.width"),
            format!(
                "the block width {} m must be smaller than the guide width {} m (clearance \
                 (h − w)/2 > 0)",
                s.block.width, s.guide.width
            ),
        ));
    }
    Ok(())
}

/// The normal law's stiffness at `np`: a flat guide face has no radii, so the stiffness is
/// given (k > 0), never derived from materials.
fn check_stiffness(np: &str, k: &Option<f64>, m: &Option<Materials>) -> Result<(), SceneError> {
    if m.is_some() {
        return Err(invalid(
            format!("{np}.materials"),
            "a flat guide face has no radii for the Hertz stiffness: give k (N/m^1.5)",
        ));
    }
    match k {
        Some(k) => C::positive(&format!("{np}.k"), *k, "stiffness k"),
        None => Err(invalid(
            np.to_string(),
            "the normal law needs its stiffness k (N/m^1.5)",
        )),
    }
}

/// The initial offset, tilt and their rates: finite, nearly aligned, and clear of the faces
/// (or, allowed, in contact at most half the block's width deep).
fn check_initial_pose(p: &str, s: &PrismaticClearanceSpec) -> Result<(), SceneError> {
    C::finite(&format!("{p}.initial_offset"), s.initial_offset)?;
    C::finite(&format!("{p}.initial_tilt"), s.initial_tilt)?;
    C::finite(&format!("{p}.initial_offset_rate"), s.initial_offset_rate)?;
    C::finite(&format!("{p}.initial_tilt_rate"), s.initial_tilt_rate)?;
    let tilt_max = (s.guide.width / s.block.length.hypot(s.block.width))
        .min(1.0)
        .asin();
    if !(s.initial_tilt.abs() < std::f64::consts::FRAC_PI_4) {
        return Err(invalid(
            format!("{p}.initial_tilt"),
            format!(
                "the block must start nearly aligned with its guide (|tilt| < π/4), got {}",
                s.initial_tilt
            ),
        ));
    }
    let pen = s.penetration_at(s.initial_offset, s.initial_tilt);
    if pen > 0.0 {
        let at = if s.initial_offset.abs() * s.initial_tilt.cos() >= pen {
            "initial_offset"
        } else {
            "initial_tilt"
        };
        if !s.allow_initial_penetration {
            return Err(invalid(
                format!("{p}.{at}"),
                format!(
                    "the block starts with a corner {pen:e} m into a guide face (offset {} m, \
                     tilt {} rad, clearance {} m); set allow_initial_penetration: true to \
                     start in contact",
                    s.initial_offset,
                    s.initial_tilt,
                    s.clearance()
                ),
            ));
        }
        if !(pen < 0.5 * s.block.width) || s.initial_tilt.abs() > tilt_max {
            return Err(invalid(
                format!("{p}.{at}"),
                format!(
                    "the block starts {pen:e} m into a guide face, more than half its width \
                     ({} m): the corners' contact geometry no longer holds",
                    0.5 * s.block.width
                ),
            ));
        }
    }
    Ok(())
}

/// The event function of each corner of a prismatic clearance joint: its gap δ_i
/// (docs/model.md §7, §11).
pub(crate) const CORNER_CONTACT: EventLabels = EventLabels {
    kind: "corner_contact",
    rising: "corner_contact_onset",
    falling: "corner_contact_loss",
};

/// A compiled prismatic clearance joint (docs/model.md §11).
#[derive(Debug)]
pub(crate) struct Prismatic {
    pub joint: usize,
    pub name: String,
    pub body: usize,
    /// The block centre, local.
    pub s_c: [f64; 2],
    /// The corners, local offsets from the body's centre of mass, and their sides σ.
    pub corners: [([f64; 2], f64); 4],
    pub o: [f64; 2],
    pub u: [f64; 2],
    pub n: [f64; 2],
    pub half_h: f64,
    pub clearance: f64,
    /// Block axis angle in the body frame minus the guide's angle.
    pub angle_offset: f64,
    pub normal: NormalLaw,
    pub friction: Option<FrictionLaw>,
    pub offset0: f64,
    pub tilt0: f64,
    pub offset_rate0: f64,
    pub tilt_rate0: f64,
    /// δ̇⁻ of each corner at its last contact onset.
    pub impact_velocity: [Cell<f64>; 4],
}

/// One prismatic clearance joint at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct PrismaticEval {
    pub delta: [f64; 4],
    pub delta_dot: [f64; 4],
    pub v_t: [f64; 4],
    pub f_n: [f64; 4],
    pub f_t: [f64; 4],
    pub elastic: [f64; 4],
    pub offset: f64,
    pub tilt: f64,
}

impl Prismatic {
    /// Builds the joint from its validated spec.
    pub(crate) fn new(refs: &dyn SceneRefs, ji: usize, s: &PrismaticClearanceSpec) -> Prismatic {
        let k = refs.body_index(&s.block.body).expect("validated");
        let s_c = refs.body_points(k)[&s.block.point];
        let la = s.block.axis[0].hypot(s.block.axis[1]);
        let a = [s.block.axis[0] / la, s.block.axis[1] / la];
        let ap = perp(a);
        let (hl, hw) = (0.5 * s.block.length, 0.5 * s.block.width);
        let corner = |sl: f64, sw: f64| {
            (
                [
                    s_c[0] + sl * hl * a[0] + sw * hw * ap[0],
                    s_c[1] + sl * hl * a[1] + sw * hw * ap[1],
                ],
                sw,
            )
        };
        let lu = s.guide.direction[0].hypot(s.guide.direction[1]);
        let u = [s.guide.direction[0] / lu, s.guide.direction[1] / lu];
        let normal = normal_law(&s.normal, |k, _| k.expect("validated"));
        let friction = friction_law(&s.friction);
        Prismatic {
            joint: ji,
            name: s.name.clone(),
            body: k,
            s_c,
            corners: [
                corner(1.0, 1.0),
                corner(-1.0, 1.0),
                corner(-1.0, -1.0),
                corner(1.0, -1.0),
            ],
            o: s.guide.at,
            u,
            n: perp(u),
            half_h: 0.5 * s.guide.width,
            clearance: s.clearance(),
            angle_offset: a[1].atan2(a[0]) - u[1].atan2(u[0]),
            normal,
            friction,
            offset0: s.initial_offset,
            tilt0: s.initial_tilt,
            offset_rate0: s.initial_offset_rate,
            tilt_rate0: s.initial_tilt_rate,
            impact_velocity: Default::default(),
        }
    }

    /// The equations held during the initial assembly (docs/model.md §1.6): the block's
    /// offset and tilt at their initial values and rates (rows "offset", "tilt"); none when
    /// its body is not integrated.
    pub(crate) fn assembly_rows(&self, integrated: &dyn Fn(usize) -> bool, t0: f64) -> Vec<Row> {
        if !integrated(self.body) {
            return Vec::new();
        }
        let mut r1 = Row::new(self.joint, "offset");
        r1.push(Term {
            body: self.body,
            kind: TermKind::Point {
                s: self.s_c,
                w: self.n,
            },
        });
        r1.konst = -(self.n[0] * self.o[0] + self.n[1] * self.o[1]) - self.offset0;
        let mut r2 = Row::new(self.joint, "tilt");
        r2.push(Term {
            body: self.body,
            kind: TermKind::Angle { c: 1.0 },
        });
        r2.konst = self.angle_offset - self.tilt0;
        vec![
            r1.with_rate(self.offset_rate0, t0),
            r2.with_rate(self.tilt_rate0, t0),
        ]
    }

    /// The gap δ_i and its rate δ̇_i of corner i.
    #[inline]
    pub(crate) fn corner_gap(&self, i: usize, kin: &Kin<'_>) -> (f64, f64) {
        let (s, side) = self.corners[i];
        let (r, v, _) = point_state(
            &Pt {
                body: Some(self.body),
                s,
            },
            kin,
        );
        let y = dot(self.n, [r[0] - self.o[0], r[1] - self.o[1]]);
        (side * y - self.half_h, side * dot(self.n, v))
    }

    /// Forces of the four corners; `apply` receives each contact load on the block.
    #[inline]
    pub(crate) fn eval(&self, kin: &Kin<'_>, mut apply: impl FnMut(Load)) -> PrismaticEval {
        let k = self.body;
        let mut ev = PrismaticEval::default();
        for i in 0..4 {
            let (s, side) = self.corners[i];
            let (r, v, arm) = point_state(&Pt { body: Some(k), s }, kin);
            let d = [r[0] - self.o[0], r[1] - self.o[1]];
            let delta = side * dot(self.n, d) - self.half_h;
            let ddot = side * dot(self.n, v);
            let vt = dot(self.u, v);
            ev.delta[i] = delta;
            ev.delta_dot[i] = ddot;
            ev.v_t[i] = vt;
            if delta > 0.0 {
                let fnn = self
                    .normal
                    .force(delta, ddot, self.impact_velocity[i].get());
                let ft = self.friction.map_or(0.0, |f| f.force(vt, fnn));
                ev.f_n[i] = fnn;
                ev.f_t[i] = ft;
                ev.elastic[i] = self.normal.stiffness() * delta * delta.sqrt();
                let f = [
                    -side * fnn * self.n[0] + ft * self.u[0],
                    -side * fnn * self.n[1] + ft * self.u[1],
                ];
                apply((k, arm, f, 0.0));
            }
        }
        let c = rot(kin.cs[k], self.s_c);
        let rc = [kin.pose[k][0] + c[0], kin.pose[k][1] + c[1]];
        ev.offset = dot(self.n, [rc[0] - self.o[0], rc[1] - self.o[1]]);
        ev.tilt = kin.pose[k][2] + self.angle_offset;
        ev
    }
}
