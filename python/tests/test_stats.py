"""Statistics as data from Python: parts equal to the command line's, a fit from them
equal to the direct fit, and a fleet of logs on a Dask LocalCluster."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

import mrsysid
from mrsysid.errors import StatsError

from conftest import FLIGHT, QUAD_X, SWEEP, run_cli


def test_parts_are_the_cli_bytes_and_fit_as_the_direct_fit(cli: Path, tmp_path: Path, quad_x) -> None:
    # The same bytes from the command line and from Python (threads change nothing).
    run_cli(cli, "accumulate", SWEEP, "--vehicle", QUAD_X, "-o", tmp_path / "sweep.stats")
    sweep = mrsysid.accumulate(quad_x, SWEEP, threads=1)
    assert (tmp_path / "sweep.stats").read_bytes() == sweep
    flight = mrsysid.accumulate(quad_x, FLIGHT)
    from_stats = mrsysid.fit_from_stats(quad_x, [sweep, flight])
    direct = mrsysid.fit(quad_x, [SWEEP, FLIGHT], residual_pass=False, diagnose=False)
    # Tolerance zero: the same statistics merged in the same order.
    pd.testing.assert_frame_equal(from_stats.parameters, direct.parameters, rtol=0, atol=0)
    pd.testing.assert_frame_equal(from_stats.metrics, direct.metrics, rtol=0, atol=0)
    with pytest.raises(StatsError, match="at least two fit logs"):
        mrsysid.fit_from_stats(quad_x, sweep)
    with pytest.raises(StatsError, match="in two statistics parts"):
        mrsysid.merge_stats([sweep, sweep])
    with pytest.raises(StatsError, match="not a mrsysid statistics file"):
        mrsysid.merge_stats([sweep, b"not a part"])


def test_fleet_groups_name_every_log(tmp_path: Path) -> None:
    # Refused before any task is sent (the client is never touched).
    from mrsysid.dask import fit_fleet

    with pytest.raises(ValueError, match="one name per log of paths, got 1 names for 2 logs"):
        fit_fleet([SWEEP, FLIGHT], QUAD_X, client=object(), groups=["day1"])


def split(tmp_path: Path, shipped: Path, logs: int) -> list:
    """The shipped log `shipped` cut into `logs` contract CSVs of consecutive rows, of
    equal length (pieces of the flight are time series of their own)."""
    lines = shipped.read_text().splitlines()
    header, rows = lines[0], lines[1:]
    n = len(rows) // logs
    paths = []
    for k in range(logs):
        path = tmp_path / f"{shipped.stem}-{k:02d}.csv"
        path.write_text("\n".join([header, *rows[k * n : (k + 1) * n]]) + "\n")
        paths.append(path)
    return paths


def test_a_fleet_on_two_dask_workers_equals_the_single_process_fit(tmp_path: Path, quad_x) -> None:
    distributed = pytest.importorskip("distributed")
    from mrsysid.dask import fit_fleet

    logs = split(tmp_path, SWEEP, 50)
    flights = split(tmp_path, FLIGHT, 4)
    corrupt = tmp_path / "corrupt.csv"
    corrupt.write_text("t,u,v\n0,1\n")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        # Four "days" of ten logs each as cross-validation groups; the corrupt log's
        # group goes with it. Both passes and the diagnosis run as map-reduce.
        days = [f"day{k // 10}" for k in range(40)]
        fleet = fit_fleet(
            [*logs[:40], corrupt],
            QUAD_X,
            validate=logs[40:],
            client=client,
            groups=[*days, "day9"],
        )
        eq22 = fit_fleet(logs[:40], QUAD_X, client=client, groups=days, diagnose=False)
        # Time series: the remainder pass runs as a third map.
        flight = fit_fleet(flights[:3], QUAD_X, validate=flights[3:], client=client)
    assert fleet.fitted == [str(p) for p in logs[:40]]
    assert list(fleet.failed) == [str(corrupt)]
    assert "corrupt.csv" in fleet.failed[str(corrupt)]
    direct = mrsysid.fit(quad_x, logs[:40], validate=logs[40:], groups=days)
    folds = [f["name"] for f in fleet.results.report()["cross_validation"]]
    assert folds == ["group day0", "group day1", "group day2", "group day3", "pooled"]
    # Tolerance zero: the same statistics merged in the same order, the same decisions.
    assert fleet.results.report() == direct.report()
    assert direct.report()["diagnosis"]["effects_added"], "the sweep's drag is found"
    pd.testing.assert_frame_equal(fleet.results.parameters, direct.parameters, rtol=0, atol=0)
    eq22_direct = mrsysid.fit(quad_x, logs[:40], residual_pass=False, diagnose=False, groups=days)
    pd.testing.assert_frame_equal(eq22.results.parameters, eq22_direct.parameters, rtol=0, atol=0)
    pd.testing.assert_frame_equal(eq22.results.metrics, eq22_direct.metrics, rtol=0, atol=0)
    flight_direct = mrsysid.fit(quad_x, flights[:3], validate=flights[3:])
    assert flight_direct.report()["diagnosis"]["remainder"], "a remainder pass ran"
    assert flight.results.report() == flight_direct.report()


def test_a_log_lost_after_its_first_pass_is_left_out_and_the_fleet_fitted_again(
    tmp_path: Path, quad_x, monkeypatch
) -> None:
    # A log whose second pass fails (e.g. removed after its first pass) is reported and
    # the fleet is planned and fitted again without it: the result is the fit of the
    # other logs. In-process workers, so the patched task is the one they run.
    distributed = pytest.importorskip("distributed")
    import mrsysid.dask as fleet_module

    logs = split(tmp_path, SWEEP, 6)
    lost = str(logs[2])
    real_pass = fleet_module._pass_one

    def flaky_pass(path, *args, **kwargs):
        if path == lost:
            return path, None, f"{path}: removed after its first pass"
        return real_pass(path, *args, **kwargs)

    monkeypatch.setattr(fleet_module, "_pass_one", flaky_pass)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        fleet = fleet_module.fit_fleet(logs, QUAD_X, client=client)
    assert list(fleet.failed) == [lost]
    assert "removed after its first pass" in fleet.failed[lost]
    kept = [p for p in logs if str(p) != lost]
    assert fleet.fitted == [str(p) for p in kept]
    assert fleet.results.report() == mrsysid.fit(quad_x, kept).report()
