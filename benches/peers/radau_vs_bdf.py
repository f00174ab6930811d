#!/usr/bin/env python3
"""Radau IIA order 5 against BDF (and LSODA) on the lubricated press, at equal error.

What it measures
    Would a Radau IIA order-5 method (Hairer & Wanner's RADAU5, as ported in
    scipy.integrate's "Radau") beat BDF at tight tolerances on the lubricated press
    (150 rpm, c = 0.1 mm, two crank revolutions, t in [0, 0.8] s)? The problem is the
    hand-written 4-state minimal-coordinate press of benches/src/handwritten.rs
    (`HandPress::paper(150.0, 1e-4, true)`), ported below to plain Python floats formula by
    formula: state y = (psi, x, psi_dot, x_dot), crank prescribed, long-bearing Guembel film
    with eps capped at 0.99, ADAMS IMPACT contact and Coulomb friction with Ambrosio's
    correction when the journal penetrates (docs/model.md sections 2-6).

    Error (as benches/examples/targets.rs sections b and f): max over the 2001 equally
    spaced points of the second revolution, t in [0.4, 0.8] s, of
    |x_ddot - x_ddot_ref| in m/s^2, x_ddot the slider acceleration from the right-hand side
    at the dense-output state. Reference: scipy Radau at rtol 1e-13 (atol = rtol*1e-3 on
    every component); its distance to scipy BDF, LSODA and DOP853 at rtol 1e-13 is printed
    (the references' disagreement: errors below it in the table are not resolved).

    Scan: rtol = 1e-6 ... 1e-12 in quarter decades, atol = rtol*1e-3 on every component (as
    section f of targets.rs gives diffsol's BDF on the same press), methods "Radau", "BDF",
    "LSODA" of scipy.integrate.solve_ivp with dense_output=True and no Jacobian (scipy forms
    it by finite differences).

How to run
    python3 benches/peers/radau_vs_bdf.py            (requires numpy and scipy)
    Options: --quick (half-decade scan), --max-wall S (skip the rest of a method's scan
    once one of its runs took more than S seconds; default 60).

What the numbers mean
    steps      accepted steps, len(sol.t) - 1
    t<0.05     of which in the first 0.05 s (1/8 revolution), where the journal leaves its
               centred start (|e| -> 0: n = e/|e| and gamma_dot are singular there)
    nfev       scipy's count of right-hand-side calls. For Radau and BDF it EXCLUDES the
               calls of the finite-difference Jacobian (scipy makes them through
               fun_single/fun_vectorized, which are not counted); for LSODA it includes them
               (the Fortran code calls the counted function for the Jacobian columns too).
    njev       Jacobian evaluations (finite-difference Jacobians)
    nlu        LU factorisations as scipy counts them. Radau factorises a real 4x4 and a
               complex 4x4 matrix per iteration matrix and counts them as 2; BDF counts 1
               per iteration matrix; LSODA reports nlu = njev (ODEPACK's NJE).
    rhs        right-hand-side calls counted by this script's own wrapper around the RHS:
               every call, those of the finite-difference Jacobians included (Radau: 4 per
               Jacobian, BDF: 5 per Jacobian, since it re-evaluates f at the point, plus the
               calls of scipy's step-size refinement in num_jac when a difference is too
               small). This is the work measure ("RHS-equivalents") used to pick the cheapest
               run; the dense-output sampling is not counted.
    nfev+4njev the usual estimate of RHS-equivalents for a 4-state forward-difference
               Jacobian (meaningful for Radau and BDF only; it double-counts for LSODA).
    wall       seconds of solve_ivp alone (Python: an interpreter-bound figure, not a
               measure of the methods' arithmetic cost).

Caveats
    scipy's "Radau" is a Python port of the RADAU5 scheme (3-stage Radau IIA, order 5,
    simplified Newton on the real/complex transformed system, Gustafsson's predictive step
    controller, embedded error estimate of order 3, collocation dense output), not the
    Fortran code: it uses rtol and atol as given (RADAU5 maps them to
    0.1*rtol^(2/3) internally), at most 6 Newton iterations (RADAU5: 7), keeps the step size
    whenever the proposed factor is below 1.2 (RADAU5: only within [1, 1.2]), refines the
    error estimate only after a rejection (RADAU5: also on the first step), recomputes the
    Jacobian after an accepted step when Newton took more than 2 iterations at a rate above
    1e-3 (RADAU5: whenever the rate is above 1e-3), and forms it with its own adaptive
    forward differences (num_jac). scipy's "BDF" is
    the variable-order (1-5) quasi-constant-step NDF/BDF of Shampine & Reichelt (ode15s
    style), not diffsol's BDF.

Self-check
    At start the script compares its right-hand side with the Rust `HandPress::rhs` at 23
    states (9 along a lubricated trajectory, 14 moved into contact, lubricated and dry,
    covering the damping ramp, both friction branches and the clipped normal force) and
    asserts agreement to 1e-12 relative (see SELF_CHECK below for where the numbers come
    from).
"""

import argparse
import math
import sys
import time
import warnings

import numpy as np
from scipy.integrate import solve_ivp


class HandPress:
    """`HandPress::paper(rpm, c, lubricated)` of benches/src/handwritten.rs."""

    def __init__(self, rpm, c, lubricated):
        r, l, m_rod = 0.015, 0.35, 412.53
        rb = 0.05
        self.r = r
        self.l = l
        self.m_rod = m_rod
        self.i_rod = m_rod * l * l / 12.0
        self.m_slider = 2700.71
        self.omega = rpm * math.pi / 30.0
        self.theta0 = 0.0
        self.g_y = -9.81
        self.rb = rb
        # The case files store R_J rounded to 1e-12 m (Rust's f64::round: half away from 0).
        v = (rb - c) * 1e12
        self.rj = math.copysign(math.floor(abs(v) + 0.5), v) / 1e12
        self.k = 2.34e10
        self.c_max = 100.0
        self.d_max = 1e-5
        self.mu = 0.01
        self.v0 = 1e-4
        self.v1 = 2e-4
        # Film: viscosity (Pa s), bearing length (m), eps_cap; None for a dry joint.
        self.film = (0.4, 0.1, 0.99) if lubricated else None

    def clearance(self):
        return self.rb - self.rj

    def normal_force(self, delta, delta_dot):
        """F_N of the ADAMS IMPACT law at delta > 0 (docs/model.md section 3.1)."""
        s = _fmin(delta / self.d_max, 1.0)
        damping = self.c_max * s * s * (3.0 - 2.0 * s)
        return _fmax(self.k * delta * math.sqrt(delta) + damping * delta_dot, 0.0)

    def friction_force(self, v_t, f_n):
        """F_T along t: Coulomb with Ambrosio's dynamic correction (section 3.2)."""
        a = abs(v_t)
        if a <= self.v0:
            cd = 0.0
        elif a < self.v1:
            cd = (a - self.v0) / (self.v1 - self.v0)
        else:
            cd = 1.0
        return -self.mu * cd * f_n * _signum(v_t)

    def film_force(self, eps, eps_dot, big_omega):
        """Long-bearing Guembel film (F_r, F_t), eps capped at eps_cap (section 4)."""
        if self.film is None:
            return 0.0, 0.0
        visc, length, cap = self.film
        e = _fmin(eps, cap)
        e2 = e * e
        q = 1.0 - e2
        rj3 = self.rj * self.rj * self.rj  # Rust's powi(3)
        k = 12.0 * visc * length * rj3 / (self.clearance() * self.clearance())
        pi = math.pi
        fr = -k * (e2 * big_omega / ((2.0 + e2) * q)
                   + eps_dot * (0.5 * pi - 8.0 / (pi * (2.0 + e2))) / (q * math.sqrt(q)))
        ft = k * (pi * e * big_omega / (2.0 * (2.0 + e2) * math.sqrt(q))
                  + 2.0 * e * eps_dot / ((2.0 + e2) * q))
        return fr, ft

    def accelerations(self, t, psi, x, psid, xd):
        """(psi_ddot, x_ddot) at (t, y)."""
        w = self.omega
        th = self.theta0 + w * t
        st, ct = math.sin(th), math.cos(th)
        r = self.r
        a0, a1 = r * ct, r * st
        ad0, ad1 = -r * w * st, r * w * ct
        add0, add1 = -r * w * w * ct, -r * w * w * st
        sp, cp = math.sin(psi), math.cos(psi)
        u0, u1 = cp, sp
        up0, up1 = -sp, cp
        l = self.l
        b0, b1 = a0 + l * u0, a1 + l * u1
        bd0, bd1 = ad0 + l * psid * up0, ad1 + l * psid * up1
        e0, e1 = b0 - x, b1
        ed0, ed1 = bd0 - xd, bd1
        norm = math.hypot(e0, e1)
        c = self.clearance()
        if norm < 1e-12 * c:
            n0, n1, gamma_dot = 1.0, 0.0, 0.0
        else:
            n0, n1 = e0 / norm, e1 / norm
            gamma_dot = (e0 * ed1 - e1 * ed0) / (norm * norm)
        tv0, tv1 = -n1, n0
        delta = norm - c
        delta_dot = n0 * ed0 + n1 * ed1
        # Moments about A and the force on the slider along x.
        h0, h1 = 0.5 * l * u0, 0.5 * l * u1
        moment = ((h0 * (self.m_rod * self.g_y) - h1 * 0.0)
                  - self.m_rod * (h0 * add1 - h1 * add0))
        fx_journal = 0.0
        if delta > 0.0:
            v_t = tv0 * ed0 + tv1 * ed1 + self.rj * psid
            f_n = self.normal_force(delta, delta_dot)
            f_t = self.friction_force(v_t, f_n)
            f0, f1 = -f_n * n0 + f_t * tv0, -f_n * n1 + f_t * tv1
            arm0, arm1 = l * u0 + self.rj * n0, l * u1 + self.rj * n1
            moment += arm0 * f1 - arm1 * f0
            fx_journal += f0
        if self.film is not None:
            fr, ft = self.film_force(norm / c, delta_dot / c, psid - 2.0 * gamma_dot)
            f0, f1 = fr * n0 + ft * tv0, fr * n1 + ft * tv1
            moment += (l * u0) * f1 - (l * u1) * f0
            fx_journal += f0
        i_a = self.i_rod + self.m_rod * 0.25 * l * l
        return moment / i_a, -fx_journal / self.m_slider

    def rhs(self, t, y):
        psi, x, psid, xd = (float(v) for v in y)
        psidd, xdd = self.accelerations(t, psi, x, psid, xd)
        return np.array([psid, xd, psidd, xdd])


def _fmin(a, b):
    """Rust's f64::min (a NaN operand yields the other)."""
    if a != a:
        return b
    if b != b:
        return a
    return a if a < b else b


def _fmax(a, b):
    """Rust's f64::max."""
    if a != a:
        return b
    if b != b:
        return a
    return a if a > b else b


def _signum(v):
    """Rust's f64::signum (+1 for +0.0, -1 for -0.0)."""
    if v != v:
        return v
    return math.copysign(1.0, v)


# Initial state of the Rust benches: `HandPress::minimal_state(&m.initial_state())` of
# cases/press/lubricated_150rpm_c0.1.json run for two revolutions (targets.rs section f): the
# ideally assembled press at theta = 0 with the journal centred, i.e. (0, r + l, -r omega / l,
# 0) up to the rounding of lash's assembly (x_dot = -3.3e-18 instead of 0).
Y0 = (0.0, 0.365, -0.6731984257692414, -3.3312030031292053e-18)
T0, PERIOD = 0.0, 0.4
T_END = T0 + 2.0 * PERIOD
N_GRID = 2001
TARGET = 1e-6

# Self-check values: HandPress::rhs of the Rust crate at 23 states, printed with Rust's
# round-trip `{:?}` formatting by a throwaway binary depending on the crate by path
# (`lash-benches = { path = "<repo>/benches" }`, `cargo run --release`) that does:
#   let m = lash_benches::press("lubricated_150rpm_c0.1", 2.0);
#   lubricated states: HandPress::minimal_state of lash's DOP853 run of m
#     (lash_benches::options(Method::Dop853, 1e-10, 1e-13, ..), Output::Times at
#     t = 0, 1e-3, 0.013, 0.1, 0.25, 0.4, 0.55, 0.7, 0.8);
#   contact states j = 0..3: the state at t = 0.25 with x moved so that |e| = c + dd,
#     dd = 3e-6, 2e-5, 3e-6, 5e-7, psi_dot += 0, 0, 1.5e-4/0.35, -1e-3, x_dot += 1e-3 j,
#     evaluated with HandPress::paper(150.0, 1e-4, true) ("lub", film capped + contact) and
#     with HandPress::paper(150.0, 1e-4, false) ("dry");
#   and at the state j = 0 with psi_dot = 0.4170357600896645 (|v_T| = 1.5e-4 m/s, inside the
#     friction ramp), psi_dot = 0.4165344302278088 (|v_T| = 5e-5 m/s, below v0) and with
#     x_dot += 10 m/s (F_N clipped at 0), lubricated and dry ("ramp", "slow", "clip");
#   then for each state: h.rhs(t, &y, &mut dy); println!("{t:?} {y:?} {dy:?}").
# Entries: (name, lubricated, t, y, dy).
SELF_CHECK = (
    ("lub0", True, 0.0,
     (0.0, 0.365, -0.6731984257692414, -3.3312030031292053e-18),
     (-0.6731984257692414, -3.3312030031292053e-18, -42.04285714285715, 2.1889501659731238e-14)),
    ("lub1", True, 0.001,
     (-0.0006738862448744406, 0.3649984774614708, -0.6738528244462727, -0.0033676955010066827),
     (-0.6738528244462727, -0.0033676955010066827, 0.2183288112168094, -3.82293617359142)),
    ("lub2", True, 0.013,
     (-0.00869972828687556, 0.36468168497878495, -0.6598916116683348, -0.049285335681675355),
     (-0.6598916116683348, -0.049285335681675355, 2.1407512348461175, -3.7735808104102575)),
    ("lub3", True, 0.1,
     (-0.04291848853191222, 0.34970699223198803, -0.00013355800262575344, -0.23559780626225507),
     (-0.00013355800262575344, -0.23559780626225507, 10.592025594127497, 0.15452870330327517)),
    ("lub4", True, 0.25,
     (0.03029631713281613, 0.3392355560421353, 0.4763764316548811, 0.16144254828654525),
     (0.4763764316548811, 0.16144254828654525, -7.48866112566061, 2.6222110043614295)),
    ("lub5", True, 0.4,
     (-6.59216854468673e-5, 0.3650087154968869, -0.6736909456512634, 0.0001249015470217549),
     (-0.6736909456512634, 0.0001249015470217549, 0.0012021567373012628, -3.859839332771716)),
    ("lub6", True, 0.55,
     (-0.030423104127198418, 0.3392470809992501, 0.4759590529786045, -0.1616167100981222),
     (0.4759590529786045, -0.1616167100981222, 7.471296658907762, 2.6160658632485716)),
    ("lub7", True, 0.7,
     (0.04269745830535225, 0.3496794457039541, -0.0001968075670268979, 0.2355830908356655),
     (-0.0001968075670268979, 0.2355830908356655, -10.578039432408513, 0.1609685030113245)),
    ("lub8", True, 0.8,
     (-0.00016754224308969097, 0.3650065871497053, -0.6730227658426536, 9.819438214603112e-5),
     (-0.6730227658426536, 9.819438214603112e-5, -0.0009040579840223511, -3.8600792465523557)),
    ("lubcontact0", True, 0.25,
     (0.03029631713281613, 0.33912988277999007, 0.4763764316548811, 0.16144254828654525),
     (0.4763764316548811, 0.16144254828654525, 6916.696228122483, 612.0684806473624)),
    ("drycontact0", False, 0.25,
     (0.03029631713281613, 0.33912988277999007, 0.4763764316548811, 0.16144254828654525),
     (0.4763764316548811, 0.16144254828654525, -52.73639704998298, 0.04499887648104158)),
    ("lubcontact1", True, 0.25,
     (0.03029631713281613, 0.33911286875734553, 0.4763764316548811, 0.16244254828654525),
     (0.4763764316548811, 0.16244254828654525, -55497.512590170925, -4955.641048146895)),
    ("drycontact1", False, 0.25,
     (0.03029631713281613, 0.33911286875734553, 0.4763764316548811, 0.16244254828654525),
     (0.4763764316548811, 0.16244254828654525, -50.439667072091595, 0.7746768894201487)),
    ("lubcontact2", True, 0.25,
     (0.03029631713281613, 0.33912988277999007, 0.4768050030834525, 0.16344254828654525),
     (0.4768050030834525, 0.16344254828654525, -123761.8573765213, -10677.023570305513)),
    ("drycontact2", False, 0.25,
     (0.03029631713281613, 0.33912988277999007, 0.4768050030834525, 0.16344254828654525),
     (0.4768050030834525, 0.16344254828654525, -52.73645354965084, 0.04498281559420549)),
    ("lubcontact3", True, 0.25,
     (0.03029631713281613, 0.3391323852428314, 0.4753764316548811, 0.16444254828654525),
     (0.4753764316548811, 0.16444254828654525, -180329.18478232756, -15666.027507179568)),
    ("drycontact3", False, 0.25,
     (0.03029631713281613, 0.3391323852428314, 0.4753764316548811, 0.16444254828654525),
     (0.4753764316548811, 0.16444254828654525, -52.88374093389988, 0.003060842746862812)),
    ("lubramp", True, 0.25,
     (0.03029631713281613, 0.33912988277999007, 0.4170357600896645, 0.16144254828654525),
     (0.4170357600896645, 0.16144254828654525, 351204.20073625265, 23738.855083350645)),
    ("dryramp", False, 0.25,
     (0.03029631713281613, 0.33912988277999007, 0.4170357600896645, 0.16144254828654525),
     (0.4170357600896645, 0.16144254828654525, -52.721951521612084, 0.045001305883527076)),
    ("lubslow", True, 0.25,
     (0.03029631713281613, 0.33912988277999007, 0.4165344302278088, 0.16144254828654525),
     (0.4165344302278088, 0.16144254828654525, 354112.8711295153, 23934.237910109947)),
    ("dryslow", False, 0.25,
     (0.03029631713281613, 0.33912988277999007, 0.4165344302278088, 0.16144254828654525),
     (0.4165344302278088, 0.16144254828654525, -52.707548813283964, 0.04499154409886834)),
    ("lubclip", True, 0.25,
     (0.03029631713281613, 0.33912988277999007, 0.4763764316548811, 10.161442548286546),
     (0.4763764316548811, 10.161442548286546, -640953249.9561683, -55609714.36245541)),
    ("dryclip", False, 0.25,
     (0.03029631713281613, 0.33912988277999007, 0.4763764316548811, 10.161442548286546),
     (0.4763764316548811, 10.161442548286546, -52.894696003278334, -0.0)),
)


def self_check(lub, dry):
    """Asserts the port against the Rust values; returns the largest relative difference."""
    # Parameters as Rust's Debug print of HandPress::paper(150.0, 1e-4, true) shows them.
    assert lub.rj == 0.0499 and lub.i_rod == 4.211243749999999, (lub.rj, lub.i_rod)
    assert lub.omega == 15.707963267948966, lub.omega
    worst = 0.0
    for name, lubricated, t, y, dy in SELF_CHECK:
        got = (lub if lubricated else dry).rhs(t, y)
        for i in range(4):
            rel = abs(got[i] - dy[i]) / abs(dy[i]) if dy[i] != 0.0 else abs(got[i])
            assert rel <= 1e-12, f"{name}[{i}]: {got[i]!r} against Rust {dy[i]!r} ({rel:.1e})"
            worst = max(worst, rel)
    return worst


def grid(a, b, n):
    """lash_benches::grid: n equally spaced times from a to b, both included."""
    return np.array([b if i + 1 == n else a + (b - a) * i / (n - 1) for i in range(n)])


def run(press, method, rtol, times):
    """One solve_ivp run; x_ddot at `times` and the counters."""
    calls = [0]

    def fun(t, y):
        calls[0] += 1
        return press.rhs(t, y)

    atol = np.full(4, rtol * 1e-3)
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol = solve_ivp(fun, (T0, T_END), np.array(Y0), method=method, rtol=rtol,
                        atol=atol, dense_output=True)
    wall = time.perf_counter() - start
    if sol.status != 0:
        return dict(method=method, rtol=rtol, failed=sol.message, wall=wall)
    ys = sol.sol(times).tolist()
    acc = np.array([press.accelerations(t, ys[0][k], ys[1][k], ys[2][k], ys[3][k])[1]
                    for k, t in enumerate(times)])
    return dict(method=method, rtol=rtol, acc=acc, steps=len(sol.t) - 1,
                early=int(np.count_nonzero(sol.t[1:] < 0.05)), nfev=sol.nfev,
                njev=sol.njev, nlu=sol.nlu, rhs=calls[0], wall=wall)


HEADER = ("| method | rtol | error (m/s²) | steps | t<0.05 | nfev | njev | nlu "
          "| rhs (counted) | nfev+4·njev |")


def row(r):
    """One table row of a successful run, in the columns of HEADER."""
    return (f"| {r['method']} | {r['rtol']:.2e} | {r['error']:.2e} | {r['steps']} "
            f"| {r['early']} | {r['nfev']} | {r['njev']} | {r['nlu']} | {r['rhs']} "
            f"| {r['nfev'] + 4 * r['njev']} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="half-decade scan")
    ap.add_argument("--max-wall", type=float, default=60.0)
    args = ap.parse_args()
    t_script = time.perf_counter()
    lub = HandPress(150.0, 1e-4, True)
    dry = HandPress(150.0, 1e-4, False)
    worst = self_check(lub, dry)
    print(f"self-check: the Python RHS equals the Rust HandPress::rhs at {len(SELF_CHECK)} "
          f"states to {worst:.1e} relative (asserted <= 1e-12)")

    times = grid(PERIOD, 2.0 * PERIOD, N_GRID)
    print("\nreferences (atol = rtol*1e-3), error over the second revolution:")
    refs = {}
    for method in ("Radau", "BDF", "LSODA", "DOP853"):
        r = run(lub, method, 1e-13, times)
        if "failed" in r:
            print(f"  {method} rtol 1e-13 failed: {r['failed']}")
            continue
        refs[method] = r
        print(f"  {method:5} rtol 1e-13: {r['steps']} steps, {r['rhs']} RHS calls, "
              f"{r['wall']:.1f} s")
    ref = refs["Radau"]["acc"]
    for method, r in refs.items():
        if method != "Radau":
            print(f"  max |{method}(1e-13) - Radau(1e-13)| = "
                  f"{np.max(np.abs(r['acc'] - ref)):.2e} m/s^2")
    print(f"  max |x_ddot_ref| = {np.max(np.abs(ref)):.3f} m/s^2")
    floor = max(np.max(np.abs(r["acc"] - ref)) for r in refs.values())

    step = 2 if args.quick else 1
    rtols = [10.0 ** (-6.0 - k / 4.0) for k in range(0, 25, step)]
    runs = []
    for method in ("Radau", "BDF", "LSODA"):
        for rtol in rtols:
            r = run(lub, method, rtol, times)
            if "failed" not in r:
                r["error"] = float(np.max(np.abs(r["acc"] - ref)))
            runs.append(r)
            if r["wall"] > args.max_wall:
                print(f"  {method}: rtol {rtol:.2e} took {r['wall']:.0f} s; "
                      "tighter tolerances skipped")
                break

    print(f"\nscan, atol = rtol*1e-3 (errors below {floor:.0e} m/s², the references' "
          "disagreement, are not resolved):")
    print("\n" + HEADER + " wall (s) |")
    print("|---" * 11 + "|")
    for r in runs:
        if "failed" in r:
            print(f"| {r['method']} | {r['rtol']:.2e} | failed: {r['failed']} "
                  "| | | | | | | | |")
            continue
        print(row(r) + f" {r['wall']:.2f} |")

    print(f"\ncheapest run with error <= {TARGET:.0e} m/s² (by counted RHS calls):\n")
    print(HEADER)
    print("|---" * 10 + "|")
    best = {}
    for method in ("Radau", "BDF", "LSODA"):
        ok = [r for r in runs if r["method"] == method and "failed" not in r
              and r["error"] <= TARGET]
        if not ok:
            print(f"| {method} | none reached {TARGET:.0e} | | | | | | | | |")
            continue
        r = best[method] = min(ok, key=lambda r: r["rhs"])
        print(row(r))
    if "Radau" in best and "BDF" in best:
        a, b = best["Radau"], best["BDF"]
        print(f"\nRadau / BDF at error <= {TARGET:.0e}: RHS calls {a['rhs'] / b['rhs']:.2f}x, "
              f"Jacobians {a['njev'] / b['njev']:.2f}x, LU (scipy's count) "
              f"{a['nlu'] / b['nlu']:.2f}x, steps {a['steps'] / b['steps']:.2f}x")
    print(f"\nscript wall time {time.perf_counter() - t_script:.0f} s")


if __name__ == "__main__":
    sys.exit(main())
