//! The event functions of a mechanism (docs/model.md §7): which they are, their values and
//! rates, and their names and labels (each declared by the joint or element that owns it).
//!
//! ```text
//! order: δ of every revolute clearance joint, ε − ε_cap of every capped film, the four corner
//!        gaps δ_i of every prismatic clearance joint, every force element's own functions,
//!        and (kink_events) the kinks of every revolute clearance joint's force laws
//! ```
//! The kinks come last so that switching them keeps every other index.

use crate::clearance::geometry::ClearanceState;
use crate::clearance::prismatic::{self, Prismatic};
use crate::clearance::revolute::{self, Kink, Revolute};
use crate::elements::input::Kin;
use crate::elements::Element;
use crate::labels::EventLabels;
use crate::mechanism::forces::Forces;
use crate::mechanism::scratch::Scratch;

/// What an event function is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum EventKind {
    /// δ of revolute clearance joint k.
    Contact(usize),
    /// ε − ε_cap of revolute clearance joint k.
    EpsCap(usize),
    /// δ_i of corner i of prismatic clearance joint k (docs/model.md §11).
    Corner(usize, usize),
    /// Event function i of force element k (its [`crate::elements::interface::ForceElement`]).
    Element(usize, usize),
    /// A point where a force law of revolute clearance joint k is not smooth (§7).
    Kink(usize, Kink),
}

/// The event functions of a mechanism in their order (module doc, [`event_list`]) and, when
/// every one of them is a revolute clearance joint's δ or ε − ε_cap (a scene of lubricated or
/// dry revolute clearance joints without kink events, prismatic clearance joints or elements
/// with events: the presses), their indices by joint. [`values`] then evaluates each joint's
/// δ, δ̇, ε, ε̇ once and writes its functions, instead of the general loop over the
/// functions with its lookups (the same expressions, so the same bits). Reads as the slice
/// of its functions.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Events {
    list: Vec<EventKind>,
    /// By joint, in the order of its δ, when every function is a δ or an ε − ε_cap.
    gaps: Option<Vec<GapEvents>>,
}

/// The event functions of revolute clearance joint `k` where every function is a δ or an
/// ε − ε_cap ([`Events`]): the index of its δ and of its ε − ε_cap (None: its film has no cap,
/// or it has no film).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct GapEvents {
    k: usize,
    contact: usize,
    cap: Option<usize>,
}

impl std::ops::Deref for Events {
    type Target = [EventKind];

    fn deref(&self) -> &[EventKind] {
        &self.list
    }
}

impl Events {
    /// The functions `list` and, when each is a δ, or an ε − ε_cap of a joint whose δ is in
    /// the list too, their indices by joint.
    fn new(list: Vec<EventKind>) -> Events {
        let only_gaps = list.iter().all(|e| match *e {
            EventKind::Contact(_) => true,
            EventKind::EpsCap(k) => list.contains(&EventKind::Contact(k)),
            _ => false,
        });
        let gaps = only_gaps.then(|| {
            list.iter()
                .enumerate()
                .filter_map(|(i, e)| match *e {
                    EventKind::Contact(k) => Some(GapEvents {
                        k,
                        contact: i,
                        cap: list.iter().position(|x| *x == EventKind::EpsCap(k)),
                    }),
                    _ => None,
                })
                .collect()
        });
        Events { list, gaps }
    }

    /// Whether [`values`] evaluates them by joint (every function a δ or an ε − ε_cap).
    #[cfg(test)]
    pub(crate) fn by_joint(&self) -> bool {
        self.gaps.is_some()
    }
}

/// The event functions of a mechanism (module doc), with the kinks when `kinks`.
pub(crate) fn event_list(
    revolute: &[Revolute],
    prismatic: &[Prismatic],
    elements: &[Element],
    kinks: bool,
) -> Events {
    let mut events = Vec::new();
    for k in 0..revolute.len() {
        events.push(EventKind::Contact(k));
    }
    // A capped film changes form at ε = ε_cap; a film without a cap has no such point
    // below contact (docs/model.md §7).
    for (k, c) in revolute.iter().enumerate() {
        if c.has_eps_cap() {
            events.push(EventKind::EpsCap(k));
        }
    }
    for k in 0..prismatic.len() {
        for i in 0..4 {
            events.push(EventKind::Corner(k, i));
        }
    }
    for (k, e) in elements.iter().enumerate() {
        for i in 0..e.events().len() {
            events.push(EventKind::Element(k, i));
        }
    }
    if kinks {
        for (k, c) in revolute.iter().enumerate() {
            for kink in Kink::ALL {
                if c.has_kink(kink) {
                    events.push(EventKind::Kink(k, kink));
                }
            }
        }
    }
    Events::new(events)
}

/// The event functions at t and, when `g_dot` is given, their rates, from the kinematics in
/// `sc` (positions and velocities only): δ and δ̇, ε − ε_cap and ε̇, a corner's δ_i and δ̇_i,
/// an element's own, a kink's (docs/model.md §2, §7, §11). Where every function is a δ or an
/// ε − ε_cap, joint by joint ([`Events`]); else [`values_of`].
#[inline]
pub(crate) fn values(
    events: &Events,
    forces: &Forces,
    t: f64,
    sc: &Scratch,
    g: &mut [f64],
    g_dot: Option<&mut [f64]>,
) {
    let Some(gaps) = &events.gaps else {
        return values_of(&events.list, forces, t, sc, g, g_dot);
    };
    let kin = sc.kin();
    let mut g_dot = g_dot;
    for j in gaps {
        let c = &forces.revolute[j.k];
        let [delta, delta_dot, eps, eps_dot] = c.gap_and_rate(&kin);
        let cap = j.cap.map(|i| (i, c.eps_cap_value(eps, eps_dot)));
        g[j.contact] = delta;
        if let Some((i, (v, _))) = cap {
            g[i] = v;
        }
        if let Some(gd) = g_dot.as_deref_mut() {
            gd[j.contact] = delta_dot;
            if let Some((i, (_, d))) = cap {
                gd[i] = d;
            }
        }
    }
}

/// [`values`] of any list of event functions, one function after the other (not inlined:
/// the joint-by-joint path keeps a small frame).
#[inline(never)]
pub(crate) fn values_of(
    events: &[EventKind],
    forces: &Forces,
    t: f64,
    sc: &Scratch,
    g: &mut [f64],
    mut g_dot: Option<&mut [f64]>,
) {
    let kin = sc.kin();
    // A joint's δ, δ̇, ε, ε̇ serve its functions δ and ε − ε_cap, its clearance state its
    // kinks: the last one of each computed is kept.
    let mut gap: Option<(usize, [f64; 4])> = None;
    let mut last: Option<(usize, ClearanceState)> = None;
    for (i, ev) in events.iter().enumerate() {
        let (v, d) = match *ev {
            EventKind::Contact(k) => {
                let [delta, delta_dot, _, _] = joint_gap(&mut gap, forces, &kin, k);
                (delta, delta_dot)
            }
            EventKind::EpsCap(k) => {
                let [_, _, eps, eps_dot] = joint_gap(&mut gap, forces, &kin, k);
                forces.revolute[k].eps_cap_value(eps, eps_dot)
            }
            EventKind::Corner(k, c) => forces.prismatic[k].corner_gap(c, &kin),
            EventKind::Element(k, i) => forces.elements[k].event(i, t, &kin),
            EventKind::Kink(k, kink) => {
                let st = *joint_state(&mut last, forces, &kin, k);
                forces.revolute[k].kink_value(kink, st)
            }
        };
        g[i] = v;
        if let Some(gd) = g_dot.as_deref_mut() {
            gd[i] = d;
        }
    }
}

/// δ, δ̇, ε, ε̇ of revolute joint `k` ([`Revolute::gap_and_rate`]): the ones in `gap` when
/// they are joint k's, else computed into `gap`.
#[inline(always)]
fn joint_gap(
    gap: &mut Option<(usize, [f64; 4])>,
    forces: &Forces,
    kin: &Kin<'_>,
    k: usize,
) -> [f64; 4] {
    match *gap {
        Some((j, v)) if j == k => v,
        _ => {
            let v = forces.revolute[k].gap_and_rate(kin);
            *gap = Some((k, v));
            v
        }
    }
}

/// The clearance state of revolute joint `k`: the one in `last` when it is joint k's, else
/// computed into `last`.
#[inline]
fn joint_state<'c>(
    last: &'c mut Option<(usize, ClearanceState)>,
    forces: &Forces,
    kin: &Kin<'_>,
    k: usize,
) -> &'c ClearanceState {
    if !matches!(last, Some((j, _)) if *j == k) {
        *last = None;
    }
    &last
        .get_or_insert_with(|| (k, forces.revolute[k].state(kin)))
        .1
}

/// The labels of an event function, and the index of its owner among the revolute clearance
/// joints, the prismatic clearance joints or the force elements.
pub(crate) fn labels(event: EventKind, forces: &Forces) -> (EventLabels, usize) {
    match event {
        EventKind::Contact(k) => (revolute::CONTACT, k),
        EventKind::EpsCap(k) => (revolute::EPS_CAP, k),
        EventKind::Corner(k, _) => (prismatic::CORNER_CONTACT, k),
        EventKind::Element(k, i) => (forces.elements[k].events()[i], k),
        EventKind::Kink(k, kink) => (kink.labels(), k),
    }
}

/// The name of a crossing of an event function of kind `kind` (as
/// [`crate::Mechanism::event_name`] names it) in the given direction: the label that the joint
/// or element owning such events declares (`contact` rising: `contact_onset`, docs/model.md §7),
/// or `<kind>_rising` / `<kind>_falling` for a kind none declares.
pub fn event_label(kind: &str, rising: bool) -> String {
    match labels_of_kind(kind) {
        Some(l) => l.label(rising).to_string(),
        None => format!("{kind}_{}", if rising { "rising" } else { "falling" }),
    }
}

/// The labels of an event kind of any joint or element that has events: the clearance joints'
/// kinds and every force element kind's.
fn labels_of_kind(kind: &str) -> Option<EventLabels> {
    let fixed = [
        revolute::CONTACT,
        revolute::EPS_CAP,
        prismatic::CORNER_CONTACT,
    ];
    fixed
        .into_iter()
        .chain(Kink::ALL.map(Kink::labels))
        .chain(Element::all_events())
        .find(|l| l.kind == kind)
}

#[cfg(test)]
mod tests {
    //! Every event function's labels come from the joint that owns it, and are the names the
    //! Python package has always reported (python/tests/test_run.py).
    use super::*;
    use crate::cases::{press_scene, PressJoint};
    use crate::{FormulationName, Mechanism};
    use lash_solver::OdeSystem;

    /// The event functions δ and ε − ε_cap and their rates come from
    /// [`Revolute::gap_and_rate`] without the rest of the clearance state: its δ, δ̇, ε, ε̇
    /// are the full state's bit for bit (the same expressions), so no event time moves. Over
    /// states of the lubricated and the dry press spread across a crank revolution and across
    /// the clearance circle (the rod's angle and rate moved), under both the absolute and
    /// the minimal formulation.
    #[test]
    fn the_gap_and_its_rate_are_the_clearance_states_bits() {
        let mut checked = 0;
        for joint in [PressJoint::Lubricated, PressJoint::Dry] {
            for kind in [FormulationName::LagrangeBaumgarte, FormulationName::Minimal] {
                let mut scene = press_scene(joint, 150.0, 1e-4);
                scene.formulation = kind;
                let m = Mechanism::from_scene(&scene).unwrap();
                let y0 = m.initial_state();
                let n = y0.len() / 2;
                for j in 0..40 {
                    let mut y = y0.clone();
                    // Positions moved by up to ±0.6 clearances, rates by up to ±2 m/s or rad/s.
                    for (i, v) in y.iter_mut().enumerate() {
                        let w = ((j * 7 + i * 3) as f64 * 0.61).sin();
                        *v += if i < n { 6e-5 * w } else { 2.0 * w };
                    }
                    let t = 0.4 * j as f64 / 40.0;
                    let mut sc = m.scratch();
                    m.kinematics(t, &y, &mut sc);
                    let c = &m.forces.revolute[0];
                    let st = c.state(&sc.kin());
                    let [d, dd, e, ed] = c.gap_and_rate(&sc.kin());
                    let bits = |v: [f64; 4]| v.map(f64::to_bits);
                    assert_eq!(
                        bits([d, dd, e, ed]),
                        bits([st.delta, st.delta_dot, st.eps, st.eps_dot]),
                        "{joint:?} {kind:?} state {j}"
                    );
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 160);
    }

    /// Where every event function is a δ or an ε − ε_cap, `values` goes joint by joint and
    /// gives the bits of the general loop (`values_of`) over the same functions, values and
    /// rates, with and without the rates; with kink events it is the general loop. The
    /// lubricated press (δ and ε − ε_cap of its joint; with its kinks switched on, the general
    /// loop) and the dry press (δ alone without its kinks; with them, its default, the
    /// general loop), at states across a crank revolution and the clearance circle.
    #[test]
    fn the_functions_by_joint_are_the_general_loops_bits() {
        use crate::mechanism::events::EventKind::{Contact, EpsCap};
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut checked = 0;
        for (joint, kinks, by_joint, n) in [
            (PressJoint::Lubricated, false, true, 2),
            (PressJoint::Lubricated, true, false, 6),
            (PressJoint::Dry, false, true, 1),
            (PressJoint::Dry, true, false, 5),
        ] {
            let mut m = Mechanism::from_scene(&press_scene(joint, 150.0, 1e-4)).unwrap();
            m.set_kink_events(kinks);
            assert_eq!(
                (m.events.by_joint(), m.events.len()),
                (by_joint, n),
                "{joint:?}"
            );
            if by_joint {
                let list: &[EventKind] = &m.events;
                assert_eq!(list, &[Contact(0), EpsCap(0)][..n], "{joint:?}");
            }
            let y0 = m.initial_state();
            let half = y0.len() / 2;
            for j in 0..20 {
                let y: Vec<f64> = y0
                    .iter()
                    .enumerate()
                    .map(|(i, v)| {
                        let w = ((j * 5 + i * 3) as f64 * 0.73).sin();
                        v + if i < half { 9e-5 * w } else { 2.0 * w }
                    })
                    .collect();
                let t = 0.4 * j as f64 / 20.0;
                let mut sc = m.scratch();
                m.kinematics(t, &y, &mut sc);
                let (f, e) = (&m.forces, &m.events);
                let [mut g, mut gd, mut g0, mut gd0, mut g1] = [(); 5].map(|_| vec![f64::NAN; n]);
                values(e, f, t, &sc, &mut g, Some(&mut gd));
                values_of(e, f, t, &sc, &mut g0, Some(&mut gd0));
                values(e, f, t, &sc, &mut g1, None);
                // Numbers compared, not NaN (a kink's rate in contact is +∞ by design).
                let numbers = g.iter().all(|v| v.is_finite()) && gd.iter().all(|v| !v.is_nan());
                assert!(numbers, "{joint:?} {j}");
                assert_eq!(bits(&g), bits(&g0), "{joint:?} {j}");
                assert_eq!(bits(&gd), bits(&gd0), "{joint:?} {j}");
                assert_eq!(bits(&g1), bits(&g0), "{joint:?} {j}");
                checked += 1;
            }
        }
        assert_eq!(checked, 80);
    }

    #[test]
    fn each_kind_has_the_labels_its_owner_declares() {
        for (kind, rising, falling) in [
            ("contact", "contact_onset", "contact_loss"),
            ("eps_cap", "eps_cap_reached", "eps_cap_left"),
            (
                "corner_contact",
                "corner_contact_onset",
                "corner_contact_loss",
            ),
            (
                "kink_full_damping",
                "kink_full_damping_rising",
                "kink_full_damping_falling",
            ),
            (
                "kink_force_clip",
                "kink_force_clip_rising",
                "kink_force_clip_falling",
            ),
            (
                "kink_slip_v0",
                "kink_slip_v0_rising",
                "kink_slip_v0_falling",
            ),
            (
                "kink_slip_v1",
                "kink_slip_v1_rising",
                "kink_slip_v1_falling",
            ),
            // A kind no joint or element declares.
            ("event", "event_rising", "event_falling"),
        ] {
            assert_eq!(event_label(kind, true), rising);
            assert_eq!(event_label(kind, false), falling);
        }
    }

    #[test]
    fn a_mechanism_names_and_labels_every_event_function_by_its_owner() {
        // The dry press: δ of its clearance joint, then (kink_events, on by default for its dry
        // joint) the kinks of its IMPACT law (c_max > 0; it can clip) and of its Coulomb
        // friction (v₀ > 0, v₁ > v₀).
        let mut m = Mechanism::from_scene(&press_scene(PressJoint::Dry, 150.0, 1e-4)).unwrap();
        assert!(m.kink_events());
        m.set_kink_events(false);
        let kinds = |m: &Mechanism| -> Vec<(&'static str, String)> {
            (0..m.n_events())
                .map(|i| {
                    let (k, owner) = m.event_name(i).unwrap();
                    assert_eq!(m.event_labels(i).unwrap().kind, k);
                    (k, owner.to_string())
                })
                .collect()
        };
        assert_eq!(kinds(&m), [("contact", "rod_slider".to_string())]);
        m.set_kink_events(true);
        let all: Vec<&str> = kinds(&m).iter().map(|k| k.0).collect();
        assert_eq!(
            all,
            [
                "contact",
                "kink_full_damping",
                "kink_force_clip",
                "kink_slip_v0",
                "kink_slip_v1"
            ]
        );
        assert_eq!(m.event_labels(0).unwrap().label(true), "contact_onset");
        assert!(m.event_name(5).is_none() && m.event_labels(5).is_none());
    }
}
