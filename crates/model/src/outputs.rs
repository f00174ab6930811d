//! Outputs by name: body points, the press quantities of docs/outputs.md ("Scene roles"),
//! clearance-joint forces, constraint violation, driver torques and the energy terms.
//!
//! ```text
//! driver torque τ_d = −λ_d                                  (driver on an integrated body)
//!              τ_d from  J_pᵀ λ_p = g_p + f_c,p − M_p a_p    (prescribed body p, Newton–Euler:
//!                        λ_p = (pin reaction, driver λ); f_c,p = −Σ J_r,pᵀ λ_r of the other
//!                        joints on p; g_p gravity and clearance forces on p)
//! T = Σ ½ m |ṙ|² + ½ I φ̇²     V = −Σ m g·r + Σ 2/5 K δ^{5/2} + Σ V_spring
//!                                                    (all bodies, prescribed too)
//! P_driver = Σ τ_d φ̇_d        D_contact = (F_N − K δ^{3/2}) δ̇     D_friction = −F_T v_T
//! D_film = −(F_r δ̇ + F_t t·ė)  P_load = Σ F·v + τ φ̇ (forces, torques)  P_motor = Σ τ ω
//! D_damper = Σ c L̇² + c θ̇²
//! d/dt (T + V) = P_driver + P_load + P_motor − D_contact − D_friction − D_film − D_damper
//!                (+ work of the Baumgarte terms)
//! ```
//! Source: docs/model.md §1–§5, docs/outputs.md ("`energy`", "`trajectory.csv`").

use crate::elements::interface::Account;
use crate::labels::Column;
use crate::mechanism::{FullEvaluation, Mechanism};
use crate::planar::{cross, perp, rot};
use crate::scene::error::SceneError;
use crate::scene::format::JointSpec;

pub use crate::roles::Roles;

/// Position, velocity and acceleration of a body point (global frame).
///
/// ```text
/// r^P = r + A s',  ṙ^P = ṙ + φ̇ k×(A s'),  r̈^P = r̈ + φ̈ k×(A s') − φ̇² A s'
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointKinematics {
    /// Position (m).
    pub pos: [f64; 2],
    /// Velocity (m/s).
    pub vel: [f64; 2],
    /// Acceleration (m/s²).
    pub acc: [f64; 2],
}

/// One clearance joint at one instant (docs/model.md §2–§4).
///
/// ```text
/// e/c, ε = |e|/c, δ = |e| − c, F_N, F_T (contact), film (F_r, F_t) and |film|
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ClearanceOutput {
    /// Joint name.
    pub name: String,
    /// e_x / c.
    pub ex_over_c: f64,
    /// e_y / c.
    pub ey_over_c: f64,
    /// ε = |e| / c.
    pub eps: f64,
    /// Penetration δ = |e| − c (m; negative when apart).
    pub delta: f64,
    /// Normal contact force F_N ≥ 0 (N).
    pub contact_force: f64,
    /// Friction force F_T along t (N, signed).
    pub friction_force: f64,
    /// Film force magnitude sqrt(F_r² + F_t²) (N; 0 when dry).
    pub film_force: f64,
    /// Film force along n (N, signed).
    pub film_fr: f64,
    /// Film force along t (N, signed).
    pub film_ft: f64,
}

/// One body at one instant: its centre of mass and angle, their rates and accelerations
/// (global frame).
///
/// ```text
/// (x, y, θ), (ẋ, ẏ, θ̇), (ẍ, ÿ, θ̈)   — θ̈ from the right-hand side at (t, y)
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct BodyOutput {
    /// x of the centre of mass (m).
    pub x: f64,
    /// y of the centre of mass (m).
    pub y: f64,
    /// Angle θ (rad, not wrapped).
    pub theta: f64,
    /// ẋ (m/s).
    pub vx: f64,
    /// ẏ (m/s).
    pub vy: f64,
    /// θ̇ (rad/s).
    pub omega: f64,
    /// ẍ (m/s²).
    pub ax: f64,
    /// ÿ (m/s²).
    pub ay: f64,
    /// θ̈ (rad/s²).
    pub alpha: f64,
}

/// Column suffixes of a body, in the order of [`Outputs::column_values`].
pub const BODY_COLUMNS: [&str; 9] = ["x", "y", "theta", "vx", "vy", "omega", "ax", "ay", "alpha"];
/// Column suffixes of a clearance joint, in the order of [`Outputs::column_values`].
pub const CLEARANCE_COLUMNS: [&str; 6] = [
    "ex_over_c",
    "ey_over_c",
    "delta",
    "contact_force",
    "friction_force",
    "film_force",
];
/// Column suffix of a driver.
pub const DRIVER_COLUMNS: [&str; 1] = ["torque"];
/// Column suffixes of a prismatic clearance joint, in the order of [`Outputs::column_values`].
pub const PRISMATIC_COLUMNS: [&str; 5] =
    ["offset", "tilt", "delta", "contact_force", "friction_force"];
/// SI units of [`BODY_COLUMNS`].
pub const BODY_UNITS: [&str; 9] = [
    "m", "m", "rad", "m/s", "m/s", "rad/s", "m/s²", "m/s²", "rad/s²",
];
/// SI units of [`CLEARANCE_COLUMNS`] (`1`: a ratio).
pub const CLEARANCE_UNITS: [&str; 6] = ["1", "1", "m", "N", "N", "N"];
/// SI unit of [`DRIVER_COLUMNS`].
pub const DRIVER_UNITS: [&str; 1] = ["N·m"];
/// SI units of [`PRISMATIC_COLUMNS`].
pub const PRISMATIC_UNITS: [&str; 5] = ["m", "rad", "m", "N", "N"];

/// One force element at one instant (docs/model.md §10).
///
/// ```text
/// spring_damper             load = F (N, tension > 0),  coordinate = L (m)
/// rotational_spring_damper  load = τ (N·m),             coordinate = θ = φ_a − φ_b (rad)
/// force                     load = f (N, along its direction), coordinate = NaN
/// torque                    load = τ (N·m),             coordinate = NaN
/// motor                     load = τ (N·m, on the rotor), coordinate = ω (rad/s)
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ElementOutput {
    /// Element name.
    pub name: String,
    /// Columns of the element, suffix and unit (`force` N, `length` m; `torque` N·m, `angle`
    /// rad; `force` N; `torque` N·m; `torque` N·m, `speed` rad/s): the first is `load`, the
    /// second `coordinate`.
    pub columns: &'static [Column],
    /// The element's force or torque.
    pub load: f64,
    /// Its coordinate: length, angle or speed (NaN for forces and torques).
    pub coordinate: f64,
    /// Power it puts into the mechanism (W; forces, torques and motors, else 0).
    pub power: f64,
    /// Power its damper dissipates (W, ≥ 0; springs, else 0).
    pub dissipation: f64,
    /// Its elastic potential (J; springs, else 0).
    pub potential: f64,
}

/// One prismatic clearance joint at one instant (docs/model.md §11).
///
/// ```text
/// offset = n·(r_C − o),  tilt = φ − φ_guide,  δ_i of the corners (m, < 0 apart),
/// F_N,i ≥ 0, F_T,i (along u);  delta = max δ_i, contact_force = Σ F_N,i, friction = Σ F_T,i
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct PrismaticOutput {
    /// Joint name.
    pub name: String,
    /// Lateral offset of the block centre from the guide's centre line (m).
    pub offset: f64,
    /// Tilt of the block from the guide (rad).
    pub tilt: f64,
    /// Deepest corner penetration max δ_i (m; negative when apart).
    pub delta: f64,
    /// Radial clearance c = (h − w)/2 (m).
    pub clearance: f64,
    /// Sum of the corners' normal forces (N).
    pub contact_force: f64,
    /// Sum of the corners' friction forces along the guide (N, signed).
    pub friction_force: f64,
    /// δ_i of each corner (m): (+ℓ/2, +w/2), (−ℓ/2, +w/2), (−ℓ/2, −w/2), (+ℓ/2, −w/2).
    pub corner_delta: [f64; 4],
    /// F_N,i of each corner (N).
    pub corner_force: [f64; 4],
}

/// Everything one evaluation at (t, y) reports (trajectory.csv columns and more).
///
/// ```text
/// crank angle φ_crank; slider x, ẋ, ẍ (centre of mass, global x); clearance joints;
/// ‖Φ(q, t)‖₂; driver torques; T; V = −Σ m g·r + Σ 2/5 K δ^{5/2}
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Outputs {
    /// Crank angle (rad, not wrapped): φ of the `crank` role's body, φ_a − φ_b of its
    /// revolute joint, or φ of the body the `crank_driver` role turns.
    pub crank_angle: Option<f64>,
    /// Rate of the crank angle (rad/s).
    pub crank_rate: Option<f64>,
    /// x of the `slider` role's centre of mass (m).
    pub slider_x: Option<f64>,
    /// ẋ of the slider (m/s).
    pub slider_v: Option<f64>,
    /// ẍ of the slider (m/s²), from the right-hand side at (t, y).
    pub slider_a: Option<f64>,
    /// Every body (integrated and prescribed), in scene order.
    pub bodies: Vec<BodyOutput>,
    /// Every clearance joint, in scene order.
    pub clearance: Vec<ClearanceOutput>,
    /// Euclidean norm of the position constraints Φ(q, t) of the KKT system.
    pub constraint_violation: f64,
    /// Torque (N·m, counter-clockwise on the driven body) of every driver, in scene order.
    pub driver_torques: Vec<f64>,
    /// Kinetic energy of all bodies (J).
    pub kinetic_energy: f64,
    /// Gravity potential of all bodies, the elastic contact potential of both kinds of
    /// clearance joint and the springs' potential (J).
    pub potential_energy: f64,
    /// Every force element, in scene order (docs/model.md §10).
    pub elements: Vec<ElementOutput>,
    /// Every prismatic clearance joint, in scene order (docs/model.md §11).
    pub prismatic: Vec<PrismaticOutput>,
}

/// Power terms at one instant (W); integrate them over time for the energy balance.
///
/// ```text
/// driver           P = Σ τ_d φ̇_d                       (work done on the mechanism)
/// contact_damping  D = Σ (F_N − K δ^{3/2}) δ̇            (≥ 0)
/// friction         D = −Σ F_T v_T                       (≥ 0)
/// film             D = −Σ (F_r δ̇ + F_t t·ė)             (dissipated by the film)
/// load             P = Σ F·ṙ^P + Σ τ φ̇                 (forces and torques, docs/model.md §10.3)
/// motor            P = Σ τ ω                            (motors, §10.4)
/// damper           D = Σ c L̇² + Σ c θ̇²                  (spring-dampers, ≥ 0, §10.1–§10.2)
/// contact_damping and friction include the prismatic clearance joints' corners (§11).
/// balance: ∫(P_driver + P_load + P_motor) − ΔT − ΔV
///          − ∫(D_contact + D_friction + D_film + D_damper) = 0 up to the Baumgarte work
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct PowerTerms {
    /// Driver power input (W).
    pub driver: f64,
    /// Power dissipated by contact damping (W).
    pub contact_damping: f64,
    /// Power dissipated by friction (W).
    pub friction: f64,
    /// Power dissipated by the oil film (W).
    pub film: f64,
    /// Power of the applied forces and torques (W).
    pub load: f64,
    /// Power of the motors (W).
    pub motor: f64,
    /// Power dissipated by the dampers of the spring-dampers (W).
    pub damper: f64,
}

impl PowerTerms {
    /// Power put in: driver + load + motor (W).
    pub fn input(&self) -> f64 {
        self.driver + self.load + self.motor
    }

    /// Power dissipated: contact damping + friction + film + damper (W).
    pub fn dissipated(&self) -> f64 {
        self.contact_damping + self.friction + self.film + self.damper
    }
}

/// The ideal slider-crank of docs/model.md §5, with r, l, ω and the crank angle derived from the
/// scene's geometry.
///
/// ```text
/// θ(t) = θ_driver(t) + offset,  S = sqrt(l² − r² sin²θ)
/// x = r cos θ + S                 (distance of the rod–slider pin from the crank pivot along
///                                  the slide)
/// ẋ = −r ω sin θ (1 + r cos θ / S)
/// ẍ = −r ω² cos θ − r² ω² cos 2θ / S − r⁴ ω² sin²θ cos²θ / S³
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IdealSliderCrank {
    /// Crank radius r (m): pivot to crank pin.
    pub r: f64,
    /// Rod length l (m): crank pin to slider pin.
    pub l: f64,
    /// Crank speed ω (rad/s).
    pub omega: f64,
    /// θ at t = 0 (rad), measured from the slide direction.
    pub theta0: f64,
    /// θ − φ_crank (rad): the geometric crank angle minus the crank body's angle.
    pub offset: f64,
}

impl Outputs {
    /// The values of the per-element columns named by [`Mechanism::output_columns`], in the
    /// same order, appended to `out`.
    pub fn column_values(&self, out: &mut Vec<f64>) {
        for b in &self.bodies {
            out.extend_from_slice(&[b.x, b.y, b.theta, b.vx, b.vy, b.omega, b.ax, b.ay, b.alpha]);
        }
        for c in &self.clearance {
            out.extend_from_slice(&[
                c.ex_over_c,
                c.ey_over_c,
                c.delta,
                c.contact_force,
                c.friction_force,
                c.film_force,
            ]);
        }
        out.extend_from_slice(&self.driver_torques);
        for e in &self.elements {
            out.push(e.load);
            if e.columns.len() > 1 {
                out.push(e.coordinate);
            }
        }
        for p in &self.prismatic {
            out.extend_from_slice(&[p.offset, p.tilt, p.delta, p.contact_force, p.friction_force]);
        }
    }
}

impl IdealSliderCrank {
    /// θ(t) = θ₀ + ω t.
    pub fn theta(&self, t: f64) -> f64 {
        self.theta0 + self.omega * t
    }
    /// θ of a crank body angle φ (see [`Outputs::crank_angle`]).
    pub fn theta_of_crank_angle(&self, phi: f64) -> f64 {
        phi + self.offset
    }
    /// x(θ) (m).
    pub fn x_at(&self, th: f64) -> f64 {
        let s = (self.l * self.l - self.r * self.r * th.sin().powi(2)).sqrt();
        self.r * th.cos() + s
    }
    /// ẋ(θ) (m/s).
    pub fn v_at(&self, th: f64) -> f64 {
        let s = (self.l * self.l - self.r * self.r * th.sin().powi(2)).sqrt();
        -self.r * self.omega * th.sin() * (1.0 + self.r * th.cos() / s)
    }
    /// ẍ(θ) (m/s²).
    pub fn a_at(&self, th: f64) -> f64 {
        let (r, w) = (self.r, self.omega);
        let (sn, cs) = th.sin_cos();
        let s = (self.l * self.l - r * r * sn * sn).sqrt();
        -r * w * w * cs
            - r * r * w * w * (2.0 * th).cos() / s
            - r.powi(4) * w * w * sn * sn * cs * cs / (s * s * s)
    }
    /// x(t) (m).
    pub fn x(&self, t: f64) -> f64 {
        self.x_at(self.theta(t))
    }
    /// ẋ(t) (m/s).
    pub fn v(&self, t: f64) -> f64 {
        self.v_at(self.theta(t))
    }
    /// ẍ(t) (m/s²).
    pub fn a(&self, t: f64) -> f64 {
        self.a_at(self.theta(t))
    }
}

impl Mechanism {
    /// Names of the per-element output columns, in the order of [`Outputs::column_values`]:
    ///
    /// ```text
    /// <body>.x .y .theta .vx .vy .omega .ax .ay .alpha          every body, scene order
    /// <joint>.ex_over_c .ey_over_c .delta .contact_force
    ///        .friction_force .film_force                       every clearance joint
    /// <driver>.torque                                          every driver joint
    /// <spring>.force .length | <rotational spring>.torque .angle | <force>.force
    /// | <torque>.torque | <motor>.torque .speed
    /// | <bushing>.force .stretch                               every force element
    /// <joint>.offset .tilt .delta .contact_force .friction_force
    ///                                                          every prismatic clearance joint
    /// ```
    pub fn output_columns(&self) -> Vec<String> {
        let mut names = Vec::new();
        for b in &self.scene().bodies {
            names.extend(BODY_COLUMNS.iter().map(|c| format!("{}.{c}", b.name)));
        }
        for c in &self.forces().revolute {
            names.extend(CLEARANCE_COLUMNS.iter().map(|s| format!("{}.{s}", c.name)));
        }
        for j in &self.scene().joints {
            if let JointSpec::Driver(d) = j {
                names.extend(DRIVER_COLUMNS.iter().map(|s| format!("{}.{s}", d.name)));
            }
        }
        let forces = self.forces();
        for (e, f) in forces.elements.iter().zip(&self.scene().forces) {
            names.extend(
                e.columns()
                    .iter()
                    .map(|s| format!("{}.{}", f.name(), s.suffix)),
            );
        }
        for p in &forces.prismatic {
            names.extend(PRISMATIC_COLUMNS.iter().map(|s| format!("{}.{s}", p.name)));
        }
        names
    }

    /// The SI unit of every column of [`Mechanism::output_columns`], in the same order (`1`
    /// for a ratio): the parts' own tables, and each force element's
    /// ([`crate::Column::unit`]).
    pub fn output_units(&self) -> Vec<&'static str> {
        let mut units = Vec::new();
        for _ in &self.scene().bodies {
            units.extend(BODY_UNITS);
        }
        for _ in &self.forces().revolute {
            units.extend(CLEARANCE_UNITS);
        }
        for j in &self.scene().joints {
            if let JointSpec::Driver(_) = j {
                units.extend(DRIVER_UNITS);
            }
        }
        let forces = self.forces();
        for e in &forces.elements {
            units.extend(e.columns().iter().map(|c| c.unit));
        }
        for _ in &forces.prismatic {
            units.extend(PRISMATIC_UNITS);
        }
        units
    }

    /// One evaluation of every output at (t, y). Non-finite values (a singular KKT matrix)
    /// come out as NaN.
    pub fn outputs(&self, t: f64, y: &[f64]) -> Outputs {
        self.outputs_of(&self.full_evaluation(t, y))
    }

    /// [`Mechanism::outputs`] and [`Mechanism::power`] at (t, y) from one full evaluation: the
    /// same values as the two calls, at the cost of one.
    pub fn outputs_and_power(&self, t: f64, y: &[f64]) -> (Outputs, PowerTerms) {
        let f = self.full_evaluation(t, y);
        (self.outputs_of(&f), self.power_of(&f))
    }

    /// The outputs of one full evaluation `f`.
    fn outputs_of(&self, f: &FullEvaluation) -> Outputs {
        let (sc, forces, roles) = (&f.sc, self.forces(), self.roles());
        let nan_if = |v: f64| if f.ok { v } else { f64::NAN };
        let side = |k: Option<usize>, v: &[[f64; 3]]| k.map_or(0.0, |k| v[k][2]);
        let crank_angle = roles
            .crank
            .map(|[a, b]| side(a, &sc.pose) - side(b, &sc.pose));
        let crank_rate = roles
            .crank
            .map(|[a, b]| side(a, &sc.vel) - side(b, &sc.vel));
        let (slider_x, slider_v, slider_a) = match roles.slider {
            Some(k) => (
                Some(sc.pose[k][0]),
                Some(sc.vel[k][0]),
                Some(nan_if(sc.acc[k][0])),
            ),
            None => (None, None, None),
        };
        let clearance = forces
            .revolute
            .iter()
            .zip(&sc.revolute)
            .map(|(c, ev)| ClearanceOutput {
                name: c.name.clone(),
                ex_over_c: ev.st.e[0] / c.c,
                ey_over_c: ev.st.e[1] / c.c,
                eps: ev.st.eps,
                delta: ev.st.delta,
                contact_force: ev.f_n,
                friction_force: ev.f_t,
                film_force: ev.f_r.hypot(ev.f_tf),
                film_fr: ev.f_r,
                film_ft: ev.f_tf,
            })
            .collect();
        let bodies = (0..self.body_info().len())
            .map(|k| {
                let ([x, y, theta], [vx, vy, omega]) = (sc.pose[k], sc.vel[k]);
                let [ax, ay, alpha] = sc.acc[k].map(nan_if);
                BodyOutput {
                    x,
                    y,
                    theta,
                    vx,
                    vy,
                    omega,
                    ax,
                    ay,
                    alpha,
                }
            })
            .collect();
        let constraint_violation = f.violation;
        let driver_torques = f.torques.iter().map(|x| nan_if(x.1)).collect();
        let mut kinetic = 0.0;
        let mut potential = 0.0;
        for (k, b) in self.body_info().iter().enumerate() {
            let [vx, vy, w] = sc.vel[k];
            kinetic += 0.5 * b.mass * (vx * vx + vy * vy) + 0.5 * b.inertia * w * w;
            if let Some(g) = forces.gravity {
                potential -= b.mass * (g[0] * sc.pose[k][0] + g[1] * sc.pose[k][1]);
            }
        }
        for (c, ev) in forces.revolute.iter().zip(&sc.revolute) {
            potential += c.normal.potential(ev.st.delta);
        }
        let elements: Vec<ElementOutput> = forces
            .elements
            .iter()
            .zip(&sc.el)
            .zip(&self.scene().forces)
            .map(|((e, ev), f)| ElementOutput {
                name: f.name().to_string(),
                columns: e.columns(),
                load: ev.load,
                coordinate: ev.coord,
                power: ev.power,
                dissipation: ev.dissipation,
                potential: ev.potential,
            })
            .collect();
        potential += elements.iter().map(|e| e.potential).sum::<f64>();
        let prismatic: Vec<PrismaticOutput> = forces
            .prismatic
            .iter()
            .zip(&sc.pr)
            .map(|(p, ev)| {
                potential += ev.delta.iter().map(|&d| p.normal.potential(d)).sum::<f64>();
                PrismaticOutput {
                    name: p.name.clone(),
                    offset: ev.offset,
                    tilt: ev.tilt,
                    delta: ev.delta.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                    clearance: p.clearance,
                    contact_force: ev.f_n.iter().sum(),
                    friction_force: ev.f_t.iter().sum(),
                    corner_delta: ev.delta,
                    corner_force: ev.f_n,
                }
            })
            .collect();
        Outputs {
            elements,
            prismatic,
            crank_angle,
            crank_rate,
            slider_x,
            slider_v,
            slider_a,
            bodies,
            clearance,
            constraint_violation,
            driver_torques,
            kinetic_energy: kinetic,
            potential_energy: potential,
        }
    }

    /// Power terms at (t, y): driver input and the dissipation of contact damping, friction and
    /// film (W). The caller integrates them along the trajectory (no quadrature components are
    /// added to the state, so the state stays (q, q̇) for every method).
    pub fn power(&self, t: f64, y: &[f64]) -> PowerTerms {
        self.power_of(&self.full_evaluation(t, y))
    }

    /// The power terms of one full evaluation `f`.
    fn power_of(&self, f: &FullEvaluation) -> PowerTerms {
        let (sc, forces, scene) = (&f.sc, self.forces(), self.scene());
        let mut p = PowerTerms::default();
        for &(j, tau) in &f.torques {
            if let JointSpec::Driver(d) = &scene.joints[j] {
                let k = scene.body_index(&d.body).expect("validated");
                p.driver += tau * sc.vel[k][2];
            }
        }
        if !f.ok {
            p.driver = f64::NAN;
        }
        let kin = sc.kin();
        for (c, ev) in forces.revolute.iter().zip(&sc.revolute) {
            let st = &ev.st;
            if st.delta > 0.0 {
                p.contact_damping += (ev.f_n - ev.elastic) * st.delta_dot;
                p.friction -= ev.f_t * st.v_t;
            }
            if c.film.is_some() {
                // t·ė = v_T − R_J φ̇_J + R_B φ̇_B
                let ed_t = st.v_t - c.rj * c.journal.omega(&kin) + c.rb * c.bearing.omega(&kin);
                p.film -= ev.f_r * st.delta_dot + ev.f_tf * ed_t;
            }
        }
        for (e, ev) in forces.elements.iter().zip(&sc.el) {
            match e.account() {
                Account::Motor => p.motor += ev.power,
                _ => p.load += ev.power,
            }
            p.damper += ev.dissipation;
        }
        for ev in &sc.pr {
            for i in 0..4 {
                if ev.delta[i] > 0.0 {
                    p.contact_damping += (ev.f_n[i] - ev.elastic[i]) * ev.delta_dot[i];
                    p.friction -= ev.f_t[i] * ev.v_t[i];
                }
            }
        }
        p
    }

    /// Position, velocity and acceleration of the named point of the named body at (t, y).
    pub fn point_kinematics(
        &self,
        body: &str,
        point: &str,
        t: f64,
        y: &[f64],
    ) -> Result<PointKinematics, SceneError> {
        let k = self
            .scene()
            .body_index(body)
            .ok_or_else(|| SceneError::Unknown(format!("body '{body}'")))?;
        let s = *self.body_info()[k]
            .points
            .get(point)
            .ok_or_else(|| SceneError::Unknown(format!("point '{point}' on body '{body}'")))?;
        let mut sc = self.scratch();
        let ok = self.evaluate(t, y, &mut sc, false);
        let a = rot(sc.cs[k], s);
        let b = perp(a);
        let [x, yy, _] = sc.pose[k];
        let [vx, vy, w] = sc.vel[k];
        let [ax, ay, al] = sc.acc[k];
        let acc = [ax + al * b[0] - w * w * a[0], ay + al * b[1] - w * w * a[1]];
        Ok(PointKinematics {
            pos: [x + a[0], yy + a[1]],
            vel: [vx + w * b[0], vy + w * b[1]],
            acc: if ok { acc } else { [f64::NAN; 2] },
        })
    }

    /// The closed-form ideal slider-crank of docs/model.md §5, when the roles are declared and the
    /// geometry is an in-line slider-crank: the crank (driven body) pinned to the ground at O,
    /// a rod pinned to the crank and joined (revolute or clearance joint) to the slider, and
    /// the slider on a translational joint whose line passes through O, on the +x branch.
    pub fn ideal_slider_crank(&self) -> Option<IdealSliderCrank> {
        let scene = self.scene();
        let crank = self.roles().crank_body?;
        let slider = self.roles().slider?;
        let omega = self.crank_speed()?;
        let crank_name = &scene.bodies[crank].name;
        let slider_name = &scene.bodies[slider].name;
        let pt = |body: &str, point: &Option<String>| -> Option<[f64; 2]> {
            let k = scene.body_index(body)?;
            scene.bodies[k].points.get(point.as_ref()?).copied()
        };
        // Crank pivot on the ground.
        let (s_o, ground_o) = scene.joints.iter().find_map(|j| match j {
            JointSpec::Revolute(r)
                if &r.a.body == crank_name && r.b.body == crate::scene::GROUND =>
            {
                Some((pt(&r.a.body, &r.a.point)?, r.b.at?))
            }
            JointSpec::Revolute(r)
                if &r.b.body == crank_name && r.a.body == crate::scene::GROUND =>
            {
                Some((pt(&r.b.body, &r.b.point)?, r.a.at?))
            }
            _ => None,
        })?;
        // Rod pinned to the crank.
        let (rod, s_a, a_r) = scene.joints.iter().find_map(|j| match j {
            JointSpec::Revolute(r)
                if &r.a.body == crank_name
                    && r.b.body != crate::scene::GROUND
                    && &r.b.body != slider_name =>
            {
                Some((
                    r.b.body.clone(),
                    pt(&r.a.body, &r.a.point)?,
                    pt(&r.b.body, &r.b.point)?,
                ))
            }
            JointSpec::Revolute(r)
                if &r.b.body == crank_name
                    && r.a.body != crate::scene::GROUND
                    && &r.a.body != slider_name =>
            {
                Some((
                    r.a.body.clone(),
                    pt(&r.b.body, &r.b.point)?,
                    pt(&r.a.body, &r.a.point)?,
                ))
            }
            _ => None,
        })?;
        // Rod joined to the slider.
        let (b_r, p_s) = scene.joints.iter().find_map(|j| match j {
            JointSpec::Revolute(r) if r.a.body == rod && &r.b.body == slider_name => {
                Some((pt(&rod, &r.a.point)?, pt(slider_name, &r.b.point)?))
            }
            JointSpec::Revolute(r) if r.b.body == rod && &r.a.body == slider_name => {
                Some((pt(&rod, &r.b.point)?, pt(slider_name, &r.a.point)?))
            }
            JointSpec::Clearance(c) if c.journal.body == rod && &c.bearing.body == slider_name => {
                Some((
                    pt(&rod, &c.journal.point)?,
                    pt(slider_name, &c.bearing.point)?,
                ))
            }
            JointSpec::Clearance(c) if c.bearing.body == rod && &c.journal.body == slider_name => {
                Some((
                    pt(&rod, &c.bearing.point)?,
                    pt(slider_name, &c.journal.point)?,
                ))
            }
            _ => None,
        })?;
        // The slide.
        let (origin, dir) = scene.joints.iter().find_map(|j| match j {
            JointSpec::Translational(t) if &t.body == slider_name => Some((t.origin, t.direction)),
            _ => None,
        })?;
        let len = dir[0].hypot(dir[1]);
        let u = [dir[0] / len, dir[1] / len];
        let d = [s_a[0] - s_o[0], s_a[1] - s_o[1]];
        let r = d[0].hypot(d[1]);
        let l = (b_r[0] - a_r[0]).hypot(b_r[1] - a_r[1]);
        if !(r > 0.0 && l > r) {
            return None;
        }
        let off_line = cross(u, [ground_o[0] - origin[0], ground_o[1] - origin[1]]);
        if off_line.abs() > 1e-9 * l {
            return None;
        }
        let angle_u = u[1].atan2(u[0]);
        let offset = d[1].atan2(d[0]) - angle_u;
        let JointSpec::Driver(drv) = &scene.joints[self.roles().crank_driver?] else {
            return None;
        };
        let ideal = IdealSliderCrank {
            r,
            l,
            omega,
            theta0: drv.theta0 + offset,
            offset,
        };
        // The slider pin must be on the +S branch at the initial state.
        let t0 = self.t_start();
        let mut sc = self.scratch();
        self.kinematics(t0, &self.initial_state(), &mut sc);
        let ps = rot(sc.cs[slider], p_s);
        let pin = [sc.pose[slider][0] + ps[0], sc.pose[slider][1] + ps[1]];
        let along = u[0] * (pin[0] - ground_o[0]) + u[1] * (pin[1] - ground_o[1]);
        let theta = ideal.theta_of_crank_angle(sc.pose[crank][2]);
        if (along - ideal.x_at(theta)).abs() > 1e-3 * l {
            return None;
        }
        Some(ideal)
    }
}
