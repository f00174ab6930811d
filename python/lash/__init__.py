"""lash: ODE integrators for stiff contact problems, from Python.

lash is a Rust research solver for planar mechanisms with clearance joints. This package
runs its scenes from Python and gives its integrators to your own ODE with scipy's
interface:

- :func:`run` — a scene run as ``lash run`` runs it (same defaults, same numbers), the
  results in memory: :class:`Run` with ``summary`` (summary.json as a dict), ``columns``
  (trajectory.csv as numpy arrays), ``events`` (:class:`Event`), ``to_pandas()`` and
  ``animate()`` (:class:`Animation`: the mechanism moving, a page a notebook shows).
- :func:`sweep` — a sweep (``lash sweep``'s file, or a dict) run in process or on any
  executor (a process pool, a ``dask.distributed`` client, submitit's SLURM executor): one
  row per point in a pandas DataFrame, the points in the command's directory layout.
- :func:`solve_ivp` — scipy's ``solve_ivp`` with lash's methods (Rodas5P, BDF, TR-BDF2,
  ESDIRK3(4), the embedded pairs BS3(2), DP5(4), Tsit5(4), DOP853, fixed-step RK4), its
  Söderlind step-size controllers, and events with direction, terminal counts and hooks.
- :class:`OdeResult`, :class:`OdeSolution` — its result and continuous solution.
- :data:`METHODS`, :data:`CONTROLLERS` — the names lash accepts.
- Exceptions: :class:`UsageError` (bad arguments), :class:`SolveError` (the integration
  failed, with time and state), :class:`SceneError` (a scene that cannot be used, with its
  JSON path), :class:`OutOfMemoryError` (an implicit method's dense matrices over the memory
  budget; a :class:`MemoryError`), :class:`InternalError` (a bug), all derived from
  :class:`LashError`. An exception raised inside your own callback propagates as itself;
  Ctrl-C during :func:`run` raises :class:`KeyboardInterrupt`.

Example
-------
>>> import lash
>>> sol = lash.solve_ivp(lambda t, y: [-y[0]], (0, 1), [1.0], rtol=1e-10)
>>> abs(float(sol.y[0, -1]) - 0.36787944117144233) < 1e-9
True
"""

from ._errors import (InternalError, LashError, OutOfMemoryError, SceneError, SolveError,
                      UsageError)
from ._ivp import CONTROLLERS, METHODS, OdeResult, OdeSolution, solve_ivp
from ._lash import __version__
from ._run import Animation, Event, Run, run
from ._sweep import sweep

__all__ = [
    "run",
    "sweep",
    "Run",
    "Event",
    "Animation",
    "solve_ivp",
    "OdeResult",
    "OdeSolution",
    "METHODS",
    "CONTROLLERS",
    "LashError",
    "UsageError",
    "SolveError",
    "SceneError",
    "OutOfMemoryError",
    "InternalError",
    "__version__",
]
