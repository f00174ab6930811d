"""Type stub of the extension module lash._lash (python/src/lib.rs)."""

from typing import Any, Callable, Dict, List, Optional, Tuple

__version__: str
METHODS: Tuple[str, ...]
CONTROLLERS: Tuple[str, ...]
DEFAULT_CONTROLLERS: Tuple[Tuple[str, Optional[str]], ...]

def solve_ivp_core(fun: Callable[..., Any], args: Dict[str, Any]) -> Dict[str, Any]:
    """Integrates a Python ODE (python/src/ivp/mod.rs): `args` holds the keyword arguments
    (t0, t1, y0, method, t_eval, dense_output, events, rtol, atol, jac, jac_matrix,
    jac_sparsity, vectorized, controller, max_step, first_step, min_step, max_steps, step,
    max_memory, args), arrays as bytes of native-endian float64."""

def run_core(args: Dict[str, Any]) -> Dict[str, Any]:
    """Runs one scene by the engine (python/src/scene.rs): `args` holds the keyword arguments
    (path, text, name, method, rtol, atol, controller, step, t_end, samples_per_revolution,
    output_every, max_wall_time, max_steps, max_memory), each None for "as the case says"
    (name: a string); `columns` in the result: one F64Column per trajectory column."""

class F64Column:
    """A run's column: the engine's vector behind numpy's array interface (numpy.asarray
    wraps it without a copy; python/src/convert.rs)."""
    __array_interface__: Dict[str, Any]
    def __len__(self) -> int: ...

def sweep_points_core(args: Dict[str, Any]) -> List[Tuple[int, str, str, Optional[str]]]:
    """A sweep's points as `lash sweep` expands and checks them (python/src/sweep.rs): `args`
    holds file and text; (index, id, params JSON, scene JSON or None) per point."""

def sweep_run_core(args: Dict[str, Any]) -> int:
    """Runs a sweep's points (all, or `only`) into `out` as `lash sweep` does
    (python/src/sweep.rs): `args` holds file, text, out, only, jobs, max_wall_time."""


def animation_html(scene_json: str, names: List[str], columns: bytes, rows: int, title: str,
                   trace: Optional[str] = ..., column: Optional[str] = ...,
                   max_frames: Optional[int] = ...) -> str:
    """A run's animation page (python/src/animation.rs)."""
