//! A hand-written right-hand side of the paper's press in minimal coordinates: the comparator
//! of the performance goals (BENCHMARKS.md, "(g) Close to the limit: lash against a
//! hand-written model").
//!
//! ```text
//! crank prescribed: θ = θ₀ + ω t,  A = r (cos θ, sin θ),  Ä = −r ω² (cos θ, sin θ)
//! state y = (ψ, x, ψ̇, ẋ): rod angle, slider position along the slide, and their rates
//! rod:    u = (cos ψ, sin ψ),  G = A + (l/2) u,  B = A + l u   (journal centre)
//! slider: P = (x, 0)                                           (bearing centre)
//! clearance (docs/model.md §2): e = B − P, n = e/|e|, t = (−n_y, n_x), δ = |e| − c,
//!   δ̇ = n·ė, v_T = t·ė + R_J ψ̇, ε = |e|/c, ε̇ = δ̇/c, γ̇ = (e × ė)/|e|², Ω = ψ̇ − 2γ̇
//! forces on the journal: dry f_c = −F_N n + F_T t at Q_J = B + R_J n (δ > 0, §3);
//!   film f_f = F_r n + F_t t at B (long-bearing Gümbel, ε capped at ε_cap, §4)
//! rod about its moving pin A (the pin force has no moment about A):
//!   I_A ψ̈ = (G − A) × m_rod g + (B − A) × f_f + (Q_J − A) × f_c − m_rod (G − A) × Ä,
//!   I_A = I_G + m_rod (l/2)²
//! slider (the guide holds y and the angle): m_s ẍ = −(f_f + f_c)·x̂
//! ```
//! Written from docs/model.md §2–§6 alone, independent of `lash_model`'s code; a test checks
//! that it gives the general model's slider acceleration to 1e-12 relative at states along a
//! trajectory. Four states against the general model's twelve (two bodies of three absolute
//! coordinates each, four constraints), so the method's own work can be measured apart from the
//! cost of the general formulation.

use std::cell::Cell;

use lash_solver::OdeSystem;

/// Parameters of the press (docs/model.md §6) with a dry or lubricated rod–slider clearance.
#[derive(Clone, Debug, PartialEq)]
pub struct HandPress {
    /// Crank radius r (m).
    pub r: f64,
    /// Rod length l (m).
    pub l: f64,
    /// Rod mass (kg).
    pub m_rod: f64,
    /// Rod inertia about its centre of mass (kg·m²).
    pub i_rod: f64,
    /// Slider mass (kg).
    pub m_slider: f64,
    /// Crank speed ω (rad/s) and initial angle θ₀ (rad).
    pub omega: f64,
    /// θ₀ (rad).
    pub theta0: f64,
    /// Gravity along y (m/s²; the slide is along x).
    pub g_y: f64,
    /// Bearing radius R_B and journal radius R_J (m).
    pub rb: f64,
    /// Journal radius (m).
    pub rj: f64,
    /// Contact stiffness K (N/m^1.5), damping c_max (N·s/m) and its ramp depth d_max (m).
    pub k: f64,
    /// c_max (N·s/m).
    pub c_max: f64,
    /// d_max (m).
    pub d_max: f64,
    /// Friction μ and the thresholds v₀ < v₁ of the dynamic correction (m/s).
    pub mu: f64,
    /// v₀ (m/s).
    pub v0: f64,
    /// v₁ (m/s).
    pub v1: f64,
    /// Film: viscosity (Pa·s), bearing length (m), ε_cap; None for a dry joint.
    pub film: Option<(f64, f64, f64)>,
    /// RHS evaluations so far.
    pub evals: Cell<usize>,
}

impl HandPress {
    /// The press of docs/model.md §6 at `rpm` with radial clearance `c` (m), dry or lubricated.
    pub fn paper(rpm: f64, c: f64, lubricated: bool) -> HandPress {
        let (r, l, m_rod) = (0.015, 0.35, 412.53);
        let rb = 0.05;
        HandPress {
            r,
            l,
            m_rod,
            i_rod: m_rod * l * l / 12.0,
            m_slider: 2700.71,
            omega: rpm * std::f64::consts::PI / 30.0,
            theta0: 0.0,
            g_y: -9.81,
            rb,
            // The case files store R_J rounded to 1e-12 m.
            rj: ((rb - c) * 1e12).round() / 1e12,
            k: 2.34e10,
            c_max: 100.0,
            d_max: 1e-5,
            mu: 0.01,
            v0: 1e-4,
            v1: 2e-4,
            film: lubricated.then_some((0.4, 0.1, 0.99)),
            evals: Cell::new(0),
        }
    }

    /// Radial clearance c = R_B − R_J (m).
    pub fn clearance(&self) -> f64 {
        self.rb - self.rj
    }

    /// The state of the general model (rod (x, y, φ), slider (x, y, φ), then their rates)
    /// with the same configuration as the minimal state `y` = (ψ, x, ψ̇, ẋ) at time t: it
    /// satisfies the constraints and their rates exactly.
    pub fn full_state(&self, t: f64, y: &[f64]) -> Vec<f64> {
        let th = self.theta0 + self.omega * t;
        let (st, ct) = th.sin_cos();
        let (sp, cp) = y[0].sin_cos();
        let h = 0.5 * self.l;
        let (a, ad) = (
            [self.r * ct, self.r * st],
            [-self.r * self.omega * st, self.r * self.omega * ct],
        );
        vec![
            a[0] + h * cp,
            a[1] + h * sp,
            y[0],
            y[1],
            0.0,
            0.0,
            ad[0] - h * sp * y[2],
            ad[1] + h * cp * y[2],
            y[2],
            y[3],
            0.0,
            0.0,
        ]
    }

    /// The minimal state (ψ, x, ψ̇, ẋ) of a general-model state (rod and slider coordinates
    /// as in [`HandPress::full_state`]).
    pub fn minimal_state(full: &[f64]) -> [f64; 4] {
        [full[2], full[3], full[8], full[9]]
    }

    /// Normal force F_N of the ADAMS IMPACT law at penetration δ > 0 and rate δ̇ (§3).
    fn normal_force(&self, delta: f64, delta_dot: f64) -> f64 {
        let s = (delta / self.d_max).min(1.0);
        let damping = self.c_max * s * s * (3.0 - 2.0 * s);
        (self.k * delta * delta.sqrt() + damping * delta_dot).max(0.0)
    }

    /// Friction F_T along t: Coulomb with Ambrósio's dynamic correction (§3).
    fn friction_force(&self, v_t: f64, f_n: f64) -> f64 {
        let a = v_t.abs();
        let cd = if a <= self.v0 {
            0.0
        } else if a < self.v1 {
            (a - self.v0) / (self.v1 - self.v0)
        } else {
            1.0
        };
        -self.mu * cd * f_n * v_t.signum()
    }

    /// Long-bearing Gümbel film (F_r, F_t) at (ε, ε̇, Ω) with ε capped at ε_cap (§4).
    fn film_force(&self, eps: f64, eps_dot: f64, big_omega: f64) -> (f64, f64) {
        let Some((visc, len, cap)) = self.film else {
            return (0.0, 0.0);
        };
        let e = eps.min(cap);
        let e2 = e * e;
        let q = 1.0 - e2;
        let k = 12.0 * visc * len * self.rj.powi(3) / (self.clearance() * self.clearance());
        let pi = std::f64::consts::PI;
        let fr = -k
            * (e2 * big_omega / ((2.0 + e2) * q)
                + eps_dot * (0.5 * pi - 8.0 / (pi * (2.0 + e2))) / (q * q.sqrt()));
        let ft = k
            * (pi * e * big_omega / (2.0 * (2.0 + e2) * q.sqrt())
                + 2.0 * e * eps_dot / ((2.0 + e2) * q));
        (fr, ft)
    }

    /// (ψ̈, ẍ) at (t, y).
    pub fn accelerations(&self, t: f64, y: &[f64]) -> [f64; 2] {
        let (psi, x, psid, xd) = (y[0], y[1], y[2], y[3]);
        let w = self.omega;
        let th = self.theta0 + w * t;
        let (st, ct) = th.sin_cos();
        let a = [self.r * ct, self.r * st];
        let ad = [-self.r * w * st, self.r * w * ct];
        let add = [-self.r * w * w * ct, -self.r * w * w * st];
        let (sp, cp) = psi.sin_cos();
        let u = [cp, sp];
        let up = [-sp, cp];
        let l = self.l;
        let b = [a[0] + l * u[0], a[1] + l * u[1]];
        let bd = [ad[0] + l * psid * up[0], ad[1] + l * psid * up[1]];
        let e = [b[0] - x, b[1]];
        let ed = [bd[0] - xd, bd[1]];
        let cross = |p: [f64; 2], q: [f64; 2]| p[0] * q[1] - p[1] * q[0];
        let norm = e[0].hypot(e[1]);
        let c = self.clearance();
        let (n, gamma_dot) = if norm < 1e-12 * c {
            ([1.0, 0.0], 0.0)
        } else {
            ([e[0] / norm, e[1] / norm], cross(e, ed) / (norm * norm))
        };
        let tv = [-n[1], n[0]];
        let delta = norm - c;
        let delta_dot = n[0] * ed[0] + n[1] * ed[1];
        // Moments about A and the force on the slider along x.
        let half = [0.5 * l * u[0], 0.5 * l * u[1]];
        let mut moment = cross(half, [0.0, self.m_rod * self.g_y]) - self.m_rod * cross(half, add);
        let mut fx_journal = 0.0;
        if delta > 0.0 {
            let v_t = tv[0] * ed[0] + tv[1] * ed[1] + self.rj * psid;
            let f_n = self.normal_force(delta, delta_dot);
            let f_t = self.friction_force(v_t, f_n);
            let f = [-f_n * n[0] + f_t * tv[0], -f_n * n[1] + f_t * tv[1]];
            let arm = [l * u[0] + self.rj * n[0], l * u[1] + self.rj * n[1]];
            moment += cross(arm, f);
            fx_journal += f[0];
        }
        if self.film.is_some() {
            let (fr, ft) = self.film_force(norm / c, delta_dot / c, psid - 2.0 * gamma_dot);
            let f = [fr * n[0] + ft * tv[0], fr * n[1] + ft * tv[1]];
            moment += cross([l * u[0], l * u[1]], f);
            fx_journal += f[0];
        }
        let i_a = self.i_rod + self.m_rod * 0.25 * l * l;
        [moment / i_a, -fx_journal / self.m_slider]
    }
}

impl OdeSystem for HandPress {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.evals.set(self.evals.get() + 1);
        let [psidd, xdd] = self.accelerations(t, y);
        dy[0] = y[2];
        dy[1] = y[3];
        dy[2] = psidd;
        dy[3] = xdd;
    }
}

/// One run of diffsol's BDF alone on the hand-written press: its own problem built from
/// closures, no lash code between diffsol and the right-hand side.
#[derive(Clone, Debug)]
pub struct DiffsolRun {
    /// ẍ_slider at each requested time (m/s²), from the right-hand side at diffsol's dense
    /// output.
    pub slider_a: Vec<f64>,
    /// RHS evaluations, those of the finite-difference Jacobians included.
    pub rhs_evals: usize,
    /// Accepted steps.
    pub steps: usize,
    /// Wall time of the integration (s): problem set-up and solve, no sampling.
    pub wall: f64,
}

/// The most copies [`diffsol_bdf_copies`] takes (12 states, the general model's dimension).
pub const MAX_COPIES: usize = 3;

/// [`diffsol_bdf`] on `copies` identical copies of the hand-written press stacked into one
/// state of 4·copies entries: the same method, steps and Newton iterations (every block sees
/// the same arithmetic, and diffsol's RMS error norm over identical blocks is that of one, up
/// to its rounding: over two revolutions at rtol 3.2e-10, 1148 steps against 1146), the
/// linear algebra and bookkeeping of the larger dimension, and one right-hand side per call
/// (computed once and copied while the blocks are bitwise equal, as they stay). A measurement
/// of what the dimension alone costs diffsol: with 3 copies it runs at the general model's 12
/// states. Its finite-difference Jacobian differences each block's columns (4·copies
/// evaluations instead of 4, ~40 Jacobians per run). `rhs_evals` counts calls.
pub fn diffsol_bdf_copies(
    press: &HandPress,
    t0: f64,
    y0: [f64; 4],
    rtol: f64,
    atol: f64,
    times: &[f64],
    copies: usize,
) -> Result<DiffsolRun, String> {
    use diffsol::{NalgebraLU, NalgebraMat, OdeBuilder, OdeSolverMethod};
    use std::cell::{Cell, RefCell};
    if copies == 0 || copies > MAX_COPIES {
        return Err(format!("copies must be in 1..={MAX_COPIES}"));
    }
    let n = 4 * copies;
    let calls = Cell::new(0usize);
    // f of the stacked state: blocks equal to the first get its derivative copied.
    let f = |x: &[f64], t: f64, out: &mut [f64]| {
        calls.set(calls.get() + 1);
        press.rhs(t, &x[..4], &mut out[..4]);
        for b in 1..copies {
            let (head, tail) = out.split_at_mut(4 * b);
            if x[4 * b..4 * b + 4] == x[..4] {
                tail[..4].copy_from_slice(&head[..4]);
            } else {
                press.rhs(t, &x[4 * b..4 * b + 4], &mut tail[..4]);
            }
        }
    };
    let cache: RefCell<(f64, [f64; 4 * MAX_COPIES], [f64; 4 * MAX_COPIES], bool)> =
        RefCell::new((0.0, [0.0; 4 * MAX_COPIES], [0.0; 4 * MAX_COPIES], false));
    let start = std::time::Instant::now();
    let problem = OdeBuilder::<NalgebraMat<f64>>::new()
        .t0(t0)
        .rtol(rtol)
        .atol(vec![atol; n])
        .rhs_implicit(
            |x: &[f64], _p: &[f64], t: f64, y: &mut [f64]| f(x, t, y),
            |x: &[f64], _p: &[f64], t: f64, v: &[f64], y: &mut [f64]| {
                let mut c = cache.borrow_mut();
                if !(c.3 && c.0 == t && c.1[..n] == x[..]) {
                    let mut fx = [0.0; 4 * MAX_COPIES];
                    f(x, t, &mut fx[..n]);
                    let mut xs = [0.0; 4 * MAX_COPIES];
                    xs[..n].copy_from_slice(x);
                    *c = (t, xs, fx, true);
                }
                y.fill(0.0);
                // Each block depends on its own four states only.
                for b in 0..copies {
                    let r = 4 * b..4 * b + 4;
                    let vmax = v[r.clone()].iter().fold(0.0f64, |m, a| m.max(a.abs()));
                    if vmax == 0.0 {
                        continue;
                    }
                    let xmax = x[r.clone()].iter().fold(1.0f64, |m, a| m.max(a.abs()));
                    let eps = f64::EPSILON.sqrt() * xmax / vmax;
                    let mut xp = [0.0; 4];
                    for i in 0..4 {
                        xp[i] = x[4 * b + i] + eps * v[4 * b + i];
                    }
                    let mut fp = [0.0; 4];
                    calls.set(calls.get() + 1);
                    press.rhs(t, &xp, &mut fp);
                    for i in 0..4 {
                        y[4 * b + i] = (fp[i] - c.2[4 * b + i]) / eps;
                    }
                }
            },
        )
        .init(
            move |_p: &[f64], _t: f64, y: &mut [f64]| {
                for b in 0..copies {
                    y[4 * b..4 * b + 4].copy_from_slice(&y0);
                }
            },
            n,
        )
        .build()
        .map_err(|e| e.to_string())?;
    let mut problem = problem;
    problem.ode_options.max_nonlinear_solver_failures = usize::MAX;
    let mut solver = problem
        .bdf::<NalgebraLU<f64>>()
        .map_err(|e| e.to_string())?;
    let (ys, _) = solver.solve_dense(times).map_err(|e| e.to_string())?;
    let wall = start.elapsed().as_secs_f64();
    let steps = solver.get_statistics().number_of_steps;
    let slider_a = times
        .iter()
        .enumerate()
        .map(|(k, &t)| {
            let b = 4 * (copies - 1);
            let y = [ys[(b, k)], ys[(b + 1, k)], ys[(b + 2, k)], ys[(b + 3, k)]];
            press.accelerations(t, &y)[1]
        })
        .collect();
    Ok(DiffsolRun {
        slider_a,
        rhs_evals: calls.get(),
        steps,
        wall,
    })
}

/// Integrates the hand-written press from (t0, y0) to the last of `times` with diffsol's BDF
/// (nalgebra LU) at (rtol, atol), the Jacobian-vector products by forward differences of the
/// right-hand side (f(x) cached across the columns of one Jacobian, so a dense Jacobian costs
/// n + 1 evaluations, as a finite-difference Jacobian does), diffsol's cap of 50 Newton
/// failures per run lifted, and samples ẍ_slider at `times`.
pub fn diffsol_bdf(
    press: &HandPress,
    t0: f64,
    y0: [f64; 4],
    rtol: f64,
    atol: [f64; 4],
    times: &[f64],
) -> Result<DiffsolRun, String> {
    use diffsol::{NalgebraLU, NalgebraMat, OdeBuilder, OdeSolverMethod};
    use std::cell::RefCell;
    press.evals.set(0);
    let cache: RefCell<(f64, [f64; 4], [f64; 4], bool)> =
        RefCell::new((0.0, [0.0; 4], [0.0; 4], false));
    let f = |x: &[f64], t: f64, out: &mut [f64]| press.rhs(t, x, out);
    let start = std::time::Instant::now();
    let problem = OdeBuilder::<NalgebraMat<f64>>::new()
        .t0(t0)
        .rtol(rtol)
        .atol(atol)
        .rhs_implicit(
            |x: &[f64], _p: &[f64], t: f64, y: &mut [f64]| f(x, t, y),
            |x: &[f64], _p: &[f64], t: f64, v: &[f64], y: &mut [f64]| {
                let mut c = cache.borrow_mut();
                if !(c.3 && c.0 == t && c.1[..] == x[..]) {
                    let mut fx = [0.0; 4];
                    f(x, t, &mut fx);
                    *c = (t, [x[0], x[1], x[2], x[3]], fx, true);
                }
                let vmax = v.iter().fold(0.0f64, |m, a| m.max(a.abs()));
                if vmax == 0.0 {
                    y.fill(0.0);
                    return;
                }
                let xmax = x.iter().fold(1.0f64, |m, a| m.max(a.abs()));
                let eps = f64::EPSILON.sqrt() * xmax / vmax;
                let xp: Vec<f64> = x.iter().zip(v).map(|(a, b)| a + eps * b).collect();
                let mut fp = [0.0; 4];
                f(&xp, t, &mut fp);
                for i in 0..4 {
                    y[i] = (fp[i] - c.2[i]) / eps;
                }
            },
        )
        .init(
            move |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(&y0),
            4,
        )
        .build()
        .map_err(|e| e.to_string())?;
    // diffsol stops after 50 Newton failures in a whole run unless told otherwise; lash's
    // stepper lifts the cap too (to its step budget).
    let mut problem = problem;
    problem.ode_options.max_nonlinear_solver_failures = usize::MAX;
    let mut solver = problem
        .bdf::<NalgebraLU<f64>>()
        .map_err(|e| e.to_string())?;
    let (ys, _) = solver.solve_dense(times).map_err(|e| e.to_string())?;
    let wall = start.elapsed().as_secs_f64();
    let rhs_evals = press.evals.get();
    let steps = solver.get_statistics().number_of_steps;
    let slider_a = times
        .iter()
        .enumerate()
        .map(|(k, &t)| {
            let y = [ys[(0, k)], ys[(1, k)], ys[(2, k)], ys[(3, k)]];
            press.accelerations(t, &y)[1]
        })
        .collect();
    Ok(DiffsolRun {
        slider_a,
        rhs_evals,
        steps,
        wall,
    })
}
