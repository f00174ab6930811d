//! What both assembly paths share (assembly.rs, assembly/sparse.rs): the tolerances and
//! bounds, the exact initial velocities' rows, the largest residual and the report of what
//! assembly changed.

use crate::mechanism::constraints::{Row, Term, TermKind};
use crate::mechanism::Mechanism;
use crate::projection::{CoordinateChange, ProjectionReport, REPORT_TOL};
use crate::scene::format::JointSpec;
use crate::scene::refs::GROUND;

/// Position tolerance of the assembly (m or rad): below it the positions are assembled, and
/// [`Polish`] then takes them to rounding.
pub(super) const POS_TOL: f64 = 1e-12;
/// Newton steps [`Polish`] takes at most past [`POS_TOL`].
pub(super) const MAX_POLISH: usize = 3;
/// The residual (m or rad) [`Polish`] takes no step below: the rounding of a few operations on
/// coordinates of order 1 (ε = 2.2e-16). A scene whose guesses meet the constraints to this
/// (the catalogue's centred press: 1.4e-17) keeps its state bit for bit.
pub(super) const POLISH_FLOOR: f64 = 1e-15;
/// Velocity tolerance after the projection (m/s or rad/s).
pub(super) const VEL_TOL: f64 = 1e-10;
/// Newton iterations before giving up.
pub(super) const MAX_ITER: usize = 50;
/// Relative singular-value threshold of the rank check.
pub(super) const RANK_TOL: f64 = 1e-9;
/// Largest condition number of the velocity projection that meets exact initial velocities
/// (docs/model.md §1.6).
pub(super) const MAX_PROJECTION_CONDITION: f64 = 1e8;
/// Largest ratio of the kinetic energy the projection adds to the energy the exact initial
/// velocities carry (docs/model.md §1.6): a lever multiplies it by (1 + its arm ratio²), a
/// pinned rod given its centre's speed by 4/3.
pub(super) const MAX_PROJECTION_ENERGY_RATIO: f64 = 100.0;

/// Velocity-only equations: the exact initial velocities the scene asks for (joint
/// `initial_rate`, body `initial_velocity`), each with its JSON path and a description.
pub(super) fn velocity_rows(mech: &Mechanism) -> Vec<(Row, String, String)> {
    let scene = mech.scene();
    let t0 = mech.t_start();
    let mut out = Vec::new();
    for (ji, j) in scene.joints.iter().enumerate() {
        match j {
            JointSpec::Revolute(r) => {
                let Some(v) = r.initial_rate else { continue };
                let mut row = Row::new(ji, "initial rate");
                for (a, c) in [(&r.a, 1.0), (&r.b, -1.0)] {
                    if a.body != GROUND {
                        row.push(Term {
                            body: scene.body_index(&a.body).expect("validated"),
                            kind: TermKind::Angle { c },
                        });
                    }
                }
                out.push((
                    row.with_rate(v, t0),
                    format!("joints[{ji}].initial_rate"),
                    format!("the initial rate {v} rad/s of {j}"),
                ));
            }
            JointSpec::Translational(tr) => {
                let Some(v) = tr.initial_rate else { continue };
                let k = scene.body_index(&tr.body).expect("validated");
                let l = tr.direction[0].hypot(tr.direction[1]);
                let mut row = Row::new(ji, "initial rate");
                row.push(Term {
                    body: k,
                    kind: TermKind::Point {
                        s: scene.bodies[k].points[&tr.point],
                        w: [tr.direction[0] / l, tr.direction[1] / l],
                    },
                });
                out.push((
                    row.with_rate(v, t0),
                    format!("joints[{ji}].initial_rate"),
                    format!("the initial rate {v} m/s of {j}"),
                ));
            }
            _ => {}
        }
    }
    for (k, b) in scene.bodies.iter().enumerate() {
        let Some(iv) = &b.initial_velocity else {
            continue;
        };
        for (name, v, kind) in [
            (
                "vx",
                iv.vx,
                TermKind::Point {
                    s: [0.0; 2],
                    w: [1.0, 0.0],
                },
            ),
            (
                "vy",
                iv.vy,
                TermKind::Point {
                    s: [0.0; 2],
                    w: [0.0, 1.0],
                },
            ),
            ("omega", iv.omega, TermKind::Angle { c: 1.0 }),
        ] {
            let Some(v) = v else { continue };
            let mut row = Row::new(usize::MAX, "initial velocity");
            row.push(Term { body: k, kind });
            out.push((
                row.with_rate(v, t0),
                format!("bodies[{k}].initial_velocity.{name}"),
                format!("the initial velocity {name} = {v} of body '{}'", b.name),
            ));
        }
    }
    out
}

/// The Newton steps past [`POS_TOL`]: the positions on the constraints to rounding, not only
/// to the tolerance.
///
/// ```text
/// after max|Φ_a| ≤ POS_TOL: step again while max|Φ_a| > POLISH_FLOOR and the last step
///                           at least halved it (at most MAX_POLISH steps; the best iterate
///                           is kept)
/// ```
/// Why: a residual left at the tolerance is a different initial state for each formulation.
/// One Newton step from the guess leaves the second-order remainder of the step (3.3e-13 m
/// for the dry press with its journal started 1 µm off centre: the rod's pin 3.3e-13 m off
/// the crank's). Lagrange–Baumgarte integrates that state as it is, the minimal formulation
/// rebuilds the bodies from the joint coordinates, which meets the pin exactly and moves the
/// journal by the residual instead; the dry press's contacts amplify the 3e-13 m to 1e-5 m/s²
/// of slider acceleration within half a crank revolution. Newton converges quadratically, so
/// one more step brings the residual to rounding (1.4e-17 there), where the polish ends; a
/// step that no longer halves the residual (rounding of larger coordinates) ends it too.
#[derive(Debug, Default)]
pub(super) struct Polish {
    steps: usize,
    /// The best iterate so far and its largest residual.
    best: Option<(f64, Vec<f64>)>,
}

impl Polish {
    /// Called with the largest residual `err` (≤ [`POS_TOL`]) of the positions `y[..nq]`:
    /// whether to take another Newton step from `y`. When not, `y` holds the best iterate.
    pub(super) fn another(&mut self, err: f64, y: &mut [f64], nq: usize) -> bool {
        if let Some((best, yb)) = &self.best {
            if !(err <= 0.5 * best) {
                if !(err < *best) {
                    y[..nq].copy_from_slice(&yb[..nq]);
                }
                return false;
            }
        }
        if err <= POLISH_FLOOR || self.steps == MAX_POLISH {
            return false;
        }
        self.best = Some((err, y[..nq].to_vec()));
        self.steps += 1;
        true
    }
}

/// The report of what assembly changed: `given` and `assembled` states (q, q̇).
pub(super) fn report(mech: &Mechanism, given: &[f64], y: &[f64]) -> ProjectionReport {
    let nq = mech.nq();
    let mut r = ProjectionReport::default();
    const NAMES: [&str; 6] = ["x", "y", "theta", "vx", "vy", "omega"];
    for (i, &k) in mech.bodies().int_bodies.iter().enumerate() {
        let b = &mech.body_info()[k];
        let m = [b.mass, b.mass, b.inertia];
        for c in 0..3 {
            let (vg, va) = (given[nq + 3 * i + c], y[nq + 3 * i + c]);
            r.kinetic_energy_given += 0.5 * m[c] * vg * vg;
            r.kinetic_energy_assembled += 0.5 * m[c] * va * va;
        }
        for (c, name) in NAMES.iter().enumerate() {
            let j = if c < 3 { 3 * i + c } else { nq + 3 * i + c - 3 };
            let change = y[j] - given[j];
            if c < 3 {
                r.max_position_change = r.max_position_change.max(change.abs());
            } else {
                r.max_velocity_change = r.max_velocity_change.max(change.abs());
            }
            if change.abs() > REPORT_TOL * given[j].abs().max(1.0) {
                r.changes.push(CoordinateChange {
                    body: b.name.clone(),
                    coordinate: name,
                    given: given[j],
                    assembled: y[j],
                    change,
                });
            }
        }
    }
    // Positions first, then velocities (stable within each).
    r.changes
        .sort_by_key(|c| matches!(c.coordinate, "vx" | "vy" | "omega"));
    r
}

/// The row of largest |value| and that value (the first NaN, if any).
pub(super) fn worst(phi: &[f64]) -> (usize, f64) {
    phi.iter().enumerate().fold((0, 0.0), |(bi, bv), (i, v)| {
        if !(v.abs() <= bv) {
            (i, v.abs())
        } else {
            (bi, bv)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The polish steps while a step at least halves the residual, ends on a step that does
    /// not (keeping the better of the last two iterates), at POLISH_FLOOR or after
    /// MAX_POLISH steps; velocities (beyond nq) are never touched.
    #[test]
    fn the_polish_keeps_the_best_iterate() {
        // Halved, then worse: back to the best positions.
        let mut p = Polish::default();
        let mut y = [1.0, 2.0, 9.0];
        assert!(p.another(3e-13, &mut y, 2));
        y[0] = 1.5;
        assert!(p.another(2e-14, &mut y, 2));
        y = [1.75, 2.5, 8.0];
        assert!(!p.another(4e-14, &mut y, 2));
        assert_eq!(y, [1.5, 2.0, 8.0]);
        // Better but not halved: the last iterate is kept.
        let mut p = Polish::default();
        let mut y = [1.0];
        assert!(p.another(1e-13, &mut y, 1));
        y[0] = 2.0;
        assert!(!p.another(0.8e-13, &mut y, 1));
        assert_eq!(y, [2.0]);
        // A NaN residual after a step: back to the best.
        y[0] = 3.0;
        let mut p = Polish::default();
        assert!(p.another(1e-13, &mut y, 1));
        y[0] = 4.0;
        assert!(!p.another(f64::NAN, &mut y, 1));
        assert_eq!(y, [3.0]);
        // A residual at rounding takes no step; at most MAX_POLISH steps.
        assert!(!Polish::default().another(0.0, &mut [1.0], 1));
        assert!(!Polish::default().another(POLISH_FLOOR, &mut [1.0], 1));
        assert!(Polish::default().another(2.0 * POLISH_FLOOR, &mut [1.0], 1));
        let (mut p, mut e, mut n) = (Polish::default(), 1e-12, 0);
        while p.another(e, &mut [0.0], 1) {
            n += 1;
            e *= 0.4;
        }
        assert_eq!(n, MAX_POLISH);
    }
}
