//! Analysis of an ODE beyond integrating it: stiffness diagnostics and Lyapunov exponents.
//!
//! ```text
//! stiffness:  J = ∂f/∂y (t, y),  λ_i = eig(J);  RK4 is stable for h ≤ h_max = min_i r(arg λ_i)/|λ_i|
//!             with r(θ) the extent of RK4's stability region along the ray θ (HNW II, §IV.2)
//! lyapunov:   λ_max = lim_{T→∞} (1/T) ln(‖δy(T)‖ / ‖δy(0)‖)  (Benettin et al. 1980)
//! ```
//!
//! Everything here is generic over [`crate::OdeSystem`] and uses only the public solver API
//! ([`crate::solve`], [`crate::Integrator`]), so it works with every method and with systems
//! whose events run hooks.
//!
//! - [`stiffness`]: dominant eigenvalues of the Jacobian, RK4 stability limits (predicted from
//!   the eigenvalues and measured by bisection), stiffness ratio, a verdict on the method
//!   family, and a sampler along a trajectory.
//! - [`lyapunov`]: largest Lyapunov exponent by Benettin's two-trajectory method, and a
//!   stroboscopic (once-per-period Poincaré) map.

pub(crate) mod error;
pub mod lyapunov;
pub(crate) mod spectrum;
pub mod stiffness;

pub use error::AnalysisError;

pub use lyapunov::{
    largest_lyapunov, largest_lyapunov_pair, stroboscopic_map, LyapunovEstimate, LyapunovOptions,
    Stroboscopic,
};
pub use stiffness::{
    analyze, eigenvalues, jacobian_at, measure_rk4_limit, measure_rk4_limit_where,
    rk4_amplification, rk4_is_stable, rk4_ray_limit, sample_solution, sample_states,
    sample_trajectory, summarize, verdict, Eigenvalue, Family, MeasuredLimit, Rk4ProbeOptions,
    StiffnessOptions, StiffnessSummary, Verdict,
};
