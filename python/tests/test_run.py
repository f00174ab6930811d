"""lash.run: scenes run by lash's engine from Python, against the command line's own files.

The command line (`lash run`) and lash.run call the same engine
(lash_validation::run and run_in_memory) with the same options, so every number of
summary.json except the measured wall time, and every cell of trajectory.csv, must be equal
bit for bit: trajectory.csv writes each number in the shortest form that reads back to the
same f64 (crates/validation/src/report/trajectory.rs), so float() of a cell is the f64 the run made.
The command is the release binary of this checkout: $LASH_BIN, else target/release/lash
(.ci/run builds it first).
"""

import concurrent.futures
import copy
import csv
import json
import math
import os
import pathlib
import subprocess
import threading
import time

import numpy as np
import pytest

import lash

ROOT = pathlib.Path(__file__).resolve().parents[2]
PRESS = ROOT / "cases" / "press"
DRY = PRESS / "dry_150rpm_c0.1.json"
LUBRICATED = PRESS / "lubricated_150rpm_c0.1.json"
IDEAL = PRESS / "ideal_150rpm.json"


def lash_bin():
    path = pathlib.Path(os.environ.get("LASH_BIN", ROOT / "target" / "release" / "lash"))
    if not path.is_file():
        pytest.fail(f"the lash command is not built at {path}: run `cargo build --release` "
                    "(or set LASH_BIN)")
    return path


def cli_run(tmp_path, scene, *flags):
    out = tmp_path / "out"
    subprocess.run([str(lash_bin()), "run", str(scene), "--out", str(out), *flags],
                   check=True, capture_output=True)
    summary = json.loads((out / "summary.json").read_text())
    with open(out / "trajectory.csv", newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    columns = {name: np.array([float(r[k]) if r[k] != "" else math.nan for r in body])
               for k, name in enumerate(header)}
    return summary, columns


def without_wall_time(summary):
    s = copy.deepcopy(summary)
    assert s.pop("wall_time_s") > 0
    return s


def assert_same_columns(ours, theirs):
    assert list(ours) == list(theirs)
    for name in theirs:
        # equal_nan: a column the scene lacks is empty in the CSV, NaN in both.
        np.testing.assert_array_equal(ours[name], theirs[name], err_msg=name)


@pytest.mark.parametrize("scene, flags, kwargs", [
    (DRY, [], {}),
    (LUBRICATED, ["--method", "rodas5p", "--rtol", "1e-7", "--samples-per-revolution", "500"],
     {"method": "rodas5p", "rtol": 1e-7, "samples_per_revolution": 500}),
    (DRY, ["--method", "rk4", "--step", "2e-5", "--t-end", "0.2"],
     {"method": "rk4", "step": 2e-5, "t_end": 0.2}),
])
def test_the_press_run_equals_the_commands_files(tmp_path, scene, flags, kwargs):
    summary, columns = cli_run(tmp_path, scene, *flags)
    r = lash.run(scene, **kwargs)
    assert without_wall_time(r.summary) == without_wall_time(summary)
    assert_same_columns(r.columns, columns)
    assert r.summary["wall_time_s"] <= r.engine_time_s


def test_events_are_the_runs_contacts():
    """Every contact onset of the dry press is followed by a loss of contact (it ends in
    flight or the run ends), and the onsets inside the metrics window (the last revolution,
    docs/outputs.md) are the summary's contact_onsets. The dry joint's laws have kinks, so the
    run also restarts at those by default (docs/model.md §7, "The default")."""
    r = lash.run(DRY)
    assert r.summary["kink_events"] is True
    assert r.summary["events"] == len(r.events) > 0
    times = [e.time for e in r.events]
    assert times == sorted(times)
    assert {e.name for e in r.events} == {"rod_slider"}
    assert {e.kind for e in r.events if not e.kind.startswith("contact")} <= {
        f"kink_{k}_{d}" for k in ("full_damping", "force_clip", "slip_v0", "slip_v1")
        for d in ("rising", "falling")}
    kinds = [e.kind for e in r.events if e.kind.startswith("contact")]
    assert set(kinds) == {"contact_onset", "contact_loss"}
    # Onsets and losses alternate, starting with an onset (the journal starts centred).
    assert all(k == ("contact_onset" if i % 2 == 0 else "contact_loss")
               for i, k in enumerate(kinds))
    period = 60.0 / 150.0
    window_start = r.summary["t_end"] - period
    onsets = sum(e.kind == "contact_onset" and e.time >= window_start for e in r.events)
    assert onsets == r.summary["metrics"]["contact_onsets"]
    # The clearance joint's eccentricity is 1 at each contact event (δ = |e| − c = 0; the
    # kinks lie inside contact, at δ > 0).
    t = r.columns["t"]
    eps = np.hypot(r.columns["ex_over_c"], r.columns["ey_over_c"])
    for e in [e for e in r.events if e.kind.startswith("contact")][:6]:
        assert np.interp(e.time, t, eps) == pytest.approx(1.0, abs=0.05)


def test_kink_events_add_kinks_and_keep_the_contacts():
    """With kink events (docs/model.md §7: the dry press's default) the dry press's run
    reports the kinks of its force laws as well; its contact onsets and losses stay those of
    the run with "kink_events": false (the first 0.1 s: seven contact phases, default
    options), to the integration tolerance."""
    scene = json.loads(DRY.read_text())
    assert "kink_events" not in scene
    kinked = lash.run(scene, t_end=0.1)
    scene["kink_events"] = False
    plain = lash.run(scene, t_end=0.1)
    assert kinked.summary["kink_events"] is True and plain.summary["kink_events"] is False
    kinds = {e.kind for e in kinked.events}
    assert {"kink_full_damping_rising", "kink_full_damping_falling",
            "kink_slip_v0_rising", "kink_slip_v0_falling"} <= kinds
    contacts = [(e.time, e.kind) for e in kinked.events if e.kind.startswith("contact")]
    reference = [(e.time, e.kind) for e in plain.events]
    assert [k for _, k in contacts] == [k for _, k in reference]
    assert len(reference) == 15
    for (a, _), (b, _) in zip(contacts, reference):
        assert a == pytest.approx(b, abs=2e-6)
    assert kinked.summary["events"] == len(kinked.events) > len(reference)


def test_a_dict_scene_runs_like_its_file():
    scene = json.loads(LUBRICATED.read_text())
    from_file = lash.run(LUBRICATED, t_end=0.1)
    from_dict = lash.run(scene, t_end=0.1, name="mine")
    assert from_dict.summary["case"] == "mine"
    assert from_dict.summary["scene_sha256"] != from_file.summary["scene_sha256"]
    for key in ("version", "case", "scene_sha256", "wall_time_s"):
        from_dict.summary.pop(key)
        from_file.summary.pop(key)
    assert from_dict.summary == from_file.summary
    assert_same_columns(from_dict.columns, from_file.columns)


def test_columns_are_the_engines_vectors_and_outlive_the_run():
    """The columns are the engine's own vectors behind numpy's array interface (no copy):
    each is a writable float64 array that keeps its memory alive after the Run and every
    other reference is gone, whatever is allocated meanwhile; the values stay the command's
    (test_the_press_run_equals_the_commands_files)."""
    import gc
    r = lash.run(LUBRICATED, t_end=0.05)
    t, a = r.columns["t"], r.columns["slider_a"]
    expected_t, expected_a = t.copy(), a.copy()
    assert t.dtype == np.float64 and t.flags.writeable and t.flags.c_contiguous
    assert t[0] == 0.0 and t[-1] == 0.05 and np.all(np.diff(t) > 0)
    del r
    gc.collect()
    junk = [np.full(len(t), 7.0) for _ in range(64)]  # reuses freed memory, if any
    assert not np.shares_memory(t, a)
    np.testing.assert_array_equal(t, expected_t)
    np.testing.assert_array_equal(a, expected_a)
    t[0] = -1.0
    assert t[0] == -1.0 and a[0] == expected_a[0] and len(junk) == 64


def test_a_built_in_test_problem_meets_its_reference():
    """VDPOLM of the IVP Test Set through the engine's defaults (rodas5p, rtol 1e-6): the
    summary's reference_error is the engine's own measure against the Test Set's reference
    (lash_solver::testset); at rtol 1e-6 it must stay below 1e-3 (stiff_testset.rs' bound at
    rtol 1e-8 is 1e-5, and the error scales with the tolerance)."""
    r = lash.run("testset:vdpolm")
    assert r.summary["case"] == "testset:vdpolm" and r.summary["method"] == "rodas5p"
    assert r.summary["reference_error"] < 1e-3
    np.testing.assert_allclose(r.summary["final_state"][0], 1.706167732170469, rtol=1e-3)
    # The fixed columns of trajectory.csv are there, the mechanism's ones empty (NaN); the
    # test problem's states come last.
    assert list(r.columns)[-2:] == ["y0", "y1"]
    assert np.all(np.isnan(r.columns["slider_a"]))
    assert r.columns["t"][-1] == 2000.0
    assert r.columns["y0"][-1] == r.summary["final_state"][0]
    assert r.events == []


def test_to_pandas_is_the_csv_as_pandas_reads_it(tmp_path):
    pd = pytest.importorskip("pandas")
    summary, _ = cli_run(tmp_path, IDEAL, "--t-end", "0.1")
    r = lash.run(IDEAL, t_end=0.1)
    df = r.to_pandas()
    theirs = pd.read_csv(tmp_path / "out" / "trajectory.csv")
    assert list(df.columns) == list(theirs.columns)
    pd.testing.assert_frame_equal(df, theirs.astype(np.float64), check_exact=True)


def test_threads_run_scenes_in_parallel_with_the_same_results():
    """Four scenes on a pool of four threads give what they give one by one; and while a scene
    integrates, the GIL is free: a Python loop in the calling thread keeps running."""
    jobs = [(DRY, {"t_end": 0.3}), (LUBRICATED, {"t_end": 0.3}),
            (IDEAL, {"t_end": 0.3}), (DRY, {"t_end": 0.3, "method": "rodas5p"})]
    one_by_one = [lash.run(s, **kw) for s, kw in jobs]
    with concurrent.futures.ThreadPoolExecutor(max_workers=4) as pool:
        together = list(pool.map(lambda job: lash.run(job[0], **job[1]), jobs))
    for a, b in zip(one_by_one, together):
        assert without_wall_time(a.summary) == without_wall_time(b.summary)
        assert_same_columns(a.columns, b.columns)
        assert a.events == b.events

    done = threading.Event()
    worker = threading.Thread(target=lambda: (lash.run(DRY), done.set()))
    spins = 0
    worker.start()
    while not done.is_set():
        spins += 1
    worker.join()
    # The run takes ~0.4 s; with the GIL held throughout, the loop could not run at all
    # (a Rust call does not give the GIL up at the switch interval).
    assert spins > 10_000


def test_a_bad_scene_raises_scene_error_with_its_path():
    scene = json.loads(DRY.read_text())
    k = next(i for i, j in enumerate(scene["joints"]) if j["type"] == "clearance")
    scene["joints"][k]["bearing"]["radius"] = 0
    with pytest.raises(lash.SceneError) as info:
        lash.run(scene)
    e = info.value
    assert e.path == f"joints[{k}].bearing.radius"
    assert e.reason == "bearing radius must be > 0, got 0"
    assert str(e) == f"{e.path}: {e.reason}"

    scene = json.loads(DRY.read_text())
    scene["bodies"][0]["mas"] = 1.0
    with pytest.raises(lash.SceneError) as info:
        lash.run(scene)
    assert info.value.path == "bodies[0].mas"
    assert info.value.reason.startswith("unknown field `mas`")


def test_a_scene_file_that_is_not_json_is_a_scene_error(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text("{oops")
    with pytest.raises(lash.SceneError) as info:
        lash.run(bad)
    assert info.value.path == "."
    assert "not valid JSON" in info.value.reason
    with pytest.raises(FileNotFoundError):
        lash.run(tmp_path / "missing.json")


@pytest.mark.parametrize("kwargs, fragment", [
    ({"method": "rk4"}, "method rk4 is fixed-step and needs step"),
    ({"method": "rk4", "step": 1e-5, "rtol": 1e-6}, "rtol is only for adaptive methods"),
    ({"step": 1e-5}, "step is only for fixed-step methods"),
    ({"controller": "pi"}, "controller does not apply to bdf"),
    ({"method": "euler"}, "unknown method 'euler'"),
    ({"controller": "p"}, "unknown controller 'p'"),
    ({"rtol": 0.0}, "rtol must be in [1e-14, 1)"),
    ({"atol": -1.0}, "atol must be finite and > 0"),
    ({"atol": [1e-9, 1e-9]}, "atol"),
    ({"t_end": -1.0}, "t_end must be a finite number > 0"),
    ({"samples_per_revolution": 0}, "samples_per_revolution must be a whole number >= 1"),
    ({"max_steps": 0}, "max_steps must be a whole number >= 1"),
    ({"max_wall_time": math.inf}, "max_wall_time must be a finite number > 0"),
    ({"samples_per_revolution": 10, "output_every": 1e-3}, "exclude each other"),
    ({"energy_check": 1}, "energy_check must be True or False"),
])
def test_bad_options_raise_usage_error(kwargs, fragment):
    with pytest.raises(lash.UsageError) as info:
        lash.run(DRY, **kwargs)
    assert fragment in str(info.value)
    assert isinstance(info.value, ValueError)


def test_a_broken_energy_balance_raises_unless_the_check_is_left_out():
    """The fuzzed 2 µm film under ESDIRK3(4) (docs/outputs.md, "The energy check of a run"):
    every step passes the error test but the driver's work is ~16 J short of 128 J of flows:
    SolveError of kind energy_balance at the end time; energy_check=False returns the run,
    whose summary shows the balance refused; bdf closes the same scene and passes."""
    scene = ROOT / "crates" / "validation" / "tests" / "data" / "fuzz_2082.json"
    with pytest.raises(lash.SolveError) as info:
        lash.run(scene, method="esdirk34")
    assert info.value.kind == "energy_balance"
    assert info.value.t == 0.01
    assert str(info.value).startswith("energy balance off at t = 1e-2")
    kept = lash.run(scene, method="esdirk34", energy_check=False)
    e = kept.summary["metrics"]["energy"]
    assert e["balance_error"] < -10.0
    assert info.value.y.shape == (12,) and np.all(np.isfinite(info.value.y))
    e = lash.run(scene, method="bdf").summary["metrics"]["energy"]
    assert abs(e["balance_error"]) < 1e-2


def test_a_solver_failure_raises_solve_error_with_time_and_state():
    with pytest.raises(lash.SolveError) as info:
        lash.run(DRY, max_steps=50)
    e = info.value
    assert e.kind == "too_many_steps"
    assert str(e).startswith("too many steps: 50 steps taken")
    # 50 steps of at most T/100 (the step limit near contact of a press run: the dry journal
    # starts at its wall) from t = 0.
    assert 0.0 < e.t <= 50 * 0.4 / 100
    # The state under the default formulation (auto: minimal on the press, a tree): the rod's
    # angle and the slider's x, then their rates; under lagrange_baumgarte (x, y, theta) then
    # the velocities of the three integrated bodies.
    assert e.y.shape == (4,) and np.all(np.isfinite(e.y))
    with pytest.raises(lash.SolveError) as info:
        lash.run(DRY, max_steps=50, formulation="lagrange_baumgarte")
    assert info.value.y.shape == (12,) and np.all(np.isfinite(info.value.y))

    with pytest.raises(lash.SolveError) as info:
        lash.run(DRY, max_wall_time=1e-3)
    assert info.value.kind == "budget_exhausted"
