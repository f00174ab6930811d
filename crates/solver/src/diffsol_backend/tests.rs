//! Unit tests of diffsol_backend: the starting step and the Jacobian operators.
use super::*;
use crate::testset::Orego;
use diffsol::{
    MatrixCommon, NalgebraContext, NalgebraMat, NalgebraVec, NonLinearOpJacobian, VectorCommon,
};

type Vd = NalgebraVec<f64>;
type Md = NalgebraMat<f64>;
type Cx = NalgebraContext;

/// Orego without its Jacobian (finite differences).
struct OregoFd;
impl OdeSystem for OregoFd {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        Orego.rhs(t, y, dy);
    }
}

fn rhs_op<S: OdeSystem + ?Sized>(sys: &S) -> SysRhs<'_, S, Dense> {
    let n = sys.dim();
    SysRhs {
        sys,
        n,
        ctx: Cx::default(),
        jac_eval: RefCell::new(JacobianEvaluator::new(vec![1.0; n])),
        work: RefCell::new((
            vec![0.0; n],
            vec![0.0; n],
            vec![0.0; n],
            faer::Mat::zeros(n, n),
        )),
        counts: RefCell::new(Stats::default()),
        colouring: None,
        sparsity: None,
        kkt: None,
    }
}

/// Where the probe fits the span, the starting step is diffsol's own `set_step_size`, bit
/// for bit (so runs whose span is longer than the probe are unchanged); where it does not,
/// the probe lands on the stop time.
#[test]
fn the_starting_step_is_diffsols_where_the_probe_fits() {
    let o = SolverOptions {
        method: Method::Bdf,
        rtol: 1e-6,
        atol: crate::options::Atol::Scalar(1e-9),
        ..Default::default()
    };
    let crate::options::Config::Diffsol(cfg) = o.configure(3).unwrap() else {
        panic!("bdf has a diffsol configuration")
    };
    let problem = DiffsolProblem::new(&OregoFd, &cfg, LinearAlgebra::Auto, None).unwrap();
    let AnyProblem::Dense(p) = &problem.inner else {
        panic!("three unknowns are dense")
    };
    let ctx = *p.context();
    for (y, order) in [([2.0, 300.0, 40.0], 1), ([1.0, 2.0, 3.0], 3), ([0.0; 3], 5)] {
        let common = || {
            let yv = Vd::from_slice(&y, ctx);
            let mut dy = Vd::zeros(3, ctx);
            p.eqn.rhs.call_inplace(&yv, 0.5, &mut dy);
            StateCommon {
                y: yv,
                dy,
                g: Vd::zeros(0, ctx),
                dg: Vd::zeros(0, ctx),
                s: Vd::zeros(0, ctx),
                ds: Vd::zeros(0, ctx),
                sg: Vd::zeros(0, ctx),
                dsg: Vd::zeros(0, ctx),
                t: 0.5,
                h: 1.0,
            }
        };
        let mut theirs = BdfState::<Vd>::new_from_common(common());
        theirs
            .as_mut()
            .set_step_size(1.0, &p.atol, p.rtol, &p.eqn, order);
        let mut ours = BdfState::<Vd>::new_from_common(common());
        Core::<OregoFd, Dense>::initial_h(&mut ours, None, p, order, &o, 1e3);
        assert_eq!(
            ours.as_ref().h.to_bits(),
            theirs.as_ref().h.to_bits(),
            "{y:?}"
        );
        // A span shorter than the probe: the probe is the span.
        let mut short = BdfState::<Vd>::new_from_common(common());
        let calls = p.eqn.rhs.counts.borrow().rhs_evals;
        Core::<OregoFd, Dense>::initial_h(&mut short, None, p, order, &o, 1e-12);
        assert_eq!(p.eqn.rhs.counts.borrow().rhs_evals, calls + 1);
        let h = short.as_ref().h;
        assert!(h > 0.0 && h.is_finite() && h < 1e-9, "{h}");
    }
}

/// J v from the product and column j of the dense Jacobian agree with the analytic
/// Jacobian, for the system's Jacobian and for finite differences.
#[test]
fn jacobian_products_and_dense_jacobians_agree() {
    let ctx = Cx::default();
    let y = [2.0, 300.0, 40.0];
    let v = [0.3, -1.0, 2.0];
    let mut exact = faer::Mat::<f64>::zeros(3, 3);
    Orego.jacobian(0.0, &y, exact.as_mut());
    let jv: Vec<f64> = (0..3)
        .map(|i| (0..3).map(|j| exact[(i, j)] * v[j]).sum())
        .collect();
    let (yv, vv) = (Vd::from_slice(&y, ctx), Vd::from_slice(&v, ctx));
    for fd in [false, true] {
        let mut out = Vd::zeros(3, ctx);
        let mut dense = <Md as Matrix>::zeros(3, 3, ctx);
        let (prod, jac) = if fd {
            let op = rhs_op(&OregoFd);
            op.jac_mul_inplace(&yv, 0.0, &vv, &mut out);
            op.jacobian_inplace(&yv, 0.0, &mut dense);
            // one product: f(y) and f(y + εv); one Jacobian: f(y) and 3 columns
            assert_eq!(op.counts.borrow().rhs_evals, 2 + 4);
            assert_eq!(op.counts.borrow().jac_evals, 1);
            (
                out.inner().as_slice().to_vec(),
                dense.inner().as_slice().to_vec(),
            )
        } else {
            let op = rhs_op(&Orego);
            op.jac_mul_inplace(&yv, 0.0, &vv, &mut out);
            op.jacobian_inplace(&yv, 0.0, &mut dense);
            assert_eq!(op.counts.borrow().rhs_evals, 0);
            assert_eq!(op.counts.borrow().jac_evals, 2);
            (
                out.inner().as_slice().to_vec(),
                dense.inner().as_slice().to_vec(),
            )
        };
        // Forward differences: relative error ~√ε·(curvature) ≲ 1e-6 of the row scale.
        let tol = if fd { 1e-5 } else { 1e-12 };
        for i in 0..3 {
            let scale = jv[i].abs().max(77.27 * 300.0 * 1e-3);
            assert!((prod[i] - jv[i]).abs() < tol * scale, "fd {fd}: J v [{i}]");
            for j in 0..3 {
                let e = exact[(i, j)];
                // column-major dense storage
                let d = jac[i + 3 * j];
                assert!(
                    (d - e).abs() < tol * e.abs().max(1.0),
                    "fd {fd}: J[{i},{j}] {d} vs {e}"
                );
            }
        }
    }
}
