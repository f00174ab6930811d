//! The mechanism: a validated scene turned into the index-1 ODE of docs/model.md §1.
//!
//! ```text
//! bodies.rs        which bodies are integrated, which prescribed; where a force goes
//! constraints.rs   the equations Φ(q, t) = 0 of the ideal joints and drivers
//! forces.rs        gravity, clearance joints and force elements → g, and ∂g/∂(q, q̇)
//! formulation/     the state y and the acceleration solve (Lagrange–Baumgarte today)
//! events.rs        the event functions, their values and labels
//! scratch.rs       the buffers of one evaluation
//! build.rs         Mechanism::from_scene, in named phases
//! ode.rs           impl OdeSystem, and the event hooks
//! accepted.rs      the checks of an accepted state: a singular configuration, a violation
//!
//! one evaluation at (t, y): kinematics (formulation: y → poses and velocities of every
//!   body) → applied forces g (forces.rs) → q̈ (formulation) → ẏ (formulation)
//! ```
//! A body whose motion is prescribed (a rotational driver plus a revolute joint to the ground
//! or to another prescribed body: the press's crank) is not integrated; its pose, velocity and
//! acceleration are closed-form functions of t, and the joints to it are rheonomic constraints
//! on the other body. Nothing outside this module reads the mechanism's fields: the rest of
//! the crate goes through the methods and views below.
//!
//! Sources: docs/model.md §1 (Nikravesh, Computer-Aided Analysis of Mechanical Systems, 1988;
//! Baumgarte 1972), Peng et al. 2025 §3.

pub(crate) mod accepted;
pub(crate) mod bodies;
mod build;
pub(crate) mod constraints;
pub(crate) mod events;
pub(crate) mod forces;
pub(crate) mod formulation;
mod ode;
pub(crate) mod row;
pub(crate) mod scratch;

use std::cell::{RefCell, RefMut};

use crate::labels::EventLabels;
use crate::mechanism::bodies::{Bodies, BodyInfo};
use crate::mechanism::constraints::Constraints;
use crate::mechanism::events::{EventKind, Events};
use crate::mechanism::forces::{ForceJacWork, Forces};
use crate::mechanism::formulation::{Formulation, FormulationStats};
use crate::mechanism::scratch::Scratch;
use crate::planar::{cross, perp, rot};
use crate::projection::ProjectionReport;
use crate::roles::Roles;
use crate::scene::format::{JointSpec, Scene};

/// A planar mechanism as an ODE: build it with [`Mechanism::from_scene`], integrate it with
/// `lash_solver::solve` from [`Mechanism::initial_state`], read it with
/// [`Mechanism::outputs`].
///
/// ```text
/// y' = f(t, y),  y = (q, q̇)  (docs/model.md §1);  events δ_k(q), ε_k − ε_cap and the
/// corner gaps δ_i of the prismatic clearance joints (§7, §11)
/// ```
#[derive(Debug)]
pub struct Mechanism {
    scene: Scene,
    bodies: Bodies,
    constraints: Constraints,
    forces: Forces,
    formulation: Formulation,
    events: Events,
    /// Whether the kink events are on: the scene's `kink_events`, or the automatic choice
    /// (build.rs; docs/model.md §7), or [`Mechanism::set_kink_events`].
    kink_events: bool,
    projection: ProjectionReport,
    t_start: f64,
    t_end: f64,
    y0: Vec<f64>,
    roles: Roles,
    /// Under Lagrange–Baumgarte: the ideal joints form a tree, so Φ_q has full row rank in
    /// every configuration (mechanism::accepted: no crossing to look for).
    rank_holds: bool,
    scratch: RefCell<Scratch>,
    force_jac: RefCell<ForceJacWork>,
}

/// One full evaluation at (t, y): its buffers, whether the acceleration solve succeeded, the
/// torque of every driver (joint index, τ; scene order) and ‖Φ(q, t)‖₂. Its buffers go back
/// to [`SPARE`] when it is dropped.
pub(crate) struct FullEvaluation {
    pub sc: Scratch,
    pub ok: bool,
    pub torques: Vec<(usize, f64)>,
    pub violation: f64,
}

/// Most buffers kept per thread for full evaluations.
const SPARE_MAX: usize = 4;

thread_local! {
    /// The buffers of dropped full evaluations, reused by the next ones (outputs are evaluated
    /// thousands of times per run: a copy into kept buffers instead of ten allocations).
    static SPARE: RefCell<Vec<Scratch>> = const { RefCell::new(Vec::new()) };
}

impl Drop for FullEvaluation {
    fn drop(&mut self) {
        let sc = std::mem::replace(&mut self.sc, Scratch::empty());
        // A thread being torn down has no pool left: the buffers are then simply freed.
        let _ = SPARE.try_with(|s| {
            if let Ok(mut s) = s.try_borrow_mut() {
                if s.len() < SPARE_MAX {
                    s.push(sc);
                }
            }
        });
    }
}

impl Mechanism {
    /// What the projection onto the constraints changed in the scene's initial guesses
    /// (docs/model.md §1, "Initial conditions").
    pub fn projection_report(&self) -> &ProjectionReport {
        &self.projection
    }

    /// Names of the force elements, in the order of [`crate::Outputs::elements`].
    pub fn element_names(&self) -> Vec<&str> {
        self.scene.forces.iter().map(|e| e.name()).collect()
    }

    /// Names of the prismatic clearance joints, in the order of [`crate::Outputs::prismatic`].
    pub fn prismatic_names(&self) -> Vec<&str> {
        self.forces
            .prismatic
            .iter()
            .map(|p| p.name.as_str())
            .collect()
    }

    /// y0 after assembly: (q, q̇) of the integrated bodies.
    pub fn initial_state(&self) -> Vec<f64> {
        self.y0.clone()
    }

    /// The state y of this mechanism's formulation for an absolute state (q, q̇) of the
    /// integrated bodies (as [`Mechanism::integrated_bodies`] orders them, (x, y, φ) each):
    /// itself for `lagrange_baumgarte` and `augmented_lagrangian`, the joint coordinates and
    /// their rates for `minimal` (exact on the constraint manifold). For comparing
    /// formulations at one state.
    pub fn state_of_absolute(&self, y_abs: &[f64]) -> Vec<f64> {
        self.formulation.state_of(y_abs)
    }

    /// Start time (s).
    pub fn t_start(&self) -> f64 {
        self.t_start
    }

    /// End time (s): `t_end`, or t_start + revolutions · 2π/|ω| of the crank driver.
    pub fn t_end(&self) -> f64 {
        self.t_end
    }

    /// The scene this mechanism was built from.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Resolved roles.
    pub fn roles(&self) -> &Roles {
        &self.roles
    }

    /// The name of the formulation (mechanism/formulation): `lagrange_baumgarte`,
    /// `augmented_lagrangian` or `minimal`.
    pub fn formulation_name(&self) -> &'static str {
        self.formulation.name()
    }

    /// The iteration statistics of the formulation since the mechanism was built or the last
    /// [`Mechanism::reset_formulation_stats`]; None for one that does not iterate
    /// (`lagrange_baumgarte`, `minimal` on a tree; `minimal` with loop closures iterates on
    /// them).
    pub fn formulation_stats(&self) -> Option<FormulationStats> {
        self.formulation.stats()
    }

    /// Sets the formulation's iteration statistics back to zero (before a run).
    pub fn reset_formulation_stats(&self) {
        self.formulation.reset_stats();
    }

    /// ω (rad/s) of the `crank_driver` role, if declared.
    pub fn crank_speed(&self) -> Option<f64> {
        let j = self.roles.crank_driver?;
        match &self.scene.joints[j] {
            JointSpec::Driver(d) => Some(d.omega_rad_s()),
            _ => None,
        }
    }

    /// Names of the integrated bodies, in the order of q.
    pub fn integrated_bodies(&self) -> Vec<&str> {
        self.bodies
            .int_bodies
            .iter()
            .map(|&k| self.bodies.info[k].name.as_str())
            .collect()
    }

    /// Names of the prescribed (not integrated) bodies.
    pub fn prescribed_bodies(&self) -> Vec<&str> {
        self.bodies
            .pres
            .iter()
            .map(|p| self.bodies.info[p.body].name.as_str())
            .collect()
    }

    /// Number of constraint equations in the KKT system.
    pub fn n_constraints(&self) -> usize {
        self.constraints.len()
    }

    /// Names of the clearance joints, in the order of [`crate::Outputs::clearance`].
    pub fn clearance_names(&self) -> Vec<&str> {
        self.forces
            .revolute
            .iter()
            .map(|c| c.name.as_str())
            .collect()
    }

    /// The stored impact velocity δ̇⁻ of every clearance joint (m/s; 0 before any onset).
    pub fn impact_velocities(&self) -> Vec<f64> {
        self.forces
            .revolute
            .iter()
            .map(|c| c.impact_velocity.get())
            .collect()
    }

    /// Which event function index `i` is: its kind and the name of the joint or element that
    /// owns it — ("contact" | "eps_cap" | "kink_…", clearance joint), ("corner_contact",
    /// prismatic clearance joint) for the gap δ_i of one of its four corners (docs/model.md
    /// §7, §11), or an element's own kind.
    pub fn event_name(&self, i: usize) -> Option<(&'static str, &str)> {
        let e = *self.events.get(i)?;
        let (labels, k) = events::labels(e, &self.forces);
        let owner = match e {
            EventKind::Contact(_) | EventKind::EpsCap(_) | EventKind::Kink(..) => {
                self.forces.revolute[k].name.as_str()
            }
            EventKind::Corner(..) => self.forces.prismatic[k].name.as_str(),
            EventKind::Element(..) => self.scene.forces[k].name(),
        };
        Some((labels.kind, owner))
    }

    /// The labels of event function `i`: its kind and the names of its rising and falling
    /// crossings, as the joint or element that owns it declares them.
    pub fn event_labels(&self, i: usize) -> Option<EventLabels> {
        let e = *self.events.get(i)?;
        Some(events::labels(e, &self.forces).0)
    }

    // -----------------------------------------------------------------------------------------
    // Views for the rest of the crate
    // -----------------------------------------------------------------------------------------

    /// Number of integrated coordinates n_q.
    pub(crate) fn nq(&self) -> usize {
        self.bodies.nq()
    }

    /// The bodies: who moves how, the prescriptions.
    pub(crate) fn bodies(&self) -> &Bodies {
        &self.bodies
    }

    /// Every body, in scene order.
    pub(crate) fn body_info(&self) -> &[BodyInfo] {
        &self.bodies.info
    }

    /// The constraint equations.
    pub(crate) fn constraints(&self) -> &Constraints {
        &self.constraints
    }

    /// Gravity, the clearance joints and the force elements.
    pub(crate) fn forces(&self) -> &Forces {
        &self.forces
    }

    /// The formulation.
    pub(crate) fn formulation(&self) -> &Formulation {
        &self.formulation
    }

    /// The mechanism's buffers (borrowed for one evaluation).
    pub(crate) fn scratch(&self) -> RefMut<'_, Scratch> {
        self.scratch.borrow_mut()
    }

    /// The buffers of the force side of the Jacobian.
    pub(crate) fn force_jac_work(&self) -> RefMut<'_, ForceJacWork> {
        self.force_jac.borrow_mut()
    }

    // -----------------------------------------------------------------------------------------
    // Evaluation core
    // -----------------------------------------------------------------------------------------

    /// Poses and velocities of every body at (t, y); accelerations of prescribed bodies.
    #[inline]
    pub(crate) fn kinematics(&self, t: f64, y: &[f64], sc: &mut Scratch) {
        self.formulation.kinematics(t, y, &self.bodies, sc);
    }

    /// One full evaluation at (t, y) into the scratch; false if the acceleration solve fails.
    /// After it, `acc` holds every body's acceleration.
    pub(crate) fn evaluate(&self, t: f64, y: &[f64], sc: &mut Scratch, full: bool) -> bool {
        self.kinematics(t, y, sc);
        self.forces.applied(&self.bodies, t, sc, full);
        let ok = self
            .formulation
            .accelerations(t, &self.constraints, &self.bodies.info, sc, full);
        for (i, &k) in self.bodies.int_bodies.iter().enumerate() {
            sc.acc[k] = [sc.qdd[3 * i], sc.qdd[3 * i + 1], sc.qdd[3 * i + 2]];
        }
        ok
    }

    /// The integrator's right-hand side ẏ at (t, y) into `dy`, in the scratch `sc`. Under
    /// `minimal` on a small tree (formulation/minimal/small.rs) θ̈ alone, on the stack: no
    /// q̈, no bodies' accelerations, no `sc.g` or clearance evaluations, no copy of (t, y) or
    /// of R into the formulation's buffers (whatever reads those evaluates first); otherwise
    /// [`Mechanism::evaluate`] and the formulation's ẏ.
    #[inline]
    pub(crate) fn rhs_into(&self, t: f64, y: &[f64], sc: &mut Scratch, dy: &mut [f64]) {
        if let Formulation::Minimal(f) = &self.formulation {
            if f.takes_small_path() {
                let n = f.n();
                f.positions(t, y, &self.bodies, sc);
                dy[..n].copy_from_slice(&y[n..2 * n]);
                if !f.small_accelerations(&self.bodies, &self.forces, t, sc, &mut dy[n..2 * n]) {
                    dy[n..2 * n].iter_mut().for_each(|v| *v = f64::NAN);
                }
                return;
            }
        }
        let ok = self.evaluate(t, y, sc, false);
        self.formulation.derivative(y, &sc.qdd, ok, dy);
    }

    /// A copy of the buffers after an evaluation at (t, y); None when the acceleration solve
    /// fails (for tests).
    #[cfg(test)]
    pub(crate) fn evaluated(&self, t: f64, y: &[f64]) -> Option<Scratch> {
        let mut sc = self.scratch.borrow().clone();
        self.evaluate(t, y, &mut sc, false).then_some(sc)
    }

    /// One full evaluation at (t, y) with the driver torques (docs/model.md §1.5):
    ///
    /// ```text
    /// τ_d = −λ_d                                  (driver on an integrated body)
    /// τ_d from  J_pᵀ λ_p = g_p + f_c,p − M_p a_p   (prescribed body p, Newton–Euler:
    ///           λ_p = (pin reaction, driver λ); f_c,p = −Σ J_r,pᵀ λ_r of the other joints
    ///           on p; g_p gravity and clearance forces on p), children before parents
    /// ```
    pub(crate) fn full_evaluation(&self, t: f64, y: &[f64]) -> FullEvaluation {
        // A copy of the right-hand side's buffers (as a clone, into kept ones).
        let mut sc = SPARE
            .try_with(|s| s.try_borrow_mut().ok().and_then(|mut s| s.pop()))
            .ok()
            .flatten()
            .unwrap_or_else(Scratch::empty);
        sc.clone_from(&self.scratch.borrow());
        let ok = self.evaluate(t, y, &mut sc, true);
        let violation = self.formulation.constraint_violation();
        let nb = self.bodies.info.len();
        // Constraint forces −Σ J_r,kᵀ λ_r on every body, and the driver rows' torques.
        let mut cf = vec![[0.0f64; 3]; nb];
        let mut torques: Vec<(usize, f64)> = Vec::new();
        self.formulation
            .reactions(&self.constraints, &mut cf, &mut torques);
        // Newton–Euler of the prescribed bodies, children before parents.
        for p in self.bodies.pres.iter().rev() {
            let k = p.body;
            let b = &self.bodies.info[k];
            let m = [b.mass, b.mass, b.inertia];
            let mut res = [0.0; 3];
            for c in 0..3 {
                res[c] = sc.gb[k][c] + cf[k][c] - m[c] * sc.acc[k][c];
            }
            let bs = perp(rot(sc.cs[k], p.s_own));
            let lam_pin = [res[0], res[1]];
            let lam_d = res[2] - (bs[0] * lam_pin[0] + bs[1] * lam_pin[1]);
            torques.push((p.driver_joint, -lam_d));
            if let Some((kp, sp)) = p.parent {
                let a = rot(sc.cs[kp], sp);
                cf[kp][0] += lam_pin[0];
                cf[kp][1] += lam_pin[1];
                cf[kp][2] += cross(a, lam_pin);
            }
        }
        torques.sort_by_key(|x| x.0);
        FullEvaluation {
            sc,
            ok,
            torques,
            violation,
        }
    }
}
