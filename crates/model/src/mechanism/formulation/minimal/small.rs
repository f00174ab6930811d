//! The integrator's right-hand side on a small tree: θ̈ alone, on the stack.
//!
//! ```text
//! a tree without closing joints with n ≤ SMALL_MAX coordinates (so at most n integrated
//! bodies): per body b, parents before children,
//!   R_b (3 × n) and a_c,b (3)       as Tree::velocity_matrix_and_bias writes them
//!   M̄ += R_bᵀ M_b R_b,  Q̄ += R_bᵀ (g_b − M_b a_c,b)     (lower triangle of M̄)
//! M̄ θ̈ = Q̄ by LDLᵀ: n divisions and no square root (a 1 × 1 block of a branch that couples
//!   with no other is one division: the press's rod and slider)
//! ```
//! Fixed-size arrays (const generic N = n) instead of the general path's R (n_q × n), term
//! tables and Cholesky; q̈ of the absolute coordinates and the bodies' accelerations are not
//! formed: the integrator reads θ̈ only. Everything that reads q̈, the bodies' accelerations
//! or the evaluation's buffers (the Jacobian, ∂f/∂t, outputs, full evaluations, the initial
//! check) runs its own evaluation through the general path (`Mechanism::evaluate`), so after
//! this right-hand side `Scratch::qdd`, the integrated bodies' `Scratch::acc` and the
//! formulation's `Work` hold what the last general evaluation left there. The two paths agree
//! to rounding (the sums in another order, LDLᵀ instead of Cholesky): tested in
//! tests/minimal_small.rs and below.

use crate::mechanism::formulation::minimal::tree::{Link, Parent};
use crate::mechanism::formulation::minimal::Minimal;
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

    /// θ̈ (n) into `thdd` from the applied forces `sc.g` at the kinematics in `sc` (module
    /// doc); false if M̄ is not positive definite in f64 or θ̈ is not finite. Only where
    /// [`Minimal::takes_small_path`].
    #[inline]
    pub(crate) fn small_accelerations(&self, sc: &Scratch, thdd: &mut [f64]) -> bool {
        match self.tree.n {
            1 => self.small::<1>(sc, thdd),
            2 => self.small::<2>(sc, thdd),
            3 => self.small::<3>(sc, thdd),
            4 => self.small::<4>(sc, thdd),
            5 => self.small::<5>(sc, thdd),
            6 => self.small::<6>(sc, thdd),
            _ => false,
        }
    }

    /// [`Minimal::small_accelerations`] with n = N.
    #[inline(always)]
    fn small<const N: usize>(&self, sc: &Scratch, out: &mut [f64]) -> bool {
        // R's rows and a_c of every integrated body (by integrated index: at most N of them,
        // each has a coordinate).
        let mut rows = [[[0.0f64; N]; 3]; N];
        let mut acs = [[0.0f64; 3]; N];
        let mut mbar = [[0.0f64; N]; N];
        let mut qbar = [0.0f64; N];
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
                    [0.0; 3]
                }
                Link::Revolute { parent, s } => {
                    // The parent's point: its rows and its acceleration at θ̈ = 0.
                    let ap = match parent {
                        Parent::Ground(_) => [0.0; 2],
                        Parent::Prescribed(kp, sp) => {
                            let a = rot(sc.cs[kp], sp);
                            let b = perp(a);
                            let [ax, ay, alp] = sc.acc[kp];
                            let w2 = sc.vel[kp][2] * sc.vel[kp][2];
                            [ax + alp * b[0] - w2 * a[0], ay + alp * b[1] - w2 * a[1]]
                        }
                        Parent::Integrated(kp, ip, sp) => {
                            let a = rot(sc.cs[kp], sp);
                            let b = perp(a);
                            let rp = &rows[ip];
                            for j in 0..N {
                                r[0][j] = rp[0][j] + rp[2][j] * b[0];
                                r[1][j] = rp[1][j] + rp[2][j] * b[1];
                            }
                            let [ax, ay, alp] = acs[ip];
                            let w2 = sc.vel[kp][2] * sc.vel[kp][2];
                            [ax + alp * b[0] - w2 * a[0], ay + alp * b[1] - w2 * a[1]]
                        }
                    };
                    let a = rot(sc.cs[k], s);
                    let b = perp(a);
                    let w2 = sc.vel[k][2] * sc.vel[k][2];
                    r[0][c] = -b[0];
                    r[1][c] = -b[1];
                    r[2][c] = 1.0;
                    [ap[0] + w2 * a[0], ap[1] + w2 * a[1], 0.0]
                }
            };
            // This body's part of M̄ and Q̄.
            let q = 3 * i;
            let (m, g) = (&self.mass[q..q + 3], &sc.g[q..q + 3]);
            let f = [
                g[0] - m[0] * ac[0],
                g[1] - m[1] * ac[1],
                g[2] - m[2] * ac[2],
            ];
            for x in 0..N {
                qbar[x] += r[0][x] * f[0] + r[1][x] * f[1] + r[2][x] * f[2];
                let mr = [m[0] * r[0][x], m[1] * r[1][x], m[2] * r[2][x]];
                for y in 0..=x {
                    mbar[x][y] += mr[0] * r[0][y] + mr[1] * r[1][y] + mr[2] * r[2][y];
                }
            }
            rows[i] = r;
            acs[i] = ac;
        }
        if !ldl_solve(&mut mbar, &mut qbar) {
            return false;
        }
        out[..N].copy_from_slice(&qbar);
        qbar.iter().all(|v| v.is_finite())
    }
}

/// Solves A x = b in place for symmetric A (its lower triangle in `a`, overwritten by L and
/// D) by LDLᵀ: A = L D Lᵀ, L unit lower triangular; false (b unfinished) if a pivot d_j is
/// not positive (A not positive definite in f64). No square root: n divisions, which need
/// not wait for each other where the columns do not couple.
#[inline(always)]
pub(crate) fn ldl_solve<const N: usize>(a: &mut [[f64; N]; N], b: &mut [f64; N]) -> bool {
    let mut inv = [0.0f64; N];
    let mut d = [0.0f64; N];
    for j in 0..N {
        // Column j: s_i = A_ij − Σ_{k<j} L_ik d_k L_jk (i ≥ j), then d_j = s_j, L_ij = s_i/d_j.
        let mut ljd = [0.0f64; N];
        for k in 0..j {
            ljd[k] = a[j][k] * d[k];
        }
        let mut s = a[j][j];
        for k in 0..j {
            s -= ljd[k] * a[j][k];
        }
        if !(s > 0.0) {
            return false;
        }
        d[j] = s;
        inv[j] = 1.0 / s;
        for i in j + 1..N {
            let mut x = a[i][j];
            for k in 0..j {
                x -= a[i][k] * ljd[k];
            }
            a[i][j] = x * inv[j];
        }
    }
    // L z = b, D y = z, Lᵀ x = y.
    for i in 0..N {
        let mut s = b[i];
        for k in 0..i {
            s -= a[i][k] * b[k];
        }
        b[i] = s;
    }
    for i in 0..N {
        b[i] *= inv[i];
    }
    for i in (0..N).rev() {
        let mut s = b[i];
        for k in i + 1..N {
            s -= a[k][i] * b[k];
        }
        b[i] = s;
    }
    true
}

#[cfg(test)]
mod tests {
    //! The small-tree right-hand side against the general path on a scene of every kind of
    //! revolute link and a free body, and on the lubricated press; which scenes take it; the
    //! LDLᵀ solve against the general path's Cholesky.
    use super::*;
    use crate::linalg::{block_cholesky_inv, cholesky_solve};
    use crate::mechanism::formulation::Formulation;

    /// A = B Bᵀ + I with B_ij = sin(1.3 (i + 1) (j + 2)) 10^(i − j) (entries of mixed
    /// magnitude, condition numbers up to ~1e6 at N = 6).
    fn spd<const N: usize>() -> [[f64; N]; N] {
        let bm = |i: usize, j: usize| {
            (1.3 * (i + 1) as f64 * (j + 2) as f64).sin() * 10f64.powi(i as i32 - j as i32)
        };
        std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                (0..N).map(|k| bm(i, k) * bm(j, k)).sum::<f64>() + if i == j { 1.0 } else { 0.0 }
            })
        })
    }

    fn check<const N: usize>() {
        let a0 = spd::<N>();
        let rhs: [f64; N] = std::array::from_fn(|i| (i as f64 + 0.5).cos() * 1e2);
        let (mut a, mut x) = (a0, rhs);
        assert!(ldl_solve(&mut a, &mut x));
        let mut dense: Vec<f64> = a0.iter().flatten().copied().collect();
        let all: Vec<usize> = (0..N).collect();
        assert_eq!(block_cholesky_inv(&mut dense, N, &all), Ok(()));
        let mut y = rhs.to_vec();
        cholesky_solve(&dense, N, &mut y);
        // Two backward-stable factorisations of one matrix: their solutions differ by about
        // κ(A) ε ‖x‖ (κ ≤ ~1e6 here): 1e-9 relative to the largest entry.
        let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (p, q) in x.iter().zip(&y) {
            assert!(
                (p - q).abs() <= 1e-9 * scale,
                "N = {N}: {x:?} against {y:?}"
            );
        }
        // Its own residual: A x = b to rounding (‖A‖ ‖x‖ ε scale).
        let norm = a0.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..N {
            let ax: f64 = (0..N).map(|j| a0[i][j] * x[j]).sum();
            assert!(
                (ax - rhs[i]).abs() <= 1e-12 * norm * scale * N as f64,
                "N = {N}, row {i}"
            );
        }
        // Not positive definite (the last pivot negative): refused.
        let mut bad = a0;
        bad[N - 1][N - 1] = -1.0;
        let mut b = rhs;
        assert!(!ldl_solve(&mut bad, &mut b));
    }

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
    /// one, every angle turned and every rate nonzero; returns the largest θ̈ compared.
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
            assert_eq!(fast[..n], general[..n]);
            // The same sums in another order and LDLᵀ instead of Cholesky of the same M̄
            // (κ(M̄) ≲ 1e2 on these links): each θ̈ to ~1e2 ε relative, 1e-10 with margin,
            // plus 1e-13 of the largest (the forces of a contact reach every coordinate it
            // couples through sums of that size); a wrong entry of R or a_c moves θ̈ at O(1)
            // (gravity's g/L) or more.
            let scale = general[n..].iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for (a, b) in fast[n..].iter().zip(&general[n..]) {
                let tol = 1e-10 * b.abs() + 1e-13 * scale;
                assert!((a - b).abs() <= tol, "{fast:?} against {general:?}");
            }
            largest = largest.max(scale);
        }
        largest
    }

    #[test]
    fn the_small_path_gives_the_general_path_on_a_chain_a_free_body_and_a_crank() {
        let m = crate::Mechanism::from_scene(&chain_free_and_crank()).unwrap();
        // Gravity and the turned links make every θ̈ of size: numbers, not zeros, compared.
        assert!(compare(&m, 4, 0.1) > 1.0);
    }

    #[test]
    fn the_small_path_gives_the_general_path_on_the_lubricated_press() {
        // The slider (a translational link) and the rod on the prescribed crank, the film
        // and the contact of the clearance joint: small offsets (the clearance is 1e-4 m, so
        // the journal is moved within it and across it, contact included).
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../cases/press/lubricated_150rpm_c0.1.json");
        let m = crate::Mechanism::from_scene(&crate::Scene::from_path(p).unwrap()).unwrap();
        assert!(compare(&m, 4, 3e-5) > 1.0);
    }

    #[test]
    fn a_scene_with_a_closing_joint_or_many_coordinates_keeps_the_general_path() {
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

    #[test]
    fn ldl_solves_as_the_cholesky_does_to_rounding() {
        check::<1>();
        check::<2>();
        check::<3>();
        check::<4>();
        check::<5>();
        check::<6>();
    }
}
