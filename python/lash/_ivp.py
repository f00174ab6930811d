"""``lash.solve_ivp``: lash's integrators for your own ODE, with scipy's interface."""

from __future__ import annotations

import math
import numbers
import warnings
from typing import Any, Callable, Iterable, Optional, Sequence, Union

import numpy as np

from . import _lash
from ._errors import SolveError, UsageError

__all__ = ["solve_ivp", "OdeResult", "OdeSolution", "METHODS", "CONTROLLERS"]

#: lash's method names, in the order the command lists them (docs/outputs.md).
METHODS: tuple = tuple(_lash.METHODS)
#: lash's step-size controller names (presets of one Söderlind filter, docs/outputs.md).
CONTROLLERS: tuple = tuple(_lash.CONTROLLERS)

# scipy's method names (and solver classes, by name) and the lash method each runs: RK45 is
# Dormand–Prince 5(4), RK23 Bogacki–Shampine 3(2), DOP853 Hairer's DOP853; scipy's BDF is a
# variable-order BDF/NDF, lash's bdf diffsol's variable-order BDF (orders 1-5). lash has no
# Radau IIA and no LSODA: Radau runs rodas5p (like Radau5 a stiffly accurate one-step method
# of order 5) and LSODA runs bdf (the stiff branch of LSODA). `OdeResult.method` names the
# lash method that ran.
_SCIPY_NAMES = {"rk45": "dopri54", "rk23": "bs32", "dop853": "dop853", "bdf": "bdf",
                "radau": "rodas5p", "lsoda": "bdf"}
_EXPLICIT = {"rk4", "bs32", "dopri54", "tsit54", "dop853"}
#: scipy's floor of rtol (100 ε): smaller values are raised to it, with scipy's warning.
_RTOL_FLOOR = 100 * np.finfo(float).eps
#: The largest whole number lash's counters hold (a 64-bit unsigned integer).
_WHOLE_MAX = 2 ** 64 - 1


class _EmptyArray(np.ndarray):
    """An empty array that is falsy, as scipy's empty lists are: ``OdeResult.t`` and ``y``
    when a terminal event came before the first time of ``t_eval`` (``not res.t`` holds, as
    code written for scipy tests it)."""

    def __bool__(self) -> bool:
        return False


def _empty(shape) -> np.ndarray:
    return np.empty(shape).view(_EmptyArray)

class OdeResult(dict):
    """The result of :func:`solve_ivp`: scipy's fields, as attributes and as dict items.

    Attributes
    ----------
    t : numpy.ndarray, shape (n_points,)
        Time points: every accepted step (with ``t_span[0]`` first), or ``t_eval``.
    y : numpy.ndarray, shape (n, n_points)
        The solution at ``t``.
    sol : OdeSolution or None
        The continuous solution when ``dense_output=True``, else None.
    t_events : list of numpy.ndarray or None
        For each event function, the times at which it occurred (None without events).
    y_events : list of numpy.ndarray or None
        For each event function, the states at those times, shape (n_occurrences, n)
        (before the event's hook, if it has one).
    nfev : int
        Evaluations of ``fun`` (finite-difference Jacobian columns included).
    njev : int
        Jacobian evaluations (by ``jac`` or by finite differences).
    nlu : int
        LU factorisations.
    status : int
        0: the end of ``t_span`` was reached; 1: a terminal event occurred; -1: the
        integration failed (only in :attr:`SolveError.result`: a failure raises).
    message : str
        Why the integration ended.
    success : bool
        ``status >= 0``.
    method : str
        lash's name of the method that ran.
    controller : str or None
        The step-size controller that ran (None for ``rk4`` and diffsol's methods).
    stats : dict
        All of lash's counters: ``steps`` (attempts), ``accepted``, ``rejected_error``,
        ``rejected_newton``, ``rhs_evals``, ``jac_evals``, ``lu_factorizations``,
        ``newton_iters``, ``event_evals``, ``events``, ``h_min_used``, ``h_max_used``, and the
        Python calls made, ``fun_calls`` and ``jac_calls``.
    """

    def __getattr__(self, name: str) -> Any:
        try:
            return self[name]
        except KeyError as e:
            raise AttributeError(name) from e

    __setattr__ = dict.__setitem__
    __delattr__ = dict.__delitem__

    def __dir__(self):
        return list(self.keys())

    def __repr__(self) -> str:
        if not self:
            return f"{type(self).__name__}()"
        width = max(map(len, self.keys())) + 1
        lines = []
        for k, v in self.items():
            text = repr(v).replace("\n", "\n" + " " * (width + 2))
            lines.append(f"{k.rjust(width)}: {text}")
        return "\n".join(lines)


class OdeSolution:
    """The continuous solution of :func:`solve_ivp` (``dense_output=True``): call it at a
    time or an array of times, like scipy's ``OdeSolution``.

    Each step's own interpolant (the method's dense output, the one that also gives the
    values at ``t_eval`` and locates events) is kept exactly: it is a polynomial of degree m
    in t (3 for ``rk4`` and ``bs32``, 4 for ``dopri54``, ``tsit54`` and ``rodas5p``, at
    most 7 for the others), stored by its values at the m + 1 Chebyshev–Lobatto points of the
    step and evaluated by the barycentric formula (Berrut & Trefethen, SIAM Review 46(3),
    2004), which is stable at every degree.

    Where an event hook changed the state, the solution jumps; at the event time itself it
    gives the state after the hook. Outside ``[t_min, t_max]`` it extrapolates the first or
    last step's polynomial, as scipy does.

    Attributes
    ----------
    ts : numpy.ndarray, shape (n_segments + 1,)
        Segment boundaries, in the direction of integration.
    t_min, t_max : float
        The interval covered.
    n_segments : int
        Number of steps (segments).
    """

    def __init__(self, t0s: np.ndarray, t1s: np.ndarray, nodes: np.ndarray,
                 values: np.ndarray, complex_n: Optional[int] = None) -> None:
        # complex_n: the solution of a complex ODE integrated as its real and imaginary
        # parts (2 complex_n real components); calls return complex values.
        self._complex_n = complex_n
        self._t0s = np.asarray(t0s, dtype=np.float64)
        self._t1s = np.asarray(t1s, dtype=np.float64)
        self._nodes = np.asarray(nodes, dtype=np.float64)
        m = len(self._nodes) - 1
        w = (-1.0) ** np.arange(m + 1)
        w[0] *= 0.5
        w[-1] *= 0.5
        self._weights = w
        self._values = np.asarray(values, dtype=np.float64)  # (segments, m + 1, n)
        self.n_segments = len(self._t0s)
        if self.n_segments == 0:
            raise UsageError("OdeSolution needs at least one step")
        self.ts = np.concatenate([self._t0s[:1], self._t1s])
        self.ascending = bool(self._t1s[0] > self._t0s[0])
        self.t_min = float(min(self.ts[0], self.ts[-1]))
        self.t_max = float(max(self.ts[0], self.ts[-1]))

    def __call__(self, t):
        """Evaluate the solution.

        Parameters
        ----------
        t : float or array_like with shape (k,)
            Time(s).

        Returns
        -------
        numpy.ndarray
            Shape (n,) for a scalar ``t``, (n, k) for an array.
        """
        t = np.asarray(t, dtype=np.float64)
        if t.ndim > 1:
            raise UsageError("t must be a scalar or 1-dimensional")
        tt = np.atleast_1d(t)
        if self.ascending:
            idx = np.searchsorted(self._t0s, tt, side="right") - 1
        else:
            idx = np.searchsorted(-self._t0s, -tt, side="right") - 1
        idx = np.clip(idx, 0, self.n_segments - 1)
        a = self._t0s[idx]
        b = self._t1s[idx]
        span = b - a
        # A segment of zero (or infinite) length is constant (t_span with t0 = t1, or an
        # empty y0): its value at the first node.
        ok = np.isfinite(span) & (span != 0)
        theta = np.where(ok, (tt - a) / np.where(ok, span, 1.0), 0.0)
        d = theta[:, None] - self._nodes[None, :]
        exact = d == 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            c = self._weights[None, :] / d
        hit = exact.any(axis=1)
        if hit.any():
            c[hit] = exact[hit].astype(np.float64)
        num = np.einsum("kj,kjn->kn", c, self._values[idx])
        y = num / c.sum(axis=1)[:, None]
        if self._complex_n is not None:
            k = self._complex_n
            y = y[:, :k] + 1j * y[:, k:]
        return y[0] if t.ndim == 0 else y.T

    def __repr__(self) -> str:
        return (f"OdeSolution(t in [{self.t_min:g}, {self.t_max:g}], "
                f"{self.n_segments} segments)")


def _floats(name: str, value, ndim: Optional[int] = None) -> np.ndarray:
    """value as a float64 array, or a UsageError naming the argument."""
    arr = np.asarray(value)
    if np.iscomplexobj(arr):
        raise UsageError(f"{name} must be real; complex values are not supported "
                         "(split them into real and imaginary parts)")
    try:
        arr = arr.astype(np.float64)
    except (TypeError, ValueError) as e:
        raise UsageError(f"{name} must be numbers: {e}") from None
    if ndim is not None and arr.ndim != ndim:
        raise UsageError(f"{name} must be {ndim}-dimensional, got shape {arr.shape}")
    return arr


def _method_name(method) -> str:
    if isinstance(method, type):
        # One of scipy's solver classes (scipy.integrate.RK45, ...), by its name.
        name = method.__name__.lower()
        if name in _SCIPY_NAMES and method.__module__.startswith("scipy."):
            return _SCIPY_NAMES[name]
        raise UsageError(f"method {method!r}: lash runs its own methods, not an OdeSolver "
                         "class; scipy's RK23, RK45, DOP853, Radau, BDF and LSODA are "
                         "accepted (mapped to bs32, dopri54, dop853, rodas5p, bdf, bdf)")
    if not isinstance(method, str):
        raise UsageError(f"method must be one of {', '.join(METHODS)} (a name) or one of "
                         f"scipy's solver classes, got {method!r}")
    m = method.lower()
    if m in METHODS:
        return m
    if m in _SCIPY_NAMES:
        return _SCIPY_NAMES[m]
    raise UsageError(f"unknown method {method!r}; lash's methods are {', '.join(METHODS)} "
                     "(and scipy's names RK45, RK23, DOP853, Radau, BDF, LSODA)")


def _controller_name(controller) -> Optional[str]:
    if controller is None:
        return None
    if not isinstance(controller, str) or controller.lower() not in CONTROLLERS:
        raise UsageError(f"unknown controller {controller!r}; lash's controllers are "
                         f"{', '.join(CONTROLLERS)}")
    return controller.lower()


def _event_decl(ev) -> tuple:
    if not callable(ev):
        raise UsageError(f"every event must be callable, got {ev!r}")
    terminal = getattr(ev, "terminal", None)
    # scipy's rule: None, False or 0: never; True: the first occurrence; an integer k > 0
    # (or a float equal to one): the k-th.
    if terminal is None:
        count = 0
    elif isinstance(terminal, (bool, np.bool_)):
        count = int(bool(terminal))
    elif (isinstance(terminal, numbers.Real) and math.isfinite(terminal) and terminal >= 0
          and int(terminal) == terminal):
        # A count beyond lash's counters is never reached: the same as the largest.
        count = min(int(terminal), _WHOLE_MAX)
    else:
        raise UsageError("The `terminal` attribute of each event must be a boolean or "
                         f"positive integer (event {getattr(ev, '__name__', ev)!r}: got "
                         f"{terminal!r}).")
    direction = getattr(ev, "direction", 0)
    try:
        direction = float(direction)
    except (TypeError, ValueError):
        raise UsageError(f"event {getattr(ev, '__name__', ev)!r}: direction must be a "
                         f"number, got {direction!r}") from None
    if math.isnan(direction):
        raise UsageError("event direction must not be NaN")
    sign = 1 if direction > 0 else (-1 if direction < 0 else 0)
    hook = getattr(ev, "hook", None)
    if hook is not None and not callable(hook):
        raise UsageError(f"event {getattr(ev, '__name__', ev)!r}: hook must be callable "
                         f"or None, got {hook!r}")
    return (ev, sign, count, hook)


def _whole(name: str, value) -> int:
    """A whole number in [1, 2**64 - 1], or a UsageError naming the argument."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
        raise UsageError(f"{name} must be an int >= 1, got {value!r}")
    if value > _WHOLE_MAX:
        raise UsageError(f"{name} must be at most 2**64 - 1, got {value!r}")
    return int(value)


def _array(raw: bytes, shape) -> np.ndarray:
    return np.frombuffer(raw, dtype=np.float64).reshape(shape)


def solve_ivp(
    fun: Callable[..., Any],
    t_span: Sequence[float],
    y0,
    method: Union[str, type] = "rodas5p",
    t_eval=None,
    dense_output: bool = False,
    events: Union[None, Callable[..., float], Iterable[Callable[..., float]]] = None,
    vectorized: bool = False,
    args: Optional[Iterable[Any]] = None,
    *,
    rtol=1e-6,
    atol=1e-9,
    jac=None,
    jac_sparsity=None,
    controller: Optional[str] = None,
    max_step: float = math.inf,
    first_step: Optional[float] = None,
    min_step: float = 0.0,
    max_steps: int = 1_000_000,
    step: Optional[float] = None,
    max_memory: Optional[int] = None,
) -> OdeResult:
    """Solve an initial value problem ``dy/dt = fun(t, y)``, ``y(t0) = y0``, with lash.

    scipy's :func:`scipy.integrate.solve_ivp` with lash's integrators: the Rosenbrock method
    Rodas5P (the default), diffsol's BDF, TR-BDF2 and ESDIRK3(4), the embedded explicit
    pairs Bogacki–Shampine 3(2), Dormand–Prince 5(4), Tsitouras 5(4) and DOP853, and
    classical RK4 with a fixed step; a choice of Söderlind step-size controllers; events
    located on each step's dense output, with an optional hook that changes the state and
    restarts the integration. Every argument scipy has means what it means in scipy, and
    the result has scipy's fields.

    Parameters
    ----------
    fun : callable
        Right-hand side ``fun(t, y, *args) -> array_like, shape (n,)``. ``t`` is a float,
        ``y`` a fresh float64 array of shape (n,) (yours to keep).
    t_span : 2-sequence of floats
        ``(t0, t1)``. ``t1 < t0`` integrates backwards; ``t1`` may be infinite (the run then
        ends at a terminal event). With ``t1 == t0`` nothing is integrated: the result holds
        ``y0`` at ``t0`` (and ``sol`` is constant), as in scipy.
    y0 : array_like, shape (n,)
        Initial state; every component finite. Complex values are integrated as the real
        system of their real and imaginary parts (2n components; ``fun`` and ``jac`` see
        complex ``y``, ``jac`` is assumed holomorphic as in scipy); the result is complex.
        An empty ``y0`` gives scipy's trivial result.
    method : str, optional
        One of lash's methods: ``"rodas5p"`` (default; Rosenbrock, order 5(4), stiffly
        accurate, Steinebach 2023), ``"bdf"``, ``"trbdf2"``, ``"esdirk34"`` (diffsol's
        implicit methods), ``"bs32"``, ``"dopri54"``, ``"tsit54"``, ``"dop853"`` (embedded
        explicit pairs) or ``"rk4"`` (fixed step: give ``step``). Case does not matter;
        scipy's names and solver classes are accepted too (``"RK45"`` or
        ``scipy.integrate.RK45`` = ``"dopri54"``, ``"RK23"`` = ``"bs32"``, ``"DOP853"``,
        ``"BDF"``); lash has no Radau IIA or LSODA, and runs ``"rodas5p"`` for ``"Radau"`` and
        ``"bdf"`` for ``"LSODA"`` (``OdeResult.method`` names the method that ran).
    t_eval : array_like or None, optional
        Times at which to store the solution, inside ``t_span`` and sorted in the direction
        of integration; taken from each step's dense output. None (default): every step.
    dense_output : bool, optional
        Whether to return the continuous solution as ``sol`` (:class:`OdeSolution`).
    events : callable, or list of callables, optional
        Event functions ``event(t, y, *args) -> float``; an event occurs where the value
        crosses zero. Attributes read from each function, as in scipy:

        - ``terminal`` (bool or int, default False): stop at the first occurrence (True),
          after the k-th (int k), or never (False or 0).
        - ``direction`` (float, default 0): only crossings from negative to positive (> 0),
          from positive to negative (< 0), or both (0), along the direction of integration.

        and one of lash:

        - ``hook`` (callable, optional): ``hook(t, y, *args)`` runs at each occurrence with
          the state there and returns the state to continue from (array_like, shape (n,)),
          or None to leave it unchanged: a bounce, an impact law, a switch. The integration
          restarts from it with a fresh first step.

        Events at ``t0`` itself are not reported; after each event the method restarts.
    vectorized : bool, optional
        As in scipy: ``fun`` takes ``y`` of shape (n, k) and returns (n, k). lash calls it
        with one state at a time, as a column of shape (n, 1), and ravels its result.
    args : tuple, optional
        Extra arguments passed to ``fun``, ``jac``, every event function and hook.
    rtol : float or array_like, shape (n,), optional
        Relative tolerance, below 1. Default 1e-6. Values below scipy's floor 100 ε are raised
        to it with scipy's warning. lash's error norm has one relative tolerance: an array
        is applied as its smallest entry. Not used by ``rk4``.
    atol : float or array_like, shape (n,), optional
        Absolute tolerance, each > 0. Default 1e-9. Not used by ``rk4``.
    jac : callable, array_like or None, optional
        Jacobian ``df/dy`` for the implicit methods: ``jac(t, y, *args) -> (n, n) array``,
        or a constant (n, n) matrix (``numpy`` or ``scipy.sparse``; a constant is never
        evaluated: ``njev`` stays 0). None (default): finite differences of ``fun`` (n calls
        of ``fun`` per Jacobian). Ignored by the explicit methods, with scipy's warning.
    jac_sparsity : array_like or scipy.sparse matrix, shape (n, n), optional
        Where ``jac`` is None: the entries of the Jacobian that may be nonzero. The
        finite-difference Jacobian then perturbs structurally independent columns together
        (a greedy colouring), one call of ``fun`` per colour instead of n.
    controller : str or None, optional
        Step-size controller of ``rodas5p`` and the explicit pairs: ``"i"``, ``"pi"``,
        ``"pid"``, ``"h211"``, ``"h312"`` or ``"gustafsson"`` (docs/outputs.md). None
        (default): ``"gustafsson"`` for ``rodas5p``, ``"pi"`` for the explicit pairs.
        ``rk4`` and diffsol's methods take none.
    max_step : float, optional
        Largest step size, > 0 (for diffsol's methods too). Default: unbounded.
    first_step : float or None, optional
        Initial step size (also after every event), > 0 and at most ``|t1 - t0|``. None
        (default): chosen by Hairer's starting-step algorithm.
    min_step : float, optional
        Smallest step size before the integration fails. Default 0 (then 16 ulps of t).
    max_steps : int, optional
        Step attempts before the integration fails, 1 to 2**64 - 1. Default 1 000 000.
    step : float or None, optional
        The fixed step of ``rk4`` (required for it, rejected by the other methods).
    max_memory : int or None, optional
        Budget in bytes of the implicit methods' dense n × n matrices (the Jacobian and its
        LU: 4 of them for ``bdf``, ``trbdf2`` and ``esdirk34``, 3 for ``rodas5p``, 8 bytes
        per entry); a problem that needs more raises :class:`OutOfMemoryError` before the
        first step. None (default): half of the memory available to the process (the
        smallest of MemAvailable, the cgroup's memory limit and ``RLIMIT_AS``). The explicit
        methods need no such matrices.

    Returns
    -------
    OdeResult
        A dict with attribute access: ``t``, ``y`` (shape (n, len(t))), ``sol``,
        ``t_events``, ``y_events``, ``nfev``, ``njev``, ``nlu``, ``status`` (0 or 1),
        ``message``, ``success``, and lash's ``method``, ``controller`` and ``stats``
        (see :class:`OdeResult`).

    Raises
    ------
    TypeError
        ``args`` that cannot be unpacked (scipy's message).
    UsageError
        A bad argument: unknown method or controller, tolerance out of range or NaN,
        malformed ``t_span``, ``y0``, ``t_eval``, ``atol`` or ``jac`` (NaN in any of them
        included), an integer option beyond 2**64 - 1, or a callback that returned the wrong
        shape. Also a ``ValueError``.
    OutOfMemoryError
        The method's dense matrices need more than ``max_memory`` (a :class:`MemoryError`).
    SolveError
        The integration failed (step size too small, ``max_steps`` reached, non-finite
        state, Newton failure, an event function that returned NaN: kind ``"event_nan"``,
        the message names the function). ``.t`` and ``.y`` are the last good time and state,
        ``.kind`` names the failure and ``.result`` holds everything computed up to it, with
        scipy's ``status = -1`` and ``success = False``. scipy returns such a result
        instead of raising; lash raises so that a failed run is never taken for a good one.
    Exception
        An exception raised inside ``fun``, ``jac``, an event function or a hook stops the
        integration and propagates unchanged.

    Notes
    -----
    The callbacks are Python functions called from Rust with the GIL held, one call per
    evaluation. Each call of ``fun`` costs, besides the time of ``fun`` itself, the creation
    of the array ``y`` and the reading of the result: under a microsecond, a list or tuple
    result being the cheapest, 5-10 times less than scipy's own step loop per call
    (measured in BENCHMARKS.md, "Python", with python/bench/callbacks.py). For an RHS
    written in Python the run time is about ``nfev`` times (the time of ``fun`` plus that
    cost): choose the method that needs the fewest evaluations (``stats`` has the counts).

    With events, each occurrence cuts the step and restarts the method, so ``t`` (without
    ``t_eval``) contains every event time. When a hook changes the state, ``t`` contains the
    event time twice: the state before the hook, then after it.

    Examples
    --------
    Van der Pol's oscillator with μ = 1000, a stiff problem, with the default method:

    >>> import lash
    >>> def vdp(t, y, mu):
    ...     return [y[1], mu * (1 - y[0] ** 2) * y[1] - y[0]]
    >>> sol = lash.solve_ivp(vdp, (0, 2000), [2, 0], args=(1000,), rtol=1e-8, atol=1e-11)
    >>> sol.status, round(float(sol.y[0, -1]), 6)
    (0, 1.706168)

    A falling ball that stops when it hits the ground (``terminal``) and one that bounces
    (``hook``):

    >>> def ground(t, y):
    ...     return y[0]
    >>> ground.terminal = True
    >>> ground.direction = -1
    >>> sol = lash.solve_ivp(lambda t, y: [y[1], -9.81], (0, 10), [1, 0], events=ground)
    >>> round(float(sol.t_events[0][0]), 6)   # sqrt(2 / 9.81)
    0.451524
    """
    method = _method_name(method)
    controller = _controller_name(controller)
    if not callable(fun):
        raise UsageError(f"fun must be callable, got {fun!r}")
    try:
        t0, t1 = (float(v) for v in t_span)
    except (TypeError, ValueError):
        raise UsageError(f"t_span must be two numbers (t0, t1), got {t_span!r}") from None
    if not math.isfinite(t0) or math.isnan(t1):
        raise UsageError(f"t_span must be (t0, t1) with t0 finite, got {t_span!r}")
    if args is not None:
        try:
            args = tuple(args)
        except TypeError as e:
            # scipy's exception and wording.
            raise TypeError("Supplied 'args' cannot be unpacked. Please supply `args` as a "
                            f"tuple (e.g. `args=({args},)`)") from e
    else:
        args = ()
    y0 = np.asarray(y0)
    is_complex = np.iscomplexobj(y0)
    y0 = _floats("y0", y0.real, ndim=1) + 1j * _floats("y0", y0.imag, ndim=1) \
        if is_complex else _floats("y0", y0, ndim=1)
    if not np.isfinite(y0).all():
        raise UsageError("All components of the initial state `y0` must be finite.")
    n = y0.shape[0]
    direction = 1.0 if t1 >= t0 else -1.0

    rtol = _floats("rtol", rtol)
    if rtol.ndim > 0 and rtol.shape != (n,):
        raise UsageError(f"`rtol` has wrong shape: {rtol.shape}, expected ({n},) or a number.")
    if not np.isfinite(rtol).all():
        raise UsageError(f"rtol must be finite (in [1e-14, 1)), got {rtol}")
    if np.any(rtol < _RTOL_FLOOR):
        warnings.warn("At least one element of `rtol` is too small. "
                      f"Setting `rtol = np.maximum(rtol, {_RTOL_FLOOR})`.", stacklevel=2)
        rtol = np.maximum(rtol, _RTOL_FLOOR)
    # lash's error norm has one rtol: an array is applied as its smallest entry.
    rtol = float(rtol.min()) if rtol.size else _RTOL_FLOOR
    atol_arr = _floats("atol", atol)
    if atol_arr.ndim == 0:
        atol_arr = atol_arr.reshape(1)
    elif atol_arr.shape != (n,):
        raise UsageError(f"`atol` has wrong shape: {atol_arr.shape}, expected ({n},) or a "
                         "number.")
    if not np.isfinite(atol_arr).all():
        raise UsageError(f"atol must be finite and > 0, got {atol_arr}")

    t_eval_arr = None
    if t_eval is not None:
        te = _floats("t_eval", t_eval)
        if te.ndim != 1:
            raise UsageError("`t_eval` must be 1-dimensional.")
        if not np.isfinite(te).all():
            bad = int(np.flatnonzero(~np.isfinite(te))[0])
            raise UsageError(f"Values in `t_eval` must be finite: t_eval[{bad}] = {te[bad]}")
        lo, hi = min(t0, t1), max(t0, t1)
        if te.size and (te.min() < lo or te.max() > hi):
            raise UsageError("Values in `t_eval` are not within `t_span`.")
        if np.any(direction * np.diff(te) < 0):
            raise UsageError("Values in `t_eval` are not properly sorted.")
        t_eval_arr = te
    if events is None:
        ev_list = []
    elif callable(events):
        ev_list = [events]
    else:
        ev_list = list(events)
    decls = [_event_decl(ev) for ev in ev_list]

    if max_step is None:
        max_step = math.inf
    max_step = float(max_step)
    if not max_step > 0:
        raise UsageError("`max_step` must be positive.")
    if first_step is not None:
        first_step = float(first_step)
        if not first_step > 0:
            raise UsageError("`first_step` must be positive.")
        if first_step > abs(t1 - t0):
            raise UsageError("`first_step` exceeds bounds.")
    min_step = float(min_step)
    if not (math.isfinite(min_step) and min_step >= 0):
        raise UsageError(f"min_step must be finite and >= 0, got {min_step}")
    if step is not None:
        step = float(step)
        if not (math.isfinite(step) and step > 0):
            raise UsageError(f"step must be finite and > 0, got {step}")
    max_steps = _whole("max_steps", max_steps)
    if max_memory is not None:
        max_memory = _whole("max_memory", max_memory)

    extraneous = []
    jac_fun, jac_matrix = None, None
    if jac is not None:
        if method in _EXPLICIT:
            extraneous.append("jac")
        elif callable(jac):
            jac_fun = jac
        else:
            jac_matrix = _matrix("jac", jac, n)
    sparsity = None
    if jac_sparsity is not None:
        if method in _EXPLICIT:
            extraneous.append("jac_sparsity")
        elif jac is None:
            sparsity = _pattern(jac_sparsity, n)
    if extraneous:
        # scipy's warning, word for word (code written for scipy filters it by its text).
        warnings.warn("The following arguments have no effect for a chosen solver: "
                      f"{', '.join(f'`{x}`' for x in extraneous)}.", stacklevel=2)

    if is_complex:
        fun, jac_fun, jac_matrix, decls, y0, atol_arr, sparsity = _as_real(
            n, fun, jac_fun, jac_matrix, decls, y0, atol_arr, sparsity)
    m = 2 * n if is_complex else n

    if n == 0 or t0 == t1:
        return _no_integration(t0, t1, y0, m, n if is_complex else None, t_eval_arr,
                               dense_output, decls, method, controller)

    raw = _lash.solve_ivp_core(fun, dict(
        t0=t0, t1=t1, y0=y0.tobytes(), method=method,
        t_eval=None if t_eval_arr is None else t_eval_arr.tobytes(),
        dense_output=bool(dense_output), events=decls, rtol=rtol,
        atol=atol_arr.tobytes(), jac=jac_fun,
        jac_matrix=None if jac_matrix is None else jac_matrix.tobytes(),
        jac_sparsity=sparsity, vectorized=bool(vectorized), controller=controller,
        max_step=max_step, first_step=first_step, min_step=min_step,
        max_steps=max_steps, step=step, max_memory=max_memory, args=list(args)))

    t = _array(raw["t"], (-1,))
    y = _array(raw["y"], (len(t), m)).T
    if t_eval_arr is not None and len(t) == 0:
        t, y = _empty((0,)), _empty((n, 0))
    elif is_complex:
        y = y[:n] + 1j * y[n:]
    sol = None
    if raw["dense"] is not None:
        nodes, t0s, t1s, values = raw["dense"]
        t0s = _array(t0s, (-1,))
        if len(t0s):
            sol = OdeSolution(t0s, _array(t1s, (-1,)), _array(nodes, (-1,)),
                              _array(values, (len(t0s), -1, m)),
                              complex_n=n if is_complex else None)
    t_events = y_events = None
    if decls:
        t_events = [_array(te, (-1,)) for te in raw["t_events"]]
        y_events = [_event_states(_array(ye, (-1, m)), n if is_complex else None)
                    for ye in raw["y_events"]]
    stats = dict(raw["stats"])
    status = raw["status"]
    result = OdeResult(
        t=t, y=y, sol=sol, t_events=t_events, y_events=y_events,
        nfev=stats["rhs_evals"], njev=raw["njev"], nlu=stats["lu_factorizations"],
        status=status, message=raw["message"], success=status >= 0,
        method=method, controller=raw["controller"], stats=stats)
    if raw["failure"] is not None:
        kind, message, t_fail, y_fail = raw["failure"]
        y_fail = _array(y_fail, (m,))
        if is_complex:
            y_fail = y_fail[:n] + 1j * y_fail[n:]
        raise SolveError(message, t_fail, y_fail, kind, result)
    return result


def _matrix(name: str, value, n: int) -> np.ndarray:
    """A constant (n, n) matrix (dense or scipy.sparse) as float64 or complex128."""
    if hasattr(value, "toarray"):
        value = value.toarray()
    arr = np.asarray(value)
    if np.iscomplexobj(arr):
        arr = arr.astype(np.complex128)
    else:
        arr = _floats(name, arr)
    if arr.shape != (n, n):
        raise UsageError(f"{name} must have shape ({n}, {n}), got {arr.shape}")
    return arr


def _pattern(value, n: int) -> tuple:
    """scipy's jac_sparsity (an (n, n) array_like or scipy.sparse matrix, nonzero where
    df_i/dy_j may be nonzero) as the lists (rows, columns) of its nonzero entries."""
    if hasattr(value, "tocoo"):
        coo = value.tocoo()
        if coo.shape != (n, n):
            raise UsageError(f"`jac_sparsity` must have shape ({n}, {n}), got {coo.shape}")
        keep = np.asarray(coo.data) != 0
        rows, cols = np.asarray(coo.row)[keep], np.asarray(coo.col)[keep]
    else:
        arr = np.asarray(value)
        if arr.shape != (n, n):
            raise UsageError(f"`jac_sparsity` must have shape ({n}, {n}), got {arr.shape}")
        rows, cols = np.nonzero(arr)
    return ([int(i) for i in rows], [int(j) for j in cols])


def _as_real(n, fun, jac_fun, jac_matrix, decls, y0, atol, sparsity):
    """A complex ODE z' = f(t, z) as the real one of its real and imaginary parts,
    y = (Re z, Im z): f as (Re f, Im f); a complex Jacobian J (f holomorphic, as scipy
    assumes) as [[Re J, -Im J], [Im J, Re J]]; event functions and hooks see z."""

    def z_of(y):
        return y[:n] + 1j * y[n:]

    def fun_real(t, y, *a):
        f = np.asarray(fun(t, z_of(y), *a), dtype=np.complex128)
        return np.concatenate([f.real, f.imag])

    def real_block(J):
        if hasattr(J, "toarray"):
            J = J.toarray()
        J = np.asarray(J, dtype=np.complex128).reshape(n, n)
        return np.block([[J.real, -J.imag], [J.imag, J.real]])

    jac_real = None
    if jac_fun is not None:
        def jac_real(t, y, *a):
            return real_block(jac_fun(t, z_of(y), *a))
    if jac_matrix is not None:
        jac_matrix = real_block(jac_matrix)

    def real_event(decl):
        ev, sign, count, hook = decl

        def g(t, y, *a):
            return ev(t, z_of(y), *a)

        hook_real = None
        if hook is not None:
            def hook_real(t, y, *a):
                z = hook(t, z_of(y), *a)
                if z is None:
                    return None
                z = np.asarray(z, dtype=np.complex128)
                return np.concatenate([z.real, z.imag])
        return (g, sign, count, hook_real)

    if sparsity is not None:
        rows, cols = sparsity
        # Each complex entry (i, j) couples both parts of z_i with both parts of z_j.
        rows_r, cols_r = [], []
        for i, j in zip(rows, cols):
            for di in (0, n):
                for dj in (0, n):
                    rows_r.append(i + di)
                    cols_r.append(j + dj)
        sparsity = (rows_r, cols_r)
    y_real = np.concatenate([y0.real, y0.imag])
    atol_real = atol if atol.size == 1 else np.concatenate([atol, atol])
    return (fun_real, jac_real, jac_matrix, [real_event(d) for d in decls], y_real,
            atol_real, sparsity)


def _event_states(ye: np.ndarray, complex_n: Optional[int]) -> np.ndarray:
    """The states at one event function's occurrences, shape (k, n); scipy's (0,) when it
    never occurred."""
    if len(ye) == 0:
        return np.empty((0,))
    if complex_n is not None:
        return ye[:, :complex_n] + 1j * ye[:, complex_n:]
    return ye


def _no_integration(t0, t1, y0, m, complex_n, t_eval, dense_output, decls, method,
                    controller) -> OdeResult:
    """scipy's result where there is nothing to integrate: t0 = t1 (the state stays y0), or
    an empty y0 (the solver reaches t1 at once). The solution is constant."""
    n = complex_n if complex_n is not None else m
    t_end = t0 if t0 == t1 else t1
    if t_eval is None:
        t = np.array([t0] if t0 == t1 else [t0, t_end])
    else:
        t = t_eval.copy()
    y = np.repeat(y0.reshape(-1, 1), len(t), axis=1)
    if complex_n is not None:
        y = y[:n] + 1j * y[n:]
    sol = None
    if dense_output:
        sol = OdeSolution(np.array([t0]), np.array([t_end]), np.zeros(1),
                          y0.reshape(1, 1, m), complex_n=complex_n)
    stats = {k: 0 for k in ("steps", "accepted", "rejected_error", "rejected_newton",
                            "rhs_evals", "jac_evals", "lu_factorizations", "newton_iters",
                            "event_evals", "events", "fun_calls", "jac_calls")}
    stats["h_min_used"] = stats["h_max_used"] = 0.0
    t_events = [np.empty((0,)) for _ in decls] if decls else None
    y_events = [np.empty((0,)) for _ in decls] if decls else None
    return OdeResult(
        t=t, y=y, sol=sol, t_events=t_events, y_events=y_events, nfev=0, njev=0, nlu=0,
        status=0, message="The solver successfully reached the end of the integration "
        "interval.", success=True, method=method,
        controller=controller if controller is not None else dict(
            _lash.DEFAULT_CONTROLLERS)[method], stats=stats)
