"""``mrsysid.fit``: the whole pipeline of ``mrsysid fit`` from Python."""

from __future__ import annotations

import os
from typing import Any, Iterable, List, Optional, Sequence, Union

from . import _mrsysid
from ._results import Results
from ._tables import is_path, is_table, named_tables

PathLike = Union[str, "os.PathLike[str]"]


def fit(
    vehicle: Union[_mrsysid.Vehicle, PathLike],
    logs: Union[PathLike, Iterable[PathLike]] = (),
    *,
    samples: Any = None,
    mapping: Optional[PathLike] = None,
    validate: Any = (),
    diagnose: bool = True,
    threads: Optional[int] = None,
    inflow: str = "derived",
    linear_vh: bool = True,
    rotor_inertia: str = "known",
    drop_invalid: bool = False,
    holdout_blocks: int = 5,
    holdout_guard: float = 2.0,
    loads_low_pass: Union[float, str, None] = None,
    keep_ground: bool = False,
    residual_pass: bool = True,
    groups: Optional[Sequence[str]] = None,
) -> Results:
    """Identifies the vehicle's model from logs: FSOA term ordering, the multivariate
    regression of all parameters, cross-validation and, with ``diagnose``, the
    closing-the-loop diagnosis — the pipeline of ``mrsysid fit``, with the same results.

    Args:
        vehicle: a ``Vehicle`` or the path of a vehicle TOML file.
        logs: log files to fit (CSV contract, mapped CSV, MCAP, PX4 ULog).
        samples: data in memory to fit: a table (pandas DataFrame, or dict of column
            name -> 1-D array) with the data contract's columns ``t u v w p q r
            omega_1..N fx fy fz mx my mz`` (optional ``omega_dot_1..N``, ``height``,
            ``qw qx qy qz``), SI units, body FRD axes; or a list of tables (named
            ``samples[k]``), or a dict of name -> table. Each table is one log.
        mapping: mapping file (TOML) for log files that do not follow the CSV contract.
        validate: reporting-only validation logs (paths and/or tables): no decision
            sees them.
        diagnose: run the closing-the-loop diagnosis.
        threads: threads for reading, accumulating and the diagnosis (default: all
            cores); results do not depend on it.
        inflow: ``"derived"`` or ``"paper"`` (the seed's printed inflow table).
        linear_vh: keep the terms linear in V_h.
        rotor_inertia: J_z terms ``"known"``, ``"estimated"`` or ``"neglected"``.
        drop_invalid: drop and count invalid samples of log files instead of stopping
            at the first.
        holdout_blocks: a single fit log is cross-validated on this many contiguous
            blocks, each held out in turn.
        holdout_guard: time on each side of a held-out block that its fold neither
            fits nor scores, s.
        loads_low_pass: the logs' forces and moments were low-passed at this cut-off
            (Hz) when they were made (from accelerations through a zero-phase filter, or
            a smoothing spline): the regressor signals pass through the same kind of
            filter (consistent filtering; as ``[loads] low_pass_hz`` in a mapping file).
            ``"estimate"``: the cut-off is not known; the fit is repeated with the
            regressors low-passed from 64 Hz down to 2 Hz and the cut-off whose model
            predicts held-out loads best is kept, or none (``Results.report()``'s
            ``loads_low_pass_scan`` lists the scan).
        keep_ground: fit ground time too (idling rotors before take-off, after
            landing); by default, as ``mrsysid fit``, only the airborne segments of log
            files are fitted (rotor thrust below the weight for 1 s or more is ground).
        residual_pass: run the second pass (residual diagnostics and the
            coloured-residual correction of σ); the diagnosis runs it regardless.
        groups: cross-validation groups, one name per fit log (the files of ``logs``,
            then the tables of ``samples``, in order): the logs of a group are left out
            together, e.g. one group per flight day. Default: each log alone.

    The GIL is released while the fit runs; Ctrl-C stops it within a chunk of data and
    raises ``KeyboardInterrupt``. Errors raise the exceptions of ``mrsysid.errors``.
    """
    if not isinstance(vehicle, _mrsysid.Vehicle):
        vehicle = _mrsysid.Vehicle.from_toml(os.fspath(vehicle))
    log_paths = [os.fspath(logs)] if is_path(logs) else [os.fspath(p) for p in logs]
    validate_logs: List[str] = []
    validate_tables: List[Any] = []
    items = [validate] if (is_path(validate) or is_table(validate)) else list(validate)
    for k, v in enumerate(items):
        if is_path(v):
            validate_logs.append(os.fspath(v))
        else:
            name = "validate" if len(items) == 1 else f"validate[{k}]"
            validate_tables.extend(named_tables(v, name))
    estimate = isinstance(loads_low_pass, str)
    if estimate and loads_low_pass != "estimate":
        raise ValueError(
            f"loads_low_pass: a cut-off in Hz or \"estimate\", got {loads_low_pass!r}"
        )
    native = _mrsysid.fit(
        vehicle,
        logs=log_paths,
        tables=named_tables(samples, "samples"),
        validate_logs=validate_logs,
        validate_tables=validate_tables,
        mapping=None if mapping is None else os.fspath(mapping),
        diagnose=diagnose,
        threads=threads,
        inflow=inflow,
        linear_vh=linear_vh,
        rotor_inertia=rotor_inertia,
        drop_invalid=drop_invalid,
        holdout_blocks=holdout_blocks,
        holdout_guard=holdout_guard,
        loads_low_pass=None if estimate else loads_low_pass,
        estimate_loads_low_pass=estimate,
        keep_ground=keep_ground,
        residual_pass=residual_pass,
        groups=list(groups or ()),
    )
    return Results(native)
