//! The system as diffsol's `OdeEquations` (the operators of diffsol_backend's module doc):
//! the right-hand side with its Jacobian products, Jacobian and pattern, the unused initial
//! value operator, and the equations that hold them, on either linear algebra.

use std::cell::RefCell;
use std::rc::Rc;

use diffsol::{
    Matrix, NonLinearOp, NonLinearOpJacobian, OdeEquations, OdeEquationsRef, Op, UnitCallable,
};
use faer::MatMut;

use crate::jacobian::{Colouring, JacobianEvaluator};
use crate::kkt::KktNewton;
use crate::linear_algebra::{JacView, La};
use crate::stats::Stats;
use crate::system::OdeSystem;

/// Scratch of [`SysRhs`]: f(t, y), f(t, y + εv) and y + εv for finite differences; the dense
/// J for products.
pub(super) type Work = (Vec<f64>, Vec<f64>, Vec<f64>, faer::Mat<f64>);

/// The right-hand side operator handed to diffsol, on the linear algebra `B`.
pub(super) struct SysRhs<'a, S: OdeSystem + ?Sized, B: La> {
    pub(super) sys: &'a S,
    pub(super) n: usize,
    pub(super) ctx: B::C,
    pub(super) jac_eval: RefCell<JacobianEvaluator>,
    pub(super) work: RefCell<Work>,
    /// rhs_evals and jac_evals of this operator.
    pub(super) counts: RefCell<Stats>,
    /// The sparse path's pattern, coloured, and diffsol's form of it (None: dense).
    pub(super) colouring: Option<Colouring>,
    pub(super) sparsity: Option<<B::M as Matrix>::Sparsity>,
    /// The `kkt` path's shared linearisation (crate::kkt; None on the other paths).
    pub(super) kkt: Option<Rc<RefCell<KktNewton>>>,
}

impl<S: OdeSystem + ?Sized, B: La> SysRhs<'_, S, B> {
    pub(super) fn eval(&self, t: f64, y: &[f64], out: &mut [f64]) {
        self.sys.rhs(t, y, out);
        self.counts.borrow_mut().rhs_evals += 1;
    }

    /// Dense Jacobian at (t, x) into `jac` (column-major n × n).
    fn dense_jacobian(&self, t: f64, x: &[f64], jac: MatMut<'_, f64>) {
        let mut work = self.work.borrow_mut();
        let mut counts = self.counts.borrow_mut();
        let f0 = &mut work.0;
        if !self.sys.has_jacobian() {
            self.sys.rhs(t, x, f0);
            counts.rhs_evals += 1;
        }
        self.jac_eval
            .borrow_mut()
            .jacobian(self.sys, t, x, f0, jac, &mut counts);
    }
}

impl<S: OdeSystem + ?Sized, B: La> Op for SysRhs<'_, S, B> {
    type T = f64;
    type V = B::V;
    type M = B::M;
    type C = B::C;
    fn context(&self) -> &B::C {
        &self.ctx
    }
    fn nstates(&self) -> usize {
        self.n
    }
    fn nout(&self) -> usize {
        self.n
    }
    fn nparams(&self) -> usize {
        0
    }
}

impl<S: OdeSystem + ?Sized, B: La> NonLinearOp for SysRhs<'_, S, B> {
    fn call_inplace(&self, x: &B::V, t: f64, y: &mut B::V) {
        self.eval(t, B::slice(x), B::slice_mut(y));
    }
}

impl<S: OdeSystem + ?Sized, B: La> NonLinearOpJacobian for SysRhs<'_, S, B> {
    fn jac_mul_inplace(&self, x: &B::V, t: f64, v: &B::V, y: &mut B::V) {
        let (xs, vs) = (B::slice(x), B::slice(v));
        let n = self.n;
        let out = B::slice_mut(y);
        if B::SYSTEM_PRODUCTS && self.sys.has_jacobian() {
            let mut jac = std::mem::replace(&mut self.work.borrow_mut().3, faer::Mat::zeros(0, 0));
            if jac.nrows() != n {
                jac = faer::Mat::zeros(n, n);
            }
            self.dense_jacobian(t, xs, jac.as_mut());
            for (i, o) in out.iter_mut().enumerate() {
                *o = (0..n).map(|j| jac[(i, j)] * vs[j]).sum();
            }
            self.work.borrow_mut().3 = jac;
        } else {
            // Directional forward difference: J v ≈ (f(x + εv) − f(x)) / ε with
            // ε = √eps · max(‖x‖∞, 1) / ‖v‖∞.
            let vmax = vs.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if vmax == 0.0 {
                out.fill(0.0);
                return;
            }
            let xmax = xs.iter().fold(1.0f64, |m, v| m.max(v.abs()));
            let eps = f64::EPSILON.sqrt() * xmax / vmax;
            let mut work = self.work.borrow_mut();
            let (f0, f1, xp, _) = &mut *work;
            for i in 0..n {
                xp[i] = xs[i] + eps * vs[i];
            }
            self.eval(t, xs, f0);
            self.eval(t, xp, f1);
            for i in 0..n {
                out[i] = (f1[i] - f0[i]) / eps;
            }
        }
    }

    fn jacobian_inplace(&self, x: &B::V, t: f64, y: &mut B::M) {
        let x = B::slice(x);
        if let (Some(kkt), Some(sys)) = (&self.kkt, self.sys.kkt()) {
            // J's exact identity block (q' = v); the rest is the linearisation's.
            if let JacView::Sparse { values, .. } = B::view(y) {
                values.fill(1.0);
            }
            let mut counts = self.counts.borrow_mut();
            kkt.borrow_mut().linearise(sys, t, x, &mut counts);
            return;
        }
        match (B::view(y), &self.colouring) {
            (JacView::Dense(jac), _) => self.dense_jacobian(t, x, jac),
            (
                JacView::Sparse {
                    col_ptr,
                    row_idx,
                    values,
                },
                Some(colouring),
            ) => {
                let mut work = self.work.borrow_mut();
                let mut counts = self.counts.borrow_mut();
                let f0 = &mut work.0;
                self.sys.rhs(t, x, f0);
                counts.rhs_evals += 1;
                self.jac_eval.borrow_mut().sparse_difference(
                    self.sys,
                    t,
                    x,
                    f0,
                    colouring,
                    (col_ptr, row_idx),
                    values,
                    &mut counts,
                );
            }
            // A sparse matrix is built only with a colouring (DiffsolProblem::new).
            (JacView::Sparse { values, .. }, None) => values.fill(f64::NAN),
        }
    }

    fn jacobian_sparsity(&self) -> Option<<B::M as Matrix>::Sparsity> {
        self.sparsity.clone()
    }
}

/// The initial-value operator (diffsol requires one; our states are built directly).
pub(super) struct SysInit<B: La> {
    pub(super) y0: Vec<f64>,
    pub(super) ctx: B::C,
}

impl<B: La> Op for SysInit<B> {
    type T = f64;
    type V = B::V;
    type M = B::M;
    type C = B::C;
    fn context(&self) -> &B::C {
        &self.ctx
    }
    fn nstates(&self) -> usize {
        self.y0.len()
    }
    fn nout(&self) -> usize {
        self.y0.len()
    }
    fn nparams(&self) -> usize {
        0
    }
}

impl<B: La> diffsol::ConstantOp for SysInit<B> {
    fn call_inplace(&self, _t: f64, y: &mut B::V) {
        B::slice_mut(y).copy_from_slice(&self.y0);
    }
}

/// The system's quadrature integrand q(t, y) ([`OdeSystem::quadrature`]) as diffsol's output
/// function, which diffsol integrates with the method's own formula when the problem's
/// `integrate_out` is set (out of the error norm: no `out_rtol`/`out_atol`).
pub(super) struct SysOut<'a, S: OdeSystem + ?Sized, B: La> {
    pub(super) sys: &'a S,
    pub(super) n: usize,
    /// m_q = sys.n_quadratures().
    pub(super) m: usize,
    pub(super) ctx: B::C,
}

impl<S: OdeSystem + ?Sized, B: La> Op for SysOut<'_, S, B> {
    type T = f64;
    type V = B::V;
    type M = B::M;
    type C = B::C;
    fn context(&self) -> &B::C {
        &self.ctx
    }
    fn nstates(&self) -> usize {
        self.n
    }
    fn nout(&self) -> usize {
        self.m
    }
    fn nparams(&self) -> usize {
        0
    }
}

impl<S: OdeSystem + ?Sized, B: La> NonLinearOp for SysOut<'_, S, B> {
    fn call_inplace(&self, x: &B::V, t: f64, y: &mut B::V) {
        self.sys.quadrature(t, B::slice(x), B::slice_mut(y));
    }
}

/// The system as diffsol `OdeEquations`: y' = f(t, y), no mass matrix, no roots; the
/// quadrature integrand as the output function when the system has one.
pub(super) struct SysEqn<'a, S: OdeSystem + ?Sized, B: La> {
    pub(super) rhs: SysRhs<'a, S, B>,
    pub(super) init: SysInit<B>,
    pub(super) out: SysOut<'a, S, B>,
}

impl<S: OdeSystem + ?Sized, B: La> Op for SysEqn<'_, S, B> {
    type T = f64;
    type V = B::V;
    type M = B::M;
    type C = B::C;
    fn context(&self) -> &B::C {
        &self.rhs.ctx
    }
    fn nstates(&self) -> usize {
        self.rhs.n
    }
    /// diffsol sizes BDF's output difference table by the equations' `nout`: the
    /// quadrature's when there is one.
    fn nout(&self) -> usize {
        if self.out.m > 0 {
            self.out.m
        } else {
            self.rhs.n
        }
    }
    fn nparams(&self) -> usize {
        0
    }
}

impl<'b, 'a, S: OdeSystem + ?Sized, B: La> OdeEquationsRef<'b> for SysEqn<'a, S, B> {
    type Rhs = &'b SysRhs<'a, S, B>;
    type Mass = &'b UnitCallable<B::M>;
    type Root = &'b UnitCallable<B::M>;
    type Init = &'b SysInit<B>;
    type Out = &'b SysOut<'a, S, B>;
    type Reset = &'b UnitCallable<B::M>;
}

impl<'a, S: OdeSystem + ?Sized, B: La> OdeEquations for SysEqn<'a, S, B> {
    fn rhs(&self) -> &SysRhs<'a, S, B> {
        &self.rhs
    }
    fn mass(&self) -> Option<&UnitCallable<B::M>> {
        None
    }
    fn init(&self) -> &SysInit<B> {
        &self.init
    }
    fn out(&self) -> Option<&SysOut<'a, S, B>> {
        (self.out.m > 0).then_some(&self.out)
    }
    fn set_params(&mut self, _p: &B::V) {}
    fn get_params(&self, _p: &mut B::V) {}
}
