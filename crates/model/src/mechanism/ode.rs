//! The mechanism as an `OdeSystem` for the integrators of `lash-solver`.

use faer::MatMut;
use lash_solver::{Direction, EventAction, EventHit, EventSpec, OdeSystem};

use crate::mechanism::events::EventKind;
use crate::mechanism::Mechanism;

impl OdeSystem for Mechanism {
    fn dim(&self) -> usize {
        2 * self.nq()
    }

    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        let nq = self.nq();
        let mut sc = self.scratch.borrow_mut();
        let ok = self.evaluate(t, y, &mut sc, false);
        dy[..nq].copy_from_slice(&y[nq..2 * nq]);
        if ok {
            dy[nq..].copy_from_slice(&sc.qdd);
        } else {
            dy[nq..].iter_mut().for_each(|v| *v = f64::NAN);
        }
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, t: f64, y: &[f64], jac: MatMut<'_, f64>) {
        crate::jacobian::jacobian(self, t, y, jac);
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
        self.kinematics(t, y, &mut sc);
        self.event_values(&sc, g, None);
    }

    fn event_rates(&self, t: f64, y: &[f64], g: &mut [f64], g_dot: &mut [f64]) -> bool {
        let mut sc = self.scratch.borrow_mut();
        self.kinematics(t, y, &mut sc);
        self.event_values(&sc, g, Some(g_dot));
        true
    }

    fn on_event(&self, hit: &EventHit, y: &mut [f64]) -> EventAction {
        match self.events.get(hit.index).copied() {
            Some(EventKind::Contact(k)) if hit.rising => {
                let mut sc = self.scratch.borrow_mut();
                self.kinematics(hit.t, y, &mut sc);
                let st = self.clearance_state(k, &sc);
                self.clr[k].impact_velocity.set(st.delta_dot);
            }
            Some(EventKind::Corner(k, c)) if hit.rising => {
                let mut sc = self.scratch.borrow_mut();
                self.kinematics(hit.t, y, &mut sc);
                let (_, ddot) = self.prismatic[k].corner_gap(c, &sc.pose, &sc.vel, &sc.cs);
                self.prismatic[k].impact_velocity[c].set(ddot);
            }
            _ => {}
        }
        EventAction::Continue
    }
}

#[cfg(test)]
mod tests {
    //! The Schur-complement solve equals faer's LU solve of the full KKT matrix.
    use super::*;
    use crate::cases::{press_scene, PressJoint};
    use faer::Mat;

    #[test]
    fn schur_complement_equals_the_full_kkt_solve() {
        let m = Mechanism::from_scene(&press_scene(PressJoint::Dry, 150.0, 1e-4)).unwrap();
        let nq = m.nq();
        let nc = m.rows.len();
        // A perturbed state: off the constraint manifold, in contact, moving.
        let mut y = m.initial_state();
        let pert = [
            3e-5, -1.2e-4, 2e-3, 1e-4, 2e-5, -1e-3, 0.02, -0.01, 0.3, -0.05, 0.01, 0.002,
        ];
        for (v, p) in y.iter_mut().zip(pert) {
            *v += p;
        }
        let t = 0.123;
        let mut sc = m.scratch.borrow().clone();
        assert!(m.evaluate(t, &y, &mut sc, false));
        m.dense_constraint_jacobian(&mut sc);
        assert!(sc.clr[0].f_n > 0.0, "the test state is in contact");
        let n = nq + nc;
        let mut kkt = Mat::<f64>::zeros(n, n);
        let mut rhs = Mat::<f64>::zeros(n, 1);
        for j in 0..nq {
            kkt[(j, j)] = 1.0 / m.minv[j];
            rhs[(j, 0)] = sc.g[j];
        }
        for a in 0..nc {
            for j in 0..nq {
                kkt[(nq + a, j)] = sc.jac[a * nq + j];
                kkt[(j, nq + a)] = sc.jac[a * nq + j];
            }
            rhs[(nq + a, 0)] = sc.rc[a];
        }
        use faer::linalg::solvers::Solve;
        let sol = kkt.partial_piv_lu().solve(&rhs);
        for j in 0..nq {
            let d = (sol[(j, 0)] - sc.qdd[j]).abs();
            assert!(
                d <= 1e-9 * sol[(j, 0)].abs().max(1.0),
                "q̈[{j}]: {} vs {}",
                sol[(j, 0)],
                sc.qdd[j]
            );
        }
        for a in 0..nc {
            let d = (sol[(nq + a, 0)] - sc.lam[a]).abs();
            assert!(d <= 1e-9 * sol[(nq + a, 0)].abs().max(1.0), "λ[{a}]");
        }
    }
}
