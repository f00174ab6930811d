//! `lash study paper`: the paper's whole §4, its figures, and its claims checked against runs.
//!
//! ```text
//! cases        dry and lubricated at 120, 150, 180, 200 rpm (c = 0.1 mm) and at 150 rpm with
//!              c = 0.1, 0.2, 0.3, 0.5 mm; the ideal mechanism at the four speeds (18 cases)
//! realisation  k = 0..N−1 (N = 8): the case with the crank's initial angle θ₀ = k·Δθ,
//!              Δθ = 1e-6 rad (k = 0 is the paper's case; the ideal cases run once)
//! run          BDF, rtol 1e-10, atol 1e-12, 2 event samples per step, no h_max; two
//!              revolutions through the shared runner (simulate::simulate, no energy
//!              accounting); samples on metrics::grid of each revolution (2 × 2001 points:
//!              the run's metrics window and, as extra output times, the revolution before)
//! reference    every realisation again at rtol 1e-12, atol 1e-14 (convergence check), and
//! loose        at rtol 1e-8, atol 1e-10 (to show what a looser tolerance changes)
//! statistics   metrics of the last revolution (docs/outputs.md, "`metrics`") + [`Deviations`]
//! claims       claims::evaluate on the ensemble means (and per realisation)
//! files        DIR/figures/figNN[a-d].{svg,png} → DIR/report.md → DIR/study.json (last)
//! resuming     every finished run is kept in DIR/cache/ under the hash of its inputs
//!              (crate::store::cache); a rerun reuses it, so an interrupted study (SIGINT, SIGTERM:
//!              the runs in flight are abandoned) goes on where it stopped
//! ```
//!
//! The dry cases are chaotic (docs/model.md §9), which is why each case is an ensemble and the
//! claims compare statistics, never pointwise values. The realisations differ by a crank phase
//! of micro-radians: physically nothing (r·Δθ = 15 nm per step), but more than the integration
//! error at either setting (rtol·|q| ≈ 4e-11 m at rtol 1e-10), so that they are different
//! trajectories rather than copies of one numerical trajectory, and a smooth change of every
//! case alike (the journal's initial eccentricity is not perturbed: e = 0 is where the film's
//! attitude angle is undefined, docs/model.md §2, and nanometre offsets there change the
//! lubricated start discontinuously). Nothing but the cache of finished runs is written if any
//! run fails.
//!
//! Source: the paper's §4 and Figures 5–16; docs/model.md §5, §6, §9; docs/outputs.md (`metrics`).

pub(crate) mod claims;
pub(crate) mod figures;
pub(crate) mod markdown;
pub(crate) mod plan;
pub(crate) mod result;
pub(crate) mod runner;
pub(crate) mod stats;

#[cfg(test)]
mod tests;
