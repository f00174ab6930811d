//! The constraint equations of the ideal joints and the drivers that prescribe no body: each a
//! scalar Φ = konst + rate·t + Σ terms, with its value, rate, γ and Jacobian blocks.
//!
//! ```text
//! revolute       Φ = r_a^P − r_b^P              (rows "x", "y")
//! translational  Φ = (n·(r^P − o), φ − φ₀)      (rows "across the line", "rotation")
//! driver         Φ = φ − θ₀ − ω t               (row "angle")
//! Φ̇ = Φ_q q̇ + Φ_t,   Φ̈ = Φ_q q̈ − γ   (prescribed accelerations folded into γ)
//! ```
//! Every formulation uses these equations (docs/model.md §1.2); how it enforces them is its own
//! (mechanism/formulation).

use crate::mechanism::bodies::{Bodies, BodyInfo, Owner};
use crate::mechanism::scratch::Scratch;
use crate::planar::{dot, perp, rot};
use crate::scene::error::SceneError;
use crate::scene::format::{JointSpec, Scene};

pub(crate) use crate::mechanism::row::{Row, RowEval, Term, TermKind};

/// Value Φ, rate Φ̇, γ (Φ̈ = Φ_q q̈ − γ, prescribed accelerations folded in) and the Jacobian
/// block of each term of one constraint row (after the kinematics of `sc`).
#[inline]
pub(crate) fn eval_row(row: &Row, info: &[BodyInfo], t: f64, sc: &Scratch) -> RowEval {
    let mut out = RowEval {
        phi: row.konst + row.rate * t,
        phid: row.rate,
        gamma: 0.0,
        jrows: [[0.0; 3]; 2],
    };
    for (ti, term) in row.terms[..row.n_terms].iter().enumerate() {
        let k = term.body;
        let [x, y, _] = sc.pose[k];
        let [vx, vy, w] = sc.vel[k];
        let owner = info[k].owner;
        out.jrows[ti] = match term.kind {
            TermKind::Point { s, w: wv } => {
                let a = rot(sc.cs[k], s);
                let b = perp(a);
                out.phi += wv[0] * (x + a[0]) + wv[1] * (y + a[1]);
                let jphi = dot(wv, b);
                out.phid += wv[0] * vx + wv[1] * vy + jphi * w;
                match owner {
                    Owner::Int(_) => out.gamma += w * w * dot(wv, a),
                    Owner::Pres(_) => {
                        let [ax, ay, al] = sc.acc[k];
                        out.gamma -= wv[0] * (ax + al * b[0] - w * w * a[0])
                            + wv[1] * (ay + al * b[1] - w * w * a[1]);
                    }
                }
                [wv[0], wv[1], jphi]
            }
            TermKind::Angle { c } => {
                out.phi += c * sc.pose[k][2];
                out.phid += c * w;
                if let Owner::Pres(_) = owner {
                    out.gamma -= c * sc.acc[k][2];
                }
                [0.0, 0.0, c]
            }
        };
    }
    out
}

/// `equation 'x' of revolute joint 'pin'`, for messages.
pub(crate) fn describe(row: &Row, scene: &Scene) -> String {
    format!("equation '{}' of {}", row.label, scene.joints[row.joint])
}

/// The constraint equations of a mechanism, and the integrated body of each of their terms.
#[derive(Clone, Debug, Default)]
pub(crate) struct Constraints {
    pub rows: Vec<Row>,
    /// Integrated body index of each term of each row (None: a prescribed body).
    pub row_int: Vec<[Option<usize>; 2]>,
}

impl Constraints {
    /// The constraint forces −Σ J_r,kᵀ λ_r on every body, added to `cf` in row order, and
    /// the torques −λ of the driver rows: (joint index, τ), from the term Jacobians and the
    /// multipliers of an evaluation (every formulation's `reactions`).
    pub(crate) fn reactions(
        &self,
        term_jac: &[[[f64; 3]; 2]],
        lam: &[f64],
        cf: &mut [[f64; 3]],
        torques: &mut Vec<(usize, f64)>,
    ) {
        for (r, row) in self.rows.iter().enumerate() {
            for (ti, term) in row.terms[..row.n_terms].iter().enumerate() {
                let j = term_jac[r][ti];
                for c in 0..3 {
                    cf[term.body][c] -= j[c] * lam[r];
                }
            }
            if row.driver {
                torques.push((row.joint, -lam[r]));
            }
        }
    }

    /// Every point term on integrated body `body` and the row it belongs to, with what the
    /// closed-form Jacobians of both formulations need of it: `f(a, w · A s, w · b, φ̇)` for
    /// row a (b = ∂(A s)/∂φ = perp(A s), φ̇ the body's angular velocity in `sc`). A point term
    /// contributes ∂Φ_q[a, φ]/∂φ = −w · A s, and its rates to γ and Φ̇ follow from the same
    /// three numbers (lagrange_baumgarte/jacobian.rs, augmented_lagrangian/jacobian.rs).
    pub(crate) fn for_point_terms_on(
        &self,
        sc: &Scratch,
        body: usize,
        f: impl FnMut(usize, f64, f64, f64),
    ) {
        self.for_point_terms_in(0..self.rows.len(), sc, body, f);
    }

    /// [`Constraints::for_point_terms_on`] over the rows `rows` only (increasing; the rows that
    /// act on the body, for a cost independent of the number of rows).
    pub(crate) fn for_point_terms_in(
        &self,
        rows: impl IntoIterator<Item = usize>,
        sc: &Scratch,
        body: usize,
        mut f: impl FnMut(usize, f64, f64, f64),
    ) {
        for a in rows {
            let (row, ints) = (&self.rows[a], &self.row_int[a]);
            for (ti, term) in row.terms[..row.n_terms].iter().enumerate() {
                if ints[ti] != Some(body) {
                    continue;
                }
                if let TermKind::Point { s, w: wv } = term.kind {
                    let av = rot(sc.cs[term.body], s);
                    let bv = perp(av);
                    let wa = wv[0] * av[0] + wv[1] * av[1];
                    let wb = wv[0] * bv[0] + wv[1] * bv[1];
                    f(a, wa, wb, sc.vel[term.body][2]);
                }
            }
        }
    }

    /// Build phase 2: the equations of every joint the prescriptions did not consume, in joint
    /// order. A joint acting only on the ground and prescribed bodies is an error.
    pub(crate) fn build(scene: &Scene, bodies: &Bodies) -> Result<Constraints, SceneError> {
        let mut rows = Vec::new();
        for (ji, joint) in scene.joints.iter().enumerate() {
            if bodies.used[ji] {
                continue;
            }
            let first = rows.len();
            joint_rows(scene, ji, joint, &mut rows);
            // A joint acting only on the ground and prescribed bodies constrains nothing that
            // moves freely: it repeats or contradicts the prescription.
            let only_prescribed = rows[first..].iter().all(|r| {
                r.terms[..r.n_terms]
                    .iter()
                    .all(|t| matches!(bodies.info[t.body].owner, Owner::Pres(_)))
            });
            if rows.len() > first && only_prescribed {
                return Err(SceneError::Redundant {
                    path: format!("joints[{ji}]"),
                    reason: format!(
                        "{joint} acts only on the ground and on bodies whose motion is already \
                         prescribed by drivers and pins"
                    ),
                });
            }
        }
        let row_int = rows
            .iter()
            .map(|row| {
                let mut o = [None; 2];
                for (ti, term) in row.terms[..row.n_terms].iter().enumerate() {
                    if let Owner::Int(i) = bodies.info[term.body].owner {
                        o[ti] = Some(i);
                    }
                }
                o
            })
            .collect();
        Ok(Constraints { rows, row_int })
    }

    /// Number of equations.
    pub(crate) fn len(&self) -> usize {
        self.rows.len()
    }
}

/// The equations of joint `ji` (none for a clearance joint: it is a force).
fn joint_rows(scene: &Scene, ji: usize, joint: &JointSpec, rows: &mut Vec<Row>) {
    match joint {
        JointSpec::Revolute(r) => {
            for (axis, label) in [(0usize, "x"), (1, "y")] {
                let mut w = [0.0; 2];
                w[axis] = 1.0;
                let mut row = Row::new(ji, label);
                row.add_attachment(scene, &r.a, w);
                row.add_attachment(scene, &r.b, [-w[0], -w[1]]);
                rows.push(row);
            }
        }
        JointSpec::Translational(t) => {
            let k = scene.body_index(&t.body).expect("validated");
            let s = scene.bodies[k].points[&t.point];
            let len = t.direction[0].hypot(t.direction[1]);
            let u = [t.direction[0] / len, t.direction[1] / len];
            let n = perp(u);
            let mut r1 = Row::new(ji, "across the line");
            r1.push(Term {
                body: k,
                kind: TermKind::Point { s, w: n },
            });
            r1.konst = -dot(n, t.origin);
            rows.push(r1);
            let mut r2 = Row::new(ji, "rotation");
            r2.push(Term {
                body: k,
                kind: TermKind::Angle { c: 1.0 },
            });
            r2.konst = -t.angle.unwrap_or(scene.bodies[k].angle);
            rows.push(r2);
        }
        JointSpec::Driver(d) => {
            let k = scene.body_index(&d.body).expect("validated");
            let mut row = Row::new(ji, "angle");
            row.push(Term {
                body: k,
                kind: TermKind::Angle { c: 1.0 },
            });
            row.konst = -d.theta0;
            row.rate = -d.omega_rad_s();
            row.driver = true;
            rows.push(row);
        }
        JointSpec::Clearance(_) | JointSpec::PrismaticClearance(_) => {}
    }
}
