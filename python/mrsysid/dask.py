"""Fleets of logs on Dask: ``fit_fleet`` reads each log in a task of its own
(``mrsysid.accumulate``), merges the parts, fits once and, with the diagnosis (the
default), passes each log again in tasks of their own: the second pass (residual sums
and the candidate effects' statistics, from a plan the client makes once and sends to
every worker), the diagnosis on the client, and the remainder pass of each fit log with
the final model. Dask is needed only here (``pip install "dask[distributed]"``); the
core is engine-neutral, so Spark (``treeAggregate`` with ``merge_stats`` as both
functions, then ``mapPartitions`` for the second and remainder passes) or Ray can drive
the same functions: ``accumulate``, ``merge_stats``, ``_mrsysid.PlannedFit`` (``plan``,
``diagnose``), ``_mrsysid.PreparedPass`` (``pass_log``, ``remainder_log``) and
``PendingFit.finish``.
"""

from __future__ import annotations

import os
import threading
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

from . import _mrsysid
from ._results import Results
from ._stats import accumulate, fit_from_stats, merge_stats
from .errors import MrsysidError

PathLike = Union[str, "os.PathLike[str]"]


@dataclass
class FleetResults:
    """What ``fit_fleet`` did: the fit, the logs fitted, and the logs left out with
    the error each raised (an unreadable or corrupt log never stops the fleet)."""

    results: Results
    fitted: List[str]
    failed: Dict[str, str] = field(default_factory=dict)


def _accumulate_one(
    path: str, vehicle_toml: str, options: Dict[str, Any], diagnose: bool
) -> Tuple[str, Optional[bytes], Optional[str]]:
    """One task: a log's part, or the error that left it out (as text: exceptions of
    the extension need not pickle across workers)."""
    try:
        vehicle = _mrsysid.Vehicle.from_toml(vehicle_toml)
        part = accumulate(vehicle, [path], threads=1, diagnose=diagnose, **options)
        return path, part, None
    except MrsysidError as e:
        return path, None, str(e)


# The plan a worker process prepared last (preparing fits Eq. 22 and builds the
# candidate effects, so it is done once per process and plan, not once per log).
_PREPARED: Dict[Tuple[Any, ...], Any] = {}
_PREPARED_LOCK = threading.Lock()


def _prepared(vehicle_toml: str, plan: bytes, options: Dict[str, Any]) -> Any:
    # The plan's 32-byte header holds its length and CRC-32.
    key = (vehicle_toml, plan[:32], tuple(sorted(options.items())))
    with _PREPARED_LOCK:
        prepared = _PREPARED.get(key)
        if prepared is None:
            _PREPARED.clear()
            vehicle = _mrsysid.Vehicle.from_toml(vehicle_toml)
            prepared = _mrsysid.PreparedPass(vehicle, plan, threads=1, **options)
            _PREPARED[key] = prepared
        return prepared


def _pass_one(
    path: str, vehicle_toml: str, plan: bytes, options: Dict[str, Any]
) -> Tuple[str, Optional[bytes], Optional[str]]:
    """One task: a log's second pass, or the error that left it out."""
    try:
        return path, _prepared(vehicle_toml, plan, options).pass_log(path), None
    except MrsysidError as e:
        return path, None, str(e)


def _remainder_one(
    path: str, vehicle_toml: str, plan: bytes, model: bytes, options: Dict[str, Any]
) -> bytes:
    """One task: a fit log's remainder pass with the final model."""
    return _prepared(vehicle_toml, plan, options).remainder_log(model, path)


def fit_fleet(
    paths: Sequence[PathLike],
    vehicle: PathLike,
    *,
    client: Any = None,
    validate: Sequence[PathLike] = (),
    mapping: Optional[PathLike] = None,
    inflow: str = "derived",
    linear_vh: bool = True,
    rotor_inertia: str = "known",
    drop_invalid: bool = False,
    loads_low_pass: Optional[float] = None,
    keep_ground: bool = False,
    groups: Optional[Sequence[str]] = None,
    diagnose: bool = True,
) -> FleetResults:
    """Fits one model to a fleet of logs on a Dask cluster: one task per log (and per
    validation log) reads it into its statistics part, and the client merges the parts
    and fits once. With ``diagnose`` (the default) the closing of the loop follows as
    map-reduce: a second task per log passes it with the plan the client made (one
    preparation per worker process), the client diagnoses from the merged results, and
    a third task per fit log passes it with the final model. ``vehicle`` is the path of
    the vehicle TOML file (the workers read it); ``client`` a ``distributed.Client``
    (default: the current one). A log whose reading fails in any pass is reported in
    ``FleetResults.failed`` and left out (the fit is then made again without it); a
    worker that dies is retried by Dask (each task is pure). The result equals
    ``mrsysid.fit`` of the logs read in one process, in the order given, without plot
    series (without the diagnosis: ``mrsysid.fit_from_stats``). ``groups``: one
    cross-validation group name per log of ``paths`` (e.g. its flight day); the logs of
    a group are left out together, and a log left out as unreadable leaves its group."""
    if groups is not None and len(groups) != len(paths):
        raise ValueError(
            f"groups: one name per log of paths, got {len(groups)} names for {len(paths)} logs"
        )
    from distributed import get_client

    client = client if client is not None else get_client()
    vehicle_toml = os.fspath(vehicle)
    options = dict(
        mapping=None if mapping is None else os.fspath(mapping),
        inflow=inflow,
        linear_vh=linear_vh,
        rotor_inertia=rotor_inertia,
        drop_invalid=drop_invalid,
        loads_low_pass=loads_low_pass,
        keep_ground=keep_ground,
    )

    def parts_of(logs: Sequence[PathLike]) -> Tuple[Dict[str, bytes], Dict[str, str]]:
        names = [os.fspath(p) for p in logs]
        tasks = client.map(
            _accumulate_one,
            names,
            vehicle_toml=vehicle_toml,
            options=options,
            diagnose=diagnose,
            pure=True,
        )
        outcomes = client.gather(tasks)
        failed = {p: e for p, _, e in outcomes if e is not None}
        return {p: b for p, b, e in outcomes if e is None}, failed

    fit_parts, failed = parts_of(paths)
    validate_parts, validate_failed = parts_of(validate)
    failed.update(validate_failed)
    native_vehicle = _mrsysid.Vehicle.from_toml(vehicle_toml)
    group_of = dict(zip([os.fspath(p) for p in paths], groups or ()))
    fit_options = {k: v for k, v in options.items() if k != "mapping"}
    while True:
        if not fit_parts:
            raise ValueError(f"no log of the fleet could be read: {failed}")
        fitted = list(fit_parts)
        fleet_groups = [group_of[p] for p in fitted] if groups else None
        if not diagnose:
            fit_part = merge_stats(list(fit_parts.values()))
            validate_part = merge_stats(list(validate_parts.values())) if validate_parts else None
            results = fit_from_stats(
                native_vehicle,
                fit_part,
                validate=validate_part if validate_part is not None else (),
                mapping=mapping,
                groups=fleet_groups,
                **fit_options,
            )
            return FleetResults(results=results, fitted=fitted, failed=failed)
        # The parts merged inside (one parse of them, no merged bytes made).
        planned = _mrsysid.PlannedFit(
            native_vehicle,
            parts=list(fit_parts.values()),
            validate_parts=list(validate_parts.values()),
            threads=None,
            groups=list(fleet_groups or ()),
            **options,
        )
        plan = planned.plan()
        plan_future = client.scatter(plan, broadcast=True)
        logs = fitted + list(validate_parts)
        tasks = client.map(
            _pass_one, logs, vehicle_toml=vehicle_toml, plan=plan_future, options=options
        )
        outcomes = client.gather(tasks)
        lost = {p: e for p, _, e in outcomes if e is not None}
        if lost:
            # Read once but not twice (changed or removed meanwhile): fit without them.
            failed.update(lost)
            fit_parts = {p: b for p, b in fit_parts.items() if p not in lost}
            validate_parts = {p: b for p, b in validate_parts.items() if p not in lost}
            continue
        pending = planned.diagnose([b for _, b, _ in outcomes])
        remainders: List[bytes] = []
        remainder_plan = pending.remainder_plan()
        if remainder_plan is not None:
            model, names = remainder_plan
            # The remainder plan names the fit logs in the order of the parts.
            assert len(names) == len(fitted)
            model_future = client.scatter(model, broadcast=True)
            remainders = client.gather(
                client.map(
                    _remainder_one,
                    fitted,
                    vehicle_toml=vehicle_toml,
                    plan=plan_future,
                    model=model_future,
                    options=options,
                )
            )
        results = Results(pending.finish(remainders))
        return FleetResults(results=results, fitted=fitted, failed=failed)
