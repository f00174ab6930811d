"""What a scene run costs from Python, against the same run by the engine alone and by the
command line (BENCHMARKS.md, "Python").

    python python/bench/overhead.py [SCENE] [--repeat N] [--lash PATH]

Per repetition, interleaved: lash.run(SCENE) timed around the call (perf_counter), the
engine's own time inside that call (Run.engine_time_s: reading the scene and the run with its
outputs and metrics, without Python), the integration alone (summary wall_time_s), and
`lash run SCENE` as a process (writes trajectory.csv, summary.json and the figures). Prints the
medians and the ratios, and the quartiles of what each call added to its own engine time.
"""

import argparse
import pathlib
import statistics
import subprocess
import tempfile
import time

import lash

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene", nargs="?", default=str(ROOT / "cases/press/dry_150rpm_c0.1.json"))
    ap.add_argument("--repeat", type=int, default=11)
    ap.add_argument("--lash", default=str(ROOT / "target/release/lash"))
    a = ap.parse_args()
    lash.run(a.scene)  # warm-up: imports, page cache
    py, engine, integ, cli = [], [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(a.repeat):
            t = time.perf_counter()
            r = lash.run(a.scene)
            py.append(time.perf_counter() - t)
            engine.append(r.engine_time_s)
            integ.append(r.summary["wall_time_s"])
            t = time.perf_counter()
            subprocess.run([a.lash, "run", a.scene, "--out", f"{tmp}/out"], check=True,
                           capture_output=True)
            cli.append(time.perf_counter() - t)
    m = statistics.median
    print(f"scene {pathlib.Path(a.scene).name}, {a.repeat} repetitions (medians)")
    print(f"  lash.run (whole call)          {m(py) * 1e3:8.1f} ms")
    print(f"  engine inside it (no Python)   {m(engine) * 1e3:8.1f} ms")
    print(f"  integration (wall_time_s)      {m(integ) * 1e3:8.1f} ms")
    print(f"  lash run (process, files)      {m(cli) * 1e3:8.1f} ms")
    print(f"  Python's cost over the engine  {(m(py) / m(engine) - 1) * 100:8.2f} %")
    # Per call, paired: what each lash.run added to its own engine time (quartiles, ms).
    extra = sorted(p - e for p, e in zip(py, engine))
    q = statistics.quantiles(extra, n=4) if len(extra) > 1 else extra * 3
    print(f"  lash.run - engine, per call    {q[0] * 1e3:.2f} / {q[1] * 1e3:.2f} / "
          f"{q[2] * 1e3:.2f} ms (quartiles; min {extra[0] * 1e3:.2f} ms)")
    print(f"  lash.run / lash run            {m(py) / m(cli):8.3f}")


if __name__ == "__main__":
    main()
