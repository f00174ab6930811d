//! Bodies: how each moves (integrated or prescribed), the prescriptions of driven bodies, and
//! where a force on a body goes.
//!
//! ```text
//! prescribed body: a rotational driver φ = θ₀ + ω t and a revolute joint to the ground or to
//!   another prescribed body (the press's crank): its pose, velocity and acceleration are
//!   closed-form functions of t, and that driver and pin are not constraint equations
//! integrated body: its (x, y, φ) are coordinates of q, in scene order
//! ```
//! Source: docs/model.md §1.1–§1.2.

use std::collections::BTreeMap;

use crate::mechanism::scratch::Scratch;
use crate::planar::{cross, perp, rot};
use crate::scene::format::{JointSpec, Scene};
use crate::scene::refs::point_of;
use crate::scene::refs::GROUND;

/// How a body moves: integrated (index into q) or prescribed (index into the prescriptions).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Owner {
    Int(usize),
    Pres(usize),
}

/// A body of the scene, resolved.
#[derive(Clone, Debug)]
pub(crate) struct BodyInfo {
    pub name: String,
    pub mass: f64,
    pub inertia: f64,
    pub points: BTreeMap<String, [f64; 2]>,
    pub owner: Owner,
}

impl BodyInfo {
    /// `body 'rod' (mass … kg, inertia … kg·m²)`, for messages.
    pub(crate) fn describe(&self) -> String {
        format!(
            "body '{}' (mass {:e} kg, inertia {:e} kg·m²)",
            self.name, self.mass, self.inertia
        )
    }
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

/// Every body of a mechanism: who moves how, and the prescriptions.
#[derive(Clone, Debug)]
pub(crate) struct Bodies {
    /// Every body, in scene order.
    pub info: Vec<BodyInfo>,
    /// Scene index of integrated body i.
    pub int_bodies: Vec<usize>,
    /// The prescriptions, parents before children.
    pub pres: Vec<Prescription>,
    /// The joints that prescriptions consumed (drivers and their pins): no equations.
    pub used: Vec<bool>,
}

impl Bodies {
    /// Build phase 1: drivers with a revolute joint to the ground or to a prescribed body make
    /// their body prescribed (repeated until nothing changes); every other body is integrated.
    pub(crate) fn prescribe(scene: &Scene) -> Bodies {
        let nb = scene.bodies.len();
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
        let info = scene
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
        Bodies {
            info,
            int_bodies,
            pres,
            used,
        }
    }

    /// Number of integrated coordinates n_q.
    pub(crate) fn nq(&self) -> usize {
        3 * self.int_bodies.len()
    }

    /// The integrated index of every body (None: prescribed).
    pub(crate) fn int_of(&self) -> Vec<Option<usize>> {
        self.info
            .iter()
            .map(|b| match b.owner {
                Owner::Int(i) => Some(i),
                Owner::Pres(_) => None,
            })
            .collect()
    }

    /// M⁻¹ of the integrated coordinates: (1/m, 1/m, 1/I) per body.
    pub(crate) fn inverse_masses(&self) -> Vec<f64> {
        let mut minv = Vec::with_capacity(self.nq());
        for &k in &self.int_bodies {
            let b = &self.info[k];
            minv.extend_from_slice(&[1.0 / b.mass, 1.0 / b.mass, 1.0 / b.inertia]);
        }
        minv
    }

    /// Poses and velocities of every body at t from the absolute (q, q̇) of the integrated
    /// bodies; accelerations of the prescribed bodies.
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
        self.prescribed_kinematics(t, sc);
    }

    /// Poses, velocities and accelerations of the prescribed bodies at t (they depend on t
    /// alone: a prescribed body's parent is the ground or another prescribed body). Kept when
    /// `sc` holds them at this t already (`Scratch::pres_t`, the same bits of t: the same
    /// result): a step's Newton iterations, its events and its Jacobian share one t.
    #[inline]
    pub(crate) fn prescribed_kinematics(&self, t: f64, sc: &mut Scratch) {
        if self.pres.is_empty() || sc.pres_t == Some(t.to_bits()) {
            return;
        }
        self.compute_prescribed(t, sc);
        sc.pres_t = Some(t.to_bits());
    }

    /// [`Bodies::prescribed_kinematics`], computed.
    #[inline]
    fn compute_prescribed(&self, t: f64, sc: &mut Scratch) {
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

    /// Adds force f at the global arm (from the centre of mass) to body k: to g when it is
    /// integrated, and (full evaluations) to its applied forces.
    #[inline]
    pub(crate) fn apply(&self, k: usize, arm: [f64; 2], f: [f64; 2], sc: &mut Scratch, full: bool) {
        self.apply_to(k, arm, f, &mut sc.g, &mut sc.gb, full);
    }

    /// [`Bodies::apply`] into the force buffers `g` and `gb` of a scratch (the rest of it may
    /// be borrowed meanwhile).
    #[inline]
    pub(crate) fn apply_to(
        &self,
        k: usize,
        arm: [f64; 2],
        f: [f64; 2],
        g: &mut [f64],
        gb: &mut [[f64; 3]],
        full: bool,
    ) {
        let mz = cross(arm, f);
        match self.info[k].owner {
            Owner::Int(i) => {
                g[3 * i] += f[0];
                g[3 * i + 1] += f[1];
                g[3 * i + 2] += mz;
            }
            Owner::Pres(_) => {}
        }
        if full {
            gb[k][0] += f[0];
            gb[k][1] += f[1];
            gb[k][2] += mz;
        }
    }

    /// Adds a torque to body k (see [`Bodies::apply`]).
    #[inline]
    pub(crate) fn apply_torque(&self, k: usize, tau: f64, sc: &mut Scratch, full: bool) {
        match self.info[k].owner {
            Owner::Int(i) => sc.g[3 * i + 2] += tau,
            Owner::Pres(_) => {}
        }
        if full {
            sc.gb[k][2] += tau;
        }
    }
}
