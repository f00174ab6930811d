"""Stiff problems of the IVP Test Set through lash.solve_ivp with the right-hand side in Python.

References: F. Mazzia and C. Magherini, Test Set for Initial Value Problem Solvers, release
2.4 (University of Bari, 2008), problems VDPOLM (van der Pol, mu = 1000, unscaled) and ROBER
(Robertson's kinetics), the values of crates/solver/src/testset.rs. The requirement is the
one crates/solver/tests/stiff_testset.rs sets for the same methods driven from Rust: at
rtol = 1e-8 and each problem's atol, a relative error below 1e-5 in every component larger
than atol. A wrong sign or index in the Python bridge, a Jacobian not passed through, or time
mapped wrongly gives errors of order 1.
"""

import numpy as np
import pytest

import lash

STIFF = ["rodas5p", "bdf", "esdirk34", "trbdf2"]


def vdpolm(t, y):
    return [y[1], 1000.0 * (1.0 - y[0] * y[0]) * y[1] - y[0]]


def vdpolm_jac(t, y):
    return [[0.0, 1.0], [-2000.0 * y[0] * y[1] - 1.0, 1000.0 * (1.0 - y[0] * y[0])]]


def rober(t, y):
    a, b, c = 0.04 * y[0], 1e4 * y[1] * y[2], 3e7 * y[1] * y[1]
    return [-a + b, a - b - c, c]


def rober_jac(t, y):
    return [
        [-0.04, 1e4 * y[2], 1e4 * y[1]],
        [0.04, -1e4 * y[2] - 6e7 * y[1], -1e4 * y[1]],
        [0.0, 6e7 * y[1], 0.0],
    ]


PROBLEMS = {
    # name: (fun, jac, t_end, y0, reference at t_end, atol)
    "vdpolm": (vdpolm, vdpolm_jac, 2000.0, [2.0, 0.0],
               [1.706167732170469, -8.928097010248125e-4], 1e-11),
    "rober": (rober, rober_jac, 1e11, [1.0, 0.0, 0.0],
              [2.083340149701255e-8, 8.333360770334713e-14, 0.999999979166505], 1e-16),
}


def reference_error(y, reference, atol):
    """Largest relative error over the components whose |reference| > atol
    (lash_solver::testset::reference_error)."""
    reference = np.asarray(reference)
    big = np.abs(reference) > atol
    return float(np.max(np.abs(y[big] - reference[big]) / np.abs(reference[big])))


@pytest.mark.parametrize("name", sorted(PROBLEMS))
@pytest.mark.parametrize("method", STIFF)
@pytest.mark.parametrize("with_jac", [False, True], ids=["fd-jac", "jac"])
def test_matches_the_ivp_test_set_reference(name, method, with_jac):
    fun, jac, t_end, y0, reference, atol = PROBLEMS[name]
    sol = lash.solve_ivp(fun, (0.0, t_end), y0, method=method, rtol=1e-8, atol=atol,
                         jac=jac if with_jac else None)
    assert sol.status == 0 and sol.success
    assert sol.t[-1] == t_end
    err = reference_error(sol.y[:, -1], reference, atol)
    assert err < 1e-5, f"{method} on {name}: relative error {err:.3e}"


def test_rodas5p_on_vdpolm_is_accurate_to_a_few_tolerances():
    """Rodas5P is of order 5 and stiffly accurate: at rtol 1e-8 its error on VDPOLM stays
    within 10 rtol (the Rust-driven run has 6e-9)."""
    fun, jac, t_end, y0, reference, atol = PROBLEMS["vdpolm"]
    sol = lash.solve_ivp(fun, (0.0, t_end), y0, rtol=1e-8, atol=atol, jac=jac)
    assert reference_error(sol.y[:, -1], reference, atol) < 1e-7


def test_counters_count_the_python_calls():
    """nfev is every call of fun (finite-difference columns included) and njev every
    Jacobian: counted here independently of lash."""
    calls = {"fun": 0, "jac": 0}

    def fun(t, y):
        calls["fun"] += 1
        return vdpolm(t, y)

    def jac(t, y):
        calls["jac"] += 1
        return vdpolm_jac(t, y)

    sol = lash.solve_ivp(fun, (0.0, 2000.0), [2.0, 0.0], rtol=1e-6, atol=1e-9, jac=jac)
    assert sol.nfev == calls["fun"] > 0
    assert sol.njev == calls["jac"] > 0
    # Rodas5P factorises its iteration matrix once per step attempt.
    assert sol.nlu == sol.stats["steps"]

    calls["fun"] = 0
    fd = lash.solve_ivp(fun, (0.0, 2000.0), [2.0, 0.0], rtol=1e-6, atol=1e-9)
    assert fd.nfev == calls["fun"]
    # Without jac each Jacobian costs n = 2 calls of fun on top of the stages.
    assert fd.nfev >= 2 * fd.njev + fd.stats["accepted"]
