//! θ̈ on a flat tree (`Tree::is_flat`: every integrated body on the ground or on a prescribed
//! body, M̄ = Rᵀ M R diagonal), planned once at assembly, coordinate by coordinate.
//!
//! ```text
//! each coordinate c of its body b (column r of R_b, a_c,b, masses m = (m, m, I)):
//!   M̄_cc = Σ_rows r m r,  Q̄_c = Σ_rows r (g_b − m a_c,b),  l = 1/√M̄_cc,  θ̈_c = (Q̄_c l) l
//! fixed column (a slider's σ: r = (u, 0), a_c = 0·(u, 0); a free body's x, y, φ: r = e_d,
//!   a_c = 0): r, m a_c, M̄_cc and l are constants, computed here by the same expressions
//! a revolute link's φ (on the ground or a prescribed body): r = (−b, 1), b = perp(A s),
//!   a_c from the parent point's acceleration and ω² A s, every call
//! ```
//! The operations and order of the small path's dense solve (formulation/minimal/small.rs)
//! with the ±0 terms of the other bodies and of M̄'s zero entries left out (they change no
//! bit: a sum from +0 never turns −0), and the constant products computed once by the same
//! expressions, so its bits (tested in small.rs against the general path). A fixed column
//! whose M̄_cc is not > 0 gets l = NaN: its θ̈ is NaN and the solve fails, as the dense path's
//! check of M̄_cc > 0 does.

use crate::mechanism::formulation::minimal::tree::{Link, Parent, Tree};
use crate::mechanism::scratch::Scratch;
use crate::planar::{perp, rot};

/// One coordinate of a flat tree's θ̈ (module doc).
#[derive(Clone, Copy, Debug)]
enum Coordinate {
    /// A column of R and an a_c that do not move: θ̈_c = (Σ r (g − m a_c)) l l.
    Fixed {
        /// Its index in θ.
        c: usize,
        /// Its body's integrated index.
        i: usize,
        /// Column c of R_b.
        r: [f64; 3],
        /// m a_c of the body (each entry the product of the dense path).
        mac: [f64; 3],
        /// 1/√M̄_cc (NaN when M̄_cc is not > 0).
        l: f64,
    },
    /// A revolute link's angle; its parent's point on a prescribed body (scene index, local
    /// point) or, None, on the ground.
    Revolute {
        /// Its index in θ.
        c: usize,
        /// Its body's integrated index.
        i: usize,
        /// Its body's scene index.
        k: usize,
        /// The body's own point of the joint.
        s: [f64; 2],
        /// The parent's body and point (None: the ground).
        parent: Option<(usize, [f64; 2])>,
        /// m, m, I of the body.
        m: [f64; 3],
    },
}

/// The plan of a flat tree's θ̈ (module doc): empty on a tree that is not flat.
#[derive(Clone, Debug, Default)]
pub(crate) struct FlatPlan {
    coords: Vec<Coordinate>,
}

impl FlatPlan {
    /// The plan of `tree` with the masses `mass` (m, m, I of every integrated body, by
    /// integrated index); empty when the tree is not flat.
    pub(crate) fn new(tree: &Tree, mass: &[f64]) -> FlatPlan {
        if !tree.is_flat() {
            return FlatPlan::default();
        }
        let mut coords = Vec::with_capacity(tree.n);
        for tb in &tree.bodies {
            let (k, c, i) = (tb.body, tb.col, tb.int);
            let m = [mass[3 * i], mass[3 * i + 1], mass[3 * i + 2]];
            // A constant column r with a_c: the dense path's M̄_cc and m a_c.
            let fixed = |c: usize, r: [f64; 3], ac: [f64; 3]| {
                let d = diagonal(r, m);
                Coordinate::Fixed {
                    c,
                    i,
                    r,
                    mac: [m[0] * ac[0], m[1] * ac[1], m[2] * ac[2]],
                    l: if d > 0.0 { 1.0 / d.sqrt() } else { f64::NAN },
                }
            };
            match tb.link {
                Link::Free => {
                    for d in 0..3 {
                        let mut r = [0.0; 3];
                        r[d] = 1.0;
                        coords.push(fixed(c + d, r, [0.0; 3]));
                    }
                }
                Link::Slider { u, .. } => {
                    coords.push(fixed(c, [u[0], u[1], 0.0], [0.0 * u[0], 0.0 * u[1], 0.0]));
                }
                Link::Revolute { parent, s } => coords.push(Coordinate::Revolute {
                    c,
                    i,
                    k,
                    s,
                    parent: match parent {
                        Parent::Ground(_) => None,
                        // (An integrated parent does not occur on a flat tree.)
                        Parent::Prescribed(kp, sp) | Parent::Integrated(kp, _, sp) => {
                            Some((kp, sp))
                        }
                    },
                    m,
                }),
            }
        }
        FlatPlan { coords }
    }

    /// Whether the tree was flat and has a plan.
    #[inline]
    pub(crate) fn is_planned(&self) -> bool {
        !self.coords.is_empty()
    }

    /// θ̈ into `out` from the applied forces `g` (one row per integrated body) at the
    /// kinematics in `sc` (module doc); false if some M̄_cc is not > 0 or some θ̈ not finite.
    #[inline(always)]
    pub(crate) fn accelerations(&self, g: &[[f64; 3]], sc: &Scratch, out: &mut [f64]) -> bool {
        for p in &self.coords {
            let (c, v) = match *p {
                Coordinate::Fixed { c, i, r, mac, l } => {
                    let gi = &g[i];
                    let f = [gi[0] - mac[0], gi[1] - mac[1], gi[2] - mac[2]];
                    (c, force(r, f) * l * l)
                }
                Coordinate::Revolute {
                    c,
                    i,
                    k,
                    s,
                    parent,
                    m,
                } => {
                    // The parent's point's acceleration at θ̈ = 0.
                    let ap = match parent {
                        Some((kp, sp)) => {
                            let a = rot(sc.cs[kp], sp);
                            let b = perp(a);
                            let [ax, ay, alp] = sc.acc[kp];
                            let w = sc.vel[kp][2];
                            [
                                ax + alp * b[0] - w * w * a[0],
                                ay + alp * b[1] - w * w * a[1],
                            ]
                        }
                        None => [0.0; 2],
                    };
                    let a = rot(sc.cs[k], s);
                    let b = perp(a);
                    let w = sc.vel[k][2];
                    let ac = [
                        ap[0] - 0.0 * b[0] + w * w * a[0],
                        ap[1] - 0.0 * b[1] + w * w * a[1],
                        0.0,
                    ];
                    let r = [-b[0], -b[1], 1.0];
                    let gi = &g[i];
                    let f = [
                        gi[0] - m[0] * ac[0],
                        gi[1] - m[1] * ac[1],
                        gi[2] - m[2] * ac[2],
                    ];
                    let (d, q) = (diagonal(r, m), force(r, f));
                    if !(d > 0.0) {
                        return false;
                    }
                    let l = 1.0 / d.sqrt();
                    (c, q * l * l)
                }
            };
            if !v.is_finite() {
                return false;
            }
            out[c] = v;
        }
        true
    }
}

/// M̄_cc = Σ_rows r m r of a column r, the rows summed in order from +0 (the dense path's
/// sum, so its bits).
#[inline(always)]
fn diagonal(r: [f64; 3], m: [f64; 3]) -> f64 {
    let mut d = 0.0;
    d += r[0] * m[0] * r[0];
    d += r[1] * m[1] * r[1];
    d += r[2] * m[2] * r[2];
    d
}

/// Q̄_c = Σ_rows r f of a column r and the body's g − m a_c, in the dense path's order.
#[inline(always)]
fn force(r: [f64; 3], f: [f64; 3]) -> f64 {
    let mut s = 0.0;
    s += r[0] * f[0];
    s += r[1] * f[1];
    s += r[2] * f[2];
    s
}

#[cfg(test)]
mod tests {
    //! Which trees get a plan, and the constants of a fixed column; the plan's bits against
    //! the general path are tested in small.rs (the press, a flat tree of every other link).
    use super::Coordinate;
    use crate::mechanism::formulation::Formulation;

    #[test]
    fn the_press_plans_a_fixed_slider_and_the_rod_on_the_crank() {
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../cases/press/lubricated_150rpm_c0.1.json");
        let m = crate::Mechanism::from_scene(&crate::Scene::from_path(p).unwrap()).unwrap();
        let Formulation::Minimal(f) = m.formulation() else {
            panic!("minimal")
        };
        assert_eq!(f.flat.coords.len(), 2);
        // The formulation's masses are 1/(1/m), from M⁻¹ (Minimal::on_tree).
        let mass = |m: f64| 1.0 / (1.0 / m);
        let (mut fixed, mut revolute) = (0, 0);
        for p in &f.flat.coords {
            match *p {
                // The slide along x: r = (1, 0, 0), a_c = 0, M̄ = 0 + 1·m·1 + 0 + 0 = m exactly.
                Coordinate::Fixed { r, mac, l, .. } => {
                    fixed += 1;
                    assert_eq!(r, [1.0, 0.0, 0.0]);
                    assert_eq!(mac, [0.0; 3]);
                    assert_eq!(l, 1.0 / mass(2700.71).sqrt());
                }
                // The rod on the prescribed crank (scene index 0), its masses.
                Coordinate::Revolute { parent, m, .. } => {
                    revolute += 1;
                    assert_eq!(parent.map(|(kp, _)| kp), Some(0));
                    assert_eq!(m, [mass(412.53), mass(412.53), mass(4.21124375)]);
                }
            }
        }
        assert_eq!((fixed, revolute), (1, 1));
    }

    #[test]
    fn a_tree_with_a_link_on_an_integrated_body_gets_no_plan() {
        let scene =
            crate::mechanism::formulation::minimal::sparse_tests::branching_scene([3.0, 3.0], &[]);
        let m = crate::Mechanism::from_scene(&scene).unwrap();
        let Formulation::Minimal(f) = m.formulation() else {
            panic!("minimal")
        };
        assert!(!f.small_flat());
        assert!(f.flat.coords.is_empty());
    }
}
