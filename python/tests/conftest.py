"""Shared fixtures: the repository's shipped data and the `mrsysid` binary whose output
the package must reproduce."""

from __future__ import annotations

import csv
import os
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import mrsysid

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data"
FLIGHT = DATA / "quad_x_flight_quadratic_drag.csv"
SWEEP = DATA / "quad_x_sweep.csv"
QUAD_X = DATA / "vehicles" / "quad_x.toml"


def read_log(path: Path) -> pd.DataFrame:
    """A contract CSV as a DataFrame, every value parsed to the nearest double by
    Python's float() (as the library's reader parses it; pandas' own parser rounds
    differently in some versions)."""
    with open(path, newline="") as f:
        rows = csv.reader(f)
        header = next(rows)
        values = np.array([[float(x) for x in row] for row in rows], dtype=np.float64)
    return pd.DataFrame(values, columns=header)


@pytest.fixture(scope="session")
def cli() -> Path:
    """The `mrsysid` binary: $MRSYSID_BIN, else the newest one cargo built in target/."""
    given = os.environ.get("MRSYSID_BIN")
    candidates = [Path(given)] if given else [
        ROOT / "target" / profile / "mrsysid" for profile in ("release", "debug")
    ]
    built = [c for c in candidates if c.is_file()]
    if not built:
        pytest.fail("no mrsysid binary: build it (`cargo build --release`) or set MRSYSID_BIN")
    return max(built, key=lambda c: c.stat().st_mtime)


def run_cli(cli: Path, *args: object) -> None:
    """Runs the binary quietly; fails the test with its stderr on a non-zero exit."""
    done = subprocess.run(
        [str(cli), *map(str, args)], capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr


@pytest.fixture(scope="session")
def quad_x() -> mrsysid.Vehicle:
    return mrsysid.Vehicle.from_toml(QUAD_X)


@pytest.fixture(scope="session")
def flight_fit(quad_x: mrsysid.Vehicle) -> mrsysid.Results:
    """The shipped flight log fitted from its file, with the diagnosis."""
    return mrsysid.fit(quad_x, [FLIGHT], threads=2)
