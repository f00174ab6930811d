//! How accurately the run's tolerances let T + V be known at one state: the floor under an
//! energy balance (docs/outputs.md, `energy.state_tolerance`).
//!
//! ```text
//! E(y) = T(y) + V(y)                           (Mechanism::outputs: kinetic + potential)
//! wᵢ = atolᵢ + rtol |yᵢ|                        (the weight of component i in the error norm)
//! s(y) = Σᵢ |E(y + wᵢ eᵢ) − E(y − wᵢ eᵢ)| / 2   (first order: Σᵢ |∂E/∂yᵢ| wᵢ)
//! state_tolerance = s(y(t_start)) + s(y(t_end))
//! ```
//!
//! The adaptive methods keep each step's local error below about one weight per component,
//! so the kinetic and potential energies they report are known to about this much, whatever
//! the quadrature: a balance error below it says nothing about the integrals. Central
//! differences (2 n full evaluations per state) take the derivative of every formulation
//! alike (absolute coordinates: ∂T/∂q̇ = M q̇, ∂V/∂q = −Q_conservative; minimal: the same
//! through the joint coordinates).

use lash_model::Mechanism;
use lash_solver::SolverOptions;

/// Above this many states the floor is not computed (its cost, 4 n full evaluations of O(n)
/// each, grows as n²: 1.5 s on a chain of 200 links, 1 200 states): summary.json reports null.
pub(crate) const MAX_STATES: usize = 300;

/// The first-order accuracy of T + V at `t0`/`y0` and `t1`/`y1` under the tolerances of
/// `opts` (module doc), J; None for a fixed-step method (no tolerance), above
/// [`MAX_STATES`], or when an evaluation is not finite.
pub(crate) fn state_tolerance(
    mech: &Mechanism,
    opts: &SolverOptions,
    (t0, y0): (f64, &[f64]),
    (t1, y1): (f64, &[f64]),
) -> Option<f64> {
    if opts.method.is_fixed_step() || y0.len() > MAX_STATES {
        return None;
    }
    let s = at(mech, opts, t0, y0)? + at(mech, opts, t1, y1)?;
    s.is_finite().then_some(s)
}

/// s(y) of the module doc at one state.
fn at(mech: &Mechanism, opts: &SolverOptions, t: f64, y: &[f64]) -> Option<f64> {
    let energy = |y: &[f64]| {
        let o = mech.outputs(t, y);
        o.kinetic_energy + o.potential_energy
    };
    let mut z = y.to_vec();
    let mut sum = 0.0;
    for i in 0..y.len() {
        let w = opts.atol.get(i) + opts.rtol * y[i].abs();
        z[i] = y[i] + w;
        let up = energy(&z);
        z[i] = y[i] - w;
        let down = energy(&z);
        z[i] = y[i];
        let d = 0.5 * (up - down).abs();
        if !d.is_finite() {
            return None;
        }
        sum += d;
    }
    Some(sum)
}
