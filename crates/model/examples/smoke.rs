use lash_model::*;
use lash_solver::*;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let stem = &args[1];
    let h: f64 = args[2].parse().unwrap();
    let cat = lash_model::cases::press_catalogue();
    let mut scene = cat.iter().find(|c| &c.0 == stem).unwrap().1.clone();
    if let Some(model) = std::env::var("FILM").ok() {
        for j in scene.joints.iter_mut() {
            if let lash_model::scene::JointSpec::Clearance(c) = j {
                if let Some(f) = c.film.as_mut() { f.model = serde_json::from_str(&format!("\"{model}\"")).unwrap(); }
            }
        }
    }
    let scene = &scene;
    let m = Mechanism::from_scene(scene).unwrap();
    let y0 = m.initial_state();
    println!("y0 {:?}", y0);
    println!("int {:?} pres {:?} t_end {}", m.integrated_bodies(), m.prescribed_bodies(), m.t_end());
    let o = m.outputs(0.0, &y0);
    println!("{:?}", o);
    let ideal = m.ideal_slider_crank();
    println!("{:?}", ideal);
    let opts = SolverOptions { method: Method::Rk4, step: Some(h), events: args.get(3).is_some(), output: Output::Times({let t0: f64 = std::env::var("T0").map(|v| v.parse().unwrap()).unwrap_or(0.0); let t1: f64 = std::env::var("T1").map(|v| v.parse().unwrap()).unwrap_or(m.t_end()); (0..=80).map(|i| t0 + i as f64 * (t1-t0)/80.0).collect()}), ..Default::default() };
    let t = std::time::Instant::now();
    let sol = solve(&m, (0.0, std::env::var("T1").map(|v| v.parse().unwrap()).unwrap_or(m.t_end())), &y0, &opts);
    let el = t.elapsed().as_secs_f64();
    match sol {
        Ok(sol) => {
            println!("time {el} s, rhs {}, per rhs {} ns, events {}", sol.stats.rhs_evals, el*1e9/sol.stats.rhs_evals as f64, sol.events.len());
            for k in 0..sol.len() {
                let o = m.outputs(sol.t[k], sol.state(k));
                let c = o.clearance.first();
                println!("t {:.4} Om {:.1} x {:.6} a {:.4} ideal_a {:.4} eps {:.3} FN {:.1} film {:.1} phi {:.2e} tau {:?} E {:.6}", sol.t[k], {let st = sol.state(k); st[8]}, o.slider_x.unwrap(), o.slider_a.unwrap(), ideal.map(|i| i.a(sol.t[k])).unwrap_or(0.0), c.map(|c| c.eps).unwrap_or(0.0), c.map(|c| c.contact_force).unwrap_or(0.0), c.map(|c| c.film_force).unwrap_or(0.0), o.constraint_violation, o.driver_torques, o.kinetic_energy + o.potential_energy);
            }
        }
        Err(e) => println!("failed after {el}: {e}"),
    }
}
