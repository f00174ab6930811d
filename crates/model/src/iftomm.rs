//! Generators of the benchmark scenes of `cases/iftomm/` and their one-degree-of-freedom
//! references (cases/iftomm/README.md).
//!
//! ```text
//! A01 simple pendulum    a 1 kg bob on a 1 m arm, pinned to the ground, released at rest
//!                        from the horizontal; the bob a body of I_c = 1e-6 kg·m² (a point
//!                        mass cannot be a body): I_O = m l² + I_c
//! A02 N-four-bar         N + 1 vertical cranks (ground pins at x = 0, 1, …, N) and N
//!                        horizontal couplers joining their tops: 2N + 1 uniform rods of 1 m,
//!                        1 kg; B0 (the top of crank 0) at 1 m/s in +x at t = 0
//! parallel cranks        three cranks of 1 m, 1 kg (ground pins at x = 0, 1, 2) joined by one
//!                        rigid bar of 2 m, 2 kg through three pins: 12 equations, rank 11
//! ```
//! Each reduces to one degree of freedom θ (the angle of every crank from +x): the cranks turn
//! together, the couplers (the bar) translate with the crank tips, so
//!
//! ```text
//! T = ½ J θ̇²,  V = g K sin θ,   J θ̈ = −g K cos θ
//! A01:  J = m l² + I_c,          K = m l
//! A02:  J = (N + 1) m L²/3 + N m L²,   K = (N + 1) m L/2 + N m L
//! bar:  J = 3 m L²/3 + m_bar L²,       K = 3 m L/2 + m_bar L
//! ```
//! [`OneDof::solve`] integrates that equation at rtol 1e-13 (DOP853).

use serde_json::{json, Value};

use crate::scene::format::Scene;

/// Gravity of the benchmarks (m/s²), in −y.
pub const G: f64 = 9.81;

/// The one-degree-of-freedom equation J θ̈ = −g K cos θ of a benchmark (module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OneDof {
    /// Inertia about the crank pivots, reduced to θ (kg·m²).
    pub j: f64,
    /// Moment of the weights about the pivots at θ = 0, divided by g (kg·m).
    pub k: f64,
    /// θ(0) (rad).
    pub theta0: f64,
    /// θ̇(0) (rad/s).
    pub omega0: f64,
}

impl OneDof {
    /// Total energy ½ J θ̇² + g K sin θ (J).
    pub fn energy(&self, theta: f64, omega: f64) -> f64 {
        0.5 * self.j * omega * omega + G * self.k * theta.sin()
    }

    /// (θ, θ̇) at each of the increasing times `ts` (from t = 0), by DOP853 at rtol 1e-13,
    /// atol 1e-14.
    pub fn solve(&self, ts: &[f64]) -> Vec<[f64; 2]> {
        use lash_solver::{solve, Atol, Method, OdeSystem, Output, SolverOptions};
        struct Eq(OneDof);
        impl OdeSystem for Eq {
            fn dim(&self) -> usize {
                2
            }
            fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
                dy[0] = y[1];
                dy[1] = -G * self.0.k * y[0].cos() / self.0.j;
            }
        }
        let eq = Eq(*self);
        let opts = SolverOptions {
            method: Method::Dop853,
            rtol: 1e-13,
            atol: Atol::Scalar(1e-14),
            output: Output::Times(ts.to_vec()),
            ..Default::default()
        };
        let t_end = ts.last().copied().unwrap_or(0.0).max(1e-9);
        let sol = solve(&eq, (0.0, t_end), &[self.theta0, self.omega0], &opts)
            .expect("a smooth two-dimensional ODE");
        (0..sol.len())
            .map(|k| [sol.state(k)[0], sol.state(k)[1]])
            .collect()
    }
}

/// A uniform rod of 1 m between its points A (−½, 0) and B (½, 0), its centre at `c`, angle
/// `phi`, turning at `omega` with centre velocity `v`.
fn rod(name: &str, mass: f64, len: f64, c: [f64; 2], phi: f64, v: [f64; 2], omega: f64) -> Value {
    json!({"name": name, "mass": mass, "inertia": mass * len * len / 12.0,
           "points": {"A": [-len / 2.0, 0.0], "B": [len / 2.0, 0.0]},
           "position": c, "angle": phi, "velocity": v, "angular_velocity": omega})
}

fn pin(name: &str, a: (&str, &str), b: Value) -> Value {
    json!({"type": "revolute", "name": name, "a": {"body": a.0, "point": a.1}, "b": b})
}

fn at(body: &str, point: &str) -> Value {
    json!({"body": body, "point": point})
}

fn ground(x: f64, y: f64) -> Value {
    json!({"body": "ground", "at": [x, y]})
}

fn scene(v: Value) -> Scene {
    Scene::from_json_str(&v.to_string()).expect("a valid generated scene")
}

/// A01: the simple pendulum (module doc), 10 s, and its reference.
pub fn simple_pendulum() -> (Scene, OneDof) {
    let (m, l, ic) = (1.0, 1.0, 1e-6);
    let s = scene(json!({
        "description": "IFToMM A01: simple pendulum, 1 kg at 1 m, released from the horizontal",
        "bodies": [{"name": "bob", "mass": m, "inertia": ic, "points": {"O": [-l, 0.0]},
                    "position": [l, 0.0]}],
        "joints": [pin("pivot", ("bob", "O"), ground(0.0, 0.0))],
        "gravity": [0.0, -G],
        "t_end": 10.0
    }));
    (
        s,
        OneDof {
            j: m * l * l + ic,
            k: m * l,
            theta0: 0.0,
            omega0: 0.0,
        },
    )
}

/// A02: the N-four-bar (module doc) over `t_end` s, and its reference. Bodies in chain order
/// (crank 0, coupler 0, crank 1, …), so that M + Φ_qᵀαΦ_q is banded. The scene chooses the
/// augmented Lagrangian with penalty 1e7 and ω = 300 1/s (its notes say why).
pub fn n_four_bar(n: usize, t_end: f64) -> (Scene, OneDof) {
    let (m, l) = (1.0, 1.0);
    let half = std::f64::consts::FRAC_PI_2;
    let mut bodies = Vec::new();
    let mut joints = Vec::new();
    for i in 0..=n {
        let x = i as f64;
        let crank = format!("crank{i}");
        // Cranks vertical, turning at −1 rad/s (their tips at +1 m/s in x).
        bodies.push(rod(&crank, m, l, [x, 0.5], half, [0.5, 0.0], -1.0));
        joints.push(pin(&format!("ground{i}"), (&crank, "A"), ground(x, 0.0)));
        if i < n {
            let coupler = format!("coupler{i}");
            bodies.push(rod(&coupler, m, l, [x + 0.5, 1.0], 0.0, [1.0, 0.0], 0.0));
            joints.push(pin(&format!("left{i}"), (&coupler, "A"), at(&crank, "B")));
            joints.push(pin(
                &format!("right{i}"),
                (&coupler, "B"),
                at(&format!("crank{}", i + 1), "B"),
            ));
        }
    }
    // B0's velocity held exactly: the crank's rate.
    bodies[0]["initial_velocity"] = json!({"omega": -1.0});
    let nf = n as f64;
    let s = scene(json!({
        "description": format!("IFToMM A02: N-four-bar, N = {n}, B0 at 1 m/s in +x"),
        "notes": [
            "Singular (N + 1 degrees of freedom) at every horizontal position: needs the \
             augmented Lagrangian (Lagrange-Baumgarte stops there or changes branch).",
            "penalty 1e7 and omega 300 1/s: near the singular positions the multiplier \
             iteration corrects the near-null constraint modes by about alpha sigma per \
             iteration, and a stiff violation dynamics keeps the parallelograms on their \
             branch; with the defaults (1e4, 10 1/s) N = 2 is 1.3e-2 m off after 10 s."
        ],
        "bodies": bodies,
        "joints": joints,
        "gravity": [0.0, -G],
        "formulation": "augmented_lagrangian",
        "augmented_lagrangian": {"penalty": 1e7, "omega": 300.0},
        "t_end": t_end
    }));
    (
        s,
        OneDof {
            j: (nf + 1.0) * m * l * l / 3.0 + nf * m * l * l,
            k: (nf + 1.0) * m * l / 2.0 + nf * m * l,
            theta0: half,
            omega0: -1.0,
        },
    )
}

/// Three parallel cranks joined by one rigid bar (module doc), hanging, started at
/// θ = −π/2 + 0.3 rad, θ̇ = 2 rad/s (a swing of about ±0.67 rad about the bottom, never
/// through the horizontal), over `t_end` s, and its reference: a redundant constraint set
/// (rank 11 of 12).
pub fn parallel_cranks(t_end: f64) -> (Scene, OneDof) {
    let (m, l, mb) = (1.0, 1.0, 2.0);
    let (th, w) = (-std::f64::consts::FRAC_PI_2 + 0.3, 2.0);
    let (s, c) = th.sin_cos();
    let mut bodies = Vec::new();
    let mut joints = Vec::new();
    for i in 0..3 {
        let x = i as f64;
        let crank = format!("crank{i}");
        bodies.push(rod(
            &crank,
            m,
            l,
            [x + 0.5 * c, 0.5 * s],
            th,
            [-0.5 * w * s, 0.5 * w * c],
            w,
        ));
        joints.push(pin(&format!("ground{i}"), (&crank, "A"), ground(x, 0.0)));
    }
    let mut bar = rod("bar", mb, 2.0, [1.0 + c, s], 0.0, [-w * s, w * c], 0.0);
    bar["points"]["M"] = json!([0.0, 0.0]);
    bodies.push(bar);
    for (i, p) in ["A", "M", "B"].into_iter().enumerate() {
        joints.push(pin(
            &format!("bar{i}"),
            ("bar", p),
            at(&format!("crank{i}"), "B"),
        ));
    }
    bodies[0]["initial_velocity"] = json!({"omega": w});
    let sc = scene(json!({
        "description": "Three parallel cranks joined by one rigid coupling bar (redundant)",
        "bodies": bodies,
        "joints": joints,
        "gravity": [0.0, -G],
        "formulation": "augmented_lagrangian",
        "t_end": t_end
    }));
    (
        sc,
        OneDof {
            j: 3.0 * m * l * l / 3.0 + mb * l * l,
            k: 3.0 * m * l / 2.0 + mb * l,
            theta0: th,
            omega0: w,
        },
    )
}
