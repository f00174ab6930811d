//! Parameter sweeps: a grid of points over a base case, run in parallel, resumable, shardable,
//! and merged into one table.
//!
//! ```text
//! SWEEP.json = { "case": PATH | "testset:NAME",            (PATH relative to the sweep file)
//!                "speed_rpm": [..], "clearance": [..], "viscosity": [..], "stiffness": [..],
//!                "method": [..], "rtol": [..] (alias "tolerance"), "step": [..],
//!                "controller": [..],
//!                "set": {PATH: [..], …},                   (every list optional, none empty;
//!                                                           PATH any scene field, module set)
//!                "sample": {count, seed, method, vary: {PATH: {"uniform": [lo, hi]} | …}} }
//!                                                          (module sample)
//! grid   = speed × clearance × viscosity × stiffness × set (paths in sorted order)
//!          × samples (in draw order) × solver choices, in that order, where
//!          solver choices = for each method: fixed-step → step list;
//!                                             diffsol   → rtol list;
//!                                             ours      → rtol × controller
//! id     = first 16 hex digits of sha256(canonical JSON of the point's parameters)
//!          (keys sorted, absent parameters left out, the base case by name and file sha256)
//! shard I/N = the points with index mod N = I
//! OUT/points.json      the whole grid (index, id, parameters), so merge can name what is missing
//! OUT/id/claim.json    created exclusively by the process that runs the point, removed when it
//!                      ends (module claim): concurrent processes never run one point twice
//! OUT/id/result.json   written atomically when the point finishes (ok or solver failure);
//!                      its presence means "done", so a rerun skips the point
//! stop requested       (SIGINT, SIGTERM: lash_solver::interrupt) no new point starts; the
//!                      point in flight is abandoned and its files removed; finished ones stay
//! merge(DIR...) = the result.json files found → one table (CSV + markdown); the points of the
//!                 manifests without a result are unfinished, unreadable results corrupt
//! ```
//!
//! Source: docs/outputs.md ("Sweeps").

pub(crate) mod merge;
pub(crate) mod runner;
pub(crate) mod sample;
pub(crate) mod set;
pub(crate) mod spec;

#[cfg(test)]
mod sample_tests;
#[cfg(test)]
mod tests;
