"""What one call of a Python right-hand side costs inside lash.solve_ivp (BENCHMARKS.md,
"Python").

    python python/bench/callbacks.py [--repeat N]

The harmonic oscillator y'' = -y over t in [0, 2000] with dopri54 at rtol 1e-10 (about
420 000 calls of fun; the solver's own work per call is a few ns for n = 2). Per way of writing
fun (returning a list, a tuple, or a numpy array): the best time of the solve divided by the
calls of fun, and the time of fun alone called from Python (timeit) on an array of the same
shape; their difference is what lash adds per call (making the array y, calling fun, reading
its result). scipy's RK45 on the same problem gives its cost per call for comparison (when
scipy is installed).
"""

import argparse
import timeit
import time

import numpy as np

import lash

C = np.array([1.0, -1.0])
FUNS = {
    "list": lambda t, y: [y[1], -y[0]],
    "tuple": lambda t, y: (y[1], -y[0]),
    "ndarray": lambda t, y: C * y[::-1],
}


def best(solve, repeat):
    times, sol = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        sol = solve()
        times.append(time.perf_counter() - t)
    return min(times), sol


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args()
    y = np.array([1.0, 0.5])
    try:
        import scipy.integrate as si
    except ImportError:
        si = None
    print(f"{'fun returns':12s} {'calls':>7s} {'per call':>9s} {'fun alone':>9s} "
          f"{'lash adds':>9s} {'scipy RK45 per call':>20s}")
    for name, f in FUNS.items():
        total, sol = best(lambda: lash.solve_ivp(f, (0, 2000), [1.0, 0.0], method="dopri54",
                                                 rtol=1e-10, atol=1e-12), a.repeat)
        alone = min(timeit.repeat(lambda: f(0.1, y), number=100_000, repeat=5)) / 100_000
        per = total / sol.nfev
        sp = ""
        if si is not None:
            st, ss = best(lambda: si.solve_ivp(f, (0, 2000), [1.0, 0.0], method="RK45",
                                               rtol=1e-10, atol=1e-12), 1)
            sp = f"{st / ss.nfev * 1e6:17.2f} µs"
        print(f"{name:12s} {sol.nfev:7d} {per * 1e6:6.2f} µs {alone * 1e6:6.2f} µs "
              f"{(per - alone) * 1e6:6.2f} µs {sp}")


if __name__ == "__main__":
    main()
