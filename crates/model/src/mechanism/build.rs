//! Building a mechanism from a validated scene.

use std::cell::RefCell;

use crate::clearance::prismatic::{Prismatic, PrismaticEval};
use crate::clearance::revolute::{build_clearance, ClrEval};
use crate::elements::ElementEval;
use crate::mechanism::bodies::{BodyInfo, Owner, Prescription};
use crate::mechanism::constraints::{point_of, Row, Term, TermKind};
use crate::mechanism::events::event_list;
use crate::mechanism::{Mechanism, SchurTerm, Scratch};
use crate::outputs::Roles;
use crate::planar::{dot, perp};
use crate::scene::{JointSpec, Scene, SceneError, GROUND};

impl Mechanism {
    /// Validates the scene, finds the prescribed bodies, builds the constraint equations,
    /// checks their rank and assembles the initial state (Newton on positions, then the
    /// velocity constraints; clearance joints held at their initial eccentricity, ė = 0), then
    /// evaluates the equations of motion there once: a right-hand side or Jacobian that is not
    /// finite, or a KKT system singular in f64, is a [`SceneError::Dynamics`] naming the body
    /// or joint (docs/scene-format.md, "Initial check").
    pub fn from_scene(scene: &Scene) -> Result<Mechanism, SceneError> {
        scene.validate()?;
        let nb = scene.bodies.len();
        // Drivers and ground/prescribed pins: which bodies are prescribed.
        let mut owner: Vec<Option<Owner>> = vec![None; nb];
        let mut pres: Vec<Prescription> = Vec::new();
        let mut used = vec![false; scene.joints.len()];
        loop {
            let mut changed = false;
            for (dj, joint) in scene.joints.iter().enumerate() {
                let JointSpec::Driver(d) = joint else {
                    continue;
                };
                if used[dj] {
                    continue;
                }
                let k = scene.body_index(&d.body).expect("validated");
                if owner[k].is_some() {
                    continue;
                }
                // A revolute joint from k to the ground or to a prescribed body.
                let found = scene.joints.iter().enumerate().find_map(|(pj, pjoint)| {
                    let JointSpec::Revolute(r) = pjoint else {
                        return None;
                    };
                    if used[pj] {
                        return None;
                    }
                    let (own, other) = if r.a.body == d.body {
                        (&r.a, &r.b)
                    } else if r.b.body == d.body {
                        (&r.b, &r.a)
                    } else {
                        return None;
                    };
                    let s_own = point_of(scene, own);
                    if other.body == GROUND {
                        Some((pj, s_own, None, other.at.expect("validated")))
                    } else {
                        let ko = scene.body_index(&other.body).expect("validated");
                        match owner[ko] {
                            Some(Owner::Pres(_)) => {
                                Some((pj, s_own, Some((ko, point_of(scene, other))), [0.0; 2]))
                            }
                            _ => None,
                        }
                    }
                });
                if let Some((pj, s_own, parent, ground_at)) = found {
                    used[dj] = true;
                    used[pj] = true;
                    owner[k] = Some(Owner::Pres(pres.len()));
                    pres.push(Prescription {
                        body: k,
                        theta0: d.theta0,
                        omega: d.omega_rad_s(),
                        s_own,
                        parent,
                        ground_at,
                        driver_joint: dj,
                    });
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        let mut int_bodies = Vec::new();
        for k in 0..nb {
            if owner[k].is_none() {
                owner[k] = Some(Owner::Int(int_bodies.len()));
                int_bodies.push(k);
            }
        }
        let bodies: Vec<BodyInfo> = scene
            .bodies
            .iter()
            .zip(&owner)
            .map(|(b, o)| BodyInfo {
                name: b.name.clone(),
                mass: b.mass,
                inertia: b.inertia,
                points: b.points.clone(),
                owner: o.expect("assigned"),
            })
            .collect();

        // Constraint equations of the remaining joints.
        let mut rows = Vec::new();
        let mut clr = Vec::new();
        let mut prismatic = Vec::new();
        for (ji, joint) in scene.joints.iter().enumerate() {
            if used[ji] {
                continue;
            }
            let first = rows.len();
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
                    rows.push(row);
                }
                JointSpec::Clearance(c) => {
                    clr.push(build_clearance(scene, ji, c));
                }
                JointSpec::PrismaticClearance(c) => {
                    prismatic.push(Prismatic::new(scene, ji, c));
                }
            }
            // A joint acting only on the ground and prescribed bodies constrains nothing that
            // moves freely: it repeats or contradicts the prescription.
            let only_prescribed = rows[first..].iter().all(|r| {
                r.terms[..r.n_terms]
                    .iter()
                    .all(|t| matches!(bodies[t.body].owner, Owner::Pres(_)))
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

        let events = event_list(&clr, prismatic.len(), scene.kink_events);
        // Defaults that need the assembled state (a spring's free length) are set after the
        // assembly below.
        let elements = crate::elements::compile(scene, &|_| f64::NAN);
        let mut minv = Vec::with_capacity(3 * int_bodies.len());
        for &k in &int_bodies {
            let b = &scene.bodies[k];
            minv.extend_from_slice(&[1.0 / b.mass, 1.0 / b.mass, 1.0 / b.inertia]);
        }
        let gravity = if scene.gravity != [0.0, 0.0] {
            Some(scene.gravity)
        } else {
            None
        };
        let nq = 3 * int_bodies.len();
        let m = rows.len();
        let scratch = Scratch {
            pose: vec![[0.0; 3]; nb],
            vel: vec![[0.0; 3]; nb],
            acc: vec![[0.0; 3]; nb],
            cs: vec![[1.0, 0.0]; nb],
            g: vec![0.0; nq],
            gb: vec![[0.0; 3]; nb],
            jac: vec![0.0; m * nq],
            phi: vec![0.0; m],
            phid: vec![0.0; m],
            rc: vec![0.0; m],
            smat: vec![0.0; m * m],
            lam: vec![0.0; m],
            qdd: vec![0.0; nq],
            clr: vec![ClrEval::default(); clr.len()],
            el: vec![ElementEval::default(); elements.len()],
            pr: vec![PrismaticEval::default(); prismatic.len()],
            term_jac: vec![[[0.0; 3]; 2]; m],
        };
        let roles = Roles::resolve(scene, &clr);
        let row_int: Vec<[Option<usize>; 2]> = rows
            .iter()
            .map(|row| {
                let mut o = [None; 2];
                for (ti, term) in row.terms[..row.n_terms].iter().enumerate() {
                    if let Owner::Int(i) = bodies[term.body].owner {
                        o[ti] = Some(i);
                    }
                }
                o
            })
            .collect();
        let mut schur = Vec::new();
        for a in 0..rows.len() {
            for b in 0..=a {
                for ta in 0..2 {
                    for tb in 0..2 {
                        if let (Some(i), Some(j)) = (row_int[a][ta], row_int[b][tb]) {
                            if i == j {
                                schur.push(SchurTerm { a, b, ta, tb, i });
                            }
                        }
                    }
                }
            }
        }
        // Diagonal blocks of S: connected components of the rows under "share a body".
        let mut comp: Vec<usize> = (0..rows.len()).collect();
        fn root(c: &mut [usize], mut a: usize) -> usize {
            while c[a] != a {
                c[a] = c[c[a]];
                a = c[a];
            }
            a
        }
        for p in &schur {
            let (ra, rb) = (root(&mut comp, p.a), root(&mut comp, p.b));
            comp[ra.max(rb)] = ra.min(rb);
        }
        let mut kkt_blocks: Vec<Vec<usize>> = Vec::new();
        let mut block_of = vec![usize::MAX; rows.len()];
        for r in 0..rows.len() {
            let c = root(&mut comp, r);
            if block_of[c] == usize::MAX {
                block_of[c] = kkt_blocks.len();
                kkt_blocks.push(Vec::new());
            }
            kkt_blocks[block_of[c]].push(r);
        }
        let mut mech = Mechanism {
            scene: scene.clone(),
            bodies,
            int_bodies,
            pres,
            rows,
            row_int,
            schur,
            kkt_blocks,
            clr,
            elements,
            prismatic,
            projection: Default::default(),
            events,
            minv,
            gravity,
            alpha: scene.baumgarte.alpha,
            beta: scene.baumgarte.beta,
            t_start: scene.t_start,
            t_end: 0.0,
            y0: Vec::new(),
            roles,
            scratch: RefCell::new(scratch),
            jac_work: RefCell::default(),
        };
        mech.t_end = match (scene.t_end, scene.revolutions) {
            (Some(te), _) => te,
            (None, Some(n)) => {
                let w = mech
                    .crank_speed()
                    .expect("validated: revolutions need a crank driver");
                scene.t_start + n * 2.0 * std::f64::consts::PI / w.abs()
            }
            (None, None) => unreachable!("validated"),
        };
        let (y0, projection) = crate::assembly::assemble(&mech)?;
        mech.y0 = y0;
        mech.projection = projection;
        if !mech.elements.is_empty() {
            mech.element_defaults();
        }
        crate::initial_check::check(&mech)?;
        Ok(mech)
    }

    /// The free lengths and angles the scene leaves to the assembled initial state.
    fn element_defaults(&mut self) {
        let y0 = self.y0.clone();
        let t0 = self.t_start;
        let mut sc = self.scratch.borrow().clone();
        self.kinematics(t0, &y0, &mut sc);
        for e in &mut self.elements {
            match &mut e.kind {
                crate::elements::Kind::Spring { a, b, l0, .. } if l0.is_nan() => {
                    *l0 =
                        crate::elements::Input::Length(*a, *b).value(t0, &sc.pose, &sc.vel, &sc.cs);
                }
                crate::elements::Kind::RotSpring { a, b, theta0, .. } if theta0.is_nan() => {
                    *theta0 = crate::elements::Input::Relative(Some(*a), *b)
                        .value(t0, &sc.pose, &sc.vel, &sc.cs);
                }
                _ => {}
            }
        }
    }
}
