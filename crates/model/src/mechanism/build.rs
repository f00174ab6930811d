//! Building a mechanism from a scene, in named phases.
//!
//! ```text
//! 1 validate        Scene::validate (every value and reference, with JSON paths)
//! 2 prescribe       Bodies::prescribe: drivers with a pin make their bodies prescribed
//! 3 constrain       Constraints::build: the equations of the other joints (a joint acting
//!                   only on prescribed bodies is an error)
//! 4 forces          Forces::build: clearance joints and force elements, compiled
//! 5 formulate       the scene's formulation and its structure (Lagrange–Baumgarte: the
//!                   shape of S; augmented Lagrangian: the envelope of M + Φ_qᵀαΦ_q;
//!                   minimal: the spanning tree); `auto` resolved here
//! 6 lay out         events, buffers, roles, the end time
//! 7 assemble        assembly.rs: a consistent initial state, the rank check; then the
//!                   elements' defaults of that state (a spring's free length)
//! 8 check           initial_check.rs: the equations of motion at the initial state
//! ```
//!
//! Between the phases, in assembly's iterations and around the initial Jacobian, set-up
//! stops at the call's deadline or a stop request (`scene::error::checkpoint`).

use std::cell::RefCell;

use crate::scene::error::checkpoint;

use crate::mechanism::bodies::Bodies;
use crate::mechanism::constraints::Constraints;
use crate::mechanism::events::event_list;
use crate::mechanism::forces::Forces;
use crate::mechanism::formulation::minimal::tree::Tree;
use crate::mechanism::formulation::{AugmentedLagrangian, Formulation, LagrangeBaumgarte, Minimal};
use crate::mechanism::scratch::Scratch;
use crate::mechanism::Mechanism;
use crate::roles::Roles;
use crate::scene::error::SceneError;
use crate::scene::format::{FormulationName, Scene};

impl Mechanism {
    /// Validates the scene, finds the prescribed bodies, builds the constraint equations,
    /// checks their rank and assembles the initial state (Newton on positions, then the
    /// velocity constraints; clearance joints held at their initial eccentricity, ė = 0), then
    /// evaluates the equations of motion there once: a right-hand side or Jacobian that is not
    /// finite, or a KKT system singular in f64, is a [`SceneError::Dynamics`] naming the body
    /// or joint (docs/scene-format.md, "Initial check").
    pub fn from_scene(scene: &Scene) -> Result<Mechanism, SceneError> {
        let t0 = scene.t_start;
        scene.validate()?;
        checkpoint("checking the scene", t0)?;
        let bodies = Bodies::prescribe(scene);
        let constraints = Constraints::build(scene, &bodies)?;
        checkpoint("building the constraints", t0)?;
        let forces = Forces::build(scene, &bodies);
        let formulation = match scene.formulation {
            FormulationName::LagrangeBaumgarte => Formulation::LagrangeBaumgarte(
                LagrangeBaumgarte::new(&constraints, &bodies, scene.baumgarte),
            ),
            FormulationName::AugmentedLagrangian => Formulation::AugmentedLagrangian(
                AugmentedLagrangian::new(&constraints, &bodies, scene.augmented_lagrangian),
            ),
            FormulationName::Minimal => {
                Formulation::Minimal(Box::new(Minimal::new(scene, &constraints, &bodies)?))
            }
            // The cheapest that is correct (docs/model.md §12): minimal on a small tree.
            FormulationName::Auto => {
                let tree = Tree::build(scene, &bodies);
                if tree.closing.is_empty() && tree.n <= FormulationName::AUTO_MINIMAL_MAX_DOF {
                    Formulation::Minimal(Box::new(Minimal::on_tree(tree, &constraints, &bodies)))
                } else {
                    Formulation::AugmentedLagrangian(AugmentedLagrangian::new(
                        &constraints,
                        &bodies,
                        scene.augmented_lagrangian,
                    ))
                }
            }
        };
        checkpoint("setting up the formulation", t0)?;
        let mut mech = Mechanism::laid_out(scene, bodies, constraints, forces, formulation);
        mech.assemble()?;
        checkpoint("assembly", t0)?;
        crate::initial_check::check(&mech)?;
        checkpoint("the initial checks", t0)?;
        Ok(mech)
    }

    /// Phase 6: the mechanism before its initial state (events, buffers, roles, end time).
    fn laid_out(
        scene: &Scene,
        bodies: Bodies,
        constraints: Constraints,
        forces: Forces,
        formulation: Formulation,
    ) -> Mechanism {
        // The scene's kink_events, or the automatic choice (docs/model.md §7): on when some
        // revolute clearance joint is dry and its laws have a kink.
        let kink_events = scene
            .kink_events
            .unwrap_or_else(|| forces.revolute.iter().any(|c| c.is_dry_with_kinks()));
        let events = event_list(
            &forces.revolute,
            &forces.prismatic,
            &forces.elements,
            kink_events,
        );
        let scratch = Scratch::new(
            bodies.info.len(),
            bodies.nq(),
            forces.revolute.len(),
            forces.elements.len(),
            forces.prismatic.len(),
        );
        let roles = Roles::resolve(scene, &forces.revolute);
        let rank_holds = matches!(formulation, Formulation::LagrangeBaumgarte(_))
            && Tree::build(scene, &bodies).closing.is_empty();
        let mut mech = Mechanism {
            scene: scene.clone(),
            bodies,
            constraints,
            forces,
            formulation,
            events,
            kink_events,
            projection: Default::default(),
            t_start: scene.t_start,
            t_end: 0.0,
            y0: Vec::new(),
            roles,
            rank_holds,
            scratch: RefCell::new(scratch),
            force_jac: RefCell::default(),
        };
        mech.t_end = match (scene.t_end, scene.revolutions) {
            (Some(te), _) => te,
            (None, Some(n)) => {
                let w = mech
                    .crank_speed()
                    .expect("validated: revolutions need a crank driver");
                scene.t_start + n * 2.0 * std::f64::consts::PI / w.abs()
            }
            (None, None) => unreachable!("validated"),
        };
        mech
    }

    /// Phase 7: the assembled initial state (absolute, mapped to the formulation's state),
    /// what the projection changed, and the elements' defaults of that state.
    fn assemble(&mut self) -> Result<(), SceneError> {
        let (y_abs, projection) = crate::assembly::assemble(self)?;
        self.y0 = self.formulation.state_of(&y_abs);
        self.projection = projection;
        if !self.forces.elements.is_empty() {
            let t0 = self.t_start;
            let mut sc = self.scratch.borrow().clone();
            self.kinematics(t0, &self.y0, &mut sc);
            self.forces.set_initial(t0, &sc);
        }
        Ok(())
    }
}
