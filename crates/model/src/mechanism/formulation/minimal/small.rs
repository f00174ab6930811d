//! The integrator's right-hand side on a small tree: θ̈ alone, on the stack.
//!
//! ```text
//! a tree without closing joints with n ≤ SMALL_MAX coordinates (so at most n integrated
//! bodies):
//!   g_b of every integrated body on the stack (Forces::applied_small: gravity, the revolute
//!     clearance joints' loads, the elements'; the general path's sums, so its bits)
//!   flat tree (Tree::is_flat: every body on the ground or on a prescribed body; the
//!     press): M̄ = Rᵀ M R is diagonal, θ̈_c = (R_bᵀ (g_b − M_b a_c,b))_c / M̄_cc of its own
//!     body b alone, by the dense path's operations, planned once per coordinate (flat.rs:
//!     a fixed column's constants computed at assembly), without the dispatch on n
//!   any other tree:
//!   R_b (3 × n) and a_c,b (3) of every body b, parents before children, each entry by the
//!     expression of Tree::velocity_matrix_and_bias
//!   M̄ = Σ_b R_bᵀ M_b R_b (lower triangle), Q̄ = Σ_b R_bᵀ (g_b − M_b a_c,b), by integrated
//!     index, each sum's terms in the order of Minimal::reduced_mass and
//!     Minimal::accelerations (the terms of the columns a body does not reach, which those
//!     skip, are ±0 and change no bit)
//!   M̄ θ̈ = Q̄ by the unrolled Cholesky of the general path (factor_fixed, solve_fixed)
//! ```
//! Fixed-size arrays (const generic N = n) instead of the general path's R (n_q × n, in the
//! formulation's buffers behind a RefCell), term tables and slices; q̈ of the absolute
//! coordinates, the bodies' accelerations, `Scratch::g` and the clearance joints'
//! evaluations (`Scratch::revolute`) are not written: the integrator reads θ̈ only. The same
//! operations in the same order as the general path (on a flat tree without its ±0 terms),
//! so the same bits (tested below on every kind of link and parent, flat and not, contact and
//! film included): every pinned count and digest stays. (A flat tree's M̄ as a constant
//! diagonal, m|s|² + I and m, solved by one division was measured too: 1 194 instead of
//! 1 279 instructions a call on the press, but its last bits move the BDF path both ways by
//! ±8 % of the steps: BENCHMARKS.md, "The press targets through `lash run` (issue 26)".)
//! Everything that reads q̈, the bodies' accelerations or the evaluation's buffers (the
//! Jacobian, ∂f/∂t, outputs, full evaluations, the initial check) runs its own evaluation
//! through the general path (`Mechanism::evaluate`), so after this right-hand side
//! `Scratch::qdd`, `Scratch::g`, `Scratch::revolute`, the integrated bodies' `Scratch::acc`
//! and the formulation's `Work` hold what the last general evaluation left there (the
//! kinematics, `pose`, `vel`, `cs`, are this right-hand side's).
//!
//! (An LDLᵀ solve without square roots was measured too: it changes the last bits, and with
//! them the BDF path of the dry press, without a measurable gain: 2 052 against 2 044 RHS.)

use crate::mechanism::bodies::Bodies;
use crate::mechanism::forces::Forces;
use crate::mechanism::formulation::minimal::tree::{Link, Parent};
use crate::mechanism::formulation::minimal::{factor_fixed, solve_fixed, Minimal};
use crate::mechanism::scratch::Scratch;
use crate::planar::{perp, rot};

/// The most coordinates θ the small-tree path takes (the press has 2; a chain of two links
/// beside a free body, 5).
pub(crate) const SMALL_MAX: usize = 6;

impl Minimal {
    /// Whether the integrator's right-hand side takes the small-tree path (module doc): no
    /// closing joint and 1 ≤ n ≤ [`SMALL_MAX`].
    pub(crate) fn takes_small_path(&self) -> bool {
        self.loops.is_none() && (1..=SMALL_MAX).contains(&self.tree.n)
    }

    /// Whether the tree is flat (`Tree::is_flat`: Rᵀ M R diagonal) and its θ̈ planned
    /// (flat.rs): the small path's flat case.
    #[inline]
    pub(crate) fn small_flat(&self) -> bool {
        self.flat.is_planned()
    }

    /// θ̈ (n) into `thdd` at the kinematics in `sc`, the applied forces on the stack
    /// (`Forces::applied_small`) (module doc); false if M̄ is not positive definite in f64 or
    /// θ̈ is not finite. Only where [`Minimal::takes_small_path`].
    #[inline]
    pub(crate) fn small_accelerations(
        &self,
        bodies: &Bodies,
        forces: &Forces,
        t: f64,
        sc: &mut Scratch,
        thdd: &mut [f64],
    ) -> bool {
        if self.small_flat() {
            // The flat plan (flat.rs), the applied forces inlined: no dispatch on n.
            let nb = self.tree.bodies.len();
            let mut g = [[0.0f64; 3]; SMALL_MAX];
            forces.applied_small(bodies, t, sc, &mut g[..nb]);
            return self.flat.accelerations(&g, sc, thdd);
        }
        match self.tree.n {
            1 => self.small::<1>(bodies, forces, t, sc, thdd),
            2 => self.small::<2>(bodies, forces, t, sc, thdd),
            3 => self.small::<3>(bodies, forces, t, sc, thdd),
            4 => self.small::<4>(bodies, forces, t, sc, thdd),
            5 => self.small::<5>(bodies, forces, t, sc, thdd),
            6 => self.small::<6>(bodies, forces, t, sc, thdd),
            _ => false,
        }
    }

    /// [`Minimal::small_accelerations`] with n = N.
    #[inline(always)]
    fn small<const N: usize>(
        &self,
        bodies: &Bodies,
        forces: &Forces,
        t: f64,
        sc: &mut Scratch,
        out: &mut [f64],
    ) -> bool {
        // The applied forces of every integrated body (by integrated index: at most N).
        let nb = self.tree.bodies.len();
        let mut g = [[0.0f64; 3]; N];
        applied_small(forces, bodies, t, sc, &mut g[..nb]);
        // R's rows and a_c of every integrated body (by integrated index: at most N of them,
        // each has a coordinate); the entries a body's rows do not reach stay +0.
        let mut rows = [[[0.0f64; N]; 3]; N];
        let mut acs = [[0.0f64; 3]; N];
        for tb in &self.tree.bodies {
            let (k, c, i) = (tb.body, tb.col, tb.int);
            let mut r = [[0.0f64; N]; 3];
            let ac = match tb.link {
                Link::Free => {
                    r[0][c] = 1.0;
                    r[1][c + 1] = 1.0;
                    r[2][c + 2] = 1.0;
                    [0.0; 3]
                }
                Link::Slider { u, .. } => {
                    r[0][c] = u[0];
                    r[1][c] = u[1];
                    [0.0 * u[0], 0.0 * u[1], 0.0]
                }
                Link::Revolute { parent, s } => {
                    // The parent's point: its rows (integrated parent: only its ancestors'
                    // columns, < c, can be nonzero) and its acceleration at θ̈ = 0.
                    let ap = match parent {
                        Parent::Ground(_) => [0.0; 2],
                        Parent::Prescribed(kp, sp) | Parent::Integrated(kp, _, sp) => {
                            let a = rot(sc.cs[kp], sp);
                            let b = perp(a);
                            let [ax, ay, alp] = match parent {
                                Parent::Integrated(_, ip, _) => {
                                    let rp = &rows[ip];
                                    for j in 0..c {
                                        let w = rp[2][j];
                                        r[0][j] = rp[0][j] + w * b[0];
                                        r[1][j] = rp[1][j] + w * b[1];
                                    }
                                    acs[ip]
                                }
                                _ => sc.acc[kp],
                            };
                            let w = sc.vel[kp][2];
                            [
                                ax + alp * b[0] - w * w * a[0],
                                ay + alp * b[1] - w * w * a[1],
                            ]
                        }
                    };
                    let a = rot(sc.cs[k], s);
                    let b = perp(a);
                    let w = sc.vel[k][2];
                    r[0][c] = -b[0];
                    r[1][c] = -b[1];
                    r[2][c] = 1.0;
                    [
                        ap[0] - 0.0 * b[0] + w * w * a[0],
                        ap[1] - 0.0 * b[1] + w * w * a[1],
                        0.0,
                    ]
                }
            };
            rows[i] = r;
            acs[i] = ac;
        }
        // M̄ (row-major lower triangle, in the general path's layout) and Q̄, body by body in
        // integrated order, every column: a column the body's rows do not reach is +0 in
        // them, so its terms are ±0, and a sum from +0 never turns −0 (x + (−x) = +0), so
        // adding them changes no bit (Tree::columns_of; while R, g and a_c are finite — else
        // θ̈ is not finite on either path and the right-hand side is NaN). Dense loops of
        // constant length cost less than the lists of reached columns.
        let mut mbar = [0.0f64; SMALL_MAX * SMALL_MAX];
        let mut qbar = [0.0f64; N];
        for (i, (r, ac)) in rows
            .iter()
            .zip(&acs)
            .enumerate()
            .take(self.tree.bodies.len())
        {
            let (m, f) = self.body_force(&g[i], ac, i);
            for x in 0..N {
                for y in 0..=x {
                    let mut s = mbar[x * N + y];
                    s += r[0][x] * m[0] * r[0][y];
                    s += r[1][x] * m[1] * r[1][y];
                    s += r[2][x] * m[2] * r[2][y];
                    mbar[x * N + y] = s;
                }
                let mut s = qbar[x];
                s += r[0][x] * f[0];
                s += r[1][x] * f[1];
                s += r[2][x] * f[2];
                qbar[x] = s;
            }
        }
        if factor_fixed::<N>(&mut mbar[..N * N]).is_err() {
            return false;
        }
        solve_fixed::<N>(&mbar[..N * N], &mut qbar);
        out[..N].copy_from_slice(&qbar);
        qbar.iter().all(|v| v.is_finite())
    }

    /// Integrated body i's masses (m, m, I) and its applied force less its mass times a_c,
    /// g_i − M_i a_c,i: the terms of Rᵀ (Q − M a_c) in the general path's order.
    #[inline(always)]
    fn body_force(&self, g: &[f64; 3], ac: &[f64; 3], i: usize) -> (&[f64], [f64; 3]) {
        let m = &self.mass[3 * i..3 * i + 3];
        (
            m,
            [
                g[0] - m[0] * ac[0],
                g[1] - m[1] * ac[1],
                g[2] - m[2] * ac[2],
            ],
        )
    }
}

/// [`Forces::applied_small`] in one place for the dense path's six sizes (not inlined into
/// each).
#[inline(never)]
fn applied_small(forces: &Forces, bodies: &Bodies, t: f64, sc: &mut Scratch, g: &mut [[f64; 3]]) {
    forces.applied_small(bodies, t, sc, g);
}

#[cfg(test)]
mod tests {
    //! The small-tree right-hand side gives the general path's bits on a scene of every kind
    //! of revolute link and a free body, and on the lubricated press; which scenes take it.
    use crate::mechanism::formulation::Formulation;

    /// A chain of two links from the ground (the second a revolute child of an integrated
    /// body), a free body held at the chain's end by a dry clearance joint, and a crank turned
    /// by a driver with a rod pinned to it (a revolute child of a prescribed body); gravity,
    /// under `minimal`: θ = (l1, l2, x_f, y_f, φ_f, rod), n = 6.
    fn chain_free_and_crank() -> crate::Scene {
        let link = |name: &str, x: f64, y: f64, m: f64| {
            serde_json::json!({"name": name, "mass": m, "inertia": 0.1 * m,
                "points": {"O": [-0.5, 0.0], "E": [0.5, 0.0]},
                "position": [x, y], "angle": 0.0, "velocity": [0.0, 0.0],
                "angular_velocity": 0.0})
        };
        let scene = serde_json::json!({
            "bodies": [link("l1", 0.5, 0.0, 1.0), link("l2", 1.5, 0.0, 2.0),
                       link("f", 2.5, 0.0, 1.5), link("crank", -1.5, 0.0, 0.7),
                       link("rod", -0.5, 0.0, 1.2)],
            "joints": [
                {"type": "revolute", "name": "p1", "a": {"body": "l1", "point": "O"},
                 "b": {"body": "ground", "at": [0.0, 0.0]}},
                {"type": "revolute", "name": "p2", "a": {"body": "l1", "point": "E"},
                 "b": {"body": "l2", "point": "O"}},
                {"type": "clearance", "name": "j",
                 "bearing": {"body": "l2", "point": "E", "radius": 0.2},
                 "journal": {"body": "f", "point": "O", "radius": 0.1},
                 "normal": {"law": "impact", "k": 1e9, "c_max": 1e3, "d_max": 1e-4},
                 "friction": {"law": "none"}},
                {"type": "revolute", "name": "pivot", "a": {"body": "crank", "point": "O"},
                 "b": {"body": "ground", "at": [-2.0, 0.0]}},
                {"type": "driver", "name": "drive", "body": "crank", "theta0": 0.0, "rpm": 90.0},
                {"type": "revolute", "name": "pin", "a": {"body": "crank", "point": "E"},
                 "b": {"body": "rod", "point": "O"}}
            ],
            "gravity": [0.0, -9.81],
            "t_end": 1.0,
            "formulation": "minimal"
        });
        crate::Scene::from_json_str(&scene.to_string()).unwrap()
    }

    /// The small-tree right-hand side (`OdeSystem::rhs`) against the general path
    /// (`Mechanism::evaluate` and the formulation's ẏ) at states away from the assembled
    /// one, every angle turned and every rate nonzero, t moving the crank; returns the
    /// largest θ̈ compared.
    fn compare(m: &crate::Mechanism, states: usize, amp: f64) -> f64 {
        use lash_solver::OdeSystem;
        let Formulation::Minimal(f) = m.formulation() else {
            panic!("minimal")
        };
        assert!(f.takes_small_path(), "n = {}", f.n());
        let n = f.n();
        let y0 = m.initial_state();
        let mut largest = 0.0f64;
        for k in 0..states {
            let y: Vec<f64> = y0
                .iter()
                .enumerate()
                .map(|(i, v)| v + amp * (k as f64 + 1.0) * ((i as f64) * 1.7 + 0.4).sin())
                .collect();
            let t = 0.013 * k as f64;
            let mut fast = vec![0.0; 2 * n];
            m.rhs(t, &y, &mut fast);
            let mut general = vec![0.0; 2 * n];
            {
                let mut sc = m.scratch();
                let ok = m.evaluate(t, &y, &mut sc, false);
                assert!(ok);
                m.formulation().derivative(&y, &sc.qdd, ok, &mut general);
            }
            // The same operations in the same order: the same bits, signed zeros included.
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fast), bits(&general), "t = {t}, y = {y:?}");
            let scale = general[n..].iter().fold(0.0f64, |a, v| a.max(v.abs()));
            largest = largest.max(scale);
        }
        largest
    }

    #[test]
    fn the_small_path_gives_the_general_path_on_a_chain_a_free_body_and_a_crank() {
        let m = crate::Mechanism::from_scene(&chain_free_and_crank()).unwrap();
        let Formulation::Minimal(f) = m.formulation() else {
            panic!("minimal")
        };
        // A link on an integrated parent: not flat, the dense sums and Cholesky.
        assert!(!f.small_flat());
        // Gravity and the turned links make every θ̈ of size: numbers, not zeros, compared.
        assert!(compare(&m, 4, 0.1) > 1.0);
    }

    /// A flat tree of every kind of link but the slider (which the press has): a link
    /// pinned to the ground, a free body held at its end by a dry clearance joint, a rod on
    /// a driven crank; gravity, under `minimal`: θ = (l1, x_f, y_f, φ_f, rod), n = 5.
    #[test]
    fn the_small_path_gives_the_general_path_on_a_flat_tree() {
        let mut scene = serde_json::to_value(chain_free_and_crank()).unwrap();
        let bodies = scene["bodies"].as_array_mut().unwrap();
        bodies.retain(|b| b["name"] != "l2");
        // The free body's pin at l1's end E, (1, 0).
        let f = bodies.iter_mut().find(|b| b["name"] == "f").unwrap();
        f["position"] = serde_json::json!([1.5, 0.0]);
        let joints = scene["joints"].as_array_mut().unwrap();
        joints.retain(|j| j["name"] != "p2");
        let j = joints.iter_mut().find(|j| j["name"] == "j").unwrap();
        j["bearing"]["body"] = serde_json::json!("l1");
        let scene = crate::Scene::from_json_str(&scene.to_string()).unwrap();
        let m = crate::Mechanism::from_scene(&scene).unwrap();
        let Formulation::Minimal(f) = m.formulation() else {
            panic!("minimal")
        };
        assert_eq!(f.n(), 5);
        assert!(f.small_flat());
        assert!(compare(&m, 4, 0.1) > 1.0);
    }

    #[test]
    fn the_small_path_gives_the_general_path_on_the_lubricated_press() {
        // The slider (a translational link) and the rod on the prescribed crank, the film of
        // the clearance joint: offsets up to 1.2e-4 m and rad, the clearance's size (1e-4 m).
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../cases/press/lubricated_150rpm_c0.1.json");
        let m = crate::Mechanism::from_scene(&crate::Scene::from_path(p).unwrap()).unwrap();
        let Formulation::Minimal(f) = m.formulation() else {
            panic!("minimal")
        };
        // Rod on the prescribed crank, slider on the ground: flat, M̄ diagonal, each θ̈ from
        // its own body (small_flat), the dense path's bits.
        assert!(f.small_flat());
        assert!(compare(&m, 4, 3e-5) > 1.0);
    }

    #[test]
    fn a_tree_of_many_coordinates_keeps_the_general_path() {
        // The branching tree of the sparse sums' test: n = 7.
        let scene =
            crate::mechanism::formulation::minimal::sparse_tests::branching_scene([3.0, 3.0], &[]);
        let m = crate::Mechanism::from_scene(&scene).unwrap();
        let Formulation::Minimal(f) = m.formulation() else {
            panic!("minimal")
        };
        assert_eq!(f.n(), 7);
        assert!(!f.takes_small_path());
    }
}
