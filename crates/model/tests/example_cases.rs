//! The example scenes of cases/examples and the press with a punching load and a motor
//! (cases/press/punch_motor_150rpm_c0.1.json): each builds, runs and keeps its energy balance.
//!
//! ```text
//! ∫(P_driver + P_load + P_motor) − ∫(D_contact + D_friction + D_film + D_damper) = Δ(T + V)
//! (docs/model.md §10, up to the integration error and the Baumgarte work)
//! ```

use lash_model::{Mechanism, Scene};
use lash_solver::{
    solve, Atol, EventAction, EventHit, EventSpec, Method, OdeSystem, Solution, SolverOptions,
};

fn case(path: &str) -> Scene {
    Scene::from_path(format!("{}/../../cases/{path}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// The mechanism with its net power integrated as one more state.
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

/// Runs with the energy quadrature; returns the solution and |∫(P_in − D) − Δ(T + V)| over the
/// energy that flowed (Σ ∫|P| by the trapezoidal rule on the steps).
fn run_with_energy(m: &Mechanism, opts: &SolverOptions) -> (Solution, f64) {
    let n = m.dim();
    let mut y0 = m.initial_state();
    y0.push(0.0);
    let sol = solve(&WithEnergy(m), (m.t_start(), m.t_end()), &y0, opts).unwrap();
    let e = |t: f64, y: &[f64]| {
        let o = m.outputs(t, &y[..n]);
        o.kinetic_energy + o.potential_energy
    };
    let change = e(sol.t_final, &sol.y_final) - e(m.t_start(), &y0);
    let mut flow = 0.0;
    for k in 1..sol.len() {
        let p = m.power(sol.t[k], &sol.state(k)[..n]);
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
    }
    let err = (sol.y_final[n] - change).abs() / flow;
    (sol, err)
}

#[test]
fn the_readme_scene_is_the_pendulum_example_and_loses_energy_only_to_contact() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md")).unwrap();
    let start = readme
        .find("A two-link pendulum whose elbow has a dry clearance")
        .unwrap();
    let block = &readme[start..];
    let a = block.find("```json").unwrap() + "```json".len();
    let b = a + block[a..].find("```").unwrap();
    let from_readme = Scene::from_json_str(&block[a..b]).unwrap();
    let mut file = case("examples/pendulum.json");
    assert!(!file.description.is_empty());
    file.description.clear();
    assert_eq!(
        file, from_readme,
        "cases/examples/pendulum.json is the README's scene"
    );

    let m = Mechanism::from_scene(&case("examples/pendulum.json")).unwrap();
    let opts = SolverOptions {
        rtol: 1e-9,
        atol: Atol::Scalar(1e-11),
        ..SolverOptions::with_method(Method::Dop853)
    };
    let (sol, err) = run_with_energy(&m, &opts);
    assert!(
        err < 1e-6,
        "energy balance error {err:.2e} of the energy that flowed"
    );
    let n = m.dim();
    let dissipated = -sol.y_final[n];
    assert!(
        dissipated > 0.0,
        "the elbow's damping and friction dissipate"
    );
    assert!(sol
        .events
        .iter()
        .any(|h| h.rising && m.event_name(h.index) == Some(("contact", "elbow"))));
}

#[test]
fn the_four_bar_with_a_clearance_joint_balances_driver_work_and_dissipation() {
    let m = Mechanism::from_scene(&case("examples/fourbar_clearance.json")).unwrap();
    assert_eq!(m.prescribed_bodies(), vec!["crank"]);
    let opts = SolverOptions {
        rtol: 1e-9,
        atol: Atol::Scalar(1e-11),
        ..SolverOptions::with_method(Method::Dop853)
    };
    let (sol, err) = run_with_energy(&m, &opts);
    assert!(
        err < 1e-6,
        "energy balance error {err:.2e} of the energy that flowed"
    );
    let n = m.dim();
    let o = m.outputs(sol.t_final, &sol.y_final[..n]);
    assert!(o.constraint_violation < 1e-8, "{}", o.constraint_violation);
    assert!(
        sol.events.iter().any(|h| h.rising),
        "the joint must make contact"
    );
}

#[test]
fn the_press_with_a_punch_and_a_motor_slows_under_the_load() {
    let scene = case("press/punch_motor_150rpm_c0.1.json");
    let m = Mechanism::from_scene(&scene).unwrap();
    // The crank is integrated (no driver): its inertia counts.
    assert!(m.prescribed_bodies().is_empty());
    let y0 = m.initial_state();
    let o0 = m.outputs(0.0, &y0);
    let w150 = 150.0 * std::f64::consts::PI / 30.0;
    assert!(
        (o0.bodies[0].omega - w150).abs() < 1e-12,
        "the crank starts at 150 rpm"
    );
    let opts = SolverOptions {
        rtol: 1e-7,
        atol: Atol::Scalar(1e-10),
        ..SolverOptions::with_method(Method::Dop853)
    };
    let (sol, err) = run_with_energy(&m, &opts);
    assert!(
        err < 1e-4,
        "energy balance error {err:.2e} of the energy that flowed"
    );
    let n = m.dim();
    let names = m.element_names();
    let (motor, punch) = (
        names.iter().position(|s| *s == "motor").unwrap(),
        names.iter().position(|s| *s == "punch").unwrap(),
    );
    // Along the run: the motor follows its line, the punch resists the forward stroke only,
    // and its work (the trapezoidal rule on the steps) is the area of its table on each of the
    // two forward strokes: 60 kN × (0.5 + 5 + 0.5) mm = 360 J.
    let (ts, w0) = (3000.0, 155.0 * std::f64::consts::PI / 30.0);
    let mut work = 0.0;
    let mut prev: Option<(f64, f64)> = None;
    for k in 0..sol.len() {
        let o = m.outputs(sol.t[k], &sol.state(k)[..n]);
        let (mo, pu) = (&o.elements[motor], &o.elements[punch]);
        assert!((mo.load - ts * (1.0 - mo.coordinate / w0)).abs() < 1e-9 * ts);
        assert!(
            pu.load == 0.0 || o.bodies[2].vx > 0.0,
            "the punch resists the forward stroke"
        );
        let p = pu.power;
        if let Some((t0, p0)) = prev {
            work -= 0.5 * (p + p0) * (sol.t[k] - t0);
        }
        prev = Some((sol.t[k], p));
    }
    assert!(
        (work - 720.0).abs() < 0.01 * 720.0,
        "work of the punch {work} J, table area 720 J"
    );
    // The same press without the punch turns further in the same time.
    let mut free = scene.clone();
    free.forces.retain(|f| f.name() != "punch");
    let mf = Mechanism::from_scene(&free).unwrap();
    let (solf, errf) = run_with_energy(&mf, &opts);
    assert!(errf < 1e-4);
    let turned =
        |m: &Mechanism, s: &Solution| m.outputs(s.t_final, &s.y_final[..n]).bodies[0].theta;
    let (a, af) = (turned(&m, &sol), turned(&mf, &solf));
    let range = |m: &Mechanism, s: &Solution| {
        (0..s.len()).fold(
            (f64::INFINITY, f64::NEG_INFINITY, 0.0f64),
            |(lo, hi, f), k| {
                let o = m.outputs(s.t[k], &s.state(k)[..n]);
                let w = o.bodies[0].omega * 30.0 / std::f64::consts::PI;
                (lo.min(w), hi.max(w), f.max(o.clearance[0].contact_force))
            },
        )
    };
    eprintln!(
        "crank after 0.8 s: {a:.4} rad with the punch (rpm, rpm, N: {:?}), {af:.4} rad without \
         ({:?}); punch work {work:.1} J",
        range(&m, &sol),
        range(&mf, &solf)
    );
    assert!(a < af, "the punched crank turns less: {a} vs {af} rad");
}
