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

# scipy's names of the methods lash has too: RK45 is Dormand–Prince 5(4), RK23 is
# Bogacki–Shampine 3(2), DOP853 is Hairer's DOP853; scipy's BDF is a variable-order
# BDF/NDF, lash's bdf diffsol's variable-order BDF (orders 1-5).
_SCIPY_NAMES = {"rk45": "dopri54", "rk23": "bs32", "dop853": "dop853", "bdf": "bdf"}
_EXPLICIT = {"rk4", "bs32", "dopri54", "tsit54", "dop853"}

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
                 values: np.ndarray) -> None:
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
        theta = (tt - a) / (b - a)
        d = theta[:, None] - self._nodes[None, :]
        exact = d == 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            c = self._weights[None, :] / d
        hit = exact.any(axis=1)
        if hit.any():
            c[hit] = exact[hit].astype(np.float64)
        num = np.einsum("kj,kjn->kn", c, self._values[idx])
        y = num / c.sum(axis=1)[:, None]
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
    if not isinstance(method, str):
        raise UsageError(f"method must be one of {', '.join(METHODS)} (a name), "
                         f"got {method!r}")
    m = method.lower()
    if m in METHODS:
        return m
    if m in _SCIPY_NAMES:
        return _SCIPY_NAMES[m]
    if m in ("radau", "lsoda"):
        raise UsageError(f"lash has no {method} method; for stiff problems use 'rodas5p' "
                         "(Rosenbrock, order 5), 'bdf', 'esdirk34' or 'trbdf2'")
    raise UsageError(f"unknown method {method!r}; lash's methods are {', '.join(METHODS)} "
                     "(and scipy's names RK45, RK23, DOP853, BDF)")


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
    terminal = getattr(ev, "terminal", False)
    if isinstance(terminal, (bool, np.bool_)):
        count = 1 if terminal else 0
    elif isinstance(terminal, numbers.Integral) and terminal >= 0:
        count = int(terminal)
    else:
        raise UsageError(f"event {getattr(ev, '__name__', ev)!r}: terminal must be a bool "
                         f"or an int >= 0, got {terminal!r}")
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


def _array(raw: bytes, shape) -> np.ndarray:
    return np.frombuffer(raw, dtype=np.float64).reshape(shape)


def solve_ivp(
    fun: Callable[..., Any],
    t_span: Sequence[float],
    y0,
    method: str = "rodas5p",
    t_eval=None,
    dense_output: bool = False,
    events: Union[None, Callable[..., float], Iterable[Callable[..., float]]] = None,
    vectorized: bool = False,
    args: Optional[Iterable[Any]] = None,
    *,
    rtol: float = 1e-6,
    atol=1e-9,
    jac=None,
    controller: Optional[str] = None,
    max_step: float = math.inf,
    first_step: Optional[float] = None,
    min_step: float = 0.0,
    max_steps: int = 1_000_000,
    step: Optional[float] = None,
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
        ``(t0, t1)``. ``t1 < t0`` integrates backwards.
    y0 : array_like, shape (n,)
        Initial state (real; complex is not supported).
    method : str, optional
        One of lash's methods: ``"rodas5p"`` (default; Rosenbrock, order 5(4), stiffly
        accurate, Steinebach 2023), ``"bdf"``, ``"trbdf2"``, ``"esdirk34"`` (diffsol's
        implicit methods), ``"bs32"``, ``"dopri54"``, ``"tsit54"``, ``"dop853"`` (embedded
        explicit pairs) or ``"rk4"`` (fixed step: give ``step``). Case does not matter;
        scipy's names of the same methods are accepted too (``"RK45"`` = ``"dopri54"``,
        ``"RK23"`` = ``"bs32"``, ``"DOP853"``, ``"BDF"``). There is no Radau or LSODA.
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
        Accepted for compatibility with scipy and not used: ``fun`` is always called with
        one state.
    args : tuple, optional
        Extra arguments passed to ``fun``, ``jac``, every event function and hook.
    rtol : float, optional
        Relative tolerance, in [1e-14, 1). Default 1e-6. Not used by ``rk4``.
    atol : float or array_like, shape (n,), optional
        Absolute tolerance, each > 0. Default 1e-9. Not used by ``rk4``.
    jac : callable, array_like or None, optional
        Jacobian ``df/dy`` for the implicit methods: ``jac(t, y, *args) -> (n, n) array``,
        or a constant (n, n) matrix. None (default): finite differences of ``fun`` (n calls
        of ``fun`` per Jacobian). Ignored, with a warning, by the explicit methods.
    controller : str or None, optional
        Step-size controller of ``rodas5p`` and the explicit pairs: ``"i"``, ``"pi"``,
        ``"pid"``, ``"h211"``, ``"h312"`` or ``"gustafsson"`` (docs/outputs.md). None
        (default): ``"gustafsson"`` for ``rodas5p``, ``"pi"`` for the explicit pairs.
        ``rk4`` and diffsol's methods take none.
    max_step : float, optional
        Largest step size. Default: unbounded.
    first_step : float or None, optional
        Initial step size (also after every event). None (default): chosen by Hairer's
        starting-step algorithm.
    min_step : float, optional
        Smallest step size before the integration fails. Default 0 (then 16 ulps of t).
    max_steps : int, optional
        Step attempts before the integration fails. Default 1 000 000.
    step : float or None, optional
        The fixed step of ``rk4`` (required for it, rejected by the other methods).

    Returns
    -------
    OdeResult
        A dict with attribute access: ``t``, ``y`` (shape (n, len(t))), ``sol``,
        ``t_events``, ``y_events``, ``nfev``, ``njev``, ``nlu``, ``status`` (0 or 1),
        ``message``, ``success``, and lash's ``method``, ``controller`` and ``stats``
        (see :class:`OdeResult`).

    Raises
    ------
    UsageError
        A bad argument: unknown method or controller, tolerance out of range, malformed
        ``t_span``, ``y0``, ``t_eval``, ``atol`` or ``jac``, or a callback that returned the
        wrong shape. Also a ``ValueError``.
    SolveError
        The integration failed (step size too small, ``max_steps`` reached, non-finite
        state, Newton failure). ``.t`` and ``.y`` are the last good time and state,
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
    of the array ``y`` and the reading of the result: a few microseconds, a list or tuple
    result being the cheapest, an order of magnitude less than scipy's own step loop per
    call (measured in BENCHMARKS.md, "Python", with python/bench/callbacks.py). For an RHS
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
    if not (math.isfinite(t0) and math.isfinite(t1)) or t0 == t1:
        raise UsageError(f"t_span must be two different finite times, got {t_span!r}")
    y0 = _floats("y0", y0, ndim=1)
    n = y0.shape[0]
    if n == 0:
        raise UsageError("y0 must have at least one component")
    atol_arr = _floats("atol", atol)
    if atol_arr.ndim == 0:
        atol_arr = atol_arr.reshape(1)
    elif atol_arr.shape != (n,):
        raise UsageError(f"atol must be a number or have shape ({n},), got shape "
                         f"{atol_arr.shape}")
    direction = 1.0 if t1 > t0 else -1.0
    t_eval_bytes = None
    if t_eval is not None:
        te = _floats("t_eval", t_eval, ndim=1)
        lo, hi = min(t0, t1), max(t0, t1)
        if te.size and (te.min() < lo or te.max() > hi):
            raise UsageError("Values in t_eval are not within t_span.")
        if np.any(direction * np.diff(te) < 0):
            raise UsageError("Values in t_eval are not properly sorted.")
        t_eval_bytes = te.tobytes()
    if args is not None:
        try:
            args = tuple(args)
        except TypeError:
            raise UsageError(f"args must be a tuple, e.g. args=({args!r},)") from None
    else:
        args = ()
    if events is None:
        ev_list = []
    elif callable(events):
        ev_list = [events]
    else:
        ev_list = list(events)
    decls = [_event_decl(ev) for ev in ev_list]
    jac_fun, jac_bytes = None, None
    if jac is not None:
        if method in _EXPLICIT:
            warnings.warn(f"jac has no effect with the explicit method {method}",
                          stacklevel=2)
        elif callable(jac):
            jac_fun = jac
        else:
            if hasattr(jac, "toarray"):
                jac = jac.toarray()
            jm = _floats("jac", jac)
            if jm.shape != (n, n):
                raise UsageError(f"jac must have shape ({n}, {n}), got {jm.shape}")
            jac_bytes = jm.tobytes()
    if step is not None:
        step = float(step)
    if first_step is not None:
        first_step = float(first_step)
    if not isinstance(max_steps, numbers.Integral) or max_steps < 1:
        raise UsageError(f"max_steps must be an int >= 1, got {max_steps!r}")

    raw = _lash.solve_ivp_core(
        fun, t0, t1, y0.tobytes(), method, t_eval_bytes, bool(dense_output), decls,
        float(rtol), atol_arr.tobytes(), jac_fun, jac_bytes, controller, float(max_step),
        first_step, float(min_step), int(max_steps), step, list(args))

    t = _array(raw["t"], (-1,))
    y = _array(raw["y"], (len(t), n)).T
    sol = None
    if raw["dense"] is not None:
        nodes, t0s, t1s, values = raw["dense"]
        t0s = _array(t0s, (-1,))
        if len(t0s):
            sol = OdeSolution(t0s, _array(t1s, (-1,)), _array(nodes, (-1,)),
                              _array(values, (len(t0s), -1, n)))
    t_events = y_events = None
    if decls:
        t_events = [_array(te, (-1,)) for te in raw["t_events"]]
        y_events = [_array(ye, (-1, n)) for ye in raw["y_events"]]
    stats = dict(raw["stats"])
    status = raw["status"]
    result = OdeResult(
        t=t, y=y, sol=sol, t_events=t_events, y_events=y_events,
        nfev=stats["rhs_evals"], njev=stats["jac_evals"], nlu=stats["lu_factorizations"],
        status=status, message=raw["message"], success=status >= 0,
        method=method, controller=raw["controller"], stats=stats)
    if raw["failure"] is not None:
        kind, message, t_fail, y_fail = raw["failure"]
        raise SolveError(message, t_fail, _array(y_fail, (n,)), kind, result)
    return result
