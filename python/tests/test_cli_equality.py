"""A fit from Python is the CLI's fit: the same report, parameters and decisions."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

import mrsysid

from conftest import FLIGHT, QUAD_X, SWEEP, read_log, run_cli

# The same library code on the same data gives the same bits; 1e-12 relative is the
# issue's bar (it allows for a different build profile of the binary).
RTOL = 1e-12


def close(a: float, b: float) -> bool:
    return a == b or math.isclose(a, b, rel_tol=RTOL, abs_tol=0.0)


def assert_close_tree(a, b, path="report"):
    """Equal JSON trees, numbers to RTOL relative (`tool_version` aside)."""
    if isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for k in a:
            if k != "tool_version":
                assert_close_tree(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for k, (x, y) in enumerate(zip(a, b)):
            assert_close_tree(x, y, f"{path}[{k}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert close(float(a), float(b)), f"{path}: {a} != {b}"
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


def test_report_and_final_model_equal_the_cli(cli, tmp_path: Path, flight_fit):
    report, model = tmp_path / "report.json", tmp_path / "model.toml"
    run_cli(cli, "fit", FLIGHT, "--vehicle", QUAD_X, "--json", report,
            "--model-out", model, "--threads", "2", "--quiet")
    theirs = json.loads(report.read_text())
    ours = flight_fit.report()
    # The whole report: Eq. 22 estimates (Table 5), metrics, FSOA, the diagnosis.
    assert_close_tree(ours, theirs)
    # The same decisions: effects added and terms left out, in order.
    assert ours["diagnosis"]["effects_added"], "the shipped log lacks quadratic drag"
    names = lambda r: [e["name"] for e in r["diagnosis"]["effects_added"]]
    assert names(ours) == names(theirs)
    assert [u["name"] for u in ours["diagnosis"]["unsupported"]] == [
        u["name"] for u in theirs["diagnosis"]["unsupported"]
    ]
    # The final model's parameters equal those of the CLI's model file.
    saved = mrsysid.load_model(model).parameters
    p = flight_fit.parameters
    assert list(p.index) == list(saved.index)
    np.testing.assert_allclose(p["estimate"], saved["estimate"], rtol=RTOL, atol=0)
    np.testing.assert_allclose(p["std"], saved["std"], rtol=RTOL, atol=0)
    assert (p["unit"] == saved["unit"]).all()


def test_predictions_equal_the_cli_predict(cli, tmp_path: Path, flight_fit):
    model, out = tmp_path / "model.toml", tmp_path / "predicted.csv"
    flight_fit.model.save(model)
    run_cli(cli, "predict", "--model", model, SWEEP, "--out", out)
    theirs = read_log(out)
    states = read_log(SWEEP)
    ours = mrsysid.load_model(model)
    from_states = ours.predict(states)
    from_log = ours.predict_log(SWEEP)
    cols = ["fx", "fy", "fz", "mx", "my", "mz"]
    np.testing.assert_allclose(from_states[cols], theirs[cols], rtol=RTOL, atol=0)
    np.testing.assert_allclose(from_log[["t"] + cols], theirs[["t"] + cols], rtol=RTOL, atol=0)
    # The model in memory predicts what the saved one does (TOML keeps f64 exactly).
    pd.testing.assert_frame_equal(flight_fit.model.predict(states), from_states, check_exact=True)


def test_an_estimated_loads_cut_off_and_kept_ground_equal_the_cli(cli, tmp_path: Path, quad_x):
    """`loads_low_pass="estimate"` scans cut-offs as `--loads-low-pass estimate` does
    (the shipped flight's loads were not smoothed: none is kept), and `keep_ground`
    is `--keep-ground`."""
    report = tmp_path / "estimated.json"
    run_cli(cli, "fit", FLIGHT, "--vehicle", QUAD_X, "--json", report, "--no-diagnose",
            "--loads-low-pass", "estimate", "--keep-ground", "--threads", "2", "--quiet")
    theirs = json.loads(report.read_text())
    ours = mrsysid.fit(quad_x, logs=FLIGHT, diagnose=False, threads=2,
                       loads_low_pass="estimate", keep_ground=True).report()
    assert_close_tree(ours, theirs)
    scan = ours["loads_low_pass_scan"]
    assert scan["chosen_hz"] is None and "loads_low_pass_hz" not in ours
    assert scan["points"][0]["cutoff_hz"] is None and len(scan["points"]) >= 4
    try:
        mrsysid.fit(quad_x, logs=FLIGHT, loads_low_pass="guess")
    except ValueError as e:
        assert "estimate" in str(e)
    else:
        raise AssertionError("loads_low_pass='guess' was taken")
