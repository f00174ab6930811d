//! Event functions of a mechanism (docs/model.md §7): which they are, their values and names.

use crate::clearance::geometry::ClearanceState;
use crate::clearance::laws::{FrictionLaw, NormalLaw};
use crate::clearance::revolute::{Clr, Kink};
use crate::mechanism::{Mechanism, Scratch};

/// What the event functions are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum EventKind {
    /// δ of clearance joint k.
    Contact(usize),
    /// ε − ε_cap of clearance joint k.
    EpsCap(usize),
    /// δ_i of corner i of prismatic clearance joint k (docs/model.md §11).
    Corner(usize, usize),
    /// A point where a force law of clearance joint k is not smooth (docs/model.md §7).
    Kink(usize, Kink),
}
impl Mechanism {
    /// Event functions at (t, y) and, when `g_dot` is given, their rates (after
    /// `kinematics`): δ and δ̇, ε − ε_cap and ε̇, a corner's δ_i and δ̇_i (docs/model.md §2,
    /// §7, §11), all from positions and velocities.
    pub(crate) fn event_values(&self, sc: &Scratch, g: &mut [f64], mut g_dot: Option<&mut [f64]>) {
        // A joint's clearance state serves all of its event functions (δ, ε − ε_cap, kinks):
        // the last one computed is kept.
        let mut last: Option<(usize, ClearanceState)> = None;
        let mut state = |k: usize| match last {
            Some((j, st)) if j == k => st,
            _ => {
                let st = self.clearance_state(k, sc);
                last = Some((k, st));
                st
            }
        };
        for (i, ev) in self.events.iter().enumerate() {
            let (v, d) = match *ev {
                EventKind::Contact(k) => {
                    let st = state(k);
                    (st.delta, st.delta_dot)
                }
                EventKind::EpsCap(k) => {
                    let cap = self.clr[k].film.and_then(|f| f.eps_cap).unwrap_or(1.0);
                    let st = state(k);
                    (st.eps - cap, st.eps_dot)
                }
                EventKind::Corner(k, c) => {
                    self.prismatic[k].corner_gap(c, &sc.pose, &sc.vel, &sc.cs)
                }
                EventKind::Kink(k, kink) => self.kink_value(k, kink, state(k)),
            };
            g[i] = v;
            if let Some(gd) = g_dot.as_deref_mut() {
                gd[i] = d;
            }
        }
    }

    /// Which event function index `i` is: ("contact" | "eps_cap", clearance joint name), or
    /// ("corner_contact", prismatic clearance joint name) for the gap δ_i of one of its four
    /// corners (docs/model.md §11).
    pub fn event_name(&self, i: usize) -> Option<(&'static str, &str)> {
        self.events.get(i).map(|e| match *e {
            EventKind::Contact(k) => ("contact", self.clr[k].name.as_str()),
            EventKind::EpsCap(k) => ("eps_cap", self.clr[k].name.as_str()),
            EventKind::Corner(k, _) => ("corner_contact", self.prismatic[k].name.as_str()),
            EventKind::Kink(k, kink) => (
                match kink {
                    Kink::FullDamping => "kink_full_damping",
                    Kink::Clip => "kink_force_clip",
                    Kink::SlipV0 => "kink_slip_v0",
                    Kink::SlipV1 => "kink_slip_v1",
                },
                self.clr[k].name.as_str(),
            ),
        })
    }

    /// The value and rate of a kink function ([`Kink`]) of clearance joint `k` at its clearance
    /// state `st`. The rate of δ − d_max is δ̇; the others need accelerations, so in contact
    /// their rate is given as infinite (the step is always sampled) and outside contact, where
    /// they are held at 1, as 0.
    fn kink_value(&self, k: usize, kink: Kink, st: ClearanceState) -> (f64, f64) {
        let c = &self.clr[k];
        if kink == Kink::FullDamping {
            let d_max = match c.normal {
                NormalLaw::Impact { d_max, .. } => d_max,
                _ => f64::INFINITY,
            };
            return (st.delta - d_max, st.delta_dot);
        }
        if st.delta <= 0.0 {
            return (1.0, 0.0);
        }
        let (v0, v1) = match c.friction {
            Some(FrictionLaw::Coulomb { v0, v1, .. }) => (v0, v1),
            _ => (0.0, 0.0),
        };
        let g = match kink {
            Kink::Clip => c
                .normal
                .unclipped_ratio(st.delta, st.delta_dot, c.impact_velocity.get()),
            Kink::SlipV0 => st.v_t * st.v_t - v0 * v0,
            _ => st.v_t * st.v_t - v1 * v1,
        };
        (g, f64::INFINITY)
    }

    /// Adds (or removes) the kink events of the revolute clearance joints' force laws
    /// (δ = d_max, the clip of F_N at 0, |v_T| = v₀ and v₁; docs/model.md §7), as the scene
    /// field `kink_events` does. With them an integration restarts at every kink, so a method
    /// of high order keeps its order through a contact; every other event keeps its index.
    pub fn set_kink_events(&mut self, on: bool) {
        self.events = event_list(&self.clr, self.prismatic.len(), on);
    }

    /// Whether the kink events are on ([`Mechanism::set_kink_events`]).
    pub fn kink_events(&self) -> bool {
        self.events.iter().any(|e| matches!(e, EventKind::Kink(..)))
    }

    /// Sets the stored impact velocity δ̇⁻ of clearance joint `k` (m/s), as the contact-onset
    /// event does. For tests and for restarting a run from a saved state.
    pub fn set_impact_velocity(&self, k: usize, v: f64) {
        if let Some(c) = self.clr.get(k) {
            c.impact_velocity.set(v);
        }
    }
}

/// The event functions of a mechanism: every clearance joint's δ, the ε − ε_cap of each capped
/// film, the four corner gaps of each prismatic clearance joint and, with `kinks`, the kinks of
/// each revolute clearance joint's force laws ([`Kink`]).
pub(crate) fn event_list(clr: &[Clr], n_prismatic: usize, kinks: bool) -> Vec<EventKind> {
    let mut events = Vec::new();
    for k in 0..clr.len() {
        events.push(EventKind::Contact(k));
    }
    // A capped film changes form at ε = ε_cap; a film without a cap has no such point
    // below contact (docs/model.md §7).
    for (k, c) in clr.iter().enumerate() {
        if c.film.is_some_and(|f| f.eps_cap.is_some()) {
            events.push(EventKind::EpsCap(k));
        }
    }
    for k in 0..n_prismatic {
        for i in 0..4 {
            events.push(EventKind::Corner(k, i));
        }
    }
    if kinks {
        for (k, c) in clr.iter().enumerate() {
            if let NormalLaw::Impact { c_max, .. } = c.normal {
                if c_max > 0.0 {
                    events.push(EventKind::Kink(k, Kink::FullDamping));
                }
            }
            if c.normal.can_clip() {
                events.push(EventKind::Kink(k, Kink::Clip));
            }
            if let Some(FrictionLaw::Coulomb { mu, v0, v1 }) = c.friction {
                if mu > 0.0 && v0 > 0.0 {
                    events.push(EventKind::Kink(k, Kink::SlipV0));
                }
                if mu > 0.0 && v1 > v0 {
                    events.push(EventKind::Kink(k, Kink::SlipV1));
                }
            }
        }
    }
    events
}
