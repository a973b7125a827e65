"""The identified model: save, load, prediction uncertainty; the vehicle."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

import mrsysid

from conftest import SWEEP, read_log


def test_saved_model_predicts_the_same_with_its_uncertainty(flight_fit, tmp_path: Path):
    path = tmp_path / "model.toml"
    model = flight_fit.model
    model.save(path)
    back = mrsysid.load_model(path)
    pd.testing.assert_frame_equal(back.parameters, model.parameters, check_exact=True)
    states = read_log(SWEEP).iloc[:200]
    std = back.prediction_std(states)
    assert std is not None and list(std.columns) == ["fx", "fy", "fz", "mx", "my", "mz"]
    assert np.isfinite(std.to_numpy()).all() and (std.to_numpy() >= 0).all()
    pd.testing.assert_frame_equal(std, model.prediction_std(states), check_exact=True)
    # The thrust's uncertainty is not zero where the rotors turn.
    assert (std["fz"] > 0).all()


def test_predict_keeps_the_index_and_ignores_measured_columns(flight_fit):
    states = read_log(SWEEP).iloc[10:20]
    without = states.drop(columns=["fx", "fy", "fz", "mx", "my", "mz", "t"])
    a, b = flight_fit.model.predict(states), flight_fit.model.predict(without)
    assert list(a.index) == list(states.index)
    pd.testing.assert_frame_equal(a, b, check_exact=True)


def test_vehicle_properties(quad_x):
    assert (quad_x.name, quad_x.rotor_count, quad_x.configuration) == (
        "example-quad-x", 4, "quadrotorx")
    assert quad_x.mass > 0 and quad_x.notes() == []
