//! The revolute clearance joint (docs/model.md §2–§4): its scene types, its checks, its
//! compiled form and its evaluation.

use std::cell::Cell;

use serde::{Deserialize, Deserializer, Serialize};

use crate::clearance::contact::{
    check_contact_laws, friction_law, normal_law, FrictionSpec, Materials, NormalSpec,
};
use crate::clearance::geometry::{ClearanceInput, ClearanceState};
use crate::clearance::laws::{
    hertz_stiffness, Film, FilmConstants, FilmModel, FrictionLaw, NormalLaw, DEFAULT_MIRROR_WIDTH,
};
use crate::elements::input::Kin;
use crate::labels::EventLabels;
use crate::mechanism::row::{Row, Term, TermKind};
use crate::planar::rot;
use crate::scene::check::Checker;
use crate::scene::de::{object, object_opt};
use crate::scene::error::{invalid, SceneError};
use crate::scene::refs::{check_attachment, pt_at, SceneRefs};

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

impl End {
    fn of(refs: &dyn SceneRefs, e: &ClearanceEnd) -> End {
        let p = pt_at(refs, &e.body, &e.point, &e.at);
        End {
            body: p.body,
            s: p.s,
        }
    }

    /// Global position and velocity of the end, and the angular velocity of its body.
    #[inline]
    fn point(&self, kin: &Kin<'_>) -> ([f64; 2], [f64; 2], f64) {
        match self.body {
            None => (self.s, [0.0; 2], 0.0),
            Some(k) => {
                let a = rot(kin.cs[k], self.s);
                let [x, y, _] = kin.pose[k];
                let [vx, vy, w] = kin.vel[k];
                ([x + a[0], y + a[1]], [vx - w * a[1], vy + w * a[0]], w)
            }
        }
    }

    /// φ̇ of the end's body (0 for the ground).
    #[inline]
    pub(crate) fn omega(&self, kin: &Kin<'_>) -> f64 {
        self.body.map_or(0.0, |b| kin.vel[b][2])
    }
}

/// A compiled revolute clearance joint (docs/model.md §2–§4).
#[derive(Debug)]
pub(crate) struct Revolute {
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
    /// The film's constants (`Film::constants`; unused without a film).
    pub film_k: FilmConstants,
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

/// The event function δ of a revolute clearance joint (docs/model.md §7); its others are
/// [`EPS_CAP`] (a capped film) and the kinks ([`Kink`], with `kink_events`).
pub(crate) const CONTACT: EventLabels = EventLabels {
    kind: "contact",
    rising: "contact_onset",
    falling: "contact_loss",
};
/// ε − ε_cap of a capped film.
pub(crate) const EPS_CAP: EventLabels = EventLabels {
    kind: "eps_cap",
    rising: "eps_cap_reached",
    falling: "eps_cap_left",
};

impl Kink {
    /// Every kink, in the order of the event list.
    pub(crate) const ALL: [Kink; 4] = [Kink::FullDamping, Kink::Clip, Kink::SlipV0, Kink::SlipV1];

    /// The labels of its event.
    pub(crate) const fn labels(self) -> EventLabels {
        match self {
            Kink::FullDamping => EventLabels {
                kind: "kink_full_damping",
                rising: "kink_full_damping_rising",
                falling: "kink_full_damping_falling",
            },
            Kink::Clip => EventLabels {
                kind: "kink_force_clip",
                rising: "kink_force_clip_rising",
                falling: "kink_force_clip_falling",
            },
            Kink::SlipV0 => EventLabels {
                kind: "kink_slip_v0",
                rising: "kink_slip_v0_rising",
                falling: "kink_slip_v0_falling",
            },
            Kink::SlipV1 => EventLabels {
                kind: "kink_slip_v1",
                rising: "kink_slip_v1_rising",
                falling: "kink_slip_v1_falling",
            },
        }
    }
}

/// Per-joint results of one evaluation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RevoluteEval {
    pub st: ClearanceState,
    pub f_n: f64,
    pub f_t: f64,
    pub f_r: f64,
    pub f_tf: f64,
    pub elastic: f64,
}

impl Default for RevoluteEval {
    fn default() -> Self {
        RevoluteEval {
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

/// A force on a body: (body, global arm from its centre of mass, force).
pub(crate) type PointLoad = (usize, [f64; 2], [f64; 2]);

/// The journal's end of a joint, as [`Revolute::each_load_at`] names it.
pub(crate) const JOURNAL: usize = 0;
/// The bearing's end of a joint, as [`Revolute::each_load_at`] names it.
pub(crate) const BEARING: usize = 1;

impl Revolute {
    /// Builds the joint from its validated spec (scene joint `ji`).
    pub(crate) fn new(refs: &dyn SceneRefs, ji: usize, c: &ClearanceSpec) -> Revolute {
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
        let film = c.film.as_ref().map(|f| Film {
            model: f.model,
            viscosity: f.viscosity,
            length: f.length,
            radius: rj,
            clearance: rb - rj,
            eps_cap: f.eps_cap,
            mirror_width: f.omega0.unwrap_or(DEFAULT_MIRROR_WIDTH),
        });
        Revolute {
            joint: ji,
            name: c.name.clone(),
            bearing: End::of(refs, &c.bearing),
            journal: End::of(refs, &c.journal),
            rb,
            rj,
            c: rb - rj,
            normal: normal_law(&c.normal, stiffness),
            friction: friction_law(&c.friction),
            film_k: film.map(|f| f.constants()).unwrap_or_default(),
            film,
            e0: c.initial_eccentricity,
            e0_rate: c.initial_eccentricity_rate,
            impact_velocity: Cell::new(0.0),
        }
    }

    /// The clearance kinematics of the joint (docs/model.md §2).
    #[inline]
    pub(crate) fn state(&self, kin: &Kin<'_>) -> ClearanceState {
        self.state_inline(kin)
    }

    /// [`Revolute::state`], always inlined: for the small-tree right-hand side, where the
    /// state's fields stay in registers (no call, no copy of the state; the same operations).
    #[inline(always)]
    pub(crate) fn state_inline(&self, kin: &Kin<'_>) -> ClearanceState {
        let (r_b, v_b, w_b) = self.bearing.point(kin);
        let (r_j, v_j, w_j) = self.journal.point(kin);
        ClearanceState::compute(&ClearanceInput {
            r_j,
            r_b,
            v_j,
            v_b,
            phi_dot_j: w_j,
            phi_dot_b: w_b,
            radius_j: self.rj,
            radius_b: self.rb,
        })
    }

    /// ė = ṙ_J^P − ṙ_B^P.
    pub(crate) fn edot(&self, kin: &Kin<'_>) -> [f64; 2] {
        let vel = |end: &End| match end.body {
            None => [0.0; 2],
            Some(kb) => {
                let a = rot(kin.cs[kb], end.s);
                let [vx, vy, w] = kin.vel[kb];
                [vx - w * a[1], vy + w * a[0]]
            }
        };
        let (vj, vb) = (vel(&self.journal), vel(&self.bearing));
        [vj[0] - vb[0], vj[1] - vb[1]]
    }

    /// The force laws at the clearance state `st` (docs/model.md §3–§4): normal force,
    /// friction, elastic part (δ > 0 only) and film forces (when lubricated).
    #[inline]
    pub(crate) fn forces(&self, st: ClearanceState) -> RevoluteEval {
        let mut ev = self.forces_only(st);
        if st.delta > 0.0 {
            ev.elastic = self.normal.stiffness() * st.delta * st.delta.sqrt();
        }
        ev
    }

    /// [`Revolute::forces`] without the elastic part (`elastic` left 0): the forces alone,
    /// for a right-hand side that reads nothing else (its square root saved; the small-tree
    /// path of the minimal formulation). The same operations for the forces, so their bits.
    /// (Always inlined: the small path then builds no [`RevoluteEval`] in memory.)
    #[inline(always)]
    pub(crate) fn forces_only(&self, st: ClearanceState) -> RevoluteEval {
        let mut ev = RevoluteEval {
            st,
            ..RevoluteEval::default()
        };
        if st.delta > 0.0 {
            ev.f_n = self
                .normal
                .force(st.delta, st.delta_dot, self.impact_velocity.get());
            if let Some(fr) = &self.friction {
                ev.f_t = fr.force(st.v_t, ev.f_n);
            }
        }
        if let Some(film) = &self.film {
            let (fr, ft) = film.force_with(&self.film_k, st.eps, st.eps_dot, st.omega);
            ev.f_r = fr;
            ev.f_tf = ft;
        }
        ev
    }

    /// The loads of one evaluation on the joint's bodies, handed to `apply` in the order they
    /// are applied: the contact pair at the contact points Q_J, Q_B (δ > 0), then the film
    /// pair at the joint centres (lubricated). (Handed over one by one: an array of them
    /// returned was copied by memcpy in every right-hand side.)
    #[inline]
    pub(crate) fn each_load(
        &self,
        ev: &RevoluteEval,
        cs: &[[f64; 2]],
        mut apply: impl FnMut(PointLoad),
    ) {
        self.each_load_at(ev, cs, |_, l| apply(l));
    }

    /// [`Revolute::each_load`] with the end each load acts on ([`JOURNAL`] or [`BEARING`])
    /// handed over beside it, always inlined (the small-tree right-hand side finds the
    /// end's integrated body by it, in a table made once).
    #[inline(always)]
    pub(crate) fn each_load_at(
        &self,
        ev: &RevoluteEval,
        cs: &[[f64; 2]],
        mut apply: impl FnMut(usize, PointLoad),
    ) {
        let st = &ev.st;
        // Dry contact.
        if st.delta > 0.0 {
            let f_j = [
                -ev.f_n * st.n[0] + ev.f_t * st.t[0],
                -ev.f_n * st.n[1] + ev.f_t * st.t[1],
            ];
            if let Some(kj) = self.journal.body {
                let a = rot(cs[kj], self.journal.s);
                let arm = [a[0] + self.rj * st.n[0], a[1] + self.rj * st.n[1]];
                apply(JOURNAL, (kj, arm, f_j));
            }
            if let Some(kb) = self.bearing.body {
                let a = rot(cs[kb], self.bearing.s);
                let arm = [a[0] + self.rb * st.n[0], a[1] + self.rb * st.n[1]];
                apply(BEARING, (kb, arm, [-f_j[0], -f_j[1]]));
            }
        }
        // Oil film.
        if self.film.is_some() {
            let (fr, ft) = (ev.f_r, ev.f_tf);
            let f_j = [fr * st.n[0] + ft * st.t[0], fr * st.n[1] + ft * st.t[1]];
            if let Some(kj) = self.journal.body {
                apply(JOURNAL, (kj, rot(cs[kj], self.journal.s), f_j));
            }
            if let Some(kb) = self.bearing.body {
                apply(
                    BEARING,
                    (kb, rot(cs[kb], self.bearing.s), [-f_j[0], -f_j[1]]),
                );
            }
        }
    }

    /// The joint's event functions besides δ: ε − ε_cap when its film is capped.
    pub(crate) fn has_eps_cap(&self) -> bool {
        self.film.is_some_and(|f| f.eps_cap.is_some())
    }

    /// Whether its force laws have the kink `kink` (docs/model.md §7).
    pub(crate) fn has_kink(&self, kink: Kink) -> bool {
        match kink {
            Kink::FullDamping => {
                matches!(self.normal, NormalLaw::Impact { c_max, .. } if c_max > 0.0)
            }
            Kink::Clip => self.normal.can_clip(),
            Kink::SlipV0 => {
                matches!(self.friction, Some(FrictionLaw::Coulomb { mu, v0, .. }) if mu > 0.0 && v0 > 0.0)
            }
            Kink::SlipV1 => {
                matches!(self.friction, Some(FrictionLaw::Coulomb { mu, v0, v1 }) if mu > 0.0 && v1 > v0)
            }
        }
    }

    /// Whether the joint is dry (no film) and its laws have at least one kink ([`Kink`]): what
    /// turns a scene's kink events on when the scene does not say (docs/model.md §7, "Kink
    /// events"). Without a film the contact laws are the joint's only forces, and an explicit
    /// pair stepping across one of their kinks loses its order; a lubricated joint is left out
    /// (its film carries the journal, contact is rare, and its runs are stiff ones, whose
    /// implicit methods gain nothing from a restart), and so is a dry joint whose laws have no
    /// kink (an undamped Hertz law without friction: nothing to restart at).
    pub(crate) fn is_dry_with_kinks(&self) -> bool {
        self.film.is_none() && Kink::ALL.into_iter().any(|k| self.has_kink(k))
    }

    /// ε − ε_cap and ε̇ at the eccentricity ratio `eps` and its rate `eps_dot`.
    #[inline]
    pub(crate) fn eps_cap_value(&self, eps: f64, eps_dot: f64) -> (f64, f64) {
        let cap = self.film.and_then(|f| f.eps_cap).unwrap_or(1.0);
        (eps - cap, eps_dot)
    }

    /// The value and rate of a kink function ([`Kink`]) at the clearance state `st`. The rate
    /// of δ − d_max is δ̇; the others need accelerations, so in contact their rate is given as
    /// infinite (the step is always sampled) and outside contact, where they are held at 1, as
    /// 0.
    pub(crate) fn kink_value(&self, kink: Kink, st: ClearanceState) -> (f64, f64) {
        if kink == Kink::FullDamping {
            let d_max = match self.normal {
                NormalLaw::Impact { d_max, .. } => d_max,
                _ => f64::INFINITY,
            };
            return (st.delta - d_max, st.delta_dot);
        }
        if st.delta <= 0.0 {
            return (1.0, 0.0);
        }
        let (v0, v1) = match self.friction {
            Some(FrictionLaw::Coulomb { v0, v1, .. }) => (v0, v1),
            _ => (0.0, 0.0),
        };
        let g = match kink {
            Kink::Clip => {
                self.normal
                    .unclipped_ratio(st.delta, st.delta_dot, self.impact_velocity.get())
            }
            Kink::SlipV0 => st.v_t * st.v_t - v0 * v0,
            _ => st.v_t * st.v_t - v1 * v1,
        };
        (g, f64::INFINITY)
    }

    /// The equations held during the initial assembly (docs/model.md §1.6): e = e₀ with
    /// ė = ė₀ (rows "eccentricity x", "eccentricity y"); none when neither end is integrated
    /// (`integrated(body)`).
    pub(crate) fn assembly_rows(&self, integrated: &dyn Fn(usize) -> bool, t0: f64) -> Vec<Row> {
        if !self.bearing.body.is_some_and(integrated) && !self.journal.body.is_some_and(integrated)
        {
            return Vec::new();
        }
        let mut rows = Vec::new();
        for (axis, label) in [(0usize, "eccentricity x"), (1, "eccentricity y")] {
            let mut w = [0.0; 2];
            w[axis] = 1.0;
            let mut row = Row::new(self.joint, label);
            row.konst = -self.e0[axis];
            for (end, sign) in [(&self.journal, 1.0), (&self.bearing, -1.0)] {
                let ws = [sign * w[0], sign * w[1]];
                match end.body {
                    None => row.konst += ws[0] * end.s[0] + ws[1] * end.s[1],
                    Some(k) => row.push(Term {
                        body: k,
                        kind: TermKind::Point { s: end.s, w: ws },
                    }),
                }
            }
            rows.push(row.with_rate(self.e0_rate[axis], t0));
        }
        rows
    }

    /// δ, δ̇, ε and ε̇ of the joint (what its event functions δ and ε − ε_cap read), without
    /// the rest of [`Revolute::state`] (v_T, γ̇, Ω): the same expressions as
    /// [`ClearanceState::compute`], so the same bits.
    #[inline(always)]
    pub(crate) fn gap_and_rate(&self, kin: &Kin<'_>) -> [f64; 4] {
        let (r_b, v_b, _) = self.bearing.point(kin);
        let (r_j, v_j, _) = self.journal.point(kin);
        let c = self.rb - self.rj;
        let e = [r_j[0] - r_b[0], r_j[1] - r_b[1]];
        let ed = [v_j[0] - v_b[0], v_j[1] - v_b[1]];
        let (e_norm, _, n) = ClearanceState::normal_of(e, c);
        let delta_dot = n[0] * ed[0] + n[1] * ed[1];
        [e_norm - c, delta_dot, e_norm / c, delta_dot / c]
    }
}

/// Checks a revolute clearance joint at JSON path `p` (docs/scene-format.md, "clearance"):
/// its ends and radii, its contact laws, its film, its initial eccentricity.
pub(crate) fn validate(refs: &dyn SceneRefs, p: &str, c: &ClearanceSpec) -> Result<(), SceneError> {
    let clearance = check_ends(refs, p, c)?;
    check_contact_laws(p, &c.normal, &c.friction, &|path, k, m| {
        check_stiffness(c, path, k, m)
    })?;
    if let Some(film) = &c.film {
        check_film(&format!("{p}.film"), film)?;
    }
    check_initial_eccentricity(p, c, clearance)
}

type C = Checker;

/// Bearing and journal: attachments on different bodies, radii with 0 < R_B − R_J < R_B. The
/// clearance R_B − R_J.
fn check_ends(refs: &dyn SceneRefs, p: &str, c: &ClearanceSpec) -> Result<f64, SceneError> {
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
    Ok(clearance)
}

/// The normal law's stiffness at `path`: k > 0, or materials from which the Hertz K is finite.
fn check_stiffness(
    c: &ClearanceSpec,
    path: &str,
    k: &Option<f64>,
    m: &Option<Materials>,
) -> Result<(), SceneError> {
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
                c.bearing.radius,
                c.journal.radius,
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
}

/// The film at path `fp`: viscosity ≥ 0, length > 0, ε_cap in (0, 1) or none, Ω₀ > 0 only
/// with a mirrored model.
fn check_film(fp: &str, film: &FilmSpec) -> Result<(), SceneError> {
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
    Ok(())
}

/// The initial eccentricity: within the clearance (or, allowed, in contact up to the journal
/// radius), and finite with its rate.
fn check_initial_eccentricity(
    p: &str,
    c: &ClearanceSpec,
    clearance: f64,
) -> Result<(), SceneError> {
    let j = &c.journal;
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
