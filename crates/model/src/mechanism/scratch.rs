//! The buffers of one evaluation of a mechanism (no allocation in a right-hand side).
//!
//! ```text
//! pose, vel, acc, cs   every body (scene order): (x, y, φ), (ẋ, ẏ, φ̇), (ẍ, ÿ, φ̈), (cos φ, sin φ)
//! g                    applied generalized forces on the integrated coordinates (n_q)
//! gb                   applied forces on every body (full evaluations: Newton–Euler, outputs)
//! qdd                  q̈ of the integrated coordinates, as the formulation solved it
//! revolute, el, pr     what each clearance joint, force element, prismatic joint did
//! pres_t               the t (its bits) of the prescribed bodies' kinematics in pose, vel,
//!                      acc, cs (functions of t alone): a right-hand side, the events and the
//!                      Jacobian at the t of the last evaluation skip recomputing them
//! ```
//! `pres_t` is set by `Bodies::prescribed_kinematics` and travels with every copy of the
//! kinematics (`clone`, `clone_from`, [`Scratch::copy_kinematics_from`]); whatever writes the
//! prescribed bodies' kinematics another way must clear it.

use crate::clearance::prismatic::PrismaticEval;
use crate::clearance::revolute::RevoluteEval;
use crate::elements::input::Kin;
use crate::elements::interface::ElementEval;

/// Buffers of one evaluation (module doc). `clone_from` copies into the existing buffers
/// (no allocation once they have the size): what a full evaluation's copy uses
/// ([`crate::mechanism::Mechanism::full_evaluation`]).
#[derive(Debug)]
pub(crate) struct Scratch {
    pub pose: Vec<[f64; 3]>,
    pub vel: Vec<[f64; 3]>,
    pub acc: Vec<[f64; 3]>,
    pub cs: Vec<[f64; 2]>,
    /// Applied generalized forces on integrated coordinates.
    pub g: Vec<f64>,
    /// Applied forces on every body (filled in full evaluations, for Newton–Euler and outputs).
    pub gb: Vec<[f64; 3]>,
    /// q̈ of the integrated coordinates.
    pub qdd: Vec<f64>,
    /// Every revolute clearance joint (docs/model.md §2–§4).
    pub revolute: Vec<RevoluteEval>,
    /// Every force element (docs/model.md §10).
    pub el: Vec<ElementEval>,
    /// Every prismatic clearance joint (docs/model.md §11).
    pub pr: Vec<PrismaticEval>,
    /// The bits of the t at which the prescribed bodies' kinematics were computed; None:
    /// not known (module doc).
    pub pres_t: Option<u64>,
}

impl Clone for Scratch {
    fn clone(&self) -> Scratch {
        Scratch {
            pose: self.pose.clone(),
            vel: self.vel.clone(),
            acc: self.acc.clone(),
            cs: self.cs.clone(),
            g: self.g.clone(),
            gb: self.gb.clone(),
            qdd: self.qdd.clone(),
            revolute: self.revolute.clone(),
            el: self.el.clone(),
            pr: self.pr.clone(),
            pres_t: self.pres_t,
        }
    }

    fn clone_from(&mut self, o: &Scratch) {
        self.pose.clone_from(&o.pose);
        self.vel.clone_from(&o.vel);
        self.acc.clone_from(&o.acc);
        self.cs.clone_from(&o.cs);
        self.g.clone_from(&o.g);
        self.gb.clone_from(&o.gb);
        self.qdd.clone_from(&o.qdd);
        self.revolute.clone_from(&o.revolute);
        self.el.clone_from(&o.el);
        self.pr.clone_from(&o.pr);
        self.pres_t = o.pres_t;
    }
}

impl Scratch {
    /// No buffers (no allocation): a placeholder, or the start of a `clone_from`.
    pub(crate) fn empty() -> Scratch {
        Scratch::new(0, 0, 0, 0, 0)
    }

    /// Buffers for `nb` bodies, `nq` integrated coordinates and the given numbers of revolute
    /// clearance joints, force elements and prismatic clearance joints.
    pub(crate) fn new(nb: usize, nq: usize, n_rev: usize, n_el: usize, n_pr: usize) -> Scratch {
        Scratch {
            pose: vec![[0.0; 3]; nb],
            vel: vec![[0.0; 3]; nb],
            acc: vec![[0.0; 3]; nb],
            cs: vec![[1.0, 0.0]; nb],
            g: vec![0.0; nq],
            gb: vec![[0.0; 3]; nb],
            qdd: vec![0.0; nq],
            revolute: vec![RevoluteEval::default(); n_rev],
            el: vec![ElementEval::default(); n_el],
            pr: vec![PrismaticEval::default(); n_pr],
            pres_t: None,
        }
    }

    /// Copies the poses, velocities, accelerations and (cos φ, sin φ) of every body from `o`
    /// (the same number of bodies), with the t of its prescribed bodies' kinematics.
    pub(crate) fn copy_kinematics_from(&mut self, o: &Scratch) {
        self.pose.copy_from_slice(&o.pose);
        self.vel.copy_from_slice(&o.vel);
        self.acc.copy_from_slice(&o.acc);
        self.cs.copy_from_slice(&o.cs);
        self.pres_t = o.pres_t;
    }

    /// The poses, velocities and (cos φ, sin φ) of every body.
    #[inline]
    pub(crate) fn kin(&self) -> Kin<'_> {
        Kin {
            pose: &self.pose,
            vel: &self.vel,
            cs: &self.cs,
        }
    }
}
