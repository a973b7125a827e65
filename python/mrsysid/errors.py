"""Exceptions of mrsysid, one class per variant of the library's ``mrsysid::Error``.

Every exception carries the message the command-line tool prints, the exit code it
would give (``exit_code``: 1 when the data cannot support the fit, 2 for bad input)
and, where known, where the error happened: ``file`` (a file name, or the name of a
table given in memory), one of ``line`` (CSV or TOML text line, 1-based), ``record``
(MCAP message, 0-based), ``offset`` (byte of a binary log, 0-based) or ``sample``
(row of a table in memory, 0-based), and ``field`` (e.g. ``column "u"``).
"""

from __future__ import annotations

from typing import Optional

__all__ = [
    "MrsysidError",
    "VehicleError",
    "InputError",
    "ModelError",
    "AccumulateError",
    "EstimateError",
    "DiagnoseError",
    "ModelFileError",
    "RequestError",
    "SpillError",
    "StatsError",
]


class MrsysidError(Exception):
    """Base class of every error mrsysid raises."""

    #: Exit code of ``mrsysid`` for this error: 1 the data cannot support the fit,
    #: 2 bad input or usage.
    exit_code: int
    #: The file (or table name) concerned, when one is.
    file: Optional[str]
    #: Text line (1-based) of a CSV or TOML file.
    line: Optional[int]
    #: Message index (0-based) of an MCAP file.
    record: Optional[int]
    #: Byte offset (0-based) of a binary log.
    offset: Optional[int]
    #: Row (0-based) of a table given in memory.
    sample: Optional[int]
    #: The field concerned, labelled: ``column "u"``, ``field "/imu.x"``, ``key "signals"``.
    field: Optional[str]
    #: Short reason of an input error (``"not finite"``, ``"missing signal"``, ...).
    reason: Optional[str]

    def __init__(
        self,
        message: str,
        *,
        exit_code: int = 2,
        file: Optional[str] = None,
        line: Optional[int] = None,
        record: Optional[int] = None,
        offset: Optional[int] = None,
        sample: Optional[int] = None,
        field: Optional[str] = None,
        reason: Optional[str] = None,
    ) -> None:
        super().__init__(message)
        self.exit_code = exit_code
        self.file = file
        self.line = line
        self.record = record
        self.offset = offset
        self.sample = sample
        self.field = field
        self.reason = reason


class VehicleError(MrsysidError, ValueError):
    """The vehicle file or definition is invalid (``file`` is the vehicle file)."""


class InputError(MrsysidError, ValueError):
    """A log, mapping file or table is malformed: names the file or table, the line,
    message, byte or row, and the field."""


class ModelError(MrsysidError, ValueError):
    """The data lack a signal the model needs, or have another rotor count."""


class AccumulateError(MrsysidError, ValueError):
    """A log's regressors could not be accumulated (a non-finite regressor); ``file``
    names the log."""


class EstimateError(MrsysidError):
    """The data cannot support the fit (too little excitation, too few samples)."""


class DiagnoseError(MrsysidError):
    """The closing-the-loop diagnosis could not run."""


class ModelFileError(MrsysidError):
    """A model file could not be read or written (``file`` is the model file)."""


class RequestError(MrsysidError, ValueError):
    """The request cannot be carried out as given (no log, a log given twice, a
    validation log that is also a fit log, a log too short to cross-validate, ...)."""


class SpillError(MrsysidError):
    """The temporary file holding a log's samples between the two passes could not be
    written or read back (``file`` is that file)."""


class StatsError(MrsysidError, ValueError):
    """A statistics part cannot be read, merged or fitted: not a statistics file or
    corrupted (``file``), made with other settings, a log in two parts, or fewer than
    two fit logs."""
