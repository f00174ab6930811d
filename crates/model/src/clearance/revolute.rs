//! The revolute clearance joint (docs/model.md §2–§4): its scene types, its checks, its
//! compiled form and its evaluation.

use std::cell::Cell;

use serde::{Deserialize, Deserializer, Serialize};

use crate::clearance::contact::{
    check_contact_laws, friction_law, normal_law, FrictionSpec, Materials, NormalSpec,
};
use crate::clearance::geometry::ClearanceState;
use crate::clearance::laws::{
    hertz_stiffness, Film, FilmModel, FrictionLaw, NormalLaw, DEFAULT_MIRROR_WIDTH,
};
use crate::scene::check::Checker;
use crate::scene::de::{object, object_opt};
use crate::scene::error::{invalid, SceneError};
use crate::scene::refs::{check_attachment, SceneRefs, GROUND};

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

fn end_of(refs: &dyn SceneRefs, e: &ClearanceEnd) -> End {
    if e.body == GROUND {
        End {
            body: None,
            s: e.at.expect("validated"),
        }
    } else {
        let k = refs.body_index(&e.body).expect("validated");
        End {
            body: Some(k),
            s: refs.body_points(k)[e.point.as_ref().expect("validated")],
        }
    }
}

pub(crate) fn build_clearance(refs: &dyn SceneRefs, ji: usize, c: &ClearanceSpec) -> Clr {
    let rb = c.bearing.radius;
    let rj = c.journal.radius;
    let stiffness = |k: Option<f64>, m: Option<Materials>| match (k, m) {
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
    let normal = normal_law(&c.normal, stiffness);
    let friction = friction_law(&c.friction);
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
        bearing: end_of(refs, &c.bearing),
        journal: end_of(refs, &c.journal),
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

/// Checks a revolute clearance joint at JSON path `p` (docs/scene-format.md, "clearance").
pub(crate) fn validate(refs: &dyn SceneRefs, p: &str, c: &ClearanceSpec) -> Result<(), SceneError> {
    type C = Checker;
    let b = &c.bearing;
    let j = &c.journal;
    check_attachment(refs, &format!("{p}.bearing"), &b.body, &b.point, &b.at)?;
    check_attachment(refs, &format!("{p}.journal"), &j.body, &j.point, &j.at)?;
    if b.body == j.body {
        return Err(invalid(
            format!("{p}.journal.body"),
            format!(
                "bearing and journal must be on different bodies, both are '{}'",
                b.body
            ),
        ));
    }
    C::positive(&format!("{p}.bearing.radius"), b.radius, "bearing radius")?;
    C::finite(&format!("{p}.journal.radius"), j.radius)?;
    let clearance = b.radius - j.radius;
    if !(clearance > 0.0) {
        return Err(invalid(
                format!("{p}.journal.radius"),
                format!(
                    "clearance R_B − R_J = {clearance} m must be > 0 (bearing radius {}, journal radius {})",
                    b.radius, j.radius
                ),
            ));
    }
    if !(clearance < b.radius) {
        return Err(invalid(
                format!("{p}.journal.radius"),
                format!(
                    "clearance R_B − R_J = {clearance} m must be smaller than the bearing radius {} m (the journal radius must be > 0)",
                    b.radius
                ),
            ));
    }
    let check_k = |path: &str, k: &Option<f64>, m: &Option<Materials>| -> Result<(), SceneError> {
        match (k, m) {
            (Some(k), None) => C::positive(&format!("{path}.k"), *k, "stiffness k"),
            (None, Some(m)) => {
                for (side, mat) in [("bearing", m.bearing), ("journal", m.journal)] {
                    let mp = format!("{path}.materials.{side}");
                    C::positive(
                        &format!("{mp}.youngs_modulus"),
                        mat.youngs_modulus,
                        "Young's modulus",
                    )?;
                    C::finite(&format!("{mp}.poisson_ratio"), mat.poisson_ratio)?;
                    if !(mat.poisson_ratio > -1.0 && mat.poisson_ratio < 0.5) {
                        return Err(invalid(
                            format!("{mp}.poisson_ratio"),
                            format!(
                                "Poisson's ratio must lie in (-1, 0.5), got {}",
                                mat.poisson_ratio
                            ),
                        ));
                    }
                }
                // Within the magnitude range K stays finite and positive (c ≥ ulp(R_B)
                // bounds K by about E·√(R_B/(2ε)) < 1e233); the check guards the
                // formula should the range ever be widened.
                let k = hertz_stiffness(
                    b.radius,
                    j.radius,
                    m.bearing.youngs_modulus,
                    m.bearing.poisson_ratio,
                    m.journal.youngs_modulus,
                    m.journal.poisson_ratio,
                );
                if !(k.is_finite() && k > 0.0) {
                    return Err(invalid(
                        format!("{path}.materials"),
                        format!(
                            "the Hertz stiffness K = {k} N/m^1.5 of these materials is \
                                     not a finite positive number"
                        ),
                    ));
                }
                Ok(())
            }
            (Some(_), Some(_)) => Err(invalid(
                format!("{path}.materials"),
                "give either k or materials, not both",
            )),
            (None, None) => Err(invalid(
                path,
                "the normal law needs its stiffness: k (N/m^1.5) or materials",
            )),
        }
    };
    check_contact_laws(p, &c.normal, &c.friction, &check_k)?;
    if let Some(film) = &c.film {
        let fp = format!("{p}.film");
        C::non_negative(&format!("{fp}.viscosity"), film.viscosity, "viscosity")?;
        C::positive(&format!("{fp}.length"), film.length, "bearing length")?;
        if let Some(cap) = film.eps_cap {
            C::finite(&format!("{fp}.eps_cap"), cap)?;
            if !(cap > 0.0 && cap < 1.0) {
                return Err(invalid(
                    format!("{fp}.eps_cap"),
                    format!("eps_cap must lie in (0, 1) or be null (no cap), got {cap}"),
                ));
            }
        }
        if let Some(w) = film.omega0 {
            C::positive(&format!("{fp}.omega0"), w, "omega0")?;
            if !matches!(
                film.model,
                FilmModel::LongGumbelMirrored | FilmModel::ShortOcvirkMirrored
            ) {
                return Err(invalid(
                    format!("{fp}.omega0"),
                    "omega0 (the width of the smooth sign of the mirrored models) applies \
                         only to long_gumbel_mirrored and short_ocvirk_mirrored"
                        .to_string(),
                ));
            }
        }
    }
    C::finite2(&format!("{p}.initial_eccentricity"), c.initial_eccentricity)?;
    C::finite2(
        &format!("{p}.initial_eccentricity_rate"),
        c.initial_eccentricity_rate,
    )?;
    let e0 = c.initial_eccentricity[0].hypot(c.initial_eccentricity[1]);
    if e0 > clearance && !c.allow_initial_penetration {
        return Err(invalid(
            format!("{p}.initial_eccentricity"),
            format!(
                "|e| = {e0:e} m exceeds the clearance R_B − R_J = {clearance:e} m (the \
                     journal would start {:e} m into the bearing); set \
                     allow_initial_penetration: true to start in contact",
                e0 - clearance
            ),
        ));
    }
    if !(e0 - clearance < j.radius) {
        return Err(invalid(
            format!("{p}.initial_eccentricity"),
            format!(
                "|e| = {e0:e} m puts the journal {:e} m into the bearing, beyond the \
                     journal radius {} m: the contact law does not hold there",
                e0 - clearance,
                j.radius
            ),
        ));
    }
    Ok(())
}
