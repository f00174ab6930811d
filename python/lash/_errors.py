"""The exceptions lash raises.

Every lash exception derives from :class:`LashError` (an :class:`Exception`): nothing lash
raises escapes ``except Exception``. An exception raised by your own code inside a callback
(``fun``, ``jac``, an event function or its hook) is not wrapped: it propagates as itself,
with its traceback, after lash has stopped the integration. Ctrl-C during :func:`lash.run`
raises Python's own :class:`KeyboardInterrupt`.
"""

from __future__ import annotations

__all__ = ["LashError", "UsageError", "SceneError", "SolveError", "OutOfMemoryError",
           "InternalError"]


class LashError(Exception):
    """Base class of the exceptions lash raises."""


class UsageError(LashError, ValueError):
    """A bad argument or option: an unknown method or controller name, a tolerance out of
    range, a malformed ``t_span``, ``y0``, ``t_eval``, ``atol`` or ``jac``, or a callback
    that returned an array of the wrong shape.

    Also a :class:`ValueError`, so code written for scipy that catches ``ValueError`` keeps
    working.
    """


class SceneError(LashError, ValueError):
    """A scene that cannot be used: the JSON path of the offending value and the reason.

    Parameters
    ----------
    path : str
        JSON path of the value in the notation of docs/scene-format.md ("Errors"), e.g.
        ``"joints[4].bearing.radius"``; ``"."`` is the document itself.
    reason : str
        Why the value is rejected.

    Attributes
    ----------
    path : str
        As given.
    reason : str
        As given.

    Examples
    --------
    >>> e = SceneError("joints[4].bearing.radius", "bearing radius must be > 0, got 0")
    >>> str(e)
    'joints[4].bearing.radius: bearing radius must be > 0, got 0'
    """

    def __init__(self, path: str, reason: str) -> None:
        super().__init__(f"{path}: {reason}")
        self.path = path
        self.reason = reason

    def __reduce__(self):
        return (type(self), (self.path, self.reason))


class SolveError(LashError, RuntimeError):
    """The integration failed: the step size fell below its floor, ``max_steps`` ran out,
    the state became non-finite (``fun`` returned NaN or inf, or the solution blew up) or
    the Newton iteration of an implicit method failed.

    Parameters
    ----------
    message : str
        What happened, with the time.
    t : float
        Time of the last good state.
    y : numpy.ndarray
        The last good state, shape (n,).
    kind : str
        ``"step_size_too_small"``, ``"too_many_steps"``, ``"non_finite_state"``,
        ``"rk4_unstable"`` (fixed-step RK4 beyond its stability limit, only where a scene
        asks for the check), ``"newton_failure"``, ``"budget_exhausted"``,
        ``"event_nan"`` (an event function returned NaN: the message names it),
        ``"law_out_of_range"`` (a mechanism left the range its contact laws hold in),
        ``"singular_configuration"`` (a mechanism reached a singular configuration) or
        ``"energy_balance"`` (a finished :func:`lash.run` whose energy balance is off by
        more than its accuracy allows; docs/outputs.md, "The energy check of a run").
    result : OdeResult or None
        What :func:`lash.solve_ivp` had computed up to the failure, with ``status = -1``,
        ``success = False`` and ``message`` (scipy's failed result).

    Attributes
    ----------
    t, y, kind, result
        As given.
    """

    def __init__(self, message: str, t: float, y, kind: str = "", result=None) -> None:
        super().__init__(message)
        self.t = t
        self.y = y
        self.kind = kind
        self.result = result

    def __reduce__(self):
        return (type(self), (self.args[0], self.t, self.y, self.kind, self.result))


class OutOfMemoryError(LashError, MemoryError):
    """Memory refused before it was allocated: the dense n × n matrices of an implicit method
    (its Jacobian and LU; 4 of them for ``bdf``, ``trbdf2``, ``esdirk34``, 3 for ``rodas5p``)
    need more than the budget, which is ``max_memory`` when given, else half of the memory
    available to the process (the smallest of /proc/meminfo's MemAvailable, the cgroup's
    memory limit and the address-space limit ``RLIMIT_AS``). Also raised when the allocator
    itself refused a matrix. Nothing was integrated. An explicit method (``dopri54``, ...)
    needs no such matrices.

    Also a :class:`MemoryError`.

    Parameters
    ----------
    message : str
        What needed how much, and the budget.
    needed : int
        Bytes needed.
    budget : int
        The budget in bytes (0 when the allocator refused).

    Attributes
    ----------
    needed, budget
        As given.
    """

    def __init__(self, message: str, needed: int = 0, budget: int = 0) -> None:
        super().__init__(message)
        self.needed = needed
        self.budget = budget

    def __reduce__(self):
        return (type(self), (self.args[0], self.needed, self.budget))


class InternalError(LashError, RuntimeError):
    """A bug in lash: an internal inconsistency (a Rust panic, caught where it would have
    left the extension). The message says where; please report it."""
