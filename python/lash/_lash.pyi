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
    args), arrays as bytes of native-endian float64."""

def run_core(path: Optional[str], text: Optional[bytes], name: str, method: Optional[str],
             rtol: Optional[float], atol: Optional[Any], controller: Optional[str],
             step: Optional[float], t_end: Optional[float],
             samples_per_revolution: Optional[int], output_every: Optional[float],
             max_wall_time: Optional[float], max_steps: Optional[int]) -> Dict[str, Any]:
    """Runs one scene by the engine (python/src/scene.rs)."""


def animation_html(scene_json: str, names: List[str], columns: bytes, rows: int, title: str,
                   trace: Optional[str] = ..., column: Optional[str] = ...,
                   max_frames: Optional[int] = ...) -> str:
    """A run's animation page (python/src/animation.rs)."""
