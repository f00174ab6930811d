//! The revolute clearance joint (docs/model.md §2–§4): its compiled form and its evaluation.

use std::cell::Cell;

use serde::{Deserialize, Deserializer, Serialize};

use crate::clearance::contact::{FrictionSpec, NormalSpec};
use crate::clearance::geometry::ClearanceState;
use crate::clearance::laws::{
    hertz_stiffness, Film, FilmModel, FrictionLaw, NormalLaw, DEFAULT_MIRROR_WIDTH,
};
use crate::scene::de::{object, object_opt};
use crate::scene::{Scene, GROUND};

/// One side of a clearance joint: an attachment with a radius.
///
/// ```text
/// r^P as for [`Attachment`]; R (m) the bearing (hole) or journal (pin) radius
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClearanceEnd {
    /// Body name, or "ground".
    pub body: String,
    /// Point name on the body (bodies only): the centre of the hole or pin.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<String>,
    /// Global location (m) (ground only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<[f64; 2]>,
    /// Radius (m), > 0.
    pub radius: f64,
}

/// Revolute clearance joint (docs/model.md §2–§4): no constraint, a force pair.
///
/// ```text
/// e = r_J^P − r_B^P,  c = R_B − R_J,  δ = |e| − c
/// f_J = −F_N n + F_T t (at Q_J = r_J^P + R_J n) [+ F_r n + F_t t at P_J with a film]
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClearanceSpec {
    /// Unique joint name.
    pub name: String,
    /// The bearing (hole), radius R_B.
    #[serde(deserialize_with = "object")]
    pub bearing: ClearanceEnd,
    /// The journal (pin), radius R_J < R_B.
    #[serde(deserialize_with = "object")]
    pub journal: ClearanceEnd,
    /// Normal contact law.
    pub normal: NormalSpec,
    /// Friction law. Default none.
    #[serde(default)]
    pub friction: FrictionSpec,
    /// Hydrodynamic film. Default none (dry joint).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "object_opt"
    )]
    pub film: Option<FilmSpec>,
    /// Initial eccentricity e(t_start), global (m). Default [0, 0] (centred). |e| must not
    /// exceed the clearance unless `allow_initial_penetration` is set.
    #[serde(default)]
    pub initial_eccentricity: [f64; 2],
    /// Initial eccentricity rate ė(t_start), global (m/s). Default [0, 0].
    #[serde(default, skip_serializing_if = "is_zero2")]
    pub initial_eccentricity_rate: [f64; 2],
    /// Accept |e(t_start)| > c (a start in contact, up to the journal radius). Default false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub allow_initial_penetration: bool,
}

fn is_zero2(v: &[f64; 2]) -> bool {
    *v == [0.0, 0.0]
}

/// Hydrodynamic film of a lubricated clearance joint (docs/model.md §4).
///
/// ```text
/// F_r, F_t = film model(ε_eff, ε̇, Ω);  R = R_J, c = R_B − R_J
/// ε_eff = min(ε, ε_cap)  ("eps_cap": number, default 0.99)
///       = min(ε, 1 − 1e-12)  ("eps_cap": null: no cap, the law at the true ε)
/// mirrored models: sign(Ω) → tanh(Ω/Ω₀)  ("omega0": Ω₀ > 0, rad/s, default 0.01)
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilmSpec {
    /// Film model. Default `long_gumbel` (the paper's formula).
    #[serde(default = "default_film_model")]
    pub model: FilmModel,
    /// Dynamic viscosity μ (Pa·s), ≥ 0.
    pub viscosity: f64,
    /// Bearing length L (m), > 0.
    pub length: f64,
    /// Eccentricity cap ε_cap in (0, 1), or `None` (JSON `null`): no cap. An absent field is
    /// the default cap 0.99, not `None`.
    #[serde(default = "default_eps_cap", deserialize_with = "nullable")]
    pub eps_cap: Option<f64>,
    /// Width Ω₀ of the smooth sign of the mirrored models (rad/s), > 0; only with a mirrored
    /// model. Default [`crate::laws::DEFAULT_MIRROR_WIDTH`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub omega0: Option<f64>,
}

fn default_film_model() -> FilmModel {
    FilmModel::LongGumbel
}
fn default_eps_cap() -> Option<f64> {
    Some(0.99)
}
/// A number or `null` (`None`); the field's absence is handled by its `default`.
fn nullable<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    Option::<f64>::deserialize(d)
}

/// One side of a clearance joint: a body point (local s) or a ground location (global s).
#[derive(Clone, Copy, Debug)]
pub(crate) struct End {
    pub body: Option<usize>,
    pub s: [f64; 2],
}

#[derive(Debug)]
pub(crate) struct Clr {
    pub joint: usize,
    pub name: String,
    pub bearing: End,
    pub journal: End,
    pub rb: f64,
    pub rj: f64,
    pub c: f64,
    pub normal: NormalLaw,
    pub friction: Option<FrictionLaw>,
    pub film: Option<Film>,
    pub e0: [f64; 2],
    /// ė(t_start) (m/s).
    pub e0_rate: [f64; 2],
    /// δ̇⁻ stored at the last contact onset (event hook).
    pub impact_velocity: Cell<f64>,
}

/// The points where the force laws of a revolute clearance joint have a kink in time while it
/// is in contact (docs/model.md §7), each an event when the run asks for them:
///
/// ```text
/// FullDamping  g = δ − d_max                   (IMPACT: STEP's damping reaches c_max)
/// Clip         g = r(δ, δ̇) in contact, else 1  (F_N's clip at 0, NormalLaw::unclipped_ratio)
/// SlipV0       g = v_T² − v₀² in contact, else 1  (c_d leaves 0)
/// SlipV1       g = v_T² − v₁² in contact, else 1  (c_d reaches 1)
/// ```
/// Outside contact the laws act not at all, so the last three are held at 1 there; at contact
/// onset r → 1 (continuous), and the slip functions jump only when the contact begins below
/// v₁, where the onset's own restart already covers the kink.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kink {
    FullDamping,
    Clip,
    SlipV0,
    SlipV1,
}

/// Per-joint results of one evaluation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ClrEval {
    pub st: ClearanceState,
    pub f_n: f64,
    pub f_t: f64,
    pub f_r: f64,
    pub f_tf: f64,
    pub elastic: f64,
}

impl Default for ClrEval {
    fn default() -> Self {
        ClrEval {
            st: ClearanceState {
                e: [0.0; 2],
                e_norm: 0.0,
                n: [1.0, 0.0],
                t: [0.0, 1.0],
                delta: 0.0,
                delta_dot: 0.0,
                v_t: 0.0,
                eps: 0.0,
                eps_dot: 0.0,
                omega: 0.0,
            },
            f_n: 0.0,
            f_t: 0.0,
            f_r: 0.0,
            f_tf: 0.0,
            elastic: 0.0,
        }
    }
}

fn end_of(scene: &Scene, e: &ClearanceEnd) -> End {
    if e.body == GROUND {
        End {
            body: None,
            s: e.at.expect("validated"),
        }
    } else {
        let k = scene.body_index(&e.body).expect("validated");
        End {
            body: Some(k),
            s: scene.bodies[k].points[e.point.as_ref().expect("validated")],
        }
    }
}

pub(crate) fn build_clearance(scene: &Scene, ji: usize, c: &crate::scene::ClearanceSpec) -> Clr {
    let rb = c.bearing.radius;
    let rj = c.journal.radius;
    let stiffness = |k: Option<f64>, m: Option<crate::scene::Materials>| match (k, m) {
        (Some(k), _) => k,
        (None, Some(m)) => hertz_stiffness(
            rb,
            rj,
            m.bearing.youngs_modulus,
            m.bearing.poisson_ratio,
            m.journal.youngs_modulus,
            m.journal.poisson_ratio,
        ),
        (None, None) => unreachable!("validated"),
    };
    let normal = match &c.normal {
        NormalSpec::Impact(s) => NormalLaw::Impact {
            k: stiffness(s.k, s.materials),
            c_max: s.c_max,
            d_max: s.d_max,
        },
        NormalSpec::LankaraniNikravesh(s) => NormalLaw::LankaraniNikravesh {
            k: stiffness(s.k, s.materials),
            restitution: s.restitution,
        },
        NormalSpec::Flores(s) => NormalLaw::Flores {
            k: stiffness(s.k, s.materials),
            restitution: s.restitution,
        },
        NormalSpec::HuntCrossley(s) => NormalLaw::HuntCrossley {
            k: stiffness(s.k, s.materials),
            restitution: s.restitution,
        },
    };
    let friction = match &c.friction {
        FrictionSpec::None => None,
        FrictionSpec::Coulomb(f) if f.mu == 0.0 => None,
        FrictionSpec::Coulomb(f) => Some(FrictionLaw::Coulomb {
            mu: f.mu,
            v0: f.v0,
            v1: f.v1,
        }),
    };
    let film = c.film.as_ref().map(|f| Film {
        model: f.model,
        viscosity: f.viscosity,
        length: f.length,
        radius: rj,
        clearance: rb - rj,
        eps_cap: f.eps_cap,
        mirror_width: f.omega0.unwrap_or(DEFAULT_MIRROR_WIDTH),
    });
    Clr {
        joint: ji,
        name: c.name.clone(),
        bearing: end_of(scene, &c.bearing),
        journal: end_of(scene, &c.journal),
        rb,
        rj,
        c: rb - rj,
        normal,
        friction,
        film,
        e0: c.initial_eccentricity,
        e0_rate: c.initial_eccentricity_rate,
        impact_velocity: Cell::new(0.0),
    }
}
