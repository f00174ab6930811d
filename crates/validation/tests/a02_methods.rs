//! IFToMM A02, the N-four-bar (cases/iftomm/a02_n1.json, a02_n2.json), through the path of
//! `lash run` with every adaptive method at the case's defaults (rtol 1e-8, atol following it,
//! the scene's formulation: the augmented Lagrangian): the run ends without error and keeps
//! its branch through the horizontal (singular) positions (issue 26's target).
//!
//! ```text
//! span 3 s: the cranks pass the horizontal at t = 0.71 s and again about 1.3 s later
//! branch: every crank i keeps crank 0's angle (the parallelogram); the anti-parallelogram
//!         puts them π apart, so |θ_i − θ_0| < 1e-4 rad at every row tells them apart
//! B0 = (cos θ, sin θ) against the one-degree-of-freedom reference (lash_model::iftomm):
//!         within 1e-3 m, the benchmark's own "high precision" bar (a branch switch is ~1 m)
//! ```

use lash_model::iftomm::n_four_bar;
use lash_solver::Method;
use lash_validation::{Case, RunOptions, SolverChoice};

/// Largest |a − b| wrapped to [0, π].
fn angle_err(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    d.min(std::f64::consts::TAU - d)
}

fn a02_keeps_its_branch(method: Method) {
    let t_end = 3.0;
    for n in [1usize, 2] {
        let path = format!(
            "{}/../../cases/iftomm/a02_n{n}.json",
            env!("CARGO_MANIFEST_DIR")
        );
        let o = RunOptions {
            case: path.clone(),
            solver: SolverChoice {
                method: Some(method),
                ..Default::default()
            },
            t_end: Some(t_end),
            ..Default::default()
        };
        let case = Case::load(&path, None).unwrap();
        let r = lash_validation::run_in_memory(case, &o)
            .unwrap_or_else(|e| panic!("{method} N = {n}: {e}"));
        let col = |name: &str| {
            r.trajectory
                .column(name)
                .unwrap_or_else(|| panic!("no column {name}"))
                .to_vec()
        };
        let t = col("t");
        assert!((t[t.len() - 1] - t_end).abs() < 1e-12, "{method} N = {n}");
        let th0 = col("crank0.theta");
        for i in 1..=n {
            let thi = col(&format!("crank{i}.theta"));
            let worst = th0
                .iter()
                .zip(&thi)
                .map(|(a, b)| angle_err(*a, *b))
                .fold(0.0, f64::max);
            assert!(
                worst < 1e-4,
                "{method} N = {n}: crank {i} off by {worst:e} rad"
            );
        }
        // B0, the tip of crank 0 (its centre ± half its 1 m length along θ).
        let (x0, y0) = (col("crank0.x"), col("crank0.y"));
        let reference = n_four_bar(n, t_end).1.solve(&t);
        let err = (0..t.len())
            .map(|k| {
                let (bx, by) = (x0[k] + 0.5 * th0[k].cos(), y0[k] + 0.5 * th0[k].sin());
                let th = reference[k][0];
                (bx - th.cos()).abs().max((by - th.sin()).abs())
            })
            .fold(0.0, f64::max);
        assert!(err < 1e-3, "{method} N = {n}: B0 off by {err:e} m");
    }
}

macro_rules! per_method {
    ($($name:ident: $method:expr,)*) => {$(
        #[test]
        fn $name() {
            a02_keeps_its_branch($method);
        }
    )*};
}

per_method! {
    a02_with_bs32: Method::Bs32,
    a02_with_dopri54: Method::Dopri54,
    a02_with_tsit54: Method::Tsit54,
    a02_with_dop853: Method::Dop853,
    a02_with_bdf: Method::Bdf,
    a02_with_trbdf2: Method::Trbdf2,
    a02_with_esdirk34: Method::Esdirk34,
    a02_with_rodas5p: Method::Rodas5p,
}
