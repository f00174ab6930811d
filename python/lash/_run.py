"""``lash.run``: a scene run by lash's engine, as ``lash run`` runs it, results in memory."""

from __future__ import annotations

import html
import json
import math
import numbers
import os
from typing import Any, Dict, List, NamedTuple, Optional, Sequence, Union

import numpy as np

from . import _lash
from ._errors import UsageError

__all__ = ["run", "Run", "Event", "Animation"]


class Event(NamedTuple):
    """An event of a scene run.

    Attributes
    ----------
    time : float
        When it happened, s (located on the dense output for adaptive methods; for the
        fixed-step RK4, which runs without event location, the crossing between two step ends
        by linear interpolation, as ``lash run`` counts it).
    name : str
        The joint it concerns (a clearance joint's, or a prismatic clearance joint's name).
    kind : str
        ``"contact_onset"`` / ``"contact_loss"`` (the penetration δ of a clearance joint
        crossing zero upwards / downwards), ``"eps_cap_reached"`` / ``"eps_cap_left"`` (the
        eccentricity ratio of a lubricated joint crossing the film's cap ε_cap),
        ``"corner_contact_onset"`` / ``"corner_contact_loss"`` (a corner of a prismatic
        clearance joint), docs/model.md §7; with kink events (the scene's ``"kink_events"``,
        by default on for a dry revolute clearance joint whose laws have kinks, off for
        ``rk4``; ``summary["kink_events"]`` says) also ``"kink_full_damping_rising"`` …
        (``kink_full_damping``, ``kink_force_clip``, ``kink_slip_v0``, ``kink_slip_v1``, each
        ``_rising`` / ``_falling``).
    """

    time: float
    name: str
    kind: str


class Run:
    """The result of :func:`run`: what ``lash run`` writes, in memory.

    Attributes
    ----------
    summary : dict
        Exactly the content of summary.json (docs/outputs.md, "summary.json"): version,
        case, scene_sha256, method, controller, rtol, atol, step, t_end, stats, wall_time_s,
        events, metrics, final_state, reference_error.
    columns : dict of str to numpy.ndarray
        Each column of trajectory.csv, in the file's order (``t``, ``crank_angle``,
        ``slider_x``, …, then the scene's ``<body>.x``, … columns; ``y0``, ``y1``, … for a
        built-in test problem), as a float64 array with one value per row. A column whose
        role the scene lacks is empty in the CSV and NaN here.
    events : list of Event
        Every event of the run, in time order: ``(time, name, kind)``.
    engine_time_s : float
        Wall time of the engine's part of the call (reading the scene, the run with its
        outputs and metrics), s, without Python: ``summary["wall_time_s"]`` is the
        integration's alone. BENCHMARKS.md ("Python") compares both with the whole call.
    scene : str or None
        The scene's JSON text as it ran (what ``lash run`` keeps as scene.json); None for a
        built-in test problem.
    """

    def __init__(self, summary: Dict[str, Any], columns: Dict[str, np.ndarray],
                 events: List[Event], engine_time_s: float = math.nan,
                 scene: Optional[str] = None) -> None:
        self.summary = summary
        self.columns = columns
        self.events = events
        self.engine_time_s = engine_time_s
        self.scene = scene

    def animate(self, trace: Optional[str] = None, column: Optional[str] = None,
                max_frames: Optional[int] = None) -> "Animation":
        """The run as the page ``lash animate`` writes (docs/outputs.md, "lash animate
        RUN_DIR"): the mechanism moving, each clearance joint's journal magnified in its
        bearing with its forces as arrows, the path of a point, a time-series panel; one
        self-contained HTML text, nothing fetched. In a notebook the returned
        :class:`Animation` shows itself (``_repr_html_``); ``.save(path)`` writes the page.

        Parameters
        ----------
        trace : str, optional
            ``BODY.POINT`` or ``BODY`` (its centre of mass): the point whose path is drawn.
            Default: the centre of mass of the body carrying the clearance joint's journal.
        column : str, optional
            The column the time-series panel shows first. Default: ``contact_force``, else
            ``slider_a``, else the first body's angle.
        max_frames : int, optional
            Most frames (>= 2; default 2500): rows are decimated to at most this.

        Raises
        ------
        UsageError
            A built-in test problem (no mechanism), an unknown trace point or column, a bad
            ``max_frames``.
        SceneError
            The columns do not fit the scene.
        """
        if self.scene is None:
            raise UsageError("Run.animate needs a scene: a built-in test problem has no "
                             "mechanism to draw")
        for name, value in (("trace", trace), ("column", column)):
            if value is not None and not isinstance(value, str):
                raise UsageError(f"{name} must be a string, got {value!r}")
        max_frames = _whole("max_frames", max_frames, 2)
        names = list(self.columns)
        rows = len(self.columns["t"])
        data = b"".join(np.ascontiguousarray(self.columns[n], dtype=np.float64).tobytes()
                        for n in names)
        page = _lash.animation_html(self.scene, names, data, rows, _title(self.summary),
                                    trace, column, max_frames)
        return Animation(page)

    def to_pandas(self):
        """The trajectory as a :class:`pandas.DataFrame`, one column per trajectory.csv
        column (NaN where the CSV has empty cells): what ``pandas.read_csv`` makes of the
        file. Needs pandas (``pip install pandas``); raises ImportError without it."""
        try:
            import pandas as pd
        except ImportError as e:
            raise ImportError("Run.to_pandas needs pandas: pip install pandas") from e
        return pd.DataFrame(self.columns, copy=False)

    def __repr__(self) -> str:
        s = self.summary
        rows = len(self.columns.get("t", ()))
        return (f"Run(case={s.get('case')!r}, method={s.get('method')!r}, "
                f"t_end={s.get('t_end')!r}, rows={rows}, events={len(self.events)})")


def _short(x: float) -> str:
    """``1e-8``, ``2.5e-4``: a number as the engine's title writes it."""
    m, e = f"{x:e}".split("e")
    return f"{m.rstrip('0').rstrip('.')}e{int(e)}"


def _title(summary: Dict[str, Any]) -> str:
    """The page's heading: case, method and setting (as ``lash animate`` heads it)."""
    title = str(summary.get("case") or "run")
    method, rtol, step = summary.get("method"), summary.get("rtol"), summary.get("step")
    if method and isinstance(rtol, (int, float)):
        title += f", {method} rtol {_short(rtol)}"
    elif method and isinstance(step, (int, float)):
        title += f", {method} step {_short(step)} s"
    elif method:
        title += f", {method}"
    return title


class Animation:
    """A run's animation page (:meth:`Run.animate`): one self-contained HTML document.

    Attributes
    ----------
    html : str
        The page, as ``lash animate`` writes animation.html.
    height : int
        Height in pixels of its frame in a notebook.
    """

    def __init__(self, page: str, height: int = 980) -> None:
        self.html = page
        self.height = height

    def save(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Writes the page to ``path`` (UTF-8)."""
        with open(path, "w", encoding="utf-8") as f:
            f.write(self.html)

    def _repr_html_(self) -> str:
        # In an iframe of its own, so that the page's script, ids and styles stay apart from
        # the notebook's (and of other animations); sandboxed: scripts only.
        return (f'<iframe srcdoc="{html.escape(self.html, quote=True)}" '
                f'style="width:100%;height:{int(self.height)}px;border:0" '
                f'sandbox="allow-scripts"></iframe>')

    def __repr__(self) -> str:
        return f"Animation({len(self.html)} characters of HTML)"


def _positive(name: str, value, what: str = "a finite number > 0") -> Optional[float]:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise UsageError(f"{name} must be {what}, got {value!r}")
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise UsageError(f"{name} must be {what}, got {value!r}")
    return v


#: The largest whole number the engine's counters hold (a 64-bit unsigned integer).
_WHOLE_MAX = 2 ** 64 - 1


def _whole(name: str, value, minimum: int) -> Optional[int]:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < minimum:
        raise UsageError(f"{name} must be a whole number >= {minimum}, got {value!r}")
    if value > _WHOLE_MAX:
        raise UsageError(f"{name} must be at most 2**64 - 1, got {value!r}")
    return int(value)


def run(
    scene: Union[str, "os.PathLike[str]", Dict[str, Any]],
    method: Optional[str] = None,
    rtol: Optional[float] = None,
    atol: Union[None, float, Sequence[float]] = None,
    controller: Optional[str] = None,
    step: Optional[float] = None,
    t_end: Optional[float] = None,
    samples_per_revolution: Optional[int] = None,
    max_wall_time: Optional[float] = None,
    max_steps: Optional[int] = None,
    *,
    output_every: Optional[float] = None,
    name: str = "scene",
    max_memory: Optional[int] = None,
    formulation: Optional[str] = None,
    energy_check: bool = True,
) -> Run:
    """Run a scene as ``lash run`` does and return its results in memory.

    The same engine, defaults and checks as the command ``lash run SCENE`` with the flags of
    the same names (docs/outputs.md, "lash run CASE"): the numbers are the command's, bit for
    bit. Nothing is written to disk. The GIL is released while the scene is read and
    integrated, so threads can run scenes in parallel.

    Parameters
    ----------
    scene : str, os.PathLike or dict
        A scene file (JSON, docs/scene-format.md), a built-in test problem
        ``"testset:NAME"`` (rober, vdpolm, hires, orego), or the scene itself as a dict
        (the same JSON as the files).
    method : str, optional
        ``--method``: rk4, bs32, dopri54, tsit54, dop853, bdf, trbdf2, esdirk34, rodas5p.
        Default: the case's (bdf for scenes, rodas5p for test problems).
    rtol : float, optional
        ``--rtol``, in [1e-14, 1) (adaptive methods). Default: the case's (1e-8 for scenes).
    atol : float or sequence of floats, optional
        ``--atol``: one number, or one per state component; each finite and > 0 (adaptive
        methods). Default: rtol times the scene's length and speed scales (docs/outputs.md).
    controller : str, optional
        ``--controller``: i, pi, pid, h211, h312, gustafsson (lash's adaptive methods, not
        diffsol's bdf, trbdf2, esdirk34).
    step : float, optional
        ``--step``: the fixed step of rk4, s; finite and > 0 (required with rk4).
    t_end : float, optional
        ``--t-end``: end time, s; finite and > 0 (scenes only). Default: the scene's.
    samples_per_revolution : int, optional
        ``--samples-per-revolution``: trajectory rows per crank revolution, >= 1 (scenes
        with a crank driver). Default 2000.
    max_wall_time : float, optional
        ``--max-wall-time``: wall-clock budget of the whole run, s, counted from the call;
        running out raises :class:`SolveError` (kind ``"budget_exhausted"``).
    max_steps : int, optional
        ``--max-steps``: most step attempts, >= 1; running out raises :class:`SolveError`
        (kind ``"too_many_steps"``). Default: the case's (50 000 000 for scenes).
    output_every : float, optional
        ``--output-every``: time between trajectory rows, s (any scene); not together with
        ``samples_per_revolution``. Keyword only.
    formulation : str, optional
        ``--formulation``: ``"lagrange_baumgarte"``, ``"augmented_lagrangian"``, ``"minimal"``
        or ``"auto"``
        (docs/model.md §12), over the scene's own ``formulation``. Recorded in
        ``summary["formulation"]``. Keyword only.
    energy_check : bool, optional
        The energy check of the finished run (docs/outputs.md, "The energy check of a run"):
        a run whose energy balance is off by more than its accuracy allows (5 % of its energy
        flows plus its integrals' and its states' own error) raises :class:`SolveError` of
        kind ``"energy_balance"``. ``False`` (``--no-energy-check``) leaves it out, for a run
        that is coarse on purpose. Default ``True``. Keyword only.
    name : str, optional
        The case name recorded in the summary for a dict scene (``lash run`` records a
        file's stem); its ``scene_sha256`` is the sha256 of the JSON text the dict is
        serialised to (``json.dumps(scene, allow_nan=False)``). Keyword only.
    max_memory : int, optional
        ``--max-memory``: the budget in bytes of the implicit methods' dense n × n matrices
        (Jacobian and LU), a whole number >= 1; a run that needs more raises
        :class:`OutOfMemoryError` before it starts. Default: half of the memory available to
        the process. Keyword only.

    Returns
    -------
    Run
        ``summary`` (the content of summary.json), ``columns`` (trajectory.csv as numpy
        arrays), ``events`` and :meth:`Run.to_pandas`.

    Raises
    ------
    SceneError
        The scene is rejected: ``.path`` is the JSON path of the offending value, ``.reason``
        why (docs/scene-format.md, "Errors"); a file that is not JSON has path ``"."``.
    UsageError
        A bad option or combination (rtol with rk4, a controller with bdf, …), named by its
        argument name.
    SolveError
        The integration failed: ``.t`` and ``.y`` are the time and state of the failure,
        ``.kind`` what happened.
    OutOfMemoryError
        The method's dense matrices need more than the memory budget (a
        :class:`MemoryError`); nothing was integrated.
    KeyboardInterrupt
        Ctrl-C (or any signal whose Python handler raises): the run stops at its next step,
        within about 0.1 s, and its results are dropped. In the main thread the scene is
        read and integrated on the calling thread, the GIL released, with Python's signal
        wakeup fd pointed at a watcher of lash's for the time of the call (an event loop's
        wakeup fd, if one is set, is left alone: then the run goes to a thread of lash's while
        the calling thread looks for signals every 50 ms). Python runs signal handlers in its
        main thread only: in other threads Ctrl-C is seen after the run. The stop request is
        one for the process: lash runs of other threads stop too.
    FileNotFoundError
        ``scene`` names no file.

    Examples
    --------
    >>> import lash
    >>> r = lash.run("cases/press/lubricated_150rpm_c0.1.json", t_end=0.1)  # doctest: +SKIP
    >>> r.summary["metrics"]["slider_acc_max"], r.columns["slider_a"].max()  # doctest: +SKIP
    """
    path, text, scene_text = None, None, None
    if isinstance(scene, dict):
        if not isinstance(name, str) or not name:
            raise UsageError(f"name must be a non-empty string, got {name!r}")
        try:
            text = json.dumps(scene, allow_nan=False).encode("utf-8")
        except (TypeError, ValueError) as e:
            raise UsageError(f"scene is not JSON data: {e}") from None
    elif isinstance(scene, (str, os.PathLike)):
        path = os.fspath(scene)
        if not isinstance(path, str):
            path = os.fsdecode(path)
        if not path.startswith("testset:") and not os.path.isfile(path):
            raise FileNotFoundError(2, "No such scene file", path)
        if not path.startswith("testset:"):
            with open(path, "rb") as f:
                scene_text = f.read().decode("utf-8", errors="replace")
    else:
        raise UsageError(f"scene must be a path or a dict, got {type(scene).__name__}")
    if method is not None:
        if not isinstance(method, str) or method.lower() not in _lash.METHODS:
            raise UsageError(f"unknown method {method!r}; lash's methods are "
                             f"{', '.join(_lash.METHODS)}")
        method = method.lower()
    if controller is not None:
        if not isinstance(controller, str) or controller.lower() not in _lash.CONTROLLERS:
            raise UsageError(f"unknown controller {controller!r}; lash's controllers are "
                             f"{', '.join(_lash.CONTROLLERS)}")
        controller = controller.lower()
    # rtol's range and atol's sign are the solver's rules (lash_solver::options), checked by
    # the engine and raised as UsageError in the solver's words; here they are only converted.
    if rtol is not None:
        if isinstance(rtol, bool) or not isinstance(rtol, numbers.Real):
            raise UsageError(f"rtol must be a number, got {rtol!r}")
        rtol = float(rtol)
    atol_list = None
    if atol is not None:
        try:
            arr = np.atleast_1d(np.asarray(atol, dtype=np.float64))
        except (TypeError, ValueError):
            raise UsageError(f"atol must be a number or a sequence of numbers, "
                             f"got {atol!r}") from None
        if arr.ndim != 1 or arr.size == 0:
            raise UsageError(f"atol must be one number or one per state component, "
                             f"got {atol!r}")
        atol_list = [float(a) for a in arr]
    step = _positive("step", step)
    t_end = _positive("t_end", t_end)
    output_every = _positive("output_every", output_every)
    max_wall_time = _positive("max_wall_time", max_wall_time)
    samples_per_revolution = _whole("samples_per_revolution", samples_per_revolution, 1)
    max_steps = _whole("max_steps", max_steps, 1)
    max_memory = _whole("max_memory", max_memory, 1)
    if samples_per_revolution is not None and output_every is not None:
        raise UsageError("samples_per_revolution and output_every exclude each other: give "
                         "one")

    if formulation is not None and formulation not in ("lagrange_baumgarte",
                                                       "augmented_lagrangian", "minimal",
                                                       "auto"):
        raise UsageError(f"unknown formulation {formulation!r}; lash's formulations are "
                         "lagrange_baumgarte, augmented_lagrangian, minimal, auto")
    if not isinstance(energy_check, bool):
        raise UsageError(f"energy_check must be True or False, got {energy_check!r}")
    raw = _lash.run_core(dict(
        path=path, text=text, name=name, method=method, rtol=rtol, atol=atol_list,
        controller=controller, step=step, t_end=t_end,
        samples_per_revolution=samples_per_revolution, output_every=output_every,
        max_wall_time=max_wall_time, max_steps=max_steps, max_memory=max_memory,
        formulation=formulation, skip_energy_check=not energy_check))

    summary = json.loads(raw["summary"])
    # Each column is the engine's own vector, wrapped by numpy without a copy.
    columns = {col: np.asarray(c) for col, c in zip(raw["names"], raw["columns"])}
    events = [Event(float(t), n, kind) for (t, n, kind) in raw["events"]]
    if text is not None:
        scene_text = text.decode("utf-8")
    return Run(summary, columns, events, raw["engine_time_s"], scene=scene_text)
