//! The mechanism as an `OdeSystem` for the integrators of `lash-solver`, with its event hooks.

use faer::MatMut;
use lash_solver::{Direction, EventAction, EventHit, EventSpec, OdeSystem, Rejection};

use crate::mechanism::events::{self, event_list, EventKind};
use crate::mechanism::Mechanism;

impl OdeSystem for Mechanism {
    fn dim(&self) -> usize {
        self.formulation.dim(&self.bodies)
    }

    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.rhs_into(t, y, &mut self.scratch.borrow_mut(), dy);
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, t: f64, y: &[f64], jac: MatMut<'_, f64>) {
        crate::jacobian::jacobian(self, t, y, jac);
    }

    /// Block diagonal over the clusters of bodies (crate::jacobian); None for one cluster.
    fn jacobian_sparsity(&self) -> Option<Vec<Vec<usize>>> {
        self.sparsity()
    }

    /// The absolute formulations' KKT form (crate::kkt); None under minimal.
    fn kkt(&self) -> Option<&dyn lash_solver::kkt::KktSystem> {
        self.formulation
            .kkt_stabilisation()
            .map(|_| self as &dyn lash_solver::kkt::KktSystem)
    }

    fn has_time_derivative(&self) -> bool {
        self.formulation.has_time_derivative()
    }

    fn time_derivative(&self, t: f64, y: &[f64], dfdt: &mut [f64]) {
        crate::jacobian::time_derivative(self, t, y, dfdt);
    }

    fn n_events(&self) -> usize {
        self.events.len()
    }

    fn event_spec(&self, _i: usize) -> EventSpec {
        EventSpec {
            direction: Direction::Either,
            action: EventAction::Continue,
        }
    }

    fn events(&self, t: f64, y: &[f64], g: &mut [f64]) {
        let mut sc = self.scratch.borrow_mut();
        self.formulation
            .event_kinematics(t, y, &self.bodies, &mut sc);
        events::values(&self.events, &self.forces, t, &sc, g, None);
    }

    fn event_rates(&self, t: f64, y: &[f64], g: &mut [f64], g_dot: &mut [f64]) -> bool {
        let mut sc = self.scratch.borrow_mut();
        self.formulation
            .event_kinematics(t, y, &self.bodies, &mut sc);
        events::values(&self.events, &self.forces, t, &sc, g, Some(g_dot));
        true
    }

    /// mechanism/accepted.rs: a singular configuration Lagrange–Baumgarte cannot pass, or a
    /// constraint violation over its tolerance.
    /// (Inline: where there is nothing to check, a minimal tree or no constraint rows, the
    /// call returns at once without entering the checks.)
    #[inline]
    fn check_accepted(
        &self,
        t_a: f64,
        y_a: &[f64],
        t_b: f64,
        y_b: &[f64],
    ) -> Result<(), Rejection> {
        if !self.checks_accepted_steps() {
            return Ok(());
        }
        self.check_accepted_state(t_a, y_a, t_b, y_b)
    }

    fn on_event(&self, hit: &EventHit, y: &mut [f64]) -> EventAction {
        match self.events.get(hit.index).copied() {
            Some(EventKind::Contact(k)) if hit.rising => {
                let mut sc = self.scratch.borrow_mut();
                self.kinematics(hit.t, y, &mut sc);
                let c = &self.forces.revolute[k];
                let st = c.state(&sc.kin());
                c.impact_velocity.set(st.delta_dot);
            }
            Some(EventKind::Corner(k, c)) if hit.rising => {
                let mut sc = self.scratch.borrow_mut();
                self.kinematics(hit.t, y, &mut sc);
                let p = &self.forces.prismatic[k];
                let (_, ddot) = p.corner_gap(c, &sc.kin());
                p.impact_velocity[c].set(ddot);
            }
            _ => {}
        }
        EventAction::Continue
    }
}

impl Mechanism {
    /// Adds (or removes) the kink events of the revolute clearance joints' force laws
    /// (δ = d_max, the clip of F_N at 0, |v_T| = v₀ and v₁; docs/model.md §7), as the scene
    /// field `kink_events` does. With them an integration restarts at every kink, so a method
    /// of high order keeps its order through a contact; every other event keeps its index.
    pub fn set_kink_events(&mut self, on: bool) {
        let f = &self.forces;
        self.events = event_list(&f.revolute, &f.prismatic, &f.elements, on);
        self.kink_events = on;
    }

    /// Whether the kink events are on: the scene's `kink_events` where it gives one, else the
    /// automatic choice — on when some revolute clearance joint is dry (no film) and its laws
    /// have a kink (docs/model.md §7, "Kink events") — or the last
    /// [`Mechanism::set_kink_events`]. The one place where the effective value is decided; a
    /// run turns the solver's exact event steps on with it.
    pub fn kink_events(&self) -> bool {
        self.kink_events
    }

    /// Sets the stored impact velocity δ̇⁻ of clearance joint `k` (m/s), as the contact-onset
    /// event does. For tests and for restarting a run from a saved state.
    pub fn set_impact_velocity(&self, k: usize, v: f64) {
        if let Some(c) = self.forces.revolute.get(k) {
            c.impact_velocity.set(v);
        }
    }
}
