//! What both assembly paths share (assembly.rs, assembly/sparse.rs): the tolerances and
//! bounds, the exact initial velocities' rows, the largest residual and the report of what
//! assembly changed.

use crate::mechanism::constraints::{Row, Term, TermKind};
use crate::mechanism::Mechanism;
use crate::projection::{CoordinateChange, ProjectionReport, REPORT_TOL};
use crate::scene::format::JointSpec;
use crate::scene::refs::GROUND;

/// Position tolerance of the assembly (m or rad).
pub(super) const POS_TOL: f64 = 1e-12;
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
