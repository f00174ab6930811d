//! A system without state (n = 0: a mechanism whose every body is prescribed) integrates to
//! its end with every method, diffsol's included (issue 23's fuzzing pass: BDF panicked in
//! diffsol's LU on the empty matrix, exit 1).

use lash_solver::{solve, Atol, Method, OdeSystem, SolverOptions};

struct Empty;

impl OdeSystem for Empty {
    fn dim(&self) -> usize {
        0
    }
    fn rhs(&self, _t: f64, _y: &[f64], _dy: &mut [f64]) {}
}

#[test]
fn an_empty_system_reaches_its_end_with_every_method() {
    for method in [
        Method::Rk4,
        Method::Dopri54,
        Method::Rodas5p,
        Method::Bdf,
        Method::Trbdf2,
        Method::Esdirk34,
    ] {
        let opts = SolverOptions {
            method,
            rtol: 1e-8,
            atol: Atol::Scalar(1e-10),
            step: method.is_fixed_step().then_some(0.1),
            ..Default::default()
        };
        let sol =
            solve(&Empty, (0.0, 1.0), &[], &opts).unwrap_or_else(|e| panic!("{method:?}: {e}"));
        assert_eq!(sol.t_final, 1.0, "{method:?}");
        assert!(sol.y_final.is_empty());
    }
}
