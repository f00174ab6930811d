//! diffsol's sparse path (lash_solver::linear_algebra) on systems with a known answer: a
//! diagonal linear system y_i' = −k_i y_i (exact solution e^{−k_i t}) of 1 000 unknowns, whose
//! pattern is the diagonal (one colour: each Jacobian costs 2 RHS evaluations), and a
//! right-hand side that is NaN off its initial state, which must end in a typed error, not a
//! panic (the NaN Jacobian reaches faer's sparse LU; diffsol's own sparse LU
//! panics whenever a factorisation fails, lash_solver's returns the failure).
use lash_solver::{
    Atol, LinearAlgebra, Method, OdeSystem, Output, Problem, SolveError, SolverOptions,
};

struct Diagonal(Vec<f64>);

impl OdeSystem for Diagonal {
    fn dim(&self) -> usize {
        self.0.len()
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        for ((d, k), y) in dy.iter_mut().zip(&self.0).zip(y) {
            *d = -k * y;
        }
    }
    fn jacobian_sparsity(&self) -> Option<Vec<Vec<usize>>> {
        Some((0..self.0.len()).map(|j| vec![j]).collect())
    }
}

fn opts(method: Method, la: LinearAlgebra) -> SolverOptions {
    let mut o = SolverOptions::with_method(method);
    o.rtol = 1e-8;
    o.atol = Atol::Scalar(1e-10);
    o.output = Output::Final;
    o.linear_algebra = la;
    o
}

/// Each path's error against e^{−k t} stays within 100 rtol of the largest component (the
/// global error of a tolerance-controlled run: a few to tens of tolerances over a span of
/// k t up to 10), and the two paths take the same steps: the diagonal Jacobian by one
/// coloured difference equals the analytic one to √ε, far inside Newton's tolerance.
#[test]
fn a_diagonal_system_on_sparse_matrices_meets_its_exact_solution() {
    let n = 1000;
    let sys = Diagonal((0..n).map(|i| 1.0 + 9.0 * i as f64 / n as f64).collect());
    let y0 = vec![1.0; n];
    for method in [Method::Bdf, Method::Trbdf2, Method::Esdirk34] {
        let mut stats = Vec::new();
        for la in [LinearAlgebra::Dense, LinearAlgebra::Auto] {
            let p = Problem::new(&sys, &opts(method, la)).unwrap();
            assert_eq!(p.diffsol().unwrap().is_sparse(), la == LinearAlgebra::Auto);
            let sol = p.solve((0.0, 1.0), &y0).unwrap();
            let err = sol
                .y_final
                .iter()
                .zip(&sys.0)
                .map(|(y, k)| (y - (-k).exp()).abs())
                .fold(0.0, f64::max);
            assert!(err <= 100.0 * 1e-8, "{method} {la:?}: error {err:e}");
            stats.push(sol.stats);
        }
        // Without an analytic Jacobian the dense path colours its differences by the same
        // pattern (lash_solver::jacobian): both paths evaluate the same f at the same points
        // and take the same steps, Newton iterations and factorisations.
        let (d, s) = (stats[0], stats[1]);
        assert!(s.jac_evals > 0, "{method}");
        assert_eq!(
            (
                d.accepted,
                d.rhs_evals,
                d.jac_evals,
                d.newton_iters,
                d.lu_factorizations
            ),
            (
                s.accepted,
                s.rhs_evals,
                s.jac_evals,
                s.newton_iters,
                s.lu_factorizations
            ),
            "{method}"
        );
    }
}

struct NanOff(Vec<f64>);

impl OdeSystem for NanOff {
    fn dim(&self) -> usize {
        self.0.len()
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        let at_start = y == self.0.as_slice();
        for (d, y) in dy.iter_mut().zip(y) {
            *d = if at_start { -y } else { f64::NAN };
        }
    }
    fn jacobian_sparsity(&self) -> Option<Vec<Vec<usize>>> {
        Some((0..self.0.len()).map(|j| vec![j]).collect())
    }
}

#[test]
fn a_nan_jacobian_on_the_sparse_path_is_a_typed_error() {
    let sys = NanOff(vec![1.0; 800]);
    for method in [Method::Bdf, Method::Trbdf2, Method::Esdirk34] {
        let p = Problem::new(&sys, &opts(method, LinearAlgebra::Sparse)).unwrap();
        match p.solve((0.0, 1.0), &sys.0) {
            Err(
                SolveError::NewtonFailure { .. }
                | SolveError::StepSizeTooSmall { .. }
                | SolveError::NonFiniteState { .. },
            ) => {}
            other => panic!("{method}: {:?}", other.map(|s| s.t_final)),
        }
    }
}

/// Rodas5P on the sparse path (lash_solver::rosenbrock, sparse_lu::ShiftedSparse) on the
/// diagonal system: its error against e^{−k t} within 100 rtol as diffsol's methods' above,
/// and, the system giving no analytic Jacobian, the same f at the same points on both paths
/// (the dense path colours its differences by the same pattern) with a diagonal W whose LU is
/// a division per entry on both: the same steps, evaluations and factorisations.
#[test]
fn rodas5p_on_sparse_matrices_meets_the_exact_solution() {
    let n = 1000;
    let sys = Diagonal((0..n).map(|i| 1.0 + 9.0 * i as f64 / n as f64).collect());
    let y0 = vec![1.0; n];
    let mut runs = Vec::new();
    for la in [LinearAlgebra::Dense, LinearAlgebra::Auto] {
        let p = Problem::new(&sys, &opts(Method::Rodas5p, la)).unwrap();
        assert_eq!(p.is_sparse(), la == LinearAlgebra::Auto);
        let sol = p.solve((0.0, 1.0), &y0).unwrap();
        let err = sol
            .y_final
            .iter()
            .zip(&sys.0)
            .map(|(y, k)| (y - (-k).exp()).abs())
            .fold(0.0, f64::max);
        assert!(err <= 100.0 * 1e-8, "{la:?}: error {err:e}");
        runs.push(sol);
    }
    let (d, s) = (runs[0].stats, runs[1].stats);
    assert!(s.jac_evals > 0 && s.lu_factorizations > 0);
    assert_eq!(
        (
            d.accepted,
            d.rejected_error,
            d.rhs_evals,
            d.jac_evals,
            d.lu_factorizations
        ),
        (
            s.accepted,
            s.rejected_error,
            s.rhs_evals,
            s.jac_evals,
            s.lu_factorizations
        )
    );
    let diff = runs[0]
        .y_final
        .iter()
        .zip(&runs[1].y_final)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(diff <= 1e-14, "difference {diff:e}");
}

/// A NaN Jacobian reaching Rodas5P's sparse LU ends in a typed error, as on diffsol's path.
#[test]
fn a_nan_jacobian_on_rodas5ps_sparse_path_is_a_typed_error() {
    let sys = NanOff(vec![1.0; 800]);
    let p = Problem::new(&sys, &opts(Method::Rodas5p, LinearAlgebra::Sparse)).unwrap();
    assert!(p.is_sparse());
    match p.solve((0.0, 1.0), &sys.0) {
        Err(
            SolveError::NewtonFailure { .. }
            | SolveError::StepSizeTooSmall { .. }
            | SolveError::NonFiniteState { .. },
        ) => {}
        other => panic!("{:?}", other.map(|s| s.t_final)),
    }
}
