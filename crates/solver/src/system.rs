//! The problem interface: a first-order ODE `y' = f(t, y)` with optional Jacobian and event
//! functions.
//!
//! ```text
//! y' = f(t, y),  y(t0) = y0,  y ∈ ℝⁿ
//! events: g_i(t, y), i = 0..m; a crossing of zero in the chosen direction is located,
//!         the hook `on_event` runs (it may change y and the system's own state),
//!         and integration either stops or restarts from the event state.
//! ```
//!
//! All methods take `&self`: the solvers (diffsol's included) hold a shared reference for the
//! whole integration. A system that keeps state changed by events (an impact velocity, a contact
//! mode) or scratch buffers keeps them behind `Cell`/`RefCell`.

use faer::MatMut;

/// Which sign changes of an event function count as events.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    /// g goes from negative to positive.
    Rising,
    /// g goes from positive to negative.
    Falling,
    /// Either sign change.
    #[default]
    Either,
}

impl Direction {
    /// Whether a change of sign from `before` to `after` is an event in this direction.
    pub fn matches(self, before: f64, after: f64) -> bool {
        let rising = before < 0.0 && after > 0.0;
        let falling = before > 0.0 && after < 0.0;
        match self {
            Direction::Rising => rising,
            Direction::Falling => falling,
            Direction::Either => rising || falling,
        }
    }
}

/// What the integrator does after an event has been located and the hook has run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum EventAction {
    /// Restart from the event state (controller history, FSAL stage and multistep history are
    /// discarded) and go on.
    #[default]
    Continue,
    /// End the integration at the event.
    Stop,
}

/// The declaration of one event function.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, Default)]
pub struct EventSpec {
    /// Which crossings count.
    pub direction: Direction,
    /// What to do after the hook has run (the hook may override it).
    pub action: EventAction,
}

/// A located event, as passed to [`OdeSystem::on_event`] and recorded in the solution.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EventHit {
    /// Index of the event function.
    pub index: usize,
    /// Event time (the end of the final bracket on the side after the crossing, so that
    /// `g(t, y)` already has its new sign there).
    pub t: f64,
    /// True for a crossing from negative to positive.
    pub rising: bool,
}

/// Why a system refused an accepted state ([`OdeSystem::check_accepted`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Rejection {
    /// What happened, as a snake_case name (`"singular_configuration"`).
    pub kind: &'static str,
    /// The message: the time and what happened, and what to do about it when there is a
    /// remedy.
    pub reason: String,
}

/// A first-order ODE system `y' = f(t, y)`.
pub trait OdeSystem {
    /// Dimension n of the state.
    fn dim(&self) -> usize;

    /// Right-hand side: writes `f(t, y)` into `dy` (length n). A system that cannot evaluate
    /// (for example a singular constraint matrix) writes non-finite values; the solvers turn
    /// them into [`crate::SolveError::NonFiniteState`].
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]);

    /// Whether [`OdeSystem::jacobian`] is implemented. When false, implicit methods use finite
    /// differences of `rhs`.
    fn has_jacobian(&self) -> bool {
        false
    }

    /// Dense Jacobian ∂f/∂y at (t, y), written into `jac` (n × n). Called only when
    /// [`OdeSystem::has_jacobian`] returns true.
    fn jacobian(&self, _t: f64, _y: &[f64], _jac: MatMut<'_, f64>) {}

    /// The sparsity pattern of ∂f/∂y when it is known: for each column j, the rows i at which
    /// ∂f_i/∂y_j may be nonzero (entries outside it are taken as 0). Default None: dense.
    /// Used by the finite-difference Jacobian (when the system has no Jacobian of its own),
    /// which then perturbs structurally orthogonal columns together and costs one RHS
    /// evaluation per colour instead of one per column (crate::jacobian). Called once per
    /// integration.
    fn jacobian_sparsity(&self) -> Option<Vec<Vec<usize>>> {
        None
    }

    /// The system's KKT form when its state is y = (q, v), q' = v and its accelerations solve
    /// a sparse linear system (crate::kkt): the `kkt` linear algebra's Newton solve. Default
    /// None.
    fn kkt(&self) -> Option<&dyn KktSystem> {
        None
    }

    /// Whether [`OdeSystem::time_derivative`] is implemented. When false, Rosenbrock methods
    /// take ∂f/∂t by a central difference in t (two RHS evaluations per step), which is
    /// accurate only when f is smooth in t on the scale of the difference's step.
    fn has_time_derivative(&self) -> bool {
        false
    }

    /// ∂f/∂t at (t, y) at fixed y, written into `dfdt` (length n). Called only when
    /// [`OdeSystem::has_time_derivative`] returns true (and the system is not autonomous).
    fn time_derivative(&self, _t: f64, _y: &[f64], _dfdt: &mut [f64]) {}

    /// Whether f does not depend on t (∂f/∂t = 0). Default false. Rosenbrock methods need
    /// ∂f/∂t; for a system that says it is autonomous they skip its finite-difference estimate
    /// (one RHS evaluation per step).
    fn is_autonomous(&self) -> bool {
        false
    }

    /// Number m of event functions.
    fn n_events(&self) -> usize {
        0
    }

    /// Direction and action of event function `i`.
    fn event_spec(&self, _i: usize) -> EventSpec {
        EventSpec::default()
    }

    /// Evaluates all m event functions into `g`.
    fn events(&self, _t: f64, _y: &[f64], _g: &mut [f64]) {}

    /// The event functions into `g` and their rates ġ_i = dg_i/dt along the solution into
    /// `g_dot`, at (t, y); returns false (the default) when the system does not provide the
    /// rates, and then writes nothing.
    ///
    /// ```text
    /// ġ_i(t) = ∂g_i/∂t + ∂g_i/∂y · f(t, y)
    /// ```
    /// With the rates at both ends of a step the integrator skips the interior event samples
    /// when every g_i stays far from zero (see [`crate::Integrator`]). A system should provide
    /// them only when they are cheap: for a mechanism, g and ġ come from positions and
    /// velocities (kinematics) without the force laws or the constraint solve.
    fn event_rates(&self, t: f64, y: &[f64], g: &mut [f64], g_dot: &mut [f64]) -> bool {
        let _ = (t, y, g, g_dot);
        false
    }

    /// Checks a step the method has accepted, from (t_a, y_a) (the last accepted state, or
    /// the state an event hook left) to (t_b, y_b), before events are looked for in it: `Err`
    /// stops the integration with [`crate::SolveError::StateRejected`] at t_b. For the
    /// conditions a step's error estimate cannot see: a finite state that is no longer a
    /// solution of the system's model, or a step that crossed a point where the model does not
    /// hold. The default accepts every step. Not counted as an RHS evaluation.
    fn check_accepted(
        &self,
        t_a: f64,
        y_a: &[f64],
        t_b: f64,
        y_b: &[f64],
    ) -> Result<(), Rejection> {
        let _ = (t_a, y_a, t_b, y_b);
        Ok(())
    }

    /// Number m_q of quadrature variables Q (default 0: none).
    ///
    /// ```text
    /// Q' = q(t, y),  Q(t0) = 0,  Q ∈ ℝ^{m_q}      (q does not depend on Q)
    /// ```
    /// As CVODES's quadrature variables without error control: the integrals are taken by the
    /// method's own formula at its own stage states (`Integrator::step_quadrature`), and they
    /// never enter the error norm, so the step sequence is the one without them, bit for bit.
    fn n_quadratures(&self) -> usize {
        0
    }

    /// The integrand q(t, y) of the quadrature variables, written into `q` (length
    /// [`OdeSystem::n_quadratures`]). Called only when that is nonzero; not counted as an RHS
    /// evaluation.
    fn quadrature(&self, _t: f64, _y: &[f64], _q: &mut [f64]) {}

    /// Runs after an event has been located, with the state at the event time. It may change
    /// `y` (a bounce) and the system's own state (an impact velocity stored for a contact law).
    /// Returns what the integrator does next; the default is the event's declared action.
    fn on_event(&self, hit: &EventHit, _y: &mut [f64]) -> EventAction {
        self.event_spec(hit.index).action
    }
}

/// The integrand of [`WithQuadrature`]: q(t, y) into its last argument.
pub type QuadratureFn<'a> = &'a dyn Fn(f64, &[f64], &mut [f64]);

/// A system with quadrature variables added ([`OdeSystem::quadrature`]): `m` integrands
/// `q`; every other method is the system's own, so the integration is the one without them,
/// bit for bit.
pub struct WithQuadrature<'a, S: OdeSystem + ?Sized> {
    /// The system.
    pub sys: &'a S,
    /// Number of quadrature variables.
    pub m: usize,
    /// The integrand q(t, y).
    pub q: QuadratureFn<'a>,
}

impl<S: OdeSystem + ?Sized> OdeSystem for WithQuadrature<'_, S> {
    fn dim(&self) -> usize {
        self.sys.dim()
    }
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.sys.rhs(t, y, dy)
    }
    fn has_jacobian(&self) -> bool {
        self.sys.has_jacobian()
    }
    fn jacobian(&self, t: f64, y: &[f64], jac: MatMut<'_, f64>) {
        self.sys.jacobian(t, y, jac)
    }
    fn jacobian_sparsity(&self) -> Option<Vec<Vec<usize>>> {
        self.sys.jacobian_sparsity()
    }
    fn kkt(&self) -> Option<&dyn KktSystem> {
        self.sys.kkt()
    }
    fn has_time_derivative(&self) -> bool {
        self.sys.has_time_derivative()
    }
    fn time_derivative(&self, t: f64, y: &[f64], dfdt: &mut [f64]) {
        self.sys.time_derivative(t, y, dfdt)
    }
    fn is_autonomous(&self) -> bool {
        self.sys.is_autonomous()
    }
    fn n_events(&self) -> usize {
        self.sys.n_events()
    }
    fn event_spec(&self, i: usize) -> EventSpec {
        self.sys.event_spec(i)
    }
    fn events(&self, t: f64, y: &[f64], g: &mut [f64]) {
        self.sys.events(t, y, g)
    }
    fn event_rates(&self, t: f64, y: &[f64], g: &mut [f64], g_dot: &mut [f64]) -> bool {
        self.sys.event_rates(t, y, g, g_dot)
    }
    fn check_accepted(
        &self,
        t_a: f64,
        y_a: &[f64],
        t_b: f64,
        y_b: &[f64],
    ) -> Result<(), Rejection> {
        self.sys.check_accepted(t_a, y_a, t_b, y_b)
    }
    fn on_event(&self, hit: &EventHit, y: &mut [f64]) -> EventAction {
        self.sys.on_event(hit, y)
    }
    fn n_quadratures(&self) -> usize {
        self.m
    }
    fn quadrature(&self, t: f64, y: &[f64], q: &mut [f64]) {
        (self.q)(t, y, q)
    }
}

/// The shape of a system's KKT form (crate::kkt's module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct KktShape {
    /// Number n_q of coordinates q (the state is y = (q, v), 2 n_q long).
    pub nq: usize,
    /// Number m of multipliers λ (constraint equations).
    pub m: usize,
    /// Number of triplets of K ([`KktSystem::kkt_assemble`]), for the memory check.
    pub k_entries: usize,
    /// For each column j < 2 n_q of R = ∂ρ/∂y, the rows (< n_q + m) where it may be nonzero.
    pub residual_pattern: Vec<Vec<usize>>,
    /// ε > 0 when the system's accelerations stay defined where K is singular (redundant
    /// constraints, singular configurations: the augmented Lagrangian, ε = 1/α): the `kkt`
    /// path then factors K_ε = [[M, Φ_qᵀ], [Φ_q, −εI]] (nonsingular when M is positive
    /// definite) and refines K z = b with it (crate::kkt). None: K itself is factored.
    pub regularisation: Option<f64>,
}

/// A second-order system whose accelerations solve a sparse linear system (crate::kkt's
/// module doc):
/// [`crate::OdeSystem::kkt`] gives it to the `kkt` linear algebra.
pub trait KktSystem {
    /// Its shape; the same at every call.
    fn kkt_shape(&self) -> KktShape;

    /// K(t, y) as (row, column, value) triplets into `k` (cleared first; duplicates are
    /// summed; the same rows and columns in the same order at every call: only the values
    /// change) and b(t, y) into `b` (length n_q + m). False when the system cannot evaluate
    /// at (t, y).
    fn kkt_assemble(
        &self,
        t: f64,
        y: &[f64],
        k: &mut Vec<(usize, usize, f64)>,
        b: &mut [f64],
    ) -> bool;

    /// R = ∂ρ/∂y at fixed `z` (ρ(y; z) = b(t, y) − K(t, y) z, crate::kkt) in closed form,
    /// into `r`: column by column over `pattern` (the shape's `residual_pattern`), each
    /// column's entries in its rows' order. False when the system has no closed form at
    /// (t, y) (`r` is then unspecified): the `kkt` path differences ρ over the pattern's
    /// colours instead. The default has none.
    fn kkt_residual_jacobian(
        &self,
        _t: f64,
        _y: &[f64],
        _z: &[f64],
        _pattern: &[Vec<usize>],
        _r: &mut [f64],
    ) -> bool {
        false
    }
}
