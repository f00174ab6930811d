"""``lash.sweep``: a sweep's points run in process or on any executor, as ``lash sweep``
runs them, one row per point in a pandas DataFrame."""

from __future__ import annotations

import json
import os
import tempfile
from typing import Any, Dict, List, Optional, Union

from . import _lash
from ._errors import UsageError

__all__ = ["sweep"]

#: The name a sweep given as a dict is read as (its errors name it; a relative ``case`` is
#: resolved against the current directory before the points leave this process).
_DICT = "<dict>"


def _source(sweep) -> "tuple[str, Optional[bytes]]":
    """(file, text): the sweep file's absolute path and None, or the name ``<dict>`` and the
    dict's JSON text with a relative ``case`` made absolute (tasks may run elsewhere)."""
    if isinstance(sweep, dict):
        spec = dict(sweep)
        case = spec.get("case")
        if isinstance(case, str) and not case.startswith("testset:") \
                and not os.path.isabs(case):
            spec["case"] = os.path.abspath(case)
        try:
            text = json.dumps(spec, allow_nan=False).encode("utf-8")
        except (TypeError, ValueError) as e:
            raise UsageError(f"sweep is not JSON data: {e}") from None
        return _DICT, text
    if isinstance(sweep, (str, os.PathLike)):
        path = os.fsdecode(os.fspath(sweep))
        if not os.path.isfile(path):
            raise FileNotFoundError(2, "No such sweep file", path)
        return os.path.abspath(path), None
    raise UsageError(f"sweep must be a sweep file or a dict, got {type(sweep).__name__}")


def _run_point(file: str, text: Optional[bytes], out: str, index: int, point_id: str,
               max_wall_time: Optional[float]) -> Dict[str, Any]:
    """One task: the point ``index`` run into ``out`` by the engine as ``lash sweep`` runs
    it (skipped if it finished before), then its result.json. Runs wherever the executor
    puts it: ``lash`` must be importable there and ``out`` shared."""
    _lash.sweep_run_core(dict(file=file, text=text, out=out, only=index, jobs=1,
                              max_wall_time=max_wall_time))
    return _record(out, point_id)


def _record(out: str, point_id: str) -> Dict[str, Any]:
    with open(os.path.join(out, point_id, "result.json"), encoding="utf-8") as f:
        return json.load(f)


def _row(index: int, point_id: str, params: Dict[str, Any], status: str,
         error: Optional[str], values: Dict[str, Any]) -> Dict[str, Any]:
    row: Dict[str, Any] = {"index": index, "id": point_id}
    row.update(params)
    row["status"] = status
    row["error"] = error
    row.update(values)
    return row


def sweep(
    sweep: Union[str, "os.PathLike[str]", Dict[str, Any]],
    executor: Any = None,
    out: Union[None, str, "os.PathLike[str]"] = None,
    *,
    jobs: Optional[int] = None,
    max_wall_time: Optional[float] = None,
):
    """Run a sweep as ``lash sweep`` does, in this process or on any executor, and return one
    row per point.

    The points are the engine's own (docs/outputs.md, "Sweeps"): the same grid, the same ids
    (a hash of each point's parameters) and the same numbers as ``lash sweep`` on the same
    file, and each point lands in the command's directory layout (``OUT/points.json``,
    ``OUT/ID/summary.json``, ``OUT/ID/result.json``), so ``lash merge OUT`` joins what ran
    here, and a rerun skips the points that finished.

    Parameters
    ----------
    sweep : str, os.PathLike or dict
        A sweep file, or its content as a dict (a relative ``case`` is relative to the current
        directory).
    executor : concurrent.futures.Executor or dask.distributed.Client, optional
        Where the points run, one task per point: anything with ``submit(fn, *args)``
        returning a future with ``result()`` — a ``ProcessPoolExecutor``, a
        ``dask.distributed`` ``Client`` or its ``client.get_executor()``, submitit's
        ``AutoExecutor`` (SLURM). The workers import ``lash`` and write into ``out``, which
        they must all see (a shared file system). None: in this process, the points in
        parallel on ``jobs`` threads, as ``lash sweep --jobs``.
    out : str or os.PathLike, optional
        The sweep's output directory. Default: a new temporary directory (its path is
        ``df.attrs["out"]``).
    jobs : int, optional
        Parallel points with ``executor=None`` (>= 1; default one per core).
    max_wall_time : float, optional
        ``--max-wall-time``: budget of each point's integration, s; a point over it is a
        solver failure, recorded like any other.

    Returns
    -------
    pandas.DataFrame
        One row per point, in grid order: ``index``, ``id``, the parameters (``case``,
        ``scene_sha256``, the shorthands and every ``set`` path named exactly as written),
        ``status`` (``ok``, ``solver_failed``, or ``failed``: the task raised, not recorded,
        rerun tries it again), ``error`` (the solver's or the task's message, else None), and
        the metrics as ``lash merge`` names them (``metrics.slider_acc_max``, …).

    Raises
    ------
    SceneError, UsageError
        A bad sweep (an unknown key or path, a wrong type, an empty list, a value the scene
        rejects), naming the key and the point, before anything runs.
    KeyboardInterrupt
        Ctrl-C with ``executor=None``: the point in flight is abandoned, finished ones stay.
    """
    try:
        import pandas as pd
    except ImportError as e:
        raise ImportError("lash.sweep needs pandas: pip install pandas") from e
    if jobs is not None and (isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1):
        raise UsageError(f"jobs must be a whole number >= 1, got {jobs!r}")
    if max_wall_time is not None:
        if isinstance(max_wall_time, bool) or not isinstance(max_wall_time, (int, float)) \
                or not max_wall_time > 0 or max_wall_time == float("inf"):
            raise UsageError(f"max_wall_time must be a finite number > 0, got "
                             f"{max_wall_time!r}")
        max_wall_time = float(max_wall_time)
    if executor is not None and not callable(getattr(executor, "submit", None)):
        raise UsageError(f"executor must have submit(fn, *args) (a concurrent.futures "
                         f"Executor or a dask Client), got {type(executor).__name__}")
    file, text = _source(sweep)
    # Expanded and checked by the engine before anything runs (nothing written yet).
    points = [(i, pid, json.loads(params)) for (i, pid, params, _scene)
              in _lash.sweep_points_core(dict(file=file, text=text))]
    out = tempfile.mkdtemp(prefix="lash-sweep-") if out is None \
        else os.path.abspath(os.fsdecode(os.fspath(out)))

    rows: List[Dict[str, Any]] = []
    if executor is None:
        _lash.sweep_run_core(dict(file=file, text=text, out=out, only=None, jobs=jobs,
                                  max_wall_time=max_wall_time))
        for i, pid, params in points:
            r = _record(out, pid)
            rows.append(_row(i, pid, params, r["status"], r["error"], r["values"]))
    else:
        futures = [(i, pid, params,
                    executor.submit(_run_point, file, text, out, i, pid, max_wall_time))
                   for i, pid, params in points]
        for i, pid, params, f in futures:
            try:
                r = f.result()
            except KeyboardInterrupt:
                raise
            except Exception as e:  # the task failed otherwise than in the solver
                rows.append(_row(i, pid, params, "failed", f"{type(e).__name__}: {e}", {}))
                continue
            rows.append(_row(i, pid, params, r["status"], r["error"], r["values"]))
    df = pd.DataFrame(rows)
    df.attrs["out"] = out
    return df
