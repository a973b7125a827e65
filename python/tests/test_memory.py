"""Tables in memory fit as the same data from a file, and are read without copies
where their layout allows."""

from __future__ import annotations

import numpy as np
import pandas as pd

import mrsysid
from mrsysid import _tables

from conftest import FLIGHT, SWEEP, read_log


def decisions(r: mrsysid.Results):
    d = r.report()["diagnosis"]
    return [e["name"] for e in d["effects_added"]], [u["name"] for u in d["unsupported"]]


def test_a_dataframe_fits_as_its_csv(quad_x, flight_fit):
    # The same samples pass through the same chunking, statistics and decisions, so
    # the results are equal to the bit, not just within a tolerance.
    frame = mrsysid.fit(quad_x, samples=read_log(FLIGHT), threads=2)
    pd.testing.assert_frame_equal(frame.parameters, flight_fit.parameters, check_exact=True)
    pd.testing.assert_frame_equal(frame.metrics, flight_fit.metrics, check_exact=True)
    assert decisions(frame) == decisions(flight_fit)
    assert frame.report()["parameters"] == flight_fit.report()["parameters"]


def test_a_dict_of_arrays_fits_as_the_dataframe(quad_x):
    df = read_log(SWEEP)
    arrays = {c: df[c].to_numpy() for c in df.columns}
    a = mrsysid.fit(quad_x, samples=df, diagnose=False, threads=1)
    b = mrsysid.fit(quad_x, samples=arrays, diagnose=False, threads=2)
    pd.testing.assert_frame_equal(a.parameters, b.parameters, check_exact=True)


def test_columns_are_views_where_the_layout_allows():
    df = read_log(SWEEP)
    cols = _tables.columns(df, "df")
    assert np.shares_memory(cols["u"], df["u"].to_numpy()), "float64 column: no copy"
    strided = np.arange(20.0)[::2]
    converted = _tables.columns({"x": strided, "n": np.arange(10)}, "d")
    assert converted["x"].flags.c_contiguous and converted["n"].dtype == np.float64
    np.testing.assert_array_equal(converted["x"], strided)


def test_two_tables_are_two_logs_left_out_in_turn(quad_x):
    df = read_log(FLIGHT)
    half = len(df) // 2
    parts = {"first half": df.iloc[:half], "second half": df.iloc[half:]}
    r = mrsysid.fit(quad_x, samples=parts, diagnose=False, threads=2)
    folds = [f["name"] for f in r.report()["cross_validation"]]
    assert folds == ["first half", "second half", "pooled"]
    # Validation tables are reported on, never fitted.
    v = mrsysid.fit(quad_x, samples=parts["first half"], validate=parts["second half"],
                    diagnose=False, threads=2)
    assert v.report()["validation_samples"] == len(df) - half
    assert v.report()["samples"] <= half
    assert set(v.metrics.index.get_level_values("data")) == {"fit", "cross-validated", "validation"}
