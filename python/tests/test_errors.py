"""Errors: lash.UsageError for bad arguments, lash.SolveError with time and state for a
failed integration, lash.SceneError with its JSON path, and an exception raised inside a
callback propagating as itself after the integration has stopped."""

import math
import pickle

import numpy as np
import pytest

import lash


def decay(t, y):
    return [-y[0]]


@pytest.mark.parametrize(
    "kwargs, fragment",
    [
        ({"method": "radau5"}, "unknown method"),
        ({"method": type("MySolver", (), {})}, "not an OdeSolver class"),
        ({"method": 3}, "method must be one of"),
        ({"controller": "pi2"}, "unknown controller"),
        ({"method": "bdf", "controller": "pi"}, "takes no controller"),
        ({"rtol": 1.0}, "rtol must be in [1e-14, 1)"),
        ({"atol": -1.0}, "atol must be finite and > 0"),
        ({"atol": [1e-9, 1e-9]}, "`atol` has wrong shape"),
        ({"rtol": [1e-3, 1e-3]}, "`rtol` has wrong shape"),
        ({"method": "rk4"}, "needs a fixed step"),
        ({"step": 0.1}, "step is only for fixed-step methods"),
        ({"max_step": 0.0}, "`max_step` must be positive."),
        ({"first_step": -1.0}, "`first_step` must be positive."),
        ({"first_step": 2.0}, "`first_step` exceeds bounds."),
        ({"max_steps": 0}, "max_steps must be an int >= 1"),
        ({"t_eval": [0.5, 2.0]}, "not within `t_span`"),
        ({"t_eval": [0.5, 0.2]}, "not properly sorted"),
        ({"jac": [[1.0, 0.0]]}, "jac must have shape (1, 1)"),
    ],
)
def test_bad_options_raise_usage_error(kwargs, fragment):
    with pytest.raises(lash.UsageError) as info:
        lash.solve_ivp(decay, (0.0, 1.0), [1.0], **kwargs)
    assert fragment in str(info.value)
    assert isinstance(info.value, ValueError)
    assert isinstance(info.value, lash.LashError)


def test_args_that_cannot_be_unpacked_raise_scipys_type_error():
    with pytest.raises(TypeError, match="Supplied 'args' cannot be unpacked."):
        lash.solve_ivp(lambda t, y, a: [a * y[0]], (0.0, 1.0), [1.0], args=3)


@pytest.mark.parametrize(
    "t_span, y0, fragment",
    [
        ((math.inf, 1.0), [1.0], "t0 finite"),
        ((0.0,), [1.0], "t_span must be two numbers"),
        ((0.0, 1.0), [[1.0]], "y0 must be 1-dimensional"),
        ((0.0, 1.0), [math.nan], "All components of the initial state `y0` must be finite."),
        ((0.0, 1.0), [math.inf], "All components of the initial state `y0` must be finite."),
    ],
)
def test_bad_problem_raises_usage_error(t_span, y0, fragment):
    with pytest.raises(lash.UsageError, match=None) as info:
        lash.solve_ivp(decay, t_span, y0)
    assert fragment in str(info.value)


@pytest.mark.parametrize(
    "attr, value, fragment",
    [
        ("terminal", 1.5, "The `terminal` attribute of each event must be"),
        ("terminal", -1, "The `terminal` attribute of each event must be"),
        ("direction", "up", "direction must be a number"),
        ("hook", 3, "hook must be callable"),
    ],
)
def test_bad_event_attributes_raise_usage_error(attr, value, fragment):
    def ev(t, y):
        return y[0] - 0.5

    setattr(ev, attr, value)
    with pytest.raises(lash.UsageError) as info:
        lash.solve_ivp(decay, (0.0, 1.0), [1.0], events=ev)
    assert fragment in str(info.value)


@pytest.mark.parametrize(
    "fun, fragment",
    [
        (lambda t, y: [1.0, 2.0], "fun(t, y) returned a list of length 2; expected shape (1,)"),
        (lambda t, y: np.zeros((1, 1)), "fun(t, y) returned shape (1, 1); expected shape (1,)"),
    ],
)
def test_callback_returning_a_wrong_shape_is_a_usage_error(fun, fragment):
    with pytest.raises(lash.UsageError) as info:
        lash.solve_ivp(fun, (0.0, 1.0), [1.0])
    assert fragment in str(info.value)


def test_jac_returning_a_wrong_shape_is_a_usage_error():
    with pytest.raises(lash.UsageError, match=r"jac\(t, y\) returned shape \(2,\); expected "
                                              r"shape \(1, 1\)"):
        lash.solve_ivp(decay, (0.0, 1.0), [1.0], jac=lambda t, y: [1.0, 2.0])


def test_blow_up_raises_solve_error_with_time_and_state():
    """y' = y^2, y(0) = 1 has y = 1 / (1 - t), which blows up at t = 1. Along every solution
    1/y + t is constant (the blow-up time), so the last good state must give 1/y + t = 1 up
    to the global error (rtol 1e-10 on y: measured 1.5e-11), while y itself is beyond 1e12:
    the run went into the singularity, not stopped early."""
    with pytest.raises(lash.SolveError) as info:
        lash.solve_ivp(lambda t, y: y * y, (0.0, 2.0), [1.0], method="dopri54",
                       rtol=1e-10, atol=1e-10)
    e = info.value
    assert e.kind in ("step_size_too_small", "non_finite_state")
    assert abs(e.t - 1.0) < 1e-6
    assert e.y.shape == (1,)
    assert abs(1.0 / e.y[0] + e.t - 1.0) < 1e-9
    assert e.y[0] > 1e12
    # The message names the time, exactly.
    assert float(str(e).split("at t = ")[1].split(":")[0]) == e.t
    assert isinstance(e, RuntimeError) and isinstance(e, lash.LashError)
    # The partial result, as scipy returns a failed run.
    r = e.result
    assert r.status == -1 and not r.success
    assert r.message == str(e)
    assert r.t[-1] == e.t
    np.testing.assert_array_equal(r.y[:, -1], e.y)
    assert np.all(np.diff(r.t) > 0)


def test_max_steps_raises_too_many_steps():
    with pytest.raises(lash.SolveError) as info:
        lash.solve_ivp(decay, (0.0, 100.0), [1.0], method="dopri54", max_steps=10,
                       max_step=0.1)
    e = info.value
    assert e.kind == "too_many_steps"
    # Ten steps of at most 0.1 from t = 0.
    assert 0.0 < e.t <= 1.0 + 1e-12
    assert e.y[0] == pytest.approx(math.exp(-e.t), rel=1e-6)
    assert len(e.result.t) == 11


def test_fun_returning_nan_raises_non_finite_state():
    with pytest.raises(lash.SolveError) as info:
        lash.solve_ivp(lambda t, y: [math.nan if t > 0.5 else -y[0]], (0.0, 1.0), [1.0],
                       method="dopri54")
    assert info.value.kind in ("non_finite_state", "step_size_too_small")
    assert 0.0 < info.value.t <= 0.5


class Boom(Exception):
    pass


def test_exception_in_fun_propagates_as_itself_and_stops_the_run():
    calls = []

    def fun(t, y):
        calls.append(t)
        if t > 0.5:
            raise Boom(f"at {t}")
        return [-y[0]]

    with pytest.raises(Boom) as info:
        lash.solve_ivp(fun, (0.0, 1.0), [1.0], method="rodas5p")
    # The traceback reaches into the user's function, and fun was not called again.
    assert info.traceback[-1].name == "fun"
    assert calls[-1] > 0.5
    assert sum(t > 0.5 for t in calls) == 1


@pytest.mark.parametrize("where", ["jac", "event", "hook"])
def test_exception_in_other_callbacks_propagates(where):
    def jac(t, y):
        if where == "jac" and t > 0.3:
            raise KeyError("jac")
        return [[-1.0]]

    def ev(t, y):
        if where == "event" and t > 0.3:
            raise KeyError("event")
        return y[0] - 0.5

    def hook(t, y):
        if where == "hook":
            raise KeyError("hook")
        return None

    ev.hook = hook
    with pytest.raises(KeyError) as info:
        lash.solve_ivp(decay, (0.0, 1.0), [1.0], method="rodas5p", jac=jac, events=ev)
    assert info.value.args == (where,)


def test_scene_error_fields():
    e = lash.SceneError("joints[4].bearing.radius", "bearing radius must be > 0, got 0")
    assert e.path == "joints[4].bearing.radius"
    assert e.reason == "bearing radius must be > 0, got 0"
    assert str(e) == "joints[4].bearing.radius: bearing radius must be > 0, got 0"
    assert isinstance(e, ValueError) and isinstance(e, lash.LashError)
    back = pickle.loads(pickle.dumps(e))
    assert (back.path, back.reason, str(back)) == (e.path, e.reason, str(e))


def test_solve_error_pickles_with_its_fields():
    with pytest.raises(lash.SolveError) as info:
        lash.solve_ivp(decay, (0.0, 100.0), [1.0], method="dopri54", max_steps=3)
    back = pickle.loads(pickle.dumps(info.value))
    assert (back.t, back.kind, str(back)) == (info.value.t, info.value.kind, str(info.value))
    np.testing.assert_array_equal(back.y, info.value.y)
    assert back.result.status == -1
