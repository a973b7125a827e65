"""Fleets of logs on Dask: ``fit_fleet`` reads each log in a task of its own
(``mrsysid.accumulate``), merges the parts and fits once (``mrsysid.fit_from_stats``). Dask is needed only here (``pip install
"dask[distributed]"``); the core is engine-neutral, so Spark (``treeAggregate`` with
``merge_stats`` as both functions) or Ray can drive the same three functions.

Limits of this version: the fit is the Eq. 22 fit with leave-one-log-out
cross-validation; the residual pass and the closing-the-loop diagnosis, which need a
second pass over the logs, do not run on a fleet yet.
"""

from __future__ import annotations

import os
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
    path: str, vehicle_toml: str, options: Dict[str, Any]
) -> Tuple[str, Optional[bytes], Optional[str]]:
    """One task: a log's part, or the error that left it out (as text: exceptions of
    the extension need not pickle across workers)."""
    try:
        vehicle = _mrsysid.Vehicle.from_toml(vehicle_toml)
        return path, accumulate(vehicle, [path], threads=1, **options), None
    except MrsysidError as e:
        return path, None, str(e)


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
) -> FleetResults:
    """Fits one model to a fleet of logs on a Dask cluster: one task per log (and per
    validation log) reads it into its statistics part, and the client merges the parts
    (a few tens of kB a log) and fits once. ``vehicle``
    is the path of the vehicle TOML file (the workers read it); ``client`` a
    ``distributed.Client`` (default: the current one). A log whose reading fails is
    reported in ``FleetResults.failed`` and left out; a worker that dies is retried by
    Dask (each task is pure). The result equals ``mrsysid.fit_from_stats`` of the logs
    read in one process, in the order given. ``groups``: one cross-validation group
    name per log of ``paths`` (e.g. its flight day); the logs of a group are left out
    together, and a log left out as unreadable leaves its group."""
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

    def parts_of(logs: Sequence[PathLike]) -> Tuple[Any, List[str], Dict[str, str]]:
        names = [os.fspath(p) for p in logs]
        tasks = client.map(
            _accumulate_one, names, vehicle_toml=vehicle_toml, options=options, pure=True
        )
        outcomes = client.gather(tasks)
        failed = {p: e for p, _, e in outcomes if e is not None}
        good = [(p, b) for p, b, e in outcomes if e is None]
        merged = merge_stats([b for _, b in good]) if good else None
        return merged, [p for p, _ in good], failed

    fit_part, fitted, failed = parts_of(paths)
    validate_part, _, validate_failed = parts_of(validate)
    failed.update(validate_failed)
    if fit_part is None:
        raise ValueError(f"no log of the fleet could be read: {failed}")
    options.pop("mapping")
    group_of = dict(zip([os.fspath(p) for p in paths], groups or ()))
    results = fit_from_stats(
        _mrsysid.Vehicle.from_toml(vehicle_toml),
        fit_part,
        validate=validate_part if validate_part is not None else (),
        mapping=mapping,
        groups=[group_of[p] for p in fitted] if groups else None,
        **options,
    )
    return FleetResults(results=results, fitted=fitted, failed=failed)
