//! The mechanism: a validated scene turned into the index-1 ODE of docs/model.md §1.
//!
//! ```text
//! y = (q, q̇),  q = (x_i, y_i, φ_i) of every integrated body (scene order)
//!
//! [ M    Φ_qᵀ ] [ q̈ ]   [ g                 ]        M = diag(m_i, m_i, I_i)
//! [ Φ_q  0    ] [ λ  ] = [ γ − 2αΦ̇ − β²Φ    ]        Φ̈ = Φ_q q̈ − γ
//!
//! solved by the range-space (Schur complement) reduction, exactly equivalent for M > 0 and
//! Φ_q of full row rank (checked at the initial state):
//!   S = Φ_q M⁻¹ Φ_qᵀ  (SPD),   S λ = Φ_q M⁻¹ g − (γ − 2αΦ̇ − β²Φ)   (Cholesky),
//!   q̈ = M⁻¹ (g − Φ_qᵀ λ)
//! ```
//! A body whose motion is prescribed (a rotational driver plus a revolute joint to the ground
//! or to another prescribed body: the press's crank) is not integrated; its pose, velocity and
//! acceleration are closed-form functions of t, and the joints to it are rheonomic constraints
//! on the other body. The clearance joints add forces to g (docs/model.md §2–§4), and so do the
//! force elements and prismatic clearance joints (§10–§11); absent features (gravity, friction,
//! film, force elements) run no code.
//!
//! Sources: docs/model.md §1 (Nikravesh, Computer-Aided Analysis of Mechanical Systems, 1988;
//! Baumgarte 1972), Peng et al. 2025 §3.

use std::cell::{Cell, RefCell};
use std::collections::BTreeMap;

use faer::MatMut;
use lash_solver::{Direction, EventAction, EventHit, EventSpec, OdeSystem};

use crate::elements::{Element, ElementEval, Prismatic, PrismaticEval};
use crate::geometry::{ClearanceInput, ClearanceState};
use crate::laws::{hertz_stiffness, Film, FrictionLaw, NormalLaw, DEFAULT_MIRROR_WIDTH};
use crate::outputs::Roles;
use crate::scene::{
    Attachment, ClearanceEnd, FrictionSpec, JointSpec, NormalSpec, Scene, SceneError, GROUND,
};

// ---------------------------------------------------------------------------------------------
// Small planar helpers
// ---------------------------------------------------------------------------------------------

/// A(φ) s with (c, s) = (cos φ, sin φ).
#[inline]
pub(crate) fn rot(cs: [f64; 2], v: [f64; 2]) -> [f64; 2] {
    [cs[0] * v[0] - cs[1] * v[1], cs[1] * v[0] + cs[0] * v[1]]
}

/// k × v = (−v_y, v_x).
#[inline]
pub(crate) fn perp(v: [f64; 2]) -> [f64; 2] {
    [-v[1], v[0]]
}

#[inline]
pub(crate) fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

#[inline]
pub(crate) fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

// ---------------------------------------------------------------------------------------------
// Internal model
// ---------------------------------------------------------------------------------------------

/// How a body moves: integrated (index into q) or prescribed (index into the prescriptions).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Owner {
    Int(usize),
    Pres(usize),
}

#[derive(Clone, Debug)]
pub(crate) struct BodyInfo {
    pub name: String,
    pub mass: f64,
    pub inertia: f64,
    pub points: BTreeMap<String, [f64; 2]>,
    pub owner: Owner,
}

/// A prescribed body: φ = θ₀ + ω t, and its point `s_own` pinned to a ground location or to a
/// point of an earlier prescribed body.
#[derive(Clone, Debug)]
pub(crate) struct Prescription {
    pub body: usize,
    pub theta0: f64,
    pub omega: f64,
    pub s_own: [f64; 2],
    /// Parent body and its local point; None: the ground at `ground_at`.
    pub parent: Option<(usize, [f64; 2])>,
    pub ground_at: [f64; 2],
    pub driver_joint: usize,
}

#[derive(Clone, Copy, Debug)]
pub(crate) enum TermKind {
    /// w · r^P, r^P = r + A(φ) s
    Point { s: [f64; 2], w: [f64; 2] },
    /// c · φ
    Angle { c: f64 },
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct Term {
    pub body: usize,
    pub kind: TermKind,
}

/// One scalar constraint equation Φ = konst + rate·t + Σ terms.
#[derive(Clone, Debug)]
pub(crate) struct Row {
    pub terms: [Term; 2],
    pub n_terms: usize,
    pub konst: f64,
    pub rate: f64,
    /// Scene joint index.
    pub joint: usize,
    /// Which equation of the joint ("x", "y", "across the line", ...).
    pub label: &'static str,
}

/// One side of a clearance joint: a body point (local s) or a ground location (global s).
#[derive(Clone, Copy, Debug)]
pub(crate) struct End {
    pub body: Option<usize>,
    pub s: [f64; 2],
}

#[derive(Debug)]
pub(crate) struct Clr {
    pub joint: usize,
    pub name: String,
    pub bearing: End,
    pub journal: End,
    pub rb: f64,
    pub rj: f64,
    pub c: f64,
    pub normal: NormalLaw,
    pub friction: Option<FrictionLaw>,
    pub film: Option<Film>,
    pub e0: [f64; 2],
    /// ė(t_start) (m/s).
    pub e0_rate: [f64; 2],
    /// δ̇⁻ stored at the last contact onset (event hook).
    pub impact_velocity: Cell<f64>,
}

/// One evaluated constraint row.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RowEval {
    pub phi: f64,
    pub phid: f64,
    pub gamma: f64,
    /// ∂Φ/∂(x, y, φ) of the body of each term.
    pub jrows: [[f64; 3]; 2],
}

/// One block product of the Schur complement S = Φ_q M⁻¹ Φ_qᵀ: term `ta` of row `a` and term
/// `tb` of row `b` (a ≥ b) act on the same integrated body `i`, and add
/// J_{a,ta} M_i⁻¹ J_{b,tb}ᵀ (3-vectors, M_i⁻¹ = diag(1/m, 1/m, 1/I)) to S_ab. Built once per
/// scene: the rows of bodies that share no term give S_ab = 0 and cost nothing.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SchurTerm {
    pub a: usize,
    pub b: usize,
    pub ta: usize,
    pub tb: usize,
    pub i: usize,
}

/// What the event functions are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum EventKind {
    /// δ of clearance joint k.
    Contact(usize),
    /// ε − ε_cap of clearance joint k.
    EpsCap(usize),
    /// δ_i of corner i of prismatic clearance joint k (docs/model.md §11).
    Corner(usize, usize),
    /// A point where a force law of clearance joint k is not smooth (docs/model.md §7).
    Kink(usize, Kink),
}

/// The points where the force laws of a revolute clearance joint have a kink in time while it
/// is in contact (docs/model.md §7), each an event when the run asks for them:
///
/// ```text
/// FullDamping  g = δ − d_max                   (IMPACT: STEP's damping reaches c_max)
/// Clip         g = r(δ, δ̇) in contact, else 1  (F_N's clip at 0, NormalLaw::unclipped_ratio)
/// SlipV0       g = v_T² − v₀² in contact, else 1  (c_d leaves 0)
/// SlipV1       g = v_T² − v₁² in contact, else 1  (c_d reaches 1)
/// ```
/// Outside contact the laws act not at all, so the last three are held at 1 there; at contact
/// onset r → 1 (continuous), and the slip functions jump only when the contact begins below
/// v₁, where the onset's own restart already covers the kink.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kink {
    FullDamping,
    Clip,
    SlipV0,
    SlipV1,
}

/// Per-joint results of one evaluation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ClrEval {
    pub st: ClearanceState,
    pub f_n: f64,
    pub f_t: f64,
    pub f_r: f64,
    pub f_tf: f64,
    pub elastic: f64,
}

impl Default for ClrEval {
    fn default() -> Self {
        ClrEval {
            st: ClearanceState {
                e: [0.0; 2],
                e_norm: 0.0,
                n: [1.0, 0.0],
                t: [0.0, 1.0],
                delta: 0.0,
                delta_dot: 0.0,
                v_t: 0.0,
                eps: 0.0,
                eps_dot: 0.0,
                omega: 0.0,
            },
            f_n: 0.0,
            f_t: 0.0,
            f_r: 0.0,
            f_tf: 0.0,
            elastic: 0.0,
        }
    }
}

/// Buffers of one evaluation (no allocation in `rhs`).
#[derive(Clone, Debug)]
pub(crate) struct Scratch {
    pub pose: Vec<[f64; 3]>,
    pub vel: Vec<[f64; 3]>,
    pub acc: Vec<[f64; 3]>,
    pub cs: Vec<[f64; 2]>,
    /// Applied generalized forces on integrated coordinates.
    pub g: Vec<f64>,
    /// Applied forces on every body (filled in full evaluations, for Newton–Euler and outputs).
    pub gb: Vec<[f64; 3]>,
    pub jac: Vec<f64>,
    pub phi: Vec<f64>,
    pub phid: Vec<f64>,
    pub rc: Vec<f64>,
    pub smat: Vec<f64>,
    pub lam: Vec<f64>,
    pub qdd: Vec<f64>,
    pub clr: Vec<ClrEval>,
    /// Every force element (docs/model.md §10).
    pub el: Vec<ElementEval>,
    /// Every prismatic clearance joint (docs/model.md §11).
    pub pr: Vec<PrismaticEval>,
    /// Jacobian blocks of every row with respect to each of its terms' bodies (full mode).
    pub term_jac: Vec<[[f64; 3]; 2]>,
}

/// A planar mechanism as an ODE: build it with [`Mechanism::from_scene`], integrate it with
/// `lash_solver::solve` from [`Mechanism::initial_state`], read it with
/// [`Mechanism::outputs`].
///
/// ```text
/// y' = f(t, y),  y = (q, q̇)  (docs/model.md §1);  events δ_k(q), ε_k − ε_cap and the
/// corner gaps δ_i of the prismatic clearance joints (§7, §11)
/// ```
#[derive(Debug)]
pub struct Mechanism {
    pub(crate) scene: Scene,
    pub(crate) bodies: Vec<BodyInfo>,
    /// Scene index of integrated body i.
    pub(crate) int_bodies: Vec<usize>,
    pub(crate) pres: Vec<Prescription>,
    pub(crate) rows: Vec<Row>,
    /// Integrated body index of each term of each row (None: a prescribed body).
    pub(crate) row_int: Vec<[Option<usize>; 2]>,
    /// The nonzero block products of S (fixed structure, built once).
    pub(crate) schur: Vec<SchurTerm>,
    /// The rows of each diagonal block of S (rows that share no body, directly or through
    /// other rows, are in different blocks), each in increasing order.
    pub(crate) kkt_blocks: Vec<Vec<usize>>,
    pub(crate) clr: Vec<Clr>,
    pub(crate) elements: Vec<Element>,
    pub(crate) prismatic: Vec<Prismatic>,
    pub(crate) projection: crate::assembly::ProjectionReport,
    pub(crate) events: Vec<EventKind>,
    pub(crate) minv: Vec<f64>,
    pub(crate) gravity: Option<[f64; 2]>,
    pub(crate) alpha: f64,
    pub(crate) beta: f64,
    pub(crate) t_start: f64,
    pub(crate) t_end: f64,
    pub(crate) y0: Vec<f64>,
    pub(crate) roles: Roles,
    pub(crate) scratch: RefCell<Scratch>,
    pub(crate) jac_work: RefCell<crate::jacobian::JacWork>,
}

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

    /// What the projection onto the constraints changed in the scene's initial guesses
    /// (docs/model.md §1, "Initial conditions").
    pub fn projection_report(&self) -> &crate::assembly::ProjectionReport {
        &self.projection
    }

    /// Names of the force elements, in the order of [`crate::Outputs::elements`].
    pub fn element_names(&self) -> Vec<&str> {
        self.elements.iter().map(|e| e.name.as_str()).collect()
    }

    /// Names of the prismatic clearance joints, in the order of [`crate::Outputs::prismatic`].
    pub fn prismatic_names(&self) -> Vec<&str> {
        self.prismatic.iter().map(|p| p.name.as_str()).collect()
    }

    /// y0 after assembly: (q, q̇) of the integrated bodies.
    pub fn initial_state(&self) -> Vec<f64> {
        self.y0.clone()
    }

    /// Start time (s).
    pub fn t_start(&self) -> f64 {
        self.t_start
    }

    /// End time (s): `t_end`, or t_start + revolutions · 2π/|ω| of the crank driver.
    pub fn t_end(&self) -> f64 {
        self.t_end
    }

    /// The scene this mechanism was built from.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Resolved roles.
    pub fn roles(&self) -> &Roles {
        &self.roles
    }

    /// ω (rad/s) of the `crank_driver` role, if declared.
    pub fn crank_speed(&self) -> Option<f64> {
        let j = self.roles.crank_driver?;
        match &self.scene.joints[j] {
            JointSpec::Driver(d) => Some(d.omega_rad_s()),
            _ => None,
        }
    }

    /// Names of the integrated bodies, in the order of q.
    pub fn integrated_bodies(&self) -> Vec<&str> {
        self.int_bodies
            .iter()
            .map(|&k| self.bodies[k].name.as_str())
            .collect()
    }

    /// Names of the prescribed (not integrated) bodies.
    pub fn prescribed_bodies(&self) -> Vec<&str> {
        self.pres
            .iter()
            .map(|p| self.bodies[p.body].name.as_str())
            .collect()
    }

    /// Number of constraint equations in the KKT system.
    pub fn n_constraints(&self) -> usize {
        self.rows.len()
    }

    /// Names of the clearance joints, in the order of [`crate::Outputs::clearance`].
    pub fn clearance_names(&self) -> Vec<&str> {
        self.clr.iter().map(|c| c.name.as_str()).collect()
    }

    /// The stored impact velocity δ̇⁻ of every clearance joint (m/s; 0 before any onset).
    pub fn impact_velocities(&self) -> Vec<f64> {
        self.clr.iter().map(|c| c.impact_velocity.get()).collect()
    }

    /// Number of integrated coordinates (n_q = dim/2).
    pub(crate) fn nq(&self) -> usize {
        3 * self.int_bodies.len()
    }

    // -----------------------------------------------------------------------------------------
    // Evaluation core
    // -----------------------------------------------------------------------------------------

    /// Poses and velocities of every body at (t, y); accelerations of prescribed bodies.
    pub(crate) fn kinematics(&self, t: f64, y: &[f64], sc: &mut Scratch) {
        let nq = self.nq();
        for (i, &k) in self.int_bodies.iter().enumerate() {
            let q = &y[3 * i..3 * i + 3];
            let v = &y[nq + 3 * i..nq + 3 * i + 3];
            sc.pose[k] = [q[0], q[1], q[2]];
            sc.vel[k] = [v[0], v[1], v[2]];
            let (s, c) = q[2].sin_cos();
            sc.cs[k] = [c, s];
        }
        for p in &self.pres {
            let phi = p.theta0 + p.omega * t;
            let (s, c) = phi.sin_cos();
            let cs = [c, s];
            let as_ = rot(cs, p.s_own);
            let bs = perp(as_);
            let (pp, vp, ap) = match p.parent {
                None => (p.ground_at, [0.0; 2], [0.0; 2]),
                Some((kp, sp)) => {
                    let a = rot(sc.cs[kp], sp);
                    let b = perp(a);
                    let [x, y, _] = sc.pose[kp];
                    let [vx, vy, w] = sc.vel[kp];
                    let [ax, ay, al] = sc.acc[kp];
                    (
                        [x + a[0], y + a[1]],
                        [vx + w * b[0], vy + w * b[1]],
                        [ax + al * b[0] - w * w * a[0], ay + al * b[1] - w * w * a[1]],
                    )
                }
            };
            let w = p.omega;
            sc.cs[p.body] = cs;
            sc.pose[p.body] = [pp[0] - as_[0], pp[1] - as_[1], phi];
            sc.vel[p.body] = [vp[0] - w * bs[0], vp[1] - w * bs[1], w];
            sc.acc[p.body] = [ap[0] + w * w * as_[0], ap[1] + w * w * as_[1], 0.0];
        }
    }

    /// Global position and velocity of a clearance end, and the angular velocity of its body.
    #[inline]
    fn end_point(&self, e: &End, sc: &Scratch) -> ([f64; 2], [f64; 2], f64) {
        match e.body {
            None => (e.s, [0.0; 2], 0.0),
            Some(k) => {
                let a = rot(sc.cs[k], e.s);
                let [x, y, _] = sc.pose[k];
                let [vx, vy, w] = sc.vel[k];
                ([x + a[0], y + a[1]], [vx - w * a[1], vy + w * a[0]], w)
            }
        }
    }

    /// Clearance kinematics of joint k (after `kinematics`).
    #[inline]
    pub(crate) fn clearance_state(&self, k: usize, sc: &Scratch) -> ClearanceState {
        let c = &self.clr[k];
        let (r_b, v_b, w_b) = self.end_point(&c.bearing, sc);
        let (r_j, v_j, w_j) = self.end_point(&c.journal, sc);
        ClearanceState::compute(&ClearanceInput {
            r_j,
            r_b,
            v_j,
            v_b,
            phi_dot_j: w_j,
            phi_dot_b: w_b,
            radius_j: c.rj,
            radius_b: c.rb,
        })
    }

    /// Adds force f at global point (r_body + A s + arm_extra) to body k.
    #[inline]
    pub(crate) fn apply(&self, k: usize, arm: [f64; 2], f: [f64; 2], sc: &mut Scratch, full: bool) {
        let mz = cross(arm, f);
        match self.bodies[k].owner {
            Owner::Int(i) => {
                sc.g[3 * i] += f[0];
                sc.g[3 * i + 1] += f[1];
                sc.g[3 * i + 2] += mz;
            }
            Owner::Pres(_) => {}
        }
        if full {
            sc.gb[k][0] += f[0];
            sc.gb[k][1] += f[1];
            sc.gb[k][2] += mz;
        }
    }

    /// Applied forces: gravity and the clearance joints (docs/model.md §3–§4), then the force
    /// elements and prismatic clearance joints (§10–§11) when the scene has any.
    pub(crate) fn applied_forces(&self, t: f64, sc: &mut Scratch, full: bool) {
        sc.g.iter_mut().for_each(|v| *v = 0.0);
        if full {
            sc.gb.iter_mut().for_each(|v| *v = [0.0; 3]);
        }
        if let Some(gv) = self.gravity {
            for (i, &k) in self.int_bodies.iter().enumerate() {
                let m = self.bodies[k].mass;
                sc.g[3 * i] += m * gv[0];
                sc.g[3 * i + 1] += m * gv[1];
            }
            if full {
                for (k, b) in self.bodies.iter().enumerate() {
                    sc.gb[k][0] += b.mass * gv[0];
                    sc.gb[k][1] += b.mass * gv[1];
                }
            }
        }
        for k in 0..self.clr.len() {
            let st = self.clearance_state(k, sc);
            let c = &self.clr[k];
            let ev = self.clearance_forces(k, st);
            // Dry contact.
            if st.delta > 0.0 {
                let f_j = [
                    -ev.f_n * st.n[0] + ev.f_t * st.t[0],
                    -ev.f_n * st.n[1] + ev.f_t * st.t[1],
                ];
                if let Some(kj) = c.journal.body {
                    let a = rot(sc.cs[kj], c.journal.s);
                    let arm = [a[0] + c.rj * st.n[0], a[1] + c.rj * st.n[1]];
                    self.apply(kj, arm, f_j, sc, full);
                }
                if let Some(kb) = c.bearing.body {
                    let a = rot(sc.cs[kb], c.bearing.s);
                    let arm = [a[0] + c.rb * st.n[0], a[1] + c.rb * st.n[1]];
                    self.apply(kb, arm, [-f_j[0], -f_j[1]], sc, full);
                }
            }
            // Oil film.
            if c.film.is_some() {
                let (fr, ft) = (ev.f_r, ev.f_tf);
                let f_j = [fr * st.n[0] + ft * st.t[0], fr * st.n[1] + ft * st.t[1]];
                if let Some(kj) = c.journal.body {
                    let arm = rot(sc.cs[kj], c.journal.s);
                    self.apply(kj, arm, f_j, sc, full);
                }
                if let Some(kb) = c.bearing.body {
                    let arm = rot(sc.cs[kb], c.bearing.s);
                    self.apply(kb, arm, [-f_j[0], -f_j[1]], sc, full);
                }
            }
            sc.clr[k] = ev;
        }
        if !(self.elements.is_empty() && self.prismatic.is_empty()) {
            self.element_forces(t, sc, full);
        }
    }

    /// Adds a load (body, arm, force, torque) to the generalized forces.
    #[inline]
    fn apply_load(&self, l: crate::elements::Load, sc: &mut Scratch, full: bool) {
        let (k, arm, f, tau) = l;
        self.apply(k, arm, f, sc, full);
        if tau != 0.0 {
            match self.bodies[k].owner {
                Owner::Int(i) => sc.g[3 * i + 2] += tau,
                Owner::Pres(_) => {}
            }
            if full {
                sc.gb[k][2] += tau;
            }
        }
    }

    /// The force elements and prismatic clearance joints (docs/model.md §10–§11), after
    /// `kinematics`.
    pub(crate) fn element_forces(&self, t: f64, sc: &mut Scratch, full: bool) {
        let mut loads: [crate::elements::Load; 4] = [(0, [0.0; 2], [0.0; 2], 0.0); 4];
        for (i, e) in self.elements.iter().enumerate() {
            let mut n = 0;
            let ev = e.eval(t, &sc.pose, &sc.vel, &sc.cs, |l| {
                loads[n] = l;
                n += 1;
            });
            for l in &loads[..n] {
                self.apply_load(*l, sc, full);
            }
            sc.el[i] = ev;
        }
        for (i, p) in self.prismatic.iter().enumerate() {
            let mut n = 0;
            let ev = p.eval(&sc.pose, &sc.vel, &sc.cs, |l| {
                loads[n] = l;
                n += 1;
            });
            for l in &loads[..n] {
                self.apply_load(*l, sc, full);
            }
            sc.pr[i] = ev;
        }
    }

    /// The force laws of clearance joint k at the clearance state `st` (docs/model.md §3–§4):
    /// normal force, friction, elastic part (δ > 0 only) and film forces (when lubricated).
    #[inline]
    pub(crate) fn clearance_forces(&self, k: usize, st: ClearanceState) -> ClrEval {
        let c = &self.clr[k];
        let mut ev = ClrEval {
            st,
            ..ClrEval::default()
        };
        if st.delta > 0.0 {
            ev.f_n = c
                .normal
                .force(st.delta, st.delta_dot, c.impact_velocity.get());
            ev.elastic = c.normal.stiffness() * st.delta * st.delta.sqrt();
            if let Some(fr) = &c.friction {
                ev.f_t = fr.force(st.v_t, ev.f_n);
            }
        }
        if let Some(film) = &c.film {
            let (fr, ft) = film.force(st.eps, st.eps_dot, st.omega);
            ev.f_r = fr;
            ev.f_tf = ft;
        }
        ev
    }

    /// Value Φ, rate Φ̇, γ (Φ̈ = Φ_q q̈ − γ, prescribed accelerations folded in) and the
    /// Jacobian block of each term of one constraint row (after `kinematics`).
    #[inline]
    pub(crate) fn eval_row(&self, row: &Row, t: f64, sc: &Scratch) -> RowEval {
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
            let owner = self.bodies[k].owner;
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

    /// Constraint values, Φ̇, the Baumgarte right-hand side and the Jacobian blocks of every
    /// term (for the Schur complement and, in full mode, the reactions on any body); in full
    /// mode also the dense Φ_q of the integrated columns (`sc.jac`).
    pub(crate) fn constraint_rows(&self, t: f64, sc: &mut Scratch, full: bool) {
        let (a2, b2) = (2.0 * self.alpha, self.beta * self.beta);
        for (r, row) in self.rows.iter().enumerate() {
            let ev = self.eval_row(row, t, sc);
            sc.term_jac[r] = ev.jrows;
            sc.phi[r] = ev.phi;
            sc.phid[r] = ev.phid;
            sc.rc[r] = ev.gamma - a2 * ev.phid - b2 * ev.phi;
        }
        if full {
            self.dense_constraint_jacobian(sc);
        }
    }

    /// Φ_q (m × n_q, row-major) into `sc.jac` from the term blocks (after `constraint_rows`).
    pub(crate) fn dense_constraint_jacobian(&self, sc: &mut Scratch) {
        let nq = self.nq();
        sc.jac.iter_mut().for_each(|v| *v = 0.0);
        for (r, (row, jr)) in self.row_int.iter().zip(&sc.term_jac).enumerate() {
            for (ti, bi) in row.iter().enumerate() {
                if let Some(i) = *bi {
                    let base = r * nq + 3 * i;
                    sc.jac[base] += jr[ti][0];
                    sc.jac[base + 1] += jr[ti][1];
                    sc.jac[base + 2] += jr[ti][2];
                }
            }
        }
    }

    /// Solves the KKT system by its Schur complement; false if S is not positive definite.
    ///
    /// ```text
    /// S = Φ_q M⁻¹ Φ_qᵀ,  S λ = Φ_q M⁻¹ g − r,  q̈ = M⁻¹ (g − Φ_qᵀ λ)
    /// ```
    /// Φ_q is used through its term blocks (`term_jac`, three columns of one body each) and S
    /// through its fixed structure (`schur`): no product with a zero block is formed.
    pub(crate) fn solve_kkt(&self, sc: &mut Scratch) -> bool {
        let nq = self.nq();
        let m = self.rows.len();
        let Scratch {
            term_jac,
            smat,
            lam,
            qdd,
            g,
            rc,
            ..
        } = sc;
        let minv = &self.minv[..nq];
        let g = &g[..nq];
        let qdd = &mut qdd[..nq];
        if m == 0 {
            for j in 0..nq {
                qdd[j] = minv[j] * g[j];
            }
            return true;
        }
        // q̈ first holds M⁻¹ g, the right-hand side Φ_q M⁻¹ g − r of λ is read from it.
        for j in 0..nq {
            qdd[j] = minv[j] * g[j];
        }
        let term_jac = &term_jac[..m];
        let smat = &mut smat[..m * m];
        for (a, (row, jr)) in self.row_int.iter().zip(term_jac).enumerate() {
            let mut ba = -rc[a];
            for (ti, bi) in row.iter().enumerate() {
                if let Some(i) = *bi {
                    let x = &qdd[3 * i..3 * i + 3];
                    let j = &jr[ti];
                    ba += j[0] * x[0] + j[1] * x[1] + j[2] * x[2];
                }
            }
            lam[a] = ba;
            smat[a * m..a * m + a + 1].fill(0.0);
        }
        for p in &self.schur {
            let (ja, jb) = (&term_jac[p.a][p.ta], &term_jac[p.b][p.tb]);
            let w = &minv[3 * p.i..3 * p.i + 3];
            smat[p.a * m + p.b] +=
                ja[0] * w[0] * jb[0] + ja[1] * w[1] * jb[1] + ja[2] * w[2] * jb[2];
        }
        // S is block diagonal (up to the order of the rows): each block is factored and solved
        // on its own, so the square roots and divisions of different blocks do not wait for
        // each other. The factor, stored in place, is the dense factor of S.
        for blk in &self.kkt_blocks {
            if block_cholesky_inv(smat, m, blk).is_err() {
                return false;
            }
            block_cholesky_solve(smat, m, blk, lam);
        }
        // q̈ = M⁻¹ g − M⁻¹ Φ_qᵀ λ.
        for (a, (row, jr)) in self.row_int.iter().zip(term_jac).enumerate() {
            let la = lam[a];
            for (ti, bi) in row.iter().enumerate() {
                if let Some(i) = *bi {
                    let j = &jr[ti];
                    let w = &minv[3 * i..3 * i + 3];
                    let x = &mut qdd[3 * i..3 * i + 3];
                    x[0] -= w[0] * j[0] * la;
                    x[1] -= w[1] * j[1] * la;
                    x[2] -= w[2] * j[2] * la;
                }
            }
        }
        true
    }

    /// One full evaluation at (t, y) into the scratch; false if the KKT matrix is singular.
    /// After it, `acc` holds every body's acceleration.
    pub(crate) fn evaluate(&self, t: f64, y: &[f64], sc: &mut Scratch, full: bool) -> bool {
        self.kinematics(t, y, sc);
        self.applied_forces(t, sc, full);
        self.constraint_rows(t, sc, full);
        let ok = self.solve_kkt(sc);
        for (i, &k) in self.int_bodies.iter().enumerate() {
            sc.acc[k] = [sc.qdd[3 * i], sc.qdd[3 * i + 1], sc.qdd[3 * i + 2]];
        }
        ok
    }

    /// Event functions at (t, y) and, when `g_dot` is given, their rates (after
    /// `kinematics`): δ and δ̇, ε − ε_cap and ε̇, a corner's δ_i and δ̇_i (docs/model.md §2,
    /// §7, §11), all from positions and velocities.
    fn event_values(&self, sc: &Scratch, g: &mut [f64], mut g_dot: Option<&mut [f64]>) {
        // A joint's clearance state serves all of its event functions (δ, ε − ε_cap, kinks):
        // the last one computed is kept.
        let mut last: Option<(usize, ClearanceState)> = None;
        let mut state = |k: usize| match last {
            Some((j, st)) if j == k => st,
            _ => {
                let st = self.clearance_state(k, sc);
                last = Some((k, st));
                st
            }
        };
        for (i, ev) in self.events.iter().enumerate() {
            let (v, d) = match *ev {
                EventKind::Contact(k) => {
                    let st = state(k);
                    (st.delta, st.delta_dot)
                }
                EventKind::EpsCap(k) => {
                    let cap = self.clr[k].film.and_then(|f| f.eps_cap).unwrap_or(1.0);
                    let st = state(k);
                    (st.eps - cap, st.eps_dot)
                }
                EventKind::Corner(k, c) => {
                    self.prismatic[k].corner_gap(c, &sc.pose, &sc.vel, &sc.cs)
                }
                EventKind::Kink(k, kink) => self.kink_value(k, kink, state(k)),
            };
            g[i] = v;
            if let Some(gd) = g_dot.as_deref_mut() {
                gd[i] = d;
            }
        }
    }

    /// Which event function index `i` is: ("contact" | "eps_cap", clearance joint name), or
    /// ("corner_contact", prismatic clearance joint name) for the gap δ_i of one of its four
    /// corners (docs/model.md §11).
    pub fn event_name(&self, i: usize) -> Option<(&'static str, &str)> {
        self.events.get(i).map(|e| match *e {
            EventKind::Contact(k) => ("contact", self.clr[k].name.as_str()),
            EventKind::EpsCap(k) => ("eps_cap", self.clr[k].name.as_str()),
            EventKind::Corner(k, _) => ("corner_contact", self.prismatic[k].name.as_str()),
            EventKind::Kink(k, kink) => (
                match kink {
                    Kink::FullDamping => "kink_full_damping",
                    Kink::Clip => "kink_force_clip",
                    Kink::SlipV0 => "kink_slip_v0",
                    Kink::SlipV1 => "kink_slip_v1",
                },
                self.clr[k].name.as_str(),
            ),
        })
    }

    /// The value and rate of a kink function ([`Kink`]) of clearance joint `k` at its clearance
    /// state `st`. The rate of δ − d_max is δ̇; the others need accelerations, so in contact
    /// their rate is given as infinite (the step is always sampled) and outside contact, where
    /// they are held at 1, as 0.
    fn kink_value(&self, k: usize, kink: Kink, st: ClearanceState) -> (f64, f64) {
        let c = &self.clr[k];
        if kink == Kink::FullDamping {
            let d_max = match c.normal {
                NormalLaw::Impact { d_max, .. } => d_max,
                _ => f64::INFINITY,
            };
            return (st.delta - d_max, st.delta_dot);
        }
        if st.delta <= 0.0 {
            return (1.0, 0.0);
        }
        let (v0, v1) = match c.friction {
            Some(FrictionLaw::Coulomb { v0, v1, .. }) => (v0, v1),
            _ => (0.0, 0.0),
        };
        let g = match kink {
            Kink::Clip => c
                .normal
                .unclipped_ratio(st.delta, st.delta_dot, c.impact_velocity.get()),
            Kink::SlipV0 => st.v_t * st.v_t - v0 * v0,
            _ => st.v_t * st.v_t - v1 * v1,
        };
        (g, f64::INFINITY)
    }

    /// Adds (or removes) the kink events of the revolute clearance joints' force laws
    /// (δ = d_max, the clip of F_N at 0, |v_T| = v₀ and v₁; docs/model.md §7), as the scene
    /// field `kink_events` does. With them an integration restarts at every kink, so a method
    /// of high order keeps its order through a contact; every other event keeps its index.
    pub fn set_kink_events(&mut self, on: bool) {
        self.events = event_list(&self.clr, self.prismatic.len(), on);
    }

    /// Whether the kink events are on ([`Mechanism::set_kink_events`]).
    pub fn kink_events(&self) -> bool {
        self.events.iter().any(|e| matches!(e, EventKind::Kink(..)))
    }

    /// Sets the stored impact velocity δ̇⁻ of clearance joint `k` (m/s), as the contact-onset
    /// event does. For tests and for restarting a run from a saved state.
    pub fn set_impact_velocity(&self, k: usize, v: f64) {
        if let Some(c) = self.clr.get(k) {
            c.impact_velocity.set(v);
        }
    }
}

/// The event functions of a mechanism: every clearance joint's δ, the ε − ε_cap of each capped
/// film, the four corner gaps of each prismatic clearance joint and, with `kinks`, the kinks of
/// each revolute clearance joint's force laws ([`Kink`]).
fn event_list(clr: &[Clr], n_prismatic: usize, kinks: bool) -> Vec<EventKind> {
    let mut events = Vec::new();
    for k in 0..clr.len() {
        events.push(EventKind::Contact(k));
    }
    // A capped film changes form at ε = ε_cap; a film without a cap has no such point
    // below contact (docs/model.md §7).
    for (k, c) in clr.iter().enumerate() {
        if c.film.is_some_and(|f| f.eps_cap.is_some()) {
            events.push(EventKind::EpsCap(k));
        }
    }
    for k in 0..n_prismatic {
        for i in 0..4 {
            events.push(EventKind::Corner(k, i));
        }
    }
    if kinks {
        for (k, c) in clr.iter().enumerate() {
            if let NormalLaw::Impact { c_max, .. } = c.normal {
                if c_max > 0.0 {
                    events.push(EventKind::Kink(k, Kink::FullDamping));
                }
            }
            if c.normal.can_clip() {
                events.push(EventKind::Kink(k, Kink::Clip));
            }
            if let Some(FrictionLaw::Coulomb { mu, v0, v1 }) = c.friction {
                if mu > 0.0 && v0 > 0.0 {
                    events.push(EventKind::Kink(k, Kink::SlipV0));
                }
                if mu > 0.0 && v1 > v0 {
                    events.push(EventKind::Kink(k, Kink::SlipV1));
                }
            }
        }
    }
    events
}

/// Cholesky factorisation S = L Lᵀ in place: the lower triangle of the row-major m × m
/// `smat` (holding S) becomes L. `Err(j)` when the pivot d_j = S_jj − Σ_{k<j} L_jk² of row j
/// is not a positive number (S is not positive definite in f64); d_j is then left at (j, j).
#[inline]
pub(crate) fn cholesky_in_place(smat: &mut [f64], m: usize) -> Result<(), usize> {
    for j in 0..m {
        let (row_j, rest) = smat[j * m..m * m].split_at_mut(m);
        let mut d = row_j[j];
        for &v in &row_j[..j] {
            d -= v * v;
        }
        if !(d > 0.0) {
            row_j[j] = d;
            return Err(j);
        }
        let d = d.sqrt();
        row_j[j] = d;
        let lj = &row_j[..j];
        for row_i in rest.chunks_exact_mut(m) {
            let mut s = row_i[j];
            for (&x, &y) in row_i[..j].iter().zip(lj) {
                s -= x * y;
            }
            row_i[j] = s / d;
        }
    }
    Ok(())
}

/// Cholesky factorisation S = L Lᵀ in place over the rows `blk` of a diagonal block of S (the
/// entries of S between `blk` and the other rows being zero, those of L are too): the strict
/// lower triangle of the row-major m × m `smat` becomes that of L and its diagonal holds
/// 1/L_jj, so that the solves multiply instead of divide (one division per column, none per
/// solve: the latency of divisions and square roots dominated the Schur-complement solve of a
/// small S). `Err(j)` when the pivot d_j = S_jj − Σ_k L_jk² of row j is not a positive number
/// (S is not positive definite in f64).
#[inline]
pub(crate) fn block_cholesky_inv(smat: &mut [f64], m: usize, blk: &[usize]) -> Result<(), usize> {
    for (p, &j) in blk.iter().enumerate() {
        let mut d = smat[j * m + j];
        for &k in &blk[..p] {
            let v = smat[j * m + k];
            d -= v * v;
        }
        if !(d > 0.0) {
            smat[j * m + j] = d;
            return Err(j);
        }
        let r = 1.0 / d.sqrt();
        smat[j * m + j] = r;
        for &i in &blk[p + 1..] {
            let mut s = smat[i * m + j];
            for &k in &blk[..p] {
                s -= smat[i * m + k] * smat[j * m + k];
            }
            smat[i * m + j] = s * r;
        }
    }
    Ok(())
}

/// [`cholesky_solve`] restricted to the rows `blk` of a diagonal block (after
/// [`block_cholesky_inv`]).
#[inline]
pub(crate) fn block_cholesky_solve(l: &[f64], m: usize, blk: &[usize], b: &mut [f64]) {
    for (p, &i) in blk.iter().enumerate() {
        let mut s = b[i];
        for &k in &blk[..p] {
            s -= l[i * m + k] * b[k];
        }
        b[i] = s * l[i * m + i];
    }
    for (p, &i) in blk.iter().enumerate().rev() {
        let mut s = b[i];
        for &k in &blk[p + 1..] {
            s -= l[k * m + i] * b[k];
        }
        b[i] = s * l[i * m + i];
    }
}

/// Solves L Lᵀ x = b in place (forward, then back substitution), L the dense factor left by
/// [`block_cholesky_inv`] on every block of S (the diagonal holding 1/L_jj).
#[inline]
pub(crate) fn cholesky_solve(l: &[f64], m: usize, b: &mut [f64]) {
    let l = &l[..m * m];
    let b = &mut b[..m];
    for i in 0..m {
        let li = &l[i * m..i * m + i];
        let mut s = b[i];
        for (&x, &y) in li.iter().zip(&b[..i]) {
            s -= x * y;
        }
        b[i] = s * l[i * m + i];
    }
    for i in (0..m).rev() {
        let mut s = b[i];
        for k in i + 1..m {
            s -= l[k * m + i] * b[k];
        }
        b[i] = s * l[i * m + i];
    }
}

impl Row {
    pub(crate) fn new(joint: usize, label: &'static str) -> Row {
        Row {
            terms: [Term {
                body: 0,
                kind: TermKind::Angle { c: 0.0 },
            }; 2],
            n_terms: 0,
            konst: 0.0,
            rate: 0.0,
            joint,
            label,
        }
    }

    pub(crate) fn push(&mut self, t: Term) {
        self.terms[self.n_terms] = t;
        self.n_terms += 1;
    }

    /// Adds w · r^P of an attachment (folds a ground location into the constant).
    fn add_attachment(&mut self, scene: &Scene, a: &Attachment, w: [f64; 2]) {
        if a.body == GROUND {
            self.konst += dot(w, a.at.expect("validated"));
        } else {
            let k = scene.body_index(&a.body).expect("validated");
            self.push(Term {
                body: k,
                kind: TermKind::Point {
                    s: point_of(scene, a),
                    w,
                },
            });
        }
    }
}

fn point_of(scene: &Scene, a: &Attachment) -> [f64; 2] {
    if a.body == GROUND {
        return a.at.expect("validated");
    }
    let k = scene.body_index(&a.body).expect("validated");
    scene.bodies[k].points[a.point.as_ref().expect("validated")]
}

fn end_of(scene: &Scene, e: &ClearanceEnd) -> End {
    if e.body == GROUND {
        End {
            body: None,
            s: e.at.expect("validated"),
        }
    } else {
        let k = scene.body_index(&e.body).expect("validated");
        End {
            body: Some(k),
            s: scene.bodies[k].points[e.point.as_ref().expect("validated")],
        }
    }
}

fn build_clearance(scene: &Scene, ji: usize, c: &crate::scene::ClearanceSpec) -> Clr {
    let rb = c.bearing.radius;
    let rj = c.journal.radius;
    let stiffness = |k: Option<f64>, m: Option<crate::scene::Materials>| match (k, m) {
        (Some(k), _) => k,
        (None, Some(m)) => hertz_stiffness(
            rb,
            rj,
            m.bearing.youngs_modulus,
            m.bearing.poisson_ratio,
            m.journal.youngs_modulus,
            m.journal.poisson_ratio,
        ),
        (None, None) => unreachable!("validated"),
    };
    let normal = match &c.normal {
        NormalSpec::Impact(s) => NormalLaw::Impact {
            k: stiffness(s.k, s.materials),
            c_max: s.c_max,
            d_max: s.d_max,
        },
        NormalSpec::LankaraniNikravesh(s) => NormalLaw::LankaraniNikravesh {
            k: stiffness(s.k, s.materials),
            restitution: s.restitution,
        },
        NormalSpec::Flores(s) => NormalLaw::Flores {
            k: stiffness(s.k, s.materials),
            restitution: s.restitution,
        },
        NormalSpec::HuntCrossley(s) => NormalLaw::HuntCrossley {
            k: stiffness(s.k, s.materials),
            restitution: s.restitution,
        },
    };
    let friction = match &c.friction {
        FrictionSpec::None => None,
        FrictionSpec::Coulomb(f) if f.mu == 0.0 => None,
        FrictionSpec::Coulomb(f) => Some(FrictionLaw::Coulomb {
            mu: f.mu,
            v0: f.v0,
            v1: f.v1,
        }),
    };
    let film = c.film.as_ref().map(|f| Film {
        model: f.model,
        viscosity: f.viscosity,
        length: f.length,
        radius: rj,
        clearance: rb - rj,
        eps_cap: f.eps_cap,
        mirror_width: f.omega0.unwrap_or(DEFAULT_MIRROR_WIDTH),
    });
    Clr {
        joint: ji,
        name: c.name.clone(),
        bearing: end_of(scene, &c.bearing),
        journal: end_of(scene, &c.journal),
        rb,
        rj,
        c: rb - rj,
        normal,
        friction,
        film,
        e0: c.initial_eccentricity,
        e0_rate: c.initial_eccentricity_rate,
        impact_velocity: Cell::new(0.0),
    }
}

impl OdeSystem for Mechanism {
    fn dim(&self) -> usize {
        2 * self.nq()
    }

    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        let nq = self.nq();
        let mut sc = self.scratch.borrow_mut();
        let ok = self.evaluate(t, y, &mut sc, false);
        dy[..nq].copy_from_slice(&y[nq..2 * nq]);
        if ok {
            dy[nq..].copy_from_slice(&sc.qdd);
        } else {
            dy[nq..].iter_mut().for_each(|v| *v = f64::NAN);
        }
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, t: f64, y: &[f64], jac: MatMut<'_, f64>) {
        crate::jacobian::jacobian(self, t, y, jac);
    }

    fn n_events(&self) -> usize {
        self.events.len()
    }

    fn event_spec(&self, _i: usize) -> EventSpec {
        EventSpec {
            direction: Direction::Either,
            action: EventAction::Continue,
        }
    }

    fn events(&self, t: f64, y: &[f64], g: &mut [f64]) {
        let mut sc = self.scratch.borrow_mut();
        self.kinematics(t, y, &mut sc);
        self.event_values(&sc, g, None);
    }

    fn event_rates(&self, t: f64, y: &[f64], g: &mut [f64], g_dot: &mut [f64]) -> bool {
        let mut sc = self.scratch.borrow_mut();
        self.kinematics(t, y, &mut sc);
        self.event_values(&sc, g, Some(g_dot));
        true
    }

    fn on_event(&self, hit: &EventHit, y: &mut [f64]) -> EventAction {
        match self.events.get(hit.index).copied() {
            Some(EventKind::Contact(k)) if hit.rising => {
                let mut sc = self.scratch.borrow_mut();
                self.kinematics(hit.t, y, &mut sc);
                let st = self.clearance_state(k, &sc);
                self.clr[k].impact_velocity.set(st.delta_dot);
            }
            Some(EventKind::Corner(k, c)) if hit.rising => {
                let mut sc = self.scratch.borrow_mut();
                self.kinematics(hit.t, y, &mut sc);
                let (_, ddot) = self.prismatic[k].corner_gap(c, &sc.pose, &sc.vel, &sc.cs);
                self.prismatic[k].impact_velocity[c].set(ddot);
            }
            _ => {}
        }
        EventAction::Continue
    }
}

#[cfg(test)]
mod tests {
    //! The Schur-complement solve equals faer's LU solve of the full KKT matrix.
    use super::*;
    use crate::cases::{press_scene, PressJoint};
    use faer::Mat;

    #[test]
    fn schur_complement_equals_the_full_kkt_solve() {
        let m = Mechanism::from_scene(&press_scene(PressJoint::Dry, 150.0, 1e-4)).unwrap();
        let nq = m.nq();
        let nc = m.rows.len();
        // A perturbed state: off the constraint manifold, in contact, moving.
        let mut y = m.initial_state();
        let pert = [
            3e-5, -1.2e-4, 2e-3, 1e-4, 2e-5, -1e-3, 0.02, -0.01, 0.3, -0.05, 0.01, 0.002,
        ];
        for (v, p) in y.iter_mut().zip(pert) {
            *v += p;
        }
        let t = 0.123;
        let mut sc = m.scratch.borrow().clone();
        assert!(m.evaluate(t, &y, &mut sc, false));
        m.dense_constraint_jacobian(&mut sc);
        assert!(sc.clr[0].f_n > 0.0, "the test state is in contact");
        let n = nq + nc;
        let mut kkt = Mat::<f64>::zeros(n, n);
        let mut rhs = Mat::<f64>::zeros(n, 1);
        for j in 0..nq {
            kkt[(j, j)] = 1.0 / m.minv[j];
            rhs[(j, 0)] = sc.g[j];
        }
        for a in 0..nc {
            for j in 0..nq {
                kkt[(nq + a, j)] = sc.jac[a * nq + j];
                kkt[(j, nq + a)] = sc.jac[a * nq + j];
            }
            rhs[(nq + a, 0)] = sc.rc[a];
        }
        use faer::linalg::solvers::Solve;
        let sol = kkt.partial_piv_lu().solve(&rhs);
        for j in 0..nq {
            let d = (sol[(j, 0)] - sc.qdd[j]).abs();
            assert!(
                d <= 1e-9 * sol[(j, 0)].abs().max(1.0),
                "q̈[{j}]: {} vs {}",
                sol[(j, 0)],
                sc.qdd[j]
            );
        }
        for a in 0..nc {
            let d = (sol[(nq + a, 0)] - sc.lam[a]).abs();
            assert!(d <= 1e-9 * sol[(nq + a, 0)].abs().max(1.0), "λ[{a}]");
        }
    }
}
