"""Type stub of the extension module lash._lash (python/src/lib.rs)."""

from typing import Any, Callable, Dict, Optional, Tuple

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
    (name: a string)."""
