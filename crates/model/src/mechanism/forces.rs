//! The force side of a mechanism: gravity, the clearance joints (revolute and prismatic) and
//! the force elements, which add applied forces to g (docs/model.md §1.3, §2–§4, §10–§11) —
//! and their Jacobian ∂g/∂(q, q̇) in absolute coordinates.
//!
//! ```text
//! g = gravity + Σ revolute clearance joints (contact at Q_J, Q_B; film at the centres)
//!             + Σ force elements + Σ prismatic clearance joints (corner contacts)
//! ∂g/∂y: each revolute clearance joint's (clearance/revolute_jacobian.rs); each element's
//!        closed form where it has one; the other elements and the prismatic joints together
//!        by central differences in y, steps h_j = 1e-8 · max(|y_j|, 1e-2) (positions) and
//!        1e-8 · max(|y_j|, 1e-3) (velocities)
//! ```
//! Absent features (gravity, friction, film, force elements) run no code.

use crate::clearance::prismatic::Prismatic;
use crate::clearance::revolute::{Revolute, BEARING, JOURNAL};
use crate::elements::input::Load;
use crate::elements::interface::ForceJacobian;
use crate::elements::Element;
use crate::linalg::zeroed;
use crate::mechanism::bodies::Bodies;
use crate::mechanism::scratch::Scratch;
use crate::planar::cross;
use crate::scene::format::{JointSpec, Scene};

/// Everything that puts forces on the bodies, compiled.
#[derive(Debug)]
pub(crate) struct Forces {
    /// Gravity (m/s²); None when zero.
    pub gravity: Option<[f64; 2]>,
    /// The revolute clearance joints, in scene order.
    pub revolute: Vec<Revolute>,
    /// The prismatic clearance joints, in scene order.
    pub prismatic: Vec<Prismatic>,
    /// The force elements, in scene order.
    pub elements: Vec<Element>,
    /// The small-tree path's tables, made once (`Forces::build`): m g of every integrated
    /// body (by integrated index; empty without gravity) and the integrated index of each
    /// revolute clearance joint's ends ([`JOURNAL`], [`BEARING`]; None: the ground or a
    /// prescribed body).
    small: SmallTables,
    /// The integrated index of every scene body ([`Bodies::int_of`]; None: the ground or a
    /// prescribed body), made once: the small path's tables and the Jacobian read it.
    int_of: Vec<Option<usize>>,
}

/// The tables of [`Forces::applied_small`] (see [`Forces`]).
#[derive(Debug)]
struct SmallTables {
    weight: Vec<[f64; 2]>,
    revolute_ends: Vec<[Option<usize>; 2]>,
}

/// The buffers of [`Forces::jacobian`], kept with the mechanism.
#[derive(Debug, Default)]
pub(crate) struct ForceJacWork {
    /// ∂g/∂(q, q̇), nq × n column-major.
    pub dg: Vec<f64>,
}

impl Forces {
    /// Build phase: the clearance joints and force elements of a validated scene (the
    /// elements' defaults of the initial state are set after the assembly: `set_initial`).
    pub(crate) fn build(scene: &Scene, bodies: &Bodies) -> Forces {
        let mut revolute = Vec::new();
        let mut prismatic = Vec::new();
        for (ji, joint) in scene.joints.iter().enumerate() {
            match joint {
                JointSpec::Clearance(c) => revolute.push(Revolute::new(scene, ji, c)),
                JointSpec::PrismaticClearance(c) => prismatic.push(Prismatic::new(scene, ji, c)),
                _ => {}
            }
        }
        let gravity = (scene.gravity != [0.0, 0.0]).then_some(scene.gravity);
        let int_of = bodies.int_of();
        let small = SmallTables {
            // The products of `applied`'s gravity loop.
            weight: gravity.map_or(Vec::new(), |gv| {
                let w = |k: usize| {
                    let m = bodies.info[k].mass;
                    [m * gv[0], m * gv[1]]
                };
                bodies.int_bodies.iter().map(|&k| w(k)).collect()
            }),
            revolute_ends: revolute
                .iter()
                .map(|c| {
                    let mut ends = [None; 2];
                    ends[JOURNAL] = c.journal.body.and_then(|b| int_of[b]);
                    ends[BEARING] = c.bearing.body.and_then(|b| int_of[b]);
                    ends
                })
                .collect(),
        };
        Forces {
            gravity,
            revolute,
            prismatic,
            elements: scene.forces.iter().map(|f| f.compile(scene)).collect(),
            small,
            int_of,
        }
    }

    /// Sets the elements' defaults from the kinematics at t₀ in `sc` (a spring's free length).
    pub(crate) fn set_initial(&mut self, t0: f64, sc: &Scratch) {
        let kin = sc.kin();
        for e in &mut self.elements {
            e.set_initial(t0, &kin);
        }
    }

    /// Applied forces into `sc.g` (and `sc.gb` in full evaluations), after the kinematics:
    /// gravity and the revolute clearance joints, then the force elements and prismatic
    /// clearance joints when the scene has any.
    pub(crate) fn applied(&self, bodies: &Bodies, t: f64, sc: &mut Scratch, full: bool) {
        sc.g.iter_mut().for_each(|v| *v = 0.0);
        if full {
            sc.gb.iter_mut().for_each(|v| *v = [0.0; 3]);
        }
        if let Some(gv) = self.gravity {
            for (i, &k) in bodies.int_bodies.iter().enumerate() {
                let m = bodies.info[k].mass;
                sc.g[3 * i] += m * gv[0];
                sc.g[3 * i + 1] += m * gv[1];
            }
            if full {
                for (k, b) in bodies.info.iter().enumerate() {
                    sc.gb[k][0] += b.mass * gv[0];
                    sc.gb[k][1] += b.mass * gv[1];
                }
            }
        }
        for (k, c) in self.revolute.iter().enumerate() {
            // Written in its slot and its loads handed over one by one from there: no copy of
            // the evaluation or of an array of loads (memcpy was 8 % of a right-hand side of
            // the lubricated press under minimal).
            sc.revolute[k] = c.forces(c.state(&sc.kin()));
            let (ev, cs, g, gb) = (&sc.revolute[k], &sc.cs, &mut sc.g, &mut sc.gb);
            c.each_load(ev, cs, |(b, arm, f)| {
                bodies.apply_to(b, arm, f, g, gb, full)
            });
        }
        if !(self.elements.is_empty() && self.prismatic.is_empty()) {
            self.element_forces(bodies, t, sc, full, &[]);
        }
    }

    /// [`Forces::applied`] into `g` (one row (f_x, f_y, m_z) per integrated body, by integrated
    /// index, +0 on entry) instead of `sc.g`: the small-tree right-hand side's (minimal,
    /// formulation/minimal/small.rs). Each entry's terms in the order and by the expressions
    /// of [`Forces::applied`] (gravity, then each revolute clearance joint's loads, then the
    /// elements and prismatic joints through `sc.g`), so its bits; no clearance evaluation is
    /// kept in `sc.revolute` and no elastic part computed (what reads them runs
    /// [`Forces::applied`] itself: outputs, the Jacobian, full evaluations).
    /// The products m g and each joint end's integrated body come from tables made once
    /// (`SmallTables`), the joint's state and forces are inlined (no call, no evaluation in
    /// memory): the same operations.
    #[inline(always)]
    pub(crate) fn applied_small(
        &self,
        bodies: &Bodies,
        t: f64,
        sc: &mut Scratch,
        g: &mut [[f64; 3]],
    ) {
        for (gi, w) in g.iter_mut().zip(&self.small.weight) {
            gi[0] += w[0];
            gi[1] += w[1];
        }
        for (c, ends) in self.revolute.iter().zip(&self.small.revolute_ends) {
            let ev = c.forces_only(c.state_inline(&sc.kin()));
            c.each_load_at(&ev, &sc.cs, |end, (_, arm, f)| {
                if let Some(i) = ends[end] {
                    let gi = &mut g[i];
                    gi[0] += f[0];
                    gi[1] += f[1];
                    gi[2] += cross(arm, f);
                }
            });
        }
        if !(self.elements.is_empty() && self.prismatic.is_empty()) {
            // Through sc.g, added to what is there (as in Forces::applied).
            for (d, gi) in sc.g.chunks_exact_mut(3).zip(g.iter()) {
                d.copy_from_slice(gi);
            }
            self.element_forces(bodies, t, sc, false, &[]);
            for (gi, d) in g.iter_mut().zip(sc.g.chunks_exact(3)) {
                gi.copy_from_slice(d);
            }
        }
    }

    /// The force elements and prismatic clearance joints (docs/model.md §10–§11), after the
    /// kinematics; the elements `i` with `skip[i]` (a shorter `skip`: none beyond it) are
    /// left out.
    pub(crate) fn element_forces(
        &self,
        bodies: &Bodies,
        t: f64,
        sc: &mut Scratch,
        full: bool,
        skip: &[bool],
    ) {
        let mut loads: [Load; 4] = [(0, [0.0; 2], [0.0; 2], 0.0); 4];
        for (i, e) in self.elements.iter().enumerate() {
            if skip.get(i) == Some(&true) {
                continue;
            }
            let mut n = 0;
            let ev = e.eval(t, &sc.kin(), |l| {
                loads[n] = l;
                n += 1;
            });
            for l in &loads[..n] {
                apply_load(bodies, *l, sc, full);
            }
            sc.el[i] = ev;
        }
        for (i, p) in self.prismatic.iter().enumerate() {
            let mut n = 0;
            let ev = p.eval(&sc.kin(), |l| {
                loads[n] = l;
                n += 1;
            });
            for l in &loads[..n] {
                apply_load(bodies, *l, sc, full);
            }
            sc.pr[i] = ev;
        }
    }

    /// ∂g/∂(q, q̇) (nq × n, column-major, into `fw.dg`) at the evaluation in `sc` (module doc).
    pub(crate) fn jacobian(&self, bodies: &Bodies, t: f64, sc: &Scratch, fw: &mut ForceJacWork) {
        self.revolute_jacobian(bodies, sc, fw);
        if !(self.elements.is_empty() && self.prismatic.is_empty()) {
            self.element_jacobian(bodies, t, sc, &mut fw.dg);
        }
    }

    /// `fw.dg` zeroed (nq × 2nq) with the revolute clearance joints' closed forms added.
    fn revolute_jacobian(&self, bodies: &Bodies, sc: &Scratch, fw: &mut ForceJacWork) {
        let nq = bodies.nq();
        let n = 2 * nq;
        let dg = zeroed(&mut fw.dg, nq * n);
        let kin = sc.kin();
        for (c, ev) in self.revolute.iter().zip(&sc.revolute) {
            c.force_jacobian(ev, &kin, &self.int_of, n, dg);
        }
    }

    /// Whether ∂g/∂(q, q̇) can be nonzero: some clearance joint or force element acts
    /// (gravity is constant).
    pub(crate) fn has_jacobian(&self) -> bool {
        !(self.revolute.is_empty() && self.elements.is_empty() && self.prismatic.is_empty())
    }

    /// [`Forces::jacobian`] where every part of it is a closed form (no prismatic clearance
    /// joint, every force element with its own): true; false where some part would be
    /// differenced (`fw.dg` is then incomplete).
    pub(crate) fn closed_jacobian(
        &self,
        bodies: &Bodies,
        t: f64,
        sc: &Scratch,
        fw: &mut ForceJacWork,
    ) -> bool {
        if !self.prismatic.is_empty() {
            return false;
        }
        self.revolute_jacobian(bodies, sc, fw);
        let kin = sc.kin();
        let mut fj = ForceJacobian {
            int_of: &self.int_of,
            nq: bodies.nq(),
            dg: &mut fw.dg,
        };
        self.elements.iter().all(|e| e.jacobian(t, &kin, &mut fj))
    }

    /// Adds ∂g/∂y of the force elements and prismatic clearance joints (nq × n, column-major):
    /// each element's closed form where it has one, then central differences of the
    /// generalized forces of the others and of the prismatic clearance joints, all together.
    fn element_jacobian(&self, bodies: &Bodies, t: f64, sc: &Scratch, dg: &mut [f64]) {
        let nq = bodies.nq();
        let n = 2 * nq;
        let kin = sc.kin();
        let mut fj = ForceJacobian {
            int_of: &self.int_of,
            nq,
            dg: &mut *dg,
        };
        let closed: Vec<bool> = self
            .elements
            .iter()
            .map(|e| e.jacobian(t, &kin, &mut fj))
            .collect();
        if self.prismatic.is_empty() && closed.iter().all(|&c| c) {
            return;
        }
        // The absolute (q, q̇) of the integrated bodies.
        let mut y = vec![0.0; n];
        for (i, &k) in bodies.int_bodies.iter().enumerate() {
            y[3 * i..3 * i + 3].copy_from_slice(&sc.pose[k]);
            y[nq + 3 * i..nq + 3 * i + 3].copy_from_slice(&sc.vel[k]);
        }
        let mut s2 = sc.clone();
        let mut yp = y.clone();
        let mut gp = vec![0.0; nq];
        let mut gm = vec![0.0; nq];
        let g_of = |yp: &[f64], s2: &mut Scratch, out: &mut [f64]| {
            bodies.kinematics(t, yp, s2);
            s2.g.iter_mut().for_each(|v| *v = 0.0);
            self.element_forces(bodies, t, s2, false, &closed);
            out.copy_from_slice(&s2.g);
        };
        for j in 0..n {
            let floor = if j < nq { 1e-2 } else { 1e-3 };
            let h = 1e-8 * y[j].abs().max(floor);
            yp[j] = y[j] + h;
            let hp = yp[j] - y[j];
            g_of(&yp, &mut s2, &mut gp);
            yp[j] = y[j] - h;
            let hm = y[j] - yp[j];
            g_of(&yp, &mut s2, &mut gm);
            yp[j] = y[j];
            let col = &mut dg[j * nq..(j + 1) * nq];
            for ((c, p), m) in col.iter_mut().zip(&gp).zip(&gm) {
                *c += (p - m) / (hp + hm);
            }
        }
    }
}

/// Adds a load (body, arm, force, torque) to the generalized forces.
#[inline]
fn apply_load(bodies: &Bodies, l: Load, sc: &mut Scratch, full: bool) {
    let (k, arm, f, tau) = l;
    bodies.apply(k, arm, f, sc, full);
    if tau != 0.0 {
        bodies.apply_torque(k, tau, sc, full);
    }
}
