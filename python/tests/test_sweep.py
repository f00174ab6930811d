"""lash.sweep: the engine's points (same ids, params and numbers as ``lash sweep``), in the
command's directory layout (``lash merge`` joins it), on a process pool, on a
dask.distributed cluster started here, and in process; bad sweeps fail before anything runs;
failed points are rows."""

import concurrent.futures
import csv
import json
import os
import pathlib
import subprocess

import pytest

import lash

ROOT = pathlib.Path(__file__).resolve().parents[2]
LUBRICATED = ROOT / "cases" / "press" / "lubricated_150rpm_c0.1.json"
#: Two clearances × two tolerances of the lubricated press (about 0.1 s a point).
GRID = {"case": str(LUBRICATED), "clearance": [1e-4, 2e-4], "rtol": [1e-6, 1e-7]}


def lash_bin():
    path = pathlib.Path(os.environ.get("LASH_BIN", ROOT / "target" / "release" / "lash"))
    if not path.is_file():
        pytest.fail(f"the lash command is not built at {path}: run `cargo build --release` "
                    "(or set LASH_BIN)")
    return path


def sweep_file(tmp_path, spec=GRID):
    f = tmp_path / "grid.json"
    f.write_text(json.dumps(spec))
    return f


def results(out):
    """{id: result.json} of a sweep directory, and its points.json."""
    manifest = json.loads((out / "points.json").read_text())
    return manifest, {p["id"]: json.loads((out / p["id"] / "result.json").read_text())
                      for p in manifest["points"]}


def timeless(values):
    """A point's values without its wall times (the only numbers that differ run to run)."""
    return {k: v for k, v in values.items() if "wall_time" not in k}


def assert_same_sweep(ours, theirs):
    m1, r1 = results(ours)
    m2, r2 = results(theirs)
    assert m1 == m2  # same grid: indices, ids (hashes) and params
    assert r1.keys() == r2.keys()
    for pid in r1:
        a, b = r1[pid], r2[pid]
        assert (a["index"], a["params"], a["status"], a["error"]) == \
            (b["index"], b["params"], b["status"], b["error"])
        # Every metric to the last digit (JSON numbers compared as the floats they are).
        assert timeless(a["values"]) == timeless(b["values"]), pid
        assert a["values"]["metrics.slider_acc_max"] > 0


def assert_frame_is_the_directory(df, out):
    manifest, recs = results(out)
    assert list(df["index"]) == [p["index"] for p in manifest["points"]]
    assert list(df["id"]) == [p["id"] for p in manifest["points"]]
    assert list(df["clearance"]) == [1e-4, 1e-4, 2e-4, 2e-4]
    assert list(df["rtol"]) == [1e-6, 1e-7, 1e-6, 1e-7]
    assert set(df["status"]) == {"ok"} and df["error"].isna().all()
    for _, row in df.iterrows():
        assert row["metrics.slider_acc_max"] == recs[row["id"]]["values"]["metrics.slider_acc_max"]
        assert row["metrics.eps_max"] == recs[row["id"]]["values"]["metrics.eps_max"]


def test_a_process_pool_sweep_is_lash_sweep_point_for_point_and_merges(tmp_path):
    f = sweep_file(tmp_path)
    cli = tmp_path / "cli"
    subprocess.run([str(lash_bin()), "sweep", str(f), "--out", str(cli), "--jobs", "1"],
                   check=True, capture_output=True)
    out = tmp_path / "py"
    with concurrent.futures.ProcessPoolExecutor(2) as pool:
        df = lash.sweep(f, executor=pool, out=out)
    assert df.attrs["out"] == str(out)
    assert_same_sweep(out, cli)
    assert_frame_is_the_directory(df, out)
    # `lash merge` joins the directory Python filled: one row per point.
    subprocess.run([str(lash_bin()), "merge", str(out)], check=True, capture_output=True)
    with open(out / "merged.csv", newline="") as fh:
        merged = list(csv.DictReader(fh))
    assert sorted(r["id"] for r in merged) == sorted(df["id"])


def test_in_process_sweep_of_a_dict_is_the_files(tmp_path):
    f = sweep_file(tmp_path)
    by_file = lash.sweep(f, out=tmp_path / "file", jobs=2)
    by_dict = lash.sweep(dict(GRID), out=tmp_path / "dict")
    assert_same_sweep(tmp_path / "dict", tmp_path / "file")
    assert_frame_is_the_directory(by_dict, tmp_path / "dict")
    keep = [c for c in by_file.columns if "wall_time" not in c]
    assert by_dict[keep].equals(by_file[keep])


def test_a_dask_cluster_runs_the_points(tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    f = sweep_file(tmp_path)
    out = tmp_path / "dask"
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        df = lash.sweep(f, executor=client, out=out)
        assert_frame_is_the_directory(df, out)
        # Its concurrent.futures face too; the rerun finds every point done (result.json
        # untouched) and gives the same rows.
        before = {p: (out / p / "result.json").stat().st_mtime_ns for p in df["id"]}
        again = lash.sweep(f, executor=client.get_executor(), out=out)
        assert {p: (out / p / "result.json").stat().st_mtime_ns for p in df["id"]} == before
    assert again.equals(df)
    in_process = tmp_path / "here"
    lash.sweep(f, out=in_process)
    assert_same_sweep(out, in_process)


@pytest.mark.parametrize("spec, fragment", [
    ({"case": str(LUBRICATED), "mu": [0.1]}, "mu"),
    ({"case": str(LUBRICATED), "clearance": []}, "clearance"),
    ({"case": str(LUBRICATED), "set": {"joints[99].friction.mu": [0.1]}}, "joints[99]"),
])
def test_a_bad_sweep_fails_naming_the_key_before_anything_runs(tmp_path, spec, fragment):
    out = tmp_path / "never"
    with pytest.raises((lash.SceneError, lash.UsageError)) as e:
        lash.sweep(spec, out=out)
    assert fragment in str(e.value)
    assert not out.exists()
    with pytest.raises((lash.SceneError, lash.UsageError)):
        lash.sweep(spec, executor=concurrent.futures.ThreadPoolExecutor(1), out=out)
    assert not out.exists()


def test_failed_points_are_rows(tmp_path):
    # RK4 at a step far beyond its stability limit: a solver failure, recorded as finished.
    spec = {"case": str(LUBRICATED), "method": ["rk4"], "step": [1e-2]}
    df = lash.sweep(spec, out=tmp_path / "rk4")
    assert list(df["status"]) == ["solver_failed"]
    assert df["error"][0].startswith("solver failed: ")
    # A task that fails otherwise (its output directory cannot be made): a row with the
    # error, not recorded, so a rerun tries it again.
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        df = lash.sweep(GRID, executor=pool, out=blocker / "out")
    assert len(df) == 4 and set(df["status"]) == {"failed"}
    assert all(isinstance(e, str) and e for e in df["error"])
