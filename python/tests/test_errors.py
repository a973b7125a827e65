"""Errors raise the exceptions of mrsysid.errors with where they happened."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mrsysid

from conftest import QUAD_X, SWEEP, read_log


def test_a_missing_column_names_the_table_and_column(quad_x):
    with pytest.raises(mrsysid.InputError) as e:
        mrsysid.fit(quad_x, samples=read_log(SWEEP).drop(columns=["fx"]))
    assert (e.value.file, e.value.field, e.value.reason) == ("samples", 'column "fx"', "missing signal")
    assert e.value.exit_code == 2


def test_a_non_finite_value_names_the_row_and_signal(quad_x):
    df = read_log(SWEEP)
    df.loc[17, "q"] = np.inf
    with pytest.raises(mrsysid.InputError) as e:
        mrsysid.fit(quad_x, samples={"bad table": df})
    assert (e.value.file, e.value.sample, e.value.field) == ("bad table", 17, 'signal "q"')
    assert "not a finite number (inf)" in str(e.value)


def test_a_malformed_csv_names_file_line_and_column(quad_x, tmp_path: Path):
    lines = SWEEP.read_text().splitlines()
    header = lines[0].split(",")
    row = lines[9].split(",")
    row[header.index("w")] = "abc"
    lines[9] = ",".join(row)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(mrsysid.InputError) as e:
        mrsysid.fit(quad_x, [bad])
    assert (e.value.file, e.value.line, e.value.field) == ("bad.csv", 10, 'column "w"')
    assert e.value.reason == "not a number"


def test_vehicle_and_model_files(tmp_path: Path):
    bad = tmp_path / "v.toml"
    bad.write_text(QUAD_X.read_text().replace("mass = ", "mass = -"))
    with pytest.raises(mrsysid.VehicleError) as e:
        mrsysid.Vehicle.from_toml(bad)
    assert e.value.file == str(bad) and "mass" in str(e.value)
    model = tmp_path / "m.toml"
    model.write_text("schema_version = 1\n")
    with pytest.raises(mrsysid.ModelFileError) as e:
        mrsysid.load_model(model)
    assert e.value.file == str(model)


def test_requests_the_cli_would_refuse(quad_x, tmp_path: Path):
    with pytest.raises(mrsysid.RequestError) as e:
        mrsysid.fit(quad_x, [SWEEP, SWEEP])
    assert "given twice" in str(e.value) and e.value.exit_code == 2
    with pytest.raises(mrsysid.RequestError) as e:
        mrsysid.fit(quad_x, [SWEEP], inflow="guessed")
    assert e.value.field == "inflow"
    # A single log too short to cut into cross-validation blocks: the data cannot support the fit.
    short = read_log(SWEEP).iloc[:5]
    with pytest.raises(mrsysid.RequestError) as e:
        mrsysid.fit(quad_x, samples=short)
    assert e.value.exit_code == 1 and "too short" in str(e.value)
    with pytest.raises(mrsysid.RequestError):
        mrsysid.fit(quad_x)
    assert issubclass(mrsysid.InputError, ValueError)
    assert issubclass(mrsysid.EstimateError, mrsysid.MrsysidError)
