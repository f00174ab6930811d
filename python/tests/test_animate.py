"""Run.animate(): the page `lash animate` writes, from a run held in Python.

The page is built by the same engine function from the same numbers (lash.run's columns
are trajectory.csv's bit for bit, tests/test_run.py), so the page of a Python run equals the
file `lash run --animate` writes for the same scene and options, byte for byte. The command
is $LASH_BIN, else target/release/lash of this checkout.
"""

import html
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import lash

ROOT = pathlib.Path(__file__).resolve().parents[2]
FOURBAR = ROOT / "cases" / "examples" / "fourbar_clearance.json"


def lash_bin():
    path = pathlib.Path(os.environ.get("LASH_BIN", ROOT / "target" / "release" / "lash"))
    if not path.is_file():
        pytest.fail(f"the lash command is not built at {path}: run `cargo build --release` "
                    "(or set LASH_BIN)")
    return path


def page_data(page):
    """The JSON the page parses (its lash-data script element)."""
    start = page.index('<script id="lash-data" type="application/json">')
    start = page.index(">", start) + 1
    return json.loads(page[start:page.index("</script>", start)])


def test_the_page_of_a_python_run_is_the_commands(tmp_path):
    out = tmp_path / "fb"
    subprocess.run([str(lash_bin()), "run", str(FOURBAR), "--t-end", "0.3", "--animate",
                    "--out", str(out)], check=True, capture_output=True)
    r = lash.run(FOURBAR, t_end=0.3)
    a = r.animate()
    assert isinstance(a, lash.Animation)
    assert a.html == (out / "animation.html").read_text(encoding="utf-8")
    # The scene it ran is the file's text (what the command keeps as scene.json).
    assert r.scene == (out / "scene.json").read_text(encoding="utf-8")


def test_the_pages_geometry_is_the_runs_columns():
    r = lash.run(FOURBAR, t_end=0.3)
    d = page_data(r.animate(trace="coupler.B", column="rocker.theta").html)
    rows = len(r.columns["t"])
    assert d["rows"] == rows and d["stride"] == 1 and len(d["t"]) == rows
    np.testing.assert_array_equal(d["t"], r.columns["t"])
    for b in d["bodies"]:
        for q in ("x", "y", "theta"):
            # 7 significant digits: what the display needs.
            np.testing.assert_allclose(b[q], r.columns[f"{b['name']}.{q}"], rtol=5e-7,
                                       atol=0, err_msg=f"{b['name']}.{q}")
    c = d["clearance"][0]
    np.testing.assert_allclose(c["ex"], r.columns["coupler_rocker.ex_over_c"], rtol=5e-7)
    assert c["film_r"] is None, "a dry joint has no film"
    assert (d["trace"], d["column"]) == ("coupler.B", "rocker.theta")
    assert d["title"] == "fourbar_clearance, bdf rtol 1e-8"


def test_repr_html_frames_the_page_in_a_sandboxed_iframe(tmp_path):
    a = lash.run(FOURBAR, t_end=0.1).animate(max_frames=50)
    frame = a._repr_html_()
    assert frame.startswith('<iframe srcdoc="') and 'sandbox="allow-scripts"' in frame
    # The page sits escaped in the attribute: nothing of it can close the iframe early.
    inner = frame[len('<iframe srcdoc="'):frame.index('" style=')]
    assert "<" not in inner and '"' not in inner
    assert html.unescape(inner) == a.html
    assert len(page_data(a.html)["t"]) <= 50
    a.save(tmp_path / "a.html")
    assert (tmp_path / "a.html").read_text(encoding="utf-8") == a.html


def test_what_cannot_be_animated_says_why():
    with pytest.raises(lash.UsageError, match="needs a scene"):
        lash.run("testset:rober").animate()
    r = lash.run(FOURBAR, t_end=0.05)
    with pytest.raises(lash.UsageError, match="'crank.Z' is no body or body point"):
        r.animate(trace="crank.Z")
    with pytest.raises(lash.UsageError, match="max_frames must be a whole number >= 2"):
        r.animate(max_frames=1)
    with pytest.raises(lash.UsageError, match="no filled column"):
        r.animate(column="slider_x")
    # A dict scene keeps its JSON text.
    scene = json.loads(FOURBAR.read_text())
    d = lash.run(scene, t_end=0.05, name="fb")
    assert json.loads(d.scene) == scene
    assert page_data(d.animate().html)["title"].startswith("fb, bdf")
