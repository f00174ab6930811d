"""Dense output (OdeSolution) and t_eval.

The values at t_eval come from the integrator's own interpolation of each step; sol(t)
rebuilds that interpolant from its values at Chebyshev-Lobatto points (python/src/ivp.rs,
`dense_degree`). If the degree assumed for a method were too low, sol(t) would differ from
the t_eval values by the interpolation error of the step (of the order of the local error,
1e-6 here); with the right degree they agree to rounding: 1e-12 relative is the bound.
"""

import math

import numpy as np
import pytest

import lash


def oscillator(t, y):
    return [y[1], -y[0]]


def exact(t):
    t = np.asarray(t)
    return np.array([np.cos(t), -np.sin(t)])


def options(method):
    return {"step": 0.05} if method == "rk4" else {}


@pytest.mark.parametrize("method", lash.METHODS)
def test_sol_reproduces_the_integrators_interpolation(method):
    t_eval = np.linspace(0.0, 10.0, 997)[1:-1]  # interior points, off the step ends
    sol = lash.solve_ivp(oscillator, (0.0, 10.0), [1.0, 0.0], method=method, t_eval=t_eval,
                         dense_output=True, **options(method))
    np.testing.assert_array_equal(sol.t, t_eval)
    dense = sol.sol(t_eval)
    assert dense.shape == (2, len(t_eval))
    np.testing.assert_allclose(dense, sol.y, rtol=0, atol=1e-12)


@pytest.mark.parametrize("method", ["rodas5p", "dopri54", "dop853", "bdf"])
def test_sol_is_as_accurate_as_the_steps(method):
    """Between the steps the dense output holds the tolerance: at rtol 1e-8 the harmonic
    oscillator over 10 time units (global error within a few hundred tolerances, see
    test_scipy.py) stays within 1e-5 of cos t everywhere."""
    sol = lash.solve_ivp(oscillator, (0.0, 10.0), [1.0, 0.0], method=method, rtol=1e-8,
                         atol=1e-10, dense_output=True)
    t = np.linspace(0.0, 10.0, 2001)
    assert np.max(np.abs(sol.sol(t) - exact(t))) < 1e-5
    # At the step ends, sol gives the stored steps exactly.
    np.testing.assert_allclose(sol.sol(sol.t), sol.y, rtol=0, atol=1e-14)
    assert sol.sol.n_segments == len(sol.t) - 1
    np.testing.assert_array_equal(sol.sol.ts, sol.t)


def test_sol_backwards():
    """y' = y from t = 2 back to 0 with y(2) = e^2: y = e^t."""
    sol = lash.solve_ivp(lambda t, y: y, (2.0, 0.0), [math.e ** 2], method="dop853",
                         rtol=1e-10, atol=1e-12, dense_output=True, t_eval=[1.5, 1.0, 0.25])
    np.testing.assert_allclose(sol.y[0], np.exp([1.5, 1.0, 0.25]), rtol=1e-9)
    t = np.linspace(0.0, 2.0, 101)
    np.testing.assert_allclose(sol.sol(t)[0], np.exp(t), rtol=1e-9)
    assert sol.sol(0.5).shape == (1,)
    assert sol.sol.ts[-1] == 0.0 and sol.sol.t_min == 0.0 and sol.sol.t_max == 2.0
    assert np.all(np.diff(sol.t) < 0)


def test_sol_jumps_at_a_hook():
    """A bouncing ball: the velocity jumps at the impact; sol gives the state after the hook
    at the event time and the falling state just before it."""

    def floor(t, y):
        return y[0]

    floor.direction = -1
    floor.hook = lambda t, y: [y[0], -0.5 * y[1]]
    sol = lash.solve_ivp(lambda t, y: [y[1], -9.81], (0.0, 0.6), [1.0, 0.0],
                         method="dopri54", events=floor, dense_output=True)
    t_hit = sol.t_events[0][0]
    v_hit = -9.81 * t_hit
    assert sol.sol(t_hit)[1] == pytest.approx(-0.5 * v_hit, rel=1e-9)
    assert sol.sol(t_hit * (1 - 1e-9))[1] == pytest.approx(v_hit, rel=1e-6)
    # After the bounce: rising from the floor at 0.5 |v_hit|.
    dt = 0.05
    assert sol.sol(t_hit + dt)[0] == pytest.approx(-0.5 * v_hit * dt - 9.81 * dt * dt / 2,
                                                    rel=1e-9)


def test_t_eval_includes_the_end_points():
    sol = lash.solve_ivp(oscillator, (0.0, 1.0), [1.0, 0.0], t_eval=[0.0, 0.5, 1.0],
                         rtol=1e-10, atol=1e-12)
    np.testing.assert_array_equal(sol.t, [0.0, 0.5, 1.0])
    np.testing.assert_array_equal(sol.y[:, 0], [1.0, 0.0])
    np.testing.assert_allclose(sol.y, exact([0.0, 0.5, 1.0]), atol=1e-9)


def test_no_dense_output_gives_none():
    assert lash.solve_ivp(oscillator, (0.0, 1.0), [1.0, 0.0]).sol is None
