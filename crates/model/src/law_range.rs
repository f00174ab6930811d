//! Where the clearance joints' laws hold, checked along a run (docs/model.md §3.5).
//!
//! ```text
//! revolute clearance joint   depth δ = |e| − c
//!   out of range (fatal)     δ ≥ R_J          the journal centre reaches the bearing surface:
//!                                             the line of centres, the contact points and the
//!                                             Hertz law of §3 (δ ≪ the radii) mean nothing
//!   beyond the clearance     δ > c            counted: a penetration deeper than the gap
//!                                             itself, far outside Hertz's small-strain range
//!   film beyond its range    ε ≥ 1 − η        counted (lubricated joints): the film law is no
//!                                             longer evaluated at the true ε (η = the guard
//!                                             laws::UNCAPPED_GUARD; a capped film froze
//!                                             earlier, at ε_cap, by the scene's choice)
//! prismatic clearance joint  depth = max_i δ_i over the four corners
//!   out of range (fatal)     depth ≥ w/2      a corner half the block's width w into a face:
//!                                             the corners' contact geometry of §11 fails
//!   beyond the clearance     depth > c        counted, as for the revolute joint
//! ```
//! The fatal limits are those the scene's initial state is held to (clearance::revolute,
//! clearance::prismatic); a NaN depth is out of range. The checks read positions only (the
//! kinematics, no force law, no constraint solve).

use serde::{Deserialize, Serialize};

use crate::clearance::laws::UNCAPPED_GUARD;
use crate::mechanism::Mechanism;

/// What a run's clearance joint did against the ranges of its laws (module doc), over every
/// state a [`LawRangeMonitor`] saw.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LawRangeRecord {
    /// The joint's name.
    pub joint: String,
    /// `revolute_clearance` or `prismatic_clearance`.
    pub kind: String,
    /// The deepest penetration seen (δ, or a corner's δ_i), m; negative: never in contact.
    pub depth_max: f64,
    /// The depth at which the run stops (R_J, or half the block's width), m.
    pub depth_limit: f64,
    /// The radial (or guide) clearance c, m.
    pub clearance: f64,
    /// How many times the depth went beyond the clearance (entries into δ > c).
    pub beyond_clearance: usize,
    /// How many times the film went beyond its law's range (entries into ε ≥ 1 − η);
    /// `None` for a dry joint.
    pub film_beyond_range: Option<usize>,
}

/// A state outside the range of a law: which joint, the depth and the limit.
#[derive(Clone, Debug, PartialEq)]
pub struct LawRangeViolation {
    /// The joint's name.
    pub joint: String,
    /// The depth reached, m.
    pub depth: f64,
    /// The limit, m.
    pub limit: f64,
    /// What the limit is and why, one line.
    pub reason: String,
}

impl std::fmt::Display for LawRangeViolation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "clearance joint '{}': penetration {:e} m reached {}",
            self.joint, self.depth, self.reason
        )
    }
}

/// Follows a run's states (one call per accepted step) and keeps a [`LawRangeRecord`] per
/// clearance joint: revolute joints first, then prismatic ones, each in scene order.
#[derive(Clone, Debug)]
pub struct LawRangeMonitor {
    records: Vec<LawRangeRecord>,
    beyond: Vec<bool>,
    film_beyond: Vec<bool>,
}

impl LawRangeMonitor {
    /// A monitor of `mech`'s clearance joints, nothing seen yet.
    pub fn new(mech: &Mechanism) -> LawRangeMonitor {
        let f = mech.forces();
        let mut records = Vec::new();
        for c in &f.revolute {
            records.push(LawRangeRecord {
                joint: c.name.clone(),
                kind: "revolute_clearance".into(),
                depth_max: f64::NEG_INFINITY,
                depth_limit: c.rj,
                clearance: c.c,
                beyond_clearance: 0,
                film_beyond_range: c.film.is_some().then_some(0),
            });
        }
        for p in &f.prismatic {
            let (a, b) = (p.corners[0].0, p.corners[3].0);
            records.push(LawRangeRecord {
                joint: p.name.clone(),
                kind: "prismatic_clearance".into(),
                depth_max: f64::NEG_INFINITY,
                depth_limit: 0.5 * (a[0] - b[0]).hypot(a[1] - b[1]),
                clearance: p.clearance,
                beyond_clearance: 0,
                film_beyond_range: None,
            });
        }
        let n = records.len();
        LawRangeMonitor {
            records,
            beyond: vec![false; n],
            film_beyond: vec![false; n],
        }
    }

    /// Whether there is anything to follow (a clearance joint).
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// Checks the state (t, y) of `mech` (the mechanism this monitor was made for): counts
    /// the excursions, and returns the first joint whose depth reached its fatal limit
    /// (module doc).
    pub fn observe(
        &mut self,
        mech: &Mechanism,
        t: f64,
        y: &[f64],
    ) -> Result<(), LawRangeViolation> {
        if self.records.is_empty() {
            return Ok(());
        }
        let mut sc = mech.scratch();
        mech.kinematics(t, y, &mut sc);
        let kin = sc.kin();
        let f = mech.forces();
        let nr = f.revolute.len();
        let mut depth_eps = Vec::with_capacity(self.records.len());
        for c in &f.revolute {
            let st = c.state(&kin);
            depth_eps.push((st.delta, st.eps));
        }
        for p in &f.prismatic {
            let d = (0..4)
                .map(|i| p.corner_gap(i, &kin).0)
                .fold(
                    f64::NEG_INFINITY,
                    |a, b| if b.is_nan() { b } else { a.max(b) },
                );
            depth_eps.push((d, 0.0));
        }
        drop(sc);
        for (k, (depth, eps)) in depth_eps.into_iter().enumerate() {
            let r = &mut self.records[k];
            if depth.is_nan() || depth > r.depth_max {
                r.depth_max = depth;
            }
            let beyond = depth > r.clearance;
            if beyond && !self.beyond[k] {
                r.beyond_clearance += 1;
            }
            self.beyond[k] = beyond;
            if let Some(n) = r.film_beyond_range.as_mut() {
                let out = eps >= 1.0 - UNCAPPED_GUARD;
                if out && !self.film_beyond[k] {
                    *n += 1;
                }
                self.film_beyond[k] = out;
            }
            if !(depth < r.depth_limit) {
                let reason = if k < nr {
                    format!(
                        "the journal radius R_J = {:e} m, where the journal's centre reaches \
                         the bearing surface and the contact law (Hertz, δ ≪ R_J) does not hold",
                        r.depth_limit
                    )
                } else {
                    format!(
                        "half the block's width, {:e} m, where the corners' contact geometry \
                         does not hold",
                        r.depth_limit
                    )
                };
                return Err(LawRangeViolation {
                    joint: r.joint.clone(),
                    depth,
                    limit: r.depth_limit,
                    reason,
                });
            }
        }
        Ok(())
    }

    /// The records so far (module doc), revolute joints first.
    pub fn records(&self) -> &[LawRangeRecord] {
        &self.records
    }
}

impl Mechanism {
    /// Whether the acceleration solve succeeds at (t, y): false at a singular configuration,
    /// where the constraint Jacobian Φ_q has lost rank and the accelerations and Lagrange
    /// multipliers have no unique value (docs/model.md §1). A run that meets a non-finite
    /// output at a finite state asks this to tell a singular configuration from a bug.
    pub fn acceleration_solvable(&self, t: f64, y: &[f64]) -> bool {
        let mut sc = self.scratch().clone();
        self.evaluate(t, y, &mut sc, true)
    }
}
