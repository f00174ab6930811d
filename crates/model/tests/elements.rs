//! The force elements and the prismatic clearance joint of docs/model.md §10–§11, each
//! against a closed form or an independent computation.
//!
//! ```text
//! mass on a spring-damper     x(t) = x₀ e^{−ζω t}(cos ω_d t + ζ/√(1−ζ²) sin ω_d t)
//! pendulum on a torsion spring θ(t) = θ₀ + A cos(√(k/I_O) t)
//! constant torque              ½ I_O ω² = τ (θ − θ₀)
//! tabulated loads              f at and between the table points, outside rules
//! motor (line T_s(1 − ω/ω₀))   ω(t) = ω₀ (1 − exp(−T_s t/(I ω₀))),  τ(0) = T_s
//! block hitting a guide face   1-DOF Hertz impact m δ̈ = −2K δ^{3/2}: δ_max, t_c = 2.9432 δ_max/v
//! energy balance               ∫(P_in − D) = Δ(T + V) to 1e-6 of the energy that flowed
//! ```

use lash_model::{Mechanism, Scene, SceneError};
use lash_solver::{
    solve, Atol, EventAction, EventHit, EventSpec, Method, OdeSystem, Output, SolverOptions,
};
use serde_json::{json, Value};

fn build(v: &Value) -> Mechanism {
    // Lagrange–Baumgarte: the tests read the absolute state y = (q, q̇).
    let mut s = Scene::from_json_str(&v.to_string()).unwrap();
    s.formulation = lash_model::FormulationName::LagrangeBaumgarte;
    Mechanism::from_scene(&s).unwrap()
}

fn error_of(v: &Value) -> SceneError {
    match Scene::from_json_str(&v.to_string()) {
        Err(e) => e,
        Ok(s) => Mechanism::from_scene(&s).expect_err("the scene must be rejected"),
    }
}

fn tight(method: Method) -> SolverOptions {
    SolverOptions {
        method,
        rtol: 1e-11,
        atol: Atol::Scalar(1e-13),
        ..Default::default()
    }
}

/// A 1-DOF slider: a body on a translational joint along x.
fn slider(mass: f64, x0: f64, forces: Value, t_end: f64) -> Value {
    json!({
        "bodies": [{"name": "m", "mass": mass, "inertia": 1.0, "position": [x0, 0.0],
                    "points": {"C": [0.0, 0.0]}}],
        "joints": [{"type": "translational", "name": "slide", "body": "m", "point": "C",
                    "direction": [1.0, 0.0], "angle": 0.0}],
        "forces": forces,
        "t_end": t_end
    })
}

/// A body pinned to the ground at its centre of mass.
fn flywheel(inertia: f64, forces: Value, t_end: f64) -> Value {
    json!({
        "bodies": [{"name": "w", "mass": 2.0, "inertia": inertia, "points": {"O": [0.0, 0.0]}}],
        "joints": [{"type": "revolute", "name": "pivot", "a": {"body": "w", "point": "O"},
                    "b": {"body": "ground", "at": [0.0, 0.0]}}],
        "forces": forces,
        "t_end": t_end
    })
}

#[test]
fn a_mass_on_a_spring_damper_oscillates_and_decays_as_the_closed_form() {
    let (m, k, c, l0, x0) = (2.0, 800.0, 4.0, 1.0, 1.1);
    let scene = slider(
        m,
        x0,
        json!([{"type": "spring_damper", "name": "s", "a": {"body": "ground", "at": [0.0, 0.0]},
                "b": {"body": "m", "point": "C"}, "stiffness": k, "damping": c,
                "free_length": l0}]),
        1.0,
    );
    let mech = build(&scene);
    let w = (k / m).sqrt();
    let zeta = c / (2.0 * (k * m).sqrt());
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let exact = |t: f64| {
        let a = x0 - l0;
        l0 + a
            * (-zeta * w * t).exp()
            * ((wd * t).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * t).sin())
    };
    let times: Vec<f64> = (1..=20).map(|i| i as f64 * 0.05).collect();
    // An explicit and an implicit method (the latter uses the Jacobian of the elements).
    for method in [Method::Dop853, Method::Rodas5p] {
        let opts = SolverOptions {
            output: Output::Times(times.clone()),
            ..tight(method)
        };
        let sol = solve(&mech, (0.0, 1.0), &mech.initial_state(), &opts).unwrap();
        for (i, &t) in sol.t.iter().enumerate() {
            let o = mech.outputs(t, sol.state(i));
            let x = o.bodies[0].x;
            assert!(
                (x - exact(t)).abs() < 1e-7 * (x0 - l0),
                "{method:?} t = {t}: x = {x}, closed form {}",
                exact(t)
            );
            // The spring's columns: its force k(L − L₀) + c L̇ and its length.
            let e = &o.elements[0];
            let v = o.bodies[0].vx;
            assert!((e.coordinate - x).abs() < 1e-15);
            assert!((e.load - (k * (x - l0) + c * v)).abs() < 1e-9 * k * (x0 - l0));
        }
    }
}

#[test]
fn a_pendulum_on_a_torsion_spring_swings_at_its_closed_form_frequency() {
    // A rod of length 0.5 m pinned at one end, no gravity, a torsion spring to the ground.
    let (m, len, k): (f64, f64, f64) = (1.5, 0.5, 3.0);
    let inertia = m * len * len / 12.0;
    let i_o = inertia + m * len * len / 4.0;
    let (theta0, amp): (f64, f64) = (0.2, 0.3);
    let scene = json!({
        "bodies": [{"name": "rod", "mass": m, "inertia": inertia,
                    "position": [0.25 * (theta0 + amp).cos(), 0.25 * (theta0 + amp).sin()],
                    "angle": theta0 + amp, "points": {"O": [-0.25, 0.0]}}],
        "joints": [{"type": "revolute", "name": "pin", "a": {"body": "rod", "point": "O"},
                    "b": {"body": "ground", "at": [0.0, 0.0]}}],
        "forces": [{"type": "rotational_spring_damper", "name": "torsion", "a": "rod",
                    "stiffness": k, "free_angle": theta0}],
        "t_end": 2.0
    });
    let mech = build(&scene);
    let w = (k / i_o).sqrt();
    let times: Vec<f64> = (1..=40).map(|i| i as f64 * 0.05).collect();
    let opts = SolverOptions {
        output: Output::Times(times),
        ..tight(Method::Dop853)
    };
    let sol = solve(&mech, (0.0, 2.0), &mech.initial_state(), &opts).unwrap();
    for (i, &t) in sol.t.iter().enumerate() {
        let o = mech.outputs(t, sol.state(i));
        let th = o.bodies[0].theta;
        let exact = theta0 + amp * (w * t).cos();
        assert!(
            (th - exact).abs() < 1e-8,
            "t = {t}: θ = {th}, closed form {exact}"
        );
        // Its columns: τ = k (θ − θ₀), θ; energy ½ I_O θ̇² + ½ k (θ − θ₀)² constant.
        let e = &o.elements[0];
        assert!((e.load - k * (th - theta0)).abs() < 1e-12);
        assert!((e.coordinate - th).abs() < 1e-15);
        let energy = o.kinetic_energy + o.potential_energy;
        assert!((energy - 0.5 * k * amp * amp).abs() < 1e-9 * k * amp * amp);
    }
}

#[test]
fn a_constant_torque_does_the_work_the_kinetic_energy_gains() {
    let (inertia, tau) = (0.05, 0.7);
    let mech = build(&flywheel(
        inertia,
        json!([{"type": "torque", "name": "tq", "body": "w", "value": tau}]),
        1.0,
    ));
    let times: Vec<f64> = (1..=10).map(|i| i as f64 * 0.1).collect();
    let opts = SolverOptions {
        output: Output::Times(times),
        ..tight(Method::Dop853)
    };
    let sol = solve(&mech, (0.0, 1.0), &mech.initial_state(), &opts).unwrap();
    for (i, &t) in sol.t.iter().enumerate() {
        let o = mech.outputs(t, sol.state(i));
        let (th, w) = (o.bodies[0].theta, o.bodies[0].omega);
        let work = tau * th;
        assert!((o.kinetic_energy - work).abs() < 1e-9 * work, "t = {t}");
        assert!((w - tau * t / inertia).abs() < 1e-9 * tau * t / inertia);
        // Its power is τ ω.
        let p = mech.power(t, sol.state(i));
        assert!((p.load - tau * w).abs() < 1e-12 * tau * w);
        assert_eq!(p.input(), p.load);
    }
}

#[test]
fn a_tabulated_load_is_exact_at_and_between_table_points_and_outside_as_stated() {
    let points = [[0.0, 0.0], [0.1, 100.0], [0.3, -50.0], [0.4, 0.0]];
    let at = |t: f64, outside: &str| {
        let mech = build(&slider(
            1.0,
            0.0,
            json!([{"type": "force", "name": "f", "body": "m", "direction": [2.0, 0.0],
                    "table": {"input": {"of": "time"}, "points": points, "outside": outside}}]),
            1.0,
        ));
        let y = mech.initial_state();
        let o = mech.outputs(t, &y);
        // The force acts along +x at the centre of mass: ẍ = f/m.
        assert!((o.bodies[0].ax - o.elements[0].load).abs() < 1e-12);
        o.elements[0].load
    };
    for p in points {
        assert_eq!(at(p[0], "hold"), p[1], "at the table point {}", p[0]);
    }
    // Between points: linear interpolation.
    assert!((at(0.05, "hold") - 50.0).abs() < 1e-12);
    assert!((at(0.2, "hold") - 25.0).abs() < 1e-12);
    assert!((at(0.375, "hold") + 12.5).abs() < 1e-12);
    // Outside: held, or the end segments extended.
    assert_eq!(at(-1.0, "hold"), 0.0);
    assert_eq!(at(2.0, "hold"), 0.0);
    assert!((at(-0.05, "linear") + 50.0).abs() < 1e-12);
    assert!((at(0.5, "linear") - 50.0).abs() < 1e-12);

    // A table of a coordinate: the slider's x (a press punching load over part of the stroke,
    // acting only while it opposes the motion).
    let mech = build(&slider(
        1.0,
        0.0,
        json!([{"type": "force", "name": "punch", "body": "m", "point": "C",
                "direction": [-1.0, 0.0], "acts": "opposing",
                "table": {"input": {"of": "x", "body": "m", "point": "C"},
                          "points": [[0.0, 0.0], [0.01, 500.0], [0.02, 500.0], [0.03, 0.0]]}}]),
        1.0,
    ));
    let nq = 3;
    let state = |x: f64, v: f64| {
        let mut y = mech.initial_state();
        y[0] = x;
        y[nq] = v;
        y
    };
    let load = |x: f64, v: f64| mech.outputs(0.0, &state(x, v)).elements[0].load;
    assert!((load(0.005, 1.0) - 250.0).abs() < 1e-12);
    assert_eq!(load(0.015, 1.0), 500.0);
    assert!((load(0.025, 1.0) - 250.0).abs() < 1e-12);
    assert_eq!(load(0.05, 1.0), 0.0);
    // Moving back (−x) the load would push along the motion: it does not act.
    assert_eq!(load(0.015, -1.0), 0.0);
    let p = mech.power(0.0, &state(0.015, 1.0));
    assert!((p.load + 500.0).abs() < 1e-12);
}

#[test]
fn a_spring_with_a_force_length_curve_stores_the_curve_integral() {
    // F(L) = 0 below 1 m, then 100 N/m up to 1.2 m, held (the integral of a hold is linear).
    let mech = build(&slider(
        1.0,
        1.1,
        json!([{"type": "spring_damper", "name": "s", "a": {"body": "ground", "at": [0.0, 0.0]},
                "b": {"body": "m", "point": "C"},
                "curve": {"points": [[1.0, 0.0], [1.2, 20.0]]}}]),
        1.0,
    ));
    let o = mech.outputs(0.0, &mech.initial_state());
    assert!((o.elements[0].load - 10.0).abs() < 1e-12);
    // ∫₁^1.1 100 (L − 1) dL = 0.5 J, relative to the first table point.
    assert!((o.elements[0].potential - 0.5).abs() < 1e-12);
    assert!((o.potential_energy - 0.5).abs() < 1e-12);
}

#[test]
fn a_motor_reaches_its_no_load_speed_from_its_stall_torque() {
    let (inertia, ts, w0) = (0.02, 4.0, 150.0);
    let tc = inertia * w0 / ts;
    let exact = |t: f64| w0 * (1.0 - (-t / tc).exp());
    let times: Vec<f64> = (1..=20).map(|i| i as f64 * 10.0 * tc / 20.0).collect();
    let t_end = 10.0 * tc;
    for motor in [
        json!({"type": "motor", "name": "mot", "rotor": "w", "stall_torque": ts,
               "no_load_speed": w0}),
        // The same line as a table (its end segments extended).
        json!({"type": "motor", "name": "mot", "rotor": "w",
               "torque_speed": {"points": [[0.0, ts], [0.5 * w0, 0.5 * ts], [w0, 0.0]],
                                "outside": "linear"}}),
    ] {
        let mech = build(&flywheel(inertia, json!([motor]), t_end));
        let y0 = mech.initial_state();
        let o = mech.outputs(0.0, &y0);
        assert_eq!(o.elements[0].load, ts, "the stall torque at rest");
        assert_eq!(o.elements[0].coordinate, 0.0);
        assert!((o.bodies[0].alpha - ts / inertia).abs() < 1e-12 * ts / inertia);
        let opts = SolverOptions {
            output: Output::Times(times.clone()),
            ..tight(Method::Rodas5p)
        };
        let sol = solve(&mech, (0.0, t_end), &y0, &opts).unwrap();
        for (i, &t) in sol.t.iter().enumerate() {
            let o = mech.outputs(t, sol.state(i));
            let w = o.bodies[0].omega;
            assert!(
                (w - exact(t)).abs() < 1e-7 * w0,
                "t = {t}: ω = {w}, closed form {}",
                exact(t)
            );
            assert!((o.elements[0].coordinate - w).abs() < 1e-15);
            assert!((o.elements[0].load - ts * (1.0 - w / w0)).abs() < 1e-9 * ts);
        }
        // After ten time constants: the no-load speed to e^{-10}.
        let w_end = mech.outputs(t_end, &sol.y_final).bodies[0].omega;
        assert!((w_end - w0).abs() < 5e-5 * w0);
    }
}

/// A block of mass m in a guide along x: it starts centred and moves across the guide at
/// `v` (the joint's initial offset rate).
fn block_in_guide(v: f64, normal: Value, friction: Value, gravity: f64) -> Value {
    json!({
        "bodies": [{"name": "block", "mass": 2.0, "inertia": 0.01,
                    "points": {"C": [0.0, 0.0]}}],
        "joints": [{"type": "prismatic_clearance", "name": "guide",
                    "guide": {"body": "ground", "at": [0.0, 0.0], "direction": [1.0, 0.0],
                              "width": 0.0202},
                    "block": {"body": "block", "point": "C", "length": 0.1, "width": 0.02},
                    "normal": normal, "friction": friction, "initial_offset_rate": v}],
        "gravity": [0.0, gravity],
        "t_end": 0.01
    })
}

#[test]
fn a_block_hitting_a_guide_face_is_the_one_dof_hertz_impact() {
    let (m, k, v) = (2.0, 1e9, 1.0);
    let c = 1e-4;
    let mech = build(&block_in_guide(
        v,
        json!({"law": "impact", "k": k, "c_max": 0.0, "d_max": 1e-5}),
        json!({"law": "none"}),
        0.0,
    ));
    // The initial relative velocity is exactly what the scene asks (no silent projection).
    let y0 = mech.initial_state();
    assert!(
        y0[3] == 0.0 && (y0[4] - v).abs() < 1e-15 && y0[5] == 0.0,
        "{y0:?}"
    );
    // The report says what the projection did: the block's guess ẏ = 0 became the joint's rate.
    let rep = mech.projection_report();
    assert_eq!(rep.changes.len(), 1, "{rep}");
    let ch = &rep.changes[0];
    assert_eq!(
        (ch.body.as_str(), ch.coordinate, ch.given),
        ("block", "vy", 0.0)
    );
    assert!((ch.assembled - v).abs() < 1e-15);
    assert!((rep.kinetic_energy_assembled - 0.5 * 2.0 * v * v).abs() < 1e-12);
    // Both upper corners touch at once: m δ̈ = −2 K δ^{3/2} after the flight c / v.
    let k2 = 2.0 * k;
    let d_max = (5.0 * m * v * v / (4.0 * k2)).powf(0.4);
    // t_c = 2 ∫₀^δmax dδ / √(v² − (4K₂/(5m)) δ^{5/2}) = (δ_max / v) · 2 ∫₀¹ dx/√(1 − x^{5/2}),
    // the integral by the substitution x = 1 − s² and Simpson's rule on 20000 panels.
    let integral = {
        let f = |s: f64| {
            let x: f64 = 1.0 - s * s;
            if s == 0.0 {
                // lim 2s/√(1 − (1 − s²)^{5/2}) = 2/√(5/2).
                2.0 / 2.5f64.sqrt()
            } else {
                2.0 * s / (1.0 - x.powf(2.5)).sqrt()
            }
        };
        let n = 20000;
        let h = 1.0 / n as f64;
        (0..=n)
            .map(|i| {
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                w * f(i as f64 * h)
            })
            .sum::<f64>()
            * h
            / 3.0
    };
    let t_contact = 2.0 * d_max / v * integral;
    let opts = SolverOptions {
        event_rtol: 1e-12,
        ..tight(Method::Dop853)
    };
    // Until before the block reaches the other face (at c/v + t_c + 2c/v).
    let t_end = 0.001;
    let sol = solve(&mech, (0.0, t_end), &y0, &opts).unwrap();
    let hits: Vec<&EventHit> = sol.events.iter().filter(|h| h.index < 2).collect();
    assert!(
        mech.event_name(0) == Some(("corner_contact", "guide")),
        "{:?}",
        mech.event_name(0)
    );
    // Corners 0 and 1 (the +w/2 side) go in and come out once each.
    assert_eq!(hits.len(), 4, "{:?}", sol.events);
    let t_in = c / v;
    for h in &hits {
        let expect = if h.rising { t_in } else { t_in + t_contact };
        assert!(
            (h.t - expect).abs() < 1e-6 * t_contact,
            "event at {} (rising {}), expected {expect}",
            h.t,
            h.rising
        );
    }
    // Peak penetration and force at mid-contact; the block leaves at −v (no damping).
    let tm = t_in + 0.5 * t_contact;
    let opts = SolverOptions {
        output: Output::Times(vec![tm]),
        ..opts
    };
    let sol2 = solve(&mech, (0.0, t_end), &y0, &opts).unwrap();
    let o = mech.outputs(tm, sol2.state(0));
    let p = &o.prismatic[0];
    assert!(
        (p.delta - d_max).abs() < 1e-6 * d_max,
        "δ = {}, δ_max = {d_max}",
        p.delta
    );
    let f_max = k2 * d_max.powf(1.5);
    assert!((p.contact_force - f_max).abs() < 1e-5 * f_max);
    assert!(p.tilt.abs() < 1e-12 && (p.offset - (c + d_max)).abs() < 1e-6 * d_max);
    let o_end = mech.outputs(sol.t_final, &sol.y_final);
    assert!((o_end.bodies[0].vy + v).abs() < 1e-6 * v);
}

/// The mechanism with an energy quadrature appended: E' = P_in − D (docs/model.md §10).
struct WithEnergy<'a>(&'a Mechanism);

impl OdeSystem for WithEnergy<'_> {
    fn dim(&self) -> usize {
        self.0.dim() + 1
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        let n = self.0.dim();
        self.0.rhs(t, &y[..n], &mut dy[..n]);
        let p = self.0.power(t, &y[..n]);
        dy[n] = p.input() - p.dissipated();
    }
    fn n_events(&self) -> usize {
        self.0.n_events()
    }
    fn event_spec(&self, i: usize) -> EventSpec {
        self.0.event_spec(i)
    }
    fn events(&self, t: f64, y: &[f64], g: &mut [f64]) {
        self.0.events(t, &y[..self.0.dim()], g)
    }
    fn on_event(&self, hit: &EventHit, y: &mut [f64]) -> EventAction {
        let n = self.0.dim();
        self.0.on_event(hit, &mut y[..n])
    }
}

#[test]
fn the_energy_balance_closes_with_every_new_element() {
    // A pendulum carrying a block in a guide would need a moving guide; instead a two-body
    // chain: a crank driven by a motor and a torque, a torsion spring-damper on it, a
    // spring-damper from its tip to a block in a guide on the ground, a time-tabulated force
    // and a coordinate-tabulated opposing load on the block, gravity, damped contact with
    // friction in the guide.
    let scene = json!({
        "bodies": [
            {"name": "crank", "mass": 1.0, "inertia": 0.01, "position": [0.05, 0.0],
             "points": {"O": [-0.05, 0.0], "A": [0.05, 0.0]}},
            {"name": "block", "mass": 2.0, "inertia": 0.002, "position": [0.3, 0.0],
             "points": {"C": [0.0, 0.0]}}
        ],
        "joints": [
            {"type": "revolute", "name": "pivot", "a": {"body": "crank", "point": "O"},
             "b": {"body": "ground", "at": [0.0, 0.0]}},
            {"type": "prismatic_clearance", "name": "guide",
             "guide": {"body": "ground", "at": [0.0, 0.0], "width": 0.0404},
             "block": {"body": "block", "point": "C", "length": 0.06, "width": 0.04},
             "normal": {"law": "impact", "k": 1e8, "c_max": 200.0, "d_max": 1e-5},
             "friction": {"law": "coulomb", "mu": 0.2, "v0": 1e-4, "v1": 2e-4},
             "initial_offset_rate": 0.3, "initial_tilt_rate": 2.0}
        ],
        "forces": [
            {"type": "motor", "name": "motor", "rotor": "crank", "stall_torque": 2.0,
             "no_load_rpm": 300.0},
            {"type": "torque", "name": "brake", "body": "crank", "value": -0.3},
            {"type": "rotational_spring_damper", "name": "torsion", "a": "crank",
             "stiffness": 0.5, "damping": 0.002},
            {"type": "spring_damper", "name": "link", "a": {"body": "crank", "point": "A"},
             "b": {"body": "block", "point": "C"}, "stiffness": 2000.0, "damping": 3.0,
             "free_length": 0.2},
            {"type": "force", "name": "push", "body": "block", "point": "C", "frame": "body",
             "direction": [1.0, 0.1],
             "table": {"input": {"of": "time"}, "points": [[0.0, 0.0], [0.1, 20.0], [0.2, -5.0]]}},
            {"type": "force", "name": "punch", "body": "block", "direction": [-1.0, 0.0],
             "acts": "opposing",
             "table": {"input": {"of": "joint", "joint": "guide"},
                       "points": [[0.31, 0.0], [0.32, 30.0], [0.33, 0.0]]}}
        ],
        "gravity": [0.0, -9.81],
        "t_end": 0.4
    });
    let mech = build(&scene);
    let sys = WithEnergy(&mech);
    let mut y0 = mech.initial_state();
    y0.push(0.0);
    let opts = SolverOptions {
        rtol: 1e-10,
        atol: Atol::Scalar(1e-12),
        ..SolverOptions::with_method(Method::Dop853)
    };
    let sol = solve(&sys, (0.0, 0.4), &y0, &opts).unwrap();
    let n = mech.dim();
    let (ya, yb) = (&y0[..n], &sol.y_final[..n]);
    let (o0, o1) = (mech.outputs(0.0, ya), mech.outputs(0.4, yb));
    let change =
        (o1.kinetic_energy + o1.potential_energy) - (o0.kinetic_energy + o0.potential_energy);
    let net_work = sol.y_final[n];
    // The scale: the energy that flowed (every power term's absolute integral, by the
    // trapezoidal rule on the steps).
    let mut flow = 0.0;
    let mut contact = false;
    for k in 1..sol.len() {
        let p = mech.power(sol.t[k], &sol.state(k)[..n]);
        let terms = [
            p.driver,
            p.load,
            p.motor,
            p.contact_damping,
            p.friction,
            p.film,
            p.damper,
        ];
        flow += terms.iter().map(|v| v.abs()).sum::<f64>() * (sol.t[k] - sol.t[k - 1]);
        contact |= mech.outputs(sol.t[k], &sol.state(k)[..n]).prismatic[0].contact_force > 0.0;
    }
    assert!(contact, "the block must hit the guide");
    let err = (net_work - change).abs();
    assert!(
        err <= 1e-6 * flow,
        "∫(P_in − D) = {net_work:.12e} J, Δ(T + V) = {change:.12e} J, energy that flowed {flow:.3e} J"
    );
}

#[test]
fn the_jacobian_of_the_elements_matches_differences_of_the_right_hand_side() {
    let scene = json!({
        "bodies": [{"name": "block", "mass": 2.0, "inertia": 0.002, "position": [0.3, 0.0],
                    "points": {"C": [0.0, 0.0]}}],
        "joints": [{"type": "prismatic_clearance", "name": "guide",
                    "guide": {"body": "ground", "at": [0.0, 0.0], "width": 0.0404},
                    "block": {"body": "block", "point": "C", "length": 0.06, "width": 0.04},
                    "normal": {"law": "impact", "k": 1e8, "c_max": 200.0, "d_max": 1e-5},
                    "friction": {"law": "coulomb", "mu": 0.2, "v0": 1e-4, "v1": 2e-4}}],
        "forces": [{"type": "spring_damper", "name": "s", "a": {"body": "ground", "at": [0.0, 0.1]},
                    "b": {"body": "block", "point": "C"}, "stiffness": 2000.0, "damping": 3.0,
                    "free_length": 0.2}],
        "t_end": 0.1
    });
    let mech = build(&scene);
    // In contact on one corner, sliding, turning.
    let y = vec![0.3, 0.0002, 0.01, 0.5, 0.1, 0.7];
    let o = mech.outputs(0.0, &y);
    assert!(o.prismatic[0].contact_force > 0.0);
    let n = 6;
    let mut jac = faer::Mat::<f64>::zeros(n, n);
    mech.jacobian(0.0, &y, jac.as_mut());
    let mut f0 = vec![0.0; n];
    mech.rhs(0.0, &y, &mut f0);
    for j in 0..n {
        let h = 1e-9;
        let col = central_difference(&mech, 0.0, &y, j, h);
        for (i, &d) in col.iter().enumerate() {
            let scale = d.abs().max(1.0) * 1e-4;
            assert!(
                (jac[(i, j)] - d).abs() <= scale,
                "∂f{i}/∂y{j}: {} vs {d}",
                jac[(i, j)]
            );
        }
    }
}

#[test]
fn every_new_error_names_its_path() {
    let spring = |extra: Value| {
        let mut s = json!({"type": "spring_damper", "name": "s",
                           "a": {"body": "ground", "at": [0.0, 0.0]},
                           "b": {"body": "m", "point": "C"}, "stiffness": 10.0});
        for (k, v) in extra.as_object().unwrap() {
            s[k] = v.clone();
        }
        slider(1.0, 0.5, json!([s]), 1.0)
    };
    let cases: Vec<(Value, &str, &str)> = vec![
        (
            spring(json!({"stiffness": -1.0})),
            "forces[0].stiffness",
            "stiffness must be >= 0",
        ),
        (
            spring(json!({"damping": -1.0})),
            "forces[0].damping",
            "damping must be >= 0",
        ),
        (
            spring(json!({"free_length": -1.0})),
            "forces[0].free_length",
            "free length must be >= 0",
        ),
        (
            spring(json!({"b": {"body": "ground", "at": [1.0, 0.0]}})),
            "forces[0].b.body",
            "two different bodies",
        ),
        (
            spring(json!({"curve": {"points": [[0.0, 1.0], [1.0, 2.0]]}})),
            "forces[0].curve",
            "not both",
        ),
        (
            spring(json!({"stiffness": null, "curve": {"points": [[0.0, 1.0]]}})),
            "forces[0].curve.points",
            "at least 2 points",
        ),
        (
            spring(json!({"stiffness": null, "curve": {"points": [[0.0, 1.0], [0.0, 2.0]]}})),
            "forces[0].curve.points[1][0]",
            "increase strictly",
        ),
        (
            spring(json!({"b": {"body": "m", "point": "Q"}})),
            "forces[0].b.point",
            "no point named 'Q'",
        ),
        (
            slider(1.0, 0.0, json!([{"type": "spring", "name": "x"}]), 1.0),
            "forces[0].type",
            "unknown force element type `spring`",
        ),
        (
            slider(
                1.0,
                0.0,
                json!([{"type": "torque", "name": "t", "body": "m"}]),
                1.0,
            ),
            "forces[0]",
            "value (a constant) or table",
        ),
        (
            slider(
                1.0,
                0.0,
                json!([{"type": "torque", "name": "t", "body": "m", "value": 1.0,
                                  "table": {"input": {"of": "time"}, "points": [[0, 0], [1, 1]]}}]),
                1.0,
            ),
            "forces[0].table",
            "not both",
        ),
        (
            slider(
                1.0,
                0.0,
                json!([{"type": "torque", "name": "t", "body": "ground", "value": 1.0}]),
                1.0,
            ),
            "forces[0].body",
            "not the ground",
        ),
        (
            slider(
                1.0,
                0.0,
                json!([{"type": "force", "name": "f", "body": "m", "direction": [0.0, 0.0], "value": 1.0}]),
                1.0,
            ),
            "forces[0].direction",
            "zero vector",
        ),
        (
            slider(
                1.0,
                0.0,
                json!([{"type": "force", "name": "f", "body": "m", "direction": [1.0, 0.0],
                                  "table": {"input": {"of": "speed"}, "points": [[0, 0], [1, 1]]}}]),
                1.0,
            ),
            "forces[0].table.input.of",
            "unknown table input `speed`",
        ),
        (
            slider(
                1.0,
                0.0,
                json!([{"type": "force", "name": "f", "body": "m", "direction": [1.0, 0.0],
                                  "table": {"input": {"of": "joint", "joint": "nope"}, "points": [[0, 0], [1, 1]]}}]),
                1.0,
            ),
            "forces[0].table.input.joint",
            "no joint named 'nope'",
        ),
        (
            slider(
                1.0,
                0.0,
                json!([{"type": "force", "name": "f", "body": "m", "direction": [1.0, 0.0],
                                  "table": {"input": {"of": "length", "element": "f"}, "points": [[0, 0], [1, 1]]}}]),
                1.0,
            ),
            "forces[0].table.input.element",
            "not a spring_damper",
        ),
        (
            slider(
                1.0,
                0.0,
                json!([{"type": "torque", "name": "t", "body": "m", "value": 1.0},
                                 {"type": "torque", "name": "t", "body": "m", "value": 2.0}]),
                1.0,
            ),
            "forces[1].name",
            "duplicate force element name 't'",
        ),
        (
            slider(
                1.0,
                0.0,
                json!([{"type": "motor", "name": "mot", "rotor": "m"}]),
                1.0,
            ),
            "forces[0]",
            "a motor needs",
        ),
        (
            slider(
                1.0,
                0.0,
                json!([{"type": "motor", "name": "mot", "rotor": "m", "stall_torque": 1.0}]),
                1.0,
            ),
            "forces[0].no_load_speed",
            "needs no_load_speed",
        ),
        (
            slider(
                1.0,
                0.0,
                json!([{"type": "motor", "name": "mot", "rotor": "m", "stall_torque": 1.0, "no_load_speed": 0.0}]),
                1.0,
            ),
            "forces[0].no_load_speed",
            "must not be 0",
        ),
        (
            slider(
                1.0,
                0.0,
                json!([{"type": "motor", "name": "mot", "rotor": "m", "stator": "m", "stall_torque": 1.0, "no_load_rpm": 10.0}]),
                1.0,
            ),
            "forces[0].stator",
            "must differ",
        ),
        (
            slider(
                1.0,
                0.0,
                json!([{"type": "rotational_spring_damper", "name": "r", "a": "m", "b": "x"}]),
                1.0,
            ),
            "forces[0].b",
            "no body named 'x'",
        ),
    ];
    for (scene, path, words) in cases {
        let e = error_of(&scene);
        let msg = e.to_string();
        assert!(
            msg.starts_with(&format!("{path}: ")),
            "expected {path}: … {words}, got {msg}"
        );
        assert!(msg.contains(words), "expected {path}: … {words}, got {msg}");
    }
    // The prismatic clearance joint.
    let block = |patch: Value| {
        let mut s = block_in_guide(
            0.0,
            json!({"law": "impact", "k": 1e9, "c_max": 0.0, "d_max": 1e-5}),
            json!({"law": "none"}),
            0.0,
        );
        for (k, v) in patch.as_object().unwrap() {
            let (outer, inner) = k
                .split_once('.')
                .map_or((k.as_str(), None), |(a, b)| (a, Some(b)));
            match inner {
                Some(i) => s["joints"][0][outer][i] = v.clone(),
                None => s["joints"][0][outer] = v.clone(),
            }
        }
        s
    };
    let cases: Vec<(Value, &str, &str)> = vec![
        (
            block(json!({"block.width": 0.03})),
            "joints[0].block.width",
            "must be smaller than the guide width",
        ),
        (
            block(json!({"guide.body": "block"})),
            "joints[0].guide.body",
            "must be the ground",
        ),
        (
            block(json!({"initial_offset": 0.001})),
            "joints[0].initial_offset",
            "allow_initial_penetration",
        ),
        (
            block(json!({"initial_tilt": 0.01})),
            "joints[0].initial_tilt",
            "allow_initial_penetration",
        ),
        (
            block(
                json!({"normal": {"law": "impact", "materials": {"bearing": {"youngs_modulus": 2e11, "poisson_ratio": 0.3}, "journal": {"youngs_modulus": 2e11, "poisson_ratio": 0.3}}, "c_max": 0.0, "d_max": 1e-5}}),
            ),
            "joints[0].normal.materials",
            "no radii",
        ),
        (
            block(json!({"block.point": "Z"})),
            "joints[0].block.point",
            "no point named 'Z'",
        ),
        (
            block(json!({"initial_offset": 0.02, "allow_initial_penetration": true})),
            "joints[0].initial_offset",
            "more than half its width",
        ),
    ];
    for (scene, path, words) in cases {
        let msg = error_of(&scene).to_string();
        assert!(
            msg.starts_with(&format!("{path}: ")) && msg.contains(words),
            "expected {path}: … {words}, got {msg}"
        );
    }
    // Initial rates that contradict the constraints, or each other.
    let mut s = flywheel(1.0, json!([]), 1.0);
    s["bodies"][0]["initial_velocity"] = json!({"vx": 1.0});
    let msg = error_of(&s).to_string();
    assert!(
        msg.starts_with("bodies[0].initial_velocity.vx: initial assembly did not converge"),
        "{msg}"
    );
    let mut s = flywheel(1.0, json!([]), 1.0);
    s["bodies"][0]["initial_velocity"] = json!({"omega": 1.0});
    s["joints"][0]["initial_rate"] = json!(2.0);
    let msg = error_of(&s).to_string();
    assert!(
        msg.contains("initial_rate") || msg.contains("initial_velocity.omega"),
        "{msg}"
    );
}

/// A uniform rod (m = 1.2 kg, l = 0.5 m) pinned at one end to the ground, no gravity.
fn pinned_rod(extra_body: Value, extra_pin: Value) -> Value {
    let mut s = json!({
        "bodies": [{"name": "rod", "mass": 1.2, "inertia": 1.2 * 0.25 / 12.0,
                    "position": [0.25, 0.0], "points": {"O": [-0.25, 0.0]}}],
        "joints": [{"type": "revolute", "name": "pin", "a": {"body": "rod", "point": "O"},
                    "b": {"body": "ground", "at": [0.0, 0.0]}}],
        "t_end": 1.0
    });
    for (k, v) in extra_body.as_object().unwrap() {
        s["bodies"][0][k] = v.clone();
    }
    for (k, v) in extra_pin.as_object().unwrap() {
        s["joints"][0][k] = v.clone();
    }
    s
}

#[test]
fn initial_velocities_are_projected_by_least_kinetic_energy_and_reported() {
    // Guessed ω = 2 rad/s with the centre of mass at rest: the projection of least kinetic
    // energy of the change, min m|v|² + I (ω − 2)² with v = ω l/2, gives ω = 2 I/(I + m l²/4).
    let (m, l): (f64, f64) = (1.2, 0.5);
    let i = m * l * l / 12.0;
    let mech = build(&pinned_rod(json!({"angular_velocity": 2.0}), json!({})));
    let y0 = mech.initial_state();
    let omega = 2.0 * i / (i + m * l * l / 4.0);
    assert!((omega - 0.5).abs() < 1e-15);
    assert!((y0[5] - omega).abs() < 1e-12, "ω = {}", y0[5]);
    assert!((y0[4] - omega * l / 2.0).abs() < 1e-12, "ẏ = {}", y0[4]);
    let rep = mech.projection_report();
    let changed: Vec<(&str, f64, f64)> = rep
        .changes
        .iter()
        .map(|c| (c.coordinate, c.given, c.assembled))
        .collect();
    assert_eq!(changed.len(), 2, "{rep}");
    assert_eq!((changed[0].0, changed[0].1), ("vy", 0.0));
    assert_eq!((changed[1].0, changed[1].1), ("omega", 2.0));
    assert!((rep.kinetic_energy_given - 0.5 * i * 4.0).abs() < 1e-15);
    assert!(rep.max_velocity_change > 1.4 && rep.max_position_change == 0.0);
    let text = rep.to_string();
    assert!(
        text.contains("rod.omega: 2.000000000e0 → 5.000000000e-1"),
        "{text}"
    );
    // Stated exactly, by the body or by the pin, it is kept.
    for mech in [
        build(&pinned_rod(
            json!({"initial_velocity": {"omega": 2.0}}),
            json!({}),
        )),
        build(&pinned_rod(json!({}), json!({"initial_rate": 2.0}))),
    ] {
        let y0 = mech.initial_state();
        assert!(
            (y0[5] - 2.0).abs() < 1e-12 && (y0[4] - 0.5).abs() < 1e-12,
            "{y0:?}"
        );
    }
    // A slider's initial_rate along its line.
    let s = slider(2.0, 0.1, json!([]), 1.0);
    let mut s2 = s.clone();
    s2["joints"][0]["initial_rate"] = json!(-0.75);
    let y0 = build(&s2).initial_state();
    assert_eq!(&y0[3..6], &[-0.75, 0.0, 0.0]);
    // A clearance joint's relative velocity: a journal leaving its bearing's centre at 1 m/s.
    let mut v = build_value_clearance();
    v["joints"][0]["initial_eccentricity_rate"] = json!([0.0, -1.0]);
    let mech = build(&v);
    let o = mech.outputs(0.0, &mech.initial_state());
    assert!((o.bodies[0].vy + 1.0).abs() < 1e-12, "{:?}", o.bodies[0]);
}

/// A disk in a ground bearing (revolute clearance joint), no gravity.
fn build_value_clearance() -> Value {
    json!({
        "bodies": [{"name": "disk", "mass": 3.0, "inertia": 0.02, "points": {"c": [0.0, 0.0]}}],
        "joints": [{"type": "clearance", "name": "j",
                    "bearing": {"body": "ground", "at": [0.0, 0.0], "radius": 0.010},
                    "journal": {"body": "disk", "point": "c", "radius": 0.009},
                    "normal": {"law": "impact", "k": 1e9, "c_max": 100.0, "d_max": 1e-5}}],
        "t_end": 1.0
    })
}

#[test]
fn scenes_with_repeated_keys_or_a_journal_outside_its_clearance_are_rejected() {
    // A repeated key, nested: its path.
    let text = r#"{"bodies": [{"name": "a", "mass": 1, "inertia": 1, "points": {"P": [0, 0], "P": [1, 0]}}], "t_end": 1}"#;
    let e = Scene::from_json_str(text).unwrap_err().to_string();
    assert!(
        e.starts_with("bodies[0].points.P: duplicate key `P`"),
        "{e}"
    );
    let text = r#"{"bodies": [{"name": "a", "mass": 1, "inertia": 1}], "t_end": 1, "t_end": 2}"#;
    let e = Scene::from_json_str(text).unwrap_err().to_string();
    assert!(e.starts_with("t_end: duplicate key `t_end`"), "{e}");
    // An eccentricity beyond the clearance: an error at the field, unless stated; and never
    // beyond the journal radius (5 m in a 1 mm clearance used to hang the integrator).
    for (e0, allow, ok) in [
        (0.0011, false, false),
        (0.0011, true, true),
        (0.001, false, true),
        (5.0, false, false),
        (5.0, true, false),
    ] {
        let mut v = build_value_clearance();
        v["joints"][0]["initial_eccentricity"] = json!([e0, 0.0]);
        v["joints"][0]["allow_initial_penetration"] = json!(allow);
        let r = Scene::from_json_str(&v.to_string());
        assert_eq!(r.is_ok(), ok, "e0 = {e0}, allow = {allow}: {r:?}");
        if let Err(e) = r {
            let msg = e.to_string();
            assert!(
                msg.starts_with("joints[0].initial_eccentricity: |e| = "),
                "{msg}"
            );
            let why = if allow {
                "beyond the journal radius"
            } else {
                "allow_initial_penetration"
            };
            assert!(msg.contains(why), "{msg}");
        }
    }
}

/// A free body (no joint) of mass m carrying a linear bushing from its centre of mass to the
/// ground origin, and any other force elements.
fn on_a_bushing(m: f64, k: f64, c: f64, pos: [f64; 2], vel: [f64; 2], t_end: f64) -> Value {
    json!({
        "bodies": [{"name": "m", "mass": m, "inertia": 0.3, "position": pos, "velocity": vel,
                    "points": {"C": [0.0, 0.0]}}],
        "forces": [{"type": "linear_bushing", "name": "bush",
                    "a": {"body": "m", "point": "C"}, "b": {"body": "ground", "at": [0.0, 0.0]},
                    "stiffness": k, "damping": c}],
        "t_end": t_end
    })
}

#[test]
fn a_mass_on_a_linear_bushing_orbits_with_period_two_pi_root_m_over_k() {
    // m r̈ = −k r: x = x₀ cos ω t, y = (v₀/ω) sin ω t, ω = √(k/m), period T = 2π √(m/k).
    let (m, k, x0, v0): (f64, f64, f64, f64) = (2.0, 800.0, 0.01, 0.3);
    let w = (k / m).sqrt();
    let period = 2.0 * std::f64::consts::PI * (m / k).sqrt();
    let mech = build(&on_a_bushing(m, k, 0.0, [x0, 0.0], [0.0, v0], period));
    let times: Vec<f64> = (1..=8).map(|i| i as f64 * period / 8.0).collect();
    for method in [Method::Dop853, Method::Rodas5p] {
        let opts = SolverOptions {
            output: Output::Times(times.clone()),
            ..tight(method)
        };
        let sol = solve(&mech, (0.0, period), &mech.initial_state(), &opts).unwrap();
        for (i, &t) in sol.t.iter().enumerate() {
            let o = mech.outputs(t, sol.state(i));
            let (x, y) = (o.bodies[0].x, o.bodies[0].y);
            assert!(
                (x - x0 * (w * t).cos()).abs() < 1e-8 * x0,
                "{method:?} t = {t}: x = {x}"
            );
            assert!(
                (y - v0 / w * (w * t).sin()).abs() < 1e-8 * v0 / w,
                "{method:?} t = {t}: y = {y}"
            );
            // Its columns: |F| = k |d|, the stretch |d|; its potential ½ k |d|².
            let (e, r) = (&o.elements[0], x.hypot(y));
            assert!((e.coordinate - r).abs() < 1e-15 && (e.load - k * r).abs() < 1e-9 * k * r);
            assert!((e.potential - 0.5 * k * r * r).abs() < 1e-12 * k * r * r);
        }
        // After one period it is back where it started.
        let end = mech.outputs(period, &sol.y_final).bodies[0];
        assert!((end.x - x0).abs() < 1e-8 * x0 && end.y.abs() < 1e-8 * v0 / w);
    }
}

#[test]
fn a_damped_bushing_decays_at_rate_c_over_2m() {
    // m ẍ + c ẋ + k x = 0 from (x₀, 0): x = x₀ e^{−σ t}(cos ω_d t + σ/ω_d sin ω_d t),
    // σ = c/(2m) the decay rate, ω_d = √(k/m − σ²).
    let (m, k, c, x0): (f64, f64, f64, f64) = (2.0, 800.0, 8.0, 0.01);
    let sigma = c / (2.0 * m);
    let wd = (k / m - sigma * sigma).sqrt();
    let exact = |t: f64| x0 * (-sigma * t).exp() * ((wd * t).cos() + sigma / wd * (wd * t).sin());
    let mech = build(&on_a_bushing(m, k, c, [x0, 0.0], [0.0, 0.0], 1.0));
    let times: Vec<f64> = (1..=20).map(|i| i as f64 * 0.05).collect();
    let opts = SolverOptions {
        output: Output::Times(times),
        ..tight(Method::Rodas5p)
    };
    let sol = solve(&mech, (0.0, 1.0), &mech.initial_state(), &opts).unwrap();
    for (i, &t) in sol.t.iter().enumerate() {
        let o = mech.outputs(t, sol.state(i));
        let x = o.bodies[0].x;
        assert!(
            (x - exact(t)).abs() < 1e-8 * x0,
            "t = {t}: x = {x}, {}",
            exact(t)
        );
        // Its damper dissipates c ẋ².
        let p = mech.power(t, sol.state(i));
        let v = o.bodies[0].vx;
        assert!((p.damper - c * v * v).abs() <= 1e-12 * c * v * v + 1e-300);
        assert_eq!(p.input(), 0.0);
    }
}

/// Two free bodies joined by a bushing between off-centre points, the first also held by a
/// bushing to the ground, under gravity: the bushings turn the bodies too.
/// Column j of ∂f/∂y by central differences of the right-hand side with step h.
fn central_difference(mech: &Mechanism, t: f64, y: &[f64], j: usize, h: f64) -> Vec<f64> {
    let n = y.len();
    let (mut yp, mut ym) = (y.to_vec(), y.to_vec());
    yp[j] += h;
    ym[j] -= h;
    let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
    mech.rhs(t, &yp, &mut fp);
    mech.rhs(t, &ym, &mut fm);
    fp.iter()
        .zip(&fm)
        .map(|(p, m)| (p - m) / (2.0 * h))
        .collect()
}

fn two_bushings(c: f64) -> Value {
    json!({
        "bodies": [
            {"name": "p", "mass": 1.5, "inertia": 0.02, "position": [0.0, -0.1], "angle": 0.3,
             "velocity": [0.4, 0.0], "angular_velocity": 2.0,
             "points": {"A": [0.05, 0.02], "B": [-0.04, 0.03]}},
            {"name": "q", "mass": 0.7, "inertia": 0.004, "position": [0.1, -0.25],
             "angular_velocity": -1.0, "points": {"C": [0.02, -0.01]}}
        ],
        "forces": [
            {"type": "linear_bushing", "name": "hang", "a": {"body": "p", "point": "A"},
             "b": {"body": "ground", "at": [0.0, 0.0]}, "stiffness": 3000.0, "damping": c},
            {"type": "linear_bushing", "name": "link", "a": {"body": "p", "point": "B"},
             "b": {"body": "q", "point": "C"}, "stiffness": 1500.0, "damping": 0.5 * c}
        ],
        "gravity": [0.0, -9.81],
        "t_end": 0.5
    })
}

#[test]
fn the_energy_balance_of_damped_bushings_closes() {
    // T + V (gravity and ½ k |d|² of each bushing) + ∫ c |ḋ|² dt stays constant.
    let mech = build(&two_bushings(2.0));
    let sys = WithEnergy(&mech);
    let mut y0 = mech.initial_state();
    y0.push(0.0);
    let opts = SolverOptions {
        rtol: 1e-11,
        atol: Atol::Scalar(1e-13),
        ..SolverOptions::with_method(Method::Dop853)
    };
    let sol = solve(&sys, (0.0, 0.5), &y0, &opts).unwrap();
    let n = mech.dim();
    let (o0, o1) = (
        mech.outputs(0.0, &y0[..n]),
        mech.outputs(0.5, &sol.y_final[..n]),
    );
    let change =
        (o1.kinetic_energy + o1.potential_energy) - (o0.kinetic_energy + o0.potential_energy);
    let dissipated = -sol.y_final[n];
    assert!(
        dissipated > 1e-3,
        "the dampers must dissipate: {dissipated}"
    );
    let scale = o0.kinetic_energy + dissipated;
    assert!(
        (change + dissipated).abs() < 1e-9 * scale,
        "Δ(T + V) = {change:e} J, dissipated {dissipated:e} J"
    );
}

#[test]
fn the_bushings_closed_form_jacobian_matches_differences_of_the_right_hand_side() {
    let mech = build(&two_bushings(2.0));
    let y = {
        let mut y = mech.initial_state();
        for (i, v) in y.iter_mut().enumerate() {
            *v += 1e-2 * ((i as f64) * 1.3).sin();
        }
        y
    };
    let n = mech.dim();
    let mut jac = faer::Mat::<f64>::zeros(n, n);
    mech.jacobian(0.1, &y, jac.as_mut());
    for j in 0..n {
        // Every entry is linear in y_j but for sin and cos of the angles: central differences
        // err by h² ‖∂³f‖ ≈ 1e-12 relative.
        let h = 1e-6;
        let col = central_difference(&mech, 0.1, &y, j, h);
        for (i, &d) in col.iter().enumerate() {
            assert!(
                (jac[(i, j)] - d).abs() <= 1e-6 * d.abs().max(1.0),
                "∂f{i}/∂y{j}: closed form {:e}, differences {d:e}",
                jac[(i, j)]
            );
        }
    }
}

/// Two turning bodies on spring-dampers (one to the ground, one between body points), with a
/// constant torque: the elements whose Jacobians are closed forms (docs/model.md §10.1).
fn two_springs() -> Value {
    json!({
        "bodies": [
            {"name": "p", "mass": 1.5, "inertia": 0.02, "position": [0.0, -0.1], "angle": 0.3,
             "velocity": [0.4, -0.2], "angular_velocity": 2.0,
             "points": {"A": [0.05, 0.02], "B": [-0.04, 0.03]}},
            {"name": "q", "mass": 0.7, "inertia": 0.004, "position": [0.1, -0.25], "angle": -0.7,
             "velocity": [-0.3, 0.5], "angular_velocity": -1.0, "points": {"C": [0.02, -0.01]}}
        ],
        "forces": [
            {"type": "spring_damper", "name": "hang", "a": {"body": "ground", "at": [0.01, 0.02]},
             "b": {"body": "p", "point": "A"}, "stiffness": 3000.0, "damping": 4.0,
             "free_length": 0.05},
            {"type": "spring_damper", "name": "link", "a": {"body": "p", "point": "B"},
             "b": {"body": "q", "point": "C"}, "stiffness": 1500.0, "damping": 2.5,
             "free_length": 0.2},
            {"type": "torque", "name": "drive", "body": "q", "value": 0.3}
        ],
        "gravity": [0.0, -9.81],
        "t_end": 0.5
    })
}

#[test]
fn the_spring_dampers_closed_form_jacobian_matches_differences_of_the_right_hand_side() {
    let mech = build(&two_springs());
    let y = {
        let mut y = mech.initial_state();
        for (i, v) in y.iter_mut().enumerate() {
            *v += 1e-2 * ((i as f64) * 1.3).sin();
        }
        y
    };
    let n = mech.dim();
    let mut jac = faer::Mat::<f64>::zeros(n, n);
    mech.jacobian(0.1, &y, jac.as_mut());
    let mut nonzero = 0;
    for j in 0..n {
        // f is smooth in y (lengths ≥ 0.05 m): central differences err by h² ‖∂³f‖ (about
        // 1e-8 relative at h = 1e-6 over lengths of 0.05 m) and by rounding ε |f| / h ≈ 1e-7.
        let h = 1e-6;
        let col = central_difference(&mech, 0.1, &y, j, h);
        for (i, &d) in col.iter().enumerate() {
            nonzero += usize::from(i >= n / 2 && d.abs() > 1e-3);
            assert!(
                (jac[(i, j)] - d).abs() <= 1e-6 * d.abs().max(1.0),
                "∂f{i}/∂y{j}: closed form {:e}, differences {d:e}",
                jac[(i, j)]
            );
        }
    }
    // The springs couple every coordinate of both bodies (36 entries of ∂q̈/∂q) and the
    // dampers their rates: most of the 72 lower entries are not zero.
    assert!(nonzero >= 60, "{nonzero} nonzero entries");
}

#[test]
fn a_bad_bushing_names_its_path() {
    let bushing = |extra: Value| {
        let mut v = on_a_bushing(1.0, 10.0, 0.0, [0.1, 0.0], [0.0, 0.0], 1.0);
        for (k, x) in extra.as_object().unwrap() {
            v["forces"][0][k] = x.clone();
        }
        v
    };
    for (extra, path, words) in [
        (
            json!({"stiffness": -1.0}),
            "forces[0].stiffness",
            "stiffness must be >= 0",
        ),
        (
            json!({"damping": -2.0}),
            "forces[0].damping",
            "damping must be >= 0",
        ),
        (
            json!({"a": {"body": "ground", "at": [1.0, 0.0]}}),
            "forces[0].b.body",
            "a bushing needs two different bodies (or a body and the ground), both are 'ground'",
        ),
        (
            json!({"a": {"body": "m", "point": "Z"}}),
            "forces[0].a.point",
            "no point named 'Z'",
        ),
        (
            json!({"stiffness": null}),
            "forces[0].stiffness",
            "invalid type: null, expected f64",
        ),
    ] {
        let msg = error_of(&bushing(extra)).to_string();
        assert!(
            msg.starts_with(&format!("{path}: ")) && msg.contains(words),
            "expected {path}: … {words}, got {msg}"
        );
    }
}
