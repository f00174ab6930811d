//! diffsol's stiff methods (BDF, TR-BDF2, ESDIRK3(4)) behind the [`Stepper`] trait.
//!
//! ```text
//! BDF (variable order 1–5, NDF form):  Σ_{j=0..k} α_j y_{n+1−j} = h f(t_{n+1}, y_{n+1})
//!   diffsol's `Bdf`, after Byrne & Hindmarsh (1975) and Shampine & Reichelt's ode15s (1997)
//! TR-BDF2 (ESDIRK, order 2(3)): Bank et al. (1985); Hosea & Shampine (1996)
//! ESDIRK3(4) (order 3(4)):      Jørgensen, Kristensen & Thomsen (2018), arXiv:1803.01613
//! Newton on  (I − h γ J) Δ = −r,   J = ∂f/∂y (dense: crate::auto_lu; sparse: crate::sparse_lu)
//! ```
//!
//! Backend: diffsol 0.18 with its nalgebra matrices and LU (chosen for the small dense systems
//! of this project, where faer's dispatch and workspace handling dominate: BENCHMARKS.md, "What
//! the profile showed"), or, for large systems with a sparse Jacobian pattern, faer's vectors
//! and compressed-column matrices (crate::linear_algebra: the choice, and the sparse path's
//! coloured finite-difference Jacobian). Everything below is generic over the two
//! ([`crate::linear_algebra`]'s `La`); the public types wrap one or the other. The system
//! reaches diffsol as a custom `OdeEquations` type whose right-hand side operator supplies
//! - the Jacobian-vector product `J v` (diffsol's required interface): the system's dense
//!   Jacobian times v when it has one, a forward difference of f along v otherwise;
//! - the dense Jacobian itself (`jacobian_inplace`), so that diffsol does not assemble it
//!   column by column from n products: the system's Jacobian, or the forward-difference
//!   Jacobian of [`crate::jacobian`] (n + 1 RHS evaluations); on the sparse path the
//!   coloured forward differences into the compressed columns (colours + 1 RHS evaluations,
//!   [`crate::jacobian::JacobianEvaluator::sparse_difference`]), and its pattern
//!   (`jacobian_sparsity`), from which diffsol builds the Newton matrix's.
//!
//! Ownership: diffsol's solvers borrow their `OdeSolverProblem`. Following diffsol's own
//! pattern, the problem ([`DiffsolProblem`]) is owned by the caller's [`crate::Problem`] and
//! every [`DiffsolStepper`] borrows it; no `unsafe` is involved.
//!
//! What our driver relies on, and how it is met:
//! - `step(t_stop)` never passes `t_stop`: it is given to diffsol as its stop time
//!   (`set_stop_time`), and a step that diffsol reports as having reached it ends exactly on it.
//! - `interpolate` is diffsol's dense output (BDF: the interpolating polynomial of its
//!   difference table; SDIRK: the continuous extension of the tableau).
//! - Events are located by [`crate::Integrator`] on that dense output; diffsol's root finding
//!   is not used.
//! - `restart(t, y)` builds a new diffsol solver on the same problem from a fresh state
//!   (t, y, f(t, y), h): no history survives, BDF starts again at order 1, the Jacobian is
//!   re-evaluated. The first trial step is chosen as at the start: `opts.h0`, else Hairer's
//!   estimate (diffsol's `set_step_size`, redone here so that its probe f(t + h0, ·) stays
//!   inside the span to the stop time: diffsol's own evaluates f up to 0.01 d0/d1 ahead,
//!   beyond a short span), capped by h_max. The solver is built at the first step after a
//!   start or restart, when the stop time is known; f(t, y) is evaluated (and checked) at the
//!   start itself. States are built from diffsol's
//!   `StateCommon`, so a BDF difference table is never inherited: the known pitfall of a
//!   solver built from a state taken after `state_mut_back` (stale history unless `as_mut()`
//!   is called first) cannot arise. diffsol's `set_state` with such a fresh state (after
//!   `set_problem`) does not give the same results as a rebuilt solver: on a bouncing ball with
//!   drag its BDF failed with a too-small step at the first bounce, where the rebuilt solver
//!   runs through (it keeps the step-size history and Newton rate estimates of the old
//!   trajectory). Restarts therefore rebuild; a rebuild costs the allocation of the solver's
//!   work vectors and one Jacobian, which the fresh state needs anyway.
//! - diffsol has no maximum step. Our `h_max` is enforced with stop times, so that no step is
//!   longer than h_max·(1 + 10⁻¹⁰). Under the options' `h_max` alone each step gets the stop
//!   time t + h_max (t_stop itself when the landing rule of [`crate::stepper::landing_step`]
//!   says a step of h_max lands on it), held until it is reached, at the cost of a step-size
//!   rescale whenever a stop is reached. Under the contact-aware step limit
//!   ([`crate::Integrator`], which sets it through [`Stepper::set_h_max`] after every step) a
//!   stop time is set only where the limit binds: when the step diffsol is about to try (its
//!   state's h) is longer than h_max·(1 + 10⁻¹⁰), the step gets the stop time t + h_max (the
//!   landing rule as above), to which diffsol shortens it; otherwise the stop time is t_stop.
//!   diffsol never lengthens a step while taking it (rejections shrink it), so no step is
//!   longer than h_max·(1 + 10⁻¹⁰) either way, and under the limit a step diffsol would take
//!   anyway is never cut short of a held stop (which rescales BDF's difference table and
//!   restarts its count of equal steps, delaying order changes). On the graze of
//!   tests/step_limit.rs (bdf, rtol 1e-6, limit τ) the run takes 157 steps instead of 236.
//! - A stop time closer than diffsol's round-off (100 ε (|t| + |h|)) cannot be stepped to by
//!   diffsol; such a sliver (an event just before t_end) is bridged by one explicit Euler
//!   step and a restart.
//! - `h_min` (floor max(h_min, 16 ε |t|)) is diffsol's minimum step, updated before each step.
//! - diffsol's cumulative limit on Newton failures is raised to `max_steps` (our own budget);
//!   the budgets ([`crate::stepper::Budget`]) are checked before every step.
//! - diffsol's controllers are its own; `controller` and `limits` do not apply (options
//!   validation rejects a controller for these methods, and `adaptive = false`:
//!   [`crate::options`]).
//!
//! Errors: diffsol's step-size and error-test failures become `StepSizeTooSmall` (or
//! `NewtonFailure` when Newton convergence failures, not error-test failures, drove the step
//! size down in the failing step), its Newton and linear-solver failures `NewtonFailure`,
//! each with the time and state of the last accepted step; a non-finite state after a step
//! becomes `NonFiniteState`. No diffsol error panics.
//!
//! Statistics (diffsol → [`Stats`]): `number_of_steps` → accepted, error-test failures →
//! rejected_error, Newton convergence failures → rejected_newton, Newton iterations →
//! newton_iters, linear-solver setups (factorisations of I − hγJ) → lu_factorizations;
//! rhs_evals and jac_evals are counted by our operator (finite-difference columns included).
//! Counters of solvers replaced at restarts are carried over; the RHS and Jacobian counts are
//! those made since this stepper was built (a problem may serve several integrations).

use std::cell::RefCell;
use std::rc::Rc;

use diffsol::ode_solver::state::StateCommon;
use diffsol::{
    Bdf, BdfState, DiffsolError, Matrix, NonLinearOp, OdeBuilder, OdeEquations, OdeSolverConfig,
    OdeSolverMethod, OdeSolverProblem, OdeSolverState, OdeSolverStopReason, RkState, Sdirk,
    Tableau, Vector, VectorRef,
};
use diffsol_la::MatrixRef;

use crate::error::SolveError;
use crate::jacobian::{Colouring, JacobianEvaluator};
use crate::kkt::KktNewton;
use crate::linear_algebra::{sparse_pattern, uses_kkt, Dense, Kkt, La, LinearAlgebra, Sparse};
use crate::method::{Family, Method};
use crate::options::{Budgets, DiffsolConfig, OptionError, OptionField, Reason, SolverOptions};
use crate::stats::Stats;
use crate::stepper::{check_stop, landing_step, step_floor, Budget, StepQuadrature, Stepper};
use crate::system::OdeSystem;

mod ops;
mod quadrature;
use ops::{SysEqn, SysInit, SysOut, SysRhs};

type Problem<'a, S, B> = OdeSolverProblem<SysEqn<'a, S, B>>;

/// The relative slack of `h_max` (module documentation): a step up to h_max·(1 + 10⁻¹⁰) is not
/// cut (the landing rule's sliver, [`crate::stepper::landing_step`]).
const H_MAX_SLACK: f64 = 1e-10;

/// rhs_evals and jac_evals made through `problem` so far (by every stepper on it).
fn counts<S: OdeSystem + ?Sized, B: La>(problem: &Problem<'_, S, B>) -> Stats {
    *problem.eqn.rhs.counts.borrow()
}

/// diffsol's problem for one system and one set of tolerances: owned by the caller (our
/// [`crate::Problem`]) and borrowed by every [`DiffsolStepper`] built on it, diffsol's own
/// pattern (the caller keeps the `OdeSolverProblem`, the solver borrows it). Dense or sparse
/// ([`crate::linear_algebra`]).
pub struct DiffsolProblem<'a, S: OdeSystem + ?Sized> {
    inner: AnyProblem<'a, S>,
}

enum AnyProblem<'a, S: OdeSystem + ?Sized> {
    Dense(Problem<'a, S, Dense>),
    Sparse(Problem<'a, S, Sparse>),
    Kkt(Problem<'a, S, Kkt>),
}

impl<'a, S: OdeSystem + ?Sized> DiffsolProblem<'a, S> {
    /// Builds diffsol's problem for `sys` with the tolerances and budgets of `cfg` (the
    /// validated configuration of one of diffsol's methods), on the linear algebra `choice`
    /// picks ([`crate::linear_algebra::sparse_pattern`]), after checking its matrices against
    /// the memory budget (`max_memory`, else crate::memory's share of what is available):
    /// n² on the dense path, the pattern's entries on the sparse one.
    pub fn new(
        sys: &'a S,
        cfg: &DiffsolConfig,
        choice: LinearAlgebra,
        max_memory: Option<u64>,
    ) -> Result<Self, SolveError> {
        let n = sys.dim();
        let method = cfg.method();
        let dense = || -> Result<AnyProblem<'a, S>, SolveError> {
            crate::memory::check_method(method, n, max_memory).map_err(SolveError::OutOfMemory)?;
            // The first of the n² matrices (crate::memory): a refusal of the allocator is an
            // error here; diffsol's own (nalgebra's) allocations are covered by the budget
            // only.
            let jac_work = crate::memory::try_zeros(n, n).map_err(SolveError::OutOfMemory)?;
            Ok(AnyProblem::Dense(build::<S, Dense>(
                sys, cfg, jac_work, None, None,
            )?))
        };
        let pattern = sparse_pattern(sys, choice);
        let kkt = sys
            .kkt()
            .filter(|_| uses_kkt(sys, choice, pattern.is_some()));
        let inner = match pattern {
            None if kkt.is_some() => {
                let shape = kkt.map(|k| k.kkt_shape()).expect("checked");
                crate::memory::check_kkt(method, &shape, max_memory)
                    .map_err(SolveError::OutOfMemory)?;
                let nq = shape.nq;
                let newton = (2 * nq == n)
                    .then(|| {
                        KktNewton::new(shape, crate::kkt::increment_floors(diff_scale(cfg, n)))
                    })
                    .flatten();
                let upper = crate::kkt::upper_pattern(nq);
                match (newton, Kkt::sparsity(n, &upper)) {
                    (Some(newton), Some(s)) => AnyProblem::Kkt(build::<S, Kkt>(
                        sys,
                        cfg,
                        faer::Mat::zeros(0, 0),
                        None,
                        Some((s, Rc::new(RefCell::new(newton)))),
                    )?),
                    _ => dense()?,
                }
            }
            None => dense()?,
            Some(pattern) => {
                let nnz = pattern.iter().map(Vec::len).sum::<usize>();
                crate::memory::check_sparse(method, n, nnz, max_memory)
                    .map_err(SolveError::OutOfMemory)?;
                // sparse_pattern's rows are in range, ascending and distinct: neither fails.
                let sparse = Colouring::new(pattern)
                    .and_then(|c| Sparse::sparsity(n, c.pattern()).map(|s| (c, s)));
                match sparse {
                    Some(sparse) => AnyProblem::Sparse(build::<S, Sparse>(
                        sys,
                        cfg,
                        faer::Mat::zeros(0, 0),
                        Some(sparse),
                        None,
                    )?),
                    None => dense()?,
                }
            }
        };
        Ok(DiffsolProblem { inner })
    }

    /// Whether the problem runs on sparse matrices ([`crate::linear_algebra`]).
    pub fn is_sparse(&self) -> bool {
        matches!(self.inner, AnyProblem::Sparse(_))
    }

    /// Whether the Newton solve goes through the system's KKT form ([`crate::kkt`]).
    pub fn is_kkt(&self) -> bool {
        matches!(self.inner, AnyProblem::Kkt(_))
    }
}

/// The `kkt` path's parts of a problem: diffsol's sparsity of J's identity block and the
/// shared linearisation (crate::kkt).
type KktParts<B> = (<<B as La>::M as Matrix>::Sparsity, Rc<RefCell<KktNewton>>);

/// Floors of the difference increments: atol_i / rtol (crate::jacobian).
fn diff_scale(cfg: &DiffsolConfig, n: usize) -> Vec<f64> {
    let (rtol, atol) = (cfg.tolerances().rtol(), cfg.tolerances().atol());
    (0..n).map(|i| atol.get(i) / rtol).collect()
}

/// diffsol's problem on the linear algebra `B`; `sparse` is the sparse path's coloured
/// pattern and diffsol's form of it (None on the dense path), `jac_work` the dense products'
/// scratch.
fn build<'a, S: OdeSystem + ?Sized, B: La>(
    sys: &'a S,
    cfg: &DiffsolConfig,
    jac_work: faer::Mat<f64>,
    sparse: Option<(Colouring, <B::M as Matrix>::Sparsity)>,
    kkt: Option<KktParts<B>>,
) -> Result<Problem<'a, S, B>, SolveError> {
    let n = sys.dim();
    let ctx = B::C::default();
    let (rtol, atol) = (cfg.tolerances().rtol(), cfg.tolerances().atol());
    let scale = diff_scale(cfg, n);
    let (colouring, sparsity, kkt) = match (sparse, kkt) {
        (Some((c, s)), _) => (Some(c), Some(s), None),
        (None, Some((s, k))) => (None, Some(s), Some(k)),
        (None, None) => (None, None, None),
    };
    let eqn = SysEqn {
        rhs: SysRhs {
            sys,
            n,
            ctx,
            jac_eval: RefCell::new(JacobianEvaluator::new(scale)),
            work: RefCell::new((vec![0.0; n], vec![0.0; n], vec![0.0; n], jac_work)),
            counts: RefCell::new(Stats::default()),
            colouring,
            sparsity,
            kkt,
        },
        // Never evaluated: states are built directly from (t, y).
        init: SysInit {
            y0: vec![0.0; n],
            ctx,
        },
        out: SysOut {
            sys,
            n,
            m: sys.n_quadratures(),
            ctx,
        },
    };
    let atol: Vec<f64> = (0..n).map(|i| atol.get(i)).collect();
    let mut problem = OdeBuilder::<B::M>::new()
        .rtol(rtol)
        .atol(atol)
        .build_from_eqn(eqn)
        .map_err(|e| {
            OptionError::new(
                OptionField::Method,
                Reason::Invalid(format!("diffsol: {e}")),
            )
        })?;
    problem.ode_options.max_nonlinear_solver_failures = cfg.budgets().max_steps();
    // The quadrature (OdeSystem::quadrature) integrated by the method, out of the error norm
    // (no out_rtol/out_atol): crate::diffsol_backend::quadrature.
    problem.integrate_out = sys.n_quadratures() > 0;
    Ok(problem)
}

enum Solver<'p, 'a, S: OdeSystem + ?Sized, B: La> {
    Bdf(Box<Bdf<'p, SysEqn<'a, S, B>, B::Lu>>),
    Sdirk(Box<Sdirk<'p, SysEqn<'a, S, B>, B::Lu>>),
}

macro_rules! with_solver {
    ($solver:expr, $s:ident => $body:expr) => {
        match $solver {
            Solver::Bdf($s) => $body,
            Solver::Sdirk($s) => $body,
        }
    };
}

/// One of diffsol's stiff methods driven step by step.
///
/// ```text
/// BDF:      Σ α_j y_{n+1−j} = h f(t_{n+1}, y_{n+1}),  orders 1–5
/// TR-BDF2:  ESDIRK, order 2(3);   ESDIRK34: order 3(4)
/// ```
/// diffsol 0.18 (M. Robinson), nalgebra's dense or faer's sparse matrices
/// ([`crate::linear_algebra`]); see the module documentation for how our stepper contract
/// (stop times, dense output, restarts, h_max, errors, counters) is met.
pub struct DiffsolStepper<'p, 'a, S: OdeSystem + ?Sized> {
    inner: AnyStepper<'p, 'a, S>,
}

enum AnyStepper<'p, 'a, S: OdeSystem + ?Sized> {
    Dense(Core<'p, 'a, S, Dense>),
    Sparse(Core<'p, 'a, S, Sparse>),
    Kkt(Core<'p, 'a, S, Kkt>),
}

macro_rules! with_core {
    ($stepper:expr, $c:ident => $body:expr) => {
        match $stepper {
            AnyStepper::Dense($c) => $body,
            AnyStepper::Sparse($c) => $body,
            AnyStepper::Kkt($c) => $body,
        }
    };
}

impl<'p, 'a, S: OdeSystem + ?Sized> DiffsolStepper<'p, 'a, S> {
    /// Builds the problem's method (bdf, trbdf2 or esdirk34, from `opts`) at (t0, y0).
    /// Options must be validated and be the ones the problem was built with.
    pub fn new(
        problem: &'p DiffsolProblem<'a, S>,
        t0: f64,
        y0: &[f64],
        opts: &SolverOptions,
    ) -> Result<Self, SolveError> {
        let inner = match &problem.inner {
            AnyProblem::Dense(p) => AnyStepper::Dense(Core::new(p, t0, y0, opts)?),
            AnyProblem::Sparse(p) => AnyStepper::Sparse(Core::new(p, t0, y0, opts)?),
            AnyProblem::Kkt(p) => AnyStepper::Kkt(Core::new(p, t0, y0, opts)?),
        };
        Ok(DiffsolStepper { inner })
    }

    /// Current order of the method: BDF's variable order (1 right after a start or restart),
    /// the tableau's order for the SDIRK methods.
    pub fn order(&self) -> usize {
        with_core!(&self.inner, c => c.order())
    }
}

impl<S: OdeSystem + ?Sized> Stepper for DiffsolStepper<'_, '_, S> {
    fn method(&self) -> Method {
        with_core!(&self.inner, c => c.method)
    }
    fn t(&self) -> f64 {
        with_core!(&self.inner, c => c.t)
    }
    fn y(&self) -> &[f64] {
        with_core!(&self.inner, c => &c.y)
    }
    fn t_prev(&self) -> f64 {
        with_core!(&self.inner, c => c.t_prev)
    }
    fn step(&mut self, t_stop: f64) -> Result<(), SolveError> {
        with_core!(&mut self.inner, c => c.step(t_stop))
    }
    fn interpolate(&self, t: f64, out: &mut [f64]) {
        with_core!(&self.inner, c => c.interpolate(t, out))
    }
    fn interpolate_many(&self, ts: &[f64], out: &mut [f64]) {
        with_core!(&self.inner, c => c.interpolate_many(ts, out))
    }
    fn set_h_max(&mut self, h_max: f64) {
        with_core!(&mut self.inner, c => c.set_h_max(h_max))
    }
    fn restart(&mut self, t: f64, y: &[f64]) -> Result<(), SolveError> {
        with_core!(&mut self.inner, c => c.restart(t, y))
    }
    fn stats(&self) -> Stats {
        with_core!(&self.inner, c => c.stats())
    }
    fn step_quadrature(&self, value: &mut [f64], _estimate: &mut [f64]) -> StepQuadrature {
        with_core!(&self.inner, c => c.quad.write(value))
    }
}

/// What the stepper reads of its `SolverOptions` while it runs: the first step and the step
/// bounds (`h_max` replaced by the contact-aware limit, [`Stepper::set_h_max`]). Copied from
/// the options rather than the options cloned, which may carry an output grid.
#[derive(Clone, Copy, Debug)]
struct StepOptions {
    h0: Option<f64>,
    h_min: f64,
    h_max: f64,
}

impl From<&SolverOptions> for StepOptions {
    fn from(opts: &SolverOptions) -> Self {
        StepOptions {
            h0: opts.h0,
            h_min: opts.h_min,
            h_max: opts.h_max,
        }
    }
}

/// The stepper on the linear algebra `B`.
struct Core<'p, 'a, S: OdeSystem + ?Sized, B: La> {
    problem: &'p Problem<'a, S, B>,
    /// The live solver, borrowing `problem`: None between a start (or restart) and the first
    /// step after it, which builds it (`pending`), and after a failed restart.
    solver: Option<Solver<'p, 'a, S, B>>,
    /// f(t, y) of a start whose solver is built at the next step, when the stop time is known
    /// (the starting-step estimate keeps its probe inside it: `initial_h`).
    pending: Option<Vec<f64>>,
    method: Method,
    /// The step options of the validated `SolverOptions` (h_max: the limit in force).
    opts: StepOptions,
    budget: Budget,
    t: f64,
    t_prev: f64,
    y: Vec<f64>,
    /// The stop time the current steps head for (t_stop, or the h_max stop).
    tstop: Option<f64>,
    /// Whether `h_max` is the contact-aware step limit ([`Stepper::set_h_max`] called): a stop
    /// time only where it binds (module documentation).
    limited: bool,
    /// The stop time set in diffsol: `tstop`, or the natural end of a step that would stop a
    /// sliver short of it (the landing rule in `step`).
    tstop_set: Option<f64>,
    /// The state before an explicit Euler sliver step (see `sliver_step`), while the last
    /// step is one.
    sliver: Option<Vec<f64>>,
    /// The problem's rhs/jac counters when this stepper was built (the problem may serve
    /// several integrations).
    counts_at_start: Stats,
    /// Solver counters of replaced solvers (restarts) and of Euler slivers.
    base: Stats,
    /// The smallest and largest accepted steps (`h_min_used`, `h_max_used`; its counters
    /// stay 0). The counters are read from `base`, the live solver and the problem when
    /// asked ([`Core::stats`]), not copied after every step.
    sizes: Stats,
    buf: RefCell<B::V>,
    /// The quadrature's increments (diffsol_backend::quadrature).
    quad: quadrature::Track,
}

fn map_err(e: DiffsolError, t: f64, h: f64, y: &[f64]) -> SolveError {
    use diffsol::error::OdeSolverError as E;
    match &e {
        DiffsolError::OdeSolverError(E::StepSizeTooSmall { .. })
        | DiffsolError::OdeSolverError(E::TooManyErrorTestFailures { .. }) => {
            SolveError::StepSizeTooSmall {
                t,
                h,
                y: y.to_vec(),
            }
        }
        _ => SolveError::NewtonFailure {
            t,
            y: y.to_vec(),
            reason: format!("diffsol: {e}"),
        },
    }
}

impl<'p, 'a, S: OdeSystem + ?Sized, B: La> Core<'p, 'a, S, B>
where
    for<'b> &'b B::V: VectorRef<B::V>,
    for<'b> &'b B::M: MatrixRef<B::M>,
{
    fn new(
        problem: &'p Problem<'a, S, B>,
        t0: f64,
        y0: &[f64],
        opts: &SolverOptions,
    ) -> Result<Self, SolveError> {
        let method = opts.method;
        if !method.is_diffsol() {
            return Err(OptionError::new(
                OptionField::Method,
                Reason::WrongFamily {
                    method,
                    expected: Family::Diffsol.describe(),
                },
            )
            .into());
        }
        let n = y0.len();
        if n != problem.eqn.rhs.n {
            return Err(OptionError::new(
                OptionField::Y0,
                Reason::WrongLength {
                    len: n,
                    expected: problem.eqn.rhs.n,
                },
            )
            .into());
        }
        let ctx = *problem.context();
        let mut st = Core {
            problem,
            solver: None,
            pending: None,
            method,
            opts: StepOptions::from(opts),
            budget: Budget::new(Budgets::new(opts.max_steps, opts.max_wall_time)?),
            t: t0,
            t_prev: t0,
            y: y0.to_vec(),
            tstop: None,
            limited: false,
            tstop_set: None,
            sliver: None,
            counts_at_start: counts(problem),
            base: Stats::default(),
            sizes: Stats::default(),
            buf: RefCell::new(B::V::zeros(n, ctx)),
            quad: quadrature::Track::new(problem.eqn.out.m),
        };
        st.start(t0, y0)?;
        Ok(st)
    }

    fn order(&self) -> usize {
        match &self.solver {
            Some(solver) => with_solver!(solver, s => s.order()),
            None if self.pending.is_some() => self.start_order(),
            None => 0,
        }
    }

    /// The order a fresh solver starts with.
    fn start_order(&self) -> usize {
        match self.method {
            Method::Bdf => 1,
            Method::Trbdf2 => Tableau::<f64>::tr_bdf2().order(),
            _ => Tableau::<f64>::esdirk34().order(),
        }
    }

    /// Starts at (t, y): evaluates f(t, y) (a non-finite value fails here) and leaves the
    /// solver to be built by the next step, which knows the stop time (`build`).
    fn start(&mut self, t: f64, y: &[f64]) -> Result<(), SolveError> {
        let n = y.len();
        let mut dy = vec![0.0; n];
        self.problem.eqn.rhs.eval(t, y, &mut dy);
        self.solver = None;
        self.pending = None;
        self.quad.clear();
        if !dy.iter().all(|v| v.is_finite()) {
            return Err(SolveError::NonFiniteState { t, y: y.to_vec() });
        }
        self.pending = Some(dy);
        self.tstop = None;
        self.tstop_set = None;
        self.t = t;
        self.t_prev = t;
        self.y.copy_from_slice(y);
        Ok(())
    }

    /// Builds the fresh diffsol solver of a start at (self.t, self.y) with f = `dy`, its first
    /// trial step `opts.h0` or the starting-step estimate with its probe inside
    /// [t, `t_stop`] (`initial_h`).
    fn build(&mut self, dy: Vec<f64>, t_stop: f64) -> Result<(), SolveError> {
        let problem = self.problem;
        let ctx = *problem.context();
        let (t, y) = (self.t, &self.y);
        let yv = B::V::from_slice(y, ctx);
        let dy = B::V::from_slice(&dy, ctx);
        let empty = || B::V::zeros(0, ctx);
        let (g, dg) = self.quad.start::<S, B>(problem.eqn.rhs.sys, t, y, ctx);
        let common = StateCommon {
            y: yv,
            dy,
            g,
            dg,
            s: empty(),
            ds: empty(),
            sg: empty(),
            dsg: empty(),
            t,
            h: 1.0,
        };
        let order = self.start_order();
        let err = |e: DiffsolError| map_err(e, t, 0.0, y);
        let h = self.opts.h0;
        let span = t_stop - t;
        let solver = match self.method {
            Method::Bdf => {
                let mut state = BdfState::<B::V>::new_from_common(common);
                Self::initial_h(&mut state, h, problem, order, self.opts, span);
                Solver::Bdf(Box::new(
                    Bdf::new(problem, state, B::lu(problem.eqn.rhs.kkt.as_ref())).map_err(err)?,
                ))
            }
            m => {
                let tableau = if m == Method::Trbdf2 {
                    Tableau::<f64>::tr_bdf2()
                } else {
                    Tableau::<f64>::esdirk34()
                };
                let mut state = RkState::<B::V>::new_from_common(common);
                Self::initial_h(&mut state, h, problem, order, self.opts, span);
                Solver::Sdirk(Box::new(
                    Sdirk::new(problem, state, tableau, B::lu(problem.eqn.rhs.kkt.as_ref()))
                        .map_err(err)?,
                ))
            }
        };
        self.solver = Some(solver);
        Ok(())
    }

    /// The first trial step: `h` when given, else diffsol's starting-step estimate
    /// (`StateRefMut::set_step_size`, Hairer's rule of HNW I §II.4) with its probe kept inside
    /// the `span` to the stop time, raised to h_min; then capped by h_max.
    ///
    /// ```text
    /// d0 = ‖y0‖, d1 = ‖f0‖ (diffsol's weighted norms);  h0 = 1e-6 if d0 or d1 < 1e-5, else 0.01 d0/d1
    /// h0 = min(h0, span)             (diffsol's own estimate evaluates f at t0 + h0 beyond a
    ///                                 short span: scipy's test_tbound_respected_small_interval)
    /// f1 = f(t0 + h0, y0 + h0 f0);   d2 = ‖f1 − f0‖ / h0
    /// h1 = max(1e-6, 1e-3 h0) if max(d1, d2) < 1e-15, else (0.01 / max(d1, d2))^(1/(order+1))
    /// h  = min(100 h0, h1)
    /// ```
    /// Where h0 ≤ span the operations are diffsol's, in its order, on its vectors: the step is
    /// the one diffsol's `set_step_size` gives, bit for bit.
    fn initial_h<St: OdeSolverState<B::V>>(
        state: &mut St,
        h: Option<f64>,
        problem: &Problem<'a, S, B>,
        order: usize,
        opts: impl Into<StepOptions>,
        span: f64,
    ) {
        let opts: StepOptions = opts.into();
        match h {
            Some(h) => *state.as_mut().h = h,
            None => {
                let hs = state.as_mut();
                let (atol, rtol) = (&problem.atol, problem.rtol);
                let (y0, f0, t0) = (&*hs.y, &*hs.dy, *hs.t);
                let d0 = y0.squared_norm(y0, atol, rtol).sqrt();
                let d1 = f0.squared_norm(y0, atol, rtol).sqrt();
                let mut h0 = if d0 < 1e-5 || d1 < 1e-5 {
                    1e-6
                } else {
                    0.01 * (d0 / d1)
                };
                let t1 = if h0 < span {
                    t0 + h0
                } else {
                    h0 = span;
                    t0 + span
                };
                let y1 = f0.clone() * diffsol::scale(h0) + y0;
                let f1 = problem.eqn.rhs().call(&y1, t1);
                let df = f1 - f0;
                let d2 = df.squared_norm(y0, atol, rtol).sqrt() / h0.abs();
                let max_d = if d2 < d1 { d1 } else { d2 };
                let h1 = if max_d < 1e-15 {
                    (h0 * 1e-3).max(1e-6)
                } else {
                    (0.01 / max_d).powf(1.0 / (1.0 + order as f64))
                };
                *hs.h = 100.0 * h0;
                if *hs.h > h1 {
                    *hs.h = h1;
                }
                // Raised to h_min (the estimate is a heuristic; a step below h_min must come
                // from a rejection to count as a failure).
                *hs.h = hs.h.max(opts.h_min);
            }
        }
        let hs = state.as_mut();
        *hs.h = hs.h.min(opts.h_max);
    }

    /// Bridges a stop time closer than diffsol's round-off with one explicit Euler step
    /// y + (t_stop − t) f(t, y) (its error, O((t_stop − t)²), is below round-off) and restarts
    /// the solver there. The dense output over the sliver is linear.
    fn sliver_step(&mut self, t_stop: f64) -> Result<(), SolveError> {
        let n = self.y.len();
        let mut f = vec![0.0; n];
        self.problem.eqn.rhs.eval(self.t, &self.y, &mut f);
        let dt = t_stop - self.t;
        let y_new: Vec<f64> = self.y.iter().zip(&f).map(|(y, f)| y + dt * f).collect();
        if !y_new.iter().all(|v| v.is_finite()) {
            return Err(SolveError::NonFiniteState {
                t: self.t,
                y: self.y.clone(),
            });
        }
        let (t_old, y_old) = (self.t, self.y.clone());
        self.restart(t_stop, &y_new)?;
        self.t_prev = t_old;
        self.sliver = Some(y_old);
        self.base.accepted += 1;
        self.sizes.record_step_size(dt);
        Ok(())
    }

    /// The counters so far: those of replaced solvers (`base`) plus the live solver's
    /// (none between a start and the first step after it), the right-hand sides and
    /// Jacobians made through the problem since this stepper was built, and the step sizes.
    fn stats(&self) -> Stats {
        let counts = counts(self.problem);
        let d = self
            .solver
            .as_ref()
            .map(|solver| with_solver!(solver, s => s.get_statistics().clone()))
            .unwrap_or_default();
        let b = &self.base;
        let mut st = self.sizes;
        st.accepted = b.accepted + d.number_of_steps;
        st.rejected_error = b.rejected_error + d.number_of_error_test_failures;
        st.rejected_newton = b.rejected_newton + d.number_of_nonlinear_solver_fails;
        st.steps = st.accepted + st.rejected_error + st.rejected_newton;
        st.newton_iters = b.newton_iters + d.number_of_nonlinear_solver_iterations;
        st.lu_factorizations = b.lu_factorizations + d.number_of_linear_solver_setups;
        st.rhs_evals = counts.rhs_evals - self.counts_at_start.rhs_evals;
        st.jac_evals = counts.jac_evals - self.counts_at_start.jac_evals;
        st
    }

    /// Step attempts so far: [`Core::stats`]'s `steps`, from the three counters it adds
    /// (the budget's count, before every attempt).
    fn attempts(&self) -> usize {
        let b = &self.base;
        let live = self.solver.as_ref().map_or(0, |solver| {
            with_solver!(solver, s => {
                let d = s.get_statistics();
                d.number_of_steps
                    + d.number_of_error_test_failures
                    + d.number_of_nonlinear_solver_fails
            })
        });
        b.accepted + b.rejected_error + b.rejected_newton + live
    }
}

impl<S: OdeSystem + ?Sized, B: La> Core<'_, '_, S, B>
where
    for<'b> &'b B::V: VectorRef<B::V>,
    for<'b> &'b B::M: MatrixRef<B::M>,
{
    fn step(&mut self, t_stop: f64) -> Result<(), SolveError> {
        check_stop(self.t, t_stop)?;
        self.budget.check(self.attempts(), self.t, &self.y)?;
        self.sliver = None;
        if let Some(dy) = self.pending.take() {
            self.build(dy, t_stop)?;
        }
        let Some(solver) = self.solver.as_mut() else {
            return Err(SolveError::NewtonFailure {
                t: self.t,
                y: self.y.clone(),
                reason: "diffsol solver missing after a failed restart".into(),
            });
        };
        let h_now = with_solver!(&*solver, s => s.state().h);
        let remaining = t_stop - self.t;
        // diffsol treats a stop time within 100 ε (|t| + |h|) of its time as reached and
        // cannot step to it: such a sliver is bridged by one explicit Euler step.
        if remaining <= 200.0 * f64::EPSILON * (self.t.abs() + h_now.abs()) {
            return self.sliver_step(t_stop);
        }
        let h_max = self.opts.h_max;
        // Under the contact-aware limit, a step diffsol would take anyway heads for t_stop.
        let free = self.limited && h_now <= h_max * (1.0 + H_MAX_SLACK);
        let want = if h_max.is_finite() && !free {
            match self.tstop {
                // A fixed h_max holds its stop until it is reached; the limit sets it afresh.
                Some(ts) if ts <= t_stop && !self.limited => ts,
                _ => {
                    // The landing rule: land on t_stop rather than leave a sliver.
                    let (h, lands) = landing_step(self.t, t_stop, h_max);
                    if lands {
                        t_stop
                    } else {
                        self.t + h
                    }
                }
            }
        } else {
            t_stop
        };
        let (t, y) = (self.t, &self.y);
        let floor = step_floor(self.opts.h_min, t).max(f64::MIN_POSITIVE);
        // The landing rule for diffsol's stop times: a step that would end short of `want`
        // by more than diffsol's round-off but at most 10⁻¹⁰ h (a few hundred ulps: steps
        // of equal size drifting onto a stop) stops at its own end, reported as `want`.
        // diffsol itself would shrink the next step to the remainder, rescaling its BDF
        // difference table by ~10⁻¹², which ruins the dense output of the step just taken
        // and leaves thousands of steps to grow back (scipy's test_first_step).
        let reach = t + h_now;
        let short = want - reach;
        let set_at = if short > 200.0 * f64::EPSILON * (reach.abs() + h_now.abs())
            && short <= 1e-10 * h_now
        {
            reach
        } else {
            want
        };
        if self.tstop_set != Some(set_at) {
            with_solver!(&mut *solver, s => s.set_stop_time(set_at))
                .map_err(|e| map_err(e, t, h_now, y))?;
            self.tstop_set = Some(set_at);
        }
        self.tstop = Some(want);
        with_solver!(&mut *solver, s => {
            *s.config_mut().as_base_mut().minimum_timestep = floor;
        });
        // The live solver's failures so far, for the error below.
        let (newton_before, error_before) = with_solver!(&*solver, s => {
            let d = s.get_statistics();
            (d.number_of_nonlinear_solver_fails, d.number_of_error_test_failures)
        });
        if self.quad.is_on() {
            with_solver!(&*solver, s => self.quad.before(B::slice(s.state().g)));
        }
        let result = with_solver!(&mut *solver, s => s.step());
        let (t_new, h_state) = with_solver!(&*solver, s => (s.state().t, s.state().h));
        let reached = match result {
            Ok(OdeSolverStopReason::TstopReached) => true,
            Ok(_) => false,
            Err(e) => {
                let after = with_solver!(&*solver, s => s.get_statistics().clone());
                let newton = after.number_of_nonlinear_solver_fails - newton_before;
                let error_test = after.number_of_error_test_failures - error_before;
                // A step-size failure means the trial step fell below the floor; BDF keeps
                // it in its state, the SDIRK methods only their starting step.
                let h_fail = h_state.min(floor);
                // diffsol shrinks the step after Newton failures too: when they are what
                // drove the step size down, say so.
                return Err(match map_err(e, t, h_fail, &self.y) {
                    SolveError::StepSizeTooSmall { t, h, y }
                        if newton > 0 && newton >= error_test =>
                    {
                        SolveError::NewtonFailure {
                            t,
                            y,
                            reason: format!(
                                "diffsol: {newton} Newton convergence failures and \
                                 {error_test} error-test failures drove the step size \
                                 below {floor:e} (h = {h:e})"
                            ),
                        }
                    }
                    e => e,
                });
            }
        };
        let t_new = if reached {
            self.tstop = None;
            self.tstop_set = None;
            want
        } else {
            t_new
        };
        let finite = with_solver!(&*solver, s => {
            let y_new = B::slice(s.state().y);
            if y_new.iter().all(|v| v.is_finite()) {
                self.y.copy_from_slice(y_new);
                true
            } else {
                false
            }
        });
        if !finite {
            return Err(SolveError::NonFiniteState {
                t: self.t,
                y: self.y.clone(),
            });
        }
        if self.quad.is_on() {
            with_solver!(&*solver, s => self.quad.after(B::slice(s.state().g)));
        }
        self.t_prev = self.t;
        self.t = t_new;
        let h = self.t - self.t_prev;
        self.sizes.record_step_size(h);
        Ok(())
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) {
        if t >= self.t || self.t == self.t_prev {
            out.copy_from_slice(&self.y);
            return;
        }
        if let Some(y0) = &self.sliver {
            // The Euler sliver: linear.
            let th = ((t - self.t_prev) / (self.t - self.t_prev)).max(0.0);
            for (i, o) in out.iter_mut().enumerate() {
                *o = y0[i] + th * (self.y[i] - y0[i]);
            }
            return;
        }
        let Some(solver) = self.solver.as_ref() else {
            out.copy_from_slice(&self.y);
            return;
        };
        let mut buf = self.buf.borrow_mut();
        // diffsol's own end time may differ from ours by rounding when a stop time was hit.
        let t_end = with_solver!(solver, s => s.state().t);
        let tq = t.max(self.t_prev).min(t_end);
        match with_solver!(solver, s => s.interpolate_inplace(tq, &mut buf)) {
            Ok(()) => out.copy_from_slice(B::slice(&buf)),
            // Unreachable for t in [t_prev, t]; the end state is the safe answer.
            Err(_) => out.copy_from_slice(&self.y),
        }
    }

    /// [`Stepper::interpolate_many`]: `interpolate` at each time, the work buffer borrowed
    /// and diffsol's solver chosen once; where `interpolate` would not ask diffsol (a step of
    /// length 0, the Euler sliver, no live solver), it is called at each time.
    fn interpolate_many(&self, ts: &[f64], out: &mut [f64]) {
        let n = self.y.len();
        let solver = match &self.solver {
            Some(solver) if n > 0 && self.t != self.t_prev && self.sliver.is_none() => solver,
            _ => {
                if n > 0 {
                    for (&t, o) in ts.iter().zip(out.chunks_exact_mut(n)) {
                        self.interpolate(t, o);
                    }
                }
                return;
            }
        };
        let mut buf = self.buf.borrow_mut();
        with_solver!(solver, s => {
            let t_end = s.state().t;
            for (&t, o) in ts.iter().zip(out.chunks_exact_mut(n)) {
                if t >= self.t {
                    o.copy_from_slice(&self.y);
                    continue;
                }
                let tq = t.max(self.t_prev).min(t_end);
                match s.interpolate_inplace(tq, &mut buf) {
                    Ok(()) => o.copy_from_slice(B::slice(&buf)),
                    Err(_) => o.copy_from_slice(&self.y),
                }
            }
        })
    }

    fn set_h_max(&mut self, h_max: f64) {
        self.limited = true;
        let h_max = h_max.max(self.opts.h_min);
        if h_max != self.opts.h_max {
            // The h_max stop (module documentation) is set again at the next step.
            self.opts.h_max = h_max;
            self.tstop = None;
        }
    }

    fn restart(&mut self, t: f64, y: &[f64]) -> Result<(), SolveError> {
        self.sliver = None;
        self.base = self.stats();
        self.start(t, y)
    }
}

#[cfg(test)]
mod tests;
