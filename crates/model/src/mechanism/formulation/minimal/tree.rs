//! The spanning tree of the ideal joints and the recursive kinematics on it.
//!
//! ```text
//! roots      the ground and the prescribed bodies (their motion is a function of t)
//! tree joint a revolute joint or a translational joint that reaches a body not yet placed
//!            from a placed one (scene order, repeated until nothing changes); a body that
//!            no ideal joint reaches is free
//! link       revolute to parent p:  θ = φ_k            r_k = r_p + A_p s_p − A_k s_k
//!            translational:         θ = σ (along u)    r_k = o + σ u − A(φ₀) s,  φ_k = φ₀
//!            free:                  θ = (x, y, φ)
//! ```
//! Velocities and accelerations follow by differentiating the positions (b = perp(A s) =
//! ∂(A s)/∂φ):
//! ```text
//! revolute  v_k = v_p + ω_p b_p − ω_k b_k
//!           a_k = a_p + α_p b_p − ω_p² A_p s_p − α_k b_k + ω_k² A_k s_k
//! ```
//! so q̇ = R(θ) θ̇ + b(t) (b: the prescribed parents' motion) and q̈ = R θ̈ + a_c(t, θ, θ̇)
//! (a_c: the accelerations with θ̈ = 0). A revolute link's coordinate is the body's absolute
//! angle φ_k, not the angle relative to its parent: the two differ by a constant linear
//! change of the coordinates (θ_rel = φ_k − φ_p), which leaves the trajectory of every body
//! the same and keeps R's angle rows unit vectors.
//!
//! A joint with equations that the tree does not take (one that closes a loop, or a driver
//! of an integrated body) is refused by the minimal formulation (mod.rs).

use crate::mechanism::bodies::{Bodies, Owner};
use crate::mechanism::scratch::Scratch;
use crate::planar::{dot, perp, rot};
use crate::scene::format::{JointSpec, Scene};
use crate::scene::refs::{point_of, Attachment, GROUND};

/// The parent of a revolute link.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Parent {
    /// The ground, at this location (m).
    Ground([f64; 2]),
    /// A prescribed body (scene index) and its local point.
    Prescribed(usize, [f64; 2]),
    /// An integrated body (scene index, integrated index) and its local point.
    Integrated(usize, usize, [f64; 2]),
}

/// How a body hangs from its parent.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Link {
    /// No ideal joint reaches it: θ = (x, y, φ).
    Free,
    /// A revolute joint at its local point `s` to `parent`: θ = φ.
    Revolute {
        /// The parent and its point.
        parent: Parent,
        /// The body's own point.
        s: [f64; 2],
    },
    /// A translational joint to the ground: θ = σ, r^P = o + σ u, φ = φ₀.
    Slider {
        /// A point of the line (m).
        origin: [f64; 2],
        /// Unit direction of the line.
        u: [f64; 2],
        /// The body's fixed angle (rad).
        phi0: f64,
        /// The body's point on the line.
        s: [f64; 2],
        /// (cos φ₀, sin φ₀) and A(φ₀) s, constant (computed once: the kinematics ran sin_cos
        /// of the fixed angle at every evaluation).
        cs0: [f64; 2],
        a0: [f64; 2],
    },
}

impl Link {
    /// Coordinates it adds.
    pub(crate) fn dof(&self) -> usize {
        match self {
            Link::Free => 3,
            Link::Revolute { .. } | Link::Slider { .. } => 1,
        }
    }
}

/// A body of the tree.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TreeBody {
    /// Scene index.
    pub body: usize,
    /// Integrated index (its coordinates are q[3 int..3 int + 3]).
    pub int: usize,
    /// Its link to its parent.
    pub link: Link,
    /// Its first coordinate in θ.
    pub col: usize,
}

/// The spanning tree: the integrated bodies, parents before children.
#[derive(Clone, Debug)]
pub(crate) struct Tree {
    /// Every integrated body, parents before children.
    pub bodies: Vec<TreeBody>,
    /// Number of coordinates θ.
    pub n: usize,
    /// The joints with equations the tree does not take (they close loops), in scene order.
    pub closing: Vec<usize>,
    /// For each integrated body (by integrated index), the columns of R that can be nonzero
    /// in its rows — its own coordinates and its integrated ancestors', ascending — at
    /// `reach[reach_at[i]..reach_at[i + 1]]` ([`Tree::columns_of`]).
    reach: Vec<usize>,
    reach_at: Vec<usize>,
    /// For each coordinate of θ, the bodies (indices into `bodies`, in its order) that it
    /// moves — its own body and that body's descendants — at
    /// `moved[moved_at[c]..moved_at[c + 1]]` ([`Tree::moved_by`]).
    moved: Vec<usize>,
    moved_at: Vec<usize>,
    /// For each coordinate, the rows of q of the bodies it moves, ascending
    /// ([`Tree::rows_moved_by`]), at `rows[rows_at[c]..rows_at[c + 1]]`.
    rows: Vec<usize>,
    rows_at: Vec<usize>,
}

/// The child, its own point and its parent, when joint `own`–`other` reaches a body not yet
/// placed from a placed one (or the ground).
fn reach(
    scene: &Scene,
    bodies: &Bodies,
    placed: &[bool],
    own: &Attachment,
    other: &Attachment,
) -> Option<(usize, [f64; 2], Parent)> {
    if own.body == GROUND {
        return None;
    }
    let k = scene.body_index(&own.body)?;
    if placed[k] {
        return None;
    }
    let parent = if other.body == GROUND {
        Parent::Ground(other.at?)
    } else {
        let ko = scene.body_index(&other.body)?;
        if !placed[ko] {
            return None;
        }
        let sp = point_of(scene, other);
        match bodies.info[ko].owner {
            Owner::Pres(_) => Parent::Prescribed(ko, sp),
            Owner::Int(i) => Parent::Integrated(ko, i, sp),
        }
    };
    Some((k, point_of(scene, own), parent))
}

/// [`Tree::rows_moved_by`] of every coordinate, flattened (rows, start of each coordinate's),
/// from [`moved_of`]'s lists.
fn rows_of(bodies: &[TreeBody], moved: &[usize], moved_at: &[usize]) -> (Vec<usize>, Vec<usize>) {
    let mut rows = Vec::new();
    let mut at = vec![0];
    for c in moved_at.windows(2) {
        let mut ints: Vec<usize> = moved[c[0]..c[1]].iter().map(|&b| bodies[b].int).collect();
        ints.sort_unstable();
        rows.extend(ints.iter().flat_map(|&i| 3 * i..3 * i + 3));
        at.push(rows.len());
    }
    (rows, at)
}

/// [`Tree::moved_by`] of every coordinate, flattened: (bodies, start of each coordinate's).
fn moved_of(bodies: &[TreeBody]) -> (Vec<usize>, Vec<usize>) {
    let nbi = bodies.iter().map(|b| b.int + 1).max().unwrap_or(0);
    let mut parent_int = vec![None; nbi];
    for tb in bodies {
        if let Link::Revolute {
            parent: Parent::Integrated(_, ip, _),
            ..
        } = tb.link
        {
            parent_int[tb.int] = Some(ip);
        }
    }
    let descends = |mut int: usize, from: usize| loop {
        if int == from {
            return true;
        }
        match parent_int[int] {
            Some(p) => int = p,
            None => return false,
        }
    };
    let mut moved = Vec::new();
    let mut at = vec![0];
    for owner in bodies {
        for _ in 0..owner.link.dof() {
            moved.extend((0..bodies.len()).filter(|&b| descends(bodies[b].int, owner.int)));
            at.push(moved.len());
        }
    }
    (moved, at)
}

/// [`Tree::columns_of`] of every integrated body, flattened: (columns, start of each body's).
/// `bodies` lists parents before children, so a parent's columns are known before its child's.
fn reach_of(bodies: &[TreeBody]) -> (Vec<usize>, Vec<usize>) {
    let nbi = bodies.iter().map(|b| b.int + 1).max().unwrap_or(0);
    let mut cols: Vec<Vec<usize>> = vec![Vec::new(); nbi];
    for tb in bodies {
        let mut own = match tb.link {
            Link::Revolute {
                parent: Parent::Integrated(_, ip, _),
                ..
            } => cols[ip].clone(),
            _ => Vec::new(),
        };
        own.extend(tb.col..tb.col + tb.link.dof());
        cols[tb.int] = own;
    }
    let mut reach = Vec::new();
    let mut at = vec![0];
    for c in cols {
        reach.extend(c);
        at.push(reach.len());
    }
    (reach, at)
}

impl Tree {
    /// The spanning tree of the ideal joints of `scene` (module doc).
    pub(crate) fn build(scene: &Scene, bodies: &Bodies) -> Tree {
        let nb = bodies.info.len();
        let mut placed: Vec<bool> = bodies
            .info
            .iter()
            .map(|b| matches!(b.owner, Owner::Pres(_)))
            .collect();
        let mut in_tree = vec![false; scene.joints.len()];
        let mut out: Vec<TreeBody> = Vec::new();
        let mut col = 0;
        let mut place = |k: usize, link: Link, out: &mut Vec<TreeBody>| {
            let Owner::Int(int) = bodies.info[k].owner else {
                unreachable!("only integrated bodies are placed")
            };
            out.push(TreeBody {
                body: k,
                int,
                link,
                col,
            });
            col += link.dof();
        };
        loop {
            let mut changed = false;
            for (ji, joint) in scene.joints.iter().enumerate() {
                if bodies.used[ji] || in_tree[ji] {
                    continue;
                }
                let found = match joint {
                    JointSpec::Revolute(r) => reach(scene, bodies, &placed, &r.a, &r.b)
                        .or_else(|| reach(scene, bodies, &placed, &r.b, &r.a))
                        .map(|(k, s, parent)| (k, Link::Revolute { parent, s })),
                    JointSpec::Translational(t) => {
                        let k = scene.body_index(&t.body).expect("validated");
                        (!placed[k]).then(|| {
                            let len = t.direction[0].hypot(t.direction[1]);
                            let phi0 = t.angle.unwrap_or(scene.bodies[k].angle);
                            let s = scene.bodies[k].points[&t.point];
                            let (sn, co) = phi0.sin_cos();
                            let link = Link::Slider {
                                origin: t.origin,
                                u: [t.direction[0] / len, t.direction[1] / len],
                                phi0,
                                s,
                                cs0: [co, sn],
                                a0: rot([co, sn], s),
                            };
                            (k, link)
                        })
                    }
                    _ => None,
                };
                if let Some((k, link)) = found {
                    placed[k] = true;
                    in_tree[ji] = true;
                    place(k, link, &mut out);
                    changed = true;
                }
            }
            if changed {
                continue;
            }
            match (0..nb).find(|&k| !placed[k]) {
                Some(k) => {
                    placed[k] = true;
                    place(k, Link::Free, &mut out);
                }
                None => break,
            }
        }
        let n = out.iter().map(|b| b.link.dof()).sum();
        let closing = scene
            .joints
            .iter()
            .enumerate()
            .filter(|(ji, j)| {
                !bodies.used[*ji]
                    && !in_tree[*ji]
                    && matches!(
                        j,
                        JointSpec::Revolute(_) | JointSpec::Translational(_) | JointSpec::Driver(_)
                    )
            })
            .map(|(ji, _)| ji)
            .collect();
        let (reach, reach_at) = reach_of(&out);
        let (moved, moved_at) = moved_of(&out);
        let (rows, rows_at) = rows_of(&out, &moved, &moved_at);
        Tree {
            bodies: out,
            n,
            closing,
            reach,
            reach_at,
            moved,
            moved_at,
            rows,
            rows_at,
        }
    }

    /// The columns of R that can be nonzero in the rows of integrated body `int`: its own
    /// coordinates and those of its integrated ancestors, ascending. Every other column of R is
    /// +0 in its rows ([`Tree::velocity_matrix`] writes them as 0 + 0·b), so a sum over R's
    /// rows may skip them without changing a bit while R is finite (a sum from +0 never turns
    /// −0, and adding ±0 to a number other than ±0 leaves it as it is).
    #[inline]
    pub(crate) fn columns_of(&self, int: usize) -> &[usize] {
        &self.reach[self.reach_at[int]..self.reach_at[int + 1]]
    }

    /// Whether the tree is flat: every integrated body hangs from the ground or a prescribed
    /// body (no revolute link to an integrated parent), so each body's rows of R reach its
    /// own coordinates only and Rᵀ M R is diagonal (a free body's block diag(m, m, I)).
    pub(crate) fn is_flat(&self) -> bool {
        self.bodies.iter().all(|tb| {
            !matches!(
                tb.link,
                Link::Revolute {
                    parent: Parent::Integrated(..),
                    ..
                }
            )
        })
    }

    /// The bodies that coordinate `c` of θ (or of θ̇) moves, as indices into
    /// [`Tree::bodies`] in its order: the body it belongs to and its descendants. The
    /// kinematics of every other body do not read it.
    #[inline]
    pub(crate) fn moved_by(&self, c: usize) -> &[usize] {
        &self.moved[self.moved_at[c]..self.moved_at[c + 1]]
    }

    /// The rows of q (3 int..3 int + 3) of the bodies [`Tree::moved_by`] `c`, ascending: the
    /// rows where column c of R can be nonzero (the others are +0).
    #[inline]
    pub(crate) fn rows_moved_by(&self, c: usize) -> &[usize] {
        &self.rows[self.rows_at[c]..self.rows_at[c + 1]]
    }

    /// Poses, velocities and (cos φ, sin φ) of the integrated bodies from (θ, θ̇) into `sc`
    /// (the prescribed bodies' must be there already).
    #[inline]
    pub(crate) fn positions(&self, th: &[f64], thd: &[f64], sc: &mut Scratch) {
        for tb in &self.bodies {
            Self::place(tb, th, thd, sc);
        }
    }

    /// [`Tree::positions`] of the bodies `which` (indices into [`Tree::bodies`], ascending)
    /// only, the others' kinematics in `sc` as they are.
    pub(crate) fn positions_of(&self, which: &[usize], th: &[f64], thd: &[f64], sc: &mut Scratch) {
        for &b in which {
            Self::place(&self.bodies[b], th, thd, sc);
        }
    }

    /// One body of [`Tree::positions`] (its parent's kinematics in `sc`).
    #[inline(always)]
    fn place(tb: &TreeBody, th: &[f64], thd: &[f64], sc: &mut Scratch) {
        {
            let k = tb.body;
            let c = tb.col;
            match tb.link {
                Link::Free => {
                    sc.pose[k] = [th[c], th[c + 1], th[c + 2]];
                    sc.vel[k] = [thd[c], thd[c + 1], thd[c + 2]];
                    let (s, co) = th[c + 2].sin_cos();
                    sc.cs[k] = [co, s];
                }
                Link::Slider {
                    origin,
                    u,
                    phi0,
                    cs0,
                    a0: a,
                    ..
                } => {
                    let sig = th[c];
                    sc.cs[k] = cs0;
                    sc.pose[k] = [
                        origin[0] + sig * u[0] - a[0],
                        origin[1] + sig * u[1] - a[1],
                        phi0,
                    ];
                    sc.vel[k] = [thd[c] * u[0], thd[c] * u[1], 0.0];
                }
                Link::Revolute { parent, s } => {
                    let (pp, vp) = match parent {
                        Parent::Ground(at) => (at, [0.0; 2]),
                        Parent::Prescribed(kp, sp) | Parent::Integrated(kp, _, sp) => {
                            let a = rot(sc.cs[kp], sp);
                            let b = perp(a);
                            let [x, y, _] = sc.pose[kp];
                            let [vx, vy, w] = sc.vel[kp];
                            ([x + a[0], y + a[1]], [vx + w * b[0], vy + w * b[1]])
                        }
                    };
                    let phi = th[c];
                    let w = thd[c];
                    let (sn, co) = phi.sin_cos();
                    let a = rot([co, sn], s);
                    let b = perp(a);
                    sc.cs[k] = [co, sn];
                    sc.pose[k] = [pp[0] - a[0], pp[1] - a[1], phi];
                    sc.vel[k] = [vp[0] - w * b[0], vp[1] - w * b[1], w];
                }
            }
        }
    }

    /// Velocities of the integrated bodies from θ̇ into `sc`, at the poses and (cos φ, sin φ)
    /// that [`Tree::positions`] left there: the bits of its velocities for the same (θ, θ̇),
    /// without its sin_cos and poses (a change of θ̇ alone moves no body); of the bodies
    /// `which` only (indices into [`Tree::bodies`], ascending), the others' as they are.
    pub(crate) fn velocities_of(&self, which: &[usize], thd: &[f64], sc: &mut Scratch) {
        for tb in which.iter().map(|&b| &self.bodies[b]) {
            let (k, c) = (tb.body, tb.col);
            sc.vel[k] = match tb.link {
                Link::Free => [thd[c], thd[c + 1], thd[c + 2]],
                Link::Slider { u, .. } => [thd[c] * u[0], thd[c] * u[1], 0.0],
                Link::Revolute { parent, s } => {
                    let vp = match parent {
                        Parent::Ground(_) => [0.0; 2],
                        Parent::Prescribed(kp, sp) | Parent::Integrated(kp, _, sp) => {
                            let b = perp(rot(sc.cs[kp], sp));
                            let [vx, vy, w] = sc.vel[kp];
                            [vx + w * b[0], vy + w * b[1]]
                        }
                    };
                    let w = thd[c];
                    let b = perp(rot(sc.cs[k], s));
                    [vp[0] - w * b[0], vp[1] - w * b[1], w]
                }
            };
        }
    }

    /// R = ∂q/∂θ (n_q × n, column-major) at the positions in `sc` (the Jacobian's reference
    /// in the tests; evaluations take [`Tree::velocity_matrix_and_bias`]).
    #[cfg(test)]
    pub(crate) fn velocity_matrix(&self, sc: &Scratch, nq: usize, r: &mut [f64]) {
        r[..nq * self.n].fill(0.0);
        for tb in &self.bodies {
            Self::rows_of_r(tb, sc, nq, r);
        }
    }

    /// [`Tree::velocity_matrix`] into `r` and a_c ([`Tree::accelerations`] with θ̈ = 0) into
    /// `ac` in one pass over the bodies: each entry by the same expression as the two passes
    /// (the same bits), each body's rotated points read once for both (the reduced
    /// right-hand side's R and a_c).
    pub(crate) fn velocity_matrix_and_bias(
        &self,
        sc: &Scratch,
        nq: usize,
        r: &mut [f64],
        ac: &mut [f64],
    ) {
        r[..nq * self.n].fill(0.0);
        for tb in &self.bodies {
            Self::rows_of_r(tb, sc, nq, r);
            Self::acceleration(tb, sc, None, ac);
        }
    }

    /// [`Tree::velocity_matrix`] in the rows of the bodies `which` only (indices into
    /// [`Tree::bodies`], ascending; their parents' rows in `r` as that would leave them). It
    /// writes the entries that pass writes; the rows' other entries, zero in R at any state,
    /// must be zero in `r` already (as in an R these rows are restored to).
    pub(crate) fn velocity_matrix_of(
        &self,
        which: &[usize],
        sc: &Scratch,
        nq: usize,
        r: &mut [f64],
    ) {
        for tb in which.iter().map(|&b| &self.bodies[b]) {
            Self::rows_of_r(tb, sc, nq, r);
        }
    }

    /// One body's entries of R (its rows' others are zero).
    #[inline(always)]
    fn rows_of_r(tb: &TreeBody, sc: &Scratch, nq: usize, r: &mut [f64]) {
        {
            let (i, c) = (3 * tb.int, tb.col);
            match tb.link {
                Link::Free => {
                    for d in 0..3 {
                        r[(c + d) * nq + i + d] = 1.0;
                    }
                }
                Link::Slider { u, .. } => {
                    r[c * nq + i] = u[0];
                    r[c * nq + i + 1] = u[1];
                }
                Link::Revolute { parent, s } => {
                    let b = perp(rot(sc.cs[tb.body], s));
                    if let Parent::Integrated(kp, ip, sp) = parent {
                        let bp = perp(rot(sc.cs[kp], sp));
                        let ip = 3 * ip;
                        // Only the parent's ancestors' columns (< c) can be nonzero.
                        for j in 0..c {
                            let col = &mut r[j * nq..(j + 1) * nq];
                            let w = col[ip + 2];
                            col[i] = col[ip] + w * bp[0];
                            col[i + 1] = col[ip + 1] + w * bp[1];
                        }
                    }
                    r[c * nq + i] = -b[0];
                    r[c * nq + i + 1] = -b[1];
                    r[c * nq + i + 2] = 1.0;
                }
            }
        }
    }

    /// q̈ of the integrated coordinates (n_q) at the positions and velocities in `sc` for the
    /// given θ̈ (None: θ̈ = 0, which gives a_c).
    pub(crate) fn accelerations(&self, sc: &Scratch, thdd: Option<&[f64]>, out: &mut [f64]) {
        for tb in &self.bodies {
            Self::acceleration(tb, sc, thdd, out);
        }
    }

    /// [`Tree::accelerations`] of the bodies `which` only (indices into [`Tree::bodies`],
    /// ascending; their integrated parents' in `out` as that would leave them).
    pub(crate) fn accelerations_of(
        &self,
        which: &[usize],
        sc: &Scratch,
        thdd: Option<&[f64]>,
        out: &mut [f64],
    ) {
        for &b in which {
            Self::acceleration(&self.bodies[b], sc, thdd, out);
        }
    }

    /// One body of [`Tree::accelerations`].
    #[inline(always)]
    fn acceleration(tb: &TreeBody, sc: &Scratch, thdd: Option<&[f64]>, out: &mut [f64]) {
        let al = |c: usize| thdd.map_or(0.0, |v| v[c]);
        {
            let (i, c, k) = (3 * tb.int, tb.col, tb.body);
            let acc = match tb.link {
                Link::Free => [al(c), al(c + 1), al(c + 2)],
                Link::Slider { u, .. } => [al(c) * u[0], al(c) * u[1], 0.0],
                Link::Revolute { parent, s } => {
                    let ap = match parent {
                        Parent::Ground(_) => [0.0; 2],
                        Parent::Prescribed(kp, sp) | Parent::Integrated(kp, _, sp) => {
                            let [ax, ay, alp] = match parent {
                                Parent::Integrated(_, ip, _) => {
                                    [out[3 * ip], out[3 * ip + 1], out[3 * ip + 2]]
                                }
                                _ => sc.acc[kp],
                            };
                            let a = rot(sc.cs[kp], sp);
                            let b = perp(a);
                            let w = sc.vel[kp][2];
                            [
                                ax + alp * b[0] - w * w * a[0],
                                ay + alp * b[1] - w * w * a[1],
                            ]
                        }
                    };
                    let a = rot(sc.cs[k], s);
                    let b = perp(a);
                    let (w, alk) = (sc.vel[k][2], al(c));
                    [
                        ap[0] - alk * b[0] + w * w * a[0],
                        ap[1] - alk * b[1] + w * w * a[1],
                        alk,
                    ]
                }
            };
            out[i..i + 3].copy_from_slice(&acc);
        }
    }

    /// ∂a_c/∂θ̇_j (a_c: the accelerations at θ̈ = 0, [`Tree::accelerations`] with None) in the
    /// rows of the bodies `which` = [`Tree::moved_by`]`(j)` into `out` (a_c's other rows do
    /// not read θ̇_j), at the positions and velocities in `sc`. a_c is quadratic in the
    /// bodies' angular rates ω and reads θ̇ through them only (a revolute link's θ is its
    /// absolute angle, a slider's is a distance, a free body's (x, y, φ)), so only a
    /// coordinate that is some body m's ω moves it:
    /// ```text
    /// ∂a_m/∂ω_m = 2 ω_m A_m s_m               (m revolute: its own term ω_m² A_m s_m)
    /// ∂a_k/∂ω_m = ∂a_p/∂ω_m − [p = m] 2 ω_m A_m s_p   (k revolute on parent p, descending)
    /// ```
    /// and the angular rows are zero (α = θ̈ or its parent's). Exact: the central difference
    /// of a quadratic in its step, without the rounding of the difference.
    pub(crate) fn rate_derivative_of(
        &self,
        j: usize,
        which: &[usize],
        sc: &Scratch,
        out: &mut [f64],
    ) {
        let Some((&first, rest)) = which.split_first() else {
            return;
        };
        let owner = &self.bodies[first];
        let m = owner.body;
        // Whether θ̇_j is the owner's ω, and the owner's own row.
        let (is_rate, own) = match owner.link {
            Link::Revolute { s, .. } if j == owner.col => {
                let (w, a) = (sc.vel[m][2], rot(sc.cs[m], s));
                (true, [2.0 * w * a[0], 2.0 * w * a[1], 0.0])
            }
            Link::Free if j == owner.col + 2 => (true, [0.0; 3]),
            _ => (false, [0.0; 3]),
        };
        let i = 3 * owner.int;
        out[i..i + 3].copy_from_slice(&own);
        let w2 = 2.0 * sc.vel[m][2];
        for tb in rest.iter().map(|&b| &self.bodies[b]) {
            let i = 3 * tb.int;
            let d = match tb.link {
                Link::Revolute {
                    parent: Parent::Integrated(kp, ip, sp),
                    ..
                } if is_rate => {
                    let (x, y) = (out[3 * ip], out[3 * ip + 1]);
                    if kp == m {
                        let a = rot(sc.cs[m], sp);
                        [x - w2 * a[0], y - w2 * a[1], 0.0]
                    } else {
                        [x, y, 0.0]
                    }
                }
                // A descendant hangs from an integrated parent by a revolute link; a
                // coordinate that is no ω moves no a_c.
                _ => [0.0; 3],
            };
            out[i..i + 3].copy_from_slice(&d);
        }
    }

    /// θ of the absolute (q, q̇) of the integrated bodies (the inverse of
    /// [`Tree::positions`] on the constraint manifold).
    pub(crate) fn state_of(&self, y_abs: &[f64]) -> Vec<f64> {
        let nq = y_abs.len() / 2;
        let n = self.n;
        let mut y = vec![0.0; 2 * n];
        for tb in &self.bodies {
            let (i, c) = (3 * tb.int, tb.col);
            let q = &y_abs[i..i + 3];
            let v = &y_abs[nq + i..nq + i + 3];
            match tb.link {
                Link::Free => {
                    y[c..c + 3].copy_from_slice(q);
                    y[n + c..n + c + 3].copy_from_slice(v);
                }
                Link::Revolute { .. } => {
                    y[c] = q[2];
                    y[n + c] = v[2];
                }
                Link::Slider { origin, u, s, .. } => {
                    let (sn, co) = q[2].sin_cos();
                    let a = rot([co, sn], s);
                    let b = perp(a);
                    y[c] = dot(u, [q[0] + a[0] - origin[0], q[1] + a[1] - origin[1]]);
                    y[n + c] = dot(u, [v[0] + v[2] * b[0], v[1] + v[2] * b[1]]);
                }
            }
        }
        y
    }
}
