//! The buffers of one evaluation of a mechanism (no allocation in a right-hand side).
//!
//! ```text
//! pose, vel, acc, cs   every body (scene order): (x, y, φ), (ẋ, ẏ, φ̇), (ẍ, ÿ, φ̈), (cos φ, sin φ)
//! g                    applied generalized forces on the integrated coordinates (n_q)
//! gb                   applied forces on every body (full evaluations: Newton–Euler, outputs)
//! qdd                  q̈ of the integrated coordinates, as the formulation solved it
//! revolute, el, pr     what each clearance joint, force element, prismatic joint did
//! ```

use crate::clearance::prismatic::PrismaticEval;
use crate::clearance::revolute::RevoluteEval;
use crate::elements::input::Kin;
use crate::elements::interface::ElementEval;

/// Buffers of one evaluation (module doc).
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
    /// q̈ of the integrated coordinates.
    pub qdd: Vec<f64>,
    /// Every revolute clearance joint (docs/model.md §2–§4).
    pub revolute: Vec<RevoluteEval>,
    /// Every force element (docs/model.md §10).
    pub el: Vec<ElementEval>,
    /// Every prismatic clearance joint (docs/model.md §11).
    pub pr: Vec<PrismaticEval>,
}

impl Scratch {
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
        }
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
