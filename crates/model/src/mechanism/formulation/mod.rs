//! The constraint side of a mechanism: a formulation owns the layout of the state y and the
//! acceleration solve. Everything else — bodies, clearance joints, force elements, events,
//! outputs — works in absolute coordinates (x, y, φ of every body, docs/model.md §1.1), which a
//! formulation maps its state to.
//!
//! # The contract
//!
//! ```text
//! name()            the name a scene field or flag would give it ("lagrange_baumgarte")
//! dim()             length of y
//! kinematics(t, y, bodies, sc)
//!                   the poses, velocities and (cos φ, sin φ) of the integrated bodies in sc
//!                   from y, then the prescribed bodies (Bodies::kinematics does both from an
//!                   absolute (q, q̇); a formulation whose y is not (q, q̇) first recovers it,
//!                   e.g. q̇ = R(θ) θ̇ on a spanning tree)
//! state_of(y_abs)   y of an absolute (q, q̇) of the integrated bodies (the assembled initial
//!                   state is absolute: assembly.rs)
//! accelerations(t, constraints, bodies, sc, full) → ok
//!                   q̈ of the integrated coordinates into sc.qdd, from the applied forces
//!                   sc.g (absolute, n_q) and the kinematics in sc; false when the solve fails
//!                   (the right-hand side is then NaN, never a silent wrong value)
//! derivative(y, qdd, dy)
//!                   ẏ from y and q̈
//! jacobian(constraints, sc, dg, jac)
//!                   ∂ẏ/∂y after an evaluation, given dg = ∂g/∂(q, q̇) of the applied forces in
//!                   absolute coordinates (n_q × 2n_q, column-major: what the clearance joints
//!                   and force elements give); dg = None: the evaluation failed (NaN rows)
//! reactions(constraints, cf, torques)
//!                   the constraint forces on every body and the driver torques of the last
//!                   evaluation (outputs; the Newton–Euler balance of prescribed bodies)
//! constraint_violation()
//!                   ‖Φ(q, t)‖₂ of the last evaluation
//! needs_full_rank() the assembly checks that Φ_q has full row rank at the initial state
//! check_point_mobility(..), check_equations(..)
//!                   its checks at the assembled initial state (initial_check.rs calls them)
//! ```
//! The constraint equations themselves ([`crate::mechanism::constraints`]: Φ, Φ̇, γ and their
//! Jacobian blocks) are shared by every formulation; how they are enforced is each one's own.
//! A formulation keeps its buffers to itself (behind a `RefCell`), so `&self` evaluates.
//!
//! # Adding one (issue 26)
//!
//! A file beside `lagrange_baumgarte/` with a struct that implements the contract, and a
//! variant of [`Formulation`] with its arm in each method below; the mechanism builds it in
//! `Mechanism::from_scene` (mechanism/build.rs, phase 3). An augmented Lagrangian keeps
//! y = (q, q̇) and replaces the Schur-complement solve by (M + Φ_qᵀαΦ_q) q̈ = … with λ*
//! iterated; a minimal formulation has y = (θ, θ̇) and maps it in `kinematics` and
//! `state_of`, its `jacobian` chaining dg through ∂(q, q̇)/∂(θ, θ̇). Neither touches the
//! clearance joints, the force elements or the outputs.
//!
//! `lagrange_baumgarte`, `augmented_lagrangian` and `minimal` (minimal/: joint
//! coordinates on the spanning tree of the ideal joints, the joints that close loops kept as
//! constraints on the reduced system: minimal/loops.rs) exist today; the augmented
//! Lagrangian's core (augmented_lagrangian/core.rs) and the columns of its Jacobian
//! (augmented_lagrangian/columns.rs) work on any (M, Φ_q, c) and serve both. The scene's
//! `auto` (the default) is resolved to one of them in `Mechanism::from_scene`.

pub(crate) mod augmented_lagrangian;
pub(crate) mod column_terms;
pub(crate) mod lagrange_baumgarte;
pub(crate) mod minimal;

use faer::MatMut;

use crate::mechanism::bodies::{Bodies, BodyInfo};
use crate::mechanism::constraints::Constraints;
use crate::mechanism::forces::Forces;
use crate::mechanism::scratch::Scratch;
use crate::scene::error::SceneError;
use crate::scene::format::Scene;

pub(crate) use augmented_lagrangian::{AugmentedLagrangian, FormulationStats};
pub(crate) use lagrange_baumgarte::LagrangeBaumgarte;
pub(crate) use minimal::Minimal;

/// The formulation of a mechanism (module doc).
#[derive(Debug)]
pub(crate) enum Formulation {
    /// Lagrange multipliers with Baumgarte stabilisation (docs/model.md §1.3–§1.5).
    LagrangeBaumgarte(LagrangeBaumgarte),
    /// The augmented Lagrangian (augmented_lagrangian/, docs/model.md §12).
    AugmentedLagrangian(AugmentedLagrangian),
    /// Joint coordinates on the spanning tree of the ideal joints (minimal/, docs/model.md
    /// §12).
    Minimal(Box<Minimal>),
}

/// ε·α of the `kkt` path's regularised KKT matrix under the augmented Lagrangian
/// ([`Formulation::kkt_regularisation`]). K_ε's Newton matrix differs from K's by about
/// ε/σ relative, σ the smallest singular value of Φ_q M⁻¹ Φ_qᵀ where Φ_q has full rank (about
/// 1/m̄ for links of mean mass m̄, α = 10⁴ m̄ by default): 10⁻⁸/α leaves it 10⁻¹² relative, the
/// augmented Lagrangian's own tolerance, so Newton converges as on the exact matrix (measured:
/// the chains of tests/kkt.rs take the dense path's Newton iterations); 1/α itself (the
/// iteration's penalty) left it 10⁻⁴ off and cost TR-BDF2 15 % more Newton iterations there.
/// Where Φ_q loses rank, ε keeps K_ε's pivots ≥ ε instead of rounding.
pub(crate) const KKT_REGULARISATION: f64 = 1e-8;

impl Formulation {
    /// Its name.
    pub(crate) fn name(&self) -> &'static str {
        match self {
            Formulation::LagrangeBaumgarte(_) => "lagrange_baumgarte",
            Formulation::AugmentedLagrangian(_) => "augmented_lagrangian",
            Formulation::Minimal(_) => "minimal",
        }
    }

    /// (p, s) of the constraint rows' right-hand side c = γ − pΦ̇ − sΦ of the KKT form
    /// (crate::kkt) under the absolute formulations; None under minimal.
    pub(crate) fn kkt_stabilisation(&self) -> Option<(f64, f64)> {
        match self {
            Formulation::LagrangeBaumgarte(f) => Some(f.stabilisation()),
            Formulation::AugmentedLagrangian(f) => Some(f.stabilisation()),
            Formulation::Minimal(_) => None,
        }
    }

    /// ε of the regularised KKT matrix [[M, Φ_qᵀ], [Φ_q, −εI]] of the `kkt` path (crate::kkt):
    /// [`KKT_REGULARISATION`]/α for the augmented Lagrangian, whose iteration tolerates a
    /// singular K; None for Lagrange–Baumgarte, which needs Φ_q of full row rank.
    pub(crate) fn kkt_regularisation(&self) -> Option<f64> {
        match self {
            Formulation::AugmentedLagrangian(f) => Some(KKT_REGULARISATION / f.penalty()),
            _ => None,
        }
    }

    /// Length of the state y.
    pub(crate) fn dim(&self, bodies: &Bodies) -> usize {
        match self {
            Formulation::LagrangeBaumgarte(_) | Formulation::AugmentedLagrangian(_) => {
                2 * bodies.nq()
            }
            Formulation::Minimal(f) => 2 * f.n(),
        }
    }

    /// The kinematics of every body at (t, y) into `sc`.
    #[inline]
    pub(crate) fn kinematics(&self, t: f64, y: &[f64], bodies: &Bodies, sc: &mut Scratch) {
        match self {
            Formulation::LagrangeBaumgarte(_) | Formulation::AugmentedLagrangian(_) => {
                bodies.kinematics(t, y, sc)
            }
            Formulation::Minimal(f) => f.kinematics(t, y, bodies, sc),
        }
    }

    /// The poses, velocities and (cos φ, sin φ) of every body at (t, y) into `sc` (what the
    /// event functions read), without what `kinematics` keeps for an evaluation.
    #[inline]
    pub(crate) fn event_kinematics(&self, t: f64, y: &[f64], bodies: &Bodies, sc: &mut Scratch) {
        match self {
            Formulation::Minimal(f) => f.positions(t, y, bodies, sc),
            _ => self.kinematics(t, y, bodies, sc),
        }
    }

    /// y of the absolute (q, q̇) of the integrated bodies.
    pub(crate) fn state_of(&self, y_abs: &[f64]) -> Vec<f64> {
        match self {
            Formulation::LagrangeBaumgarte(_) | Formulation::AugmentedLagrangian(_) => {
                y_abs.to_vec()
            }
            Formulation::Minimal(f) => f.state_of(y_abs),
        }
    }

    /// q̈ into `sc.qdd` from `sc.g` and the kinematics; false if the solve fails.
    #[inline]
    pub(crate) fn accelerations(
        &self,
        t: f64,
        cons: &Constraints,
        info: &[BodyInfo],
        sc: &mut Scratch,
        full: bool,
    ) -> bool {
        match self {
            Formulation::LagrangeBaumgarte(f) => f.accelerations(t, cons, info, sc, full),
            Formulation::AugmentedLagrangian(f) => f.accelerations(t, cons, info, sc),
            Formulation::Minimal(f) => f.accelerations(t, cons, info, sc, full),
        }
    }

    /// ẏ from y and q̈ (NaN accelerations when the solve failed: `ok` false).
    #[inline]
    pub(crate) fn derivative(&self, y: &[f64], qdd: &[f64], ok: bool, dy: &mut [f64]) {
        match self {
            Formulation::LagrangeBaumgarte(_) | Formulation::AugmentedLagrangian(_) => {
                let nq = qdd.len();
                dy[..nq].copy_from_slice(&y[nq..2 * nq]);
                if ok {
                    dy[nq..].copy_from_slice(qdd);
                } else {
                    dy[nq..].iter_mut().for_each(|v| *v = f64::NAN);
                }
            }
            Formulation::Minimal(f) => f.derivative(y, ok, dy),
        }
    }

    /// ∂ẏ/∂y after an evaluation, given ∂g/∂(q, q̇) (None: the evaluation failed).
    pub(crate) fn jacobian(
        &self,
        cons: &Constraints,
        sc: &Scratch,
        dg: Option<&[f64]>,
        jac: MatMut<'_, f64>,
    ) {
        match self {
            Formulation::LagrangeBaumgarte(f) => f.jacobian(cons, sc, dg, jac),
            Formulation::AugmentedLagrangian(f) => f.jacobian(cons, sc, dg, jac),
            Formulation::Minimal(f) => f.jacobian(sc, dg, jac),
        }
    }

    /// Whether [`Formulation::time_derivative`] gives ∂ẏ/∂t: minimal on a tree only (with
    /// loop closures, whose drivers' rows enter through t, it is left to the integrator as
    /// for the augmented Lagrangian). The others keep
    /// the integrator's central difference in t, well conditioned there (time enters
    /// through the driver rows and the prescribed bodies' joints, not through the bodies the
    /// stiff forces act on).
    pub(crate) fn has_time_derivative(&self) -> bool {
        matches!(self, Formulation::Minimal(f) if f.loops().is_none())
    }

    /// ∂ẏ/∂t at fixed y after an evaluation at (t, y), given ∂g/∂(q, q̇) (minimal on a tree
    /// only: minimal/jacobian.rs); false (nothing written) for the others.
    pub(crate) fn time_derivative(
        &self,
        bodies: &Bodies,
        forces: &Forces,
        t: f64,
        sc: &Scratch,
        dg: &[f64],
        out: &mut [f64],
    ) -> bool {
        match self {
            Formulation::Minimal(f) if f.loops().is_none() => {
                f.time_derivative(bodies, forces, t, sc, dg, out);
                true
            }
            _ => false,
        }
    }

    /// The constraint forces on every body (added to `cf`) and the driver torques (pushed to
    /// `torques` as (joint, τ)) of the last evaluation.
    pub(crate) fn reactions(
        &self,
        cons: &Constraints,
        cf: &mut [[f64; 3]],
        torques: &mut Vec<(usize, f64)>,
    ) {
        match self {
            Formulation::LagrangeBaumgarte(f) => f.reactions(cons, cf, torques),
            Formulation::AugmentedLagrangian(f) => f.reactions(cons, cf, torques),
            Formulation::Minimal(f) => f.reactions(cons, cf, torques),
        }
    }

    /// ‖Φ(q, t)‖₂ of the last evaluation.
    pub(crate) fn constraint_violation(&self) -> f64 {
        match self {
            Formulation::LagrangeBaumgarte(f) => f.constraint_violation(),
            Formulation::AugmentedLagrangian(f) => f.constraint_violation(),
            Formulation::Minimal(f) => f.constraint_violation(),
        }
    }

    /// Whether Φ_q must have full row rank (checked by the assembly).
    pub(crate) fn needs_full_rank(&self) -> bool {
        match self {
            // The tree's rows have full rank by construction (each link's rows hold the
            // identity in its own body's coordinates); the reactions' normal equations need it.
            // Loop closures are enforced by the augmented Lagrangian: no rank condition.
            Formulation::LagrangeBaumgarte(_) => true,
            Formulation::Minimal(f) => f.loops().is_none(),
            Formulation::AugmentedLagrangian(_) => false,
        }
    }

    /// Iteration statistics (None for a formulation that does not iterate: Lagrange–
    /// Baumgarte, minimal on a tree).
    pub(crate) fn stats(&self) -> Option<FormulationStats> {
        match self {
            Formulation::LagrangeBaumgarte(_) => None,
            Formulation::Minimal(f) => f.loops().map(|l| l.stats()),
            Formulation::AugmentedLagrangian(f) => Some(f.stats()),
        }
    }

    /// Sets the iteration statistics back to zero.
    pub(crate) fn reset_stats(&self) {
        match self {
            Formulation::AugmentedLagrangian(f) => f.reset_stats(),
            Formulation::Minimal(f) => {
                if let Some(l) = f.loops() {
                    l.reset_stats();
                }
            }
            Formulation::LagrangeBaumgarte(_) => {}
        }
    }

    /// Its checks before any evaluation (initial_check.rs, check 1).
    pub(crate) fn check_point_mobility(
        &self,
        scene: &Scene,
        cons: &Constraints,
        info: &[BodyInfo],
    ) -> Result<(), SceneError> {
        match self {
            Formulation::LagrangeBaumgarte(f) => f.check_point_mobility(scene, cons, info),
            // M + Φ_qᵀαΦ_q is positive definite at every angle: no mobility bound.
            Formulation::AugmentedLagrangian(_) => Ok(()),
            // Rᵀ M R is positive definite whatever the angles: no mobility bound.
            Formulation::Minimal(_) => Ok(()),
        }
    }

    /// Its checks of the equations at (t, y) after the kinematics and applied forces in `sc`
    /// (initial_check.rs, check 2).
    pub(crate) fn check_equations(
        &self,
        t: f64,
        scene: &Scene,
        cons: &Constraints,
        info: &[BodyInfo],
        sc: &Scratch,
    ) -> Result<(), SceneError> {
        match self {
            Formulation::LagrangeBaumgarte(f) => f.check_equations(t, scene, cons, info, sc),
            Formulation::AugmentedLagrangian(f) => f.check_equations(t, scene, cons, info, sc),
            Formulation::Minimal(f) => f.check_equations(t, scene, cons, info, sc),
        }
    }
}

#[cfg(test)]
mod tests {
    //! The seam's state mapping: y → the absolute (q, q̇) of the integrated bodies (through
    //! `kinematics`) and back (`state_of`) is the identity, bit for bit in absolute
    //! coordinates and to rounding in joint coordinates, and the initial state a formulation
    //! gives satisfies the constraints it enforces.
    use crate::cases::{press_scene, PressJoint};
    use crate::{FormulationName, Mechanism, Scene};
    use lash_solver::OdeSystem;

    /// y → (q, q̇) → y: bit for bit (`tol` 0), or to `tol` relative (minimal: trigonometry).
    fn round_trip(m: &Mechanism, t: f64, y: &[f64], tol: f64) {
        let f = m.formulation();
        assert_eq!(f.dim(m.bodies()), y.len());
        let mut sc = m.scratch();
        f.kinematics(t, y, m.bodies(), &mut sc);
        let nq = m.nq();
        let mut y_abs = vec![0.0; 2 * nq];
        for (i, &k) in m.bodies().int_bodies.iter().enumerate() {
            y_abs[3 * i..3 * i + 3].copy_from_slice(&sc.pose[k]);
            y_abs[nq + 3 * i..nq + 3 * i + 3].copy_from_slice(&sc.vel[k]);
            let (s, c) = sc.pose[k][2].sin_cos();
            assert_eq!(sc.cs[k], [c, s]);
        }
        let back = f.state_of(&y_abs);
        if tol == 0.0 {
            assert_eq!(
                back.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                y.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            );
        } else {
            for (a, b) in back.iter().zip(y) {
                assert!((a - b).abs() <= tol * (1.0 + b.abs()), "{back:?} vs {y:?}");
            }
        }
    }

    #[test]
    fn the_state_maps_to_absolute_coordinates_and_back() {
        let pendulum = Scene::from_path(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../cases/examples/pendulum.json"
        ))
        .unwrap();
        let mut built = Vec::new();
        for scene in [press_scene(PressJoint::Dry, 150.0, 1e-4), pendulum] {
            for f in [FormulationName::LagrangeBaumgarte, FormulationName::Auto] {
                let mut s = scene.clone();
                s.formulation = f;
                built.push(Mechanism::from_scene(&s).unwrap());
            }
        }
        for m in &built {
            // Both scenes are trees: auto takes minimal.
            let (name, tol) = (m.formulation().name(), 1e-13);
            let tol = if name == "lagrange_baumgarte" {
                0.0
            } else {
                tol
            };
            assert!(["lagrange_baumgarte", "minimal"].contains(&name), "{name}");
            let y0 = m.initial_state();
            round_trip(m, m.t_start(), &y0, tol);
            // Off the constraint manifold too: the mapping does not project.
            let y: Vec<f64> = y0
                .iter()
                .enumerate()
                .map(|(i, v)| v + 1e-3 * (i as f64 + 1.0).sin())
                .collect();
            round_trip(m, m.t_start() + 0.01, &y, tol);
            // The assembled initial state meets the constraints to the assembly's tolerance.
            let o = m.outputs(m.t_start(), &y0);
            assert!(o.constraint_violation < 1e-11, "{}", o.constraint_violation);
            assert_eq!(m.dim(), y0.len());
        }
    }
}
