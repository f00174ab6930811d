//! The Jacobian ∂f/∂y of the mechanism ODE for implicit methods (docs/model.md §1.7): the
//! formulation's, given the applied forces' ∂g/∂(q, q̇).
//!
//! ```text
//! f(t, y) = formulation(y, q̈(t, q, q̇; g)),  g = g(q, q̇) the applied forces
//! ∂g/∂(q, q̇): mechanism/forces.rs (each revolute clearance joint's closed form,
//!             clearance/revolute_jacobian.rs; each force element's closed form or central
//!             differences of the others and of the prismatic clearance joints)
//! ∂f/∂t:      minimal's (the prescribed bodies carry their subtrees: the same ∂g/∂(q, q̇)
//!             times ∂(q, q̇)/∂t; mechanism/formulation/minimal/jacobian.rs); the others
//!             leave it to the integrator's difference in t
//! ∂f/∂y:      the formulation's (Lagrange–Baumgarte:
//!             mechanism/formulation/lagrange_baumgarte/jacobian.rs)
//! ```

use faer::MatMut;

use crate::mechanism::Mechanism;

/// Fills `jac` (n × n) with ∂f/∂y at (t, y); NaN rows when the evaluation fails.
pub(crate) fn jacobian(mech: &Mechanism, t: f64, y: &[f64], jac: MatMut<'_, f64>) {
    let mut sc = mech.scratch();
    if !mech.evaluate(t, y, &mut sc, false) {
        mech.formulation()
            .jacobian(mech.constraints(), &sc, None, jac);
        return;
    }
    let mut fw = mech.force_jac_work();
    mech.forces().jacobian(mech.bodies(), t, &sc, &mut fw);
    mech.formulation()
        .jacobian(mech.constraints(), &sc, Some(&fw.dg), jac);
}

/// ∂f/∂t at (t, y) into `out` when the formulation gives it (minimal: its
/// `time_derivative`, from the forces' closed-form ∂g/∂(q, q̇)); false (nothing written)
/// otherwise. NaN when the evaluation fails.
pub(crate) fn time_derivative(mech: &Mechanism, t: f64, y: &[f64], out: &mut [f64]) -> bool {
    let form = mech.formulation();
    if !form.has_time_derivative() {
        return false;
    }
    let mut sc = mech.scratch();
    if !mech.evaluate(t, y, &mut sc, false) {
        out.iter_mut().for_each(|v| *v = f64::NAN);
        return true;
    }
    let mut fw = mech.force_jac_work();
    mech.forces().jacobian(mech.bodies(), t, &sc, &mut fw);
    form.time_derivative(mech.bodies(), mech.forces(), t, &sc, &fw.dg, out)
}
