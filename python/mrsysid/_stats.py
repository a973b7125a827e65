"""Statistics as data: each log's first pass as bytes, merged and fitted without the
logs (``mrsysid accumulate`` and ``mrsysid fit --from-stats`` of the command line; the
byte format is ``docs/stats-format.md``)."""

from __future__ import annotations

import os
from typing import Any, Iterable, Optional, Sequence, Union

from . import _mrsysid
from ._results import Results
from ._tables import is_path, named_tables

PathLike = Union[str, "os.PathLike[str]"]


def _vehicle(vehicle: Union[_mrsysid.Vehicle, PathLike]) -> _mrsysid.Vehicle:
    if isinstance(vehicle, _mrsysid.Vehicle):
        return vehicle
    return _mrsysid.Vehicle.from_toml(os.fspath(vehicle))


def _options(mapping: Optional[PathLike], **options: Any) -> dict:
    return dict(mapping=None if mapping is None else os.fspath(mapping), **options)


def accumulate(
    vehicle: Union[_mrsysid.Vehicle, PathLike],
    logs: Union[PathLike, Iterable[PathLike]] = (),
    *,
    samples: Any = None,
    mapping: Optional[PathLike] = None,
    threads: Optional[int] = None,
    inflow: str = "derived",
    linear_vh: bool = True,
    rotor_inertia: str = "known",
    drop_invalid: bool = False,
    loads_low_pass: Optional[float] = None,
    keep_ground: bool = False,
    diagnose: bool = False,
) -> bytes:
    """Reads logs once and returns their first-pass statistics as the bytes of one
    statistics part (about 25 kB a log for a quadrotor, whatever its length): the same
    bytes ``mrsysid accumulate`` writes. Parts merge with ``merge_stats`` and fit with
    ``fit_from_stats`` when made with the same vehicle, mapping and options (the
    arguments mean what they mean for ``mrsysid.fit``). With ``diagnose=True`` a part
    also keeps the log's thinned samples for the diagnosis's screening (up to 20 000
    samples a log: 320 kB for a 1000-point sweep, 1 MB for a 30 s flight at 100 Hz), which a diagnosis from statistics
    needs (``mrsysid.dask.fit_fleet``). Errors raise the exceptions of
    ``mrsysid.errors``."""
    log_paths = [os.fspath(logs)] if is_path(logs) else [os.fspath(p) for p in logs]
    return _mrsysid.accumulate(
        _vehicle(vehicle),
        logs=log_paths,
        tables=named_tables(samples, "samples"),
        **_options(
            mapping,
            threads=threads,
            inflow=inflow,
            linear_vh=linear_vh,
            rotor_inertia=rotor_inertia,
            drop_invalid=drop_invalid,
            loads_low_pass=loads_low_pass,
            keep_ground=keep_ground,
        ),
        diagnose=diagnose,
    )


def merge_stats(parts: Sequence[bytes]) -> bytes:
    """The statistics parts ``parts`` merged, in order, into one: their logs side by
    side (associative, so any tree of merges gives the same part when the order of the
    leaves is kept). Raises ``mrsysid.errors.StatsError`` for parts made with other
    settings, a log in two parts, or bytes that are not a statistics part."""
    return _mrsysid.merge_stats(list(parts))


def fit_from_stats(
    vehicle: Union[_mrsysid.Vehicle, PathLike],
    parts: Union[bytes, Sequence[bytes]],
    *,
    validate: Union[bytes, Sequence[bytes]] = (),
    mapping: Optional[PathLike] = None,
    threads: Optional[int] = None,
    inflow: str = "derived",
    linear_vh: bool = True,
    rotor_inertia: str = "known",
    drop_invalid: bool = False,
    loads_low_pass: Optional[float] = None,
    keep_ground: bool = False,
    groups: Optional[Sequence[str]] = None,
) -> Results:
    """The Eq. 22 fit of the logs in ``parts`` (at least two: leave one log out, or
    leave one group out with ``groups``, one name per log of ``parts`` in order) with
    validation figures on those in ``validate``, from their statistics alone: equal to
    ``mrsysid.fit`` of the same logs with ``residual_pass=False`` and
    ``diagnose=False`` (the residual pass and the diagnosis need the samples). The
    vehicle, mapping and options must be those the parts were made with."""
    fit_part = parts if isinstance(parts, bytes) else merge_stats(parts)
    if isinstance(validate, bytes):
        validate_part: Optional[bytes] = validate
    else:
        validate_part = merge_stats(validate) if len(validate) > 0 else None
    native = _mrsysid.fit_from_stats(
        _vehicle(vehicle),
        parts=fit_part,
        validate_parts=validate_part,
        **_options(
            mapping,
            threads=threads,
            inflow=inflow,
            linear_vh=linear_vh,
            rotor_inertia=rotor_inertia,
            drop_invalid=drop_invalid,
            loads_low_pass=loads_low_pass,
            keep_ground=keep_ground,
        ),
        groups=list(groups or ()),
    )
    return Results(native)
