//! `lash stiffness CASE`: the Jacobian's dominant eigenvalues along a trajectory, the RK4 step
//! limit they predict, the limit measured by bisection, and which method family should win.
//!
//! ```text
//! reference run     the case's solver options (default bdf rtol 1e-8; test problems rodas5p),
//!                   one Integrator; at each of N equally spaced times t_k (both ends) the dense
//!                   output y_k is analysed at once (so a contact law's stored impact velocity is
//!                   the one in force): J = ∂f/∂y (t_k, y_k), λ_i = eig(J) (faer)
//! per sample        ρ = max|λ_i|,  h_k = min_i r(arg λ_i)/|λ_i| over Re λ_i ≤ 0 (RK4's ray
//!                   limit: r = 2.785 on the negative real axis, 2√2 on the imaginary axis),
//!                   S = max|Re λ| / min|Re λ| over decaying modes, growing modes Re λ > 0
//! predicted limit   h_pred = min_k h_k (and where: t, crank angle, the limiting λ); also the
//!                   5th percentile of h_k (the limit on 95 % of the run: a single deep impact
//!                   between flights sets the minimum but not the percentile)
//! measured limit    fixed-step RK4 over the whole run, without event location, bisection on
//!                   ln h until h_unstable/h_stable ≤ 1 + 1e-4; stable(h) ⇔ no non-finite state,
//!                   RK4's own stability check (the case's `rk4_instability_steps`, the one
//!                   `lash run` applies) does not stop the run, and max_k ‖y_k‖∞ ≤ 10 · M_ref (M_ref: the run at the bracket's lower end,
//!                   checked against h/2), and for a mechanism ‖Φ(q_k, t_k)‖₂ ≤ c/100 at every
//!                   accepted step ([`PHI_MAX_PER_LENGTH`]); bracket [h_pred/2, 2 h_pred]
//!                   widened by ×4 until it brackets
//!                   (lash_solver::analysis::stiffness::measure_rk4_limit_where)
//! accuracy step     h_acc = median accepted step of the reference run (an implicit method's
//!                   steps are set by accuracy alone, not by stability)
//! verdict           q = h_acc / h_stab (h_stab = measured h_stable, else h_pred):
//!                   q ≤ 1 explicit · 1 < q < 10 either · q ≥ 10 implicit
//! files             stiffness.csv, stiffness.{svg,png}, stiffness.md, stiffness.json (last)
//! ```
//!
//! The eigenvalue analysis is local (the linearisation at one point); the measured limit
//! answers the global question over the run. Sources: E. Hairer, G. Wanner, *Solving Ordinary
//! Differential Equations II*, 2nd ed., Springer 1996, §IV.2 (RK4's stability domain) and
//! §IV.1 (stiffness); J. D. Lambert, *Numerical Methods for Ordinary Differential Systems*,
//! Wiley 1991, ch. 6 (stiffness ratio).

pub(crate) mod analyse;
pub(crate) mod report;
pub(crate) mod sample;

#[cfg(test)]
mod tests;
