"""Events: terminal, direction, counts and lash's hooks, against closed forms.

A ball dropped from h0 = 1 m at rest under g = 9.81 m/s^2 is at y(t) = h0 - g t^2 / 2: it
reaches the ground at t* = sqrt(2 h0 / g). The motion is a quadratic in t, which every method
of order >= 2 and its dense output reproduce exactly up to rounding (RK4 and BS3(2) by cubic
Hermite interpolation, the others by continuous extensions of order >= 3), so the located
event time is limited only by the event tolerance (1e-13 relative, crates/solver's
`event_rtol`): 1e-12 relative is the bound. diffsol's BDF starts at order 1 (implicit Euler),
which is not exact on a quadratic: its error is held by the tolerance, so its bound is rtol.
"""

import math

import numpy as np
import pytest

import lash

G = 9.81
T_HIT = math.sqrt(2.0 / G)


def fall(t, y):
    return [y[1], -G]


def ground(t, y):
    return y[0]


ground.terminal = True
ground.direction = -1


def options(method):
    return {"step": 1e-3} if method == "rk4" else {}


@pytest.mark.parametrize("method", lash.METHODS)
def test_terminal_event_at_the_analytic_time(method):
    sol = lash.solve_ivp(fall, (0.0, 5.0), [1.0, 0.0], method=method, events=ground,
                         **options(method))
    assert sol.status == 1
    assert sol.message == "A termination event occurred."
    assert sol.success
    (t_hit,) = sol.t_events[0]
    bound = 1e-6 if method == "bdf" else 1e-12
    assert abs(t_hit - T_HIT) < bound * T_HIT, (method, t_hit - T_HIT)
    # The integration ends at the event, with the state there.
    assert sol.t[-1] == t_hit
    assert sol.y_events[0].shape == (1, 2)
    np.testing.assert_allclose(sol.y_events[0][0], sol.y[:, -1], rtol=0, atol=0)
    assert abs(sol.y_events[0][0][0]) < 1e-9
    assert sol.y_events[0][0][1] == pytest.approx(-G * T_HIT, rel=1e-6)


def test_direction_selects_crossings():
    """A ball thrown up at v0 = 5 m/s crosses h = 1 m rising at t1 and falling at t2, the
    roots of v0 t - g t^2 / 2 = 1."""
    v0 = 5.0
    disc = math.sqrt(v0 * v0 - 2 * G * 1.0)
    t_up, t_down = (v0 - disc) / G, (v0 + disc) / G

    def make(direction):
        def at_one(t, y):
            return y[0] - 1.0

        at_one.direction = direction
        return at_one

    up, down, both = make(1), make(-1), make(0)
    sol = lash.solve_ivp(fall, (0.0, 1.0), [0.0, v0], method="dopri54",
                         events=[up, down, both])
    assert sol.status == 0
    np.testing.assert_allclose(sol.t_events[0], [t_up], rtol=1e-12)
    np.testing.assert_allclose(sol.t_events[1], [t_down], rtol=1e-12)
    np.testing.assert_allclose(sol.t_events[2], [t_up, t_down], rtol=1e-12)
    # Velocities at the crossings: +-sqrt(v0^2 - 2 g).
    np.testing.assert_allclose(sol.y_events[0][:, 1], [disc], rtol=1e-10)
    np.testing.assert_allclose(sol.y_events[1][:, 1], [-disc], rtol=1e-10)


def bounce_times(e, count):
    """Closed form: first impact at sqrt(2/g), then flights of 2 e^k v1 / g."""
    times = [T_HIT]
    v = G * T_HIT
    while len(times) < count:
        v *= e
        times.append(times[-1] + 2 * v / G)
    return np.array(times), G * T_HIT * e ** np.arange(count)


@pytest.mark.parametrize("method", ["rodas5p", "dopri54", "tsit54", "dop853", "bs32"])
def test_hook_bounces_the_ball(method):
    """The hook reverses the velocity with restitution e = 0.8: every impact time and
    impact speed follows the closed form (lash's own bouncing-ball doc-test, driven from
    Python)."""
    e = 0.8

    def floor(t, y):
        return y[0]

    floor.direction = -1
    floor.hook = lambda t, y: [y[0], -e * y[1]]
    times, speeds = bounce_times(e, 4)
    t_end = times[-1] + 0.1  # before the 5th impact
    sol = lash.solve_ivp(fall, (0.0, t_end), [1.0, 0.0], method=method, events=floor)
    assert sol.status == 0
    np.testing.assert_allclose(sol.t_events[0], times, rtol=1e-10)
    # y_events holds the state before the hook: falling at the impact speed.
    np.testing.assert_allclose(sol.y_events[0][:, 1], -speeds, rtol=1e-9)
    # t holds each impact twice: before the hook, then after it.
    for t_k, v_k in zip(sol.t_events[0], speeds):
        (at,) = np.nonzero(sol.t == t_k)
        assert len(at) == 2
        assert sol.y[1, at[0]] == pytest.approx(-v_k, rel=1e-9)
        assert sol.y[1, at[1]] == pytest.approx(e * v_k, rel=1e-9)
    # Height never goes below the floor by more than rounding.
    assert sol.y[0].min() > -1e-9


def test_terminal_count_stops_after_the_kth_occurrence():
    e = 0.8

    def floor(t, y):
        return y[0]

    floor.direction = -1
    floor.terminal = 3
    floor.hook = lambda t, y: [y[0], -e * y[1]]
    times, _ = bounce_times(e, 3)
    sol = lash.solve_ivp(fall, (0.0, 10.0), [1.0, 0.0], events=floor)
    assert sol.status == 1
    np.testing.assert_allclose(sol.t_events[0], times, rtol=1e-10)
    assert sol.t[-1] == sol.t_events[0][-1]


def test_hook_returning_none_keeps_the_state():
    seen = []

    def at_half(t, y):
        return y[0] - 0.5

    def record(t, y):
        seen.append((t, y.copy()))

    at_half.hook = record
    sol = lash.solve_ivp(fall, (0.0, T_HIT * 0.99), [1.0, 0.0], method="dopri54",
                         events=at_half)
    t_half = math.sqrt(1.0 / G)
    assert len(seen) == 1
    assert seen[0][0] == pytest.approx(t_half, rel=1e-12)
    assert np.count_nonzero(sol.t == seen[0][0]) == 1  # no duplicate: unchanged state
    assert sol.y[0, -1] == pytest.approx(1 - G * sol.t[-1] ** 2 / 2, rel=1e-12)


def test_events_take_args():
    def fall_g(t, y, g):
        return [y[1], -g]

    def floor(t, y, g):
        return y[0]

    floor.terminal = True
    sol = lash.solve_ivp(fall_g, (0.0, 5.0), [2.0, 0.0], method="dopri54", events=floor,
                         args=(4.0,))
    assert sol.t_events[0][0] == pytest.approx(1.0, rel=1e-12)  # sqrt(2 * 2 / 4)


def test_no_events_gives_none_and_unfound_events_empty_arrays():
    sol = lash.solve_ivp(fall, (0.0, 0.1), [1.0, 0.0])
    assert sol.t_events is None and sol.y_events is None
    sol = lash.solve_ivp(fall, (0.0, 0.1), [1.0, 0.0], events=[ground])
    assert sol.t_events[0].shape == (0,)
    # scipy's shape for an event that never occurred (np.asarray of an empty list).
    assert sol.y_events[0].shape == (0,)


def test_backward_integration_finds_events_along_its_direction():
    """From the ground at t = T_HIT back to t = 0: the height rises from 0 to 1 m, so
    h - 0.5 crosses upwards (direction +1 along the integration) at sqrt(1/g)."""

    def at_half(t, y):
        return y[0] - 0.5

    at_half.direction = 1
    sol = lash.solve_ivp(fall, (T_HIT, 0.0), [0.0, -G * T_HIT], method="dopri54",
                         events=at_half, rtol=1e-10)
    np.testing.assert_allclose(sol.t_events[0], [math.sqrt(1.0 / G)], rtol=1e-10)
    assert sol.t[-1] == 0.0
    np.testing.assert_allclose(sol.y[:, -1], [1.0, 0.0], atol=1e-9)
